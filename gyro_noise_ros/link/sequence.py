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
Sample and message counters: the board's wrapping uint32 sample counter and DDS sequence numbers.

Pure numpy, no ROS. :class:`SequenceTracker` is the driver's publish-once filter and loss counter;
:class:`SequenceGapCounter` counts messages missing from a stream of DDS publication sequence
numbers (compensator); :class:`PublisherCounts` does it per publisher (analyzer, recorder).
"""

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

_UINT32 = 1 << 32


def wrapped_delta(a: npt.ArrayLike, b: npt.ArrayLike) -> NDArray[np.int64]:
    """Return the signed distance ``a - b`` of uint32 counters (int64, -2**31..2**31-1)."""
    return ((np.asarray(a, np.int64) - np.asarray(b, np.int64) + (1 << 31)) % _UINT32) - (1 << 31)


def consecutive(seq: NDArray[np.uint32]) -> bool:
    """Return whether each uint32 counter is the one before it plus 1 (modulo 2**32)."""
    return bool((seq[1:] - seq[:-1] == 1).all())


@dataclass(frozen=True)
class Accepted:
    """
    What :meth:`SequenceTracker.accept` decided for a batch.

    Attributes
    ----------
    keep : numpy.ndarray of bool
        Samples of the accepted prefix to publish (counter ahead of everything published before).
    stop : int
        Length of the prefix decided; ``stop < len(batch)`` means a board restart at ``stop``.
    lost : int
        Counter gaps between the previous published sample and the kept ones.
    duplicates : int
        Samples dropped because their counter was already published.
    whole : bool
        True when the decision is the whole batch, every sample kept (``keep`` all True).

    """

    keep: np.ndarray
    stop: int
    lost: int
    duplicates: int
    whole: bool = False


class SequenceTracker:
    """
    Publish-once filter and loss counter over the board's wrapping uint32 sample counter.

    Parameters
    ----------
    restart_window : int
        A counter that falls back by at least this many samples is a board restart (new epoch),
        a smaller fall-back (including a repeat of the last counter) is a re-sent duplicate.

    """

    def __init__(self, restart_window: int) -> None:
        self.restart_window = int(restart_window)
        self.last: int | None = None

    def reset(self) -> None:
        """Forget the last published counter (new epoch: the next sample is accepted as is)."""
        self.last = None

    def accept(self, seq: NDArray[np.integer[Any]]) -> Accepted:
        """
        Decide which samples of a batch to publish.

        Parameters
        ----------
        seq : numpy.ndarray of uint32
            Sample counters in arrival order.

        Returns
        -------
        Accepted
            The decision for ``seq[:stop]``; the caller resets its epoch and calls again with
            ``seq[stop:]`` when ``stop < len(seq)``.

        """
        n = len(seq)
        if n == 0:
            return Accepted(np.zeros(0, bool), 0, 0, 0)
        first, last = int(seq[0]), int(seq[-1])
        # With no published sample yet the first one is accepted as is (its step counts as 1).
        step0 = 1 if self.last is None else int(wrapped_delta(first, self.last))
        # uint32 differences wrap like the counter, so 1 means "next sample" across 2**32 too.
        # A one-sample batch takes this path only when it is ahead (step0 > 0); a repeat of the
        # last counter (step0 == 0) falls through and is counted as a duplicate below.
        if step0 > 0 and (n == 1 or (last - first) % _UINT32 == n - 1
                          and consecutive(np.asarray(seq, np.uint32))):
            # The common case, one call per read: consecutive after a gap of step0 - 1.
            self.last = last
            return Accepted(np.ones(n, bool), n, step0 - 1, 0, whole=True)
        seq64 = np.asarray(seq, np.int64)
        steps = wrapped_delta(seq64[1:], seq64[:-1])
        if step0 > 0 and np.all(steps > 0):
            # Strictly increasing with gaps inside the batch.
            self.last = last
            return Accepted(np.ones(n, bool), n, step0 - 1 + int(np.sum(steps - 1)), 0,
                            whole=True)
        keep = np.zeros(n, bool)
        lost = duplicates = 0
        for i in range(n):
            s = int(seq64[i])
            if self.last is None:
                keep[i] = True
                self.last = s
                continue
            d = int(wrapped_delta(s, self.last))
            if d > 0:
                keep[i] = True
                lost += d - 1
                self.last = s
            elif d > -self.restart_window:
                duplicates += 1
            else:
                return Accepted(keep[:i], i, lost, duplicates)
        return Accepted(keep, n, lost, duplicates)


#: Batches up to this many sequence numbers (lists) are counted in a plain loop.
_SHORT = 64


class SequenceGapCounter:
    """
    Count messages missing from a stream of DDS publication sequence numbers.

    A sequence number that does not increase starts a new run (a restarted publisher); a
    sequence number of 0 means the middleware gave none and is ignored. The count assumes one
    publisher: with several, their numbers interleave and the count is meaningless; keep one
    counter per publisher (:class:`PublisherCounts`).
    """

    def __init__(self) -> None:
        self.last: int | None = None
        self.missing = 0

    def update(self, sequence: npt.ArrayLike) -> int:
        """
        Add the sequence numbers of one batch and return the new misses.

        Parameters
        ----------
        sequence : array_like of int
            Publication sequence numbers in arrival order (0: none given).

        Returns
        -------
        int
            Messages missing between the previous batch and the end of this one.

        """
        if isinstance(sequence, list) and len(sequence) <= _SHORT:
            # A live batch of a few messages: a plain loop costs less than the array calls.
            last, new = self.last, 0
            for s in sequence:
                if s > 0:
                    if last is not None and s > last + 1:
                        new += s - last - 1
                    last = int(s)
            self.last = last
            self.missing += new
            return new
        seq = np.asarray(sequence, dtype=np.int64)
        seq = seq[seq > 0]
        if seq.size == 0:
            return 0
        if self.last is not None:
            seq = np.concatenate(([self.last], seq))
        step = np.diff(seq)
        new = int(step[step > 1].sum() - np.count_nonzero(step > 1))
        self.last = int(seq[-1])
        self.missing += new
        return new


class PublisherCounts:
    """
    Messages and DDS sequence gaps per publisher of one topic.

    Each publisher (writer GID) numbers its messages on its own; a :class:`SequenceGapCounter` per
    publisher keeps two interleaved streams from looking like millions of drops. A GID of None
    (the middleware or the client library gave none) is one more publisher, unknown.
    """

    def __init__(self) -> None:
        # gid -> [messages, SequenceGapCounter], in order of first message
        self._by_gid: dict[bytes | None, list[Any]] = {}

    def update(self, gids: NDArray[np.void] | Sequence[bytes] | None,
               sequence: npt.ArrayLike) -> list[bytes | None]:
        """
        Count one batch.

        Parameters
        ----------
        gids : numpy.ndarray or sequence of bytes or None
            The writer of each message (a ``V16`` array or 16-byte strings; None for the whole
            batch: unknown).
        sequence : array_like of int
            Publication sequence numbers in arrival order (0: none given).

        Returns
        -------
        list
            The batch's writers (bytes, or None), in order of their first message in it.

        """
        seq = np.asarray(sequence, dtype=np.int64)
        if seq.size == 0:
            return []
        if gids is None:
            groups: dict[bytes | None, NDArray[np.int64]] = {None: seq}
        else:
            keys = np.asarray(gids)
            if keys.dtype.kind != 'V':
                keys = np.array([bytes(g) for g in gids], dtype='V16')
            if np.all(keys == keys[0]):  # the usual case: one publisher
                groups = {bytes(keys[0]): seq}
            else:
                _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
                inverse = inverse.reshape(-1)
                groups = {bytes(keys[first[k]]): seq[inverse == k]
                          for k in np.argsort(first, kind='stable')}
        for gid, part in groups.items():
            entry = self._by_gid.get(gid)
            if entry is None:
                entry = self._by_gid[gid] = [0, SequenceGapCounter()]
            entry[0] += int(part.size)
            entry[1].update(part)
        return list(groups)

    def publishers(self) -> list[bytes | None]:
        """Return the GIDs seen, in order of their first message."""
        return list(self._by_gid)

    def table(self) -> list[tuple[bytes | None, int, int]]:
        """Return ``[(gid, messages, missing), ...]`` in order of first message."""
        return [(gid, n, gaps.missing) for gid, (n, gaps) in self._by_gid.items()]

    @property
    def messages(self) -> int:
        """int: Messages counted, all publishers."""
        return sum(n for n, _ in self._by_gid.values())

    @property
    def missing(self) -> int:
        """int: Messages missing from the publishers' sequences, all publishers."""
        return sum(gaps.missing for _, gaps in self._by_gid.values())
