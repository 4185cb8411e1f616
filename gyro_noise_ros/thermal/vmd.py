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
Variational mode decomposition (Dragomiretskiy and Zosso 2014; paper 002, eqs. 1-7).

The signal is mirrored at both ends (as in the authors' reference code), transformed with a
real FFT, and the modes are updated in the one-sided spectrum by the alternating direction
method of multipliers: for each frequency bin the mode estimates are Wiener-filter updates
around their centre frequencies (eq. 4), the centre frequencies are the power-weighted mean
frequencies of their modes (eq. 5), the Lagrange multiplier takes a dual ascent step of size
``tau`` (eq. 6), and the loop stops when the summed relative change of the modes falls below
``tol`` (eq. 7).

Convention: the mode update divides by ``1 + alpha (f - f_k)^2`` as the reference code does
(eq. 4 of the paper prints ``2 alpha``); the paper's range alpha in [1000, 10000] and its choice
alpha = 9755 come from that code, so ``alpha`` here means what it means there. Frequencies are in
cycles per sample (0 to 0.5). VMD is non-causal: it needs the whole record.
"""

from dataclasses import dataclass

from gyro_noise_ros.errors import InputDataError, ParameterError
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.fft

#: Accepted values of ``init``.
INITS = ('uniform', 'random', 'zero')


@dataclass(frozen=True)
class VmdResult:
    """
    Outcome of :func:`vmd`.

    Attributes
    ----------
    modes : numpy.ndarray
        Intrinsic mode functions (k, n), ordered by ascending centre frequency; their sum
        approximates the signal.
    center_freqs : numpy.ndarray
        Centre frequency of each mode (k,), cycles/sample.
    iterations : int
        ADMM iterations run.
    converged : bool
        True when eq. 7 fell below ``tol`` before ``max_iter``.

    """

    modes: np.ndarray
    center_freqs: np.ndarray
    iterations: int
    converged: bool


@numba.njit(cache=True, fastmath=False)
def _update_centres(omega: NDArray[np.float64], num: NDArray[np.float64], den: NDArray[np.float64],
                    diff: NDArray[np.float64], old_norm: NDArray[np.float64],
                    fix_dc: bool) -> float:  # pragma: no cover - JIT
    """Set each centre frequency to its mode's spectral centroid (eq. 6); return eq. 7's sum."""
    total = 0.0
    for k in range(omega.size):
        if den[k] > 0.0:
            omega[k] = num[k] / den[k]
        if fix_dc and k == 0:
            omega[k] = 0.0
        total += diff[k] / max(old_norm[k], 1e-300)
    return total


@numba.njit(cache=True, fastmath=False)
def _admm_sweep(f_hat: NDArray[np.complex128], freqs: NDArray[np.float64],
                u: NDArray[np.complex128], lam: NDArray[np.complex128], omega: NDArray[np.float64],
                alpha: float, tau: float, fix_dc: bool) -> float:  # pragma: no cover - JIT
    """Run one ADMM iteration in place; return sum_k ||du_k||^2 / ||u_k||^2 (eq. 7)."""
    nbins, k_modes = u.shape
    num = np.zeros(k_modes)
    den = np.zeros(k_modes)
    diff = np.zeros(k_modes)
    old_norm = np.zeros(k_modes)
    for j in range(nbins):
        s = 0j
        for k in range(k_modes):
            s += u[j, k]
        fj = f_hat[j]
        fr = freqs[j]
        half_lam = 0.5 * lam[j]
        for k in range(k_modes):
            old = u[j, k]
            others = s - old
            d = fr - omega[k]
            new = (fj - others - half_lam) * (1.0 / (1.0 + alpha * d * d))
            u[j, k] = new
            s = others + new
            p = new.real * new.real + new.imag * new.imag
            num[k] += fr * p
            den[k] += p
            dd = new - old
            diff[k] += dd.real * dd.real + dd.imag * dd.imag
            old_norm[k] += old.real * old.real + old.imag * old.imag
        if tau != 0.0:
            lam[j] = lam[j] + tau * (s - fj)
    return _update_centres(omega, num, den, diff, old_norm, fix_dc)


@numba.njit(cache=True, fastmath=False)
def _exact_sweep(f_hat: NDArray[np.complex128], freqs: NDArray[np.float64],
                 u: NDArray[np.complex128], omega: NDArray[np.float64], alpha: float,
                 fix_dc: bool) -> float:  # pragma: no cover - JIT
    """Solve the modes exactly for the current centre frequencies (tau = 0), then update them."""
    nbins, k_modes = u.shape
    num = np.zeros(k_modes)
    den = np.zeros(k_modes)
    diff = np.zeros(k_modes)
    old_norm = np.zeros(k_modes)
    inv = np.zeros(k_modes)
    for j in range(nbins):
        fr = freqs[j]
        total_inv = 0.0
        for k in range(k_modes):
            d = fr - omega[k]
            a = alpha * d * d
            inv[k] = 1.0 / max(a, 1e-300)
            total_inv += inv[k]
        fj = f_hat[j]
        for k in range(k_modes):
            old = u[j, k]
            new = fj * (inv[k] / (1.0 + total_inv))
            u[j, k] = new
            p = new.real * new.real + new.imag * new.imag
            num[k] += fr * p
            den[k] += p
            dd = new - old
            diff[k] += dd.real * dd.real + dd.imag * dd.imag
            old_norm[k] += old.real * old.real + old.imag * old.imag
    return _update_centres(omega, num, den, diff, old_norm, fix_dc)


def mirror_extend(signal: ArrayLike) -> tuple[NDArray[np.float64], int]:
    """
    Mirror a signal at both ends as the VMD reference code does; return (extended, start).

    The first ``n // 2`` samples are reflected before the start and the rest after the end, so
    the extended signal has length ``2 n`` and the original occupies ``[start, start + n)``.
    """
    x = np.asarray(signal, dtype=float)
    half = x.size // 2
    return np.concatenate([x[:half][::-1], x, x[half:][::-1]]), half


def initial_center_freqs(k: int, init: str, n_ext: int, *, dc: bool = False,
                         rng: np.random.Generator | int | None = None) -> NDArray[np.float64]:
    """
    Return the starting centre frequencies (cycles/sample) of :func:`vmd`.

    ``'uniform'`` spreads them as ``0.5 i / k``, ``'random'`` draws them log-uniformly between
    ``1 / n_ext`` and 0.5 (sorted), ``'zero'`` starts all at 0; ``dc`` pins the first at 0.
    """
    if init == 'uniform':
        omega = 0.5 * np.arange(k) / k
    elif init == 'random':
        gen = np.random.default_rng(rng)
        fs = 1.0 / n_ext
        omega = np.sort(np.exp(np.log(fs) + (np.log(0.5) - np.log(fs)) * gen.random(k)))
    elif init == 'zero':
        omega = np.zeros(k)
    else:
        raise ParameterError(f'init must be one of {INITS}, got {init!r}')
    if dc:
        omega[0] = 0.0
    return omega


def vmd(signal: ArrayLike, *, k: int, alpha: float, tau: float = 0.0, tol: float = 1e-7,
        init: str = 'uniform', max_iter: int = 500, dc: bool = False,
        rng: np.random.Generator | int | None = None, center_freqs: ArrayLike | None = None,
        solver: str = 'admm', workers: int = 1) -> VmdResult:
    """
    Decompose a signal into ``k`` band-limited modes by variational mode decomposition.

    Parameters
    ----------
    signal : array_like
        Real samples (n,), n >= 4, finite.
    k : int, keyword-only
        Number of modes (>= 1).
    alpha : float, keyword-only
        Bandwidth penalty (> 0); larger gives narrower modes (reference-code convention, see
        the module docstring).
    tau : float, keyword-only
        Dual ascent step of the Lagrange multiplier (eq. 6); 0 (the paper's choice when exact
        reconstruction is not required) leaves the multiplier at zero.
    tol : float, keyword-only
        Convergence threshold on sum_k ||u_k^{n+1} - u_k^n||^2 / ||u_k^n||^2 (eq. 7).
    init : {'uniform', 'random', 'zero'}, keyword-only
        Initial centre frequencies (see :func:`initial_center_freqs`); ignored when
        ``center_freqs`` is given.
    max_iter : int, keyword-only
        Iteration cap.
    dc : bool, keyword-only
        Keep the first mode's centre frequency at 0 (a trend mode).
    rng : numpy.random.Generator or int or None, keyword-only
        Randomness for ``init='random'``.
    center_freqs : array_like or None, keyword-only
        Warm start: initial centre frequencies (k,), cycles/sample, e.g. from a decomposition
        of a similar record at the same sample rate.
    solver : {'admm', 'exact'}, keyword-only
        ``'admm'``: the reference algorithm (one Gauss-Seidel sweep of eq. 4 per iteration).
        ``'exact'`` (``tau = 0`` only): each iteration solves eq. 4's fixed point for the
        current centre frequencies in closed form, ``u_k = f / (a_k (1 + sum_i 1 / a_i))`` with
        ``a_k = alpha (f - f_k)^2``, then applies eq. 5. Both stop at the same stationary point
        (the ADMM fixed point with tau = 0 satisfies that equation); ``'exact'`` reaches it in
        far fewer sweeps on long records.
    workers : int, keyword-only
        Threads of the FFTs (scipy.fft); the sweeps are single-threaded.

    Returns
    -------
    VmdResult
        Modes (k, n) by ascending centre frequency, centre frequencies, iterations, convergence.

    """
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1 or x.size < 4:
        raise InputDataError(f'vmd needs a 1-D signal of at least 4 samples, got shape {x.shape}')
    if not np.all(np.isfinite(x)):
        raise InputDataError('vmd: the signal contains NaN or Inf')
    k = int(k)
    if k < 1:
        raise ParameterError(f'k must be >= 1, got {k}')
    if not alpha > 0:
        raise ParameterError(f'alpha must be > 0, got {alpha!r}')
    if not tau >= 0:
        raise ParameterError(f'tau must be >= 0, got {tau!r}')
    if not tol > 0:
        raise ParameterError(f'tol must be > 0, got {tol!r}')
    if int(max_iter) < 1:
        raise ParameterError(f'max_iter must be >= 1, got {max_iter!r}')
    if solver not in ('admm', 'exact'):
        raise ParameterError(f"solver must be 'admm' or 'exact', got {solver!r}")
    if solver == 'exact' and tau != 0:
        raise ParameterError("solver='exact' needs tau = 0")
    ext, start = mirror_extend(x)
    n_ext = ext.size
    f_hat = scipy.fft.rfft(ext, workers=workers)
    # The reference code keeps the one-sided spectrum without the Nyquist bin.
    f_hat[-1] = 0.0
    freqs = np.arange(f_hat.size) / n_ext
    if center_freqs is not None:
        omega = np.array(center_freqs, dtype=float).reshape(-1)
        if omega.size != k or not np.all(np.isfinite(omega)):
            raise ParameterError(f'center_freqs must hold {k} finite values')
        omega = np.clip(omega, 0.0, 0.5)
        if dc:
            omega[0] = 0.0
    else:
        omega = initial_center_freqs(k, init, n_ext, dc=dc, rng=rng)
    u = np.zeros((f_hat.size, k), dtype=complex)
    lam = np.zeros(f_hat.size, dtype=complex)
    converged = False
    it = 0
    for it in range(1, int(max_iter) + 1):
        if solver == 'exact':
            change = _exact_sweep(f_hat, freqs, u, omega, float(alpha), bool(dc))
        else:
            change = _admm_sweep(f_hat, freqs, u, lam, omega, float(alpha), float(tau),
                                 bool(dc))
        # The first sweep changes every mode from zero: its relative change is undefined.
        if it > 1 and change < tol:
            converged = True
            break
    order = np.argsort(omega, kind='stable')
    modes = scipy.fft.irfft(np.ascontiguousarray(u.T[order]), n=n_ext, axis=1,
                            workers=workers)[:, start:start + x.size]
    modes = np.ascontiguousarray(modes)
    return VmdResult(modes=modes, center_freqs=omega[order].copy(),
                     iterations=it, converged=converged)
