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

"""Elman network (paper 002 eq. 33) and beetle antennae search (eqs. 30-32)."""

from _thermal_reference import elman_forward_loop
from gyro_noise_ros.thermal.elman import (_forward, bas_minimize, ElmanModel, fit_elman,
                                          n_weights)
from gyro_noise_ros.thermal.run import temperature_rate_c_s
import numpy as np
import pytest


def test_forward_matches_loop():
    rng = np.random.default_rng(0)
    theta = rng.standard_normal(n_weights(2, (4, 3)))
    x = rng.standard_normal((50, 2))
    assert np.allclose(_forward(theta, x, 4, 3), elman_forward_loop(theta, x, 4, 3),
                       rtol=1e-12, atol=1e-12)


def test_bas_decay_rules_and_descent():
    def sphere(v):
        return float(np.sum((v - 1.0) ** 2))

    x, f, hist = bas_minimize(sphere, np.zeros(5), rng=np.random.default_rng(1),
                              iterations=100, epochs=5, d0=2.0, step0=0.5)
    d = np.array([h[0] for h in hist[:100]])
    lam = np.array([h[1] for h in hist[:100]])
    assert np.allclose(d[1:], 0.95 * d[:-1] + 0.01)
    assert np.allclose(lam[1:], 0.95 * lam[:-1])
    # Each epoch restarts from the initial lengths.
    assert hist[100][0] == 2.0 and hist[100][1] == 0.5
    # From f = 5 the search descends by more than 100x on a 5-D sphere (five epochs of
    # steps summing to 10 units each).
    assert f < 0.05 and f <= min(h[2] for h in hist)


def _drift_case(n=1500, dt=7.2):
    t = np.arange(n) * dt
    temp = 20 + 40 * np.sin(2 * np.pi * t / t[-1]) ** 2 - 30 * (t > t[-1] / 2)
    temp = np.convolve(temp, np.ones(20) / 20, mode='same')
    rate = temperature_rate_c_s(t, temp, window_s=60)
    drift = 1e-3 * (0.02 * (temp - 25) + 1e-4 * (temp - 25) ** 2 + 0.5 * rate)
    return np.c_[temp, rate], drift


def test_fit_learns_a_drift_law():
    x, y = _drift_case()
    model = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1))
    pred = model.predict(x)
    # 20 epochs of BAS explain more than 95 % of the drift's variance of this smooth law
    # (what a 3rd-order polynomial in T alone cannot: the dT term is a quarter of it).
    assert 1 - np.var(pred - y) / np.var(y) > 0.95
    again = ElmanModel.from_dict(model.to_dict())
    assert np.array_equal(again.predict(x), pred)
    # Seeded: the same seed, the same network.
    other = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1), epochs=2)
    same = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1), epochs=2)
    assert np.array_equal(other.theta, same.theta)


def test_bad_input():
    with pytest.raises(ValueError):
        fit_elman(np.ones((5, 2)), np.ones(4), dt_s=1.0, rng=np.random.default_rng(0))
    with pytest.raises(ValueError):
        fit_elman(np.ones((5, 2)), np.ones(5), dt_s=1.0, rng=np.random.default_rng(0),
                  hidden=(0, 2))
