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

"""Causal temperature-rate estimate against a slow per-sample polyfit twin."""

from gyro_noise_ros.thermal.run import (rate_window_filled, RateWindowError,
                                        temperature_rate_c_s)
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
