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
The slow per-window accumulation of core/segments.py before it was made linear: the test oracle.

One boolean mask per window of a batch (O(batch x windows)), rows in a dict of lists; the rule
itself is the package's (:func:`gyro_noise_ros.core.segments.judge_windows`).
"""

from gyro_noise_ros.core.segments import judge_windows, StaticSegment
import numpy as np


class SlowWindowStats:
    """The accumulation of WindowStats as it was: a mask per window, a dict of rows."""

    def __init__(self, *, window_s: float = 1.0) -> None:
        self._w = int(round(window_s * 1e9))
        self._t0: int | None = None
        self._rows: dict[int, list] = {}  # window index -> [n, sum(3), sumsq(3)]

    def update(self, stamp_ns, gyro) -> None:
        s = np.asarray(stamp_ns, dtype=np.int64)
        if s.size == 0:
            return
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

    def table(self):
        keys = sorted(self._rows)
        width = len(next(iter(self._rows.values()))[1]) if keys else 0
        return (np.array(keys, dtype=np.int64),
                np.array([self._rows[k][0] for k in keys], dtype=np.int64),
                np.array([self._rows[k][1] for k in keys]).reshape(len(keys), width),
                np.array([self._rows[k][2] for k in keys]).reshape(len(keys), width))

    def segment(self) -> StaticSegment | None:
        if self._t0 is None:
            return None
        return judge_windows(*self.table(), t0_ns=self._t0, window_ns=self._w)
