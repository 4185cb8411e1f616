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

"""Entropies (paper 002 eqs. 8-22) against slow loops and against antropy."""

from _thermal_reference import (fuzzy_entropy_loop, permutation_entropy_loop,
                                sample_entropy_loop)
from gyro_noise_ros.errors import InputDataError
from gyro_noise_ros.thermal.entropy import (fuzzy_entropy, permutation_entropy,
                                            sample_entropy)
import numpy as np
import pytest


def _series(seed, n=150):
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    return np.sin(0.2 * t) + 0.5 * rng.standard_normal(n)


@pytest.mark.parametrize('seed', [0, 1, 2])
@pytest.mark.parametrize('m', [1, 2, 3])
def test_fuzzy_matches_loop(seed, m):
    x = _series(seed)
    # Same sums in a different order: agreement to rounding.
    assert fuzzy_entropy(x, m=m) == pytest.approx(fuzzy_entropy_loop(x, m=m), rel=1e-10)


@pytest.mark.parametrize('seed', [0, 1])
@pytest.mark.parametrize('order,delay', [(3, 1), (4, 2), (5, 1)])
def test_permutation_matches_loop(seed, order, delay):
    x = _series(seed, 300)
    got = permutation_entropy(x, order=order, delay=delay)
    assert got == pytest.approx(permutation_entropy_loop(x, order, delay), rel=1e-12)


@pytest.mark.parametrize('seed', [0, 1, 2])
@pytest.mark.parametrize('m', [1, 2, 3])
def test_sample_matches_loop(seed, m):
    x = _series(seed, 300)
    assert sample_entropy(x, m=m) == pytest.approx(sample_entropy_loop(x, m=m), rel=1e-12)


# slow: importing antropy pulls scikit-learn and compiles its numba kernels (10-25 s); the loop
# twins above check the same functions in make test
@pytest.mark.slow
def test_against_antropy():
    ant = pytest.importorskip('antropy')
    x = _series(5, 2000)
    assert sample_entropy(x, m=2) == pytest.approx(ant.sample_entropy(x, order=2), rel=1e-12)
    assert permutation_entropy(x, order=4, delay=2) == pytest.approx(
        ant.perm_entropy(x, order=4, delay=2, normalize=True), rel=1e-12)


def test_closed_form_limits():
    rng = np.random.default_rng(3)
    noise = rng.standard_normal(20000)
    # White noise: every ordinal pattern equally likely; 20000 samples, 24 patterns: the
    # normalised entropy is within 1e-3 of 1 (sampling bias ~ 23 / (2 n ln 24) = 2e-4).
    assert permutation_entropy(noise, order=4) == pytest.approx(1.0, abs=1e-3)
    # A monotone ramp has one pattern.
    assert permutation_entropy(np.arange(100.0), order=3) == 0.0
    # Sample entropy of Gaussian white noise, m = 2, r = 0.2: -ln P(|x - y| < 0.2 sigma)
    # with x - y ~ N(0, 2 sigma^2), i.e. -ln(erf(0.1)) = 2.1965 (pairs independent).
    from math import erf, log
    assert sample_entropy(noise[:4000]) == pytest.approx(-log(erf(0.2 / 2)), abs=0.08)
    assert fuzzy_entropy(np.ones(50)) == 0.0


def test_regular_below_noise():
    t = np.arange(1000)
    rng = np.random.default_rng(4)
    sine = np.sin(2 * np.pi * t / 50)
    noise = rng.standard_normal(1000)
    for fn in (fuzzy_entropy, sample_entropy, permutation_entropy):
        assert fn(sine) < fn(noise)


def test_bad_input():
    with pytest.raises(InputDataError):
        fuzzy_entropy([1.0, np.nan, 2.0, 3.0, 4.0, 5.0])
    with pytest.raises(InputDataError):
        sample_entropy([1.0, 2.0])
