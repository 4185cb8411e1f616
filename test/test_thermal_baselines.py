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

"""Thermal baselines against closed forms, hand-written twins and known functions."""

import json

from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.thermal.baselines import (_fit_net, BASELINES, BPNetwork, EmdWtdSaBp,
                                              LinearTdT, RawMethod, simulated_annealing,
                                              TemperaturePolynomial, wavelet_denoise,
                                              WaveletThreshold, zero_crossing_hz)
from gyro_noise_ros.thermal.run import (RateWindowError, temperature_rate_c_s,
                                        ThermalMethod, ThermalRun)
from gyro_noise_ros.thermal.simulate import simulate_run
import numpy as np
import pytest


def _run(t, gyro, temp, name='synthetic'):
    return ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=1.0 / (t[1] - t[0]),
                      name=name)


def _temperature(t):
    # non-monotone, with holds and ramps, so T and dT are not collinear
    return 20.0 + 15.0 * np.sin(t / 400.0) + 5.0 * np.sin(t / 97.0)


@pytest.fixture(scope='module')
def sim_pair():
    train, _ = simulate_run(rng=np.random.default_rng(21), hours=0.25, rate_hz=20.0)
    test, truth = simulate_run(rng=np.random.default_rng(22), hours=0.25, rate_hz=20.0)
    return train, test, truth


def test_every_baseline_follows_the_protocol():
    assert set(BASELINES) == {'raw', 'wtd', 'bp', 'emd_wtd_sabp', 'poly3', 'linear_tdt'}
    for name, cls in BASELINES.items():
        m = cls()
        assert m.name == name and isinstance(m, ThermalMethod)
    assert [BASELINES[n].causal for n in ('raw', 'bp', 'poly3', 'linear_tdt')] == [True] * 4
    assert not WaveletThreshold.causal and not EmdWtdSaBp.causal


def test_poly3_recovers_a_cubic_and_clips_like_px4():
    t = np.arange(0.0, 3000.0, 0.5)
    temp = -10.0 + 60.0 * t / t[-1]
    coef = np.array([[0.01, 2e-4, -3e-6, 4e-8], [-0.02, 1e-4, 5e-6, -1e-8], [0.0, -3e-4, 0, 2e-8]])
    t_ref = 20.0   # PX4: midpoint of the training range, here (-10 + 50) / 2
    d = temp - t_ref
    gyro = np.column_stack([c[0] + c[1] * d + c[2] * d ** 2 + c[3] * d ** 3 for c in coef])
    m = TemperaturePolynomial()
    m.fit(_run(t, gyro, temp), rng=np.random.default_rng(0))
    assert (m.t_min_c, m.t_max_c, m.t_ref_c) == (-10.0, 50.0, 20.0)
    np.testing.assert_allclose(m.coef, coef, rtol=1e-7, atol=1e-13)
    np.testing.assert_allclose(m.apply(_run(t, gyro, temp)), 0.0, atol=1e-12)
    # beyond the calibration range the offset is held at the ends (PX4's documented formula);
    # stated in out_of_range and counted by methods.range_report, never silent
    assert 'held' in m.out_of_range
    out = m.drift_rad_s([-30.0, 80.0], [0.0, 0.0])
    np.testing.assert_allclose(out, m.drift_rad_s([-10.0, 50.0], [0.0, 0.0]), rtol=1e-12)


def _poly_truth(temp_c, rate_c_s):
    x, r = temp_c - 20.0, rate_c_s * 100.0
    return np.column_stack([1e-3 + 2e-4 * x - 3e-6 * x * x + 1e-7 * x ** 3 + 5e-3 * r,
                            -4e-4 * x + 2e-3 * r * r - 1e-4 * x * r,
                            1e-8 * x ** 3 + 1e-3 * r ** 3 + 3e-5 * x * x * r])


def _gradient_truth(temp_c, rate_c_s):
    x, r = temp_c - 20.0, rate_c_s * 100.0
    return np.column_stack([1e-3 + 2e-4 * x - 3e-6 * x * x + 1e-7 * x ** 3 + 5e-3 * r,
                            -4e-4 * x - 1e-4 * x * r, 1e-8 * x ** 3 + 3e-5 * x * x * r])


