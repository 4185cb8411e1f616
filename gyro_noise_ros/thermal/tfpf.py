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
Time-frequency peak filtering with the pseudo Wigner-Ville distribution (paper 002, eqs. 24-27).

The noisy signal is scaled into the band ``[f_lo, f_hi]`` (cycles/sample) and used as the
instantaneous frequency of a unit-amplitude analytic signal (eq. 25),
``z(n) = exp(j 2 pi Phi(n))`` with ``Phi`` the running sum of the scaled samples (trapezoidal,
so the phase difference ``Phi(n + tau) - Phi(n - tau)`` is centred on n). Its pseudo
Wigner-Ville distribution with a Hamming lag window of ``window`` samples (eq. 26),
``PW(n, f) = sum_tau h(tau) z(n + tau) z*(n - tau) exp(-j 4 pi f tau)``, peaks at the
instantaneous frequency; the peak (FFT grid refined by a parabola through the top three bins)
scaled back is the estimate of the clean signal (eq. 27). TFPF is unbiased for signals linear
over the window; the window length trades noise reduction against bandwidth. It is
non-causal: each output sample uses ``window // 2`` samples ahead (offline only). The record is
mirrored by ``window // 2`` samples at both ends.
"""

from gyro_noise_ros.errors import InputDataError, ParameterError
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Samples per FFT batch (bounds memory: batch x nfft complex values).
_BATCH = 8192


@numba.njit(cache=True)
def _fill_kernel(phase: NDArray[np.float64], start: int, count: int, half: int,
                 h: NDArray[np.float64],
                 kernel: NDArray[np.complex128]) -> None:  # pragma: no cover - JIT
    """Write h(tau) z(n + tau) z*(n - tau) for ``count`` centres from ``start`` into rows."""
    nfft = kernel.shape[1]
    for r in range(count):
        c = start + r + half
        for j in range(nfft):
            kernel[r, j] = 0.0
        for t in range(-half, half + 1):
            ang = 2.0 * np.pi * (phase[c + t] - phase[c - t])
            kernel[r, t % nfft] = h[t + half] * (np.cos(ang) + 1j * np.sin(ang))


@numba.njit(cache=True)
def _peaks(spec: NDArray[np.float64], count: int,
           out: NDArray[np.float64]) -> None:  # pragma: no cover - JIT
    """Write the refined peak bin of each of the first ``count`` rows of ``spec`` into out."""
    nfft = spec.shape[1]
    for r in range(count):
        best = 0
        for j in range(1, nfft):
            if spec[r, j] > spec[r, best]:
                best = j
        y0 = spec[r, (best - 1) % nfft]
        y1 = spec[r, best]
        y2 = spec[r, (best + 1) % nfft]
        den = y0 - 2.0 * y1 + y2
        out[r] = best + (0.5 * (y0 - y2) / den if den < 0.0 else 0.0)


def tfpf(signal: ArrayLike, *, window: int = 31, band: tuple[float, float] = (0.05, 0.45),
         nfft: int | None = None) -> NDArray[np.float64]:
    """
    Denoise a signal by time-frequency peak filtering.

    Parameters
    ----------
    signal : array_like
        Samples (n,), finite.
    window : int, keyword-only
        Lag window length (odd, >= 3): longer removes more noise and more signal bandwidth.
    band : tuple, keyword-only
        (f_lo, f_hi), cycles/sample, the instantaneous frequency range the signal is coded
        into; inside (0, 0.5).
    nfft : int or None, keyword-only
        Frequency grid of the distribution (default: the next power of two >= 2 window; the
        peak is refined between bins).

    Returns
    -------
    numpy.ndarray
        The filtered signal (n,), same units.

    """
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise InputDataError(f'tfpf needs a 1-D signal of at least 2 samples, got {x.shape}')
    if not np.all(np.isfinite(x)):
        raise InputDataError('tfpf: the signal contains NaN or Inf')
    window = int(window)
    if window < 3 or window % 2 == 0:
        raise ParameterError(f'window must be odd and >= 3, got {window}')
    f_lo, f_hi = (float(b) for b in band)
    if not 0 < f_lo < f_hi < 0.5:
        raise ParameterError(f'band must satisfy 0 < f_lo < f_hi < 0.5, got {band!r}')
    half = window // 2
    if nfft is None:
        nfft = 1 << int(np.ceil(np.log2(2 * window)))
    nfft = int(nfft)
    if nfft < window:
        raise ParameterError(f'nfft must be >= window ({window}), got {nfft}')
    lo, hi = x.min(), x.max()
    if hi == lo:
        return x.copy()
    s = f_lo + (f_hi - f_lo) * (x - lo) / (hi - lo)
    # Mirror the ends so every sample has a full window.
    pad = min(half, x.size - 1)
    s_ext = np.concatenate([s[1:pad + 1][::-1], s, s[-pad - 1:-1][::-1]])
    if pad < half:
        s_ext = np.pad(s_ext, half - pad, mode='edge')
    phase = np.concatenate([[0.0], np.cumsum(s_ext)])[:-1] + 0.5 * s_ext
    h = np.hamming(window)
    est = np.empty(x.size)
    kernel = np.empty((min(_BATCH, x.size), nfft), dtype=complex)
    peaks = np.empty(kernel.shape[0])
    for b0 in range(0, x.size, _BATCH):
        count = min(_BATCH, x.size - b0)
        _fill_kernel(phase, b0, count, half, h, kernel)
        spec = np.fft.fft(kernel[:count], axis=1).real
        _peaks(spec, count, peaks)
        # The lag product holds exp(j 2 pi f 2 tau): bin k is f = k / (2 nfft).
        est[b0:b0 + count] = peaks[:count] / (2.0 * nfft)
    return lo + (est - f_lo) / (f_hi - f_lo) * (hi - lo)
