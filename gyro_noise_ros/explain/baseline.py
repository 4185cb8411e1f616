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
Baseline model of the discrepancy workflow: bias, fractional-order noise, white measurement noise.

Paper 000 eqs. (2), (10), (11): ``Delta^alpha x[k+1] = f x[k] + w[k]``, ``v[k] = x[k] + nu[k]``
plus a constant bias. :func:`fit_baseline` returns a :class:`BaselineModel`:

1. bias = the record mean (every effect term is zero-mean over the record);
2. (alpha, f): the paper's variance method
   (:class:`~gyro_noise_ros.core.fractional.OrderIdentifier`) on up to :data:`MAX_ID_CHUNKS`
   chunks; every local minimum within :data:`BRANCH_TOLERANCE` of a chunk's minimum is a
   candidate pair (near-white data nearly tie the alpha ~ 0 and alpha ~ 1 branches); unstable
   pairs are skipped (:func:`stable`) and f is refined by the PSD misfit above fs / 100;
3. sigma_w, sigma_nu: non-negative least squares of the one-sided model PSD
   ``(2 / fs) (sigma_w^2 / |A(e^{i w})|^2 + sigma_nu^2)`` on the Welch bins above fs / 100,
   reweighted by the previous model, spectral lines dropped; among the pairs within 10 % of the
   best misfit the shortest simulation memory wins.

