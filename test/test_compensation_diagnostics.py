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
from gyro_noise_ros.thermal.live import LiveDriftEvaluator, TemperatureGate
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
    hold = TemperatureGate(max_wait_s=1.0, first_wait_s=0.3)
    hold.push('a', np.arange(400), now_s=10.0)
    hold.release(None, 12.0)  # no temperature within 0.3 s: dropped
    hold.push('b', np.arange(400, 407), now_s=12.4)
    status = t.run(12.5, thermal=ev, hold=hold)
    # the first WARN among equals names the drop, checked before the age
    assert status.message == '400 messages dropped: no temperature within 0.3 s of them.'
    values = dict(status.values)
    assert values['Messages dropped waiting for the first temperature'] == '400'
    assert values['Messages waiting for a temperature'] == '7'


def _late_hold(late):
    # ``late`` samples newer than the newest temperature (stamp 0) that waited the 1 s bound.
    hold = TemperatureGate(max_wait_s=1.0, first_wait_s=2.0)
    hold.push('a', np.arange(1, late + 1), now_s=0.0)
    assert hold.release(0, 1.0) == [('a', 0, late, True)]
    return hold


def test_samples_with_a_held_offset_warn_once_per_published_status():
    t = task(max_temperature_wait_s=1.0)
    t.tick_data(10.0)
    t.tick_temperature(10.0)
    ev, hold = evaluator(25.0), _late_hold(5)
    late = '5 messages compensated with a held offset: no newer temperature within 1 s.'
    # An unpublished status (a query) leaves the late samples to the next published one.
    for _ in range(2):
        status = t.run(10.5, thermal=ev, hold=hold)
        assert (status.level, status.message) == ('WARN', late)
    status = t.run(10.5, thermal=ev, hold=hold, record=True)
    assert (status.level, status.message) == ('WARN', late)
    values = dict(status.values)
    assert values['Messages compensated with a held offset'] == '5'
    assert values['Messages waiting for a temperature'] == '0'
    # The next period has none new: OK, and the count stays in the values.
    status = t.run(11.0, thermal=ev, hold=hold, record=True)
    assert (status.level, status.message) == ('OK', 'Compensating.')
    assert dict(status.values)['Messages compensated with a held offset'] == '5'
    # Two more go late: the WARN counts only them.
    hold.push('b', [10, 11], now_s=11.0)
    assert hold.release(0, 12.0) == [('b', 0, 2, True)]
    status = t.run(12.0, thermal=ev, hold=hold, record=True)
    assert status.level == 'WARN' and status.message.startswith('2 messages compensated')
    assert dict(status.values)['Messages compensated with a held offset'] == '7'


def test_held_offsets_rank_after_drops_and_before_the_temperature_age():
    t = task(temperature_timeout_s=2.0, temperature_wait_s=0.3)
    t.tick_data(10.0)
    t.tick_temperature(10.0)
    ev, hold = evaluator(25.0), _late_hold(3)
    status = t.run(13.0, thermal=ev, hold=hold)  # 3 s old temperature: also a WARN
    assert status.message.startswith('3 messages compensated with a held offset')
    hold.push('c', [7, 8, 9, 10], now_s=0.0)
    hold.release(None, 2.5)  # (as before a first temperature) 4 wait 2.5 s > 2 s: dropped
    assert hold.dropped == 4
    assert t.run(13.0, thermal=ev, hold=hold).message.startswith('4 messages dropped')
    # Beyond the margin: the ERROR leads.
    assert t.run(13.0, thermal=evaluator(40.0), hold=hold).level == 'ERROR'


def test_the_hold_is_reported_with_its_longest_on_time_wait():
    t = task()
    t.tick_data(10.0)
    t.tick_temperature(10.0)
    hold = TemperatureGate(max_wait_s=1.0, first_wait_s=2.0)
    hold.push('a', [5, 6], now_s=10.0)
    assert hold.release(6, 10.25) == [('a', 0, 2, False)]
    values = dict(t.run(10.5, thermal=evaluator(25.0), hold=hold).values)
    assert values['Longest wait for a temperature (s)'] == '0.250'
    assert values['Messages compensated with a held offset'] == '0'


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
