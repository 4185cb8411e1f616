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

"""Inputs (CSV, bags), bad-input errors and the gyro_noise_explain command line."""

import json
import subprocess
import sys

from gyro_noise_ros.cli.explain import main
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.explain.effects import NAMES
from gyro_noise_ros.explain.inputs import load_input, make_measurement, MIN_SAMPLES
from gyro_noise_ros.explain.synthetic import make_record as synthetic_record
import numpy as np
import pytest


def _write_csv(make_record, path, t, rate, *, temperature=None, unit='rad_s'):
    """Write a CSV through the factory: ``rate`` (rad/s) on z, half of it on x, a quarter on y."""
    return make_record(path, np.column_stack((rate * 0.5, rate * 0.25, rate)), t_s=t,
                       temperature_c=temperature, storage='csv', csv_gyro_unit=unit)


def _record(n=MIN_SAMPLES + 100, seed=0):
    rng = np.random.default_rng(seed)
    return np.arange(n) / 200.0, rng.standard_normal(n) * 1e-3 + 0.01


def test_csv_columns_and_units(tmp_path, make_record):
    t, rate = _record()
    path = tmp_path / 'a.csv'
    _write_csv(make_record, path, t, rate, temperature=np.full(t.size, 25.0))
    meas = load_input(path, axis='z')
    np.testing.assert_allclose(meas.rate, rate, rtol=1e-11)
    assert meas.rate_hz == pytest.approx(200.0, rel=1e-9)
    assert meas.temperature_c is not None and meas.axis == 'z'
    # deg/s columns are converted to rad/s
    path2 = tmp_path / 'b.csv'
    _write_csv(make_record, path2, t, rate, unit='dps')  # written in deg/s
    np.testing.assert_allclose(load_input(path2, axis='z').rate, rate, rtol=1e-10)
    assert load_input(path2, axis='x').rate[0] == pytest.approx(rate[0] * 0.5, rel=1e-10)


def test_csv_without_time_needs_rate(tmp_path, make_record):
    _, rate = _record()
    path = tmp_path / 'c.csv'
    make_record(path, np.column_stack((rate * 0, rate * 0, rate)), storage='csv', csv_time=False)
    with pytest.raises(ParameterError, match='rate_hz'):
        load_input(path)
    assert load_input(path, rate_hz=100.0).rate_hz == 100.0


def test_bad_input_errors(tmp_path):
    t, rate = _record()
    bad = rate.copy()
    bad[123] = np.nan
    with pytest.raises(InputDataError, match='NaN.*index 123'):
        make_measurement(bad, t_s=t)
    with pytest.raises(InputDataError, match='too short'):
        make_measurement(rate[:1000], t_s=t[:1000])
    with pytest.raises(InputDataError, match='temperature was asked for'):
        make_measurement(rate, t_s=t, require_temperature=True)
    with pytest.raises(InputDataError, match='constant'):
        make_measurement(np.ones(MIN_SAMPLES), rate_hz=100.0)
    with pytest.raises(ParameterError, match='axis'):
        make_measurement(rate, t_s=t, axis='w')


def test_bag_with_temperature(tmp_path, make_record):
    t, rate = _record()
    gyro = np.column_stack((rate * 0, rate * 0, rate))
    # stamps 1_700_000_000 s + t; accel (0, 0, 9.81); one temperature message a second
    bag = make_record(tmp_path / 'bag', gyro, t_s=t, temperature_c=25.0 + t[::200] * 0.01,
                      temperature_t_s=t[::200])
    meas = load_input(bag, axis='z', require_temperature=True)
    np.testing.assert_array_equal(meas.rate, rate)
    assert meas.rate_hz == pytest.approx(200.0, rel=1e-6)
    # linear interpolation of a linear temperature ramp onto the Imu stamps is exact inside the
    # span
    inner = t <= t[::200][-1]
    np.testing.assert_allclose(meas.temperature_c[inner], 25.0 + t[inner] * 0.01, rtol=1e-9)
    bag2 = make_record(tmp_path / 'bag2', gyro, t_s=t)
    with pytest.raises(InputDataError, match='temperature was asked for'):
        load_input(bag2, require_temperature=True)


def test_cli_bad_input_exit_codes(tmp_path, capsys, make_record):
    t, rate = _record()
    short = tmp_path / 'short.csv'
    _write_csv(make_record, short, t[:500], rate[:500])
    assert main([str(short), '--out', str(tmp_path / 'o1')]) == InputDataError.exit_code
    assert 'too short' in capsys.readouterr().err
    nan = tmp_path / 'nan.csv'
    bad = rate.copy()
    bad[7] = np.nan
    _write_csv(make_record, nan, t, bad)
    assert main([str(nan), '--out', str(tmp_path / 'o2')]) == InputDataError.exit_code
    assert 'NaN' in capsys.readouterr().err
    ok = tmp_path / 'ok.csv'
    _write_csv(make_record, ok, t, rate)
    assert main([str(ok), '--out', str(tmp_path / 'o3'),
                 '--require-temperature']) == InputDataError.exit_code
    assert 'temperature was asked for' in capsys.readouterr().err
    assert main([str(tmp_path / 'missing.bag'), '--out', str(tmp_path / 'o4')]) == 3
    assert main([str(ok), '--out', str(tmp_path / 'o5'), '--ensemble',
                 '2']) == ParameterError.exit_code


def test_cli_end_to_end(tmp_path, capsys, make_record):
    meas, _ = synthetic_record(('quantization',), np.random.default_rng([0, 7]), n=MIN_SAMPLES)
    path = tmp_path / 'q.csv'
    _write_csv(make_record, path, meas.t_s, meas.rate)
    out = tmp_path / 'out'
    assert main([str(path), '--out', str(out), '--ensemble', '6', '--seed', '3', '--quiet',
                 '--axis', 'z']) == 0
    assert 'quantization' in capsys.readouterr().out
    data = json.loads((out / 'explain.json').read_text())
    assert {'baseline', 'steps', 'gap_initial', 'gap_final', 'unexplained'} <= set(data)
    step = data['steps'][0]
    assert step['effect'] == 'quantization' and step['effect'] in NAMES
    assert set(step) >= {'effect', 'params', 'gap_before', 'gap_after', 'where'}
    assert step['gap_after'] < step['gap_before']
    assert step['params']['step_rad_s'] > 0
    report = (out / 'report.md').read_text()
    assert 'Step 1: quantization' in report
    assert (out / 'overview.png').stat().st_size > 1000
    assert (out / 'step1_quantization.png').stat().st_size > 1000


def test_module_runs_as_script():
    proc = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.explain', '--help'],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and '--temperature-topic' in proc.stdout


def test_cli_bag_without_asked_temperature(tmp_path, capsys, make_record):
    t, rate = _record()
    bag = make_record(tmp_path / 'bag', np.column_stack((rate, rate, rate)), t_s=t,
                      t0_ns=10 ** 9)
    code = main([str(bag), '--temperature-topic', '/imu/temperature', '--out',
                 str(tmp_path / 'o')])
    err = capsys.readouterr().err
    # the named topic does not exist: the bag reader refuses it (3, a recording problem) in one
    # line
    assert code == 3 and 'temperature' in err and err.count('\n') == 1
    code = main([str(bag), '--require-temperature', '--out', str(tmp_path / 'o')])
    assert code == InputDataError.exit_code
    assert 'temperature was asked for' in capsys.readouterr().err
