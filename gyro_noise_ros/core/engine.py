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

Issue 4.

One :class:`NoiseEngine` consumes batches of ``(stamp_ns, angular rate xyz in rad/s, optional
temperature)`` and cuts every selected axis into fixed-length chunks (10,000 samples by default, as
in the paper). The work is split in three steps so that the caller decides where the heavy part
runs:

1. :meth:`NoiseEngine.ingest` (cheap, in the caller's thread): validation, gap and stamp-order
   counting, chunking, per-chunk bias and variance; returns one :class:`ChunkJob` per complete
   chunk and axis.
2. :func:`analyze_chunk` (heavy, pure, picklable): fractional-order identification by both methods
   (:class:`.fractional.OrderIdentifier`); safe in a worker thread or process.
3. :meth:`NoiseEngine.record` (cheap): adds the :class:`ChunkResult` to the per-axis sequence
   statistics (paper Tables 3-6) from which :meth:`NoiseEngine.summary` and
   :meth:`NoiseEngine.health` are computed.

Stamps and gaps. Rates come from :mod:`.timebase` (one estimator for every tool). While streaming,
the period is ``1 / rate_hz``, or when ``rate_hz`` is None the :mod:`.timebase` estimate of the
first :data:`RATE_ESTIMATE_SAMPLES` stamps (samples are held back until then). At the end
(:meth:`NoiseEngine.counts`, :meth:`NoiseEngine.summary`) the estimate over the whole run replaces
it: the Allan taus are rescaled to it (tau = m / rate), and the counts report the method, the stamp
jitter and the disagreement warnings.

*Regular* stamps (a device clock): steps are taken from the latest stamp seen so far; a step larger
than ``gap_factor`` nominal periods is a gap that lost ``round(step / period) - 1`` samples when it
is a whole number of periods (within 6 robust sigmas of the step scatter, 0.1-0.45 of a period) or
2.5 periods and more. A long step of a fractional number of periods below that is a correction of
the stamping clock (a driver re-anchoring its device-clock map, a host clock slewing: every later
stamp stays on the grid), counted as a clock step (``StreamCounts.clock_steps``), not as loss.
Samples that share the stamp right after a long step (a packet stamped once) are the samples the
step seemed to skip: they are subtracted from its loss (a group reaching the end of a batch waits
for the next batch), so a packet-stamped record shows no phantom loss. Every gap is kept as (start,
length, missing samples) and the longest are reported (``StreamCounts.longest_gaps``).
*Bursty* stamps (host receive times, USB packets; :mod:`.timebase`: more than 1 % of the steps
shorter than half a period): a long step followed by a burst is jitter, not loss, so single steps
are not read. Loss is the deficit of samples against elapsed time, per chunk (``round(span * rate)
+ 1 - n`` when it exceeds the chunk's jitter allowance; such a chunk counts one gap) and over the
run (the timebase estimate). Under 'split' or 'drop' such a chunk is dropped (there is no single
step to split at). A step of zero (a stamp equal to the latest one: one packet) is a normal time
base, counted in ``equal_stamps`` and nothing else. A step < 0 is an out-of-order stamp: counted,
never reordered, never a gap. So two swapped samples count as one out-of-order stamp *and* one
one-sample gap (the hole is seen before the late sample arrives; the engine does not look back to
fill it). The
``gap_policy`` decides what a gap does to the chunk it falls in:

* ``'flag'`` (default): the chunk is kept and analysed; its ``samples_lost`` and ``gaps`` say so.
* ``'split'``: the partial chunk before the gap is discarded (counted in ``discarded_samples`` and
  ``discarded_partials``) and a new chunk starts at the first sample after the gap, so every
  analysed chunk is gap-free.
* ``'drop'``: a chunk containing a gap is reported with status ``'dropped'`` and left out of the
  sequence statistics.

NaN/Inf samples never stop the stream: they are counted, the chunk holding them gets status
``'nan'`` (per axis: a NaN on x does not spoil y), its moments and orders are NaN and it is left
out of the statistics. The incomplete tail at the end is counted (``tail_samples``), never silently
dropped.

Allan deviation. When ``allan`` is on and :mod:`.allan` provides an incremental accumulator, every
finite sample of every axis goes into it (gaps are ignored: Allan deviation assumes uniform
sampling, so heavy loss biases it; the loss is reported beside it).
"""

from collections import deque
from dataclasses import dataclass, field, fields, replace
from functools import lru_cache

import numpy as np

from .chunks import DEFAULT_CHUNK_SIZE, noise_colour, SequenceSummary, summarise_sequence
from .fractional import default_grid, DEFAULT_MEMORY, OrderIdentifier
from .readout import fit_noise_terms_band_limited, read_allan
from .timebase import rescale_allan, TimebaseTracker
from ..errors import InputDataError, ParameterError

#: Axis names in column order of the gyro array.
AXES = ('x', 'y', 'z')
#: Valid gap policies (see module doc).
GAP_POLICIES = ('flag', 'split', 'drop')
#: Stamps used to estimate the sample rate when it is not configured (16 timebase blocks).
RATE_ESTIMATE_SAMPLES = 16 * 64 + 1
#: Chunk statuses: analysed, left out because of a gap ('drop'), holding NaN/Inf, skipped by the
#: caller, or failing identification (e.g. a constant chunk).
STATUSES = ('ok', 'dropped', 'nan', 'skipped', 'failed')

#: Gaps kept (the longest, by missing samples) for the reports; all are counted.
MAX_GAP_EVENTS = 5

_NS = 1_000_000_000
_EARLY_CHECK = 101


def _packet_loss(steps, at, apparent, credit):
    """
    Subtract the samples of equal-stamp groups next to long steps from their apparent loss.

    A packet of samples stamped once shows as zero steps right after a long step (stamped with
    its last sample's time) or right before one (its first sample's time): those samples are the
    ones the long step seemed to skip. Each zero step pays for one missing sample of the long step
    it touches (before it first, then after it), once.

    Parameters
    ----------
    steps : numpy.ndarray of int64
        Steps of the batch from the latest earlier stamp (ns).
    at : numpy.ndarray of int
        Indices of the long steps, increasing.
    apparent : numpy.ndarray of int64
        ``round(step / period) - 1`` at those indices.
    credit : int
        Zero steps at the end of the previous batch not yet paid to a long step.

    Returns
    -------
    lost : numpy.ndarray of int64
        Samples missing at each long step.
    credit : int
        Zero steps at the end of this batch not paid to a long step.

    """
    nonzero = np.flatnonzero(steps != 0)
    lost = np.array(apparent, dtype=np.int64)
    used_after = {}
    for n, i in enumerate(at.tolist()):
        k = int(np.searchsorted(nonzero, i)) - 1
        prev = int(nonzero[k]) if k >= 0 else -1
        before = i - prev - 1 - used_after.get(prev, 0) + (credit if prev < 0 else 0)
        nxt = int(nonzero[k + 2]) if k + 2 < nonzero.size else steps.size
        after = nxt - i - 1
        take = min(int(lost[n]), before)
        lost[n] -= take
        take = min(int(lost[n]), after)
        lost[n] -= take
        used_after[i] = take
    last = int(nonzero[-1]) if nonzero.size else -1
    trailing = steps.size - last - 1 - used_after.get(last, 0) + (credit if last < 0 else 0)
    return lost, int(trailing)


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
    axes: tuple = AXES
    alphas: np.ndarray = None
    memory: int = DEFAULT_MEMORY
    demean: bool = True
    max_lag: int = None
    rate_hz: float = None
    gap_factor: float = 1.5
    gap_policy: str = 'flag'
    allan: bool = True
    allan_taus: str = 'dense'
    history_chunks: int = 0

    def __post_init__(self):
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
        if self.rate_hz is not None and not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ParameterError(
                f'rate_hz must be a positive number or None, got {self.rate_hz!r}')
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

    def identifier_key(self):
        """Return the hashable arguments of :func:`identifier_for` for this configuration."""
        return (int(self.chunk_size), tuple(self.alphas.tolist()), int(self.memory),
                bool(self.demean), None if self.max_lag is None else int(self.max_lag))

    def as_dict(self):
        """Return the options as plain JSON-able values (the grid as start/stop/step/count)."""
        a = self.alphas
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
def identifier_for(chunk_size, alphas, memory, demean, max_lag):
    """
    Return a cached :class:`.fractional.OrderIdentifier`.

    Its set-up transforms every grid filter once, so one per configuration is kept.

    Parameters
    ----------
    chunk_size : int
        Samples per chunk.
    alphas : tuple of float
        Order grid.
    memory : int
        L.
    demean : bool
        Remove the chunk mean.
    max_lag : int or None
        Largest lag of J.

    Returns
    -------
    OrderIdentifier

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


def _same(a, b):
    """Equality that treats NaN as equal to NaN (results carry NaN for 'not identified')."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (a != a and b != b)
    return a == b


@dataclass(frozen=True, eq=False)
class ChunkResult:
    """
    Per-chunk results of one axis (identical from the node and the offline tool for the same data).

    Equality compares every field except the curves and treats NaN as equal to NaN, so ``a == b``
    is the "same numbers" test between two runs.

    Attributes
    ----------
    axis, chunk, stamp_start_ns, t_start_s, t_mid_s, samples_lost, gaps, nan_samples, temperature_c
        As in :class:`ChunkJob`.
    samples : int
        Samples in the chunk.
    bias_rad_s : float
        Chunk mean (rad/s), paper sec. 3.3.
    variance_rad2_s2 : float
        Chunk variance, ddof = 1 ((rad/s)^2), paper sec. 3.4.
    alpha_var, f_var : float
        Order and f of the variance method (paper eqs. 6-9, sec. 3.5).
    var_min : float
        Minimum source-noise variance ((rad/s)^2).
    alpha_corr, f_corr : float
        Order and f of the correlation method (eqs. 13-14).
    j_min : float
        Minimum of J ((rad/s)^2).
    tie_var, tie_corr : bool
        The minimum was an exact tie between grid orders (the largest is reported; see
        fractional.py).
    noise_colour : float
        Log-log slope of the chunk's Allan deviation over m = 2-64 samples (dimensionless,
        :func:`.chunks.noise_colour`); NaN when the chunk is too short or not analysed.
    status : str
        One of :data:`STATUSES`.
    message : str
        Why the status is not 'ok' (empty otherwise).
    var_curve, j_curve : numpy.ndarray or None
        var(w)(alpha) and J(alpha) over the grid when curves were requested (not compared).

    """

    axis: str
    chunk: int
    t_start_s: float
    t_mid_s: float
    stamp_start_ns: int
    samples: int
    samples_lost: int
    gaps: int
    nan_samples: int
    bias_rad_s: float
    variance_rad2_s2: float
    alpha_var: float
    f_var: float
    var_min: float
    alpha_corr: float
    f_corr: float
    j_min: float
    tie_var: bool
    tie_corr: bool
    noise_colour: float
    temperature_c: float
    status: str
    message: str = ''
    var_curve: np.ndarray = field(default=None, repr=False, compare=False)
    j_curve: np.ndarray = field(default=None, repr=False, compare=False)

    def __eq__(self, other):
        """Compare field by field, NaN equal to NaN (curves are not compared)."""
        if not isinstance(other, ChunkResult):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)

    __hash__ = None


_NAN = float('nan')


def analyze_chunk(job, identifier=None, *, curves=False):
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
    base = {'axis': job.axis, 'chunk': job.chunk, 't_start_s': job.t_start_s,
            't_mid_s': job.t_mid_s, 'stamp_start_ns': job.stamp_start_ns,
            'samples': int(job.samples.shape[0]), 'samples_lost': job.samples_lost,
            'gaps': job.gaps, 'nan_samples': job.nan_samples, 'bias_rad_s': job.bias_rad_s,
            'variance_rad2_s2': job.variance_rad2_s2, 'temperature_c': job.temperature_c}
    empty = {'alpha_var': _NAN, 'f_var': _NAN, 'var_min': _NAN, 'alpha_corr': _NAN,
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


@dataclass(frozen=True)
class StreamCounts:
    """
    Counters of the input stream, shared by all axes (stamps are common).

    Attributes
    ----------
    samples : int
        Samples ingested (including the tail and samples still held for rate estimation).
    samples_lost : int
        Samples missing according to the stamps (sum over gaps of ``round(step / period) - 1``).
    gaps : int
        Stamp steps above ``gap_factor`` nominal periods.
    out_of_order : int
        Stamps earlier than the latest stamp before them (step < 0).
    chunks : int
        Complete chunks cut so far (per axis).
    tail_samples : int
        Samples after the last complete chunk (not analysed).
    discarded_samples, discarded_partials : int
        Samples and partial chunks thrown away by the 'split' policy.
    rate_hz : float
        Sample rate (Hz): configured, else the :mod:`.timebase` estimate over everything so far;
        NaN while still unknown.
    duration_s : float
        Last minus first stamp (s).
    rate_method : str
        How ``rate_hz`` was obtained (:class:`.timebase.RateEstimate` ``method``).
    bursty : bool
        The stamps are bursty: loss is read from the deficit against elapsed time, not from steps.
    jitter_s : float
        RMS stamp jitter (s, :mod:`.timebase`).
    timebase : timebase.RateEstimate or None
        The full estimate (estimators, irregularity, warnings).
    clock_steps : int
        Long steps (regular stamps) that were not a whole number of periods: corrections of the
        stamping clock, paid back by other steps, not lost samples.
    equal_stamps : int
        Stamps equal to the one before (samples of one packet): a normal time base, neither out of
        order nor a gap.
    longest_gaps : tuple of (float, float, int)
        The longest gaps (at most :data:`MAX_GAP_EVENTS`, most missing samples first) as (start
        after the first sample in s, length of the stamp step in s, missing samples); with
        bursty stamps the start and length are those of the longest step of the chunk whose
        deficit showed the loss.

    """

    samples: int
    samples_lost: int
    gaps: int
    out_of_order: int
    chunks: int
    tail_samples: int
    discarded_samples: int
    discarded_partials: int
    rate_hz: float
    duration_s: float
    rate_method: str = ''
    bursty: bool = False
    jitter_s: float = float('nan')
    timebase: object = None
    clock_steps: int = 0
    equal_stamps: int = 0
    longest_gaps: tuple = ()


@dataclass(frozen=True)
class AxisSummary:
    """
    Everything known about one axis of the run: paper Tables 3-6, Allan deviation, counts.

    Attributes
    ----------
    axis : str
    sequence : SequenceSummary
        Tables 3-6 over the 'ok' chunks (rad/s units inside).
    stream : StreamCounts
    nan_samples : int
        NaN/Inf samples on this axis.
    chunks_ok, chunks_nan, chunks_dropped, chunks_failed, chunks_skipped : int
        Chunks by status.
    temperature_mean_c : float
        Mean of the chunk temperatures (degC), NaN if none.
    allan : object or None
        The Allan deviation result of :mod:`.allan` (None if unavailable or off).
    noise_terms : object or None
        The fitted Allan noise terms of :mod:`.allan` (None if unavailable, off or not fittable),
        band-limited short taus left out (:mod:`.readout`).
    readout : readout.AllanReadout or None
        The datasheet numbers of the Allan deviation (:func:`.readout.read_allan`: bias
        stability, B, ARW, K and its bound, Q, fit quality).

    """

    axis: str
    sequence: SequenceSummary
    stream: StreamCounts
    nan_samples: int
    chunks_ok: int
    chunks_nan: int
    chunks_dropped: int
    chunks_failed: int
    chunks_skipped: int
    temperature_mean_c: float
    allan: object = None
    noise_terms: object = None
    readout: object = None

    @property
    def offset_drift_deg_s_per_h(self):
        """Signed offset drift (Table 3) in (deg/s)/h."""
        return rad_s2_to_deg_s_per_h(self.sequence.drift.slope)


def rad_s2_to_deg_s_per_h(value):
    """
    Convert a rate drift from rad/s^2 to (deg/s)/h (the unit of the paper's Table 3).

    See chunks.py.

    Parameters
    ----------
    value : float
        Drift in rad/s per s.

    Returns
    -------
    float
        Drift in deg/s per hour.

    """
    return float(np.degrees(value) * 3600.0)


class _AxisState:
    """Per-axis sequence statistics (bounded by ``history_chunks`` when > 0)."""

    def __init__(self, history):
        maxlen = history or None
        # (t_mid, bias, variance, alpha_var, alpha_corr, tie_v, tie_c, temp, noise colour)
        self.rows = deque(maxlen=maxlen)
        self.nan_samples = 0
        self.by_status = dict.fromkeys(STATUSES, 0)
        self.last = None


class NoiseEngine:
    """
    Streaming chunk analysis of a 3-axis gyro: ingest, analyze, record, summarise, judge.

    The module doc describes the steps.

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

    def __init__(self, config=None, *, reference=None, thresholds=None):
        from . import health as _health

        self.config = config if config is not None else EngineConfig()
        self.thresholds = thresholds if thresholds is not None else _health.HealthThresholds()
        self.reference = _health.reference_per_axis(reference, self.config.axes)
        self._cols = [AXES.index(a) for a in self.config.axes]
        self._key = self.config.identifier_key()
        grid = self.config.alphas
        # the grid's step (its mean step if uneven): the floor of the orders' chunk spread
        self._order_step = float((grid[-1] - grid[0]) / (grid.size - 1)) if grid.size > 1 else 0.0
        self._period_ns = None if self.config.rate_hz is None else _NS / float(self.config.rate_hz)
        self._pending = []  # batches held until the rate is known
        self._timebase = TimebaseTracker()
        self._classified = False
        self._bursty = False
        self._allowance = 0.0  # per-chunk deficit allowance under bursty stamps (samples)
        # How far from a whole number of periods a long step may be and still be loss (regular
        # stamps), and how many long steps were clock corrections instead.
        self._step_tol = 0.45
        self._clock_steps = 0
        self._chunk_loss_events = 0
        self._estimate_cache = (None, None)
        self._first_ns = None
        self._last_ns = None
        self._max_ns = None
        self._chunk_index = 0
        self._reset_buffer()
        self._samples = 0
        self._lost = 0
        self._gaps = 0
        self._out_of_order = 0
        self._equal = 0
        self._credit = 0  # zero steps at the end of the last batch not paid to a long step
        self._hold = None  # (stamps, gyro, temperature) of an equal-stamp group after a gap
        self._gap_events = []  # (t_s, length_s, missing samples), the longest MAX_GAP_EVENTS
        self._discarded = 0
        self._discarded_partials = 0
        self._axis = {a: _AxisState(int(self.config.history_chunks)) for a in self.config.axes}
        self._allan = None
        self._allan_error = None

    # ---- ingestion
    # -------------------------------------------------------------------------------

    def _reset_buffer(self):
        # list of (rel_ns int64, lost_before int64, temp float64, gyro (n, k) float64)
        self._buf = []
        self._buffered = 0

    def ingest(self, stamp_ns, gyro, temperature_c=None):
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
        self._samples += n
        self._timebase.update(stamps)
        g = np.ascontiguousarray(g[:, self._cols])
        if not self._classified:
            # Held even with a configured rate: the stamp pattern (regular or bursty) decides how
            # loss is read.
            self._pending.append((stamps, g, temp))
            held = sum(p[0].shape[0] for p in self._pending)
            if held < RATE_ESTIMATE_SAMPLES:
                if held >= _EARLY_CHECK and len(
                        self._pending) == 1 or held - n < _EARLY_CHECK <= held:
                    self._early_check()
                return []
            return self._release_pending()
        return self._process(stamps, g, temp)

    def _early_check(self):
        # Refuse obviously broken (shuffled) stamps after ~100 samples instead of 1025. Equal
        # stamps are not broken: a packet of samples shares one stamp.
        held = np.concatenate([p[0] for p in self._pending])
        bad = int(np.count_nonzero(np.diff(held) < 0))
        if bad > 0.1 * (held.shape[0] - 1):
            self._pending = []
            raise InputDataError(
                f'cannot estimate the sample rate: {bad} of the first {held.shape[0] - 1} '
                'stamp steps go backwards (a stamp earlier than its predecessor)')

    def _release_pending(self):
        stamps = np.concatenate([p[0] for p in self._pending])
        g = np.concatenate([p[1] for p in self._pending])
        temp = np.concatenate([p[2] for p in self._pending])
        self._pending = []
        tracker = TimebaseTracker()
        tracker.update(stamps)
        try:
            est = tracker.estimate(self.config.rate_hz)
        except InputDataError as err:
            raise InputDataError(f'cannot estimate the sample rate: {err}') from err
        if not est.usable:
            raise InputDataError(f'cannot estimate the sample rate: {est.warnings[0]} (first '
                                 f'{stamps.shape[0]} samples)')
        self._period_ns = _NS / est.rate_hz
        self._classified = True
        self._set_mode(est)
        # Tolerance of the whole-period test for regular stamps: 6 robust sigmas of the step
        # scatter (a median absolute deviation, so the clock corrections themselves do not widen
        # it), at least 0.1 and at most 0.45 of a period.
        ratio = np.diff(stamps) / self._period_ns
        ratio = ratio[ratio > 0]
        if ratio.size:
            mad = 1.4826 * float(np.median(np.abs(ratio - 1.0)))
            self._step_tol = min(0.45, max(0.1, 6.0 * mad))
        return self._process(stamps, g, temp)

    def _set_mode(self, est):
        self._bursty = bool(est.bursty)
        if self._bursty:
            rate = _NS / self._period_ns
            rel_se = est.stamp_rate_se_hz / est.stamp_rate_hz if np.isfinite(
                est.stamp_rate_se_hz) else 0.0
            self._allowance = (2.0 * est.burst_step_s * rate + 6.0 * est.jitter_s * rate
                               + 3.0 * rel_se * self.config.chunk_size + 1.0)

    def _process(self, stamps, g, temp, *, final=False):
        if self._hold is not None:
            hs, hg, ht = self._hold
            self._hold = None
            stamps, g, temp = (np.concatenate((hs, stamps)), np.concatenate((hg, g)),
                               np.concatenate((ht, temp)))
        first = self._first_ns is None
        if first:
            self._first_ns = int(stamps[0])
            self._max_ns = int(stamps[0])
        # Steps are taken from the latest stamp seen so far, so one late stamp is one out-of-order
        # count and does not also make the next step look like a gap.
        run_max = np.maximum.accumulate(np.concatenate(([np.int64(self._max_ns)], stamps)))
        steps = stamps - run_max[:-1]
        if first:
            steps[0] = max(1, int(round(self._period_ns)))  # the first sample has no step
        if not self._bursty and not final:
            # A long step whose equal-stamp group reaches the end of the batch may be followed
            # by more samples of the same stamp in the next batch: they fill the hole, so the
            # group waits for that batch (or flush) before its loss is decided.
            moved = np.flatnonzero(steps != 0)
            j = int(moved[-1]) if moved.size else -1
            if j >= 0:
                if steps[j] > self.config.gap_factor * self._period_ns:
                    self._hold = (stamps[j:].copy(), g[j:].copy(), temp[j:].copy())
                    stamps, g, temp, steps = stamps[:j], g[:j], temp[:j], steps[:j]
                    run_max = run_max[:j + 1]
                    if stamps.shape[0] == 0:
                        return []
        self._max_ns = int(run_max[-1])
        self._last_ns = int(stamps[-1])
        # A stamp equal to the latest one is a sample of the same packet (a normal time base);
        # only a stamp earlier than the latest is out of order.
        self._out_of_order += int(np.count_nonzero(steps < 0))
        self._equal += int(np.count_nonzero(steps == 0))
        if self._bursty:
            gap = np.zeros(stamps.shape[0], dtype=bool)  # loss is read per chunk from the deficit
        else:
            ratio = steps / self._period_ns
            long_step = ratio > self.config.gap_factor
            # A correction of the stamping clock (the driver re-anchoring its device-clock map,
            # a host clock slewing) is one step of a non-whole number of periods, paid back by
            # other steps: every later stamp stays on the grid. A lost sample shifts the grid by
            # a whole period. Steps of 2.5 periods and more are loss whatever their fraction.
            near_whole = np.abs(ratio - np.rint(ratio)) <= self._step_tol
            gap = long_step & (near_whole | (ratio >= 2.5))
            self._clock_steps += int(np.count_nonzero(long_step & ~gap))
        lost = np.zeros(stamps.shape[0], dtype=np.int64)
        at = np.flatnonzero(gap)
        # Samples sharing a stamp next to a long step (one packet stamped once) are the ones it
        # seemed to skip: a packet-stamped record shows no phantom loss.
        lost[at], self._credit = _packet_loss(
            steps, at, np.maximum(np.rint(steps[at] / self._period_ns).astype(np.int64) - 1, 0),
            self._credit)
        gap[at] = lost[at] > 0
        if gap.any():
            self._gaps += int(gap.sum())
            self._lost += int(lost.sum())
            for i in np.flatnonzero(gap):
                self._log_gap((int(run_max[i]) - self._first_ns) / 1e9, steps[i] / 1e9,
                              int(lost[i]))
        self._feed_allan(g)
        rel = stamps - self._first_ns
        jobs = []
        if self.config.gap_policy == 'split' and gap.any():
            bounds = [0, *np.flatnonzero(gap).tolist(), stamps.shape[0]]
            for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
                if i > 0:
                    self._discard_partial()
                    lost_a = lost[a:b].copy()
                    lost_a[0] = 0  # the gap lies before the new chunk, not inside it
                else:
                    lost_a = lost[a:b]
                jobs += self._push(rel[a:b], lost_a, temp[a:b], g[a:b])
            return jobs
        return self._push(rel, lost, temp, g)

    def _log_gap(self, t_s, length_s, missing):
        self._gap_events.append((float(t_s), float(length_s), int(missing)))
        if len(self._gap_events) > 4 * MAX_GAP_EVENTS:
            self._gap_events = sorted(self._gap_events, key=lambda e: -e[2])[:MAX_GAP_EVENTS]

    def _discard_partial(self):
        if self._buffered:
            self._discarded += self._buffered
            self._discarded_partials += 1
        self._reset_buffer()

    def _push(self, rel, lost, temp, g):
        if rel.shape[0] == 0:
            return []
        if self._buffered == 0 and lost.shape[0]:
            # A gap before the first sample of a chunk is not inside it.
            lost = lost.copy()
            lost[0] = 0
        self._buf.append((rel, lost, temp, g))
        self._buffered += rel.shape[0]
        size = int(self.config.chunk_size)
        if self._buffered < size:
            return []
        rel = np.concatenate([b[0] for b in self._buf])
        lost = np.concatenate([b[1] for b in self._buf])
        temp = np.concatenate([b[2] for b in self._buf])
        g = np.concatenate([b[3] for b in self._buf])
        whole = (rel.shape[0] // size) * size
        jobs = []
        for start in range(0, whole, size):
            sl = slice(start, start + size)
            chunk_lost = lost[sl].copy()
            chunk_lost[0] = 0
            jobs += self._make_jobs(rel[sl], chunk_lost, temp[sl], g[sl])
        self._reset_buffer()
        if whole < rel.shape[0]:
            self._buf.append((rel[whole:].copy(), lost[whole:].copy(),
                             temp[whole:].copy(), g[whole:].copy()))
            self._buffered = rel.shape[0] - whole
        return jobs

    def _make_jobs(self, rel, lost, temp, g):
        index = self._chunk_index
        self._chunk_index += 1
        samples_lost = int(lost.sum())
        gaps = int(np.count_nonzero(lost))
        if self._bursty:
            deficit = (rel[-1] - rel[0]) / self._period_ns + 1.0 - rel.shape[0]
            if deficit > self._allowance:
                samples_lost, gaps = int(round(deficit)), 1
                self._chunk_loss_events += 1
                longest = int(np.argmax(np.diff(rel)))
                self._log_gap(rel[longest] / 1e9, (rel[longest + 1] - rel[longest]) / 1e9,
                              samples_lost)
        finite_t = temp[np.isfinite(temp)]
        temperature = float(finite_t.mean()) if finite_t.size else _NAN
        t_start = rel[0] / 1e9
        t_mid = (rel[0] + rel[-1]) / 2e9
        dropped = gaps > 0 and (self.config.gap_policy == 'drop'
                                or (self._bursty and self.config.gap_policy == 'split'))
        jobs = []
        for k, axis in enumerate(self.config.axes):
            col = np.ascontiguousarray(g[:, k])
            finite = np.isfinite(col)
            nan = int(col.shape[0] - np.count_nonzero(finite))
            self._axis[axis].nan_samples += nan
            if nan:
                status, bias, var = 'nan', _NAN, _NAN
            else:
                status = 'dropped' if dropped else 'ok'
                bias = float(col.mean())
                var = float(col.var(ddof=1))
            jobs.append(ChunkJob(
                axis=axis, chunk=index, samples=col, stamp_start_ns=int(rel[0]) + self._first_ns,
                t_start_s=float(t_start), t_mid_s=float(t_mid), samples_lost=samples_lost,
                gaps=gaps,
                nan_samples=nan, temperature_c=temperature, status=status, bias_rad_s=bias,
                variance_rad2_s2=var, identifier_key=self._key))
        return jobs

    def flush(self):
        """
        Finish ingestion: release samples held for rate estimation.

        The tail stays counted, unanalysed.

        Returns
        -------
        list of ChunkJob
            Jobs completed by the released samples.

        """
        jobs = []
        if self._pending:
            held = sum(p[0].shape[0] for p in self._pending)
            if held >= 2:
                jobs = self._release_pending()
        if self._hold is not None:
            empty = np.empty(0, dtype=np.int64)
            jobs += self._process(empty, np.empty((0, len(self.config.axes))), np.empty(0),
                                  final=True)
        return jobs

    # ---- Allan
    # -------------------------------------------------------------------------------------

    def _feed_allan(self, g):
        if not self.config.allan or self._allan_error is not None:
            return
        if self._allan is None:
            try:
                from . import allan as _allan_mod
                acc = getattr(_allan_mod, 'AllanAccumulator')
                rate = _NS / self._period_ns
                self._allan = {a: acc(rate, taus=self.config.allan_taus) for a in self.config.axes}
            except (ImportError, AttributeError, TypeError) as err:
                self._allan_error = f'Allan deviation unavailable: {err}'
                return
        for k, axis in enumerate(self.config.axes):
            col = g[:, k]
            finite = np.isfinite(col)
            self._allan[axis].update(col if finite.all() else col[finite])

    def _allan_result(self, axis):
        if self._allan is None:
            return None, None
        try:
            result = self._allan[axis].result()
            if self.config.rate_hz is None:
                result = rescale_allan(result, self.counts().rate_hz)
        except (InputDataError, ParameterError, ValueError):
            return None, None
        try:
            terms = fit_noise_terms_band_limited(result)
        except (InputDataError, ParameterError, ValueError):
            terms = None    # too few taus for the fit; the readout still reads the curve
        return result, terms

    # ---- analysis and bookkeeping
    # --------------------------------------------------------------------

    @staticmethod
    def analyze(job, *, curves=False):
        """
        Identify one chunk; see :func:`analyze_chunk` (pure, safe in a worker thread or process).

        Parameters
        ----------
        job : ChunkJob
            The chunk to analyse.
        curves : bool, keyword-only
            Keep the criterion curves in the result.

        Returns
        -------
        ChunkResult

        """
        return analyze_chunk(job, curves=curves)

    def record(self, result):
        """
        Add a chunk result to its axis' sequence statistics (only 'ok' chunks enter Tables 3-6).

        Parameters
        ----------
        result : ChunkResult
            An analysed chunk of this engine.

        """
        state = self._axis.get(result.axis)
        if state is None:
            raise ParameterError(
                f'axis {result.axis!r} is not analysed by this engine ({self.config.axes})')
        state.by_status[result.status] = state.by_status.get(result.status, 0) + 1
        state.last = result
        if result.status == 'ok':
            state.rows.append((result.t_mid_s, result.bias_rad_s, result.variance_rad2_s2,
                               result.alpha_var, result.alpha_corr, result.tie_var,
                               result.tie_corr, result.temperature_c, result.noise_colour))

    def skip(self, job, reason=''):
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

    def counts(self):
        """
        Return the stream counters.

        Returns
        -------
        StreamCounts

        """
        held = sum(p[0].shape[0] for p in self._pending)
        est = self.timebase()
        rate = _NS / self._period_ns if self._period_ns else _NAN
        if est is not None and self._period_ns:
            rate = est.rate_hz
        lost, gaps = self._lost, self._gaps
        if self._bursty:
            lost = est.loss_samples if est is not None else 0
            gaps = self._chunk_loss_events
        return StreamCounts(samples=self._samples, samples_lost=lost, gaps=gaps,
                            out_of_order=self._out_of_order, chunks=self._chunk_index,
                            tail_samples=self._buffered + held, discarded_samples=self._discarded,
                            discarded_partials=self._discarded_partials, rate_hz=rate,
                            duration_s=(self._last_ns - self._first_ns) / 1e9
                            if self._first_ns is not None else 0.0, rate_method=est.method
                            if est is not None else '', bursty=self._bursty, jitter_s=est.jitter_s
                            if est is not None else _NAN, timebase=est,
                            clock_steps=self._clock_steps, equal_stamps=self._equal,
                            longest_gaps=tuple(sorted(self._gap_events,
                                                      key=lambda e: -e[2])[:MAX_GAP_EVENTS]))

    def timebase(self):
        """
        Return the :mod:`.timebase` estimate over every stamp so far (None before 2 stamps).

        Returns
        -------
        timebase.RateEstimate or None

        """
        n = self._timebase.samples
        if self._estimate_cache[0] == n:
            return self._estimate_cache[1]
        try:
            est = self._timebase.estimate(self.config.rate_hz)
        except InputDataError:
            est = None
        self._estimate_cache = (n, est)
        return est

    def summary(self, *, allan=True):
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
        out = {}
        for axis, state in self._axis.items():
            rows = np.array(list(state.rows), dtype=np.float64).reshape(-1, 9)
            seq = summarise_sequence(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4],
                                     tail_samples=counts.tail_samples,
                                     ties_var=int(rows[:, 5].sum()),
                                     ties_corr=int(rows[:, 6].sum()),
                                     order_step=self._order_step, noise_colour=rows[:, 8])
            temps = rows[:, 7][np.isfinite(rows[:, 7])]
            result, terms = self._allan_result(axis) if allan else (None, None)
            sheet = None
            if result is not None:
                try:
                    sheet = read_allan(result, terms)
                except (InputDataError, ParameterError):
                    sheet = None
            out[axis] = AxisSummary(
                axis=axis, sequence=seq, stream=counts, nan_samples=state.nan_samples,
                chunks_ok=state.by_status['ok'], chunks_nan=state.by_status['nan'],
                chunks_dropped=state.by_status['dropped'], chunks_failed=state.by_status['failed'],
                chunks_skipped=state.by_status['skipped'],
                temperature_mean_c=float(temps.mean()) if temps.size else _NAN,
                allan=result, noise_terms=terms, readout=sheet)
        return out

    def health(self, *, seconds_since_data=None, summaries=None):
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
        from .health import evaluate_health

        summaries = summaries if summaries is not None else self.summary(allan=False)
        return {axis: evaluate_health(s, reference=self.reference.get(axis),
                                      thresholds=self.thresholds,
                                      seconds_since_data=seconds_since_data)
                for axis, s in summaries.items()}

    @property
    def allan_status(self):
        """Why the Allan deviation is unavailable (empty string when it is available or off)."""
        return self._allan_error or ''


def warm_up(config):
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
