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
Stamp and gap accounting of a sample stream (pure): rate, gaps, lost samples, stamp order.

:class:`StampAccountant` reads the stamps of the batches a stream delivers and decides, per
sample, how many samples were lost just before it; it carries the samples' payload (any arrays
aligned with the stamps) through unchanged, holding some back while it cannot decide yet. It
knows nothing of chunks or axes: :class:`.engine.NoiseEngine` cuts what it releases with
:class:`.chunks.Chunker`. The rules (the module doc of :mod:`.engine` tells them in full):

* Rate: the configured one, else the :mod:`.timebase` estimate of the first
  :data:`RATE_ESTIMATE_SAMPLES` stamps (held back until then; held even with a configured rate,
  because the stamp pattern, regular or bursty, decides how loss is read). At the end the
  estimate over every stamp replaces it (:meth:`StampAccountant.counts`).
* Regular stamps: a step above ``gap_factor`` periods from the latest stamp so far is a gap of
  ``round(step / period) - 1`` samples when it is a whole number of periods (within 6 robust
  sigmas of the step scatter, 0.1-0.45 of a period) or 2.5 periods and more; otherwise a clock
  step. Samples sharing the stamp next to a long step (one packet) pay back its apparent loss.
* Bursty stamps: loss is the deficit of a chunk's samples against its elapsed time
  (:meth:`StampAccountant.chunk_loss`) and over the run the timebase estimate's.
* A step of zero is an equal stamp (a packet); a step < 0 is out of order, never reordered.
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .timebase import RateEstimate, TimebaseTracker
from ..errors import InputDataError

#: Stamps used to estimate the sample rate when it is not configured (16 timebase blocks).
RATE_ESTIMATE_SAMPLES = 16 * 64 + 1
#: Gaps kept (the longest, by missing samples) for the reports; all are counted.
MAX_GAP_EVENTS = 5

_NS = 1_000_000_000
_NAN = float('nan')
#: Samples after which obviously broken (shuffled) stamps are refused.
_EARLY_CHECK = 101


def _packet_loss(steps: NDArray[np.int64], at: NDArray[np.intp], apparent: NDArray[np.int64],
                 credit: int) -> tuple[NDArray[np.int64], int]:
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
    used_after: dict[int, int] = {}
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
    timebase: RateEstimate | None = None
    clock_steps: int = 0
    equal_stamps: int = 0
    longest_gaps: tuple = ()


@dataclass(frozen=True)
class StampedBatch:
    """
    Samples released by :class:`StampAccountant`, with the loss decided for each.

    Attributes
    ----------
    rel_ns : numpy.ndarray of int64
        Stamps relative to the first stamp of the stream (ns).
    lost : numpy.ndarray of int64
        Samples lost in the gap just before each sample (0 almost everywhere).
    gap : numpy.ndarray of bool
        The sample follows a gap that lost samples (regular stamps only).
    payload : tuple of numpy.ndarray
        The caller's arrays, aligned with the stamps, as given.

    """

    rel_ns: np.ndarray
    lost: np.ndarray
    gap: np.ndarray
    payload: tuple


