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
Bulk rosbag2 writing for recordings converted offline (the SD-log importer).

:class:`ImuBagWriter` hands every message to rosbags as one Python ``bytes`` object, and its
sqlite3 fast path still costs one ``executemany`` row (several microseconds) per message.
:class:`BulkImuBagWriter` writes the same bytes in blocks instead:

* sqlite3: one ``INSERT ... SELECT`` per block of :data:`SQL_BLOCK` messages; the block's CDR
  messages travel as one blob (every message of a topic has the same size) cut by ``substr``
  and its bag times as one JSON array read by ``json_each``, so sqlite does the per-row work
  in C. Same schema, same rows in the same order, same ``metadata.yaml`` (rosbags' writer still
  creates and closes the bag).
* MCAP: the message records (opcode, length, channel, sequence 0, log and publish time, CDR)
  are laid out one chunk at a time in a numpy byte matrix (Imu messages written field by field over
  a template message); a chunk that a block fills from its first message on goes straight to the
  file with its message index, the rest through rosbags' pending chunk. Chunks are closed at
  exactly the message where rosbags would close them (past :data:`MCAP_CHUNK_BYTES`). The file
  is byte-identical to rosbags' own.

See ``docs/scale.md``.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
import functools
import io
import sqlite3
import struct
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .storage import describe
from .writer import ImuBagWriter
from ..errors import BagError, OutputError
from ..msgs import (
    encode_imu_rows,
    encode_temperature_rows,
    IMU_TAIL_F8,
    split_stamps,
    TEMPERATURE_MSGTYPE,
    typestore,
)
from ..msgs.imu_rows import RowEncoder

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2.storage_mcap import McapWriter

#: ``build(a, b)``: the records of messages a to b - 1 as a C-contiguous (b - a, record) matrix.
RecordBuilder = Callable[[int, int], np.ndarray]

#: Messages per ``INSERT ... SELECT`` statement (blocks of a few MB; measured best near 10k).
SQL_BLOCK = 8192
#: rosbags closes an MCAP chunk after the message that takes it past this size (bytes).
MCAP_CHUNK_BYTES = 1 << 20
_MCAP_MESSAGE_HEAD = 1 + 8 + 2 + 4 + 8 + 8


