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
:class:`ImuBagWriter`: write ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` into a rosbag2.

Messages are serialised in bulk (:mod:`gyro_noise_ros.msgs`) and handed to the rosbags writer
(:func:`write_raw`); :class:`~gyro_noise_ros.bag.bulk.BulkImuBagWriter` writes the same bag in
blocks.
"""

from __future__ import annotations

from collections.abc import Sequence
import itertools
from pathlib import Path
from typing import Any, Literal, Self, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .storage import describe, STORAGES
from ..errors import BagError, OutputError, ParameterError
from ..msgs import encode_imu_cdr, encode_temperature_cdr, IMU_MSGTYPE, split_stamps
from ..msgs import TEMPERATURE_MSGTYPE, typestore
from ..outputs import StrPath

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2 import Writer

#: What :class:`ImuBagWriter` writes: no compression, or zstd MCAP chunks.
COMPRESSIONS = ('none', 'zstd')


def write_raw(writer: Writer, conn: Connection, log_ns: np.ndarray,
              blobs: Sequence[bytes | memoryview], path: StrPath) -> None:
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
        # rosbags' storage writer, its layout probed by name and attributes
        storage: Any = writer.storage
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
    compression : {'none', 'zstd'}
        MCAP only: zstd chunk compression (what ``ros2 bag record --storage mcap
        --storage-preset-profile zstd_fast`` writes; rosbag2's ``storage`` compression mode).
        Measured on the bench's simulated gyro: 7x smaller (99 MB instead of 708 MB for 2 M
        messages), about 0.4 s more per million messages to write, 0.1 us more per message to
        read.

    Raises
    ------
    ParameterError
        Unknown storage or compression, compression with sqlite3, or bad frame_id.
    OutputError
        The bag cannot be created (path exists, not writable); later, a write, flush or close
        fails (disk full). Exit code 6 in the tools, like every output that cannot be written.

    """

    def __init__(self, path: StrPath, *, storage: str = 'sqlite3',
                 imu_topic: str = '/imu/data_raw',
                 temperature_topic: str | None = '/imu/temperature', frame_id: str = 'imu_link',
                 fsync: bool = False, compression: str = 'none') -> None:
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        if storage not in STORAGES:
            raise ParameterError(f"storage must be 'sqlite3' or 'mcap', got {storage!r}")
        if compression not in COMPRESSIONS:
            raise ParameterError(f"compression must be 'none' or 'zstd', got {compression!r}")
        if compression != 'none' and storage != 'mcap':
            raise ParameterError(f'compression {compression!r} needs mcap storage (chunk '
                                 f'compression), got {storage!r}')
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
        self._writer: Writer | None = None
        try:
            writer = Writer(self.path, version=9, storage_plugin=plugin)
            if compression == 'zstd':
                writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
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
        self._temperature_conn: Connection | None = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> Literal[False]:
        self.close()
        return False

    def _write(self, conn: Connection | None, log_ns: np.ndarray,
               blobs: Sequence[bytes | memoryview]) -> None:
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        assert conn is not None  # an open writer has made the topic's connection
        write_raw(writer, conn, log_ns, blobs, self.path)

    @staticmethod
    def _log_times(stamps: np.ndarray, log_ns: ArrayLike | None) -> np.ndarray:
        if log_ns is None:
            return stamps
        logs = split_stamps(log_ns, 'log_ns')[0]
        if logs.shape != stamps.shape:
            raise ParameterError(f'log_ns has {logs.shape[0]} values for {stamps.shape[0]} stamps')
        return logs

    def write_imu(self, stamp_ns: ArrayLike, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, *,
                  angular_velocity_covariance: ArrayLike | None = None,
                  linear_acceleration_covariance: ArrayLike | None = None,
                  log_ns: ArrayLike | None = None, topic: str | None = None) -> None:
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

    def write_imu_raw(self, blobs: Sequence[bytes], log_ns: ArrayLike) -> None:
        """
        Append serialised ROS 2 CDR Imu messages as they are (what ``ros2 bag record`` stores).

        The caller has checked them (e.g. :func:`gyro_noise_ros.msgs.imu_rows.imu_rows`): they
        are written byte for byte, without a decode and re-encode.

        Parameters
        ----------
        blobs : sequence of bytes
            The messages.
        log_ns : array_like of int, shape (n,)
            Bag (receive) time of each in ns.

        """
        logs = split_stamps(log_ns, 'log_ns')[0]
        if logs.shape[0] != len(blobs):
            raise ParameterError(f'log_ns has {logs.shape[0]} values for {len(blobs)} messages')
        self._write(self._imu_conn, logs, blobs)
        self.imu_count += len(blobs)

    def _extra_imu(self, topic: str) -> Connection:
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

    def write_temperature(self, stamp_ns: ArrayLike, temperature_c: ArrayLike, *,
                          variance: ArrayLike = 0.0, log_ns: ArrayLike | None = None) -> None:
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

    def flush(self) -> None:
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
        storage: Any = writer.storage  # rosbags' storage writer, probed by attribute
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

    def close(self) -> None:
        """Finish the bag: write its index and ``metadata.yaml`` (idempotent)."""
        writer, self._writer = self._writer, None
        if writer is not None:
            try:
                writer.close()
            except Exception as err:  # noqa: BLE001
                raise OutputError(
                    f'bag {str(self.path)!r} cannot be finished: {describe(err)}') from err
