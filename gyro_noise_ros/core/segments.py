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
Static-segment detection: find where a gyro was at rest, so motion is skipped (and said).

Noise characterisation assumes a sensor at rest; real logs often begin or end with handling (PX4
sample: 7 s of motion, then 61 s at rest). The record is cut into windows of ``window_s`` (1 s);
per window and axis the mean and the standard deviation of the angular rate are kept (constant
memory per window, fed batch by batch: :class:`WindowStats`). The static noise level of an axis is
the 20th percentile of its window standard deviations (robust when motion fills most of the record,
as in the x-io example); the static rate is the median window mean of the windows at that noise
level. A window is **moving** when on any axis its standard deviation exceeds ``3x`` the static
noise level, or its mean departs from the static rate by more than ``3x`` that level (a slow turn
raises the mean, not the spread). The analysed segment is the longest run of static windows; when
it covers at least 95 % of the windows the record counts as static throughout.

Only a moving window ends a run. Windows without samples (a stamp gap: the recorder or the link
lost data) do not: the samples on both sides of a gap belong to one static run, and the gap is
reported by the engine as a gap (its length and the samples missing), never as motion.
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
        Static noise level per axis (rad/s).

    """

    start_ns: int
    end_ns: int
    static_throughout: bool
    windows: int
    static_windows: int
    segments: tuple
    noise_rad_s: tuple


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
        runs, start = [], None
        for i, still in enumerate(~moving):
            # windows without data (a stamp gap) are skipped, not motion: only motion ends a run
            if still and start is None:
                start = i
            elif not still and start is not None:
                runs.append((start, i))
                start = None
        if start is not None:
            runs.append((start, len(keys)))
        edges = [(self._t0 + int(keys[a]) * self._w, self._t0 + (int(keys[b - 1]) + 1) * self._w)
                 for a, b in runs]
        if not runs:
            # an empty segment at the record's start, never at stamp 0 (1970)
            return StaticSegment(self._t0, self._t0, False, len(keys), 0, (),
                                 tuple(float(v) for v in noise))
        best = max(range(len(runs)), key=lambda i: runs[i][1] - runs[i][0])
        length = runs[best][1] - runs[best][0]
        throughout = length >= STATIC_ALL * len(keys)
        start_ns, end_ns = edges[best]
        if throughout:
            start_ns, end_ns = self._t0, self._t0 + (int(keys[-1]) + 1) * self._w
        return StaticSegment(int(start_ns), int(end_ns), bool(throughout), len(keys),
                             int((~moving).sum()), tuple(edges), tuple(float(v) for v in noise))
