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
The MCAP record layout: the one walk of a file's records and of a chunk's (pure, numpy only).

An MCAP file is ``magic, records..., magic``; a record is ``opcode u8, length u64, body``. The
walk of a file without summary and footer (a killed writer) reads the data section's records by
their length fields up to the first record that runs past the end of the file (or a zero-filled
tail): :func:`walk_records` gives each complete Chunk record's head with the per-channel counts of
the MessageIndex records that follow it; :func:`walk_chunk` walks one decompressed chunk (its
Message, Schema and Channel records); :class:`McapTruncation` is what such a file turned out to
hold. The block reader (:mod:`.storage`) and the repair (:mod:`.repair`) read chunks through
:func:`read_mcap_chunk` and :func:`mcap_message_records`; the rosbags reader of a cut file
(:mod:`._recovering_mcap`) uses the walks. Offsets and sizes are in bytes, times in ns.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import struct
from typing import Any, BinaryIO, NamedTuple, TYPE_CHECKING

import numpy as np

from ..errors import BagError
from ..outputs import StrPath

if TYPE_CHECKING:
    from rosbags.rosbag2.storage_mcap import ChunkInfo

MCAP_MAGIC = b'\x89MCAP0\r\n'
_OP_FOOTER = 0x02
_OP_SCHEMA = 0x03
_OP_CHANNEL = 0x04
_OP_MESSAGE = 0x05
_OP_CHUNK = 0x06
_OP_MESSAGE_INDEX = 0x07
_OP_DATA_END = 0x0F
# Footer record: opcode, length (8), summary start (8), summary offset start (8), crc (4), magic.
_FOOTER_BYTES = 1 + 8 + 8 + 8 + 4 + 8
# Message record: opcode u8, record length u64, channel id u16, sequence u32, log time u64,
# publish time u64, then the payload.
_MESSAGE_HEAD = 1 + 8 + 2 + 4 + 8 + 8
_RECORD_HEAD = struct.Struct('<BQ')
_CHUNK_HEAD = struct.Struct('<QQQI')


def mcap_has_footer(path: StrPath) -> bool:
    """
    Tell whether an MCAP file ends with its footer and closing magic (a writer closed it).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    bool

    """
    try:
        with open(path, 'rb') as fh:
            size = fh.seek(0, 2)
            if size < len(MCAP_MAGIC) + _FOOTER_BYTES:
                return False
            fh.seek(size - _FOOTER_BYTES)
            tail = fh.read(_FOOTER_BYTES)
    except OSError:
        return True  # let the reader report the file as unreadable
    return tail[0] == _OP_FOOTER and tail.endswith(MCAP_MAGIC)