def test_linear_tdt_recovers_a_polynomial_in_t_and_dt():
    t = np.arange(0.0, 4000.0, 0.5)
    temp = _temperature(t)
    rate = temperature_rate_c_s(t, temp)
    full = LinearTdT(rate_degree=3)
    full.fit(_run(t, _poly_truth(temp, rate), temp), rng=np.random.default_rng(0))
    assert full.n_terms == 10
    # a polynomial of total degree 3 is identified on any in-range points (unisolvent here)
    probe_t = np.random.default_rng(1).uniform(temp.min(), temp.max(), 500)
    probe_r = np.random.default_rng(2).uniform(rate.min(), rate.max(), 500)
    np.testing.assert_allclose(full.drift_rad_s(probe_t, probe_r),
                               _poly_truth(probe_t, probe_r), atol=1e-12)
    # the default basis (cubic in T, dT with T dT and T^2 dT: 7 terms) identifies its own
    # family and extrapolates it: nothing is clipped beyond the trained range
    m = LinearTdT()
    assert m.n_terms == 7
    m.fit(_run(t, _gradient_truth(temp, rate), temp), rng=np.random.default_rng(0))
    far_t = np.array([temp.min() - 10.0, temp.max() + 10.0, 20.0])
    far_r = np.array([rate.min() * 3.0, rate.max() * 3.0, -rate.max() * 2.0])
    np.testing.assert_allclose(m.drift_rad_s(far_t, far_r), _gradient_truth(far_t, far_r),
                               atol=1e-11)
    assert 'extrapolated' in m.out_of_range


def test_linear_tdt_is_plain_least_squares_on_its_basis(sim_pair):
    train, test, _ = sim_pair
    m = LinearTdT()
    m.fit(train, rng=np.random.default_rng(0))
    # slow twin: the seven monomials written out, in degC and degC/s, solved by lstsq
    rate = temperature_rate_c_s(train.t_s, train.temperature_c)
    x, r = train.temperature_c - 20.0, rate * 100.0

    def design(x, r):
        return np.column_stack([np.ones_like(x), x, r, x * x, x * r, x ** 3, x * x * r])

    coef = np.linalg.lstsq(design(x, r), train.gyro_rad_s, rcond=None)[0]
    test_rate = temperature_rate_c_s(test.t_s, test.temperature_c)
    expected = test.gyro_rad_s - design(test.temperature_c - 20.0, test_rate * 100.0) @ coef
    # the same least-squares problem in another scaling: equal to its conditioning (~1e-10
    # rad/s here, against a drift of ~1e-2 rad/s)
    np.testing.assert_allclose(m.apply(test), expected, rtol=0, atol=1e-9)


def test_networks_continue_linearly_beyond_the_trained_box(sim_pair):
    train, _, _ = sim_pair
    for shortcut in (True, False):
        m = BPNetwork(epochs=300, shortcut=shortcut)
        m.fit(train, rng=np.random.default_rng(3))
        net = m.net
        lo, hi = net.x_min, net.x_max
        edge = np.array([[hi[0], lo[1]], [lo[0], hi[1]]])
        step = np.array([[4.0, -0.02], [-3.0, 0.01]])
        beyond = edge + step
        # the network part beyond the box is its value at the nearest point of the box plus
        # the gradient there (central differences, 1e-6 of the box) times the step out
        h = 1e-6 * (hi - lo)
        grad = np.stack([(net.network(edge + h * e) - net.network(edge - h * e)) / (2 * h[i])
                         for i, e in enumerate(np.eye(2))], axis=1)
        expected = net.network(edge) + np.einsum('ni,nio->no', step, grad)
        np.testing.assert_allclose(net.network(beyond), expected, rtol=1e-5, atol=1e-12)
        if shortcut:
            basis, coef = net.shortcut
            np.testing.assert_allclose(m.drift_rad_s(beyond[:, 0], beyond[:, 1]),
                                       net.network(beyond)
                                       + basis(beyond[:, 0], beyond[:, 1]) @ coef, atol=1e-15)
        else:
            assert net.shortcut is None


def _hand_haar_denoise(x, level):
    """Orthonormal Haar DWT, universal soft threshold from the finest level, inverse."""
    approx = x.copy()
    details = []
    for _ in range(level):
        even, odd = approx[0::2], approx[1::2]
        details.append((even - odd) / np.sqrt(2.0))
        approx = (even + odd) / np.sqrt(2.0)
    sigma = np.median(np.abs(details[0])) / 0.6745
    lam = sigma * np.sqrt(2.0 * np.log(x.size))
    for j in range(level - 1, -1, -1):
        d = np.sign(details[j]) * np.maximum(np.abs(details[j]) - lam, 0.0)
        up = np.empty(2 * approx.size)
        up[0::2] = (approx + d) / np.sqrt(2.0)
        up[1::2] = (approx - d) / np.sqrt(2.0)
        approx = up
    return approx


