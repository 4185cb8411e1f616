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

"""Thermal simulator: profile, lag and hysteresis against closed forms, noise, determinism."""

from dataclasses import replace
import json

from gyro_noise_ros.bag import ImuBagReader
from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.simulate import gauss_markov_avar
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.simulate import (gyro_noise_rad_s, OvenProfile, resolve_timing,
                                             simulate_run, ThermalModel, ThermalStream,
                                             write_train_test)
from gyro_noise_ros.units import DEG_TO_RAD, MG_TO_M_S2, STANDARD_GRAVITY_M_S2
import numpy as np
import pytest


def _slow_lag_play(t, u, tau, r):
    """Twin of the kernel: the exact ramp response written segment by segment, then play."""
    y = np.empty(t.size)
    z = np.empty(t.size)
    y[0] = z[0] = u[0]
    for k in range(1, t.size):
        h = t[k] - t[k - 1]
        s = (u[k] - u[k - 1]) / h
        # error from the moving equilibrium u - s tau decays with exp(-h / tau)
        err0 = y[k - 1] - (u[k - 1] - s * tau)
        y[k] = u[k] - s * tau + err0 * np.exp(-h / tau)
        z[k] = min(max(z[k - 1], y[k] - r), y[k] + r)
    return y, z


def test_profile_is_the_papers_experiment():
    times, temps = OvenProfile().breakpoints()
    levels = temps[1::2]
    # room, 60, then 50 .. -40 in 10 degC steps (paper 002 section 4.1)
    np.testing.assert_array_equal(levels, [25, 60, 50, 40, 30, 20, 10, 0, -10, -20, -30, -40])
    holds = np.diff(times)[0::2]
    np.testing.assert_allclose(holds, 3600.0)
    # 12 one-hour holds, 35 degC at 2 degC/min, 10 steps of 10 degC at 1 degC/min
    assert OvenProfile().duration_s == pytest.approx(12 * 3600 + 35 * 30 + 100 * 60)


def test_resolve_timing():
    p = OvenProfile()
    assert resolve_timing(p) == (p.duration_s, 1.0)
    assert resolve_timing(p, hours=2.0) == pytest.approx((7200.0, p.duration_s / 7200.0))
    assert resolve_timing(p, compress=10.0) == pytest.approx((p.duration_s / 10.0, 10.0))
    assert resolve_timing(p, hours=1.0, compress=60.0) == (3600.0, 60.0)
    with pytest.raises(ParameterError, match='hours'):
        resolve_timing(p, hours=0.0)


def test_lag_is_the_first_order_ramp_response():
    profile = OvenProfile(room_c=20.0, peak_c=30.0, low_c=10.0, step_c=20.0, hold_s=100.0,
                          heat_rate_c_s=0.1, cool_rate_c_s=0.1)
    model = ThermalModel(tau_die_s=30.0, self_heating_c=0.0, hysteresis_half_width_c=0.0)
    stream = ThermalStream(model, profile)
    t = np.arange(0.0, 300.0, 0.5)
    die = stream.step(t).die_c
    tau, s = 30.0, 0.1
    # closed forms: equilibrium before the ramp, u - s tau (1 - e^{-(t-100)/tau}) on it, and an
    # exponential approach to 30 degC after it ends at t = 200 s
    ramp = 20.0 + s * (t - 100) - s * tau * (1 - np.exp(-(t - 100) / tau))
    expected = np.where(t <= 100, 20.0, ramp)
    lag_end = s * tau * (1 - np.exp(-100.0 / tau))
    after = t >= 200
    expected[after] = 30.0 - lag_end * np.exp(-(t[after] - 200) / tau)
    np.testing.assert_allclose(die, expected, atol=1e-9)


def test_kernel_matches_slow_twin_and_batching_does_not_matter():
    profile = OvenProfile(hold_s=60.0, heat_rate_c_s=1.0, cool_rate_c_s=0.5)
    model = ThermalModel(tau_die_s=20.0, hysteresis_half_width_c=1.5)
    t = np.arange(0.0, profile.duration_s, 0.25)
    whole = ThermalStream(model, profile).step(t)
    u = whole.oven_c + model.self_heating_c
    y, z = _slow_lag_play(t, u, 20.0, 1.5)
    np.testing.assert_allclose(whole.die_c, y, atol=1e-10)
    np.testing.assert_allclose(whole.played_c, z, atol=1e-10)
    stream = ThermalStream(model, profile)
    cuts = np.sort(np.random.default_rng(0).choice(t.size, 40, replace=False))
    parts = [stream.step(chunk) for chunk in np.split(t, cuts)]
    np.testing.assert_array_equal(np.concatenate([p.die_c for p in parts]), whole.die_c)
    np.testing.assert_array_equal(np.concatenate([p.bias_rad_s for p in parts]), whole.bias_rad_s)
    # the die rate is exact: it matches the slope of the die temperature. A central difference
    # is off by up to h |jump of y''| / 4 where the oven slope changes: 0.25 * (1 / 20) / 4.
    mid = np.gradient(whole.die_c, t)
    np.testing.assert_allclose(whole.die_rate_c_s[1:-1], mid[1:-1], atol=4e-3)