def mcap_message_records(
        chunk: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Locate the Message records of one decompressed MCAP chunk.

    Parameters
    ----------
    chunk : bytes
        The chunk's records.

    Returns
    -------
    starts, lengths, channel, log_ns : numpy.ndarray of int64, shape (n,)
        Payload offset and length, channel id and log time of each message, in chunk order.

    Raises
    ------
    BagError
        A record runs past the end of the chunk or is too short for a Message.

    """
    size = len(chunk)
    buf = np.frombuffer(chunk, np.uint8)
    if size >= 9 and chunk[0] == _OP_MESSAGE:
        stride = 9 + int.from_bytes(chunk[1:9], 'little')
        if stride >= _MESSAGE_HEAD and size % stride == 0:
            # A chunk of one topic with a fixed-size payload: every record is at a multiple of
            # the first one's size; checked on all records before it is believed.
            rec = buf.reshape(size // stride, stride)
            if (rec[:, 0] == _OP_MESSAGE).all() and (
                    np.ascontiguousarray(rec[:, 1:9]).view('<u8')[:, 0] == stride - 9).all():
                n = rec.shape[0]
                at = np.arange(n, dtype=np.int64) * stride + _MESSAGE_HEAD
                cid = np.ascontiguousarray(rec[:, 9:11]).view('<u2')[:, 0].astype(np.int64)
                log = np.ascontiguousarray(rec[:, 15:23]).view('<u8')[:, 0].astype(np.int64)
                return at, np.full(n, stride - _MESSAGE_HEAD, np.int64), cid, log
    head = _RECORD_HEAD.unpack_from
    msg_head = struct.Struct('<HIQ').unpack_from
    starts: list[int] = []
    lengths: list[int] = []
    channel: list[int] = []
    log_ns: list[int] = []
    pos = 0
    while pos < size:
        if pos + 9 > size:
            raise BagError(f'MCAP chunk record at byte {pos} is cut off')
        op, length = head(chunk, pos)
        end = pos + 9 + length
        if end > size:
            raise BagError(
                f'MCAP chunk record at byte {pos} claims {length} bytes beyond the chunk')
        if op == _OP_MESSAGE:
            if length < _MESSAGE_HEAD - 9:
                raise BagError(f'MCAP message record at byte {pos} is too short ({length} bytes)')
            cid, _, log = msg_head(chunk, pos + 9)
            starts.append(pos + _MESSAGE_HEAD)
            lengths.append(length - (_MESSAGE_HEAD - 9))
            channel.append(cid)
            log_ns.append(log)
        pos = end
    return (np.array(starts, np.int64), np.array(lengths, np.int64), np.array(channel, np.int64),
            np.array(log_ns, np.uint64).astype(np.int64))


def read_mcap_chunk(fh: BinaryIO, info: ChunkInfo) -> bytes:
    """
    Read, decompress and CRC-check one MCAP chunk with rosbags' ``decompress``.

    Parameters
    ----------
    fh : BinaryIO
        The MCAP file, opened for binary reading.
    info : rosbags.rosbag2.storage_mcap.ChunkInfo
        The chunk's index entry.

    Returns
    -------
    bytes
        The chunk's records.

    Raises
    ------
    BagError
        The chunk is cut off by the end of the file (rosbags raises its own errors on a bad
        compression or checksum).

    """
    from rosbags.rosbag2.storage_mcap import decompress

    # Chunk record: opcode, length, start, end, uncompressed size (8 each), crc (4),
    # compression string (4 + len), compressed size (8), records.
    fh.seek(info.chunk_start_offset + 9 + 24)
    crc = int.from_bytes(fh.read(4), 'little')
    fh.seek(info.chunk_start_offset + 9 + 40 + len(info.compression))
    data = fh.read(info.compressed_size)
    if len(data) != info.compressed_size:
        raise BagError(f'MCAP chunk at byte {info.chunk_start_offset} is cut off')
    return decompress(data, info.compression, info.uncompressed_size, crc)


@dataclass(frozen=True)
class McapTruncation:
    """
    What the walk of an MCAP file without footer found.

    Attributes
    ----------
    messages : int
        Messages in the readable chunks (all channels).
    chunks : int
        Readable chunks.
    readable_bytes : int
        Offset of the first byte not read (the cut record, or the end of the data section).
    file_bytes : int
        Size of the file.
    start_ns, end_ns : int
        Log time of the first and last readable message (0 when there is none).
    stop_reason : str
        Why the walk stopped: ``'end of file'``, ``'record cut by the end of the file'``,
        ``'zero-filled tail'``, ``'end of data section'``, or an unreadable chunk.

    """

    messages: int
    chunks: int
    readable_bytes: int
    file_bytes: int
    start_ns: int
    end_ns: int
    stop_reason: str

    @property
    def lost_bytes(self) -> int:
        """int: Bytes after the readable part (an unfinished chunk, a cut summary)."""
        return self.file_bytes - self.readable_bytes

    @property
    def span_s(self) -> float:
        """float: Log time from the first to the last readable message (s)."""
        return (self.end_ns - self.start_ns) / 1e9 if self.messages else 0.0


#: What :func:`walk_chunk` finds: (schemas, channels, counts, start_ns, end_ns).
ChunkWalk = tuple[dict[int, bytes], dict[int, bytes], dict[int, int], int | None, int | None]


def walk_chunk(raw: bytes) -> ChunkWalk:
    """
    Walk one decompressed chunk: its Schema, Channel and Message records.

    Parameters
    ----------
    raw : bytes
        The chunk's records.

    Returns
    -------
    ChunkWalk
        Schema and Channel record bodies by id, messages per channel id, and the log time of the
        first and last message (None without messages).

    Raises
    ------
    BagError
        A record runs past the end of the chunk.

    """
    starts, lengths, channel, log_ns = mcap_message_records(raw)
    counts = {int(c): int(k) for c, k in zip(*np.unique(channel, return_counts=True))}
    start = int(log_ns.min()) if log_ns.size else None
    end = int(log_ns.max()) if log_ns.size else None
    schemas: dict[int, bytes] = {}
    channels: dict[int, bytes] = {}
    if int(lengths.sum()) + _MESSAGE_HEAD * lengths.shape[0] != len(raw):
        # Not only Message records: find the Schema and Channel records (walk already validated).
        pos, size = 0, len(raw)
        while pos < size:
            op, length = _RECORD_HEAD.unpack_from(raw, pos)
            body = raw[pos + 9:pos + 9 + length]
            if op == _OP_SCHEMA and length >= 2:
                schemas[struct.unpack_from('<H', body)[0]] = body
            elif op == _OP_CHANNEL and length >= 2:
                channels[struct.unpack_from('<H', body)[0]] = body
            pos += 9 + length
    return schemas, channels, counts, start, end


class RecordWalk(NamedTuple):
    """
    What :func:`walk_records` found.

    Attributes
    ----------
    heads : list of (dict, bool)
        Each complete Chunk record's head (times, offsets, compression, sizes, crc, per-channel
        counts and MessageIndex offsets) and whether its MessageIndex records are complete
        (another record follows them).
    stop : int
        Offset of the first record not read.
    reason : str
        Why the walk stopped (:class:`McapTruncation` ``stop_reason``).
    top_messages : int
        Message records outside chunks.

    """

    heads: list[tuple[dict[str, Any], bool]]
    stop: int
    reason: str
    top_messages: int


def _chunk_head(bio: BinaryIO, pos: int, length: int) -> dict[str, Any] | None:
    """Return the head of the Chunk record at ``pos`` (``length``: its body), None if malformed."""
    if length < 40:
        return None
    fields = bio.read(min(length, 40 + 255))
    start_t, end_t, usize, crc = _CHUNK_HEAD.unpack_from(fields)
    (clen,) = struct.unpack_from('<I', fields, 28)
    if 40 + clen > len(fields):
        return None
    compression = fields[32:32 + clen].decode('utf-8', 'replace')
    (csize,) = struct.unpack_from('<Q', fields, 32 + clen)
    if 40 + clen + csize > length:
        return None
    return {'start': start_t, 'end': end_t, 'offset': pos, 'length': 9 + length,
            'data_offset': pos + 9 + 40 + clen, 'compression': compression,
            'compressed_size': csize, 'uncompressed_size': usize, 'crc': crc,
            'counts': {}, 'index_offsets': {}, 'index_length': 0}


def walk_records(bio: BinaryIO, pos: int, size: int, *, on_schema: Callable[[bytes], None],
                 on_channel: Callable[[bytes], None]) -> RecordWalk:
    """
    Walk the data section's records by their length fields, from ``pos`` up to the first cut.

    Parameters
    ----------
    bio : BinaryIO
        The MCAP file, opened for binary reading.
    pos : int
        Offset of the first data record (after the header).
    size : int
        Size of the file (bytes).
    on_schema, on_channel : callable, keyword-only
        Called with the body of each Schema and Channel record outside chunks, in file order.

    Returns
    -------
    RecordWalk

    """
    heads: list[tuple[dict[str, Any], bool]] = []
    head: dict[str, Any] | None = None
    reason, top_messages = 'end of file', 0
    while True:
        if pos + 9 > size:
            reason = 'record cut by the end of the file' if pos < size else reason
            break
        bio.seek(pos)
        op, length = _RECORD_HEAD.unpack(bio.read(9))
        end = pos + 9 + length
        if op == 0:
            reason = 'zero-filled tail'
            break
        if end > size:
            reason = 'record cut by the end of the file'
            break
        if op == _OP_MESSAGE_INDEX and head is not None and length >= 6:
            cid, nbytes = struct.unpack('<HI', bio.read(6))
            head['counts'][cid] = nbytes // 16
            head['index_offsets'][cid] = pos
            head['index_length'] += 9 + length
            pos = end
            continue
        if head is not None:
            heads.append((head, True))
            head = None
        if op in (_OP_DATA_END, _OP_FOOTER):
            reason = 'end of data section'
            break
        if op == _OP_CHUNK:
            head = _chunk_head(bio, pos, length)
            if head is None:
                reason = f'malformed chunk record at byte {pos}'
                break
        elif op == _OP_SCHEMA:
            on_schema(bio.read(length))
        elif op == _OP_CHANNEL:
            on_channel(bio.read(length))
        elif op == _OP_MESSAGE:
            top_messages += 1
        pos = end
    if head is not None:
        heads.append((head, False))  # the last chunk: its index may be cut
    return RecordWalk(heads, pos, reason, top_messages)
