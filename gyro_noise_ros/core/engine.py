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
Streaming analysis engine shared by the analyzer node and the offline tool (paper 000 3.2-3.5).

One :class:`NoiseEngine` consumes batches of ``(stamp_ns, angular rate xyz in rad/s, optional
temperature in degC)`` and cuts every selected axis into fixed-length chunks (10,000 samples by
default, as in the paper), in three steps so that the caller decides where the heavy part runs:

1. :meth:`NoiseEngine.ingest` (cheap, the caller's thread): validation, stamp and gap accounting
   (:class:`.stamps.StampAccountant`), chunking (:class:`.chunks.Chunker`), per-chunk bias and
   variance (:func:`chunk_jobs`); returns one :class:`ChunkJob` per complete chunk and axis.
2. :func:`analyze_chunk` (heavy, pure, picklable): both fractional-order identifications
   (:class:`.fractional.OrderIdentifier`); safe in a worker thread or process.
3. :meth:`NoiseEngine.record` (cheap): adds the :class:`.results.ChunkResult` to the per-axis
   sequence statistics (paper Tables 3-6, :class:`SequenceBook`) from which
   :meth:`NoiseEngine.summary` and :meth:`NoiseEngine.health` are computed.

The period is ``1 / rate_hz``, or the :mod:`.timebase` estimate of the first
:data:`RATE_ESTIMATE_SAMPLES` stamps while streaming; at the end the estimate over the whole run
replaces it (the Allan taus rescaled to it). ``gap_policy`` says what a gap does to its chunk:
``'flag'`` keeps it, ``'split'`` discards the partial chunk before the gap, ``'drop'`` reports the
chunk as ``'dropped'``. A NaN/Inf sample gives its chunk status ``'nan'`` on its axis only; the
incomplete tail is counted, never dropped silently. The Allan deviation (:class:`AllanFeed`) takes
every finite sample, gaps ignored. The rules of stamps, gaps and loss: docs/offline_tool.md.
"""

from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .allan import AllanAccumulator
from .chunks import (chunk_moments, Chunker, ChunkMoments, DEFAULT_CHUNK_SIZE, noise_colour,
                     SequenceSummary, summarise_sequence)
from .fractional import default_grid, DEFAULT_MEMORY, OrderIdentifier
from .health import evaluate_health, HealthThresholds, reference_per_axis, ReferenceStats
from .readout import fit_noise_terms_band_limited, read_allan
from .results import AxisSummary, ChunkResult, STATUSES
from .stamps import (MAX_GAP_EVENTS, RATE_ESTIMATE_SAMPLES, StampAccountant, StampedBatch,
                     StreamCounts)
from .timebase import RATE_RANGE_HZ, RateEstimate, rescale_allan
from ..errors import InputDataError, ParameterError

__all__ = ['analyze_chunk', 'AllanFeed', 'AXES', 'chunk_jobs', 'ChunkJob', 'EngineConfig',
           'GAP_POLICIES', 'identifier_for', 'MAX_GAP_EVENTS', 'NoiseEngine',
           'RATE_ESTIMATE_SAMPLES', 'SequenceBook', 'StreamCounts', 'warm_up']

#: Axis names in column order of the gyro array.
AXES = ('x', 'y', 'z')
#: Valid gap policies (see module doc).
GAP_POLICIES = ('flag', 'split', 'drop')

_NS = 1_000_000_000
_NAN = float('nan')


@dataclass(frozen=True)
class EngineConfig:
    """
    Options of the streaming engine (every default is the paper's where it has one).

    Attributes
    ----------
    chunk_size : int
        Samples per chunk (paper: 10,000).
    axes : tuple of str
        Axes to analyse, any of 'x', 'y', 'z'.
    alphas : numpy.ndarray or None
        Order grid; None = 0.00:2.00:0.01.
    memory : int
        L of the truncated GL difference (paper: 1000).
    demean : bool
        Remove the chunk mean before identification.
    max_lag : int or None
        Largest lag of J (eq. 13); None = all lags.
    rate_hz : float or None
        Nominal sample rate (Hz); None = estimated from the stamps.
    gap_factor : float
        A stamp step above ``gap_factor`` nominal periods is a gap (issue: 1.5).
    gap_policy : {'flag', 'split', 'drop'}
        What a gap does to its chunk (module doc).
    allan : bool
        Keep an incremental Allan deviation of the whole run.
    allan_taus : {'octave', 'dense'}
        Averaging times of that Allan deviation (octave: 1, 2, 4, ... samples; dense: ~10 per
        decade).
    history_chunks : int
        Chunks kept per axis for the sequence statistics; 0 = all (a live node may bound it).

    """

    chunk_size: int = DEFAULT_CHUNK_SIZE
    axes: tuple[str, ...] = AXES
    alphas: np.ndarray | None = None
    memory: int = DEFAULT_MEMORY
    demean: bool = True
    max_lag: int | None = None
    rate_hz: float | None = None
    gap_factor: float = 1.5
    gap_policy: str = 'flag'
    allan: bool = True
    allan_taus: str = 'dense'
    history_chunks: int = 0

    def __post_init__(self) -> None:
        axes = tuple(self.axes) if not isinstance(self.axes, str) else (self.axes,)
        if not axes or any(a not in AXES for a in axes) or len(set(axes)) != len(axes):
            raise ParameterError(
                f"axes must be distinct names among 'x', 'y', 'z', got {self.axes!r}")
        object.__setattr__(self, 'axes', axes)
        if self.gap_policy not in GAP_POLICIES:
            raise ParameterError(
                f'gap_policy must be one of {GAP_POLICIES}, got {self.gap_policy!r}')
        if not (np.isfinite(self.gap_factor) and self.gap_factor > 1.0):
            raise ParameterError(
                f'gap_factor must be a finite number > 1, got {self.gap_factor!r}')
        if self.rate_hz is not None and not RATE_RANGE_HZ[0] <= self.rate_hz <= RATE_RANGE_HZ[1]:
            raise ParameterError(f'rate_hz must be {RATE_RANGE_HZ[0]:g} to {RATE_RANGE_HZ[1]:g} '
                                 f'Hz or None, got {self.rate_hz!r}')
        if self.allan_taus not in ('octave', 'dense'):
            raise ParameterError(
                f"allan_taus must be 'octave' or 'dense', got {self.allan_taus!r}")
        if int(self.history_chunks) < 0:
            raise ParameterError(f'history_chunks must be >= 0, got {self.history_chunks!r}')
        alphas = (default_grid() if self.alphas is None
                  else np.asarray(self.alphas, dtype=np.float64).ravel())
        alphas.setflags(write=False)
        object.__setattr__(self, 'alphas', alphas)
        # Build once to validate chunk_size / memory / max_lag / grid together with the core's
        # messages.
        identifier_for(self.chunk_size, tuple(alphas.tolist()), int(self.memory),
                       bool(self.demean), self.max_lag)

    def _grid(self) -> np.ndarray:
        """Return the order grid (never None once built: ``__post_init__`` fills the default)."""
        assert self.alphas is not None
        return self.alphas

    def identifier_key(self) -> tuple:
        """Return the hashable arguments of :func:`identifier_for` for this configuration."""
        return (int(self.chunk_size), tuple(self._grid().tolist()), int(self.memory),
                bool(self.demean), None if self.max_lag is None else int(self.max_lag))

    def as_dict(self) -> dict:
        """Return the options as plain JSON-able values (the grid as start/stop/step/count)."""
        a = self._grid()
        return {
            'chunk_size': int(self.chunk_size), 'axes': list(self.axes),
            'order_grid': {'start': float(a[0]), 'stop': float(a[-1]),
                           'step': float(a[1] - a[0]) if a.size > 1 else 0.0,
                           'count': int(a.size)},
            'memory': int(self.memory), 'demean': bool(self.demean), 'max_lag': self.max_lag,
            'rate_hz': self.rate_hz, 'gap_factor': float(self.gap_factor),
            'gap_policy': self.gap_policy,
            'allan': bool(self.allan), 'allan_taus': self.allan_taus,
            'history_chunks': int(self.history_chunks)}


@lru_cache(maxsize=8)
def identifier_for(chunk_size: int, alphas: tuple, memory: int, demean: bool,
                   max_lag: int | None) -> OrderIdentifier:
    """
    Return a cached :class:`.fractional.OrderIdentifier` (its set-up transforms every grid filter).

    The arguments are the identifier's own (``memory`` is L, ``max_lag`` the largest lag of J),
    with ``alphas`` a tuple so that the call can be cached.

    """
    return OrderIdentifier(chunk_size, alphas=np.asarray(alphas), memory=memory, demean=demean,
                           max_lag=max_lag)


@dataclass(frozen=True)
class ChunkJob:
    """
    One complete chunk of one axis, ready for :func:`analyze_chunk` (small, picklable).

    Attributes
    ----------
    axis : str
        'x', 'y' or 'z'.
    chunk : int
        Index of the chunk in the run (shared by the axes; counts every completed chunk).
    samples : numpy.ndarray
        ``chunk_size`` angular rates (rad/s).
    stamp_start_ns : int
        Stamp of the first sample (ns).
    t_start_s, t_mid_s : float
        Time of the first sample and the midpoint of first and last sample, from the first sample
        of the run (s).
    samples_lost, gaps : int
        Samples lost in gaps between this chunk's samples, and the number of such gaps.
    nan_samples : int
        NaN/Inf samples of this axis in the chunk.
    temperature_c : float
        Mean of the finite temperatures of the chunk (degC), NaN if none.
    status : str
        'ok', 'dropped' (gap under the 'drop' policy) or 'nan'.
    bias_rad_s, variance_rad2_s2 : float
        Chunk mean (rad/s) and variance, ddof = 1 ((rad/s)^2); NaN for a 'nan' chunk.
    identifier_key : tuple
        Arguments of :func:`identifier_for`.

    """

    axis: str
    chunk: int
    samples: np.ndarray = field(repr=False, compare=False)
    stamp_start_ns: int
    t_start_s: float
    t_mid_s: float
    samples_lost: int
    gaps: int
    nan_samples: int
    temperature_c: float
    status: str
    bias_rad_s: float
    variance_rad2_s2: float
    identifier_key: tuple = field(repr=False)


def analyze_chunk(job: ChunkJob, identifier: OrderIdentifier | None = None, *,
                  curves: bool = False) -> ChunkResult:
    """
    Identify the fractional order of one chunk by both methods (the heavy, pure step).

    Paper 000 eqs. (3)-(14) via :class:`.fractional.OrderIdentifier`, and the chunk's noise colour
    (:func:`.chunks.noise_colour`). Never raises for bad data: a chunk that cannot be identified
    (NaN, constant) comes back with NaN orders and status 'nan' or 'failed'.

    Parameters
    ----------
    job : ChunkJob
        From :meth:`NoiseEngine.ingest`.
    identifier : OrderIdentifier, optional
        Reused identifier; by default a per-process cached one built from ``job.identifier_key``.
    curves : bool, keyword-only
        Keep the var(alpha) and J(alpha) curves in the result.

    Returns
    -------
    ChunkResult

    """
    # keyword arguments of ChunkResult, of mixed types
    base: dict[str, Any] = {
        'axis': job.axis, 'chunk': job.chunk, 't_start_s': job.t_start_s,
        't_mid_s': job.t_mid_s, 'stamp_start_ns': job.stamp_start_ns,
        'samples': int(job.samples.shape[0]), 'samples_lost': job.samples_lost,
        'gaps': job.gaps, 'nan_samples': job.nan_samples, 'bias_rad_s': job.bias_rad_s,
        'variance_rad2_s2': job.variance_rad2_s2, 'temperature_c': job.temperature_c}
    empty: dict[str, Any] = {
        'alpha_var': _NAN, 'f_var': _NAN, 'var_min': _NAN, 'alpha_corr': _NAN,
        'f_corr': _NAN, 'j_min': _NAN, 'tie_var': False, 'tie_corr': False,
        'noise_colour': _NAN}
    if job.status == 'nan':
        return ChunkResult(**base, **empty, status='nan',
                           message=f'{job.nan_samples} NaN/Inf sample(s) on axis {job.axis}')
    if job.status == 'dropped':
        return ChunkResult(**base, **empty, status='dropped',
                           message=f'{job.gaps} gap(s), {job.samples_lost} sample(s) lost '
                                   '(gap policy drop)')
    if identifier is None:
        identifier = identifier_for(*job.identifier_key)
    try:
        ident = identifier(job.samples, curves=curves)
    except InputDataError as err:
        return ChunkResult(**base, **empty, status='failed', message=str(err))
    return ChunkResult(
        **base, alpha_var=ident.alpha_var, f_var=ident.f_var, var_min=ident.var_min,
        alpha_corr=ident.alpha_corr, f_corr=ident.f_corr, j_min=ident.j_min,
        tie_var=len(ident.tied_alphas_var) > 1, tie_corr=len(ident.tied_alphas_corr) > 1,
        noise_colour=noise_colour(job.samples), status='ok', var_curve=ident.var_curve,
        j_curve=ident.j_curve)


def chunk_jobs(index: int, rel_ns: np.ndarray, lost: int, gaps: int, temperature_c: np.ndarray,
               gyro: np.ndarray, *, axes: tuple, first_ns: int, dropped: bool,
               identifier_key: tuple) -> list[ChunkJob]:
    """
    Return the jobs of one complete chunk: per axis its samples, moments and bookkeeping.

    Parameters
    ----------
    index : int
        Index of the chunk in the run.
    rel_ns : numpy.ndarray of int64
        Its stamps relative to the first stamp of the run (ns).
    lost, gaps : int
        Samples lost inside the chunk and the gaps they fell in.
    temperature_c : numpy.ndarray
        Per-sample temperatures (degC, NaN unknown).
    gyro : numpy.ndarray, shape (n, len(axes))
        Angular rates (rad/s), one column per axis.
    axes : tuple of str, keyword-only
        Axis names of the columns.
    first_ns : int, keyword-only
        Stamp of the run's first sample (ns).
    dropped : bool, keyword-only
        The gap policy leaves this chunk out of the statistics.
    identifier_key : tuple, keyword-only
        Arguments of :func:`identifier_for`.

    Returns
    -------
    list of ChunkJob
        One per axis; the moments are :func:`.chunks.chunk_moments` (NaN for a 'nan' chunk).

    """
    finite_t = temperature_c[np.isfinite(temperature_c)]
    temperature = float(finite_t.mean()) if finite_t.size else _NAN
    t_start = rel_ns[0] / 1e9
    t_mid = (rel_ns[0] + rel_ns[-1]) / 2e9
    jobs = []
    for k, axis in enumerate(axes):
        col = np.ascontiguousarray(gyro[:, k])
        nan = int(col.shape[0] - np.count_nonzero(np.isfinite(col)))
        if nan:
            status, moments = 'nan', ChunkMoments(_NAN, _NAN)
        else:
            status, moments = 'dropped' if dropped else 'ok', chunk_moments(col)
        jobs.append(ChunkJob(
            axis=axis, chunk=index, samples=col, stamp_start_ns=int(rel_ns[0]) + first_ns,
            t_start_s=float(t_start), t_mid_s=float(t_mid), samples_lost=lost, gaps=gaps,
            nan_samples=nan, temperature_c=temperature, status=status, bias_rad_s=moments.bias,
            variance_rad2_s2=moments.variance, identifier_key=identifier_key))
    return jobs


class AllanFeed:
    """
    The Allan deviation of the whole run, per axis: fed every finite sample, read on demand.

    Gaps are ignored (Allan deviation assumes uniform sampling, so heavy loss biases it; the loss
    is reported beside it).

    Parameters
    ----------
    axes : tuple of str
        Axis names, in the column order of the rates fed.
    taus : {'octave', 'dense'}
        Averaging times of the accumulators.

    """

    def __init__(self, axes: tuple, taus: str) -> None:
        self.axes = axes
        self.taus = taus
        self._acc: dict[str, AllanAccumulator] | None = None
        self.error = ''  # why the Allan deviation is unavailable

    def feed(self, gyro: np.ndarray, rate_hz: float) -> None:
        """
        Add rates (rad/s, one column per axis); the first call builds the accumulators.

        Parameters
        ----------
        gyro : numpy.ndarray, shape (n, len(axes))
            Angular rates; NaN/Inf samples are left out.
        rate_hz : float
            Nominal sample rate (Hz) of the accumulators.

        """
        if self.error:
            return
        if self._acc is None:
            try:
                self._acc = {a: AllanAccumulator(rate_hz, taus=self.taus) for a in self.axes}
            except TypeError as err:
                self.error = f'Allan deviation unavailable: {err}'
                return
        for k, axis in enumerate(self.axes):
            col = gyro[:, k]
            finite = np.isfinite(col)
            self._acc[axis].update(col if finite.all() else col[finite])

    def nbytes(self, axis: str) -> int:
        """Bytes the axis' accumulator holds (:attr:`.allan.AllanAccumulator.nbytes`; 0 before)."""
        return 0 if self._acc is None else self._acc[axis].nbytes

    def result(self, axis: str, rate_hz: float | None) -> tuple:
        """
        Return the axis' (Allan result, fitted noise terms); (None, None) when unavailable.

        Parameters
        ----------
        axis : str
            The axis.
        rate_hz : float or None
            Rate the taus are rescaled to (the estimate over the run); None: not rescaled.

        Returns
        -------
        tuple
            (:class:`.allan.AllanResult` or None, noise terms or None).

        """
        if self._acc is None:
            return None, None
        try:
            result = self._acc[axis].result()
            if rate_hz is not None:
                result = rescale_allan(result, rate_hz)
        except (InputDataError, ParameterError, ValueError):
            return None, None
        try:
            terms = fit_noise_terms_band_limited(result)
        except (InputDataError, ParameterError, ValueError):
            terms = None    # too few taus for the fit; the readout still reads the curve
        return result, terms


class _RowStore:
    """
    Rows of floats in arrival order, the newest ``history`` of them (0: all), in one array.

    Each row costs its 8-byte floats (a tuple of Python floats cost ~330 bytes for 9 columns); a
    run kept whole grows by doubling, a bounded one is a ring. :meth:`rows` returns them oldest
    first.
    """

    def __init__(self, columns: int, history: int) -> None:
        self._history = int(history)
        # grown by doubling up to `history` (a large history costs nothing until it fills)
        self._buf = np.empty((min(self._history, 64) or 64, columns))
        self._n = 0  # rows appended so far

    def __len__(self) -> int:
        return min(self._n, self._history) if self._history else self._n

    def append(self, row: tuple) -> None:
        """Add a row (the oldest is dropped once ``history`` rows are kept)."""
        size = len(self._buf)
        if self._n == size and (not self._history or size < self._history):
            grown = np.empty((2 * size if not self._history else min(2 * size, self._history),
                              self._buf.shape[1]))
            grown[:self._n] = self._buf
            self._buf = grown
        self._buf[self._n % len(self._buf)] = row
        self._n += 1

    def rows(self) -> np.ndarray:
        """Return a (n, columns) copy of the rows kept, oldest first."""
        if not self._history or self._n <= self._history:
            return self._buf[:len(self)].copy()
        start = self._n % self._history
        return np.concatenate((self._buf[start:], self._buf[:start]))


class SequenceBook:
    """
    Per-axis record of chunk results: counts by status and the rows of the sequence statistics.

    Parameters
    ----------
    axes : tuple of str
        Axis names.
    history : int
        Chunks kept per axis for the statistics; 0 = all.

    """

    #: Columns of a row (one 'ok' chunk).
    COLUMNS = ('t_mid', 'bias', 'variance', 'alpha_var', 'alpha_corr', 'tie_var', 'tie_corr',
               'temperature', 'noise_colour')

    def __init__(self, axes: tuple, history: int) -> None:
        self._rows = {a: _RowStore(len(self.COLUMNS), history) for a in axes}
        self.nan_samples = dict.fromkeys(axes, 0)
        self.by_status = {a: dict.fromkeys(STATUSES, 0) for a in axes}
        self.last = dict.fromkeys(axes)

    def record(self, result: ChunkResult) -> None:
        """
        Count a chunk result; an 'ok' one enters the statistics (Tables 3-6).

        Parameters
        ----------
        result : ChunkResult
            An analysed chunk of one of the axes.

        """
        if result.axis not in self._rows:
            raise ParameterError(
                f'axis {result.axis!r} is not analysed by this engine ({tuple(self._rows)})')
        counts = self.by_status[result.axis]
        counts[result.status] = counts.get(result.status, 0) + 1
        self.last[result.axis] = result
        if result.status == 'ok':
            self._rows[result.axis].append(
                (result.t_mid_s, result.bias_rad_s, result.variance_rad2_s2, result.alpha_var,
                 result.alpha_corr, result.tie_var, result.tie_corr, result.temperature_c,
                 result.noise_colour))

    def sequence(self, axis: str, *, tail_samples: int,
                 order_step: float) -> tuple[SequenceSummary, float]:
        """
        Return the axis' sequence statistics and the mean of its chunk temperatures (degC).

        Parameters
        ----------
        axis : str
            The axis.
        tail_samples : int, keyword-only
            Carried into the summary.
        order_step : float, keyword-only
            Step of the order grid (floor of the orders' robust spread).

        Returns
        -------
        (SequenceSummary, float)

        """
        rows = self._rows[axis].rows()
        seq = summarise_sequence(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4],
                                 tail_samples=tail_samples, ties_var=int(rows[:, 5].sum()),
                                 ties_corr=int(rows[:, 6].sum()), order_step=order_step,
                                 noise_colour=rows[:, 8])
        temps = rows[:, 7][np.isfinite(rows[:, 7])]
        return seq, float(temps.mean()) if temps.size else _NAN


class NoiseEngine:
    """
    Streaming chunk analysis of a 3-axis gyro: ingest, analyze, record, summarise, judge.

    Composes the pieces the module doc lists: a :class:`.stamps.StampAccountant`, a
    :class:`.chunks.Chunker`, :func:`chunk_jobs`, an :class:`AllanFeed` and a
    :class:`SequenceBook`.

    Parameters
    ----------
    config : EngineConfig
        Options.
    reference : optional, keyword-only
        Reference characterisation for the health verdicts: a path to a ``summary.json`` of the
        offline tool (loaded per configured axis), one :class:`.health.ReferenceStats` for all
        axes, or a dict ``{axis: ReferenceStats}``.
    thresholds : HealthThresholds, optional, keyword-only
        Verdict thresholds (default :class:`.health.HealthThresholds()`).

    """

    def __init__(self, config: EngineConfig | None = None, *,
                 reference: str | Path | ReferenceStats | dict[str, ReferenceStats] | None = None,
                 thresholds: HealthThresholds | None = None) -> None:
        self.config = config if config is not None else EngineConfig()
        self.thresholds = thresholds if thresholds is not None else HealthThresholds()
        self.reference = reference_per_axis(reference, self.config.axes)
        self._cols = [AXES.index(a) for a in self.config.axes]
        self._key = self.config.identifier_key()
        grid = self.config._grid()
        # the grid's step (its mean step if uneven): the floor of the orders' chunk spread
        self._order_step = float((grid[-1] - grid[0]) / (grid.size - 1)) if grid.size > 1 else 0.0
        self._stamps = StampAccountant(self.config.rate_hz, self.config.gap_factor,
                                       self.config.chunk_size)
        self._chunker = Chunker(self.config.chunk_size)
        self._discarded = 0
        self._discarded_partials = 0
        self._allan = AllanFeed(self.config.axes, self.config.allan_taus)
        self._book = SequenceBook(self.config.axes, int(self.config.history_chunks))

    # ---- ingestion ---------------------------------------------------------------------------

    def ingest(self, stamp_ns: npt.ArrayLike, gyro: npt.ArrayLike,
               temperature_c: npt.ArrayLike | None = None) -> list[ChunkJob]:
        """
        Add a batch of samples; return the jobs of the chunks it completes.

        Parameters
        ----------
        stamp_ns : array_like of int, shape (n,)
            Sample stamps (ns), in delivery order.
        gyro : array_like, shape (n, 3)
            Angular rate x, y, z (rad/s). NaN/Inf are counted, not fatal.
        temperature_c : float or array_like of shape (n,), optional
            Sensor temperature (degC) per sample or one value for the batch.

        Returns
        -------
        list of ChunkJob
            One per completed chunk and configured axis, in chunk then axis order.

        """
        stamps = np.asarray(stamp_ns)
        if stamps.dtype.kind not in 'iu':
            raise InputDataError(f'stamp_ns must be integer nanoseconds, got dtype {stamps.dtype}')
        stamps = stamps.astype(np.int64).reshape(-1)
        g = np.asarray(gyro, dtype=np.float64)
        if g.ndim != 2 or g.shape[1] != 3 or g.shape[0] != stamps.shape[0]:
            raise InputDataError(
                f'gyro must have shape ({stamps.shape[0]}, 3) to match stamp_ns, got {g.shape}')
        n = stamps.shape[0]
        if temperature_c is None:
            temp = np.full(n, np.nan)
        else:
            temp = np.broadcast_to(np.asarray(temperature_c, dtype=np.float64),
                                   (n,)).astype(np.float64)
        if n == 0:
            return []
        g = np.ascontiguousarray(g[:, self._cols])
        return self._cut(self._stamps.add(stamps, (temp, g)))

    def flush(self) -> list[ChunkJob]:
        """
        Finish ingestion: release the samples held for the rate estimate; return the jobs they end.

        The incomplete tail stays counted, unanalysed.
        """
        return self._cut(self._stamps.flush())

    def _cut(self, batches: list[StampedBatch]) -> list[ChunkJob]:
        """Feed released samples to the Allan deviation and the chunker; return the jobs."""
        jobs = []
        for batch in batches:
            temp, g = batch.payload
            if self.config.allan:
                assert self._stamps.period_ns is not None  # known before samples are released
                self._allan.feed(g, _NS / self._stamps.period_ns)
            if self.config.gap_policy == 'split' and batch.gap.any():
                # A new chunk starts at the first sample after each gap; the partial chunk
                # before it is discarded, so every analysed chunk is gap-free.
                bounds = [0, *np.flatnonzero(batch.gap).tolist(), batch.rel_ns.shape[0]]
                for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
                    if i > 0:
                        self._discard_partial()
                    jobs += self._push(batch.rel_ns[a:b], batch.lost[a:b], temp[a:b], g[a:b])
            else:
                jobs += self._push(batch.rel_ns, batch.lost, temp, g)
        return jobs

    def _discard_partial(self) -> None:
        dropped = self._chunker.discard()
        if dropped:
            self._discarded += dropped
            self._discarded_partials += 1

    def _push(self, rel: np.ndarray, lost: np.ndarray, temp: np.ndarray,
              g: np.ndarray) -> list[ChunkJob]:
        jobs = []
        first_ns = self._stamps.first_ns
        assert first_ns is not None  # set by the first released samples
        chunks = self._chunker.push_columns(rel, lost, temp, g)
        first_index = self._chunker.chunks_out - len(chunks)
        for index, (rel_c, lost_c, temp_c, g_c) in enumerate(chunks, first_index):
            lost_c[0] = 0  # a gap before the first sample of a chunk is not inside it
            samples_lost, gaps = self._stamps.chunk_loss(rel_c, int(lost_c.sum()),
                                                         int(np.count_nonzero(lost_c)))
            bursty = self._stamps.bursty
            dropped = gaps > 0 and (self.config.gap_policy == 'drop'
                                    or (bursty and self.config.gap_policy == 'split'))
            chunk = chunk_jobs(index, rel_c, samples_lost, gaps, temp_c,
                               g_c, axes=self.config.axes, first_ns=first_ns,
                               dropped=dropped, identifier_key=self._key)
            for job in chunk:
                self._book.nan_samples[job.axis] += job.nan_samples
            jobs += chunk
        return jobs

    # ---- analysis and bookkeeping ------------------------------------------------------------

    @staticmethod
    def analyze(job: ChunkJob, *, curves: bool = False) -> ChunkResult:
        """Identify one chunk (:func:`analyze_chunk`; ``curves``: keep the criterion curves)."""
        return analyze_chunk(job, curves=curves)

    def record(self, result: ChunkResult) -> None:
        """
        Add a chunk result to its axis' sequence statistics (only 'ok' chunks enter Tables 3-6).

        Parameters
        ----------
        result : ChunkResult
            An analysed chunk of this engine.

        """
        self._book.record(result)

    def skip(self, job: ChunkJob, reason: str = '') -> ChunkResult:
        """
        Count a chunk the caller did not analyse (e.g. the node fell behind); shown in diagnostics.

        Parameters
        ----------
        job : ChunkJob
            The chunk not analysed.
        reason : str
            Why (kept in the returned result's message).

        Returns
        -------
        ChunkResult
            A 'skipped' result (already recorded).

        """
        result = replace(analyze_chunk(replace(job, status='dropped')), status='skipped',
                         message=str(reason) or 'skipped')
        self.record(result)
        return result

    def counts(self) -> StreamCounts:
        """
        Return the stream counters.

        Returns
        -------
        StreamCounts

        """
        return self._stamps.counts(chunks=self._chunker.chunks_out,
                                   tail_samples=self._chunker.tail_samples,
                                   discarded_samples=self._discarded,
                                   discarded_partials=self._discarded_partials)

    def timebase(self) -> RateEstimate | None:
        """
        Return the :mod:`.timebase` estimate over every stamp so far (None before 2 stamps).

        Returns
        -------
        timebase.RateEstimate or None

        """
        return self._stamps.timebase()

    def summary(self, *, allan: bool = True) -> dict:
        """
        Summarise every axis (paper Tables 3-6, Allan deviation, counts).

        Parameters
        ----------
        allan : bool, keyword-only
            Compute the Allan deviation and noise terms (the costly part; a live node may ask
            rarely).

        Returns
        -------
        dict
            ``{axis: AxisSummary}`` in configured axis order.

        """
        counts = self.counts()
        book = self._book
        out = {}
        for axis in self.config.axes:
            seq, temperature = book.sequence(axis, tail_samples=counts.tail_samples,
                                             order_step=self._order_step)
            result, terms = (self._allan.result(
                axis, counts.rate_hz if self.config.rate_hz is None else None)
                if allan else (None, None))
            sheet = None
            if result is not None:
                try:
                    sheet = read_allan(result, terms)
                except (InputDataError, ParameterError):
                    sheet = None
            status = book.by_status[axis]
            out[axis] = AxisSummary(
                axis=axis, sequence=seq, stream=counts, nan_samples=book.nan_samples[axis],
                chunks_ok=status['ok'], chunks_nan=status['nan'],
                chunks_dropped=status['dropped'], chunks_failed=status['failed'],
                chunks_skipped=status['skipped'], temperature_mean_c=temperature,
                allan=result, noise_terms=terms, readout=sheet)
        return out

    def health(self, *, seconds_since_data: float | None = None,
               summaries: dict | None = None) -> dict:
        """
        Judge every axis against the reference and the thresholds (see :mod:`.health`).

        Parameters
        ----------
        seconds_since_data : float, optional, keyword-only
            Time since the last sample arrived (s); above ``thresholds.stale_after_s`` the verdict
            is STALE.
        summaries : dict, optional, keyword-only
            Reuse :meth:`summary` output (avoids recomputing it).

        Returns
        -------
        dict
            ``{axis: HealthVerdict}``.

        """
        summaries = summaries if summaries is not None else self.summary(allan=False)
        return {axis: evaluate_health(s, reference=self.reference.get(axis),
                                      thresholds=self.thresholds,
                                      seconds_since_data=seconds_since_data)
                for axis, s in summaries.items()}

    def allan_nbytes(self, axis: str) -> int:
        """
        Bytes the axis' Allan accumulator holds (0 before the first data or with ``allan`` off).

        By design they grow as log2 of the record: 0.5 MiB per doubling once the accumulator's
        rows fill, 6.9 MiB per axis at 12 h of 6.66 kHz ('dense' taus).
        """
        return self._allan.nbytes(axis)

    @property
    def allan_status(self) -> str:
        """Why the Allan deviation is unavailable (empty string when it is available or off)."""
        return self._allan.error


def warm_up(config: EngineConfig) -> None:
    """
    Run the analysis path once on synthetic data so the first real chunk does not stall.

    Builds (and caches, see :func:`identifier_for`) the order identifier of ``config``, plans its
    FFTs, and compiles or loads the numba kernels of the Allan accumulator. A live node calls it
    at start-up (STYLE.md: warm numba kernels before the first chunk).

    Parameters
    ----------
    config : EngineConfig
        The configuration the real data will be analysed with.

    """
    rng = np.random.default_rng(0)
    n = int(config.chunk_size) + 1
    rate_hz = config.rate_hz or 1000.0
    engine = NoiseEngine(replace(config, rate_hz=rate_hz))
    stamps = np.arange(n, dtype=np.int64) * int(_NS / rate_hz)
    jobs = engine.ingest(stamps, rng.standard_normal((n, 3)) * 1e-3)
    for job in jobs[:1]:
        engine.record(engine.analyze(job))
    engine.summary(allan=config.allan)