def test_hysteresis_is_a_loop_of_height_2hr():
    r = 2.0
    model = ThermalModel(hysteresis_half_width_c=r)
    th = ThermalStream(model, compress=20.0).step(np.arange(0, 2600.0, 0.5))
    diff = th.played_c - th.die_c
    assert np.all(np.abs(diff) <= r + 1e-12)
    heating = th.die_rate_c_s > 1e-3
    cooling = th.die_rate_c_s < -1e-3
    # Once the die has moved 2r since a reversal, z trails it by exactly r.
    assert np.mean(np.isclose(diff[heating], -r)) > 0.8
    assert np.mean(np.isclose(diff[cooling], r)) > 0.8
    # The bias law, term by term, written out independently.
    d = th.die_c - model.t_ref_c
    for i in range(3):
        expected = (np.asarray(model.bias_dps)[i] + np.asarray(model.lin_dps_per_c)[i] * d
                    + np.asarray(model.quad_dps_per_c2)[i] * d ** 2
                    + np.asarray(model.cubic_dps_per_c3)[i] * d ** 3
                    + np.asarray(model.knee_dps)[i] * np.tanh((th.die_c - 5.0) / 8.0)
                    + np.asarray(model.gradient_dps_per_c_s)[i] * th.die_rate_c_s / 20.0
                    + np.asarray(model.hysteresis_dps_per_c)[i] * diff)
        np.testing.assert_allclose(th.bias_rad_s[:, i] / DEG_TO_RAD, expected, atol=1e-12)
        accel = (np.asarray(model.accel_bias_mg)[i] + np.asarray(model.accel_lin_mg_per_c)[i] * d
                 + np.asarray(model.accel_quad_mg_per_c2)[i] * d ** 2
                 + np.asarray(model.accel_cubic_mg_per_c3)[i] * d ** 3)
        np.testing.assert_allclose(th.accel_bias_m_s2[:, i] / MG_TO_M_S2, accel, atol=1e-12)
    off = ThermalStream(replace(model, hysteresis_half_width_c=0.0), compress=20.0)
    th_off = off.step(np.arange(0, 2600.0, 0.5))
    np.testing.assert_array_equal(th_off.played_c, th_off.die_c)


def test_compression_is_a_time_scaling():
    model = ThermalModel()
    slow = ThermalStream(model).step(np.arange(0, 20000.0, 10.0))
    fast = ThermalStream(model, compress=10.0).step(np.arange(0, 2000.0, 1.0))
    np.testing.assert_allclose(fast.die_c, slow.die_c, atol=1e-9)
    np.testing.assert_allclose(fast.bias_rad_s, slow.bias_rad_s, atol=1e-12)
    np.testing.assert_allclose(fast.die_rate_c_s, 10.0 * slow.die_rate_c_s, atol=1e-9)


def test_gauss_markov_floor():
    model = ThermalModel()
    qm = model.gauss_markov_std_dps()
    taus = np.logspace(-1, 5, 2000)
    adev = np.sqrt(sum(gauss_markov_avar(taus, qm, t) for t in model.bi_corr_times_s))
    assert adev.max() == pytest.approx(0.664 * model.bias_instability_dps, rel=1e-3)


def test_gyro_noise_allan_matches_closed_form():
    model = ThermalModel(bias_instability_dps=0.01, bi_corr_times_s=(2.0, 20.0))
    rate = 10.0
    noise = gyro_noise_rad_s(400_000, rate, model, np.random.default_rng(5)) / DEG_TO_RAD
    qm = model.gauss_markov_std_dps()
    # variance: white N^2 fs plus q^2 per Gauss-Markov process; the GM part has only ~ 3 x 40000 /
    # (2 x 20) independent values, so its share scatters by ~2 %: 5 % on the total is > 2 sigma
    assert np.var(noise) == pytest.approx(model.arw_dps_rthz ** 2 * rate + 2 * qm * qm, rel=0.05)
    res = allan_deviation(noise[:, 0], rate, taus=np.array([1, 10, 100, 1000]))
    theory = (model.arw_dps_rthz ** 2 / res.tau_s
              + sum(gauss_markov_avar(res.tau_s, qm, t) for t in model.bi_corr_times_s))
    # 40000 s of data: at tau = 100 s the overlapping estimator has ~ 300 equivalent degrees of
    # freedom (8 % 1-sigma on the deviation), at 1000 s about 30 (~13 %); 30 % is > 2 sigma there.
    np.testing.assert_allclose(res.adev, np.sqrt(theory), rtol=0.3)


