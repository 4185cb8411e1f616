# Copyright 2026 gyro_noise_ros developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The compensator's diagnostics task without ROS: levels from the thresholds, rate, documented keys.

Times are passed in (monotonic seconds), so every level is reached deterministically; the node
tests (test_compensator_node.py) check the same status through ROS.
"""

from pathlib import Path
import re

from _thermal_linear import LinearThermal
from gyro_noise_ros.calibration.apply import identity
from gyro_noise_ros.diagnostics.compensation import CompensationTask, CompensationThresholds
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.live import LiveDriftEvaluator
import numpy as np
import pytest

NS = 1_000_000_000
DOC = Path(__file__).resolve().parents[1] / 'docs' / 'compensation.md'


def task(**limits):
    return CompensationTask(CompensationThresholds(**limits), calibration=identity(),
                            calibration_source='parameters', out_of_range_action='hold', now=0.0)


def evaluator(temperature_c):
    ev = LiveDriftEvaluator(LinearThermal(temperature_range_c=(20.0, 30.0), range_margin_c=2.0))
    ev.add_temperature(np.array([NS]), np.array([temperature_c]))
    return ev


def test_stale_data_is_an_error_until_data_arrives_within_the_limit():
    t = task(stale_after_s=5.0)
    status = t.run(1.0)
    assert (status.level, status.message) == ('ERROR', 'No imu/data_raw yet.')
    t.tick_data(2.0)
    assert (t.run(7.0).level, t.run(7.0).message) == ('OK', 'Compensating.')  # 5.0 s: not above
    status = t.run(7.5)
    assert (status.level, status.message) == ('ERROR', 'No imu/data_raw for 5.5 s.')
    assert dict(status.values)['Thermal model'] == 'none'


@pytest.mark.parametrize('temperature_c, level, range_name, words', [
    (25.0, 'OK', 'inside', 'Compensating.'),
    (31.0, 'WARN', 'within margin', 'within the margin'),
    (40.0, 'ERROR', 'outside', 'beyond the model range + margin: offset not extrapolated (hold)'),
])
def test_temperature_range_drives_the_level(temperature_c, level, range_name, words):
    t = task()
    t.tick_data(10.0)
    t.tick_temperature(10.0)
    status = t.run(10.5, thermal=evaluator(temperature_c))
    values = dict(status.values)
    assert status.level == level and words in status.message
    assert values['Temperature range status'] == range_name
    assert values['Temperature age (s)'] == '0.50'


def test_temperature_age_missing_temperature_and_dropped_messages_warn():
    t = task(temperature_timeout_s=2.0, temperature_wait_s=0.3)
    t.tick_data(10.0)
    ev = evaluator(25.0)
    status = t.run(10.0, thermal=ev)
    assert status.level == 'WARN' and status.message.startswith('No imu/temperature yet')
    t.tick_temperature(10.0)
    assert t.run(12.0, thermal=ev).level == 'OK'  # 2.0 s old: at the limit, not above
    status = t.run(12.5, thermal=ev)
    assert (status.level, status.message) == ('WARN', 'Temperature is 2.5 s old: offset held.')
    t.counts['uncorrected'] += 400
    status = t.run(12.5, thermal=ev, waiting=7)
    # the first WARN among equals names the drop, checked before the age
    assert status.message == '400 messages dropped: no temperature within 0.3 s of them.'
    values = dict(status.values)
    assert values['Messages dropped waiting for the first temperature'] == '400'
    assert values['Messages waiting for the first temperature'] == '7'


def test_the_first_error_among_equals_names_the_status():
    t = task()
    status = t.run(1.0, thermal=evaluator(40.0))
    assert status.level == 'ERROR' and status.message == 'No imu/data_raw yet.'


def test_output_rate_is_the_published_difference_over_at_least_the_interval():
    t = task(rate_interval_s=0.5)
    t.counts['published'] += 100
    assert dict(t.run(0.4).values)['Output rate (Hz)'] == 'nan'  # interval not over yet
    assert dict(t.run(0.5).values)['Output rate (Hz)'] == '200.0'
    t.counts['published'] += 30
    assert dict(t.run(0.9).values)['Output rate (Hz)'] == '200.0'  # kept until 1.0
    assert dict(t.run(1.1).values)['Output rate (Hz)'] == '50.0'


def test_every_key_is_documented_and_the_thresholds_refuse_bad_limits():
    section = DOC.read_text().split('\n## Diagnostics', 1)[1].split('\n## ', 1)[0]
    rows = re.findall(r'^\| (`[^|]+) \|', section, flags=re.MULTILINE)
    documented = {k for row in rows for k in re.findall(r'`([^`]+)`', row)}
    t = task()
    t.tick_data(1.0)
    keys = {k for k, _ in t.run(1.0, thermal=evaluator(25.0)).values}
    assert keys == documented
    with pytest.raises(ParameterError, match='stale_after_s'):
        CompensationThresholds(stale_after_s=-1.0)
