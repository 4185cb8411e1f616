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

Each fuses a few vector passes of :class:`.fractional._FastPlan` over a block of orders into one
loop, so the block is read once instead of once per numpy operation. They are called only by
``_FastPlan`` (inputs validated there) and checked through it against the per-order
``numpy.convolve`` oracle of ``test/_fractional_reference.py``. Flags:
:data:`.jit.JIT_OPTIONS` (no fastmath; sums use partial accumulators, which changes rounding,
not accuracy).
"""

import numba
import numpy as np
from numpy.typing import NDArray

from .jit import JIT_OPTIONS


@numba.njit(**JIT_OPTIONS)
def _sum4(x: NDArray[np.float64], n: int) -> float:  # pragma: no cover - compiled
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    k = 0
    while k + 3 < n:
        s0 += x[k]
        s1 += x[k + 1]
        s2 += x[k + 2]
        s3 += x[k + 3]
        k += 4
    while k < n:
        s0 += x[k]
        k += 1
    return (s0 + s1) + (s2 + s3)


@numba.njit(**JIT_OPTIONS)
def residual_moments(  # pragma: no cover - compiled
        d: NDArray[np.float64], w_reg: NDArray[np.float64], ww: float, f_out: NDArray[np.float64],
        var_out: NDArray[np.float64]) -> None:
    """
    Per row of ``d``: ``f = d . w_reg / ww`` (eq. 8) and the population variance of the residual.

    ``d`` is (rows, n), ``w_reg`` (n,); results go to ``f_out`` and ``var_out`` (rows,). Two passes
    (the mean first), as numpy's var, without storing the residual.
    """
    rows, n = d.shape
    reg_sum = _sum4(w_reg, n)
    for r in range(rows):
        p0 = 0.0
        p1 = 0.0
        q0 = 0.0
        q1 = 0.0
        k = 0
        while k + 1 < n:
            p0 += d[r, k] * w_reg[k]
            p1 += d[r, k + 1] * w_reg[k + 1]
            q0 += d[r, k]
            q1 += d[r, k + 1]
            k += 2
        while k < n:
            p0 += d[r, k] * w_reg[k]
            q0 += d[r, k]
            k += 1
        f = (p0 + p1) / ww
        mean = ((q0 + q1) - f * reg_sum) / n
        s0 = 0.0
        s1 = 0.0
        k = 0
        while k + 1 < n:
            t0 = d[r, k] - f * w_reg[k] - mean
            t1 = d[r, k + 1] - f * w_reg[k + 1] - mean
            s0 += t0 * t0
            s1 += t1 * t1
            k += 2
        while k < n:
            t0 = d[r, k] - f * w_reg[k] - mean
            s0 += t0 * t0
            k += 1
        f_out[r] = f
        var_out[r] = (s0 + s1) / n


@numba.njit(**JIT_OPTIONS)
def residual_power(  # pragma: no cover - compiled
        spec: NDArray[np.complex128], f: NDArray[np.float64], reg_hat: NDArray[np.complex128],
        out: NDArray[np.complex128]) -> None:
    """
    ``out[r] = |spec[r] - f[r] reg_hat|^2`` as a complex array with zero imaginary part.

    The power spectrum of the source noise w (eq. 9), ready for the inverse real FFT.
    """
    rows, m = spec.shape
    for r in range(rows):
        fr = f[r]
        for q in range(m):
            z = spec[r, q] - fr * reg_hat[q]
            out[r, q] = z.real * z.real + z.imag * z.imag


@numba.njit(**JIT_OPTIONS)
def abs_sum(corr: NDArray[np.float64], count: int, out: NDArray[np.float64],
            scale: float) -> None:  # pragma: no cover - compiled
    """``out[r] = scale * sum_{m < count} |corr[r, m]|`` (eq. 13 with the 1/n of eq. 14)."""
    rows = corr.shape[0]
    for r in range(rows):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        k = 0
        while k + 3 < count:
            s0 += abs(corr[r, k])
            s1 += abs(corr[r, k + 1])
            s2 += abs(corr[r, k + 2])
            s3 += abs(corr[r, k + 3])
            k += 4
        while k < count:
            s0 += abs(corr[r, k])
            k += 1
        out[r] = ((s0 + s1) + (s2 + s3)) * scale


@numba.njit(**JIT_OPTIONS)
def next_order(d: NDArray[np.float64], spec: NDArray[np.complex128], parents: NDArray[np.int64],
               v: NDArray[np.float64], c_last: NDArray[np.float64], memory: int,
               one_minus_e: NDArray[np.complex128], e_n: NDArray[np.complex128],
               shifted_hat: NDArray[np.complex128], d_out: NDArray[np.float64],
               spec_out: NDArray[np.complex128]) -> None:  # pragma: no cover - compiled
    """
    Difference of order ``a + 1`` from that of order ``a``, in time and frequency.

    For output row ``i`` and input row ``r = parents[i]``: ``d_out[k] = d[k] - d[k-1] + [k >= L]
    c_L v[k - L]`` (``d[-1] = v[0]``) and ``spec_out = (1 - e) spec + d[n-1] e^n - v[0] + c_L
    shifted_hat`` (see :class:`.fractional._FastPlan`), ``c_L = c_last[i]``.
    """
    n = d.shape[1]
    m = spec.shape[1]
    v0 = v[0]
    for i in range(parents.shape[0]):
        r = parents[i]
        c = c_last[i]
        d_out[i, 0] = d[r, 0] - v0
        for k in range(1, n):
            d_out[i, k] = d[r, k] - d[r, k - 1]
        for k in range(memory, n):
            d_out[i, k] += c * v[k - memory]
        last = d[r, n - 1]
        for q in range(m):
            spec_out[i, q] = (one_minus_e[q] * spec[r, q] + last * e_n[q] - v0
                              + c * shifted_hat[q])


@numba.njit(**JIT_OPTIONS)
def cosine_prep(spec: NDArray[np.complex128], f: NDArray[np.float64],
                reg_hat: NDArray[np.complex128], sin_t: NDArray[np.float64],
                cos_t: NDArray[np.float64], y: NDArray[np.float64],
                odd: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    Fold a power spectrum for its inverse transform by a half-length real FFT (DCT-I, cosft1).

    The power spectrum ``P = |spec - f reg_hat|^2`` (``m = N + 1`` bins of a size ``2N`` real
    transform) is real and even, so its inverse transform is the DCT-I of P. It is folded into
    ``y`` (rows, N): ``y[j] = (P[j] + P[N-j]) / 2 - sin(pi j / N) (P[j] - P[N-j])``, whose real FFT
    gives the even lags (:func:`cosine_abs_sum`); ``odd[r]`` receives the start of the running sum
    that gives the odd lags. ``N`` must be even; ``sin_t``, ``cos_t`` hold sin, cos(pi j / N).
    P is formed first in a row buffer (a loop the compiler vectorises), then folded; the sum for
    ``odd`` runs on four accumulators.
    """
    rows, m = spec.shape
    big_n = m - 1
    half = big_n // 2
    p = np.empty(m)
    for r in range(rows):
        fr = f[r]
        for q in range(m):
            a = spec[r, q].real - fr * reg_hat[q].real
            b = spec[r, q].imag - fr * reg_hat[q].imag
            p[q] = a * a + b * b
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
        j = 1
        while j + 3 < half:
            s0 += cos_t[j] * (p[j] - p[big_n - j])
            s1 += cos_t[j + 1] * (p[j + 1] - p[big_n - j - 1])
            s2 += cos_t[j + 2] * (p[j + 2] - p[big_n - j - 2])
            s3 += cos_t[j + 3] * (p[j + 3] - p[big_n - j - 3])
            j += 4
        while j < half:
            s0 += cos_t[j] * (p[j] - p[big_n - j])
            j += 1
        odd[r] = (s0 + s1) + (s2 + s3)


@numba.njit(**JIT_OPTIONS)
def cosine_abs_sum(y_hat: NDArray[np.complex128], odd: NDArray[np.float64], count: int,
                   scale: float, out: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    Second half of :func:`cosine_prep`: ``out[r] = scale * sum_{m < count} |N R[m]|``.

    ``y_hat`` is the real FFT (numpy sign) of the folded ``y``: lag ``2k`` is ``Re y_hat[k]``,
    lag ``2k + 1`` is ``odd - sum_{i=1..k} Im y_hat[i]``.
    """
    rows, m = y_hat.shape
    for r in range(rows):
        total = 0.0
        run = odd[r]
        for k in range(m):
            lag = 2 * k
            if lag >= count:
                break
            total += abs(y_hat[r, k].real)
            if k >= 1:
                run -= y_hat[r, k].imag
            if lag + 1 < count:
                total += abs(run)
        out[r] = total * scale
