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

"""Causal temperature-rate estimate (against a slow twin), whether it can support a dT term."""

from dataclasses import replace

from gyro_noise_ros.errors import InputDataError
from gyro_noise_ros.thermal import run
from gyro_noise_ros.thermal.run import (rate_window_filled, RateWindowError,
                                        temperature_rate_c_s, temperature_rate_newest_c_s)
import numpy as np
import pytest


def _slow_rate(t, temp, window_s):
    out = np.zeros(t.size)
    for k in range(t.size):
        mask = (t >= t[k] - window_s) & (np.arange(t.size) <= k)
        if np.unique(t[mask]).size >= 2:
            out[k] = np.polyfit(t[mask], temp[mask], 1)[0]
    return out


def test_matches_trailing_polyfit_on_irregular_stamps():
    rng = np.random.default_rng(1)
    t = 1000.0 + np.cumsum(rng.uniform(0.05, 0.15, 1500))
    temp = 20 + 0.01 * t + 0.3 * np.sin(t / 50) + rng.normal(0, 0.01, t.size)
    fast = temperature_rate_c_s(t, temp, window_s=10.0, start='partial')
    # Both are the same least-squares slope; the running sums lose at most ~1e-10 degC/s here.
    np.testing.assert_allclose(fast, _slow_rate(t, temp, 10.0), atol=1e-9)


def _numpy_rate(t, temp, window_s):
    """Return the rates by the numpy running sums temperature_rate_c_s used before its kernel."""
    tc = t - t[0]
    zero = np.zeros(1)
    s_t, s_tt = (np.concatenate([zero, np.cumsum(x)]) for x in (tc, tc * tc))
    s_y, s_ty = (np.concatenate([zero, np.cumsum(x)]) for x in (temp, tc * temp))
    end = np.arange(1, t.size + 1)
    first = np.searchsorted(t, t - window_s, side='left')
    n = end - first
    sum_t, sum_tt = s_t[end] - s_t[first], s_tt[end] - s_tt[first]
    sum_y, sum_ty = s_y[end] - s_y[first], s_ty[end] - s_ty[first]
    denom = n * sum_tt - sum_t * sum_t
    rate = np.zeros(t.size)
    ok = denom > 1e-12 * np.maximum(n * sum_tt, 1e-300)
    rate[ok] = (n[ok] * sum_ty[ok] - sum_t[ok] * sum_y[ok]) / denom[ok]
    return rate


def _records(seed, trials):
    """
    Yield (trial, t, temp, window) records that probe a running-sum slope's bits.

    Repeated stamps, nearly equal ones (every third record from the second) and stamps on an
    exact 1/64-s grid where a window's edge falls on a stamp (every third from the first);
    readings with signed zeros and 2 % NaN; windows holding one sample or all.
    """
    rng = np.random.default_rng(seed)
    for trial in range(trials):
        n = int(rng.integers(1, 300))
        steps = [rng.integers(0, 3, n) / 64.0, rng.integers(0, 3, n) * 1e-9,
                 rng.uniform(0.0, 0.05, n) * (rng.random(n) > 0.1)][trial % 3]
        t = float(rng.uniform(-1e3, 2e9)) + np.cumsum(steps)
        temp = rng.normal(20.0, 30.0, n) * rng.choice([1.0, -1.0, 0.0], n)
        temp[rng.random(n) < 0.02] = np.nan
        yield trial, t, temp, float(rng.choice([1e-9, 0.125, 0.5, 2.0, 1e3]))


def test_kernel_gives_the_numpy_formulas_bits():
    # offline numbers unchanged by the kernel that replaced the numpy formula
    for trial, t, temp, window in _records(5, 200):
        got = temperature_rate_c_s(t, temp, window_s=window, start='partial')
        assert got.tobytes() == _numpy_rate(t, temp, window).tobytes(), trial


def test_newest_rate_is_the_array_functions_last_value_bit_for_bit():
    # the live compensator's one-value rate (a wrong window edge fails on the grid records)
    for trial, t, temp, window in _records(3, 300):
        want = temperature_rate_c_s(t, temp, window_s=window, start='partial')[-1]
        got = temperature_rate_newest_c_s(t, temp, window_s=window)
        assert type(got) is float
        assert np.float64(got).tobytes() == want.tobytes(), trial


def test_is_causal_and_exact_on_a_ramp():
    t = np.arange(0, 100, 0.1)
    temp = 5.0 + 0.02 * t
    rate = temperature_rate_c_s(t, temp, window_s=5.0, start='partial')
    assert rate[0] == 0.0
    np.testing.assert_allclose(rate[1:], 0.02, rtol=1e-9)
    changed = temp.copy()
    changed[600:] += 3.0
    # A change at sample 600 leaves every earlier rate untouched.
    np.testing.assert_array_equal(
        temperature_rate_c_s(t, changed, window_s=5.0, start='partial')[:600], rate[:600])