class BulkImuBagWriter(ImuBagWriter):
    """
    :class:`ImuBagWriter` that writes blocks of messages at once (same bag, byte for byte).

    Parameters and attributes are those of :class:`ImuBagWriter`. On a rosbags version whose
    sqlite3 or MCAP writer layout is not the one recognised here, messages take the per-message
    path of :class:`ImuBagWriter`.
    """

    def _bulk_cursor(self, conn: Connection) -> sqlite3.Cursor | None:
        """Return the sqlite3 cursor if the rosbags layout allows the block insert, else None."""
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        storage: Any = writer.storage  # rosbags' storage writer, probed by name and attribute
        if (type(storage).__name__ == 'Sqlite3Writer' and hasattr(storage, 'cursor')
                and conn.id in getattr(writer, 'counts', {}) and hasattr(writer, 'min_timestamp')):
            return storage.cursor
        return None

    def _mcap_storage(self, conn: Connection) -> McapWriter | None:
        """Return rosbags' McapWriter if its layout allows the block write, else None."""
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        storage: Any = writer.storage  # rosbags' storage writer, probed by name and attribute
        chunk = getattr(storage, 'chunk', None)
        # No compression, or chunk compression (rosbag2's 'storage' mode: the chunk closer runs
        # the storage's compressor); per-message compression goes through rosbags' write.
        if (type(storage).__name__ != 'McapWriter'
                or getattr(storage, 'compression', None) not in ('', 'zstd')
                or not callable(getattr(storage, 'compressor', None))
                or not all(hasattr(chunk, name) for name in ('bio', 'msgs', 'message_start_time'))
                or conn.id not in getattr(storage, 'channel_stats', {})
                or conn.id not in getattr(writer, 'counts', {})
                or getattr(writer, 'compression_mode', None) is None
                or writer.compression_mode.name not in ('NONE', 'STORAGE')):
            return None
        if getattr(storage, '_gyro_noise_bulk', False) is False:
            storage.close_chunk = _McapChunkCloser(storage)
            storage._gyro_noise_bulk = True
        return storage

    def _write_mcap_rows(self, conn: Connection, log_ns: np.ndarray, rows: np.ndarray) -> None:
        n, size = rows.shape
        times = np.ascontiguousarray(log_ns, dtype='<u8')
        records = np.empty((n, _MCAP_MESSAGE_HEAD + size), np.uint8)
        records[:, :_MCAP_MESSAGE_HEAD] = _mcap_record_head(conn.id, size)
        records[:, 15:23] = times.view(np.uint8).reshape(n, 8)
        records[:, 23:31] = records[:, 15:23]
        records[:, _MCAP_MESSAGE_HEAD:] = rows
        self._write_mcap_records(conn, times, records.shape[1], lambda a, b: records[a:b])

    def _write_mcap_records(self, conn: Connection, times: np.ndarray, rec: int,
                            build: RecordBuilder) -> None:
        """
        Append MCAP message records to the chunks.

        ``times`` are the log times, ``rec`` the record size, ``build(a, b)`` returns the records
        of messages a to b - 1 as a C-contiguous (b - a, rec) byte matrix. Records are built one
        chunk at a time (they are written while in the CPU cache). A chunk that this call fills
        from its first message on goes to the file straight from its records (same bytes as
        rosbags' pending chunk closed by :class:`_McapChunkCloser`); the rest goes through
        rosbags' pending chunk as rosbags' ``write`` would.
        """
        writer = self._writer
        assert writer is not None  # _mcap_storage found it open
        # rosbags' McapWriter, its pending chunk's index lists holding numpy arrays too
        storage: Any = writer.storage
        n = times.shape[0]
        full = MCAP_CHUNK_BYTES // rec + 1  # messages that close a chunk begun empty
        done = 0
        try:
            while done < n:
                chunk = storage.chunk
                pos = chunk.bio.tell()
                if pos == 0 and n - done >= full:
                    part = times[done:done + full]
                    index = np.empty((full, 2), '<u8')
                    index[:, 0] = part
                    index[:, 1] = _offsets(rec, full)
                    data = build(done, done + full).data.cast('B')
                    _emit_chunk(storage, int(part.min()), int(part.max()), data,
                                {conn.id: [index]})
                    done += full
                    continue
                # rosbags closes the chunk after the first message that ends past the limit
                take = min(n - done, max(0, (MCAP_CHUNK_BYTES - pos) // rec) + 1)
                part = times[done:done + take]
                chunk.bio.write(build(done, done + take).data.cast('B'))
                index = np.empty((take, 2), '<u8')
                index[:, 0] = part
                index[:, 1] = pos + rec * np.arange(take, dtype=np.uint64)
                chunk.msgs[conn.id].append(index)
                chunk.message_start_time = min(chunk.message_start_time, int(part.min()))
                chunk.message_end_time = max(chunk.message_end_time, int(part.max()))
                done += take
                if chunk.bio.tell() > MCAP_CHUNK_BYTES:
                    storage.close_chunk()
        except Exception as err:  # noqa: BLE001 - disk full
            raise OutputError(f'bag {str(self.path)!r}: writing failed: {describe(err)}') from err
        first, last = int(times.min()), int(times.max())
        storage.message_start_time = min(storage.message_start_time, first)
        storage.message_end_time = max(storage.message_end_time, last)
        storage.channel_stats[conn.id] += n
        writer.counts[conn.id] += n
        writer.min_timestamp = min(writer.min_timestamp, first)
        writer.max_timestamp = max(writer.max_timestamp, last)

    def _write_rows(self, conn: Connection, log_ns: np.ndarray, rows: np.ndarray) -> None:
        if rows.shape[0] == 0:
            return
        if self._mcap_storage(conn) is not None:
            self._write_mcap_rows(conn, log_ns, rows)
            return
        cursor = self._bulk_cursor(conn)
        if cursor is None:
            blob = rows.tobytes()
            size = rows.shape[1]
            self._write(conn, log_ns, [blob[i:i + size] for i in range(0, len(blob), size)])
            return
        writer = self._writer
        assert writer is not None  # _bulk_cursor found it open
        size = int(rows.shape[1])
        sql = (f'INSERT INTO messages (topic_id, timestamp, data) SELECT {int(conn.id)}, value, '
               f'substr(?1, key * {size} + 1, {size}) FROM json_each(?2)')
        flat = np.ascontiguousarray(rows).data.cast('B')
        times = log_ns.tolist()
        try:
            for start in range(0, rows.shape[0], SQL_BLOCK):
                part = times[start:start + SQL_BLOCK]
                cursor.execute(sql, (flat[start * size:(start + len(part)) * size],
                                     '[' + ','.join(map(str, part)) + ']'))
        except Exception as err:  # noqa: BLE001 - disk full, sqlite errors
            raise OutputError(f'bag {str(self.path)!r}: writing failed: {describe(err)}') from err
        writer.counts[conn.id] += rows.shape[0]
        writer.min_timestamp = min(writer.min_timestamp, int(log_ns.min()))
        writer.max_timestamp = max(writer.max_timestamp, int(log_ns.max()))

    def write_imu(self, stamp_ns: ArrayLike, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, *,
                  angular_velocity_covariance: ArrayLike | None = None,
                  linear_acceleration_covariance: ArrayLike | None = None,
                  log_ns: ArrayLike | None = None, topic: str | None = None) -> None:
        """
        Append Imu messages (see :meth:`ImuBagWriter.write_imu`).

        Parameters
        ----------
        stamp_ns, gyro_rad_s, accel_m_s2 : array_like
            As in :meth:`ImuBagWriter.write_imu`.
        angular_velocity_covariance, linear_acceleration_covariance : array_like, optional
            As in :meth:`ImuBagWriter.write_imu`.
        log_ns, topic : optional
            As in :meth:`ImuBagWriter.write_imu`.

        """
        stamps, sec, nsec = split_stamps(stamp_ns, 'stamp_ns')
        conn = self._imu_conn
        if topic is not None and topic != self.imu_topic:
            conn = self._extra_imu(topic)
        logs = self._log_times(stamps, log_ns)
        build = None
        if stamps.shape[0] and self._mcap_storage(conn) is not None:
            build = _imu_records(conn.id, stamps, sec, nsec, logs, gyro_rad_s, accel_m_s2,
                                 self.frame_id, angular_velocity_covariance,
                                 linear_acceleration_covariance)
        if build is not None:
            self._write_mcap_records(conn, np.ascontiguousarray(logs, '<u8'), *build)
        else:
            rows = _imu_rows(stamps, gyro_rad_s, accel_m_s2, self.frame_id,
                             angular_velocity_covariance, linear_acceleration_covariance)
            self._write_rows(conn, logs, rows)
        if conn is self._imu_conn:
            self.imu_count += stamps.shape[0]

    def write_temperature(self, stamp_ns: ArrayLike, temperature_c: ArrayLike, *,
                          variance: ArrayLike = 0.0, log_ns: ArrayLike | None = None) -> None:
        """
        Append Temperature messages (see :meth:`ImuBagWriter.write_temperature`).

        Parameters
        ----------
        stamp_ns, temperature_c, variance, log_ns
            As in :meth:`ImuBagWriter.write_temperature`.

        """
        if self.temperature_topic is None or self._writer is None:
            super().write_temperature(stamp_ns, temperature_c, variance=variance, log_ns=log_ns)
            return
        stamps = split_stamps(stamp_ns, 'stamp_ns')[0]
        rows = encode_temperature_rows(stamps, temperature_c, frame_id=self.frame_id,
                                       variance=variance)
        logs = self._log_times(stamps, log_ns)
        if self._temperature_conn is None:
            try:
                self._temperature_conn = self._writer.add_connection(
                    self.temperature_topic, TEMPERATURE_MSGTYPE, typestore=typestore())
            except Exception as err:  # noqa: BLE001 - rosbags WriterError
                raise OutputError(
                    f'bag {str(self.path)!r}: cannot add {self.temperature_topic!r}: '
                    f'{describe(err)}') from err
        self._write_rows(self._temperature_conn, logs, rows)
        self.temperature_count += rows.shape[0]


def _imu_rows(stamps: np.ndarray, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, frame_id: str,
              av_cov: ArrayLike | None, la_cov: ArrayLike | None) -> np.ndarray:
    """
    Return :func:`encode_imu_rows` of the messages, faster when the covariances are shared.

    Shared covariances: :class:`~gyro_noise_ros.msgs.imu_rows.RowEncoder` (one message encoded in
    full, copied to every row, the stamps and the two vectors written in).
    """
    n = stamps.shape[0]
    gyro = np.asarray(gyro_rad_s, dtype=np.float64)
    accel = np.asarray(accel_m_s2, dtype=np.float64)
    shared = all(c is None or np.shape(c) in ((9,), (3, 3)) for c in (av_cov, la_cov))
    if n < 2 or not shared or gyro.shape != (n, 3) or accel.shape != (n, 3):
        return encode_imu_rows(stamps, gyro_rad_s, accel_m_s2, frame_id=frame_id,
                               angular_velocity_covariance=av_cov,
                               linear_acceleration_covariance=la_cov)
    return RowEncoder(frame_id, av_cov, la_cov).rows(stamps, gyro, accel)


@functools.lru_cache(maxsize=8)
def _offsets(rec: int, count: int) -> np.ndarray:
    """Return the chunk offsets of ``count`` records of ``rec`` bytes (uint64, read-only)."""
    out = rec * np.arange(count, dtype=np.uint64)
    out.flags.writeable = False
    return out


def _mcap_record_head(channel_id: int, size: int) -> np.ndarray:
    """Return the first 31 bytes of an MCAP message record (times zero) for a message size."""
    return np.frombuffer(struct.pack('<BQHIQQ', 0x05, _MCAP_MESSAGE_HEAD - 9 + size, channel_id,
                                     0, 0, 0), np.uint8)


def _imu_records(channel_id: int, stamps: np.ndarray, sec: np.ndarray, nsec: np.ndarray,
                 log_ns: np.ndarray, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike,
                 frame_id: str, av_cov: ArrayLike | None,
                 la_cov: ArrayLike | None) -> tuple[int, RecordBuilder] | None:
    """
    Return (record size, ``build``) for the MCAP message records of Imu messages, or None.

    ``build(a, b)`` returns the records of messages a to b - 1 as a (b - a, record) byte matrix:
    the bytes of :func:`_imu_rows` behind the record head of rosbags' ``write`` (opcode, length,
    channel, sequence 0, log and publish time). The first message's record is the template; it
    is copied once into every row of a buffer that each call reuses, and only the stamps, log
    times and the two vectors are written over it, field by field through a structured view of
    the buffer (64 of the ~355 bytes of a record), so
    the returned matrix is a view that the next call overwrites: the caller writes it out (or
    copies it) first. None when the messages do not share their covariances (the caller then
    takes the general path).
    """
    n = stamps.shape[0]
    gyro = np.asarray(gyro_rad_s, dtype=np.float64)
    accel = np.asarray(accel_m_s2, dtype=np.float64)
    shared = all(c is None or np.shape(c) in ((9,), (3, 3)) for c in (av_cov, la_cov))
    if not shared or gyro.shape != (n, 3) or accel.shape != (n, 3):
        return None
    first = RowEncoder(frame_id, av_cov, la_cov).template
    size = first.shape[0]
    vec = _MCAP_MESSAGE_HEAD + size - 8 * IMU_TAIL_F8
    template = np.concatenate((_mcap_record_head(channel_id, size), first))

    # Where the per-message fields lie in a record (the rest is the template). sec and nanosec
    # were range-checked by split_stamps, so their int32 / uint32 casts are exact.
    at_stamp, at_gyro, at_accel = _MCAP_MESSAGE_HEAD + 4, vec + 13 * 8, vec + 25 * 8
    layout = np.dtype({'names': ['log', 'publish', 'sec', 'nanosec', 'gyro', 'accel'],
                       'formats': ['<i8', '<i8', '<i4', '<u4', ('<f8', (3,)), ('<f8', (3,))],
                       'offsets': [15, 23, at_stamp, at_stamp + 4, at_gyro, at_accel],
                       'itemsize': template.size})
    reused: list[np.ndarray] = []

    def build(a: int, b: int) -> np.ndarray:
        if not reused or reused[0].shape[0] < b - a:
            reused[:] = [np.empty((b - a, template.size), np.uint8)]
            reused[0][...] = template
        records = reused[0][:b - a]
        fields = records.reshape(-1).view(layout)
        fields['log'] = log_ns[a:b]
        fields['publish'] = log_ns[a:b]
        fields['sec'] = sec[a:b]
        fields['nanosec'] = nsec[a:b]
        fields['gyro'] = gyro[a:b]
        fields['accel'] = accel[a:b]
        return records

    return template.size, build


def _emit_chunk(storage: McapWriter, start_time: int, end_time: int, data: memoryview,
                msgs: Mapping[int, Sequence[ArrayLike]]) -> None:
    """
    Write one MCAP chunk (compressed by the storage's compressor) with its message indexes.

    The bytes of rosbags' ``McapWriter.close_chunk``: chunk record, one message index record per
    channel (``msgs``: channel id -> list of (k, 2) (log time, offset) arrays or pairs, in write
    order), and the chunk index entry appended to ``storage.chunks``.
    """
    size = len(data)
    # rosbags declares its compressor bytes -> bytes; without compression it hands back the
    # buffer it is given, zstd takes any buffer
    compressed: bytes | memoryview = storage.compressor(data)  # type: ignore[arg-type]
    compressed_size = len(compressed)
    head = struct.pack('<QQQI', start_time, end_time, size, 0)
    body = head + _mcap_string(storage.compression) + struct.pack('<Q', compressed_size)
    chunk_start = storage.bio.tell()
    parts: list[bytes | memoryview] = [
        b'\x06' + struct.pack('<Q', len(body) + compressed_size) + body, compressed]
    chunk_end = chunk_start + len(parts[0]) + compressed_size
    offsets = []
    end = chunk_end
    for cid, entries in msgs.items():
        offsets.append((cid, end))
        pairs = [np.ascontiguousarray(e, dtype='<u8').reshape(-1, 2) for e in entries]
        index = (pairs[0] if len(pairs) == 1 else np.concatenate(
            pairs or [np.zeros((0, 2), '<u8')])).data.cast('B')
        parts.append(b'\x07' + struct.pack('<QHI', len(index) + 6, cid, len(index)))
        parts.append(index)
        end += len(parts[-2]) + len(index)
    for part in parts:
        storage.bio.write(part)
    rec = io.BytesIO()
    rec.write(struct.pack('<QQQQI', start_time, end_time, chunk_start, chunk_end - chunk_start,
                          len(offsets) * 10))
    for cid, offset in offsets:
        rec.write(struct.pack('<HQ', cid, offset))
    rec.write(struct.pack('<Q', end - chunk_end))
    rec.write(_mcap_string(storage.compression))
    rec.write(struct.pack('<QQ', compressed_size, size))
    storage.chunks.append(rec)


class _McapChunkCloser:
    """
    rosbags' ``McapWriter.close_chunk`` with the message index written from numpy.

    Same bytes as rosbags' loop (per channel: (log time, offset) pairs, in write order); the
    pending chunk's index lists hold (k, 2) uint64 arrays from the block writer or (time, offset)
    tuples from rosbags' own ``write``.
    """

    def __init__(self, storage: McapWriter) -> None:
        self.storage = storage

    def __call__(self) -> None:
        """Close the pending chunk: chunk record, message indexes, chunk index entry."""
        from rosbags.rosbag2.storage_mcap import PendingChunk

        storage = self.storage
        chunk = storage.chunk
        data = chunk.bio.getbuffer()  # a view, not a copy
        try:
            _emit_chunk(storage, chunk.message_start_time, chunk.message_end_time, data,
                        chunk.msgs)
        finally:
            data.release()
        storage.chunk = PendingChunk(2**63 - 1, 0, io.BytesIO(), defaultdict(list))


def _mcap_string(text: str) -> bytes:
    data = text.encode()
    return struct.pack('<I', len(data)) + data
