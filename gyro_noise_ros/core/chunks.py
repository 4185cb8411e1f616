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
Streaming chunker, per-chunk statistics and per-sequence summaries (paper 000 sections 3.2-3.5).

A sequence of angular-rate samples (rad/s) is cut into fixed-length chunks (:class:`Chunker`,
10,000 samples by default, as in the paper); per chunk the bias (mean) and the variance (``ddof =
1``) are taken (:func:`chunk_moments`), and the fractional order is identified by both methods
(:mod:`.fractional`). Per sequence (:func:`summarise_sequence` -> :class:`SequenceSummary`):

* Table 3, the offset drift: the least-squares slope of the chunk bias against the chunk mid time
  (rad/s per s; (deg/s)/h in reports), with a standard error that holds for correlated chunk biases
  (:func:`offset_drift`, :func:`drift_stderr`);
* Table 4, the mean of the chunk variances and the variance of the chunk variances;
* Tables 5 and 6, the mean and the variance of the chunk orders of each method;

variances across chunks with ``ddof = 1``. Every per-chunk quantity (bias, log variance, both
orders, the noise colour) also gets a robust location and spread (:func:`robust_location`: the
median of the chunks, or of the dominant mode when the orders fall in separate basins,
:func:`order_modes`; the normal-consistent standard deviation without the 5 % lowest and highest),
which :mod:`.health` compares like with like. The noise colour of a chunk (:func:`noise_colour`) is
the least-squares log-log slope of its overlapping Allan deviation over m = 2, 4, ..., 64 samples
(-0.5 white rate noise, 0 flicker, +0.5 random walk). Why a slope for the drift, and how the
paper's units read: docs/analysis.md; what the colour detects: docs/verdicts.md.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray
from scipy.special import ndtri

from .allan import allan_deviation_values
from ..errors import InputDataError, ParameterError

#: Default chunk length (paper 000 section 3.2).
DEFAULT_CHUNK_SIZE = 10000

#: Averaging factors (samples) of the noise colour (:func:`noise_colour`). m = 1 is left out: on
#: band-limited sensors (the ADIS16405's Bartlett filter) the ADEV bends there. m = 64 keeps ~230
#: EDF from a 10,000-sample chunk of white noise, and a chunk of 256 samples holds it under the
#: N/4 rule of the Allan taus.
NOISE_COLOUR_FACTORS = (2, 4, 8, 16, 32, 64)


