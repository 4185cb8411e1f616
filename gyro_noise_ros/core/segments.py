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
The one static-segment rule: which part of a record a tool analyses as noise, and what it cuts.

Noise characterisation assumes a sensor at rest. :func:`static_part` takes a whole record (stamps,
3-axis gyro, optionally the accelerometer) and returns the samples kept, every interval cut with
its reason, and the one line that says so; :class:`WindowStats` is the same rule fed batch by
batch (the streaming analyzer), and :func:`left_out_sentence` the one sentence every tool prints.

Rule: the record is cut into windows of :data:`WINDOW_S`; per window and column (axis) the mean
and standard deviation are kept. A column's static noise level is the :data:`NOISE_QUANTILE`
quantile of its window standard deviations; its local static rate at a window is the running
median of the quiet windows' means over :data:`LOCAL_S` around it (:func:`local_level`), so a
wandering bias is not motion. A window **moves** when on any column its standard deviation
exceeds :data:`MOTION_FACTOR` static noise levels, or its mean departs from the local rate by
more and by over :data:`SCATTER_FACTOR` robust sigmas of the means about it. A rate held longer
than half of :data:`LOCAL_S` becomes the local rate (a bias): a steady turn reads as static
unless its spread moves it. All axes are judged together: a knock on one axis cuts that time
from every axis. The segment analysed is the **longest run of static windows** (the Allan
deviation needs contiguous data); shorter static runs are cut too (``'shorter static run'``).
A run covering :data:`STATIC_ALL` of the windows means static throughout (nothing cut). Windows
without samples (a stamp gap) never end a run. Fewer than 3 windows: no judgement.
Times: s after the record's first sample. Cost O(n). Measurements: docs/offline_tool.md.
"""

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ParameterError

#: Window length (s).
WINDOW_S = 1.0
#: A window moves above this many static noise levels (std or mean offset).
MOTION_FACTOR = 3.0
#: Quantile of the window standard deviations taken as the static noise level.
NOISE_QUANTILE = 0.2
#: The longest static run covering this fraction of the windows means: static throughout.
STATIC_ALL = 0.95
#: Neighbourhood of the local static rate (s): a window's mean is compared with
#: the median mean of this many quiet windows around it, not with one rate for the record. Long
#: enough that a knock of seconds, or a rotation step of 20 s, is a minority in it (it cannot
#: move the median); short enough that a MEMS bias does not wander far within it: the mean of a
#: window departs from the neighbourhood's level by about the Allan deviation of the bias at
#: tau ~ half the span, sqrt(2) K sqrt(tau/3) for a rate random walk K (IEEE 952): ~6 K at
#: 120 s, under 1.3 N for K = N/5 (the tests' strong walk) against the limit of 3 static noise
#: levels (3 N sqrt(f_s), >= 3 N from 1 Hz). A constant rate held longer than half the span
#: becomes the local level (read as a bias: static) unless its spread moves it.
LOCAL_S = 120.0
#: A window's mean moves only beyond this many robust sigmas of the window means about the
#: local level too (two-sided 6e-7 for Gaussian scatter: ~0.02 false windows in 10 h of 3 axes).
SCATTER_FACTOR = 5.0


@dataclass(frozen=True)
class StaticSegment:
    """
    The static part of a record chosen for analysis.

    Attributes
    ----------
    start_ns, end_ns : int
        Stamps of the segment's first and last window edges (ns); samples with
        ``start_ns <= stamp < end_ns`` are analysed.
    static_throughout : bool
        No motion worth cutting (the segment is the whole record).
    windows, static_windows : int
        Windows in the record and static windows in total.
    segments : tuple of (int, int)
        Every static run as (start_ns, end_ns); a run may span windows without data (gaps).
    noise_rad_s : tuple of float
        Static noise level per column (rad/s; m/s^2 for accelerometer columns).
    moving : tuple of (int, int)
        Every run of moving windows as (start_ns, end_ns).

    """

    start_ns: int
    end_ns: int
    static_throughout: bool
    windows: int
    static_windows: int
    segments: tuple[tuple[int, int], ...]
    noise_rad_s: tuple[float, ...]
    moving: tuple[tuple[int, int], ...] = ()

    def cuts(self, first_ns: int, last_ns: int) -> tuple['Cut', ...]:
        """
        Return every interval of the record left out around the segment, with its reason.

        Parameters
        ----------
        first_ns, last_ns : int
            Stamps of the record's first and last sample (ns): times are counted from the first,
            and no interval runs past the last.

        Returns
        -------
        tuple of Cut
            In time order: the moving runs (``'motion'``) and the static runs other than the
            segment (``'shorter static run'``); empty when static throughout.

        """
        if self.static_throughout:
            return ()
        spans = [(a, b, 'motion') for a, b in self.moving]
        spans += [(a, b, 'shorter static run') for a, b in self.segments
                  if (a, b) != (self.start_ns, self.end_ns)]
        return tuple(Cut(start_s=(max(a, first_ns) - first_ns) / 1e9,
                         end_s=(min(b, last_ns) - first_ns) / 1e9, reason=why)
                     for a, b, why in sorted(spans))


@dataclass(frozen=True)
class Cut:
    """
    One interval of a record left out of the analysis.

    Attributes
    ----------
    start_s, end_s : float
        Its time range (s after the record's first sample).
    reason : str
        ``'motion'`` or ``'shorter static run'`` (module doc).

    """

    start_s: float
    end_s: float
    reason: str

    def as_dict(self) -> dict[str, Any]:
        """Return ``{'start_s', 'end_s', 'reason'}`` (the ``left_out.cut_s`` entries)."""
        return {'start_s': self.start_s, 'end_s': self.end_s, 'reason': self.reason}


class WindowStats:
    """
    Per-window sample count, sums and sums of squares of the angular rate, fed in batches.

    Each batch costs O(n) (O(n log n) when its stamps are out of order): the windows are
    summed with :func:`numpy.add.reduceat` (or :func:`numpy.bincount`) and merged into arrays
    sorted by window index (module doc).

    Parameters
    ----------
    window_s : float, keyword-only
        Window length (s, > 0).

    """

    def __init__(self, *, window_s: float = WINDOW_S) -> None:
        if not window_s > 0:
            raise ParameterError(f'window_s must be > 0 s, got {window_s!r}')
        self._w = int(round(window_s * 1e9))
        self._t0: int | None = None
        self._size = 0
        self._keys = np.zeros(0, dtype=np.int64)             # window index, increasing
        self._n = np.zeros(0, dtype=np.int64)                # samples per window
        self._sum = np.zeros((0, 0))                         # per window and column
        self._sq = np.zeros((0, 0))

    def update(self, stamp_ns: npt.ArrayLike, gyro: npt.ArrayLike) -> None:
        """
        Add samples.

        Parameters
        ----------
        stamp_ns : array_like of int
            Stamps (ns).
        gyro : array_like, shape (n, axes)
            Angular rate (rad/s), one column per axis; non-finite samples are ignored.

        """
        s = np.asarray(stamp_ns, dtype=np.int64)
        if s.size == 0:
            return  # e.g. a --start past the end: nothing selected (and nothing to reshape)
        g = np.asarray(gyro, dtype=np.float64)
        g = g.reshape(g.shape[0], -1)
        if self._t0 is None:
            self._t0 = int(s[0])
        ok = np.all(np.isfinite(g), axis=1)
        s, g = s[ok], g[ok]
        if s.size == 0:
            return
        idx = (s - self._t0) // self._w
        step = np.diff(idx)
        if np.all(step >= 0):   # the usual batch: stamps in order, one slice per window
            starts = np.flatnonzero(np.concatenate(([True], step != 0)))
            keys = idx[starts]
            counts = np.diff(np.append(starts, idx.size))
            sums = np.add.reduceat(g, starts, axis=0)
            sq = np.add.reduceat(g * g, starts, axis=0)
        else:
            keys, inv = np.unique(idx, return_inverse=True)
            counts = np.bincount(inv, minlength=keys.size)
            sums = np.column_stack([np.bincount(inv, weights=c, minlength=keys.size)
                                    for c in g.T])
            sq = np.column_stack([np.bincount(inv, weights=c * c, minlength=keys.size)
                                  for c in g.T])
        self._merge(keys, counts, sums, sq)

    def _merge(self, keys: npt.NDArray[np.int64], counts: npt.NDArray[np.int64],
               sums: npt.NDArray[np.float64], sq: npt.NDArray[np.float64]) -> None:
        """Add per-window rows (``keys`` increasing) to the stored rows."""
        size = self._size
        if size == 0:
            self._sum = np.zeros((0, sums.shape[1]))
            self._sq = np.zeros((0, sums.shape[1]))
        held = self._keys[:size]
        pos = np.searchsorted(held, keys)
        hit = pos < size
        hit[hit] = held[pos[hit]] == keys[hit]
        at = pos[hit]
        self._n[at] += counts[hit]
        self._sum[at] += sums[hit]
        self._sq[at] += sq[hit]
        new = ~hit
        if not new.any():
            return
        keys, counts, sums, sq = keys[new], counts[new], sums[new], sq[new]
        if size and keys[0] < held[-1]:
            # a batch reaching back into the record (stamps out of order): re-sort, O(W log W)
            order = np.argsort(np.concatenate((held, keys)), kind='stable')
            keys = np.concatenate((held, keys))[order]
            counts = np.concatenate((self._n[:size], counts))[order]
            sums = np.concatenate((self._sum[:size], sums))[order]
            sq = np.concatenate((self._sq[:size], sq))[order]
            size = 0
        end = size + keys.size
        if end > self._keys.size:   # grow geometrically: appending costs O(1) per window
            cap = max(2 * self._keys.size, end, 64)
            self._keys = np.resize(self._keys, cap)
            self._n = np.resize(self._n, cap)
            self._sum = np.resize(self._sum, (cap, sums.shape[1]))
            self._sq = np.resize(self._sq, (cap, sums.shape[1]))
        self._keys[size:end] = keys
        self._n[size:end] = counts
        self._sum[size:end] = sums
        self._sq[size:end] = sq
        self._size = end

    @property
    def windows(self) -> int:
        """int: the windows that have received at least one sample so far."""
        return self._size

    def table(self) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64],
                             npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """
        Return the rows so far: window indices (increasing), counts, sums and sums of squares.

        Returns
        -------
        tuple of numpy.ndarray
            ``keys`` (window index since the first stamp), ``counts``, ``sums`` and ``sumsq``
            (shape (windows, columns); rad/s and (rad/s)^2); copies.

        """
        n = self._size
        return (self._keys[:n].copy(), self._n[:n].copy(), self._sum[:n].copy(),
                self._sq[:n].copy())

    def segment(self) -> StaticSegment | None:
        """
        Choose the static part of the record (see the module doc); None below 3 windows.

        Returns
        -------
        StaticSegment or None

        """
        if self._t0 is None:
            return None
        return judge_windows(*self.table(), t0_ns=self._t0, window_ns=self._w)


def judge_windows(keys: npt.NDArray[np.int64], counts: npt.NDArray[np.int64],
                  sums: npt.NDArray[np.float64], sumsq: npt.NDArray[np.float64], *,
                  t0_ns: int, window_ns: int) -> StaticSegment | None:
    """
    Apply the rule (module doc) to per-window rows (:meth:`WindowStats.table`).

    Parameters
    ----------
    keys : numpy.ndarray of int, shape (w,)
        Window indices since ``t0_ns``, increasing.
    counts : numpy.ndarray of int, shape (w,)
        Samples per window.
    sums, sumsq : numpy.ndarray, shape (w, columns)
        Per window and column: sum and sum of squares of the rate (rad/s, (rad/s)^2).
    t0_ns : int, keyword-only
        Stamp of window 0's start (ns).
    window_ns : int, keyword-only
        Window length (ns).

    Returns
    -------
    StaticSegment or None
        None below 3 windows of at least 2 samples.

    """
    use = counts >= 2
    keys = keys[use]
    if keys.size < 3:
        return None
    n = counts[use].astype(np.float64)[:, None]
    mean = sums[use] / n
    var = np.maximum(sumsq[use] / n - mean ** 2, 0.0)
    std = np.sqrt(var * n / np.maximum(n - 1, 1))
    noise = np.quantile(std, NOISE_QUANTILE, axis=0)
    noise = np.where(noise > 0, noise, np.finfo(float).tiny)
    quiet = np.all(std <= np.quantile(std, NOISE_QUANTILE, axis=0) * 1.5 + 1e-300, axis=1)
    ref = local_level(keys, mean, quiet, round(LOCAL_S * 1e9 / window_ns))
    limit = MOTION_FACTOR * noise
    off = np.abs(mean - ref)
    # the window means' own scatter about the local level (robust sigma of the quiet windows):
    # a strong flicker moves 1 s means by ~0.7 noise levels, where 3 levels is ~4 sigma
    scatter = 1.4826 * np.median(off[quiet] if quiet.any() else off, axis=0)
    moving = np.any((std > limit) | (off > np.maximum(limit, SCATTER_FACTOR * scatter)), axis=1)
    # windows without data (a stamp gap) are not in keys, not motion: only motion ends a run
    runs = _runs(~moving)
    edges = _edges(keys, runs, t0_ns, window_ns)
    motion = _edges(keys, _runs(moving), t0_ns, window_ns)
    noise_t = tuple(float(v) for v in noise)
    if not runs:
        # an empty segment at the record's start, never at stamp 0 (1970)
        return StaticSegment(t0_ns, t0_ns, False, int(keys.size), 0, (), noise_t, motion)
    best = max(range(len(runs)), key=lambda i: runs[i][1] - runs[i][0])
    length = runs[best][1] - runs[best][0]
    throughout = length >= STATIC_ALL * keys.size
    start_ns, end_ns = edges[best]
    if throughout:
        start_ns, end_ns = t0_ns, t0_ns + (int(keys[-1]) + 1) * window_ns
    return StaticSegment(int(start_ns), int(end_ns), bool(throughout), int(keys.size),
                         int((~moving).sum()), edges, noise_t, motion)


def local_level(keys: npt.NDArray[np.int64], mean: npt.NDArray[np.float64],
                quiet: npt.NDArray[np.bool_], span: int) -> npt.NDArray[np.float64]:
    """
    Return each window's local static rate: the running median of the quiet windows' means.

    Parameters
    ----------
    keys : numpy.ndarray of int, shape (w,)
        Window indices, increasing (gaps allowed).
    mean : numpy.ndarray, shape (w, columns)
        Window means (rad/s).
    quiet : numpy.ndarray of bool, shape (w,)
        Windows whose spread is near the static noise level on every column; none: all count.
    span : int
        Neighbourhood (windows, :data:`LOCAL_S`): the median runs over the quiet windows
        nearest in order, as many as ``span`` windows hold on average (centred; mirrored at
        the record's ends; the whole record when it is shorter).

    Returns
    -------
    numpy.ndarray, shape (w, columns)
        Per window, the median of the neighbourhood around the quiet window nearest to it.

    """
    from scipy.ndimage import median_filter  # here: analyze's start does not pay for ndimage

    pick = np.flatnonzero(quiet) if quiet.any() else np.arange(keys.size)
    # as many quiet windows as ``span`` windows hold on average: the median spans ~span windows
    count = int(round(span * pick.size / keys.size))
    size = max(1, min(count | 1, (pick.size - 1) | 1))   # odd: centred; at most the record
    level = median_filter(mean[pick], size=(size, 1), mode='mirror')
    at = keys[pick]
    if at.size == 1:
        return np.repeat(level, keys.size, axis=0)
    j = np.clip(np.searchsorted(at, keys), 1, at.size - 1)
    return np.asarray(level[np.where(keys - at[j - 1] <= at[j] - keys, j - 1, j)],
                      dtype=np.float64)


def _edges(keys: npt.NDArray[np.int64], runs: list[tuple[int, int]], t0_ns: int,
           window_ns: int) -> tuple[tuple[int, int], ...]:
    """Return the stamps (ns) of the window edges of runs of window positions ``[a, b)``."""
    return tuple((t0_ns + int(keys[a]) * window_ns, t0_ns + (int(keys[b - 1]) + 1) * window_ns)
                 for a, b in runs)


def _runs(flags: npt.NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Return the runs of True in ``flags`` as ``[start, stop)`` index pairs."""
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


@dataclass(frozen=True)
class StaticPart:
    """
    What a tool analyses of one record and what it cuts (:func:`static_part`).

    Attributes
    ----------
    keep : numpy.ndarray of bool
        Per sample: analysed.
    segment : StaticSegment or None
        The rule's result (None: fewer than 3 windows, nothing judged, everything kept).
    cuts : tuple of Cut
        Every interval left out, with its reason (empty: static throughout).
    kept_samples, total_samples : int
        Samples analysed and samples given.
    segment_s : tuple of float or None
        The analysed segment (s after the first sample, ending at the last sample at most);
        None when nothing was cut.
    description : str
        One line saying what was cut (:func:`left_out_sentence`); empty when nothing was.
    first_ns, last_ns : int
        The time origin (the record's first sample, ns) and the last sample's stamp (ns; 0 for
        an empty record).

    """

    keep: npt.NDArray[np.bool_]
    segment: StaticSegment | None
    cuts: tuple[Cut, ...]
    kept_samples: int
    total_samples: int
    segment_s: tuple[float, float] | None
    description: str
    first_ns: int = 0
    last_ns: int = 0

    @property
    def cut_samples(self) -> int:
        """int: samples left out."""
        return self.total_samples - self.kept_samples

    def left_out(self) -> dict[str, Any]:
        """
        Return the ``left_out`` entries of a tool's JSON for the cut (docs/offline_tool.md).

        Returns
        -------
        dict
            ``motion`` (samples cut) and, when something was cut, ``static_segment_s`` (the
            segment analysed), ``static_segments_s`` (every static run) and ``cut_s`` (every
            interval cut: ``start_s``, ``end_s``, ``reason``); times in s after the first sample.

        """
        out: dict[str, Any] = {'motion': self.cut_samples}
        if self.segment_s is not None and self.segment is not None:
            out.update(segment_left_out(self.segment, self.first_ns, self.last_ns))
        return out


def segment_left_out(segment: StaticSegment, first_ns: int, last_ns: int) -> dict[str, Any]:
    """
    Return the time entries of ``left_out`` for a segment that cuts something.

    Parameters
    ----------
    segment : StaticSegment
        Not static throughout.
    first_ns, last_ns : int
        Stamps of the record's first and last sample (ns).

    Returns
    -------
    dict
        ``static_segment_s``, ``static_segments_s`` and ``cut_s`` (:meth:`StaticPart.left_out`).

    """
    def span(a: int, b: int) -> list[float]:
        # the segments end on window boundaries; a time range never runs past the last sample
        return [(a - first_ns) / 1e9, (min(b, last_ns) - first_ns) / 1e9]

    return {'static_segment_s': span(segment.start_ns, segment.end_ns),
            'static_segments_s': [span(a, b) for a, b in segment.segments],
            'cut_s': [c.as_dict() for c in segment.cuts(first_ns, last_ns)]}


def static_part(stamp_ns: npt.ArrayLike, gyro: npt.ArrayLike, *,
                accel: npt.ArrayLike | None = None, window_s: float = WINDOW_S,
                origin_ns: int | None = None) -> StaticPart:
    """
    Apply the static-segment rule (module doc) to a whole record.

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Sample stamps (ns), non-decreasing.
    gyro : array_like, shape (n, axes)
        Angular rate (rad/s), one column per axis (all the record holds: the rule judges the
        axes together). A column without any finite value is left out of the judgement; a row
        with a non-finite value in a judged column is not counted in its window.
    accel : array_like, shape (n, axes), optional, keyword-only
        Specific force (m/s^2): judged as further columns. Tools that must cut the same
        windows pass the same columns (analyze and explain pass the gyro only).
    window_s : float, keyword-only
        Window length (s).
    origin_ns : int, optional, keyword-only
        Stamp the times are counted from (ns): the first sample of the whole record when the
        stamps given are a part of it (a time window); default the first stamp given.

    Returns
    -------
    StaticPart

    Raises
    ------
    ParameterError
        Shapes that do not match, or a window length <= 0.

    """
    stamps = np.asarray(stamp_ns, dtype=np.int64).ravel()
    cols = np.asarray(gyro, dtype=np.float64).reshape(stamps.size, -1)
    if accel is not None:
        extra = np.asarray(accel, dtype=np.float64)
        if extra.shape[0] != stamps.size:
            raise ParameterError(f'accel has {extra.shape[0]} rows for {stamps.size} stamps')
        cols = np.column_stack((cols, extra.reshape(stamps.size, -1)))
    cols = cols[:, np.any(np.isfinite(cols), axis=0)]
    stats = WindowStats(window_s=window_s)
    seg = None
    if cols.shape[1]:
        stats.update(stamps, cols)
        seg = stats.segment()
    n = int(stamps.size)
    first, last = (int(stamps[0]), int(stamps[-1])) if n else (0, 0)
    first = first if origin_ns is None else int(origin_ns)
    if seg is None or seg.static_throughout:
        return StaticPart(keep=np.ones(n, dtype=bool), segment=seg, cuts=(), kept_samples=n,
                          total_samples=n, segment_s=None, description='', first_ns=first,
                          last_ns=last)
    keep = (stamps >= seg.start_ns) & (stamps < seg.end_ns)
    a, b = segment_left_out(seg, first, last)['static_segment_s']
    cuts = seg.cuts(first, last)
    kept = int(keep.sum())
    return StaticPart(keep=keep, segment=seg, cuts=cuts, kept_samples=kept, total_samples=n,
                      segment_s=(a, b), description=left_out_sentence(
                          n, motion=n - kept, segment_s=(a, b), cuts=cuts),
                      first_ns=first, last_ns=last)


#: Most cut intervals the sentence lists one by one.
SENTENCE_CUTS = 3


def left_out_sentence(total: int, *, before_start: int = 0, after_end: int = 0, motion: int = 0,
                      segment_s: tuple[float, float] | None = None,
                      cuts: tuple[Cut, ...] = (),
                      window_names: tuple[str, str] = ('the start', 'the end')) -> str:
    """
    Return the one line every tool prints about the samples it left out.

    Parameters
    ----------
    total : int
        Samples read.
    before_start, after_end : int, keyword-only
        Samples outside the time window asked for.
    motion : int, keyword-only
        Samples cut by the static-segment rule.
    segment_s : tuple of float, optional, keyword-only
        The segment analysed (s after the first sample).
    cuts : tuple of Cut, keyword-only
        The intervals cut (:meth:`StaticSegment.cuts`); the motion among them is listed.
    window_names : tuple of str, keyword-only
        How the tool names the two ends of its time window (its options).

    Returns
    -------
    str
        ``'N of M samples left out: ...'``; empty when nothing was left out.

    """
    parts = [f'{before_start} before {window_names[0]}'] if before_start else []
    parts += [f'{after_end} after {window_names[1]}'] if after_end else []
    if motion:
        moving = [c for c in cuts if c.reason == 'motion']
        where = ', '.join(f'{c.start_s:.1f}-{c.end_s:.1f} s' for c in moving[:SENTENCE_CUTS])
        if len(moving) > SENTENCE_CUTS:
            where += f' and {len(moving) - SENTENCE_CUTS} more'
        seen = f'in motion at t = {where}; ' if where else ''
        span = (f't = {segment_s[0]:.1f}-{segment_s[1]:.1f} s after the first sample'
                if segment_s is not None else 'it')
        parts.append(f'{motion} outside the longest static segment ({seen}analysing {span} on '
                     'every axis)')
    count = before_start + after_end + motion
    return f'{count} of {total} samples left out: ' + ', '.join(parts) if parts else ''
