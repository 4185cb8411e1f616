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

"""Forward simulation of paper 000 eq. (2) / (10)-(11) against a plain-numpy twin, closed forms."""

from gyro_noise_ros.core.fractional import gl_coefficients, gl_difference
from gyro_noise_ros.core.simulate import (
    check_stability,
    FractionalNoise,
    require_stable,
    simulate_fractional_noise,
)
from gyro_noise_ros.errors import ParameterError, UnstableModelError
import numpy as np
import pytest


def recursion_twin(w, alpha, f, memory):
    """Plain-numpy twin of the numba kernel: eq. (2) solved for v[k+1], zero history."""
    c = gl_coefficients(alpha, memory)
    v = np.zeros(len(w))
    prev = 0.0
    for k in range(len(w)):
        past = sum(c[j] * v[k - j] for j in range(1, min(k, memory) + 1))
        v[k] = f * prev + w[k] - past
        prev = v[k]
    return v


@pytest.mark.parametrize('alpha,f,memory', [(1.4, -0.5, 7), (0.6, -0.3, 12), (1.0, -0.2, 5)])
def test_kernel_matches_twin(alpha, f, memory):
    w = np.random.default_rng(0).standard_normal(300)
    fast = FractionalNoise(alpha, f, 1.0, rng=np.random.default_rng(0),
                           memory=memory).generate(300)
    np.testing.assert_allclose(fast, recursion_twin(w, alpha, f, memory), rtol=1e-12, atol=1e-12)


def test_output_satisfies_eq2_exactly():
    """Delta^alpha v[k+1] - f v[k] recovers the drawn source noise w[k] (eqs. 2 and 9)."""
    alpha, f, n = 1.3, -0.4, 5000
    v = FractionalNoise(alpha, f, 0.7, rng=np.random.default_rng(1)).generate(n)
    w = np.random.default_rng(1).standard_normal(n) * 0.7
    resid = gl_difference(v, alpha, memory=1000)[1:] - f * v[:-1]
    np.testing.assert_allclose(resid, w[1:], atol=1e-9)


def test_streaming_equals_one_call():
    a = FractionalNoise(1.2, -0.3, 1.0, rng=np.random.default_rng(2))
    b = FractionalNoise(1.2, -0.3, 1.0, rng=np.random.default_rng(2))
    parts = np.concatenate([a.generate(n) for n in (1, 999, 0, 4000, 17)])
    np.testing.assert_array_equal(parts, b.generate(5017))


def test_order_zero_is_ar1_with_known_variance():
    # alpha = 0: v[k+1] = f v[k] + w[k], stationary variance sigma^2 / (1 - f^2) = 1 / 0.75.
    v = simulate_fractional_noise(400_000, 0.0, 0.5, 1.0, rng=np.random.default_rng(3))[1000:]
    # effective independent samples ~ n (1 - f) / (1 + f) = 133,000: the relative standard error of
    # the variance is sqrt(2 / 133,000) = 0.4 %; 2 % is five standard errors.
    assert np.var(v) == pytest.approx(1 / 0.75, rel=0.02)


def test_measurement_noise_and_bias_are_added():
    base = FractionalNoise(0.8, -0.3, 1.0, rng=np.random.default_rng(4)).generate(200_000)
    noisy = FractionalNoise(0.8, -0.3, 1.0, rng=np.random.default_rng(4), sigma_nu=0.5,
                            bias=3.0).generate(200_000)
    extra = noisy - base
    # mean of 200,000 N(3, 0.25) draws: standard error 0.0011; tolerance 0.01 is nine of them
    assert extra.mean() == pytest.approx(3.0, abs=0.01)
    # variance of the added noise: relative standard error sqrt(2/200000) = 0.3 %; 2 % is ~6 of
    # them
    assert extra.var() == pytest.approx(0.25, rel=0.02)


def test_stability_agrees_with_companion_roots():
    rng = np.random.default_rng(5)
    memory = 25
    for _ in range(60):
        alpha, f = rng.uniform(0, 2), rng.uniform(-2.5, 0.5)
        a = gl_coefficients(alpha, memory)
        a[1] -= f
        radius = np.abs(np.roots(a)).max()
        if abs(radius - 1) < 1e-3:
            continue  # marginal by construction; covered below
        assert check_stability(alpha, f, memory).stable == (radius < 1), (alpha, f, radius)


def test_unstable_parameters_are_refused():
    with pytest.raises(UnstableModelError, match='unstable'):
        require_stable(1.0, 0.0)          # random walk: pole at z = 1
    with pytest.raises(UnstableModelError):
        FractionalNoise(1.4, 0.1, 1.0, rng=np.random.default_rng(0))
    with pytest.raises(UnstableModelError):
        # A(-1) < 0: oscillating divergence
        FractionalNoise(0.5, -3.0, 1.0, rng=np.random.default_rng(0))
    assert require_stable(1.4, -0.5).stable


def test_bad_parameters():
    rng = np.random.default_rng(0)
    with pytest.raises(ParameterError, match='sigma_w'):
        FractionalNoise(1.0, -0.5, -1.0, rng=rng)
    with pytest.raises(ParameterError, match='rng'):
        FractionalNoise(1.0, -0.5, 1.0, rng=42)
    with pytest.raises(ParameterError, match='n must'):
        FractionalNoise(1.0, -0.5, 1.0, rng=rng).generate(-1)