class Chunker:
    """
    Cut a stream of samples into fixed-length chunks; nothing is dropped silently.

    The one chunker of the package: the offline scripts cut plain sample arrays with
    :meth:`push`, and :class:`.engine.NoiseEngine` cuts its stamps, per-sample losses,
    temperatures and rates together with :meth:`push_columns`.

    Parameters
    ----------
    size : int
        Samples per chunk (>= 2).

    Notes
    -----
    ``push`` accepts 1-D samples or 2-D ``(n, axes)`` arrays (one column per axis); chunks are
    returned as new arrays (never views of the caller's buffer). The incomplete tail stays
    available as :attr:`tail` and is counted in :attr:`tail_samples`, for reports.

    """

    def __init__(self, size: int = DEFAULT_CHUNK_SIZE) -> None:
        size_i = int(size)
        if size_i != size or size_i < 2:
            raise ParameterError(f'chunk size must be an integer >= 2, got {size!r}')
        self.size = size_i
        self._parts: list[tuple[np.ndarray, ...]] = []  # tuples of aligned column arrays
        self._shape: tuple[tuple[int, ...], ...] | None = None
        self._buffered = 0
        self.samples_in = 0
        self.chunks_out = 0

    def push(self, samples: npt.ArrayLike) -> list[NDArray[np.float64]]:
        """
        Add samples; return the list of chunks completed by them (possibly empty).

        Parameters
        ----------
        samples : array_like
            1-D, or 2-D with one column per axis (the column count must not change).

        Returns
        -------
        list of numpy.ndarray

        """
        samples = np.asarray(samples, dtype=np.float64)
        if samples.ndim not in (1, 2):
            raise InputDataError(f'samples must be 1-D or 2-D, got shape {samples.shape}')
        return [c[0] for c in self.push_columns(samples)]

    def push_columns(self, *columns: np.ndarray) -> list:
        """
        Add aligned arrays (one row per sample); return the chunks they complete, cut alike.

        Parameters
        ----------
        *columns : numpy.ndarray
            Arrays of equal first dimension (any dtype, kept); the shape of each after the first
            dimension must not change between calls.

        Returns
        -------
        list of tuple of numpy.ndarray
            One tuple per completed chunk, the columns in the order given, each a new array of
            ``size`` rows.

        """
        n = columns[0].shape[0]
        shape = tuple(c.shape[1:] for c in columns)
        if any(c.shape[0] != n for c in columns):
            raise InputDataError(
                f'columns must have equal lengths, got {[c.shape[0] for c in columns]}')
        if self._shape is None:
            self._shape = shape
        elif shape != self._shape:
            old, new = (s[0] if len(s) == 1 else s for s in (self._shape, shape))
            raise InputDataError(f'sample shape changed from {old} to {new}')
        self.samples_in += n
        out: list[tuple[np.ndarray, ...]] = []
        if n == 0:
            return out
        self._parts.append(columns)
        self._buffered += n
        if self._buffered < self.size:
            return out
        joined = (tuple(np.concatenate(c) for c in zip(*self._parts)) if len(self._parts) > 1
                  else columns)
        n_all = joined[0].shape[0]
        whole = (n_all // self.size) * self.size
        for start in range(0, whole, self.size):
            out.append(tuple(np.array(c[start:start + self.size]) for c in joined))
        rest = tuple(np.array(c[whole:]) for c in joined)
        self._parts = [rest] if n_all > whole else []
        self._buffered = n_all - whole
        self.chunks_out += len(out)
        return out

    def discard(self) -> int:
        """
        Throw the incomplete tail away (a gap under the 'split' policy); return its length.

        Returns
        -------
        int
            Samples discarded.

        """
        dropped = self._buffered
        self._parts = []
        self._buffered = 0
        return dropped

    @property
    def tail(self) -> NDArray[Any] | tuple[NDArray[Any], ...]:
        """Copy the incomplete tail into a new array (fewer than ``size`` samples)."""
        if not self._parts:
            return np.empty(0)
        tails = tuple(np.concatenate(c) for c in zip(*self._parts))
        return tails[0] if len(tails) == 1 else tails

    @property
    def tail_samples(self) -> int:
        """Count the samples in the incomplete tail."""
        return self._buffered


@dataclass(frozen=True)
class ChunkMoments:
    """
    Bias and variance of one chunk (paper 000 sections 3.3, 3.4).

    Attributes
    ----------
    bias : float
        Chunk mean (input unit, rad/s here).
    variance : float
        Chunk variance, ddof = 1 (squared input unit).

    """

    bias: float
    variance: float


def chunk_moments(chunk: npt.ArrayLike) -> ChunkMoments:
    """
    Return the bias (mean) and variance of one chunk.

    Parameters
    ----------
    chunk : array_like
        Finite samples (at least 2).

    Returns
    -------
    ChunkMoments

    """
    v = np.asarray(chunk, dtype=np.float64)
    if v.ndim != 1 or v.shape[0] < 2:
        raise InputDataError(
            f'a chunk needs at least 2 samples in one dimension, got shape {v.shape}')
    if not np.all(np.isfinite(v)):
        raise InputDataError(f'chunk has {int((~np.isfinite(v)).sum())} NaN/Inf sample(s)')
    return ChunkMoments(float(v.mean()), float(v.var(ddof=1)))


def noise_colour(chunk: npt.ArrayLike, *, factors: Sequence[int] = NOISE_COLOUR_FACTORS) -> float:
    """
    Return the noise colour of one chunk: the log-log slope of its Allan deviation.

    The least-squares slope of ``log ADEV(m)`` against ``log m`` over ``factors``, with the fully
    overlapping Allan deviation of :func:`.allan.allan_deviation_values` (paper 001 eq. 7, NIST
    SP 1065 eq. 11). Dimensionless and independent of the sample rate, the scale and the mean of
    the chunk: -0.5 for white rate noise, 0 for flicker, +0.5 for a random walk (module doc).

    Parameters
    ----------
    chunk : array_like
        Finite rate samples of one chunk (any unit, e.g. rad/s).
    factors : sequence of int, keyword-only
        Averaging factors (samples, >= 1, at least two distinct).

    Returns
    -------
    float
        The slope; NaN when the chunk is shorter than ``4 * max(factors)`` samples (the N/4 rule
        of the Allan taus) or constant (zero Allan deviation).

    Raises
    ------
    InputDataError
        Not 1-D, or NaN/Inf samples.
    ParameterError
        Fewer than two distinct factors, or a factor below 1.

    """
    v = np.asarray(chunk, dtype=np.float64)
    if v.ndim != 1:
        raise InputDataError(f'a chunk must be 1-D, got shape {v.shape}')
    if not np.all(np.isfinite(v)):
        raise InputDataError(f'chunk has {int((~np.isfinite(v)).sum())} NaN/Inf sample(s)')
    m = np.unique(np.asarray(factors, dtype=np.int64))
    if m.size < 2 or m[0] < 1:
        raise ParameterError(
            f'factors must hold at least two distinct averaging factors >= 1, got {factors!r}')
    if v.shape[0] < 4 * m[-1]:
        return float('nan')
    # the deviation alone (bit for bit allan_deviation's adev): the noise identification, EDF
    # and intervals would cost several times the estimate on every chunk
    adev = allan_deviation_values(v, 1.0, taus=m)
    if not np.all(adev > 0):
        return float('nan')
    x = np.log(m.astype(np.float64))
    xc = x - x.mean()
    return float(xc @ np.log(adev) / (xc @ xc))


@dataclass(frozen=True)
class DriftEstimate:
    """
    Least-squares drift of the chunk bias over time (the Table 3 quantity, see module doc).

    Attributes
    ----------
    slope : float
        Signed slope, input unit per second (rad/s^2 for rates in rad/s).
    stderr : float
        Its standard error, valid for correlated chunk biases (same unit): the largest of the
        ordinary least-squares, the Newey-West and the variogram standard errors (see
        :func:`drift_stderr`); NaN with fewer than 3 chunks.
    intercept : float
        Fitted bias at t = 0 (input unit).
    span_s : float
        Time between the first and last chunk mid-times (s).
    stderr_ols : float
        The ordinary least-squares standard error (independent chunk biases assumed).

    """

    slope: float
    stderr: float
    intercept: float
    span_s: float
    stderr_ols: float = float('nan')

    @property
    def magnitude(self) -> float:
        """|slope|, the paper's 'offset drift' (input unit per second)."""
        return abs(self.slope)


def offset_drift(t_s: npt.ArrayLike, bias: npt.ArrayLike) -> DriftEstimate:
    """
    Fit the chunk bias against time by least squares (offset drift, paper 000 Table 3).

    Parameters
    ----------
    t_s : array_like
        Chunk mid-times (s).
    bias : array_like
        Chunk biases (rate unit).

    Returns
    -------
    DriftEstimate
        NaN slope for fewer than 2 chunks.

    """
    t = np.asarray(t_s, dtype=np.float64)
    b = np.asarray(bias, dtype=np.float64)
    if t.shape != b.shape or t.ndim != 1:
        raise InputDataError(
            f't_s and bias must be 1-D of equal length, got {t.shape} and {b.shape}')
    ok = np.isfinite(t) & np.isfinite(b)
    t, b = t[ok], b[ok]
    if t.size < 2 or np.ptp(t) == 0:
        return DriftEstimate(float('nan'), float('nan'), float(b.mean()) if b.size
                             else float('nan'), 0.0)
    tc = t - t.mean()
    sxx = float(tc @ tc)
    slope = float(tc @ (b - b.mean()) / sxx)
    intercept = float(b.mean() - slope * t.mean())
    if t.size > 2:
        resid = b - (intercept + slope * t)
        stderr_ols = float(np.sqrt((resid @ resid) / (t.size - 2) / sxx))
        stderr = max(stderr_ols, drift_stderr(t, b))
    else:
        stderr = stderr_ols = float('nan')
    return DriftEstimate(slope, stderr, intercept, float(np.ptp(t)), stderr_ols)


def drift_stderr(t_s: npt.ArrayLike, bias: npt.ArrayLike) -> float:
    """
    Return a standard error of the drift slope that holds for correlated chunk biases.

    Neighbouring chunk biases of a real gyro correlate (flicker and random-walk bias), where the
    ordinary least-squares error falls short. The slope is ``sum(w_k b_k)`` with ``w_k = (t_k -
    mean t) / Sxx`` and ``sum(w_k) = 0``, so for any intrinsically stationary bias process (random
    walk included) ``Var(slope) = -1/2 sum_jk w_j w_k D(|j - k|)`` with ``D(m) = E[(b_{k+m} -
    b_k)^2]`` the variogram of the chunk biases (Cressie 1993, eq. 2.4.5), estimated from the
    detrended biases (lags up to half the run, held constant beyond: detrending keeps a real drift
    from inflating its own error). The Newey-West (Bartlett, ``ceil(n^(1/3))`` lags) error is
    computed too and the larger of the two returned (the variogram estimate can come out negative
    or tiny on short records). Chunks are taken as equally spaced. How both compare with the
    spread of slopes across real runs: docs/analysis.md.

    Parameters
    ----------
    t_s : array_like
        Chunk mid-times (s), finite.
    bias : array_like
        Chunk biases (rate unit), finite.

    Returns
    -------
    float
        Standard error of the slope (rate unit per second); NaN with fewer than 3 chunks.

    """
    t = np.asarray(t_s, dtype=np.float64)
    b = np.asarray(bias, dtype=np.float64)
    n = t.size
    if n < 3 or np.ptp(t) == 0:
        return float('nan')
    tc = t - t.mean()
    sxx = float(tc @ tc)
    w = tc / sxx
    slope = float(w @ (b - b.mean()))
    resid = b - b.mean() - slope * tc
    u = tc * resid
    lags = int(np.ceil(n ** (1.0 / 3.0)))
    s = float(u @ u)
    for m in range(1, min(lags, n - 1) + 1):
        s += 2.0 * (1.0 - m / (lags + 1.0)) * float(u[m:] @ u[:-m])
    nw = np.sqrt(max(s, 0.0) * n / (n - 2)) / sxx
    centred = resid
    half = max(1, n // 2)
    d = np.empty(n)
    d[0] = 0.0
    for m in range(1, n):
        d[m] = np.mean((centred[m:] - centred[:-m]) ** 2) if m <= half else d[half]
    # -1/2 sum_jk w_j w_k D(|j - k|) = -sum_{m >= 1} D(m) sum_j w_j w_{j+m} (D(0) = 0): the
    # autocorrelation of w by FFT, O(n log n), where the n x n matrix of D took 5.6 GB and 14 s
    # for the 18,715 chunks of the paper's sequence
    size = 2 * n
    spec = np.fft.rfft(w, size)
    auto = np.fft.irfft(spec.real ** 2 + spec.imag ** 2, size)[1:n]
    var = -float(d[1:] @ auto)
    vario = np.sqrt(var) if var > 0 else 0.0
    return float(max(nw, vario))


@dataclass(frozen=True)
class SequenceSummary:
    """
    Per-sequence summary of chunk results (paper 000 Tables 3-6).

    Attributes
    ----------
    chunks : int
        Number of complete chunks analysed.
    tail_samples : int
        Samples left after the last complete chunk (reported, not analysed).
    bias_mean : float
        Mean chunk bias (rate unit).
    drift : DriftEstimate
        Offset drift (Table 3).
    mean_variance, variance_of_variances : float
        Table 4 (squared rate unit; its square).
    alpha_var_mean, alpha_var_variance : float
        Table 5 (variance method).
    alpha_corr_mean, alpha_corr_variance : float
        Table 6 (correlation method).
    ties_var, ties_corr : int
        Chunks whose minimum was an exact tie (see :mod:`.fractional`).
    alpha_var_modes, alpha_corr_modes : tuple of (float, int)
        (mean order, chunks) of each mode when the chunk orders fall in separate basins
        (:func:`order_modes`); empty when the distribution is unimodal, so the mean is meaningful.
    bias_robust, log_variance_robust, alpha_var_robust, alpha_corr_robust : RobustLocation or None
        Robust location and spread of the chunk biases (rate unit), of the natural log of the
        chunk variances (log of the squared rate unit) and of the chunk orders (dominant mode when
        multimodal), for the reference check; None when not computed.
    noise_colour_robust : RobustLocation or None
        Robust location and spread of the chunks' noise colour (:func:`noise_colour`,
        dimensionless); None when not computed.

    """

    chunks: int
    tail_samples: int
    bias_mean: float
    drift: DriftEstimate
    mean_variance: float
    variance_of_variances: float
    alpha_var_mean: float
    alpha_var_variance: float
    alpha_corr_mean: float
    alpha_corr_variance: float
    ties_var: int
    ties_corr: int
    alpha_var_modes: tuple[tuple[float, int], ...] = ()
    alpha_corr_modes: tuple[tuple[float, int], ...] = ()
    bias_robust: 'RobustLocation | None' = None
    log_variance_robust: 'RobustLocation | None' = None
    alpha_var_robust: 'RobustLocation | None' = None
    alpha_corr_robust: 'RobustLocation | None' = None
    noise_colour_robust: 'RobustLocation | None' = None


def summarise_sequence(t_mid_s: npt.ArrayLike, bias: npt.ArrayLike, variance: npt.ArrayLike,
                       alpha_var: npt.ArrayLike, alpha_corr: npt.ArrayLike, *,
                       tail_samples: int = 0, ties_var: int = 0, ties_corr: int = 0,
                       order_step: float = 0.0,
                       noise_colour: npt.ArrayLike | None = None) -> SequenceSummary:
    """
    Summarise per-chunk results of one sequence and axis (paper 000 Tables 3-6).

    Parameters
    ----------
    t_mid_s : array_like
        Chunk mid-times (s).
    bias, variance : array_like
        Chunk bias (rate unit) and variance (squared rate unit).
    alpha_var, alpha_corr : array_like
        Chunk orders of the variance and correlation methods (NaN where not identified).
    tail_samples, ties_var, ties_corr : int, keyword-only
        Counts carried into the summary.
    order_step : float, keyword-only
        Step of the order grid (floor of the orders' robust spread, :func:`robust_location`).
    noise_colour : array_like, optional, keyword-only
        Chunk noise colours (:func:`noise_colour`; NaN where not computed); None: not summarised.

    Returns
    -------
    SequenceSummary

    """
    bias = np.asarray(bias, dtype=np.float64)
    variance = np.asarray(variance, dtype=np.float64)

    def mean_var(values: npt.ArrayLike) -> tuple[float, float]:
        x = np.asarray(values, dtype=np.float64)
        x = x[np.isfinite(x)]
        if x.size == 0:
            return float('nan'), float('nan')
        return float(x.mean()), float(x.var(ddof=1)) if x.size > 1 else float('nan')

    mv, vv = mean_var(variance)
    av_m, av_v = mean_var(alpha_var)
    ac_m, ac_v = mean_var(alpha_corr)
    with np.errstate(divide='ignore', invalid='ignore'):
        log_var = np.log(variance)
    return SequenceSummary(chunks=int(bias.size), tail_samples=int(tail_samples),
                           bias_mean=float(np.nanmean(bias)) if bias.size else float('nan'),
                           drift=offset_drift(t_mid_s, bias), mean_variance=mv,
                           variance_of_variances=vv, alpha_var_mean=av_m, alpha_var_variance=av_v,
                           alpha_corr_mean=ac_m, alpha_corr_variance=ac_v, ties_var=int(ties_var),
                           ties_corr=int(ties_corr), alpha_var_modes=order_modes(alpha_var),
                           alpha_corr_modes=order_modes(alpha_corr),
                           bias_robust=robust_location(bias),
                           log_variance_robust=robust_location(log_var),
                           alpha_var_robust=robust_location(alpha_var, resolution=order_step,
                                                            modes=True),
                           alpha_corr_robust=robust_location(alpha_corr, resolution=order_step,
                                                             modes=True),
                           noise_colour_robust=(None if noise_colour is None
                                                else robust_location(noise_colour)))


#: Smallest gap between sorted chunk orders that separates two modes (order units). The model's
#: 0/1 alias puts basins ~1.0 apart; the paper's spread of sequence means is 0.009 (variance
#: method) and of chunk orders ~0.4 (correlation method, a wide unimodal cloud), hence also the 3x
#: rule.
MODE_GAP = 0.3


def _mode_pieces(orders: npt.ArrayLike, gap: float) -> list[NDArray[np.float64]]:
    x = np.sort(np.asarray(orders, dtype=np.float64))
    x = x[np.isfinite(x)]
    if x.size < 4:
        return []
    cuts = np.flatnonzero(np.diff(x) > gap) + 1
    if cuts.size == 0:
        return []
    pieces = np.split(x, cuts)
    if sum(p.size >= 2 for p in pieces) < 2:
        return []
    within = np.concatenate([p - p.mean() for p in pieces])
    pooled = float(np.sqrt(within @ within / max(within.size - len(pieces), 1)))
    if np.min(np.diff(x)[cuts - 1]) <= 3.0 * pooled:
        return []
    return pieces


def order_modes(orders: npt.ArrayLike, *,
                gap: float = MODE_GAP) -> tuple[tuple[float, int], ...]:
    """
    Split chunk orders into modes: ``(mean order, chunk count)`` per mode, ascending; () unimodal.

    The sorted finite orders (NaN ignored) are cut at every gap wider than ``gap`` (order units)
    and than 3x the pooled standard deviation inside the pieces; two or more pieces of >= 2 chunks
    are modes (three chunks at 0.02 and three at 1.02 are two modes, not one at 0.52).
    """
    return tuple((float(p.mean()), int(p.size)) for p in _mode_pieces(orders, gap))


#: Fraction of the chunks left out on each side before the standard deviation of the rest is the
#: robust spread (rounded down to whole chunks: none below 20 chunks).
SPREAD_TRIM = 0.05


def _truncated_sd(kept: float) -> float:
    """Return the SD of a standard normal truncated to its central ``kept`` fraction."""
    if kept >= 1.0:
        return 1.0
    z = float(ndtri(0.5 + kept / 2.0))
    return math.sqrt(1.0 - 2.0 * z * math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi) / kept)


@dataclass(frozen=True)
class RobustLocation:
    """
    Robust location and spread of one quantity over the chunks of a sequence.

    Attributes
    ----------
    location : float
        Median of the population (input unit).
    spread : float
        Standard deviation of the population without its ``floor(0.05 n)`` lowest and highest
        values, divided by that of a standard normal truncated alike (0.7893 for 100 chunks), so
        that it estimates the standard deviation of normal chunk values while 5 % outliers on
        either side cannot move it; never below ``resolution / sqrt(12)`` (the spread of values
        rounded to a grid). Input unit.
    count : int
        Chunks in the population.
    total : int
        Finite chunk values.
    population : str
        'all chunks' or 'dominant mode' (the largest of :func:`order_modes`' basins).
    modes : tuple of (float, int)
        :func:`order_modes` of the values when asked for, else empty.

    """

    location: float
    spread: float
    count: int
    total: int
    population: str = 'all chunks'
    modes: tuple[tuple[float, int], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """
        Return the fields as JSON-able values (NaN as None, modes as lists).

        Returns
        -------
        dict

        """
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {'location': num(self.location), 'spread': num(self.spread),
                'count': int(self.count), 'total': int(self.total),
                'population': self.population,
                'modes': [[float(m), int(c)] for m, c in self.modes]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'RobustLocation':
        """
        Build from :meth:`as_dict` output (a reference summary.json).

        Parameters
        ----------
        d : dict
            As written by :meth:`as_dict`.

        Returns
        -------
        RobustLocation

        """
        def num(v: float | None) -> float:
            return float('nan') if v is None else float(v)

        return cls(location=num(d['location']), spread=num(d['spread']), count=int(d['count']),
                   total=int(d['total']), population=str(d['population']),
                   modes=tuple((float(m), int(c)) for m, c in d.get('modes', ())))


def robust_location(values: npt.ArrayLike, *, resolution: float = 0.0, modes: bool = False,
                    gap: float = MODE_GAP) -> RobustLocation:
    """
    Return the robust location and spread of per-chunk values (module doc).

    Parameters
    ----------
    values : array_like
        One value per chunk (NaN/Inf ignored).
    resolution : float, keyword-only
        Grid step of the values (the order grid; 0 for continuous values): the spread is at least
        ``resolution / sqrt(12)``, so identical chunk orders do not give a zero tolerance.
    modes : bool, keyword-only
        Look for separate basins (:func:`order_modes`) and describe the dominant one.
    gap : float, keyword-only
        Smallest gap separating modes (order units).

    Returns
    -------
    RobustLocation
        NaN location and spread without finite values.

    """
    x = np.asarray(values, dtype=np.float64).ravel()
    x = x[np.isfinite(x)]
    total = int(x.size)
    found: tuple[tuple[float, int], ...] = ()
    population = 'all chunks'
    if modes:
        pieces = _mode_pieces(x, gap)
        if pieces:
            found = tuple((float(p.mean()), int(p.size)) for p in pieces)
            # the largest basin; between equal ones the higher order, as for exact ties in
            # fractional.py (order 1 is the paper's integer-order model)
            x = max(reversed(pieces), key=len)
            population = 'dominant mode'
    if x.size == 0:
        return RobustLocation(float('nan'), float('nan'), 0, total, population, found)
    floor = float(resolution) / math.sqrt(12.0)
    if x.size < 2:
        return RobustLocation(float(x[0]), float('nan'), 1, total, population, found)
    n = x.size
    k = int(SPREAD_TRIM * n)
    central = np.sort(x)[k:n - k]
    spread = (float(central.std(ddof=1)) / _truncated_sd(central.size / n)
              if central.size > 1 else 0.0)
    return RobustLocation(float(np.median(x)), max(spread, floor), int(x.size), total,
                          population, found)
