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

"""The one Gauss-Markov model: closed-form Allan variance and the exact sampled generator."""

import math

from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.simulate import (
    gauss_markov, gauss_markov_avar, GaussMarkov, GM_SERIES_BELOW)
from gyro_noise_ros.errors import ParameterError
import numpy as np
import pytest
from scipy.integrate import quad


def _avar_from_psd(tau, q, tc):
    """Allan variance as the PSD integral (IEEE 952 eq. C.3-like form), an independent twin."""
    # one-sided PSD of a process with autocorrelation q^2 exp(-|t|/T)
    def integrand(f):
        x = math.pi * f * tau
        psd = 4.0 * q * q * tc / (1.0 + (2 * math.pi * f * tc) ** 2)
        return psd * 2.0 * math.sin(x) ** 4 / x ** 2

    # split at the zeros of sin(pi f tau) and around the PSD's knee 1 / (2 pi T) so quad sees
    # smooth pieces; the tail beyond 200/tau is below 1e-9 of the total for these T
    knee = 1.0 / (2 * math.pi * tc)
    low = [knee * 10.0 ** (k / 4) for k in range(-12, 13) if knee * 10.0 ** (k / 4) < 1 / tau]
    edges = [0.0] + low + [k / tau for k in range(1, 201)]
    return sum(quad(integrand, a, b, limit=200)[0] for a, b in zip(edges[:-1], edges[1:]))


@pytest.mark.parametrize('x', [1e-4, 0.03, 0.5, 2.0, 20.0])
def test_closed_form_equals_psd_integral(x):
    tc = 3.0
    got = gauss_markov_avar(x * tc, 2.0, tc)
    # 1e-6: quad's tolerance over 200 pieces and the truncated tail
    assert got == pytest.approx(_avar_from_psd(x * tc, 2.0, tc), rel=1e-6)


def test_series_and_closed_form_agree_at_the_switch():
    tc = 1.0
    below = gauss_markov_avar(np.nextafter(GM_SERIES_BELOW, 0.0), 1.0, tc)
    above = gauss_markov_avar(GM_SERIES_BELOW, 1.0, tc)
    # the exact bracket at x = 0.1 carries ~1e-13 relative rounding; the series ~1e-12 truncation
    assert below == pytest.approx(above, rel=1e-10)


def test_limits_random_walk_and_white():
    q, tc = 1.5, 10.0
    tau = np.array([1e-6, 1e-3])
    # tau << T: the rate random walk (2 q^2 / T) tau / 3
    assert gauss_markov_avar(tau, q, tc) == pytest.approx(2 * q * q / tc * tau / 3, rel=1e-3)
    # tau >> T: white noise 2 q^2 T / tau (next term -3 q^2 T^2 / tau^2)
    big = 1e6
    assert gauss_markov_avar(big, q, tc) == pytest.approx(2 * q * q * tc / big, rel=1e-4)


def test_generator_equals_naive_recursion():
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    q, tc, rate = 0.7, 0.05, 200.0
    got = GaussMarkov(q, tc, rate, rng=rng_a, shape=(3,))
    out = np.concatenate([got.generate(7), got.generate(0), got.generate(500)])
    phi = math.exp(-1.0 / (rate * tc))
    x = rng_b.standard_normal(3) * q
    e = rng_b.standard_normal((7, 3)) * q * math.sqrt(1 - phi * phi)
    e = np.concatenate([e, rng_b.standard_normal((500, 3)) * q * math.sqrt(1 - phi * phi)])
    naive = np.empty_like(e)
    for k in range(e.shape[0]):
        x = phi * x + e[k]
        naive[k] = x
    np.testing.assert_allclose(out, naive, rtol=1e-12, atol=1e-14)


def test_generated_adev_follows_closed_form():
    rate, tc, q = 100.0, 2.0, 1.0
    x = gauss_markov(400_000, rate, std=q, corr_time_s=tc, rng=np.random.default_rng(11))
    res = allan_deviation(x, rate, taus=[10, 100, 400, 2000])
    model = np.sqrt(gauss_markov_avar(res.tau_s, q, tc))
    # the 99.7 % EDF intervals of each tau must hold the model (seeded; ~0.3 % chance each)
    half = 1.5 * np.maximum(res.adev - res.ci_low, res.ci_high - res.adev)
    assert np.all(np.abs(res.adev - model) <= half), (res.adev, model)
    assert np.var(x) == pytest.approx(q * q, rel=0.05)


@pytest.mark.parametrize('kwargs', [{'std': -1.0, 'corr_time_s': 1.0},
                                    {'std': 1.0, 'corr_time_s': 0.0},
                                    {'std': 1.0, 'corr_time_s': math.nan}])
def test_bad_parameters(kwargs):
    with pytest.raises(ParameterError):
        gauss_markov(10, 100.0, rng=np.random.default_rng(0), **kwargs)
    if kwargs['corr_time_s'] != 1.0:
        with pytest.raises(ParameterError):
            gauss_markov_avar(1.0, 1.0, kwargs['corr_time_s'])
