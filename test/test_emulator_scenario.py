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
The emulator's reliability scenario (paper 001 procedure with no hardware).

Gravity follows the six positions, the errors are configurable, the stress widens the
bias-instability interval, and bags come out without pacing.
"""

import json

from gyro_noise_ros.calibration.emulate import (PAPER_BEFORE_BIAS_MG, PAPER_BEFORE_SCALE_PCT,
                                                SixPosition)
from gyro_noise_ros.calibration.interval import bias_instability_interval
from gyro_noise_ros.calibration.sixpos import normal_gravity
from gyro_noise_ros.cli import _scenario
from gyro_noise_ros.cli.calibrate import main as calibrate
from gyro_noise_ros.cli.emulator import board_from_args, build_parser
from gyro_noise_ros.cli.emulator import main as emulator
from gyro_noise_ros.cli.excitation import main as excitation
from gyro_noise_ros.units import MG_TO_M_S2
import numpy as np
import pytest

QUIET = ['--accel-bias-instability-ug', '0', '--accel-random-walk-ug-sqrt-s', '0',
         '--gyro-bias-instability-dps', '0', '--gyro-random-walk-dps-sqrt-s', '0']


def test_gravity_follows_the_dwells_and_rotations_have_rate():
    args = ['--odr-hz', '104', '--scenario', 'six-position', '--dwell-s', '10', '--move-s', '4',
            '--lead-s', '0'] + QUIET
    board = board_from_args(args)
    board.next_samples(int(104 * 85))
    truth = board.last_truth
    errors = board.scenario.errors
    g = normal_gravity(45.0)
    motion = SixPosition(dwell_s=10, move_s=4, lead_s=0)
    for orientation, t0, t1 in motion.schedule():
        sel = (truth.time_s > t0 + 1) & (truth.time_s < t1 - 1)
        mean = truth.accel_m_s2[sel].mean(axis=0)
        i = 'xyz'.index(orientation[1])
        sign = 1.0 if orientation[0] == '+' else -1.0
        up = np.zeros(3)
        up[i] = sign * g
        expected = errors.accel_matrix @ up + errors.accel_bias_m_s2
        # 0.5 mg of white noise per sample over ~830 samples: 0.02 mg; 0.3 mg is > 10 sigma
        np.testing.assert_allclose(mean, expected, atol=3e-3)
    moving = (truth.time_s > 10.5) & (truth.time_s < 13.5)
    # a half turn in 4 s with a (1 - cos) profile peaks at pi * pi / (2 * 4) = 1.23 rad/s
    peak = np.abs(truth.gyro_rad_s[moving]).max()
    assert peak == pytest.approx(np.pi ** 2 / 8, rel=0.05)


def test_without_scenario_the_board_is_unchanged():
    a = board_from_args(['--seed', '3']).next_samples(500)
    parser = build_parser()
    args = parser.parse_args(['--seed', '3'])
    assert args.scenario is None
    b = board_from_args(args).next_samples(500)
    assert np.array_equal(a, b)


def test_write_bag_and_calibrate_recover_table6(tmp_path, capsys):
    bag = tmp_path / 'six'
    assert emulator(['--odr-hz', '104', '--seed', '5', '--scenario', 'six-position',
                     '--dwell-s', '20', '--write-bag', str(bag)] + QUIET) == 0
    out = tmp_path / 'cal'
    assert calibrate([str(bag), '--latitude', '45', '--out', str(out)]) == 0
    doc = json.loads((out / 'calibration.json').read_text())
    # quantised (0.12 mg LSB) white noise of 0.5 mg per sample, ~1900 samples per dwell:
    # s.e. of b ~0.008 mg, of S ~0.0008 %; 0.05 mg and 0.005 % are > 5 sigma
    np.testing.assert_allclose(np.asarray(doc['accel']['bias_m_s2']) / MG_TO_M_S2,
                               PAPER_BEFORE_BIAS_MG, atol=0.05)
    np.testing.assert_allclose(np.asarray(doc['accel']['scale_factor']) * 100,
                               PAPER_BEFORE_SCALE_PCT, atol=0.005)
    mis = np.asarray(doc['accel']['misalignment']) * 100
    expected = np.zeros((3, 3))
    expected[~np.eye(3, dtype=bool)] = _scenario.DEFAULT_MISALIGNMENT_PCT
    np.testing.assert_allclose(mis, expected, atol=0.005)
    # the board's default gyro bias (0.775, -0.35, 0.25) deg/s; Earth rate cancels
    np.testing.assert_allclose(np.degrees(doc['gyro']['bias_rad_s']), [0.775, -0.35, 0.25],
                               atol=0.02)
    assert emulator(['--scenario', 'six-position', '--write-bag', str(bag)]) == 6  # in the way
    assert emulator(['--scenario', 'static', '--write-bag', str(tmp_path / 'x')]) == 2


def test_write_bag_sweep_has_a_reference_topic(tmp_path):
    bag = tmp_path / 'sweep'
    assert emulator(['--odr-hz', '104', '--scenario', 'sweep', '--excite-axis', 'y',
                     '--excite-hz', '5', '--sweep-to-hz', '10', '--accel-scale-pct', '2,2,2',
                     '--duration-s', '42', '--write-bag', str(bag)]) == 0
    out = tmp_path / 'exc'
    assert excitation([str(bag), '--topic', '/imu/data_raw', '--sensor', 'accel', '--axis', 'y',
                       '--sweep', '5', '10', '0.5', '--reference-topic', '/shaker/imu',
                       '--no-figures', '--out', str(out)]) == 0
    doc = json.loads((out / 'excitation.json').read_text())
    dev = np.array(doc['before']['deviation_up'] + doc['before']['deviation_down'], float)
    # a +2 % scale factor on y is what the reference comparison must show
    np.testing.assert_allclose(dev, 0.02, atol=0.006)


def test_default_stress_factor_gives_the_papers_125_percent():
    # IEEE 952 model of the default levels: N white, plateau N/2, K = N / 11.5 (relative units)
    tau = np.logspace(-2, 5, 4000)

    def width(plateau):
        k = _scenario.RANDOM_WALK_PER_WHITE
        adev = np.sqrt(1.0 / tau + plateau ** 2 + k ** 2 * tau / 3.0)
        return bias_instability_interval(tau, adev).width_s

    before = width(0.5)
    after = width(0.5 * _scenario.DEFAULT_STRESS_INSTABILITY)
    assert before == pytest.approx(420.0, rel=0.15)        # paper: 420 s
    assert after / before - 1.0 == pytest.approx(1.25, abs=0.1)


def test_write_bag_multi_pose_and_a_tilted_six_position(tmp_path, capsys):
    # the multi-pose scenario: arbitrary attitudes, |a| = g fit, gyro from the turns
    bag = tmp_path / 'multi'
    assert emulator(['--odr-hz', '104', '--seed', '6', '--scenario', 'multi-pose', '--poses',
                     '12', '--dwell-s', '15', '--gyro-scale-pct', '0.3,-0.2,0.1',
                     '--write-bag', str(bag)] + QUIET) == 0
    out = tmp_path / 'cal'
    assert calibrate([str(bag), '--mode', 'multi-pose', '--latitude', '45', '--out',
                      str(out)]) == 0
    doc = json.loads((out / 'calibration.json').read_text())
    assert doc['mode'] == 'multi-pose' and len(doc['dwells']) == 12
    # quantised white noise only: b within 0.05 mg, S within 0.005 % (> 5 sigma, as above)
    np.testing.assert_allclose(np.asarray(doc['accel']['bias_m_s2']) / MG_TO_M_S2,
                               PAPER_BEFORE_BIAS_MG, atol=0.05)
    np.testing.assert_allclose(np.asarray(doc['accel']['scale_factor']) * 100,
                               PAPER_BEFORE_SCALE_PCT, atol=0.005)
    sf, sig = (np.asarray(doc['gyro'][k]) for k in ('scale_factor', 'scale_factor_sigma'))
    assert np.all(np.abs(sf - [0.003, -0.002, 0.001]) < 4 * sig)
    # a six-position fixture with its +y dwell tilted by 4 deg: named, refused
    bag = tmp_path / 'tilt'
    assert emulator(['--odr-hz', '104', '--seed', '7', '--scenario', 'six-position',
                     '--dwell-s', '20', '--tilt', '+y:4', '--write-bag', str(bag)] + QUIET) == 0
    capsys.readouterr()
    assert calibrate([str(bag), '--latitude', '45', '--out', str(tmp_path / 'c2')]) == 4
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'dwell +y at t=' in err and 'deg off' in err


def test_bad_scenario_options_leave_nothing_behind(tmp_path, capsys):
    # a bad --orientation fails before any bag folder exists (a retry must not find one), an
    # excitation at or above Nyquist is a bad option: exit 2, one line
    bag = tmp_path / 'static'
    assert emulator(['--scenario', 'static', '--orientation', 'up', '--duration-s', '2',
                     '--write-bag', str(bag)]) == 2
    assert list(tmp_path.iterdir()) == []
    for extra in (['--scenario', 'sine', '--excite-hz', '60'],
                  ['--scenario', 'sweep', '--excite-hz', '5', '--sweep-to-hz', '52']):
        capsys.readouterr()
        assert emulator(['--odr-hz', '104', '--duration-s', '2', '--write-bag',
                         str(tmp_path / 'x')] + extra) == 2
        err = capsys.readouterr().err
        assert 'Nyquist (52 Hz' in err and 'Traceback' not in err
    assert list(tmp_path.iterdir()) == []
    # the retry with a good orientation works, and the bag's storage file has the bag's name
    assert emulator(['--scenario', 'static', '--orientation=-z', '--odr-hz', '104',
                     '--duration-s', '2', '--write-bag', str(bag)]) == 0
    assert sorted(p.name for p in bag.iterdir()) == ['metadata.yaml', 'static.db3']
    assert [p.name for p in tmp_path.iterdir()] == ['static']