:func:`without_white` refits the levels with a known white noise taken out (the rounding noise of
a lattice: Sheppard's correction). The ensemble runs at the shortest memory
(:func:`simulation_memory`) whose model PSD is within 1 % of the L = 1000 model everywhere.
Reasons and measurements: docs/discrepancy.md section 1.
"""

from dataclasses import asdict, dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray
import scipy.optimize

from .signatures import FloatArray, welch
from ..core.fractional import DEFAULT_MEMORY, gl_coefficients, OrderIdentifier
from ..core.simulate import check_stability, FractionalNoise

MEMORY_STEPS = (25, 50, 100, 200, 500, 1000)
MAX_ID_CHUNKS = 16
#: Local minima of the variance-method curve within this relative distance of its minimum are
#: candidate branches (module doc).
BRANCH_TOLERANCE = 0.01


@dataclass(frozen=True)
class BaselineModel:
    """
    Fitted baseline (module doc).

    Attributes
    ----------
    bias_rad_s : float
        Constant bias (rad/s).
    alpha : float
        Fractional order (dimensionless).
    f : float
        Noise parameter of eq. (2) (dimensionless).
    sigma_w_rad_s : float
        Source-noise standard deviation (rad/s).
    sigma_nu_rad_s : float
        White measurement-noise standard deviation (rad/s).
    memory_fit : int
        L used for the identification.
    memory_sim : int
        L used for the ensemble.
    chunk_size : int
        Identification chunk length (samples).
    chunks_identified : int
        Chunks the order was identified on.
    psd_misfit : float
        RMS of log10(measured / model PSD) over the Welch bins used.

    """

    bias_rad_s: float
    alpha: float
    f: float
    sigma_w_rad_s: float
    sigma_nu_rad_s: float
    memory_fit: int
    memory_sim: int
    chunk_size: int
    chunks_identified: int
    psd_misfit: float

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for explain.json."""
        return {k: (float(v) if isinstance(v, float) else v) for k, v in asdict(self).items()}

    def generator(self, rng: np.random.Generator) -> FractionalNoise:
        """Return a :class:`~gyro_noise_ros.core.simulate.FractionalNoise` for this model."""
        return FractionalNoise(self.alpha, self.f, self.sigma_w_rad_s, rng=rng,
                               memory=self.memory_sim, sigma_nu=self.sigma_nu_rad_s,
                               bias=self.bias_rad_s)


#: Points of the unit-circle grid of the model spectrum: with L <= 1000, A(e^{i w}) varies on the
#: scale fs / L, 130x coarser than the grid.
GAIN_GRID = 1 << 17
#: Coefficient-sum bound below which :func:`stable` needs no spectrum (its docstring).
STABLE_SUM = 1.0 - 1e-3


@lru_cache(maxsize=1)
def _unit_delay() -> NDArray[np.complex128]:
    """Return e^{-i w} on the rfft grid of :data:`GAIN_GRID` points (read-only)."""
    out = np.exp(-2j * np.pi * np.arange(GAIN_GRID // 2 + 1) / GAIN_GRID)
    out.flags.writeable = False
    return out


@lru_cache(maxsize=32)
def _gl_spectrum(alpha: float, memory: int) -> NDArray[np.complex128]:
    """Return the rfft of the GL coefficients c_0..c_L on the grid (read-only, 1 MiB)."""
    out = np.fft.rfft(gl_coefficients(alpha, memory), GAIN_GRID)
    out.flags.writeable = False
    return out


def model_gain(alpha: float, f: float, memory: int, freq_hz: FloatArray,
               rate_hz: float) -> FloatArray:
    """
    Return ``1 / |A(e^{i w})|^2`` of the recursion of eq. (2) at the given frequencies.

    ``A(z) = sum_j c_j z^-j - f z^-1`` is evaluated on a grid of :data:`GAIN_GRID` points and
    interpolated. The FFT of the GL coefficients depends on (alpha, L) only and is kept
    (:func:`_gl_spectrum`); f enters as ``- f e^{-i w}``, so the many f a fit tries cost no FFT.

    Parameters
    ----------
    alpha, f : float
        Model parameters.
    memory : int
        L.
    freq_hz : numpy.ndarray
        Frequencies (Hz), 0 .. rate_hz / 2.
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    numpy.ndarray

    """
    spec = _gl_spectrum(float(alpha), int(memory)) - float(f) * _unit_delay()
    power = spec.real ** 2 + spec.imag ** 2
    grid = np.arange(power.shape[0]) * (rate_hz / GAIN_GRID)
    return 1.0 / np.interp(freq_hz, grid, power)


def stable(alpha: float, f: float, memory: int) -> bool:
    """
    Return ``core.simulate.check_stability(alpha, f, memory).stable``; cheap when a bound decides.

    With ``a = c - f e_1`` (a_0 = 1) and ``s = sum_{j>=1} |a_j|``: if s < 1 then
    ``|A(z) - 1| <= s < 1`` on and outside the unit circle, so A has no zero there (every pole of
    the recursion lies inside), A(1) and A(-1) are >= 1 - s > 0, ``min |A| / max |A| >= (1 - s) /
    (1 + s)`` and A(e^{i w}) never winds around 0: everything the core check asks for. Below
    :data:`STABLE_SUM` (a margin far above rounding) the answer is therefore True without the
    2^17-point spectrum the core check evaluates (~20 ms, most of a baseline fit); above, the
    core check decides. Near order 1 with f ~ -0.5..-1 (every sensor seen so far) s is ~0.2-0.6.

    Parameters
    ----------
    alpha, f : float
        Model parameters.
    memory : int
        L.

    Returns
    -------
    bool

    """
    c = gl_coefficients(alpha, memory)
    if abs(c[1] - f) + float(np.abs(c[2:]).sum()) < STABLE_SUM:
        return True
    return check_stability(alpha, f, memory).stable


def simulation_memory(alpha: float, f: float, rate_hz: float, *, memory_fit: int = DEFAULT_MEMORY,
                      tolerance: float = 0.01) -> int:
    """
    Return the smallest L_sim whose model PSD is within ``tolerance`` of L = ``memory_fit``.

    Parameters
    ----------
    alpha, f : float
        Model parameters.
    rate_hz : float
        Sample rate (Hz).
    memory_fit : int, keyword-only
        Reference memory.
    tolerance : float, keyword-only
        Largest relative PSD difference.

    Returns
    -------
    int

    """
    freq = np.concatenate(([0.0], np.geomspace(rate_hz * 1e-4, rate_hz / 2, 400)))
    ref = model_gain(alpha, f, memory_fit, freq, rate_hz)
    for memory in MEMORY_STEPS:
        if memory >= memory_fit:
            break
        if not stable(float(alpha), float(f), memory):
            continue
        if np.max(np.abs(model_gain(alpha, f, memory, freq, rate_hz) / ref - 1.0)) <= tolerance:
            return memory
    return int(memory_fit)


def _fit_variances(freq: FloatArray, pxx: FloatArray, gain: FloatArray,
                   rate_hz: float, known_white_var: float = 0.0) -> tuple[FloatArray, float]:
    band = freq >= rate_hz / 100.0
    keep = band
    weight = pxx
    known = 2.0 * known_white_var / rate_hz   # one-sided density of a known white variance
    for _ in range(3):
        # relative weights from the previous model, not from the noisy estimate itself: 1 / pxx
        # weights would favour bins that happen to come out low and bias the fit down by several %
        design = np.column_stack((gain, np.ones_like(gain)))[keep] / weight[keep, None]
        coef, _ = scipy.optimize.nnls(design, (pxx[keep] - known) / weight[keep])
        model = gain * coef[0] + coef[1] + known
        keep = band & (pxx < 3.0 * model)
        weight = np.maximum(model, 1e-300)
    misfit = float(np.sqrt(np.mean(np.log10(pxx[keep] / model[keep]) ** 2)))
    return coef * rate_hz / 2.0, misfit


def _refine_f(alpha: float, f: float, memory: int, freq: FloatArray, pxx: FloatArray,
              rate_hz: float) -> float:
    """
    Refine f by the PSD misfit above fs / 100 within +/-0.3.

    Keep the identified f if unstable.
    """
    def misfit(value: float) -> float:
        return _fit_variances(freq, pxx, model_gain(alpha, value, memory, freq, rate_hz),
                              rate_hz)[1]

    res = scipy.optimize.minimize_scalar(misfit, bounds=(f - 0.3, f + 0.3), method='bounded',
                                         options={'xatol': 1e-4})
    refined = round(float(res.x), 6)
    if res.fun < misfit(f) and stable(alpha, refined, memory):
        return refined
    return f


def _spectrum(x: FloatArray, rate_hz: float) -> tuple[FloatArray, FloatArray]:
    """Return the Welch PSD the levels are fitted to (without the two lowest bins)."""
    nperseg = int(min(4096, 2 ** int(np.floor(np.log2(x.shape[0] // 16)))))
    freq, pxx = welch(x, rate_hz, nperseg)
    return freq[2:], pxx[2:]


def fit_baseline(x: FloatArray, rate_hz: float) -> BaselineModel:
    """
    Fit the baseline model to one axis (module doc).

    Parameters
    ----------
    x : numpy.ndarray
        Angular rate (rad/s).
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    BaselineModel

    """
    n = x.shape[0]
    chunk = int(min(10000, n // 8))
    memory_fit = int(min(DEFAULT_MEMORY, chunk // 2))
    ident = OrderIdentifier(chunk, memory=memory_fit)
    count = int(min(MAX_ID_CHUNKS, n // chunk))
    starts = np.linspace(0, n - chunk, count).astype(np.int64)
    pairs = set()
    for s in starts:
        r = ident(x[s:s + chunk], curves=True)
        v, alphas, f_curve = r.var_curve, r.alphas, r.f_curve
        assert v is not None and alphas is not None and f_curve is not None  # curves=True
        inner = np.flatnonzero((v[1:-1] <= v[:-2]) & (v[1:-1] <= v[2:])) + 1
        for i in [int(np.argmin(v)), *inner.tolist()]:
            if v[i] <= (1.0 + BRANCH_TOLERANCE) * v.min():
                pairs.add((round(float(alphas[i]), 6), round(float(f_curve[i]), 9)))
    freq, pxx = _spectrum(x, rate_hz)
    fits = []
    for alpha, f in sorted(pairs):
        if not stable(alpha, f, memory_fit):
            continue
        memory_sim = simulation_memory(alpha, f, rate_hz, memory_fit=memory_fit)
        if not stable(alpha, f, memory_sim):
            continue
        f = _refine_f(alpha, f, memory_sim, freq, pxx, rate_hz)
        gain = model_gain(alpha, f, memory_sim, freq, rate_hz)
        (var_w, var_nu), misfit = _fit_variances(freq, pxx, gain, rate_hz)
        fits.append((misfit, alpha, f, var_w, var_nu, memory_sim))
    best = None
    if fits:
        lowest = min(fit[0] for fit in fits)
        best = min((fit for fit in fits if fit[0] <= 1.1 * lowest),
                   key=lambda fit: (fit[5], fit[0]))
    else:
        # every identified pair is unstable: fall back to white noise (alpha 0, f 0: v[k+1] = w[k])
        gain = np.ones_like(freq)
        (var_w, var_nu), misfit = _fit_variances(freq, pxx, gain, rate_hz)
        best = (misfit, 0.0, 0.0, var_w, var_nu, MEMORY_STEPS[0])
    misfit, alpha, f, var_w, var_nu, memory_sim = best
    return BaselineModel(bias_rad_s=float(np.mean(x)), alpha=float(alpha), f=float(f),
                         sigma_w_rad_s=float(np.sqrt(var_w)),
                         sigma_nu_rad_s=float(np.sqrt(var_nu)), memory_fit=memory_fit,
                         memory_sim=int(memory_sim), chunk_size=chunk, chunks_identified=count,
                         psd_misfit=misfit)


def without_white(baseline: BaselineModel, x: FloatArray, rate_hz: float,
                  white_var: float) -> BaselineModel:
    """
    Refit a baseline's noise levels with a known white noise taken out of the measurement.

    A record on a lattice of step q carries rounding noise of variance q^2 / 12 (white for a
    step below about two noise sd; Sheppard's correction). A baseline fitted to it holds that
    noise in sigma_w and sigma_nu already; once the lattice is in the model (which rounds its
    members again), the levels must leave it out or the model is louder than the record.

    Parameters
    ----------
    baseline : BaselineModel
        The fitted baseline (alpha, f and the memories are kept).
    x : numpy.ndarray
        The record it was fitted to (rad/s).
    rate_hz : float
        Sample rate (Hz).
    white_var : float
        Variance of the known white noise ((rad/s)^2).

    Returns
    -------
    BaselineModel
        The same model with sigma_w and sigma_nu refitted (module doc, step 4) to the PSD minus
        the known white density ``2 white_var / fs``.

    """
    freq, pxx = _spectrum(x, rate_hz)
    gain = model_gain(baseline.alpha, baseline.f, baseline.memory_sim, freq, rate_hz)
    (var_w, var_nu), misfit = _fit_variances(freq, pxx, gain, rate_hz, float(white_var))
    return replace(baseline, sigma_w_rad_s=float(np.sqrt(var_w)),
                   sigma_nu_rad_s=float(np.sqrt(var_nu)), psd_misfit=misfit)