class StampAccountant:
    """
    Stamp and gap accounting of one stream (module doc); carries an aligned payload through.

    Parameters
    ----------
    rate_hz : float or None
        Nominal sample rate (Hz); None: estimated from the first stamps.
    gap_factor : float
        A step above this many periods is a gap (regular stamps).
    chunk_size : int
        Samples per chunk (the bursty deficit allowance grows with it).

    """

    def __init__(self, rate_hz: float | None, gap_factor: float, chunk_size: int) -> None:
        self.rate_hz = rate_hz
        self.gap_factor = float(gap_factor)
        self.chunk_size = int(chunk_size)
        self.period_ns = None if rate_hz is None else _NS / float(rate_hz)
        # (stamps, payload) batches held until the stamp pattern is known
        self._pending: list[tuple[np.ndarray, tuple]] = []
        self._timebase = TimebaseTracker()
        self._classified = False
        self.bursty = False
        self._allowance = 0.0  # per-chunk deficit allowance under bursty stamps (samples)
        # How far from a whole number of periods a long step may be and still be loss (regular
        # stamps), and how many long steps were clock corrections instead.
        self._step_tol = 0.45
        self._clock_steps = 0
        self._chunk_loss_events = 0
        self._estimate_cache: tuple[int | None, RateEstimate | None] = (None, None)
        self.first_ns: int | None = None
        self._last_ns: int | None = None
        self._max_ns: int | None = None
        self._samples = 0
        self._lost = 0
        self._gaps = 0
        self._out_of_order = 0
        self._equal = 0
        self._credit = 0  # zero steps at the end of the last batch not paid to a long step
        # (stamps, payload) of an equal-stamp group after a long step
        self._hold: tuple[np.ndarray, tuple] | None = None
        # (t_s, length_s, missing samples), the longest MAX_GAP_EVENTS
        self._gap_events: list[tuple[float, float, int]] = []

    @property
    def held_samples(self) -> int:
        """int: Samples held back until the stamp pattern is known."""
        return sum(p[0].shape[0] for p in self._pending)

    def add(self, stamps: np.ndarray, payload: tuple) -> list[StampedBatch]:
        """
        Account for a batch of int64 stamps; return what can be released (possibly nothing).

        Parameters
        ----------
        stamps : numpy.ndarray of int64, shape (n,)
            Sample stamps (ns) in delivery order, n >= 1.
        payload : tuple of numpy.ndarray
            Arrays of first dimension n carried along with the stamps.

        Returns
        -------
        list of StampedBatch

        Raises
        ------
        InputDataError
            The first stamps go backwards too often, or give no usable rate.

        """
        n = stamps.shape[0]
        self._samples += n
        self._timebase.update(stamps)
        if self._classified:
            return self._process(stamps, payload)
        self._pending.append((stamps, payload))
        held = self.held_samples
        if held < RATE_ESTIMATE_SAMPLES:
            if held >= _EARLY_CHECK and len(self._pending) == 1 or held - n < _EARLY_CHECK <= held:
                self._early_check()
            return []
        return self._release_pending()

    def flush(self) -> list[StampedBatch]:
        """
        Release everything held: the rate-estimation samples (2 or more) and a held group.

        Returns
        -------
        list of StampedBatch

        """
        out = []
        if self._pending and self.held_samples >= 2:
            out = self._release_pending()
        if self._hold is not None:
            empty = tuple(p[:0] for p in self._hold[1])
            out += self._process(np.empty(0, dtype=np.int64), empty, final=True)
        return out

    def _early_check(self) -> None:
        # Refuse obviously broken (shuffled) stamps after ~100 samples instead of 1025. Equal
        # stamps are not broken: a packet of samples shares one stamp.
        held = np.concatenate([p[0] for p in self._pending])
        bad = int(np.count_nonzero(np.diff(held) < 0))
        if bad > 0.1 * (held.shape[0] - 1):
            self._pending = []
            raise InputDataError(
                f'cannot estimate the sample rate: {bad} of the first {held.shape[0] - 1} '
                'stamp steps go backwards (a stamp earlier than its predecessor)')

    def _release_pending(self) -> list[StampedBatch]:
        stamps = np.concatenate([p[0] for p in self._pending])
        payload = tuple(np.concatenate(parts)
                        for parts in zip(*(p[1] for p in self._pending)))
        self._pending = []
        tracker = TimebaseTracker()
        tracker.update(stamps)
        try:
            est = tracker.estimate(self.rate_hz)
        except InputDataError as err:
            raise InputDataError(f'cannot estimate the sample rate: {err}') from err
        if not est.usable:
            raise InputDataError(f'cannot estimate the sample rate: {est.warnings[0]} (first '
                                 f'{stamps.shape[0]} samples)')
        self.period_ns = _NS / est.rate_hz
        self._classified = True
        self._set_mode(est)
        # Tolerance of the whole-period test for regular stamps: 6 robust sigmas of the step
        # scatter (a median absolute deviation, so the clock corrections themselves do not widen
        # it), at least 0.1 and at most 0.45 of a period.
        ratio = np.diff(stamps) / self.period_ns
        ratio = ratio[ratio > 0]
        if ratio.size:
            mad = 1.4826 * float(np.median(np.abs(ratio - 1.0)))
            self._step_tol = min(0.45, max(0.1, 6.0 * mad))
        return self._process(stamps, payload)

    def _set_mode(self, est: RateEstimate) -> None:
        self.bursty = bool(est.bursty)
        if self.bursty:
            assert self.period_ns is not None  # set from ``est`` just before
            rate = _NS / self.period_ns
            rel_se = est.stamp_rate_se_hz / est.stamp_rate_hz if np.isfinite(
                est.stamp_rate_se_hz) else 0.0
            self._allowance = (2.0 * est.burst_step_s * rate + 6.0 * est.jitter_s * rate
                               + 3.0 * rel_se * self.chunk_size + 1.0)

    def _steps(self, stamps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the running maximum (with the one before) and the steps from it."""
        first = self.first_ns is None
        if first:
            self.first_ns = int(stamps[0])
            self._max_ns = int(stamps[0])
        # both known here: stamps are processed only once the rate is known
        assert self._max_ns is not None and self.period_ns is not None
        # Steps are taken from the latest stamp seen so far, so one late stamp is one out-of-order
        # count and does not also make the next step look like a gap.
        run_max = np.maximum.accumulate(np.concatenate(([np.int64(self._max_ns)], stamps)))
        steps = stamps - run_max[:-1]
        if first:
            steps[0] = max(1, int(round(self.period_ns)))  # the first sample has no step
        return run_max, steps

    def _hold_last_group(self, stamps: np.ndarray, payload: tuple[np.ndarray, ...],
                         steps: np.ndarray, run_max: np.ndarray
                         ) -> tuple[np.ndarray, tuple[np.ndarray, ...], np.ndarray, np.ndarray]:
        """
        Hold back a long step's equal-stamp group that reaches the end of the batch.

        More samples of the same stamp may follow in the next batch: they fill the hole, so the
        group waits for that batch (or flush) before its loss is decided.
        """
        assert self.period_ns is not None  # _steps ran on this batch: the rate is known
        moved = np.flatnonzero(steps != 0)
        j = int(moved[-1]) if moved.size else -1
        if j >= 0 and steps[j] > self.gap_factor * self.period_ns:
            self._hold = (stamps[j:].copy(), tuple(p[j:].copy() for p in payload))
            return stamps[:j], tuple(p[:j] for p in payload), steps[:j], run_max[:j + 1]
        return stamps, payload, steps, run_max

    def _gaps_of(self, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the per-sample loss and gap mask of a batch's steps (and count them)."""
        if self.bursty:
            gap = np.zeros(steps.shape[0], dtype=bool)  # loss is read per chunk from the deficit
        else:
            ratio = steps / self.period_ns
            long_step = ratio > self.gap_factor
            # A correction of the stamping clock (the driver re-anchoring its device-clock map,
            # a host clock slewing) is one step of a non-whole number of periods, paid back by
            # other steps: every later stamp stays on the grid. A lost sample shifts the grid by
            # a whole period. Steps of 2.5 periods and more are loss whatever their fraction.
            near_whole = np.abs(ratio - np.rint(ratio)) <= self._step_tol
            gap = long_step & (near_whole | (ratio >= 2.5))
            self._clock_steps += int(np.count_nonzero(long_step & ~gap))
        lost = np.zeros(steps.shape[0], dtype=np.int64)
        at = np.flatnonzero(gap)
        # Samples sharing a stamp next to a long step (one packet stamped once) are the ones it
        # seemed to skip: a packet-stamped record shows no phantom loss.
        lost[at], self._credit = _packet_loss(
            steps, at, np.maximum(np.rint(steps[at] / self.period_ns).astype(np.int64) - 1, 0),
            self._credit)
        gap[at] = lost[at] > 0
        return lost, gap

    def _process(self, stamps: np.ndarray, payload: tuple[np.ndarray, ...], *,
                 final: bool = False) -> list[StampedBatch]:
        if self._hold is not None:
            hs, hp = self._hold
            self._hold = None
            stamps = np.concatenate((hs, stamps))
            payload = tuple(np.concatenate((h, p)) for h, p in zip(hp, payload))
        run_max, steps = self._steps(stamps)
        if not self.bursty and not final:
            stamps, payload, steps, run_max = self._hold_last_group(stamps, payload, steps,
                                                                    run_max)
            if stamps.shape[0] == 0:
                return []
        self._max_ns = int(run_max[-1])
        self._last_ns = int(stamps[-1])
        # A stamp equal to the latest one is a sample of the same packet (a normal time base);
        # only a stamp earlier than the latest is out of order.
        self._out_of_order += int(np.count_nonzero(steps < 0))
        self._equal += int(np.count_nonzero(steps == 0))
        lost, gap = self._gaps_of(steps)
        assert self.first_ns is not None  # set by _steps
        if gap.any():
            self._gaps += int(gap.sum())
            self._lost += int(lost.sum())
            for i in np.flatnonzero(gap):
                self._log_gap((int(run_max[i]) - self.first_ns) / 1e9, steps[i] / 1e9,
                              int(lost[i]))
        return [StampedBatch(stamps - self.first_ns, lost, gap, payload)]

    def _log_gap(self, t_s: float, length_s: float, missing: int) -> None:
        self._gap_events.append((float(t_s), float(length_s), int(missing)))
        if len(self._gap_events) > 4 * MAX_GAP_EVENTS:
            self._gap_events = sorted(self._gap_events, key=lambda e: -e[2])[:MAX_GAP_EVENTS]

    def chunk_loss(self, rel_ns: np.ndarray, samples_lost: int, gaps: int) -> tuple[int, int]:
        """
        Return a chunk's (samples lost, gaps): its gaps' sums, or its deficit for bursty stamps.

        With bursty stamps a chunk whose samples fall short of its elapsed time by more than the
        jitter allowance lost ``round(deficit)`` samples in one gap (logged at its longest step).

        Parameters
        ----------
        rel_ns : numpy.ndarray of int64
            The chunk's relative stamps (ns).
        samples_lost, gaps : int
            Sum of the chunk's per-sample losses and their count (regular stamps).

        Returns
        -------
        (int, int)

        """
        if self.bursty:
            deficit = (rel_ns[-1] - rel_ns[0]) / self.period_ns + 1.0 - rel_ns.shape[0]
            if deficit > self._allowance:
                samples_lost, gaps = int(round(deficit)), 1
                self._chunk_loss_events += 1
                longest = int(np.argmax(np.diff(rel_ns)))
                self._log_gap(rel_ns[longest] / 1e9,
                              (rel_ns[longest + 1] - rel_ns[longest]) / 1e9, samples_lost)
        return samples_lost, gaps

    def timebase(self) -> RateEstimate | None:
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
            est = self._timebase.estimate(self.rate_hz)
        except InputDataError:
            est = None
        self._estimate_cache = (n, est)
        return est

    def counts(self, *, chunks: int, tail_samples: int, discarded_samples: int,
               discarded_partials: int) -> StreamCounts:
        """
        Return the stream counters, with the chunking counts of the caller.

        Parameters
        ----------
        chunks : int
            Complete chunks cut so far.
        tail_samples : int
            Samples buffered after the last complete chunk (the held samples are added).
        discarded_samples, discarded_partials : int
            Thrown away by the 'split' policy.

        Returns
        -------
        StreamCounts

        """
        est = self.timebase()
        rate = _NS / self.period_ns if self.period_ns else _NAN
        if est is not None and self.period_ns:
            rate = est.rate_hz
        lost, gaps = self._lost, self._gaps
        if self.bursty:
            lost = est.loss_samples if est is not None else 0
            gaps = self._chunk_loss_events
        return StreamCounts(
            samples=self._samples, samples_lost=lost, gaps=gaps, out_of_order=self._out_of_order,
            chunks=chunks, tail_samples=tail_samples + self.held_samples,
            discarded_samples=discarded_samples, discarded_partials=discarded_partials,
            rate_hz=rate, duration_s=(self._last_ns - self.first_ns) / 1e9
            if self.first_ns is not None and self._last_ns is not None else 0.0,
            rate_method=est.method if est is not None else '', bursty=self.bursty,
            jitter_s=est.jitter_s if est is not None else _NAN, timebase=est,
            clock_steps=self._clock_steps, equal_stamps=self._equal,
            longest_gaps=tuple(sorted(self._gap_events, key=lambda e: -e[2])[:MAX_GAP_EVENTS]))