def test_start_up_has_no_outliers():
    rng = np.random.default_rng(4)
    t = np.arange(0, 60, 1 / 52)
    true_rate = 0.02
    # a chamber ramp read through the LSM6DSO32's sensor: 0.02 degC noise, 1/256 degC LSB
    temp = np.round((20 + true_rate * t + rng.normal(0, 0.02, t.size)) * 256) / 256
    partial = temperature_rate_c_s(t, temp, start='partial')
    filled = rate_window_filled(t, 10.0)
    k = int(np.argmax(filled))
    assert t[k] == pytest.approx(10.0, abs=1 / 52) and not filled[:k].any() and filled[k:].all()
    # the partial windows' slopes scatter far beyond the ramp (the outliers a fit used to see)
    assert np.max(np.abs(partial[1:k] - true_rate)) > 5 * true_rate
    backfill = temperature_rate_c_s(t, temp)
    np.testing.assert_array_equal(backfill[k:], partial[k:])
    np.testing.assert_array_equal(backfill[:k], partial[k])
    # a filled 10-s window of 520 readings: slope scatter 0.02 sqrt(12 / (520 * 100)) = 3e-4
    assert np.max(np.abs(backfill - true_rate)) < 5 * 3.1e-4
    nan = temperature_rate_c_s(t, temp, start='nan')
    assert np.isnan(nan[:k]).all()
    np.testing.assert_array_equal(nan[k:], partial[k:])


def test_record_shorter_than_the_window():
    t = np.arange(0, 9.9, 0.1)
    with pytest.raises(RateWindowError, match='shorter than the 10-s window'):
        temperature_rate_c_s(t, 20 + 0.01 * t)
    assert np.isnan(temperature_rate_c_s(t, 20 + 0.01 * t, start='nan')).all()
    with pytest.raises(ValueError, match='start'):
        temperature_rate_c_s(t, t, start='zero')


@pytest.mark.parametrize('window', [0.0, -1.0, float('nan')])
def test_refuses_bad_window(window):
    with pytest.raises(ValueError, match='window_s'):
        temperature_rate_c_s([0.0, 1.0], [1.0, 2.0], window_s=window)


def _ramp(seconds, rate_hz=20.0):
    t = np.arange(int(seconds * rate_hz)) / rate_hz
    return t


def test_rate_support_refuses_a_constant_rate_and_accepts_holds_and_ramps():
    rng = np.random.default_rng(0)
    t = _ramp(3600.0)
    lsb = 1.0 / 256.0
    cases = {
        # one rate all along: dT's spread is its noise (or nothing without noise)
        'noise-free ramp': (10.0 + t / 60.0, False),
        'noisy ramp': (np.round((10.0 + t / 60.0 + rng.normal(0, 0.02, t.size)) / lsb) * lsb,
                       False),
        'constant': (np.full(t.size, 20.0), False),
        # a hold, a ramp at 1 degC/min, a hold: dT spreads 0..0.0167 degC/s
        'heating': (np.interp(t, [0, 1000, 2400, 3600], [10, 10, 33.3, 33.3]), True),
    }
    for label, (temp, supported) in cases.items():
        s = run.rate_support(t, temp)
        assert s.supported is supported, (label, s.text())
        assert not s.both_signs
    cycle = run.rate_support(t, 30.0 - 10.0 * np.cos(2 * np.pi * t / 1800.0))
    assert cycle.supported and cycle.both_signs
    assert 'cannot support a dT term' in run.rate_support(t, cases['constant'][0]).text()


def test_rate_support_noise_estimate_matches_the_slope_noise():
    # white reading noise sigma on a ramp: the slope's standard error over a 10-s window of
    # n readings is sigma sqrt(12 / (n W^2)) (least squares); the MAD estimate agrees to 20 %
    # (it is read from ~7000 second differences)
    rng = np.random.default_rng(1)
    t = _ramp(3600.0)
    sigma = 0.05
    s = run.rate_support(t, 10.0 + t / 600.0 + rng.normal(0.0, sigma, t.size))
    expected = sigma * np.sqrt(12.0 / (200 * 10.0 ** 2))
    assert s.noise_c_s == pytest.approx(expected, rel=0.2)


def test_temperature_read_too_sparsely_for_the_rate_window():
    t = _ramp(100.0)
    r = run.ThermalRun(t_s=t, gyro_rad_s=np.zeros((t.size, 3)), temperature_c=20 + t / 100,
                       rate_hz=20.0, name='slow', temperature_period_s=5.0)
    with pytest.raises(InputDataError, match=r'read every 5 s \(0\.2 Hz\).*at least 4 readings'):
        run.check_temperature_readings(r)
    run.check_temperature_readings(replace(r, temperature_period_s=2.5))   # 4 per window: ok
    run.check_temperature_readings(replace(r, temperature_period_s=None))  # unknown: not checked
