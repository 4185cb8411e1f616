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
One static-segment rule for every tool (issue 30 item 2): core/segments.py.

A knock on one axis cuts that time from every axis; the streaming rule (analyze) and the record
rule (explain, and the tools that read a record whole) choose the same segment; analyze and
explain cut the same samples of one file and print the same sentence.
"""

import json

from gyro_noise_ros.app.explain import ExplainParams, prepare_explain
from gyro_noise_ros.cli import analyze
from gyro_noise_ros.core.segments import left_out_sentence, static_part, WindowStats
import numpy as np
import pytest

RATE_HZ = 43.0
SIGMA_RAD_S = 2e-3
T0_NS = 1_700_000_000 * 10 ** 9


def _record(seconds=400.0, knock=(186.0, 189.0), axis=1, seed=3):
    """Return stamps (ns) and 3-axis gyro (rad/s) at rest with a knock on one axis."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * RATE_HZ)) / RATE_HZ
    gyro = rng.normal(0.0, SIGMA_RAD_S, (t.size, 3))
    hit = (t >= knock[0]) & (t < knock[1])
    # a knock: ~100x the noise for 3 s on one axis (the MPU-9250 log of the issue: y only)
    gyro[hit, axis] += rng.normal(0.0, 100 * SIGMA_RAD_S, int(hit.sum()))
    return T0_NS + np.rint(t * 1e9).astype(np.int64), gyro, t


def test_a_knock_on_one_axis_cuts_every_axis():
    stamps, gyro, t = _record()
    part = static_part(stamps, gyro)
    # 1 s windows: the knock's windows 186-189 s move; the longest static run follows them
    assert part.segment_s[0] == pytest.approx(189.0)
    assert part.segment_s[1] == pytest.approx(t[-1])
    assert part.kept_samples == int(np.sum(t >= 189.0))
    motion = [c for c in part.cuts if c.reason == 'motion']
    assert [(c.start_s, c.end_s) for c in motion] == [(186.0, 189.0)]
    assert [(c.start_s, c.end_s, c.reason) for c in part.cuts if c.reason != 'motion'] == [
        (0.0, 186.0, 'shorter static run')]
    assert 'in motion at t = 186.0-189.0 s' in part.description
    assert part.description.startswith(f'{part.cut_samples} of {t.size} samples left out')
    # one mask for every axis: the knock on y cuts x and z alike
    per_axis = [static_part(stamps, gyro[:, [k]]) for k in range(3)]
    assert per_axis[1].kept_samples == part.kept_samples
    assert per_axis[0].cut_samples == 0 and per_axis[2].cut_samples == 0


def test_the_streaming_rule_and_the_record_rule_agree():
    stamps, gyro, _ = _record(knock=(50.0, 52.0), axis=2)
    stats = WindowStats()
    for lo in range(0, stamps.size, 1000):   # analyze feeds batches
        stats.update(stamps[lo:lo + 1000], gyro[lo:lo + 1000])
    streamed = stats.segment()
    part = static_part(stamps, gyro)
    assert (streamed.start_ns, streamed.end_ns) == (part.segment.start_ns, part.segment.end_ns)
    assert streamed.moving == part.segment.moving


def test_a_static_record_cuts_nothing_and_a_missing_column_is_not_judged():
    stamps, gyro, _ = _record(knock=(0.0, 0.0))
    part = static_part(stamps, gyro)
    assert part.keep.all() and part.cuts == () and part.description == ''
    assert part.left_out() == {'motion': 0}
    # a CSV with the y column only reads x and z as NaN: judged on y alone, knock found
    stamps, gyro, _ = _record()
    gyro[:, [0, 2]] = np.nan
    assert static_part(stamps, gyro).segment_s[0] == pytest.approx(189.0)


def test_the_accelerometer_is_judged_when_given():
    stamps, gyro, t = _record(knock=(0.0, 0.0))
    rng = np.random.default_rng(4)
    accel = rng.normal(0.0, 0.01, (t.size, 3)) + [0.0, 0.0, 9.81]
    hit = (t >= 300.0) & (t < 302.0)
    accel[hit, 0] += 2.0   # a push the gyro does not see
    assert static_part(stamps, gyro).cut_samples == 0
    part = static_part(stamps, gyro, accel=accel)
    assert [(c.start_s, c.end_s) for c in part.cuts if c.reason == 'motion'] == [(300.0, 302.0)]


def test_the_sentence_names_the_window_and_the_motion():
    assert left_out_sentence(100) == ''
    text = left_out_sentence(100, before_start=10, after_end=5, window_names=('--start', '--end'))
    assert text == '15 of 100 samples left out: 10 before --start, 5 after --end'


def test_analyze_and_explain_cut_one_window_and_say_one_sentence(tmp_path, capsys):
    stamps, gyro, t = _record()
    path = tmp_path / 'knock.csv'
    rows = np.column_stack((t, np.rad2deg(gyro)))
    np.savetxt(path, rows, delimiter=',', fmt='%.9g',
               header='t_s,gyro_x_dps,gyro_y_dps,gyro_z_dps', comments='')
    rc = analyze.main([str(path), '--out', str(tmp_path / 'a'), '--jobs', '1', '--no-figures',
                       '--no-html', '--quiet', '--no-allan', '--chunk-size', '2000',
                       '--memory', '50', '--order-grid', '0:2:0.5'])
    assert rc == 0
    said = capsys.readouterr().err
    left = json.loads((tmp_path / 'a' / 'summary.json').read_text())['bags'][0]['left_out']
    prepared = prepare_explain(ExplainParams(path=str(path)))
    assert all(entry == left for entry in prepared.left_out)
    sentence = [w for w in prepared.warnings if 'left out' in w]
    assert len(sentence) == 1 and sentence[0] in said
    assert [m.n for m in prepared.measurements] == [int(np.sum(t >= 189.0))] * 3