def test_simulate_run_is_deterministic_and_sensor_is_quantised():
    a, ta = simulate_run(rng=np.random.default_rng(7), hours=0.2, rate_hz=50.0)
    b, _ = simulate_run(rng=np.random.default_rng(7), hours=0.2, rate_hz=50.0)
    c, tc = simulate_run(rng=np.random.default_rng(8), hours=0.2, rate_hz=50.0)
    np.testing.assert_array_equal(a.gyro_rad_s, b.gyro_rad_s)
    np.testing.assert_array_equal(a.temperature_c, b.temperature_c)
    assert not np.array_equal(a.gyro_rad_s, c.gyro_rad_s)
    lsb = 1.0 / 256.0
    np.testing.assert_array_equal(ta.temperature_reading_c / lsb,
                                  np.round(ta.temperature_reading_c / lsb))
    # readings are the die plus N(0, 0.02^2) then rounding (LSB^2/12 adds ~0.4 % variance);
    # ~1800 readings give a 2-sigma scatter of ~3.5 % on the standard deviation
    err = ta.temperature_reading_c - ta.die_c[ta.temperature_index]
    assert np.std(err) == pytest.approx(np.hypot(0.02, lsb / np.sqrt(12)), rel=0.07)
    np.testing.assert_allclose(a.gyro_rad_s, ta.drift_rad_s + ta.noise_rad_s)
    gravity = np.array([0.0, 0.0, STANDARD_GRAVITY_M_S2])
    np.testing.assert_allclose(a.accel_m_s2, gravity + ta.accel_drift_m_s2 + ta.accel_noise_m_s2)
    # accelerometer white noise: density 70 ug/sqrt(Hz) over the 25-Hz Nyquist band; 9000 x 3
    # samples give a 2-sigma scatter of ~1 % on the standard deviation
    assert np.std(ta.accel_noise_m_s2) == pytest.approx(70e-6 * STANDARD_GRAVITY_M_S2 * 5.0,
                                                        rel=0.03)
    assert a.temperature_c.shape == a.t_s.shape and a.rate_hz == 50.0
    assert ta.compress == pytest.approx(OvenProfile().duration_s / 720.0)
    # the runs differ in room temperature and turn-on bias, not in the device
    assert ta.room_c != tc.room_c


def test_train_test_bags_hold_the_runs(tmp_path):
    train, test = write_train_test(tmp_path, seed=11, hours=0.05, rate_hz=40.0)
    again = write_train_test(tmp_path / 'again', seed=11, hours=0.05, rate_hz=40.0)
    truth = np.load(tmp_path / 'train_truth.npz')
    with ImuBagReader(train) as reader:
        assert reader.topic == '/imu/data_raw'
        assert reader.temperature_topic == '/imu/temperature'
        gyro = np.concatenate([b.gyro for b in reader.iter_batches()])
        stamps, temps = reader.read_temperature()
    np.testing.assert_array_equal(gyro, truth['drift_rad_s'] + truth['noise_rad_s'])
    with ImuBagReader(train) as reader:
        accel = np.concatenate([b.accel for b in reader.iter_batches()])
    np.testing.assert_allclose(accel - [0.0, 0.0, STANDARD_GRAVITY_M_S2],
                               truth['accel_drift_m_s2'] + truth['accel_noise_m_s2'], atol=1e-12)
    np.testing.assert_array_equal(temps, truth['temperature_reading_c'])
    # one Temperature message per round(40 / 52) = 1 Imu message
    assert temps.size == gyro.shape[0]
    with ImuBagReader(test) as reader:
        gyro_test = np.concatenate([b.gyro for b in reader.iter_batches()])
    assert not np.array_equal(gyro, gyro_test)
    with ImuBagReader(again[0]) as reader:
        same = np.concatenate([b.gyro for b in reader.iter_batches()])
    np.testing.assert_array_equal(same, gyro)
    settings = json.loads((tmp_path / 'simulation.json').read_text())
    assert settings['seed'] == 11 and settings['model']['tau_die_s'] == 600.0


def test_bad_arguments():
    with pytest.raises(ParameterError, match='rng'):
        simulate_run(rng=3)
    with pytest.raises(ParameterError, match='tau_die_s'):
        ThermalStream(ThermalModel(tau_die_s=0.0))
    with pytest.raises(ParameterError, match='non-decreasing'):
        ThermalStream().step([2.0, 1.0])
