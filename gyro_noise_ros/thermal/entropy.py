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

"""
Fuzzy, permutation and sample entropy of a time series (paper 002, eqs. 8-22 and ref. [41]).

All three are O(n^2) (fuzzy, sample) or O(n) (permutation) and meant for windows of a few
thousand samples. Tolerances are relative: ``r`` multiplies the standard deviation of the
input (population, ddof = 0), as is usual and as antropy does.

* Fuzzy entropy (Chen et al. 2007; eqs. 8-15): embedding vectors of length m with their own
  mean removed (eqs. 8-9), Chebyshev distance (eq. 10), membership ``exp(-(d / w)^theta)`` with
  width ``w = r std(x)`` and gradient ``theta`` (eq. 11), the mean membership over all pairs
  ``p != q`` of the first ``n - m`` vectors for dimension m and m + 1 (eqs. 12-13),
  ``FE = ln Phi^m - ln Phi^(m+1)`` (eq. 15).
* Permutation entropy (Bandt and Pompe 2002; eqs. 16-22): ordinal patterns of ``order``
  samples spaced by ``delay``, Shannon entropy of their frequencies, divided by ``ln(order!)``
  when normalised (eq. 22). Ties are ranked by position (stable sort).
* Sample entropy (Richman and Moorman 2000): ``-ln(A / B)`` where B counts pairs of the first
  ``n - m`` templates of length m within Chebyshev distance ``r std(x)`` (strictly less, the
  antropy convention) and A the same pairs extended to length m + 1; self-matches excluded.
"""

from math import factorial

from gyro_noise_ros.errors import InputDataError, ParameterError
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray


def _series(x: ArrayLike, min_len: int, what: str) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.ndim != 1 or a.size < min_len:
        raise InputDataError(f'{what} needs a 1-D series of at least {min_len} samples, '
                             f'got shape {a.shape}')
    if not np.all(np.isfinite(a)):
        raise InputDataError(f'{what}: the series contains NaN or Inf')
    return a


@numba.njit(cache=True)
def _fuzzy_phi(x: NDArray[np.float64], m: int, n_vec: int, width: float,
               theta: float) -> tuple[float, float]:  # pragma: no cover - JIT
    """Return (Phi^m, Phi^(m+1)) of eqs. 12-13 over the first n_vec vectors."""
    # the vectors minus their own means (eqs. 8-9), once, instead of per pair
    ym = np.empty((n_vec, m))
    ym1 = np.empty((n_vec, m + 1))
    for p in range(n_vec):
        s = 0.0
        for i in range(m):
            s += x[p + i]
        base_m = s / m
        base_m1 = (s + x[p + m]) / (m + 1)
        for i in range(m):
            ym[p, i] = x[p + i] - base_m
        for i in range(m + 1):
            ym1[p, i] = x[p + i] - base_m1
    # theta = 2 (the default) as a product: a pow call per pair costs more than the rest
    square = theta == 2.0
    sum_m = 0.0
    sum_m1 = 0.0
    for p in range(n_vec - 1):
        for q in range(p + 1, n_vec):
            dm = 0.0
            for i in range(m):
                v = abs(ym[p, i] - ym[q, i])
                if v > dm:
                    dm = v
            dm1 = 0.0
            for i in range(m + 1):
                v = abs(ym1[p, i] - ym1[q, i])
                if v > dm1:
                    dm1 = v
            u = dm / width
            u1 = dm1 / width
            if square:
                sum_m += np.exp(-(u * u))
                sum_m1 += np.exp(-(u1 * u1))
            else:
                sum_m += np.exp(-u ** theta)
                sum_m1 += np.exp(-u1 ** theta)
    pairs = n_vec * (n_vec - 1) / 2.0
    return sum_m / pairs, sum_m1 / pairs


def fuzzy_entropy(x: ArrayLike, *, m: int = 2, r: float = 0.2, theta: float = 2.0) -> float:
    """
    Fuzzy entropy of a series (eqs. 8-15).

    Parameters
    ----------
    x : array_like
        Series (n,), n >= m + 3.
    m : int, keyword-only
        Embedding dimension (>= 1).
    r : float, keyword-only
        Width of the membership function as a fraction of ``std(x)`` (> 0).
    theta : float, keyword-only
        Gradient (exponent) of the membership function (> 0).

    Returns
    -------
    float
        ``ln Phi^m - ln Phi^(m+1)``; 0 for a constant series.

    """
    m = int(m)
    if m < 1:
        raise ParameterError(f'm must be >= 1, got {m}')
    if not r > 0 or not theta > 0:
        raise ParameterError(f'r and theta must be > 0, got {r!r}, {theta!r}')
    a = _series(x, m + 3, 'fuzzy_entropy')
    sd = a.std()
    if sd == 0:
        return 0.0
    phi_m, phi_m1 = _fuzzy_phi(a, m, a.size - m, r * sd, float(theta))
    return float(np.log(phi_m) - np.log(phi_m1))


