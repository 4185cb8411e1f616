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


"""Thermal profile shapes, the train/test pair and the least-squares oracle."""

from dataclasses import replace

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.hysteresis import play_operator
from gyro_noise_ros.thermal.oracle import (fit_oracle, measured_terms, oracle_residual,
                                           true_terms)
from gyro_noise_ros.thermal.simulate import (make_profile, ShapeProfile, SHAPES, simulate_pair,
                                             ThermalModel)
from gyro_noise_ros.units import DEG_TO_RAD
import numpy as np
import pytest

#: A device without noise of any kind: the oracle must then be exact.
QUIET = ThermalModel(temp_noise_c=0.0, temp_lsb_c=0.0, arw_dps_rthz=0.0,
                     bias_instability_dps=0.0, turn_on_bias_dps=0.0, room_spread_c=0.0,
                     accel_noise_ug_rthz=0.0)


def _levels(profile):
    """Return the set-points held (consecutive equal breakpoints)."""
    t, u = profile.breakpoints()
    return [u[k] for k in range(1, u.size) if u[k] == u[k - 1] and t[k] > t[k - 1]]


def test_shapes_set_points():
    h, lo, hi = 1800.0, 10.0, 50.0
    ramp = (hi - lo) * 60.0  # 1 degC/min
    t, u = make_profile('heating').breakpoints()
    np.testing.assert_array_equal(u, [lo, lo, hi, hi])
    np.testing.assert_allclose(np.diff(t), [h, ramp, h])
    t, u = make_profile('cooling').breakpoints()
    np.testing.assert_array_equal(u, [hi, hi, lo, lo])
    assert _levels(make_profile('staircase')) == [10, 20, 30, 40, 50]
    assert _levels(make_profile('staircase_down', steps=2)) == [50, 30, 10]
    assert _levels(make_profile('cycle', cycles=2)) == [10, 50, 10, 50, 10]
    assert _levels(make_profile('cool_reheat')) == [50, 10, 50]
    t, u = make_profile('soak').breakpoints()
    np.testing.assert_array_equal(u, [lo, lo, hi, hi])
    # the jump is 20 x faster than the ramp, then three holds
    np.testing.assert_allclose(np.diff(t), [60.0, ramp / 20.0, 3 * h])
    sine = make_profile('sine', period_s=1000.0)
    t, u = sine.breakpoints()
    assert t[-1] == 2000.0 and u[0] == 30.0
    # breakpoints lie on the sine; between them the set-point is linear (< 0.12 % off)
    tt = np.linspace(0, 2000, 5001)
    err = sine.temperature_c(tt) - (30 + 20 * np.sin(2 * np.pi * tt / 1000))
    assert np.max(np.abs(err)) < 20 * (1 - np.cos(np.pi / 64)) + 1e-9
    shifted = make_profile('cooling').shifted(-1.5)
    np.testing.assert_array_equal(shifted.breakpoints()[1], [48.5, 48.5, 8.5, 8.5])
    np.testing.assert_array_equal(make_profile('cooling').starting_at(30).breakpoints()[1],
                                  [30, 30, -10, -10])
    assert set(SHAPES) == {'oven', *(s for s in SHAPES if s != 'oven')}
    for shape in SHAPES:
        profile = make_profile(shape)
        assert profile.shape == shape and profile.duration_s > 0


def test_bad_profiles():
    with pytest.raises(ParameterError, match='unknown thermal profile'):
        make_profile('wobble')
    with pytest.raises(ParameterError, match='no option'):
        make_profile('heating', peak_c=3)
    with pytest.raises(ParameterError, match='low_c < high_c'):
        make_profile('cooling', low_c=50, high_c=10)
    with pytest.raises(ParameterError, match='steps'):
        ShapeProfile(shape='staircase', steps=0).breakpoints()
    with pytest.raises(ParameterError, match='finite'):
        make_profile('sine', period_s=float('nan'))


