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
quantile of its window standard deviations, its static rate the median window mean of the quiet
windows. A window **moves** when on any column its standard deviation exceeds
:data:`MOTION_FACTOR` static noise levels, or its mean departs from the static rate by more. All
axes are judged together: a knock on one axis cuts that time from every axis. The segment
analysed is the **longest run of static windows**: the Allan deviation and the chunk statistics
need contiguous data, and joining runs across a knock would put a step of unknown size into them;
shorter static runs are cut too (reason ``'shorter static run'``) and listed. A run covering
:data:`STATIC_ALL` of the windows means static throughout (nothing cut). Windows without samples
(a stamp gap) do not end a run: a gap is a gap, never motion. Fewer than 3 windows: no judgement.
Times are seconds after the record's first sample. Measurements: docs/offline_tool.md.
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
    Per-window mean and standard deviation of the angular rate, fed in batches (module doc).

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
        self._rows: dict[int, list[Any]] = {}  # window index -> [n, sum(3), sumsq(3)]

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
        idx = (s - self._t0) // self._w
        for k in np.unique(idx):
            sel = idx == k
            row = self._rows.setdefault(int(k), [0, np.zeros(g.shape[1]), np.zeros(g.shape[1])])
            row[0] += int(sel.sum())
            row[1] += g[sel].sum(axis=0)
            row[2] += (g[sel] ** 2).sum(axis=0)

    @property
    def windows(self) -> int:
        """int: the windows that have received at least one sample so far."""
        return len(self._rows)

    def segment(self) -> StaticSegment | None:
        """
        Choose the static part of the record (see the module doc); None below 3 windows.

        Returns
        -------
        StaticSegment or None

        """
        keys = sorted(k for k, r in self._rows.items() if r[0] >= 2)
        if len(keys) < 3:
            return None
        assert self._t0 is not None  # set by the update that filled the windows
        n = np.array([self._rows[k][0] for k in keys], dtype=np.float64)[:, None]
        mean = np.array([self._rows[k][1] for k in keys]) / n
        var = np.maximum(np.array([self._rows[k][2] for k in keys]) / n - mean ** 2, 0.0)
        std = np.sqrt(var * n / np.maximum(n - 1, 1))
        noise = np.quantile(std, NOISE_QUANTILE, axis=0)
        noise = np.where(noise > 0, noise, np.finfo(float).tiny)
        quiet = np.all(std <= np.quantile(std, NOISE_QUANTILE, axis=0) * 1.5 + 1e-300, axis=1)
        ref = np.median(mean[quiet], axis=0) if quiet.any() else np.median(mean, axis=0)
        limit = MOTION_FACTOR * noise
        moving = np.any((std > limit) | (np.abs(mean - ref) > limit), axis=1)
        # windows without data (a stamp gap) are not in keys, not motion: only motion ends a run
        runs = _runs(~moving)
        edges = self._edges(keys, runs)
        motion = self._edges(keys, _runs(moving))
        if not runs:
            # an empty segment at the record's start, never at stamp 0 (1970)
            return StaticSegment(self._t0, self._t0, False, len(keys), 0, (),
                                 tuple(float(v) for v in noise), motion)
        best = max(range(len(runs)), key=lambda i: runs[i][1] - runs[i][0])
        length = runs[best][1] - runs[best][0]
        throughout = length >= STATIC_ALL * len(keys)
        start_ns, end_ns = edges[best]
        if throughout:
            start_ns, end_ns = self._t0, self._t0 + (int(keys[-1]) + 1) * self._w
        return StaticSegment(int(start_ns), int(end_ns), bool(throughout), len(keys),
                             int((~moving).sum()), edges, tuple(float(v) for v in noise),
                             motion)

    def _edges(self, keys: list[int],
               runs: list[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
        """Return the stamps (ns) of the window edges of runs of window positions ``[a, b)``."""
        assert self._t0 is not None  # set by the update that filled the windows
        w, t0 = self._w, self._t0
        return tuple((t0 + int(keys[a]) * w, t0 + (int(keys[b - 1]) + 1) * w) for a, b in runs)


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
