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
from gyro_noise_ros.thermal.elman import (_forward, _mse_grad, bas_minimize, DriftModel,
                                          ElmanModel, fit_drift, fit_elman, n_weights)
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


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(4)
    theta = rng.standard_normal(n_weights(2, (4, 3)))
    x, y = rng.standard_normal((60, 2)), rng.standard_normal(60)

    def mse(th):
        return np.mean((elman_forward_loop(th, x, 4, 3) - y) ** 2)

    value, grad = _mse_grad(theta, x, y, 4, 3)
    assert value == pytest.approx(mse(theta), rel=1e-12)
    h = 1e-6
    numeric = np.array([(mse(theta + h * e) - mse(theta - h * e)) / (2 * h)
                        for e in np.eye(theta.size)])
    # Central differences of a smooth function: truncation ~ h^2 times the third derivative
    # (~1e-12) plus rounding ~ 1e-16 / h = 1e-10; the gradient's entries are of order 1.
    assert np.max(np.abs(numeric - grad)) < 1e-7


def test_fit_learns_a_drift_law():
    x, y = _drift_case()
    model = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1), epochs=3,
                      symmetric=(1,))
    pred = model.predict(x)
    # A cubic in T alone, least squares on the same series: what the PX4-style poly3 can do.
    cubic = np.polyval(np.polyfit(x[:, 0], y, 3), x[:, 0])
    rms_net, rms_cubic = np.sqrt(np.mean((pred - y) ** 2)), np.sqrt(np.mean((cubic - y) ** 2))
    # The law has a dT term a cubic cannot see (a quarter of the drift): the network on [T, dT]
    # must do at least as well as the cubic; measured 1e-6 against 1.5e-5 rad/s.
    assert rms_net <= rms_cubic
    # The refinement only goes down from BAS's best point (it keeps the better of the two).
    assert model.train_mse <= model.bas_mse
    bas_only = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1), epochs=3,
                         refine_iterations=0, symmetric=(1,))
    assert bas_only.train_mse == model.bas_mse
    assert np.array_equal(bas_only.theta, model.theta_bas)
    assert np.array_equal(model.predict(x, theta=model.theta_bas), bas_only.predict(x))
    # 0 keeps its place under symmetric scaling; the span is +- max |dT|
    assert model.x_lo[1] == -model.x_hi[1] == -np.max(np.abs(x[:, 1]))
    again = ElmanModel.from_dict(model.to_dict())
    assert np.array_equal(again.predict(x), pred)
    assert np.array_equal(again.theta_bas, model.theta_bas)
    # Seeded: the same seed, the same network.
    same = fit_elman(x, y, dt_s=7.2, rng=np.random.default_rng(1), epochs=3, symmetric=(1,))
    assert np.array_equal(same.theta, model.theta)


def test_bad_input():
    with pytest.raises(ValueError):
        fit_elman(np.ones((5, 2)), np.ones(4), dt_s=1.0, rng=np.random.default_rng(0))
    with pytest.raises(ValueError):
        fit_elman(np.ones((5, 2)), np.ones(5), dt_s=1.0, rng=np.random.default_rng(0),
                  hidden=(0, 2))
    with pytest.raises(ValueError):
        fit_elman(np.ones((5, 2)), np.ones(5), dt_s=1.0, rng=np.random.default_rng(0),
                  symmetric=(2,))


def test_drift_model_extrapolates_with_its_basis_beyond_the_trained_range():
    x, y = _drift_case()
    heating = x[:, 1] >= 0
    model = fit_drift(x[heating], y[heating], dt_s=7.2, rng=np.random.default_rng(2), epochs=2,
                      weight_decay=1e-3)
    # the law is a cubic in T plus a term linear in dT: the basis holds it exactly, so least
    # squares on the heating half recovers the cooling half to the scatter of rounding
    cooling = x[~heating]
    assert model.outside(cooling).mean() > 0.9
    np.testing.assert_allclose(model.base_part(cooling), y[~heating], atol=1e-3 * np.std(y))
    # the network's part is evaluated at the edge of the trained range out there
    held = np.clip(cooling, model.range_lo, model.range_hi)
    np.testing.assert_allclose(model.predict(cooling) - model.base_part(cooling),
                               model.network.predict(held), rtol=0, atol=1e-12 * np.std(y))
    again = DriftModel.from_dict(model.to_dict())
    assert np.array_equal(again.predict(x), model.predict(x))
    # an older model file held the bare network: it loads as base 'none', never clipped
    bare = DriftModel.from_dict(model.network.to_dict())
    assert bare.base == 'none' and np.array_equal(bare.predict(x), model.network.predict(x))
