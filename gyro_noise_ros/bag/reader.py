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
:class:`ImuBagReader`: stream ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` out of one bag.

The rosbag2 (sqlite3, MCAP) and ROS 1 message streams are read in blocks (:mod:`.storage`) and
decoded in bulk (:mod:`gyro_noise_ros.msgs`), so memory stays constant in the bag size.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Literal, Self

import numpy as np

from .batch import ImuBatch
from .storage import BagSource
from .topics import _norm, _select_topic
from ..errors import BagError, ParameterError
from ..msgs import decode_imu_spans, decode_temperature_spans, frame_id_of, IMU_MSGTYPE
from ..msgs import TEMPERATURE_MSGTYPE
from ..outputs import StrPath

#: A decoded block: (stamp_ns, log_ns, gyro, accel, (buf, starts, lengths) for frame ids).
_Decoded = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                 tuple[np.ndarray, np.ndarray, np.ndarray]]


class ImuBagReader:
    """
    Stream ``sensor_msgs/Imu`` (and optionally ``sensor_msgs/Temperature``) out of one bag.

    Memory stays constant in the bag size: messages are read and decoded a block at a time
    (ROS 1 included: only the chunk list is read; see ``docs/scale.md``).

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory (sqlite3 or MCAP), its ``metadata.yaml``, a ``.db3`` or ``.mcap`` file,
        or a ROS 1 ``.bag`` file.
    topic : str, optional
        Imu topic (with or without leading slash); the bag's single Imu topic if None.
    temperature_topic : str, optional
        ``sensor_msgs/Temperature`` topic. If None: the bag's single Temperature topic; when there
        are several, the one in the Imu topic's namespace; otherwise none.
    skip_undecodable : bool
        Skip (and count in ``undecodable_count``) messages that cannot be decoded instead of
        raising.

    Attributes
    ----------
    topic : str
        Imu topic as stored in the bag.
    msgtype : str
        ``sensor_msgs/msg/Imu``.
    temperature_topic : str or None
    storage : {'sqlite3', 'mcap', 'ros1'}
    message_count : int
        Imu messages the bag reports on the topic.
    duration_s : float
        Span of the whole bag in s (first to last message of any topic, receive time).
    undecodable_count : int
        Messages skipped so far (only with ``skip_undecodable``).
    recovery : str or None
        The note (also said once on stderr) when the recording is read although its writer did
        not finish it: an MCAP file without footer read by its chunks, an sqlite3 file read
        through a rolled-back copy, a bag without ``metadata.yaml``; None for a finished bag.

    Raises
    ------
    BagError
        Missing or corrupt bag, no/ambiguous/unknown Imu topic, wrong message type.

    """

    def __init__(self, path: StrPath, *, topic: str | None = None,
                 temperature_topic: str | None = None, skip_undecodable: bool = False) -> None:
        self.path = Path(path)
        self._source: BagSource | None = BagSource(path)
        try:
            topics = self._source.topics()
            self.topic = _select_topic(topics, topic, IMU_MSGTYPE, path)
            self.msgtype = IMU_MSGTYPE
            self.storage = self._source.storage
            self.message_count = topics[self.topic][1]
            self.duration_s = self._source.duration_s()
            self.temperature_topic = self._pick_temperature(topics, temperature_topic)
            self.recovery = self._source.recovery
        except BaseException:
            self._source.close()
            raise
        self.skip_undecodable = bool(skip_undecodable)
        self.undecodable_count = 0

    def _pick_temperature(self, topics: dict[str, tuple[str | None, int]],
                          requested: str | None) -> str | None:
        if requested is not None:
            return _select_topic(topics, requested, TEMPERATURE_MSGTYPE, self.path)
        names = sorted(name for name, (kind, _) in topics.items() if kind == TEMPERATURE_MSGTYPE)
        if len(names) == 1:
            return names[0]
        namespace = _norm(self.topic).rpartition('/')[0]
        same = [name for name in names if _norm(name).rpartition('/')[0] == namespace]
        return same[0] if len(same) == 1 else None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> Literal[False]:
        self.close()
        return False

    def close(self) -> None:
        """Close the bag (idempotent)."""
        if self._source is not None:
            self._source.close()
            self._source = None

    def _open_source(self) -> BagSource:
        if self._source is None:
            raise BagError(f'bag {str(self.path)!r} was closed')
        return self._source

    def _decoded_blocks(self, source: BagSource) -> Iterator[_Decoded]:
        """
        Yield decoded blocks.

        (stamp, log, gyro, accel, (buf, starts, lengths) for frame ids).
        """
        for buf, starts, lengths, log_ns in source.blocks(self.topic):
            try:
                keep, stamp_ns, gyro, accel = decode_imu_spans(buf, starts, lengths, source.ros1,
                                                               self.skip_undecodable)
            except BagError as err:
                raise BagError(f'bag {str(self.path)!r}, topic {self.topic!r}: {err}') from err
            if keep is not None:
                self.undecodable_count += starts.shape[0] - keep.shape[0]
                starts, lengths, log_ns = starts[keep], lengths[keep], log_ns[keep]
            if stamp_ns.shape[0]:
                yield stamp_ns, log_ns, gyro, accel, (buf, starts, lengths)

    def iter_batches(self, batch_size: int = 65536) -> Iterator[ImuBatch]:
        """
        Yield the Imu messages in bag order as :class:`ImuBatch` es of ``batch_size`` messages.

        Parameters
        ----------
        batch_size : int
            Messages per batch (the last one may be shorter); at least 1.

        Yields
        ------
        ImuBatch
            Stamps are delivered as recorded (see :func:`count_stamp_regressions`).

        Raises
        ------
        BagError
            The topic has no messages (raised at the end, nothing was yielded), the bag turns out
            corrupt or truncated, or a message cannot be decoded.

        """
        if isinstance(
                batch_size, bool) or not isinstance(batch_size,
                                                    (int, np.integer)) or batch_size < 1:
            raise ParameterError(f'batch_size must be a positive integer, got {batch_size!r}')
        source = self._open_source()
        size = int(batch_size)
        pending, have, delivered = [], 0, 0
        for block in self._decoded_blocks(source):
            pending.append(block)
            have += block[0].shape[0]
            while have >= size:
                batch, pending = _take(pending, size, source.ros1)
                have -= size
                delivered += size
                yield batch
        if have:
            delivered += have
            yield _take(pending, have, source.ros1)[0]
        if delivered == 0 and self.undecodable_count == 0:
            if self.recovery:
                raise BagError(f'bag {str(self.path)!r}: nothing on topic {self.topic!r} could '
                               f'be recovered: {self.recovery}')
            raise BagError(f'bag {str(self.path)!r} has no messages on topic {self.topic!r}')

    def read_temperature(self) -> tuple[np.ndarray, np.ndarray] | None:
        """
        Read the whole temperature topic.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(stamp_ns int64 (n,), temperature_c float64 (n,))`` in bag order, or None if the bag
            has no temperature topic.

        Raises
        ------
        BagError
            The bag turns out corrupt or a message cannot be decoded.

        """
        if self.temperature_topic is None:
            return None
        source = self._open_source()
        stamps, temps = [np.zeros(0, np.int64)], [np.zeros(0)]
        for buf, starts, lengths, _ in source.blocks(self.temperature_topic):
            try:
                s, t = decode_temperature_spans(buf, starts, lengths, source.ros1)
            except BagError as err:
                raise BagError(
                    f'bag {str(self.path)!r}, topic {self.temperature_topic!r}: {err}') from err
            stamps.append(s)
            temps.append(t)
        return np.concatenate(stamps), np.concatenate(temps)


def _take(pending: list[_Decoded], size: int, ros1: bool) -> tuple[ImuBatch, list[_Decoded]]:
    """Cut the first ``size`` messages off the pending decoded blocks; return (batch, rest)."""
    parts, rest, need = [], list(pending), size
    while need:
        stamp, log, gyro, accel, spans = rest[0]
        k = stamp.shape[0]
        if k <= need:
            parts.append(rest.pop(0))
            need -= k
        else:
            buf, starts, lengths = spans
            parts.append((stamp[:need], log[:need], gyro[:need], accel[:need],
                          (buf, starts[:need], lengths[:need])))
            rest[0] = (stamp[need:], log[need:], gyro[need:], accel[need:],
                       (buf, starts[need:], lengths[need:]))
            need = 0
    buf, starts, lengths = parts[0][4]
    frame_id = frame_id_of(buf[starts[0]:starts[0] + lengths[0]], ros1) or ''
    if len(parts) == 1:
        stamp, log, gyro, accel, _ = parts[0]
    else:
        stamp, log, gyro, accel = (np.concatenate([p[i] for p in parts]) for i in range(4))
    return ImuBatch(stamp, log, gyro, accel, frame_id), rest