def permutation_entropy(x: ArrayLike, *, order: int = 3, delay: int = 1,
                        normalize: bool = True) -> float:
    """
    Permutation entropy of a series (eqs. 16-22).

    Parameters
    ----------
    x : array_like
        Series (n,), n > (order - 1) delay.
    order : int, keyword-only
        Embedding dimension e (>= 2).
    delay : int, keyword-only
        Delay between the samples of a pattern (>= 1).
    normalize : bool, keyword-only
        Divide by ``ln(order!)`` so the result lies in [0, 1] (eq. 22).

    Returns
    -------
    float
        Entropy in nats (or normalised).

    """
    order, delay = int(order), int(delay)
    if order < 2 or delay < 1:
        raise ParameterError(f'order must be >= 2 and delay >= 1, got {order}, {delay}')
    a = _series(x, (order - 1) * delay + 1, 'permutation_entropy')
    n_vec = a.size - (order - 1) * delay
    emb = np.stack([a[i * delay:i * delay + n_vec] for i in range(order)], axis=1)
    ranks = np.argsort(emb, axis=1, kind='stable')
    codes = ranks @ (order ** np.arange(order))
    _, counts = np.unique(codes, return_counts=True)
    p = counts / n_vec
    h = float(-np.sum(p * np.log(p)))
    return h / np.log(factorial(order)) if normalize else h


@numba.njit(cache=True)
def _sample_counts(x: NDArray[np.float64], m: int,
                   r: float) -> tuple[int, int]:  # pragma: no cover - JIT
    """Return (A, B): template pairs matching at length m + 1 and m (first n - m templates)."""
    n_vec = x.size - m
    a_count = 0
    b_count = 0
    for p in range(n_vec - 1):
        for q in range(p + 1, n_vec):
            match = True
            for i in range(m):
                if abs(x[p + i] - x[q + i]) >= r:
                    match = False
                    break
            if match:
                b_count += 1
                if abs(x[p + m] - x[q + m]) < r:
                    a_count += 1
    return a_count, b_count


def sample_entropy_counts(x: ArrayLike, *, m: int = 2, tolerance: float) -> tuple[int, int]:
    """
    Return (A, B) of the sample entropy: template pairs matching at lengths m + 1 and m.

    Parameters
    ----------
    x : array_like
        Series (n,), n >= m + 2, finite.
    m : int, keyword-only
        Template length (>= 1).
    tolerance : float, keyword-only
        Absolute Chebyshev tolerance (same unit as ``x``; :func:`sample_entropy` uses
        ``r std(x)``). Counts of several windows with one tolerance add up to the entropy of
        the pooled templates, ``-ln(sum A / sum B)``.

    Returns
    -------
    tuple of int

    """
    m = int(m)
    if m < 1:
        raise ParameterError(f'm must be >= 1, got {m}')
    a = _series(x, m + 2, 'sample_entropy_counts')
    a_count, b_count = _sample_counts(a, m, float(tolerance))
    return int(a_count), int(b_count)


def sample_entropy(x: ArrayLike, *, m: int = 2, r: float = 0.2) -> float:
    """
    Sample entropy of a series (Richman and Moorman 2000; the paper's ref. [41]).

    Parameters
    ----------
    x : array_like
        Series (n,), n >= m + 2.
    m : int, keyword-only
        Template length (>= 1).
    r : float, keyword-only
        Tolerance as a fraction of ``std(x)`` (> 0).

    Returns
    -------
    float
        ``-ln(A / B)``; inf when no pair matches at length m + 1, nan when none at length m,
        0 for a constant series.

    """
    m = int(m)
    if m < 1:
        raise ParameterError(f'm must be >= 1, got {m}')
    if not r > 0:
        raise ParameterError(f'r must be > 0, got {r!r}')
    a = _series(x, m + 2, 'sample_entropy')
    sd = a.std()
    if sd == 0:
        return 0.0
    a_count, b_count = _sample_counts(a, m, r * sd)
    if b_count == 0:
        return float('nan')
    if a_count == 0:
        return float('inf')
    return float(-np.log(a_count / b_count))