def test_pair_shares_the_device_and_the_compression():
    pair = simulate_pair(seed=4, rate_hz=5.0, hours=0.2, profile=make_profile('heating'),
                         test_profile=make_profile('cycle'))
    (label_a, train, ta), (label_b, test, tb) = pair
    assert (label_a, label_b) == ('train', 'test')
    assert ta.shape == 'heating' and tb.shape == 'cycle'
    assert ta.compress == tb.compress == pytest.approx(6000.0 / 720.0)
    # the test run is its whole profile at the training compression
    assert test.t_s[-1] == pytest.approx(10200.0 / ta.compress - 0.2, abs=1e-6)
    # heating rises monotonically (after its hold); the cycle goes up and comes back down
    assert ta.die_c[-1] > ta.die_c[0] + 30 and abs(tb.die_c[-1] - tb.die_c[0]) < 3
    assert tb.die_rate_c_s.min() < -0.05 and ta.die_rate_c_s.min() > -1e-6
    replicate = simulate_pair(seed=4, rate_hz=5.0, hours=0.2, profile=make_profile('heating'))
    assert replicate[1][2].shape == 'heating'
    assert replicate[1][1].t_s.size == train.t_s.size
    np.testing.assert_array_equal(replicate[0][1].gyro_rad_s, train.gyro_rad_s)


def test_play_operator_matches_its_definition():
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.standard_normal(500))
    z = play_operator(x, 2.0, start=0.5)
    prev, slow = 0.5, []
    for v in x:
        prev = min(max(prev, v - 2.0), v + 2.0)
        slow.append(prev)
    np.testing.assert_array_equal(z, slow)
    np.testing.assert_array_equal(play_operator(x, 0.0), x)


def _pair(model, seed=2, train='staircase', test='cool_reheat'):
    return simulate_pair(seed=seed, rate_hz=5.0, hours=0.5, model=model,
                         profile=make_profile(train), test_profile=make_profile(test))


def test_oracle_is_exact_without_noise():
    (_, train, ta), (_, test, tb) = _pair(QUIET)
    oracle = fit_oracle(true_terms(ta, QUIET), train.gyro_rad_s)
    assert oracle.rank == 7
    # the fitted coefficients are the law's, to the conditioning of a 7-term polynomial basis
    np.testing.assert_allclose(oracle.coef / DEG_TO_RAD, QUIET.bias_coefficients_dps(), rtol=1e-6,
                               atol=1e-10)
    residual = oracle_residual(train, ta, test, tb, QUIET)
    assert np.max(np.abs(residual)) < 1e-9
    # the terms are the law: drift == terms @ coefficients
    np.testing.assert_allclose(true_terms(tb, QUIET) @ QUIET.bias_coefficients_dps() * DEG_TO_RAD,
                               tb.drift_rad_s, atol=1e-15)


def test_oracle_is_plain_least_squares():
    model = ThermalModel()
    (_, train, ta), (_, test, tb) = _pair(model)
    a_train, a_test = true_terms(ta, model), true_terms(tb, model)
    oracle = fit_oracle(a_train, train.gyro_rad_s)
    # slow twin: the normal equations on the unscaled basis, solved in long double precision
    ata = (a_train.T.astype(np.longdouble) @ a_train.astype(np.longdouble))
    aty = a_train.T.astype(np.longdouble) @ train.gyro_rad_s.astype(np.longdouble)
    coef = np.linalg.solve(ata.astype(float), aty.astype(float))
    # residual drift depends on the prediction; both solve the same well-posed problem, to the
    # conditioning of the unscaled normal equations (~1e11 here, so ~1e-5 relative)
    np.testing.assert_allclose(a_test @ oracle.coef, a_test @ coef, rtol=0, atol=1e-6 * DEG_TO_RAD)
    with pytest.raises(ParameterError):
        fit_oracle(a_train[:3], train.gyro_rad_s[:3])


def test_measured_terms_use_what_a_method_sees():
    model = replace(QUIET, temp_noise_c=0.0)
    (_, train, ta), _ = _pair(model)
    meas = measured_terms(train, model, compress=ta.compress)
    true = true_terms(ta, model)
    # the temperature columns are the reading, exact here (no noise, no LSB, read each sample)
    np.testing.assert_allclose(meas[:, :5], true[:, :5], atol=1e-12)
    # the rate is the 10-s trailing slope: it lags the true rate by about 5 s, so it is close
    # but not equal (the die's rate changes on its time constant tau / X ~ 200 s)
    scale = np.max(np.abs(true[:, 5]))
    assert np.max(np.abs(meas[:, 5] - true[:, 5])) < 0.15 * scale
    assert np.max(np.abs(meas[:, 5] - true[:, 5])) > 1e-4 * scale
    # the hysteresis state: the play on the measured (here exact) temperature, started at T[0]
    np.testing.assert_allclose(meas[:, 6], true[:, 6], atol=1e-9)