def test_wtd_matches_a_hand_written_haar_threshold():
    rng = np.random.default_rng(3)
    x = np.repeat([0.0, 1.0, -0.5, 2.0], 16) + 0.2 * rng.standard_normal(64)
    for mode in ('periodization', 'symmetric'):
        got = wavelet_denoise(x, wavelet='haar', level=3, mode=mode)
        np.testing.assert_allclose(got, _hand_haar_denoise(x, 3), atol=1e-12)
    m = WaveletThreshold(wavelet='haar', level=3)
    gyro = np.column_stack([x, 2 * x, -x])
    out = m.apply(_run(np.arange(64.0), gyro, np.zeros(64)))
    np.testing.assert_allclose(out[:, 0], _hand_haar_denoise(x, 3), atol=1e-12)
    np.testing.assert_allclose(out[:, 1], _hand_haar_denoise(2 * x, 3), atol=1e-12)


def test_simulated_annealing_finds_a_known_minimum():
    centre = np.array([1.5, -2.0, 0.5])

    def bowl(x):
        return float(np.sum((x - centre) ** 2) + 0.3 * np.sum(1 - np.cos(3 * (x - centre))))

    best, f_best = simulated_annealing(bowl, np.zeros(3), np.random.default_rng(4),
                                       iterations=4000, step=1.0)
    # the cosine ripple puts local minima ~2 apart; the global one is at the centre, f = 0
    assert f_best < 1e-2
    np.testing.assert_allclose(best, centre, atol=0.1)


def _smooth_target(temp, rate):
    return np.column_stack([np.sin(temp / 8.0), 0.5 * np.tanh((temp - 20) / 5) + 40 * rate,
                            1e-3 * (temp - 20) ** 2])


def test_bp_network_learns_a_smooth_function():
    t = np.arange(0.0, 4000.0, 1.0)
    temp = _temperature(t)
    rate = temperature_rate_c_s(t, temp)
    y = _smooth_target(temp, rate)
    m = BPNetwork(epochs=3000)
    m.fit(_run(t, y, temp), rng=np.random.default_rng(5))
    err = m.drift_rad_s(temp, rate) - y
    # a 12-unit sigmoid layer fits these smooth surfaces to a few % of their spread
    assert np.all(np.sqrt(np.mean(err ** 2, 0)) < 0.05 * y.std(0))


def test_annealing_alone_trains_the_network():
    t = np.arange(0.0, 4000.0, 1.0)
    temp = _temperature(t)
    y = _smooth_target(temp, temperature_rate_c_s(t, temp))
    run = _run(t, y, temp)
    # the network alone (no linear shortcut), as the paper's SA-BP
    untrained = BPNetwork(epochs=0, shortcut=False)
    untrained.fit(run, rng=np.random.default_rng(6))
    x = np.column_stack([temp, temperature_rate_c_s(t, temp)])
    _, mse = _fit_net(x, y, 8, np.random.default_rng(6), sa_iterations=3000, epochs=0,
                      learning_rate=0.01, shortcut=False)
    # standardised MSE: random weights sit near 1 (they predict ~ nothing); annealing alone
    # (no gradient step) must get well below that
    assert untrained.train_mse > 0.3
    assert mse < 0.3 * untrained.train_mse


@pytest.mark.parametrize('cls', [RawMethod, TemperaturePolynomial, LinearTdT, BPNetwork])
def test_causal_apply_is_gyro_minus_drift(cls, sim_pair):
    train, test, _ = sim_pair
    m = cls()
    m.fit(train, rng=np.random.default_rng(7))
    window = getattr(m, 'rate_window_s', 10.0)
    drift = m.drift_rad_s(test.temperature_c,
                          temperature_rate_c_s(test.t_s, test.temperature_c, window_s=window))
    np.testing.assert_array_equal(m.apply(test), test.gyro_rad_s - drift)
    # only past samples matter: changing the future leaves the past output alone
    later = ThermalRun(t_s=test.t_s, gyro_rad_s=test.gyro_rad_s.copy(),
                       temperature_c=test.temperature_c.copy(), rate_hz=test.rate_hz)
    later.temperature_c[5000:] += 3.0
    later.gyro_rad_s[5000:] += 0.1
    np.testing.assert_array_equal(m.apply(later)[:5000], m.apply(test)[:5000])


@pytest.mark.parametrize('cls', [RawMethod, WaveletThreshold, TemperaturePolynomial, LinearTdT,
                                 BPNetwork])
def test_to_dict_from_dict_round_trip(cls, sim_pair):
    train, test, _ = sim_pair
    m = cls()
    m.fit(train, rng=np.random.default_rng(8))
    d = json.loads(json.dumps(m.to_dict()))
    assert d['method'] == cls.name and 'temperature_range_c' in d
    np.testing.assert_array_equal(cls.from_dict(d).apply(test), m.apply(test))


