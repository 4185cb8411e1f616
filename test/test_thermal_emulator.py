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

"""The Portenta emulator's thermal option follows the thermal model sample for sample."""

from gyro_noise_ros.cli import emulator as cli
from gyro_noise_ros.link import lsm6dso32 as lsm
from gyro_noise_ros.link.emulator import BoardModel
from gyro_noise_ros.thermal.simulate import ThermalModel, ThermalStream
from gyro_noise_ros.units import DEG_TO_RAD
import numpy as np
import pytest


class _Zero:

    def generate(self, n):
        return np.zeros(n)


def _board(thermal, **kwargs):
    return BoardModel(rng=np.random.default_rng(3), noise=[_Zero(), _Zero(), _Zero()],
                      accel_noise_ug_rthz=0.0, odr_hz=104.0, gyro_fs_dps=125, thermal=thermal,
                      **kwargs)


def test_board_bias_and_temperature_are_the_models():
    model = ThermalModel(bias_dps=0.0)
    board = _board(ThermalStream(model, compress=500.0, room_c=22.0), bias_dps=(0.1, 0.2, 0.3))
    twin = ThermalStream(model, compress=500.0, room_c=22.0)
    samples = [board.next_samples(1000) for _ in range(10)]
    truth_gyro = board.last_truth.gyro_rad_s
    t = np.arange(10_000) / 104.0
    expected = twin.step(t)
    offset = np.array([0.1, 0.2, 0.3]) * DEG_TO_RAD
    np.testing.assert_allclose(truth_gyro, expected.bias_rad_s[-1000:] + offset, atol=1e-15)
    np.testing.assert_array_equal(board.last_truth.temperature_c, expected.die_c[-1000:])
    read = lsm.temperature_c(np.concatenate([s['temp'] for s in samples]))
    # the word is die + N(0, 0.02^2) rounded to 1/256 degC: 5 sigma plus half an LSB
    assert np.max(np.abs(read - expected.die_c)) < 5 * 0.02 + 0.5 / 256
    assert np.std(read - expected.die_c) > 0.01
    # compressed 500 x, 96 s cover the room hold and the heat to 60 degC (+2 self-heating)
    assert expected.die_c[0] == 24.0 and expected.die_c.max() > 55.0


def test_board_with_thermal_does_not_depend_on_batch_sizes():
    a = _board(ThermalStream(compress=300.0))
    b = _board(ThermalStream(compress=300.0))
    whole = a.next_samples(3000)
    parts = np.concatenate([b.next_samples(k) for k in (1, 999, 17, 1983)])
    np.testing.assert_array_equal(whole, parts)
    # an overrun moves the die on too: the next sample matches a board that read them all
    c = _board(ThermalStream(compress=300.0))
    c.next_samples(1000)
    c.sensor_overrun(500)
    after = c.next_samples(1500)
    np.testing.assert_array_equal(after['gyro'], whole['gyro'][1500:])
    np.testing.assert_array_equal(after['temp'], whole['temp'][1500:])


def test_cli_option_builds_the_oven_board():
    off = cli.board_from_args(['--odr-hz', '104'])
    assert off.thermal is None
    board = cli.board_from_args(['--thermal', 'oven', '--thermal-compress', '840', '--temp-c',
                                 '20', '--odr-hz', '104', '--bias-dps', '0', '--seed', '4'])
    assert board.thermal.compress == 840.0 and board.thermal.profile.room_c == 20.0
    n = int(board.thermal.duration_s * 104)
    samples = board.next_samples(n)
    temp = lsm.temperature_c(samples['temp'])
    # the oven goes 20 -> 60 -> -40 degC in ~60 s; the die follows 2 degC above it, lagging
    assert abs(temp[:100].mean() - 22.0) < 0.01
    assert temp.max() > 60.0 and temp[-100:].mean() < -36.0
    gyro = lsm.gyro_sensitivity_rad_s_per_lsb(2000) * samples['gyro'].astype(float) / DEG_TO_RAD
    twin = ThermalStream(ThermalModel(bias_dps=0.0), compress=840.0, room_c=20.0)
    bias = twin.step(np.arange(n) / 104.0).bias_rad_s / DEG_TO_RAD
    blocks = n // 104

    def block_means(x):
        return x[:blocks * 104].reshape(blocks, 104, 3).mean(1)

    # 1-s means of the paper-000 noise (0.058 deg/s per sample, dithering the 0.07 deg/s LSB)
    # scatter by ~0.006 deg/s; the thermal bias moves them by ~1 deg/s. With the model's bias
    # removed, only the noise is left.
    assert np.all(np.std(block_means(gyro), 0) > 0.1)
    assert np.all(np.std(block_means(gyro - bias), 0) < 0.015)


def test_cli_shapes_build_held_out_boards():
    for shape, first, last in (('cooling', 52.0, 12.0), ('heating', 12.0, 52.0),
                               ('cool_reheat', 52.0, 52.0)):
        board = cli.board_from_args(['--thermal', shape, '--thermal-compress', '200',
                                     '--odr-hz', '104', '--seed', '2'])
        assert board.thermal.profile.shape == shape
        n = int(board.thermal.duration_s * 104)
        samples = board.next_samples(n)
        temp = lsm.temperature_c(samples['temp'])
        # the shapes' own set-points (10..50 degC) plus 2 degC of self-heating. The die lags
        # the oven by tau / X = 3 s: at the end of a ramp by rate x tau = 10 degC, which the
        # last hold (9 s, three time constants) brings down to 10 e^-3 = 0.5 degC
        assert abs(temp[:50].mean() - first) < 0.05
        assert abs(temp[-50:].mean() - last) < 0.6
    # the accelerometer's offset change follows the die: the cooling board's 1-s means of x
    # fall by the model's 40 degC of c1 (0.1 mg/degC) = 4 mg, far above their 0.1 mg scatter
    board = cli.board_from_args(['--thermal', 'cooling', '--thermal-compress', '200',
                                 '--odr-hz', '104', '--seed', '2'])
    n = int(board.thermal.duration_s * 104)
    accel = board.next_samples(n)['accel'].astype(float) * lsm.accel_sensitivity_m_s2_per_lsb(
        board.accel_fs_g)
    first, last = accel[:104 * 5, 0].mean(), accel[-104 * 5:, 0].mean()
    model = ThermalModel()
    expected = (model.accel_bias_m_s2([12.0]) - model.accel_bias_m_s2([52.0]))[0, 0]
    assert last - first == pytest.approx(expected, abs=0.3e-3 * 9.80665)
