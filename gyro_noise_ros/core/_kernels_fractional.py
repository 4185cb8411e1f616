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
numba kernels of the fast fractional-order identification (private; :mod:`.fractional`).

Each fuses the passes of :class:`.fractional._FastPlan` over the spectra of a block of orders
into one loop, so a spectrum is read once instead of once per numpy operation. They are called
only by ``_FastPlan`` (inputs validated there) and checked through it against the per-order
``numpy.convolve`` oracle of ``test/_fractional_reference.py``. Flags:
:data:`.jit.JIT_OPTIONS` (no fastmath; sums use partial accumulators, which changes rounding,
not accuracy).
"""

import numba
import numpy as np
from numpy.typing import NDArray

from .jit import JIT_OPTIONS


@numba.njit(**JIT_OPTIONS)
def residual_power(  # pragma: no cover - compiled
        spec: NDArray[np.complex128], f: NDArray[np.float64], reg_hat: NDArray[np.complex128],
        nyquist: int, out: NDArray[np.complex128], energy: NDArray[np.float64]) -> None:
    """
    ``out[r] = |W|^2`` with ``W = spec[r] - f[r] reg_hat``, and ``energy[r]`` its Parseval sum.

    W is the half spectrum (numpy's rfft, size S) of the source noise w (eq. 9, zero-padded to
    S); ``out`` is ready for the inverse real FFT; ``energy[r] = S sum_k w[k]^2``: bin 0 and the
    bin ``nyquist`` (S / 2 for an even S, else -1) count once, the others twice.
    """
    rows, m = spec.shape
    for r in range(rows):
        fr = f[r]
        e0 = 0.0
        e1 = 0.0
        for q in range(m):
            a = spec[r, q].real - fr * reg_hat[q].real
            b = spec[r, q].imag - fr * reg_hat[q].imag
            p = a * a + b * b
            out[r, q] = p
            if q == 0 or q == nyquist:
                e0 += p
            else:
                e1 += p
        energy[r] = e0 + 2.0 * e1


@numba.njit(**JIT_OPTIONS)
def _sum_abs(x: NDArray[np.float64], count: int) -> float:  # pragma: no cover - compiled
    """Return ``sum_{k < count} |x[k]|`` on four accumulators."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    k = 0
    while k + 3 < count:
        s0 += abs(x[k])
        s1 += abs(x[k + 1])
        s2 += abs(x[k + 2])
        s3 += abs(x[k + 3])
        k += 4
    while k < count:
        s0 += abs(x[k])
        k += 1
    return (s0 + s1) + (s2 + s3)


@numba.njit(**JIT_OPTIONS)
def abs_sum(corr: NDArray[np.float64], count: int, out: NDArray[np.float64],
            scale: float) -> None:  # pragma: no cover - compiled
    """``out[r] = scale * sum_{m < count} |corr[r, m]|`` (eq. 13 with the 1/n of eq. 14)."""
    for r in range(corr.shape[0]):
        out[r] = _sum_abs(corr[r], count) * scale


