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
Seeded forward models of gyroscope noise (paper 000 eqs. 2, 10, 11; first-order Gauss-Markov).

The fractional-order noise of eq. (2), ``Delta^alpha v[k+1] = f v[k] + w[k]`` with the truncated GL
difference of eqs. (3)-(5), is run forward as

    v[k+1] = f v[k] + w[k] - sum_{j=1}^{min(k+1, L)} c_j(alpha) v[k+1-j],   w ~ N(0, sigma_w^2),

starting from rest (zero history, which is exactly the truncation L(k) = min(k, L)). With
measurement noise (eqs. 10-11) the state is x and the output is ``v = x + nu``, ``nu ~ N(0,
sigma_nu^2)``; a constant bias is added last. Generation streams in blocks with O(L) state, so a 12
h record at 6.66 kHz (187,159,392 samples) needs no more memory than its output (or none, block by
block).

Stability. The recursion is a linear filter ``w -> v`` with denominator
``A(z) = 1 + (c_1 - f) z^-1 + sum_{j=2}^{L} c_j z^-j``; it is stable (the output stationary) iff
all L roots of ``z^L A(z)`` lie strictly inside the unit circle. :func:`check_stability` decides
this with the argument principle on a dense unit-circle grid and refuses marginal cases. Two
necessary conditions make the region easy to picture: ``A(1) = S_L(alpha) - f > 0`` with ``S_L =
sum_{j<=L} c_j`` (tiny for alpha near 1, exactly 0 at alpha = 1: hence ``f < 0`` is required there;
f = 0 at alpha = 1 is a random walk), and ``A(-1) = sum_j |c_j| + f > 0`` (roughly ``f >
-2^alpha``).
"""

from dataclasses import dataclass
from functools import lru_cache
import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import lfilter

from ._kernels import _fractional_recursion
from .fractional import DEFAULT_MEMORY, gl_coefficients
from ..errors import ParameterError, UnstableModelError

#: Samples generated per kernel call when streaming (bounds temporary memory).
BLOCK = 1 << 20


@dataclass(frozen=True)
class StabilityReport:
    """
    Outcome of :func:`check_stability`.

    Attributes
    ----------
    stable : bool
        True when every pole of the recursion lies strictly inside the unit circle.
    a_at_one, a_at_minus_one : float
        A(1) and A(-1); both must be positive for stability.
    min_abs_on_circle : float
        Smallest |A(e^{i w})| on the grid, relative to its largest (0 means a pole on the circle).
    winding : int
        Winding number of A(e^{i w}) around 0 (0 for a stable recursion).

    """

    stable: bool
    a_at_one: float
    a_at_minus_one: float
    min_abs_on_circle: float
    winding: int


@lru_cache(maxsize=256)
def check_stability(alpha: float, f: float, memory: int = DEFAULT_MEMORY) -> 'StabilityReport':
    """
    Decide whether the recursion of eq. (2) with these parameters is stable.

    Parameters
    ----------
    alpha : float
        Order (dimensionless).
    f : float
        Noise parameter of eq. (2) (dimensionless).
    memory : int
        L of eq. (5).

    Returns
    -------
    StabilityReport

    """
    with np.errstate(all='ignore'):  # an order so large its coefficients overflow: below
        c = gl_coefficients(alpha, memory)
    a = c.copy()
    a[1] -= f
    if not np.all(np.isfinite(a)):
        return StabilityReport(False, float('nan'), float('nan'), 0.0, 0)
    # 2^17 points resolve the phase of a degree-1000 polynomial unless a root is within ~1e-4 of
    # the circle, which the relative-minimum test below treats as marginal anyway.
    size = 1 << 17
    values = np.fft.fft(a, size)
    mag = np.abs(values)
    rel_min = float(mag.min() / mag.max())
    phase = np.unwrap(np.angle(np.append(values, values[0])))
    winding = int(np.round((phase[-1] - phase[0]) / (2 * np.pi)))
    a1 = float(a.sum())
    am1 = float((a * (-1.0) ** np.arange(a.size)).sum())
    stable = winding == 0 and rel_min > 1e-6 and a1 > 0 and am1 > 0
    return StabilityReport(stable, a1, am1, rel_min, winding)


def require_stable(alpha: float, f: float,
                   memory: int = DEFAULT_MEMORY) -> 'StabilityReport':
    """
    Raise UnstableModelError unless (alpha, f, L) gives a stable recursion.

    Parameters
    ----------
    alpha, f : float
        Model parameters of eq. (2).
    memory : int
        L of eq. (5).

    """
    report = check_stability(float(alpha), float(f), int(memory))
    if not np.isfinite(report.a_at_one):
        raise UnstableModelError(f'fractional noise model alpha={alpha:g}: its GL coefficients '
                                 f'(L={memory}) overflow; the order must be a few units at most')
    if not report.stable:
        raise UnstableModelError(
            f'fractional noise model alpha={alpha}, f={f}, L={memory} is unstable or marginal '
            f'(A(1)={report.a_at_one:.3g} must be > 0, A(-1)={report.a_at_minus_one:.3g} must be '
            '> 0, '
            f'winding number {report.winding} must be 0): its output would not be stationary; '
            f'choose f < {report.a_at_one + f:.4g}')
    return report


class FractionalNoise:
    """
    Stateful, streaming generator of the fractional-order noise of eq. (2) (optionally eqs. 10-11).

    Parameters
    ----------
    alpha : float
        Order of the GL difference (dimensionless).
    f : float
        Noise parameter of eq. (2) (dimensionless).
    sigma_w : float
        Standard deviation of the source noise w (output unit, e.g. rad/s).
    rng : numpy.random.Generator, keyword-only
        Source of randomness.
    memory : int, keyword-only
        L (default 1000).
    sigma_nu : float, keyword-only
        Standard deviation of the white measurement noise of eq. (11) (output unit; 0 = none).
    bias : float, keyword-only
        Constant added to every output sample (output unit).

    """

    def __init__(self, alpha: float, f: float, sigma_w: float, *, rng: np.random.Generator,
                 memory: int = DEFAULT_MEMORY, sigma_nu: float = 0.0, bias: float = 0.0) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ParameterError(f'rng must be a numpy.random.Generator, got {type(rng).__name__}')
        for name, value in (('sigma_w', sigma_w), ('sigma_nu', sigma_nu)):
            if not np.isfinite(value) or value < 0:
                raise ParameterError(f'{name} must be finite and >= 0, got {value}')
        if not np.isfinite(bias):
            raise ParameterError(f'bias must be finite, got {bias}')
        self.alpha, self.f = float(alpha), float(f)
        self.memory = int(memory)
        require_stable(self.alpha, self.f, self.memory)
        self.sigma_w, self.sigma_nu, self.bias = float(sigma_w), float(sigma_nu), float(bias)
        self.rng = rng
        self._c_rev = np.ascontiguousarray(gl_coefficients(self.alpha, self.memory)[:0:-1])
        self._history = np.zeros(self.memory)
        self.samples_generated = 0

    def generate(self, n: int) -> np.ndarray:
        """
        Return the next ``n`` output samples (state carries over between calls).

        Parameters
        ----------
        n : int
            Number of samples (>= 0).

        Returns
        -------
        numpy.ndarray
            float64 samples in the unit of ``sigma_w``.

        """
        n = int(n)
        if n < 0:
            raise ParameterError(f'n must be >= 0, got {n}')
        out = np.empty(n)
        for start in range(0, n, BLOCK):
            stop = min(n, start + BLOCK)
            w = self.rng.standard_normal(stop - start) * self.sigma_w
            self._history = _fractional_recursion(w, self._history, self._c_rev, self.f,
                                                  out[start:stop])
        if self.sigma_nu > 0:
            for start in range(0, n, BLOCK):
                stop = min(n, start + BLOCK)
                out[start:stop] += self.rng.standard_normal(stop - start) * self.sigma_nu
        if self.bias:
            out += self.bias
        self.samples_generated += n
        return out


def simulate_fractional_noise(n: int, alpha: float, f: float, sigma_w: float, *,
                              rng: np.random.Generator, memory: int = DEFAULT_MEMORY,
                              sigma_nu: float = 0.0, bias: float = 0.0) -> np.ndarray:
    """
    Return ``n`` samples of the fractional-order noise of eq. (2) (with eqs. 10-11 and a bias).

    ``FractionalNoise(alpha, f, sigma_w, ...).generate(n)``: order, noise parameter and
    source-noise standard deviation (output unit), the keywords as in :class:`FractionalNoise`.

    """
    return FractionalNoise(alpha, f, sigma_w, rng=rng, memory=memory, sigma_nu=sigma_nu,
                           bias=bias).generate(n)


#: Below this tau / T the Allan variance of a Gauss-Markov process is taken from its series: the
#: closed form's bracket cancels to (2/3) x^3 from terms of order 1, losing ~1e-16 / x^3 relative.
GM_SERIES_BELOW = 0.1
# coefficients of x^k, k = 3..12, of 2x - 3 + 4 exp(-x) - exp(-2x): (-1)^k (4 - 2^k) / k!
_GM_SERIES = tuple((-1.0) ** k * (4.0 - 2.0 ** k) / math.factorial(k) for k in range(3, 13))


def gauss_markov_avar(tau_s: ArrayLike, std: float, corr_time_s: float) -> np.ndarray:
    """
    Allan variance of a stationary first-order Gauss-Markov process (closed form).

    ``sigma^2(tau) = q^2 (T / tau)^2 (2 tau / T - 3 + 4 exp(-tau / T) - exp(-2 tau / T))`` for a
    process of standard deviation q and correlation time T (autocorrelation
    ``q^2 exp(-|t| / T)``). It rises as the rate random walk ``(2 q^2 / T) tau / 3`` for
    tau << T, peaks near tau = 1.89 T at 0.6165 q (ADEV), and falls as white noise
    ``2 q^2 T / tau`` for tau >> T. For tau / T below :data:`GM_SERIES_BELOW` the bracket is
    summed as its Taylor series (terms to x^12, truncation below 1e-12 relative), where the
    closed form loses its digits to cancellation.

    Parameters
    ----------
    tau_s : array_like
        Averaging times (s, > 0).
    std : float
        Process standard deviation q (any rate unit; the result is in its square).
    corr_time_s : float
        Correlation time T (s, > 0).

    Returns
    -------
    numpy.ndarray
        Allan variance at each tau (unit of ``std`` squared).

    """
    if not corr_time_s > 0 or not math.isfinite(corr_time_s):
        raise ParameterError(f'corr_time_s must be finite and > 0, got {corr_time_s}')
    x = np.asarray(tau_s, dtype=np.float64) / float(corr_time_s)
    small = x < GM_SERIES_BELOW
    xs = np.where(small, x, 0.0)
    series = np.zeros_like(xs)
    for coef in reversed(_GM_SERIES):
        series = series * xs + coef
    series = series * xs ** 3
    xl = np.where(small, 1.0, x)
    exact = 2.0 * xl - 3.0 + 4.0 * np.exp(-xl) - np.exp(-2.0 * xl)
    bracket = np.where(small, series, exact)
    with np.errstate(divide='ignore', invalid='ignore'):
        return float(std) ** 2 * bracket / x ** 2


class GaussMarkov:
    """
    Stateful, streaming generator of a first-order Gauss-Markov process, sampled exactly.

    ``x[k+1] = phi x[k] + sqrt(1 - phi^2) q e[k]`` with ``phi = exp(-1 / (rate_hz T))`` and
    ``e`` standard normal is the exact sampling of the continuous process of standard deviation q
    and correlation time T (no discretisation error at any rate); the state starts in its
    stationary distribution, so there is no warm-up transient. Its Allan variance is
    :func:`gauss_markov_avar`.

    Parameters
    ----------
    std : float
        Process standard deviation q (output unit, >= 0).
    corr_time_s : float
        Correlation time T (s, > 0).
    rate_hz : float
        Sample rate (Hz, > 0).
    rng : numpy.random.Generator, keyword-only
        Source of randomness: the initial state is drawn first, then the innovations of each
        :meth:`generate` call in sample order.
    shape : tuple of int, keyword-only
        Shape of one sample (``()`` for a scalar process, ``(3,)`` for three independent axes).

    """

    def __init__(self, std: float, corr_time_s: float, rate_hz: float, *,
                 rng: np.random.Generator, shape: tuple[int, ...] = ()) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ParameterError(f'rng must be a numpy.random.Generator, got {type(rng).__name__}')
        if not math.isfinite(std) or std < 0:
            raise ParameterError(f'std must be finite and >= 0, got {std}')
        for name, value in (('corr_time_s', corr_time_s), ('rate_hz', rate_hz)):
            if not math.isfinite(value) or not value > 0:
                raise ParameterError(f'{name} must be finite and > 0, got {value}')
        self.std = float(std)
        self.corr_time_s = float(corr_time_s)
        self.rate_hz = float(rate_hz)
        self.shape = tuple(int(v) for v in shape)
        self.phi = math.exp(-1.0 / (self.rate_hz * self.corr_time_s))
        # 1 - phi^2 via expm1: phi is within 1e-6 of 1 for T of hours at 6.66 kHz
        self.innovation_std = self.std * math.sqrt(
            -math.expm1(-2.0 / (self.rate_hz * self.corr_time_s)))
        self._rng = rng
        self.state = rng.standard_normal(self.shape) * self.std

    def generate(self, n: int) -> np.ndarray:
        """
        Return the next ``n`` samples (the state carries over between calls).

        Parameters
        ----------
        n : int
            Number of samples (>= 0).

        Returns
        -------
        numpy.ndarray
            Shape ``(n,) + shape``, in the unit of ``std``.

        """
        n = int(n)
        if n < 0:
            raise ParameterError(f'n must be >= 0, got {n}')
        if n == 0:
            return np.zeros((0,) + self.shape)
        e = self._rng.standard_normal((n,) + self.shape) * self.innovation_std
        zi = (self.phi * np.asarray(self.state, dtype=np.float64))[None, ...]
        out, _ = lfilter([1.0], [1.0, -self.phi], e, axis=0, zi=zi)
        self.state = out[-1].copy()
        return out


def gauss_markov(n: int, rate_hz: float, *, std: float, corr_time_s: float,
                 rng: np.random.Generator, shape: tuple[int, ...] = ()) -> np.ndarray:
    """
    Return ``n`` samples of a stationary first-order Gauss-Markov process (:class:`GaussMarkov`).

    ``std`` is its standard deviation q (output unit), ``corr_time_s`` its correlation time T (s),
    ``rate_hz`` the sample rate (Hz); the result has shape ``(n,) + shape``, drawn from ``rng``.
    """
    return GaussMarkov(std, corr_time_s, rate_hz, rng=rng, shape=shape).generate(n)


#: Power-law rate noises with an exact expected Allan variance (:func:`power_law_rate`).
POWER_LAW_ALPHAS = (0, -1, -2)


def power_law_rate(n: int, alpha: int, *, rng: np.random.Generator,
                   oversample: int = 8) -> np.ndarray:
    """
    Return ``n`` samples of power-law rate noise, S_y(f) ~ f^alpha, whose AVAR is known exactly.

    * alpha = 0 (white FM, angle random walk): iid standard normal; AVAR(m) = 1 / m.
    * alpha = -2 (random-walk FM, rate random walk): each sample is the mean over its interval
      of a continuous Brownian rate of unit diffusion (``r(k + 1) = r(k) + w_k``; the sample is
      ``r(k) + w_k / 2 + z_k / sqrt(12)``), so the angle is the point-sampled integral and
      AVAR(m) = m / 3 exactly (IEEE 952: K^2 tau / 3).
    * alpha = -1 (flicker FM, bias instability): the first n points of a circular Gaussian
      process of ``oversample * n`` points with one-sided PSD ``1 / (ln 2 f)`` (f in cycles per
      sample, zero at f = 0), so the AVAR tends to 1 over the middle taus; its exact value at
      every m is :func:`power_law_rate_avar`.

    Parameters
    ----------
    n : int
        Number of samples (>= 1).
    alpha : {0, -1, -2}
        Exponent of the rate PSD.
    rng : numpy.random.Generator, keyword-only
        Source of randomness.
    oversample : int, keyword-only
        Period of the flicker process in records (its lowest frequency is 1 / (oversample n)).

    Returns
    -------
    numpy.ndarray
        (n,) float64 rate samples (unit rate; the time step is one sample).

    """
    n, alpha = int(n), int(alpha)
    if n < 1 or alpha not in POWER_LAW_ALPHAS or int(oversample) < 1:
        raise ParameterError(f'need n >= 1, alpha in {POWER_LAW_ALPHAS}, oversample >= 1; got '
                             f'n = {n}, alpha = {alpha}, oversample = {oversample}')
    if alpha == 0:
        return rng.standard_normal(n)
    if alpha == -2:
        w = rng.standard_normal(n)
        rate = np.concatenate(([0.0], np.cumsum(w)[:-1]))
        return rate + 0.5 * w + rng.standard_normal(n) / math.sqrt(12.0)
    size = int(oversample) * n
    coef = rng.standard_normal(size // 2 + 1) + 1j * rng.standard_normal(size // 2 + 1)
    return np.fft.irfft(coef * _flicker_gain(size), size)[:n]


def _flicker_gain(size: int) -> np.ndarray:
    f = np.fft.rfftfreq(size)
    gain = np.zeros(f.size)
    gain[1:] = np.sqrt(size / (8.0 * math.log(2.0) * f[1:]))
    return gain


def power_law_rate_avar(m: ArrayLike, alpha: int, n: int, *, oversample: int = 8) -> np.ndarray:
    """
    Return the exact expected Allan variance of :func:`power_law_rate` at averaging factors m.

    Flicker: ``AVAR(m) = 1/2 sum_k P_k 4 sin^2(pi f_k m) (sin(pi f_k m) / (m sin(pi f_k)))^2``
    over the bins of the circular process (``P_k`` the variance each contributes), the
    transfer function of the difference of two adjacent m-averages.

    Parameters
    ----------
    m : array_like of int
        Averaging factors (samples).
    alpha : {0, -1, -2}
        As :func:`power_law_rate`.
    n : int
        Record length of :func:`power_law_rate` (sets the flicker process's period).
    oversample : int, keyword-only
        As :func:`power_law_rate`.

    Returns
    -------
    numpy.ndarray
        AVAR at each m (unit rate squared).

    """
    mm = np.asarray(m, dtype=np.float64)
    if int(alpha) == 0:
        return 1.0 / mm
    if int(alpha) == -2:
        return mm / 3.0
    if int(alpha) != -1:
        raise ParameterError(f'alpha must be in {POWER_LAW_ALPHAS}, got {alpha!r}')
    size = int(oversample) * int(n)
    f = np.fft.rfftfreq(size)[1:]
    var = 2.0 * _flicker_gain(size)[1:] ** 2 / size ** 2
    if size % 2 == 0:
        var[:-1] *= 2.0   # every bin but Nyquist stands for +f and -f
    else:
        var *= 2.0
    s = np.sin(np.pi * np.outer(mm.ravel(), f))
    h2 = 4.0 * s ** 2 * (s / (mm.ravel()[:, None] * np.sin(np.pi * f))) ** 2
    return (0.5 * h2 @ var).reshape(mm.shape)
