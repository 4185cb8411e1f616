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

"""gyro_noise_calibrate on tiny bags: every output file, the YAML format, every exit code."""

import json

from _realdata import real_data
from _reliability_common import six_position_record, write_bag
from gyro_noise_ros.calibration import records
from gyro_noise_ros.calibration.emulate import PAPER_BEFORE_BIAS_MG, SensorErrors
from gyro_noise_ros.calibration.sixpos import normal_gravity
from gyro_noise_ros.cli.calibrate import main
from gyro_noise_ros.units import MG_TO_M_S2
import numpy as np
import pytest
import yaml

YAML_KEYS = ['accel_bias_m_s2', 'accel_scale_factor', 'accel_misalignment', 'gyro_bias_rad_s',
             'gyro_scale_factor', 'gyro_misalignment', 'calibration_gravity_m_s2']


@pytest.fixture(scope='module')
def record():
    return six_position_record(dwell_s=20.0, seed=21,
                               errors=SensorErrors(gyro_bias_rad_s=(0.01, -0.02, 0.005)))


def test_one_bag_gives_all_three_files(tmp_path, record, capsys):
    bag = write_bag(tmp_path / 'six', *record)
    out = tmp_path / 'out'
    assert main([str(bag), '--latitude', '45', '--height', '200', '--out', str(out)]) == 0
    doc = json.loads((out / 'calibration.json').read_text())
    g = normal_gravity(45.0, 200.0)
    assert doc['gravity_m_s2'] == g
    assert len(doc['dwells']) == 6
    for d in doc['dwells']:
        assert set(d) >= {'orientation', 't_start_s', 'duration_s', 'samples'}
    assert np.asarray(doc['accel']['misalignment']).shape == (3, 3)
    assert np.all(np.diag(doc['accel']['misalignment']) == 0)
    # the record was made with standard gravity: the local value shifts S by (9.80665 / g - 1)
    # and leaves b alone (within 4 sigma, ~0.25 mg here)
    np.testing.assert_allclose(np.asarray(doc['accel']['bias_m_s2']) / MG_TO_M_S2,
                               PAPER_BEFORE_BIAS_MG, atol=0.25)
    for key in ('accel_bias_std_m_s2', 'accel_scale_factor_std'):
        assert key in doc['uniformity']
    gc = doc['gravity_check']
    assert gc['consistent'] and len(gc['dwells']) == 6 and 'leave-one-out' in gc['method']
    assert doc['consistency']['consistent'] and len(doc['consistency']['pairs']) == 3
    np.testing.assert_allclose(doc['gyro']['bias_rad_s'], [0.01, -0.02, 0.005], atol=1e-4)
    # the record's gyro has no scale error: the five turns put every estimate near 0 (4 sigma)
    est = np.asarray(doc['gyro']['estimated'])
    sf = np.asarray(doc['gyro']['scale_factor'])
    sig = np.asarray(doc['gyro']['scale_factor_sigma'])
    assert np.all(np.abs(sf[est.diagonal()]) < 4 * sig[est.diagonal()])
    params = yaml.safe_load((out / 'calibration.yaml').read_text())
    p = params['/**']['ros__parameters']
    assert list(p) == YAML_KEYS
    assert p['calibration_gravity_m_s2'] == g
    assert len(p['accel_misalignment']) == 9 and len(p['gyro_misalignment']) == 9
    assert p['accel_bias_m_s2'] == doc['accel']['bias_m_s2']
    assert p['gyro_scale_factor'] == doc['gyro']['scale_factor']
    assert p['gyro_misalignment'] == sum(doc['gyro']['misalignment'], [])
    text = (out / 'calibration.yaml').read_text()
    assert text.startswith('#') and 'Sources: ' in text
    md = (out / 'calibration.md').read_text()
    assert '| bx |' in md and 'mg' in md and 'uniformity' in md and 'leave-one-out' in md
    printed = capsys.readouterr()
    assert 'dwell +z' in printed.out and 'warning' not in printed.err


def test_six_bags_and_standard_gravity_warning(tmp_path, record, capsys):
    t, accel, gyro = record
    bags = []
    for k in range(6):
        sel = (t >= k * 24.0 + 1.0) & (t < k * 24.0 + 19.0)   # inside each 20 s dwell
        bags.append(str(write_bag(tmp_path / f'b{k}', t[sel] - t[sel][0], accel[sel], gyro[sel])))
    assert main(bags + ['--out', str(tmp_path / 'out')]) == 0
    assert 'warning: no --gravity or --latitude' in capsys.readouterr().err
    doc = json.loads((tmp_path / 'out' / 'calibration.json').read_text())
    assert doc['gravity_m_s2'] == 9.80665
    assert sorted(d['source'] for d in doc['dwells']) == sorted(bags)


def test_exit_codes(tmp_path, record, capsys):
    t, accel, gyro = record
    out = str(tmp_path / 'out')
    assert main([str(tmp_path / 'nope'), '--out', out]) == 3
    assert main(['x', '--gravity', '100', '--out', out]) == 2
    assert main(['x', '--height', '100', '--out', out]) == 2
    five = write_bag(tmp_path / 'five', t[t < 115.0], accel[t < 115.0], gyro[t < 115.0])
    capsys.readouterr()
    assert main([str(five), '--gravity', '9.81', '--out', out]) == 4
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'orientation(s) -y missing' in err
    zero = write_bag(tmp_path / 'zero', t, np.zeros_like(accel), gyro)
    assert main([str(zero), '--gravity', '9.81', '--out', out]) == 4
    assert 'accelerometer reads ~0' in capsys.readouterr().err
    assert main([str(five), '--gravity', '9.81', '--min-static-s', '30', '--out', out]) == 4
    assert '--min-static-s 30' in capsys.readouterr().err


@pytest.mark.parametrize('where', ['file', 'under_file'])
def test_out_in_the_way_is_exit_6_before_reading_anything(tmp_path, capsys, where):
    blocker = tmp_path / 'blocker'
    blocker.write_text('x')
    out = blocker if where == 'file' else blocker / 'out'
    # the recording does not even exist: the output is checked first
    assert main([str(tmp_path / 'nope'), '--gravity', '9.81', '--out', str(out)]) == 6
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err and 'blocker' in err


def test_rate_from_bursty_host_stamps_is_the_mean_rate_not_the_median_step():
    # The MPU6050 record's host stamps come in bursts: median step 2 ms, true mean rate
    # 99.32 Hz (the median would say 500 Hz). The calibration tools use the package's one
    # estimator.
    data = np.loadtxt(real_data('mpu6050_static_sunsided', 'mpu6050_static_10min.csv'),
                      delimiter=',', skiprows=1, usecols=0)
    stamps = np.round(data * 1e9).astype(np.int64)
    mean_rate = (stamps.size - 1) / ((stamps[-1] - stamps[0]) / 1e9)
    assert records.rate_from_stamps(stamps[:65536], 'mpu6050') == pytest.approx(mean_rate,
                                                                                rel=0.01)