@numba.njit(**JIT_OPTIONS)
def _power_row(spec: NDArray[np.complex128], r: int, f: float, reg_hat: NDArray[np.complex128],
               p: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """``p = |spec[r] - f reg_hat|^2``: the power spectrum of the source noise (eq. 9)."""
    for q in range(p.shape[0]):
        a = spec[r, q].real - f * reg_hat[q].real
        b = spec[r, q].imag - f * reg_hat[q].imag
        p[q] = a * a + b * b


@numba.njit(**JIT_OPTIONS)
def _fold_row(p: NDArray[np.float64], sin_t: NDArray[np.float64], cos_t: NDArray[np.float64],
              y: NDArray[np.float64], r: int) -> tuple[float, float]:  # pragma: no cover
    """
    Fold ``p`` (N + 1 values) into ``y[r]`` for a DCT-I by a real FFT of N; return (odd, sum).

    ``y[j] = (p[j] + p[N-j]) / 2 - sin(pi j / N) (p[j] - p[N-j])`` (cosft1); ``odd`` starts the
    running sum of the odd outputs; ``sum`` is ``p[0] + p[N] + 2 sum_{0<j<N} p[j]`` (Parseval's
    sum when p is a half power spectrum).
    """
    big_n = p.shape[0] - 1
    half = big_n // 2
    y[r, 0] = 0.5 * (p[0] + p[big_n])
    for j in range(1, half):
        a = p[j]
        b = p[big_n - j]
        y1 = 0.5 * (a + b)
        y2 = a - b
        y[r, j] = y1 - sin_t[j] * y2
        y[r, big_n - j] = y1 + sin_t[j] * y2
    y[r, half] = p[half]
    s0 = 0.5 * (p[0] - p[big_n])
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    e0 = 0.0
    e1 = 0.0
    e2 = 0.0
    e3 = 0.0
    j = 1
    while j + 3 < half:
        s0 += cos_t[j] * (p[j] - p[big_n - j])
        s1 += cos_t[j + 1] * (p[j + 1] - p[big_n - j - 1])
        s2 += cos_t[j + 2] * (p[j + 2] - p[big_n - j - 2])
        s3 += cos_t[j + 3] * (p[j + 3] - p[big_n - j - 3])
        e0 += p[j] + p[big_n - j]
        e1 += p[j + 1] + p[big_n - j - 1]
        e2 += p[j + 2] + p[big_n - j - 2]
        e3 += p[j + 3] + p[big_n - j - 3]
        j += 4
    while j < half:
        s0 += cos_t[j] * (p[j] - p[big_n - j])
        e0 += p[j] + p[big_n - j]
        j += 1
    total = (p[0] + p[big_n]) + 2.0 * (((e0 + e1) + (e2 + e3)) + p[half])
    return (s0 + s1) + (s2 + s3), total


@numba.njit(**JIT_OPTIONS)
def cosine_prep(spec: NDArray[np.complex128], f: NDArray[np.float64],
                reg_hat: NDArray[np.complex128], sin_t: NDArray[np.float64],
                cos_t: NDArray[np.float64], y: NDArray[np.float64], odd: NDArray[np.float64],
                energy: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    Fold a power spectrum for its inverse transform by a half-length real FFT (DCT-I, cosft1).

    The power spectrum ``P = |W|^2``, ``W = spec - f reg_hat`` (``m = N + 1`` bins of a size
    ``2N`` real transform) is real and even, so its inverse transform is the DCT-I of P. It is
    folded into ``y`` (rows, N) by :func:`_fold_row`, whose real FFT gives the even lags
    (:func:`cosine_abs_sum`); ``odd[r]`` receives the start of the running sum that gives the
    odd lags. ``N`` must be even; ``sin_t``, ``cos_t`` hold sin, cos(pi j / N). ``energy[r]``:
    the Parseval sum of P, as in :func:`residual_power`.
    """
    rows, m = spec.shape
    p = np.empty(m)
    for r in range(rows):
        _power_row(spec, r, f[r], reg_hat, p)
        odd[r], energy[r] = _fold_row(p, sin_t, cos_t, y, r)


@numba.njit(**JIT_OPTIONS)
def cosine_fold(x: NDArray[np.float64], sin_t: NDArray[np.float64], cos_t: NDArray[np.float64],
                y: NDArray[np.float64], odd: NDArray[np.float64]) -> None:  # pragma: no cover
    """Fold the real rows ``x`` (N + 1 values each) as :func:`cosine_prep` folds its spectra."""
    for r in range(x.shape[0]):
        odd[r] = _fold_row(x[r], sin_t, cos_t, y, r)[0]


@numba.njit(**JIT_OPTIONS)
def cosine_abs_sum(y_hat: NDArray[np.complex128], odd: NDArray[np.float64], count: int,
                   scale: float, out: NDArray[np.float64],
                   signs: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    Second half of :func:`cosine_prep`: ``out[r] = scale * sum_{m < count} |N R[m]|``.

    ``y_hat`` is the real FFT (numpy sign) of the folded ``y``: lag ``2k`` is ``Re y_hat[k]``,
    lag ``2k + 1`` is ``odd - sum_{i=1..k} Im y_hat[i]``. The even lags are summed on four
    accumulators, apart from the running sum of the odd ones (a chain of dependent additions).
    When ``signs`` has rows, ``signs[r, m]`` receives the sign (-1, 0, 1) of lag m.
    """
    rows, m = y_hat.shape
    evens = min(m, (count + 1) // 2)   # lags 2k < count
    odds = min(m, count // 2)          # lags 2k + 1 < count
    keep = signs.shape[0] > 0
    for r in range(rows):
        even = _sum_abs(y_hat[r].real, evens)
        run = odd[r]
        t0 = abs(run) if odds > 0 else 0.0
        t1 = 0.0
        if keep:
            for k in range(evens):
                signs[r, 2 * k] = np.sign(y_hat[r, k].real)
            if odds > 0:
                signs[r, 1] = np.sign(run)
        for k in range(1, odds):
            run -= y_hat[r, k].imag
            t1 += abs(run)
            if keep:
                signs[r, 2 * k + 1] = np.sign(run)
        out[r] = (even + (t0 + t1)) * scale


@numba.njit(**JIT_OPTIONS)
def cosine_values(y_hat: NDArray[np.complex128], odd: NDArray[np.float64],
                  out: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    ``out[r, q]``, q = 0 .. N: the DCT-I whose folded input :func:`cosine_fold` transformed.

    The decoding of :func:`cosine_abs_sum` (even outputs from ``Re y_hat``, odd ones from the
    running sum), every value kept.
    """
    rows, m = y_hat.shape
    size = out.shape[1]
    for r in range(rows):
        run = odd[r]
        for k in range(m):
            if 2 * k < size:
                out[r, 2 * k] = y_hat[r, k].real
            if k >= 1:
                run -= y_hat[r, k].imag
            if 2 * k + 1 < size:
                out[r, 2 * k + 1] = run


@numba.njit(**JIT_OPTIONS)
def _power_at(d: NDArray[np.complex128], r: int, i: int, f: float,
              reg_hat: NDArray[np.complex128], q: int) -> float:  # pragma: no cover - compiled
    """``|d[r, i] - f reg_hat[q]|^2``: one bin of the source noise's power spectrum (eq. 9)."""
    x = d[r, i].real - f * reg_hat[q].real
    y = d[r, i].imag - f * reg_hat[q].imag
    return x * x + y * y


@numba.njit(**JIT_OPTIONS)
def power_bound_tile(d: NDArray[np.complex128], f: NDArray[np.float64],
                     reg_hat: NDArray[np.complex128], weights: NDArray[np.float64],
                     lower: NDArray[np.int64], upper: NDArray[np.int64], start: int,
                     acc: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    Add the Parseval and sign-bound sums of the bins ``start .. start + d.shape[1] - 1``.

    ``d[r]`` holds those bins of row r's difference spectrum (``reg_hat`` and ``weights`` are
    whole, ``m`` bins). With ``P = |d - f reg_hat|^2`` (the power spectrum of the source noise,
    eq. 9), adds to ``acc[r]``: the sum of P over the tile's inner bins and over its end bins
    (0 and ``m - 1``, which count once in Parseval's sum), ``P . weights[lower[r]]`` and
    ``P . weights[upper[r]]`` (the sign bounds of :class:`.fractional._FastPlan`). Called tile by
    tile, so that ``d`` is read while still in cache from the product that wrote it.
    """
    rows, width = d.shape
    last = reg_hat.shape[0] - 1
    stop = start + width
    lo_q = max(start, 1)
    hi_q = min(stop, last)
    for r in range(rows):
        fr = f[r]
        wa = weights[lower[r]]
        wb = weights[upper[r]]
        e0 = 0.0
        e1 = 0.0
        a0 = 0.0
        a1 = 0.0
        b0 = 0.0
        b1 = 0.0
        q = lo_q
        while q + 1 < hi_q:
            p0 = _power_at(d, r, q - start, fr, reg_hat, q)
            p1 = _power_at(d, r, q + 1 - start, fr, reg_hat, q + 1)
            e0 += p0
            e1 += p1
            a0 += p0 * wa[q]
            a1 += p1 * wa[q + 1]
            b0 += p0 * wb[q]
            b1 += p1 * wb[q + 1]
            q += 2
        while q < hi_q:
            p0 = _power_at(d, r, q - start, fr, reg_hat, q)
            e0 += p0
            a0 += p0 * wa[q]
            b0 += p0 * wb[q]
            q += 1
        edge = 0.0
        for q in (0, last):
            if start <= q < stop:
                p0 = _power_at(d, r, q - start, fr, reg_hat, q)
                edge += p0
                a0 += p0 * wa[q]
                b0 += p0 * wb[q]
        acc[r, 0] += e0 + e1
        acc[r, 1] += edge
        acc[r, 2] += a0 + a1
        acc[r, 3] += b0 + b1