def test_temperature_models_remove_the_simulated_drift(sim_pair):
    train, test, truth = sim_pair
    raw = np.std(truth.drift_rad_s - truth.drift_rad_s.mean(0), 0)
    for cls in (TemperaturePolynomial, LinearTdT, BPNetwork):
        m = cls()
        m.fit(train, rng=np.random.default_rng(9))
        left = m.apply(test) - truth.noise_rad_s
        # the device's drift spans ~1 deg/s; every temperature model must leave < 10 % of it
        # (turn-on bias and room temperature differ between the runs, so not 0)
        assert np.all(np.std(left - left.mean(0), 0) < 0.1 * raw), cls.name


def test_emd_wtd_sabp_end_to_end():
    t = np.arange(0.0, 1200.0, 0.25)
    temp = 20.0 + 10.0 * np.tanh((t - 600.0) / 150.0)
    rng = np.random.default_rng(10)
    drift = np.column_stack([0.02 * (temp - 20), -0.01 * (temp - 20), 0.005 * (temp - 20)])
    noise = 0.01 * rng.standard_normal((t.size, 3))
    run = _run(t, drift + noise, temp)
    m = EmdWtdSaBp(sa_iterations=500, epochs=300)
    m.fit(run, rng=np.random.default_rng(11))
    assert m.split_hz == pytest.approx(100.0 / t[-1])
    # one segment per axis here (4800 samples); both kinds of IMF in each
    assert all(len(c) == 1 and 'noise' in c[0] and 'drift' in c[0] for c in m.imf_classes)
    out = m.apply(run)
    # the drift spans 0.4, 0.2, 0.1 rad/s; what is left is below the 0.01 rad/s noise
    assert np.all(np.std(out, 0) < 0.01)
    d = json.loads(json.dumps(m.to_dict()))
    np.testing.assert_array_equal(EmdWtdSaBp.from_dict(d).apply(run), out)


def test_zero_crossing_frequency():
    t = np.arange(0.0, 10.0, 0.001)
    hz = zero_crossing_hz(np.sin(2 * np.pi * 3.0 * t + 0.1), 10.0)
    assert hz == pytest.approx(3.0, abs=0.05)


def test_refusals(sim_pair):
    train, _, _ = sim_pair
    flat = ThermalRun(t_s=train.t_s, gyro_rad_s=train.gyro_rad_s,
                      temperature_c=np.full(train.t_s.size, 25.0), rate_hz=train.rate_hz,
                      name='flat')
    short = ThermalRun(t_s=train.t_s[:300], gyro_rad_s=train.gyro_rad_s[:300],
                       temperature_c=np.linspace(20, 25, 300), rate_hz=train.rate_hz,
                       name='short')
    for cls in (TemperaturePolynomial, LinearTdT, BPNetwork, EmdWtdSaBp):
        with pytest.raises(InputDataError, match='spans'):
            cls().fit(flat, rng=np.random.default_rng(0))
        with pytest.raises(ParameterError, match='not fitted'):
            cls().apply(train)
        # 15 s of training: a method using dT needs two 10-s rate windows
        if cls.uses_rate:
            with pytest.raises(RateWindowError, match='needs at least 20 s'):
                cls().fit(short, rng=np.random.default_rng(0))
        else:
            cls().fit(short, rng=np.random.default_rng(0))
    bad = ThermalRun(t_s=train.t_s, gyro_rad_s=train.gyro_rad_s,
                     temperature_c=np.where(np.arange(train.t_s.size) == 3, np.nan, 25.0),
                     rate_hz=train.rate_hz)
    with pytest.raises(InputDataError, match='NaN'):
        LinearTdT().fit(bad, rng=np.random.default_rng(0))
    with pytest.raises(ParameterError, match="'poly3'"):
        TemperaturePolynomial.from_dict({'method': 'bp'})
    with pytest.raises(ParameterError, match='order'):
        TemperaturePolynomial(order=-1)


def test_segmented_emd_cross_fades_to_the_signal():
    t = np.arange(1000) * 0.1
    x = np.random.default_rng(12).standard_normal((1000, 3)) + np.sin(t / 10.0)[:, None]
    m = EmdWtdSaBp(segment_samples=256)
    # with every IMF called drift, the drift part is IMFs + residue of each segment, and the
    # linear cross-fade weights sum to one: the signal comes back to rounding
    denoised, drift, classes = m.decompose(t, x, np.inf)
    np.testing.assert_allclose(drift, x, atol=1e-12)
    assert not denoised.any()
    # 256-sample segments overlapping by 32 start at 0, 224, 448, 672, 896 (the last to 1000)
    assert all(len(c) == 5 for c in classes)
