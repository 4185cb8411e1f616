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
Rosbag reading and writing for gyro_noise_ros, ROS-free (rosbags library only).

Reads rosbag2 recordings (a directory with ``metadata.yaml``, or a bare ``.db3``/``.mcap`` file;
sqlite3 or MCAP storage) and ROS 1 ``.bag`` files; writes rosbag2 (sqlite3 or MCAP).
``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` are decoded and encoded in bulk with numpy
(:mod:`.codec`), and the rosbag2 message streams are read in blocks (:mod:`.storage`), so a 12 h
6.66 kHz recording streams in constant memory at millions of messages per second. See
``docs/bags.md``.

Topic discovery: with no topic given, the bag's single ``sensor_msgs/msg/Imu`` topic is used; topic
names match with or without their leading slash. Every failure to read is a :class:`BagError` with
one sentence naming the bag and the problem.
"""

from __future__ import annotations

from dataclasses import dataclass
import itertools
from pathlib import Path

import numpy as np

from .codec import (
    count_stamp_regressions,
    decode_imu_spans,
    decode_temperature_spans,
    encode_imu_cdr,
    encode_temperature_cdr,
    frame_id_of,
    IMU_MSGTYPE,
    join_raws,
    split_stamps,
    TEMPERATURE_MSGTYPE,
    typestore,
)
from .storage import BagSource, describe, STORAGES
from ..errors import BagError, OutputError, ParameterError

__all__ = [
    'IMU_MSGTYPE',
    'TEMPERATURE_MSGTYPE',
    'TopicInfo',
    'ImuBatch',
    'ImuBagReader',
    'ImuBagWriter',
    'list_topics',
    'find_imu_topic',
    'decode_imu',
    'decode_temperature',
    'encode_imu_cdr',
    'encode_temperature_cdr',
    'count_stamp_regressions',
]


@dataclass(frozen=True)
class TopicInfo:
    """
    One topic of a bag.

    Attributes
    ----------
    name : str
        Topic name as stored in the bag.
    msgtype : str or None
        ROS 2 style message type (``sensor_msgs/msg/Imu``; rosbags normalises ROS 1 names), None if
        the topic's connections disagree.
    count : int
        Number of messages the bag's index or metadata reports for the topic.

    """

    name: str
    msgtype: str | None
    count: int


@dataclass(frozen=True)
class ImuBatch:
    """
    Consecutive ``sensor_msgs/Imu`` messages of one topic, decoded to arrays.

    Attributes
    ----------
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns (``sec * 1e9 + nanosec``), in recorded order (not sorted).
    log_ns : numpy.ndarray of int64, shape (n,)
        Time the recorder received each message (bag time), in ns.
    gyro : numpy.ndarray of float64, shape (n, 3)
        ``angular_velocity`` x, y, z in rad/s; NaN stays NaN.
    accel : numpy.ndarray of float64, shape (n, 3)
        ``linear_acceleration`` x, y, z in m/s^2.
    frame_id : str
        ``header.frame_id`` of the batch's first message.

    """

    stamp_ns: np.ndarray
    log_ns: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    frame_id: str

    def __len__(self):
        return int(self.stamp_ns.shape[0])


# ---------------------------------------------------------------------------------------------
# Decoding lists of raw messages (what a raw=True rclpy subscription delivers)


def decode_imu(raws, *, log_ns=None, ros1=False, skip_undecodable=False):
    """
    Decode raw ``sensor_msgs/Imu`` messages in bulk.

    Parameters
    ----------
    raws : sequence of bytes-like
        Serialised messages: ROS 2 CDR (either endianness), or ROS 1 with ``ros1=True``.
    log_ns : array_like of int, shape (n,), optional
        Receive times in ns; the header stamps if None.
    ros1 : bool
        Messages use the ROS 1 serialisation.
    skip_undecodable : bool
        Drop messages neither the bulk nor rosbags' decoder can read instead of raising.

    Returns
    -------
    ImuBatch
        ``len(batch) < len(raws)`` only when messages were skipped.

    Raises
    ------
    BagError
        A message cannot be decoded and ``skip_undecodable`` is False.

    """
    buf, starts, lengths = join_raws(raws)
    keep, stamp_ns, gyro, accel = decode_imu_spans(buf, starts, lengths, ros1, skip_undecodable)
    if log_ns is None:
        log = stamp_ns.copy()
    else:
        log = np.asarray(log_ns, dtype=np.int64).reshape(-1)
        if log.shape[0] != len(raws):
            raise ParameterError(f'log_ns has {log.shape[0]} values for {len(raws)} messages')
        log = log if keep is None else log[keep]
    first = 0 if keep is None else (int(keep[0]) if keep.size else None)
    frame_id = (frame_id_of(raws[first], ros1) or '') if first is not None and len(raws) else ''
    return ImuBatch(stamp_ns, log, gyro, accel, frame_id)


def decode_temperature(raws, *, ros1=False):
    """
    Decode raw ``sensor_msgs/Temperature`` messages in bulk.

    Parameters
    ----------
    raws : sequence of bytes-like
        Serialised messages (ROS 2 CDR, or ROS 1 with ``ros1=True``).
    ros1 : bool
        Messages use the ROS 1 serialisation.

    Returns
    -------
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns.
    temperature_c : numpy.ndarray of float64, shape (n,)
        ``temperature`` in degC.

    Raises
    ------
    BagError
        A message cannot be decoded.

    """
    return decode_temperature_spans(*join_raws(raws), ros1)


# ---------------------------------------------------------------------------------------------
# Topics


def _norm(name):
    return name.lstrip('/')


def _select_topic(topics, topic, msgtype, path):
    """Pick the topic of ``msgtype`` (the single one if ``topic`` is None); raise BagError."""
    if topic is not None:
        matches = [name for name in topics if _norm(name) == _norm(topic)]
        if not matches:
            known = ', '.join(sorted(topics)) or 'none'
            raise BagError(f'topic {topic!r} is not in bag {str(path)!r} (topics: {known})')
        name = matches[0]
        if topics[name][0] != msgtype:
            raise BagError(
                f'topic {name!r} in bag {str(path)!r} carries {topics[name][0]}, not {msgtype}')
        return name
    candidates = sorted(name for name, (kind, _) in topics.items() if kind == msgtype)
    if not candidates:
        raise BagError(f'bag {str(path)!r} has no {msgtype} topic')
    if len(candidates) > 1:
        raise BagError(
            f'bag {str(path)!r} has {len(candidates)} {msgtype} topics ({", ".join(candidates)}); '
            'choose one with --topic')
    return candidates[0]


def list_topics(path):
    """
    List the topics of a bag.

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory, ``.db3``/``.mcap`` file, or ROS 1 ``.bag`` file.

    Returns
    -------
    list of TopicInfo
        Sorted by name.

    Raises
    ------
    BagError
        The path is missing or not a readable bag.

    """
    source = BagSource(path)
    try:
        return [TopicInfo(name, kind, count) for name,
                (kind, count) in sorted(source.topics().items())]
    finally:
        source.close()


def find_imu_topic(path, topic=None):
    """
    Name the ``sensor_msgs/Imu`` topic to analyse.

    Parameters
    ----------
    path : str or os.PathLike
        Bag path (see :func:`list_topics`).
    topic : str, optional
        Requested topic, matched with or without the leading slash. If None, the bag's single
        ``sensor_msgs/msg/Imu`` topic.

    Returns
    -------
    str
        The topic name as stored in the bag.

    Raises
    ------
    BagError
        No Imu topic, several Imu topics (the message lists them), unknown topic, or a topic of
        another message type.

    """
    source = BagSource(path)
    try:
        return _select_topic(source.topics(), topic, IMU_MSGTYPE, path)
    finally:
        source.close()


# ---------------------------------------------------------------------------------------------
# Reader


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

    def __init__(self, path, *, topic=None, temperature_topic=None, skip_undecodable=False):
        self.path = Path(path)
        self._source = BagSource(path)
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

    def _pick_temperature(self, topics, requested):
        if requested is not None:
            return _select_topic(topics, requested, TEMPERATURE_MSGTYPE, self.path)
        names = sorted(name for name, (kind, _) in topics.items() if kind == TEMPERATURE_MSGTYPE)
        if len(names) == 1:
            return names[0]
        namespace = _norm(self.topic).rpartition('/')[0]
        same = [name for name in names if _norm(name).rpartition('/')[0] == namespace]
        return same[0] if len(same) == 1 else None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self):
        """Close the bag (idempotent)."""
        if self._source is not None:
            self._source.close()
            self._source = None

    def _open_source(self):
        if self._source is None:
            raise BagError(f'bag {str(self.path)!r} was closed')
        return self._source

    def _decoded_blocks(self, source):
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

    def iter_batches(self, batch_size=65536):
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
            raise BagError(f'bag {str(self.path)!r} has no messages on topic {self.topic!r}')

    def read_temperature(self):
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


def _take(pending, size, ros1):
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


# ---------------------------------------------------------------------------------------------
# Writer


def write_raw(writer, conn, log_ns, blobs, path):
    """
    Append serialised messages of one connection to an open rosbags ``Writer``.

    Parameters
    ----------
    writer : rosbags.rosbag2.Writer
        The open writer.
    conn : rosbags.interfaces.Connection
        A connection of ``writer``.
    log_ns : numpy.ndarray of int64, shape (n,)
        Bag (receive) times in ns.
    blobs : sequence of bytes-like, length n
        The serialised messages.
    path : str or os.PathLike
        The bag, for messages.

    Raises
    ------
    OutputError
        Writing failed (disk full, sqlite errors).

    """
    if not len(blobs):
        return
    try:
        storage = writer.storage
        if (
            type(storage).__name__ == 'Sqlite3Writer'
            and hasattr(storage, 'cursor')
            and conn.id in getattr(writer, 'counts', {})
            and hasattr(writer, 'min_timestamp')
        ):
            # rosbags' Writer.write costs several us per message in Python; issuing the very
            # INSERT it would issue through one executemany, plus its bookkeeping (count and
            # time range for metadata.yaml), is several times cheaper. Any other rosbags
            # layout takes the per-message path below.
            storage.cursor.executemany(
                'INSERT INTO messages (topic_id, timestamp, data) VALUES(?, ?, ?)',
                zip(itertools.repeat(conn.id), log_ns.tolist(), blobs))
            writer.counts[conn.id] += len(blobs)
            writer.min_timestamp = min(writer.min_timestamp, int(log_ns.min()))
            writer.max_timestamp = max(writer.max_timestamp, int(log_ns.max()))
            return
        for t, blob in zip(log_ns.tolist(), blobs):
            writer.write(conn, t, blob)
    except Exception as err:  # noqa: BLE001 - disk full, sqlite errors
        raise OutputError(f'bag {str(path)!r}: writing failed: {describe(err)}') from err


class ImuBagWriter:
    """
    Write ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` into a new rosbag2.

    Messages are serialised in bulk (:func:`encode_imu_cdr`) and handed to the rosbags writer.
    The bag (its ``metadata.yaml``) is complete only after :meth:`close`; the context manager
    closes it also when the body raises, so that what was recorded is kept.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory to create; must not exist.
    storage : {'sqlite3', 'mcap'}
        rosbag2 storage plugin.
    imu_topic : str
        Imu topic name.
    temperature_topic : str or None
        Temperature topic name (its connection is created on the first temperature write);
        None records no temperature.
    frame_id : str
        ``header.frame_id`` of every message.
    fsync : bool
        sqlite3 only: make every commit (:meth:`flush`, :meth:`close`) wait for the disk. Off by
        default: a commit then costs microseconds instead of tens of milliseconds, and what was
        committed still survives the recorder process being killed (the data is in the operating
        system's cache); only an operating-system crash or power loss can lose or damage it.

    Raises
    ------
    ParameterError
        Unknown storage or bad frame_id.
    OutputError
        The bag cannot be created (path exists, not writable); later, a write, flush or close
        fails (disk full). Exit code 6 in the tools, like every output that cannot be written.

    """

    def __init__(self, path, *, storage='sqlite3', imu_topic='/imu/data_raw',
                 temperature_topic='/imu/temperature', frame_id='imu_link', fsync=False):
        from rosbags.rosbag2 import StoragePlugin, Writer

        if storage not in STORAGES:
            raise ParameterError(f"storage must be 'sqlite3' or 'mcap', got {storage!r}")
        if not isinstance(frame_id, str) or '\x00' in frame_id:
            raise ParameterError(f'frame_id must be a str without NUL, got {frame_id!r}')
        self.path = Path(path)
        self.storage = storage
        self.imu_topic = imu_topic
        self.temperature_topic = temperature_topic
        self.frame_id = frame_id
        self.imu_count = 0
        self.temperature_count = 0
        plugin = StoragePlugin.SQLITE3 if storage == 'sqlite3' else StoragePlugin.MCAP
        self._writer = None
        try:
            writer = Writer(self.path, version=9, storage_plugin=plugin)
            writer.open()
            self._writer = writer
            conn = getattr(writer.storage, 'conn', None)
            if storage == 'sqlite3' and conn is not None and not fsync:
                # The rollback journal stays on disk (process-crash safety); only the fsyncs go.
                conn.execute('PRAGMA synchronous=OFF')
            self._imu_conn = writer.add_connection(imu_topic, IMU_MSGTYPE, typestore=typestore())
        except Exception as err:  # noqa: BLE001 - rosbags WriterError, OSError, sqlite errors
            raise OutputError(
                f'bag {str(self.path)!r} cannot be created: {describe(err)}') from err
        self._temperature_conn = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _write(self, conn, log_ns, blobs):
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        write_raw(writer, conn, log_ns, blobs, self.path)

    @staticmethod
    def _log_times(stamps, log_ns):
        if log_ns is None:
            return stamps
        logs = split_stamps(log_ns, 'log_ns')[0]
        if logs.shape != stamps.shape:
            raise ParameterError(f'log_ns has {logs.shape[0]} values for {stamps.shape[0]} stamps')
        return logs

    def write_imu(self, stamp_ns, gyro_rad_s, accel_m_s2, *, angular_velocity_covariance=None,
                  linear_acceleration_covariance=None, log_ns=None, topic=None):
        """
        Append Imu messages.

        Parameters
        ----------
        stamp_ns : int or array_like of int, shape (n,)
            Header stamps in ns.
        gyro_rad_s : array_like, shape (3,) or (n, 3)
            Angular velocity in rad/s.
        accel_m_s2 : array_like, shape (3,) or (n, 3)
            Linear acceleration in m/s^2.
        angular_velocity_covariance, linear_acceleration_covariance : array_like
            Shape (9,) or (n, 9).
            Row-major covariances in (rad/s)^2 and (m/s^2)^2; zeros (unknown) if None.
        log_ns : int or array_like of int, optional
            Bag (receive) time in ns; the header stamps if None.
        topic : str, optional
            Another Imu topic of the same bag (e.g. a reference sensor), its connection created on
            first use; ``imu_topic`` if None (only those messages count in ``imu_count``).

        """
        stamps = split_stamps(stamp_ns, 'stamp_ns')[0]
        blobs = encode_imu_cdr(stamps, gyro_rad_s, accel_m_s2, frame_id=self.frame_id,
                               angular_velocity_covariance=angular_velocity_covariance,
                               linear_acceleration_covariance=linear_acceleration_covariance)
        conn = self._imu_conn
        if topic is not None and topic != self.imu_topic:
            conn = self._extra_imu(topic)
        self._write(conn, self._log_times(stamps, log_ns), blobs)
        if conn is self._imu_conn:
            self.imu_count += len(blobs)

    def _extra_imu(self, topic):
        extra = self.__dict__.setdefault('_extra_imu_conns', {})
        if topic not in extra:
            if self._writer is None:
                raise BagError(f'bag {str(self.path)!r} is closed')
            try:
                extra[topic] = self._writer.add_connection(topic, IMU_MSGTYPE,
                                                           typestore=typestore())
            except Exception as err:  # noqa: BLE001 - rosbags WriterError
                raise OutputError(f'bag {str(self.path)!r}: cannot add topic {topic!r}: '
                                  f'{describe(err)}') from err
        return extra[topic]

    def write_temperature(self, stamp_ns, temperature_c, *, variance=0.0, log_ns=None):
        """
        Append Temperature messages.

        Parameters
        ----------
        stamp_ns : int or array_like of int, shape (n,)
            Header stamps in ns.
        temperature_c : float or array_like, shape (n,)
            Temperature in degC.
        variance : float or array_like, shape (n,)
            Variance in degC^2 (0 = unknown).
        log_ns : int or array_like of int, optional
            Bag (receive) time in ns; the header stamps if None.

        """
        if self.temperature_topic is None:
            raise ParameterError(
                'temperature_topic is None, so this writer records no temperature')
        stamps = split_stamps(stamp_ns, 'stamp_ns')[0]
        blobs = encode_temperature_cdr(stamps, temperature_c, frame_id=self.frame_id,
                                       variance=variance)
        logs = self._log_times(stamps, log_ns)
        if self._temperature_conn is None and self._writer is not None:
            try:
                self._temperature_conn = self._writer.add_connection(
                    self.temperature_topic, TEMPERATURE_MSGTYPE, typestore=typestore())
            except Exception as err:  # noqa: BLE001
                raise OutputError(
                    f'bag {str(self.path)!r}: cannot add {self.temperature_topic!r}: '
                    f'{describe(err)}') from err
        self._write(self._temperature_conn, logs, blobs)
        self.temperature_count += len(blobs)

    def flush(self):
        """
        Make what was written so far survive a crash of this process (both storages).

        sqlite3: rosbags keeps one transaction open until :meth:`close`; this commits it, so a
        killed writer leaves a ``.db3`` whose rollback journal :class:`ImuBagReader` rolls back
        (in a copy) to this point. MCAP: the pending chunk (rosbags closes one only past 1 MiB)
        is closed and the file buffer handed to the operating system, so a killed writer leaves
        whole chunks that :class:`ImuBagReader` reads without the missing summary. Either way
        ``metadata.yaml`` is written by :meth:`close` only. Costs one fsync-free commit or one
        chunk record; call it about once a second, not per message.
        """
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        storage = writer.storage
        try:
            if self.storage == 'sqlite3':
                conn = getattr(storage, 'conn', None)
                if conn is not None:
                    conn.commit()
                return
            chunk = getattr(storage, 'chunk', None)
            if chunk is not None and any(chunk.msgs.values()):
                storage.close_chunk()
            bio = getattr(storage, 'bio', None)
            if bio is not None:
                bio.flush()
        except Exception as err:  # noqa: BLE001
            raise OutputError(f'bag {str(self.path)!r}: flush failed: {describe(err)}') from err

    def close(self):
        """Finish the bag: write its index and ``metadata.yaml`` (idempotent)."""
        writer, self._writer = self._writer, None
        if writer is not None:
            try:
                writer.close()
            except Exception as err:  # noqa: BLE001
                raise OutputError(
                    f'bag {str(self.path)!r} cannot be finished: {describe(err)}') from err
