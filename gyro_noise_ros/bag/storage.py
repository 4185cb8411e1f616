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
Opening bags of every supported format and streaming one topic's raw messages in blocks.

rosbags does the parsing of metadata, indexes and connections. The message stream is read here in
blocks instead of one Python tuple per message: sqlite3 through the storage's own database
connection, MCAP and ROS 1 by decompressing each indexed chunk and locating its message records
with numpy. The order is the one rosbags' ``Reader.messages`` yields (receive time, ties in
recording order); where that order cannot be guaranteed cheaply (chunks overlapping in time, an
MCAP file without chunk index, per-message compression), rosbags' own iterator is used.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
import itertools
import logging
import operator
from pathlib import Path
from typing import cast, TYPE_CHECKING, Union

import numpy as np

from .mcap_records import mcap_message_records, read_mcap_chunk
from .recover import (journal_is_hot, recovering_reader_class, rollback_note, rolled_back_copy,
                      truncation_note)
from ..errors import BagError
from ..msgs import join_raws
from ..outputs import StrPath

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag1 import Reader as Ros1Reader
    from rosbags.rosbag2 import Reader as Rosbag2Reader
    from rosbags.rosbag2.reader import ReaderProtocol
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

#: One block of a topic's messages: (buf, starts, lengths, log_ns), see :meth:`BagSource.blocks`.
Block = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
#: A reader whose ``messages(connections)`` yields (connection, log time, raw) in bag order.
MessageReader = Union['Rosbag2Reader', 'Ros1Reader', 'ReaderProtocol']

STORAGES = ('sqlite3', 'mcap')
BLOCK = 16384

_MAGIC = {
    b'#ROSBAG V2.0': 'ros1',
    b'\x89MCAP0\r\n': 'mcap',
    b'SQLite format 3\x00': 'sqlite3',
}
_SUFFIX = {'.bag': 'ros1', '.mcap': 'mcap', '.db3': 'sqlite3'}
_log = logging.getLogger(__name__)


def _sniff(path: Path) -> str | None:
    try:
        with open(path, 'rb') as fh:
            head = fh.read(16)
    except OSError as err:
        raise BagError(f'bag file {str(path)!r} cannot be read: {err.strerror or err}') from err
    for magic, kind in _MAGIC.items():
        if head.startswith(magic):
            return kind
    return None


def describe(err: BaseException) -> str:
    """First line of an exception's message, without a trailing period."""
    text = str(err).strip().rstrip('.') or type(err).__name__
    return text.splitlines()[0]


def _metadata_storage(meta: Path) -> str:
    """``storage_identifier`` of a rosbag2 ``metadata.yaml`` ('rosbag2' if it cannot be read)."""
    import yaml

    try:
        info = yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
        kind = str(info['storage_identifier'])
    except Exception:  # noqa: BLE001 - rosbags reports what is wrong with the file when opening it
        return 'rosbag2'
    return kind if kind in STORAGES else 'rosbag2'


def _resolve(path: Path) -> tuple[Path, str, list[str]]:
    """
    Return (path to hand to rosbags, storage kind, notes) or raise BagError.

    ``notes`` are the sentences to say about a recording that is read although its writer did
    not finish it (no ``metadata.yaml``; an sqlite3 file read through a rolled-back copy).
    """
    if path.is_dir():
        files = sorted(path.glob('*.db3')) + sorted(path.glob('*.mcap'))
        if (path / 'metadata.yaml').exists():
            # rosbags validates the metadata and its files (which may be zstd-compressed); only
            # the storage kind is needed here.
            return path, _metadata_storage(path / 'metadata.yaml'), []
        if len(files) == 1:
            # A recording whose writer died before writing metadata.yaml: read the storage file.
            target, kind, notes = _resolve(files[0])
            if not notes and kind != 'mcap':
                notes = [f'bag {str(path)!r} has no metadata.yaml (its writer did not finish): '
                         f'reading its storage file {files[0].name}; `gyro_noise_record repair '
                         f'{path}` writes a complete bag']
            return target, kind, notes
        detail = ' and several storage files' if files else ''
        raise BagError(f'directory {str(path)!r} is not a rosbag2 bag (no metadata.yaml{detail})')
    if path.name == 'metadata.yaml':
        return _resolve(path.parent)
    sniffed = _sniff(path)
    if sniffed is None:
        raise BagError(
            f'file {str(path)!r} is not a bag (expected a rosbag2 directory, a .db3 or .mcap '
            'file, or a ROS 1 .bag file)')
    kind = sniffed
    if _SUFFIX.get(path.suffix) != kind:
        raise BagError(f'file {str(path)!r} holds {kind} data but its suffix is {path.suffix!r}; '
                       f'rename it to end in {dict(zip(_SUFFIX.values(), _SUFFIX))[kind]}')
    if kind == 'sqlite3' and journal_is_hot(path):
        # A writer died mid-transaction; rosbags opens the file immutable and would ignore the
        # rollback journal, reading half-written pages.
        return rolled_back_copy(path), kind, [rollback_note(_bag_name(path), path)]
    return path, kind, []


def _bag_name(path: Path) -> Path:
    """Name the bag as a user does: its folder when the file is its only storage file."""
    parent = path.parent
    if not (parent / 'metadata.yaml').exists() and [
            p for p in parent.iterdir() if p.suffix in _SUFFIX] == [path]:
        return parent
    return path


def _ros1_header(chunk: bytes, start: int, stop: int) -> dict[bytes, tuple[int, bytes]]:
    """Fields of a ROS 1 record header as {name: (value offset, value bytes)}."""
    fields: dict[bytes, tuple[int, bytes]] = {}
    pos = start
    while pos < stop:
        if pos + 4 > stop:
            raise BagError(f'ROS 1 record header at byte {start} is cut off')
        flen = int.from_bytes(chunk[pos:pos + 4], 'little')
        field = chunk[pos + 4:pos + 4 + flen]
        if pos + 4 + flen > stop or b'=' not in field:
            raise BagError(f'ROS 1 record header at byte {start} holds a malformed field')
        name, _, value = field.partition(b'=')
        fields[name] = (pos + 4 + len(name) + 1, value)
        pos += 4 + flen
    return fields


def ros1_message_records(chunk: bytes) -> tuple[np.ndarray, ...]:
    """
    Locate the message data records (op 0x02) of one decompressed ROS 1 chunk.

    A record is ``uint32 header length, header fields (uint32 length, name=value), uint32 data
    length, data``; a message record's header carries ``op``, ``conn`` (uint32) and ``time``
    (uint32 sec, uint32 nsec).

    Parameters
    ----------
    chunk : bytes
        The chunk's records.

    Returns
    -------
    starts, lengths, conn, time_ns : numpy.ndarray of int64, shape (n,)
        Data offset and length, connection id and time of each message, in chunk order.

    Raises
    ------
    BagError
        A record runs past the end of the chunk or its header is malformed.

    """
    size = len(chunk)
    starts: list[int] = []
    lengths: list[int] = []
    conns: list[int] = []
    times: list[int] = []
    tail = None
    pos = 0
    tries = 3  # the layout check costs a pass over the rest of the chunk: bounded per chunk
    while pos < size:
        if pos + 4 > size:
            raise BagError(f'ROS 1 record at byte {pos} is cut off')
        hlen = int.from_bytes(chunk[pos:pos + 4], 'little')
        hend = pos + 4 + hlen
        if hend + 4 > size:
            raise BagError(f'ROS 1 record at byte {pos} claims a header beyond the chunk')
        dlen = int.from_bytes(chunk[hend:hend + 4], 'little')
        dend = hend + 4 + dlen
        if dend > size:
            raise BagError(f'ROS 1 record at byte {pos} claims data beyond the chunk')
        fields = _ros1_header(chunk, pos + 4, hend)
        if fields.get(b'op', (0, b''))[1] != b'\x02':
            pos = dend
            continue
        conn, time = fields.get(b'conn'), fields.get(b'time')
        if conn is None or time is None or len(conn[1]) != 4 or len(time[1]) != 8:
            raise BagError(f'ROS 1 message record at byte {pos} lacks a valid conn or time field')
        stride = dend - pos
        rest = size - pos
        if tries and rest % stride == 0 and rest // stride > 1:
            tries -= 1
            tail = _ros1_uniform_tail(chunk, pos, stride, hend + 4 - pos, conn[0] - pos, time[0]
                                      - pos)
            if tail is not None:
                break
        starts.append(hend + 4)
        lengths.append(dlen)
        conns.append(int.from_bytes(conn[1], 'little'))
        times.append(int.from_bytes(time[1][:4], 'little') * 1_000_000_000
                     + int.from_bytes(time[1][4:], 'little'))
        pos = dend
    out = tuple(np.array(col, np.int64) for col in (starts, lengths, conns, times))
    if tail is not None:
        out = tuple(np.concatenate(pair) for pair in zip(out, tail))
    return out


def _ros1_uniform_tail(chunk: bytes, pos: int, stride: int, head: int, c_at: int,
                       t_at: int) -> Block | None:
    """
    Columns of the records from ``pos`` to the chunk's end if they all share one layout, else None.

    The rest of a chunk is often one topic's fixed-size messages: believed only if every record's
    header bytes equal the first one's apart from the conn and time values.
    """
    rest = len(chunk) - pos
    rec = np.frombuffer(chunk, np.uint8, offset=pos).reshape(rest // stride, stride)
    mask = np.ones(head, bool)
    mask[c_at:c_at + 4] = False
    mask[t_at:t_at + 8] = False
    heads = rec[:, :head]
    if not (heads[:, mask] == heads[0, mask]).all():
        return None
    n = rec.shape[0]
    starts = pos + head + np.arange(n, dtype=np.int64) * stride
    lengths = np.full(n, stride - head, np.int64)
    conns = np.ascontiguousarray(rec[:, c_at:c_at + 4]).view('<u4')[:, 0].astype(np.int64)
    tt = np.ascontiguousarray(rec[:, t_at:t_at + 8]).view('<u4').astype(np.int64)
    return starts, lengths, conns, tt[:, 0] * 1_000_000_000 + tt[:, 1]


class BagSource:
    """
    A rosbags reader on any supported path, its storage kind and a block-wise message stream.

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory, ``metadata.yaml``, ``.db3`` or ``.mcap`` file, or ROS 1 ``.bag`` file.
    fast : bool
        Use the block readers where they apply (False: rosbags' iterator everywhere; for tests).

    Raises
    ------
    BagError
        Missing path, not a bag, or rosbags cannot open it.

    """

    def __init__(self, path: StrPath, *, fast: bool = True) -> None:
        self.path = Path(path)
        self.fast = fast
        if not self.path.exists():
            raise BagError(f'bag path {str(self.path)!r} does not exist')
        target, self.storage, notes = _resolve(self.path)
        self.ros1 = self.storage == 'ros1'
        #: rosbags' rosbag2 Reader, or its ROS 1 Reader (``ros1``); None once closed.
        self.reader: Rosbag2Reader | Ros1Reader | None = None
        Reader: type[Rosbag2Reader | Ros1Reader]
        try:
            if self.ros1:
                # rosbags' reader keeps an index entry per message (about 150 B each); the block
                # reader needs only the chunk list
                Reader = _lean_ros1_reader_class() if fast else _full_ros1_reader_class()
            else:
                # rosbags' Reader, and a bare MCAP file without footer read by its chunks
                Reader = recovering_reader_class()
            reader = Reader(target)
            reader.open()
            self.reader = reader
            self.connections = list(reader.connections)
        except BagError:
            raise
        # rosbags/apsw/zstd raise many types on corrupt files
        except Exception as err:  # noqa: BLE001
            raise BagError(f'bag {str(self.path)!r} cannot be opened as {self.storage} '
                           f'(corrupt or truncated?): {describe(err)}') from err
        truncation = getattr(getattr(reader, 'storage', None), 'truncation', None)
        #: McapTruncation of an MCAP file without footer, else None.
        self.truncation = truncation
        if truncation is not None:
            if truncation.messages == 0:
                reader.close()
                raise BagError(f'bag {str(self.path)!r} is a truncated MCAP with nothing to '
                               f'recover: no complete chunk before the cut '
                               f'({truncation.stop_reason})')
            notes = [truncation_note(self.path, truncation)]
        #: The one-line note on a recording read although its writer did not finish it, or None.
        self.recovery = notes[0] if notes else None
        if self.recovery:
            # the caller's logging configuration decides where it goes (the tools: one line on
            # stderr, once per run; cli/_common.py)
            _log.warning(self.recovery)

    def topics(self) -> dict[str, tuple[str | None, int]]:
        """Return ``{name: (msgtype or None, count)}`` merged over connections."""
        out: dict[str, tuple[str | None, int]] = {}
        for conn in self.connections:
            if self.ros1:
                count = sum(int(c.connection_counts.get(conn.id, 0))
                            for c in self._ros1_reader().chunk_infos)
            else:
                count = int(conn.msgcount or 0)
            if conn.topic in out:
                msgtype, total = out[conn.topic]
                out[conn.topic] = (msgtype if msgtype == conn.msgtype else None, total + count)
            else:
                out[conn.topic] = (conn.msgtype, count)
        return out

    def duration_s(self) -> float:
        """Span of the whole bag in s, first to last message (receive time)."""
        try:
            duration = int(self._open_reader().duration)
        except Exception:  # noqa: BLE001 - an empty bag has no meaningful duration
            return 0.0
        if duration > 0:
            duration -= 1  # rosbags reports the end time as last message + 1 ns, in every format
        return max(duration, 0) / 1e9

    def blocks(self, topic: str, block: int = BLOCK) -> Iterator[Block]:
        """
        Yield one topic's messages as ``(buf, starts, lengths, log_ns)`` blocks in bag order.

        Raises
        ------
        BagError
            The storage turns out corrupt or truncated.

        """
        delivered = 0
        try:
            for item in self._blocks(topic, block):
                delivered += item[1].shape[0]
                yield item
        except BagError as err:
            raise BagError(
                f'bag {str(self.path)!r} is corrupt after {delivered} messages on {topic!r}: '
                f'{err}') from err
        except Exception as err:  # noqa: BLE001 - corrupt/truncated storage surfaces mid-stream
            raise BagError(
                f'bag {str(self.path)!r} is corrupt or truncated after {delivered} messages on '
                f'{topic!r}: {describe(err)}') from err

    def _open_reader(self) -> Rosbag2Reader | Ros1Reader:
        """Return the rosbags reader, open until :meth:`close`."""
        assert self.reader is not None, f'bag {str(self.path)!r} was closed'
        return self.reader

    def _rosbag2_reader(self) -> Rosbag2Reader:
        """Return the open rosbags rosbag2 reader (``ros1`` False)."""
        from rosbags.rosbag2 import Reader

        reader = self._open_reader()
        assert isinstance(reader, Reader), 'a ROS 1 bag has no rosbag2 storage'
        return reader

    def _ros1_reader(self) -> Ros1Reader:
        """Return the open rosbags ROS 1 reader (``ros1`` True)."""
        from rosbags.rosbag1 import Reader

        reader = self._open_reader()
        assert isinstance(reader, Reader), 'not a ROS 1 bag'
        return reader

    def _storages(self) -> list[ReaderProtocol] | None:
        """rosbag2 storage readers in reading order, or None when the fast paths do not apply."""
        from rosbags.rosbag2.reader import DirectoryReader

        inner = self._rosbag2_reader().storage
        if isinstance(inner, DirectoryReader):
            if inner.metadata.compression_mode == 'message':
                return None
            return list(inner.storages)
        return [inner]

    def _blocks(self, topic: str, block: int) -> Iterator[Block]:
        conns = [c for c in self.connections if c.topic == topic]
        if self.ros1 and self.fast:
            yield from self._ros1_blocks(conns, block)
            return
        storages = None if (self.ros1 or not self.fast) else self._storages()
        if storages is None:
            yield from self._generic_blocks(self._open_reader(), conns, block)
            return
        for storage in storages:
            conns = [c for c in storage.connections if c.topic == topic]
            if not conns:
                continue
            # the storage kind names the rosbags storage reader class
            if self.storage == 'sqlite3':
                yield from self._sqlite_blocks(cast('Sqlite3Reader', storage), conns, block)
            else:
                yield from self._mcap_blocks(cast('McapReader', storage), conns, block)

    @staticmethod
    def _generic_blocks(reader: MessageReader, conns: Sequence[Connection],
                        block: int) -> Iterator[Block]:
        stream = reader.messages(connections=conns)
        while chunk := list(itertools.islice(stream, block)):
            _, log_ns, raws = zip(*chunk)
            del chunk
            buf, starts, lengths = join_raws(raws)
            yield buf, starts, lengths, np.fromiter(log_ns, np.int64, len(log_ns))

    @staticmethod
    def _sqlite_blocks(storage: Sqlite3Reader, conns: Sequence[Connection],
                       block: int) -> Iterator[Block]:
        ids = sorted({c.id for c in conns})
        # Same rows and order as rosbags' Sqlite3Reader.messages (timestamp order, served by the
        # timestamp index); rowid breaks ties in recording order.
        query = (
            f'SELECT timestamp, data FROM messages WHERE topic_id IN ({",".join("?" * len(ids))}) '
            'ORDER BY timestamp, id')
        dbconn = storage.dbconn
        assert dbconn is not None  # an open storage
        cursor = dbconn.execute(query, ids)
        stamp_of, data_of = operator.itemgetter(0), operator.itemgetter(1)
        while rows := list(itertools.islice(cursor, block)):
            # itemgetter maps: a third less CPU than zip(*rows) on millions of rows
            log_ns = np.fromiter(map(stamp_of, rows), np.int64, len(rows))
            raws = list(map(data_of, rows))
            del rows
            buf, starts, lengths = join_raws(raws)
            yield buf, starts, lengths, log_ns

    def _mcap_blocks(self, storage: McapReader, conns: Sequence[Connection],
                     block: int) -> Iterator[Block]:
        ids = np.array(sorted({c.id for c in conns}), np.int64)
        chunks = sorted(
            (c for c in storage.chunks if any(c.channel_count.get(int(i), 0) for i in ids)),
            key=lambda c: (c.message_start_time, c.chunk_start_offset))
        ordered = all(b.message_start_time > a.message_end_time
                      or (b.message_start_time == a.message_end_time and b.chunk_start_offset
                          > a.chunk_start_offset) for a, b in itertools.pairwise(chunks))
        if not storage.chunks or not ordered:
            # No chunk index, or chunks interleaved in time: rosbags merges them message by
            # message.
            yield from self._generic_blocks(storage, conns, block)
            return
        with open(cast(Path, storage.path), 'rb') as fh:
            for info in chunks:
                raw = read_mcap_chunk(fh, info)
                starts, lengths, channel, log_ns = mcap_message_records(raw)
                sel = np.flatnonzero(np.isin(channel, ids))
                if sel.size == 0:
                    continue
                # rosbags yields a chunk's messages sorted by log time, stably.
                sel = sel[np.argsort(log_ns[sel], kind='stable')]
                buf = np.frombuffer(raw, np.uint8)
                for i in range(0, sel.size, block):
                    part = sel[i:i + block]
                    yield buf, starts[part], lengths[part], log_ns[part]

    def _ros1_blocks(self, conns: Sequence[Connection], block: int) -> Iterator[Block]:
        reader = self._ros1_reader()
        ids = np.array(sorted({c.id for c in conns}), np.int64)
        infos = sorted(
            (
                c
                for c in reader.chunk_infos
                if any(c.connection_counts.get(int(i), 0) for i in ids)
            ),
            key=lambda c: (c.start_time, c.pos),
        )
        # rosbags orders by (time, chunk position, offset) and reports end_time as last + 1 ns.
        ordered = all(b.start_time >= a.end_time or (b.start_time == a.end_time - 1 and b.pos
                                                     > a.pos) for a,
                      b in itertools.pairwise(infos))
        if not ordered:
            # chunks overlap in time: only rosbags' per-message index gives its merge order
            full = self._full_ros1_reader()
            try:
                yield from self._generic_blocks(full, [c for c in full.connections if c.topic in
                                                       {k.topic for k in conns}], block)
            finally:
                full.close()
            return
        with open(cast(Path, reader.path), 'rb') as fh:
            for info in infos:
                chunk = reader.chunks[info.pos]
                fh.seek(chunk.datapos)
                data = fh.read(chunk.datasize)
                if len(data) != chunk.datasize:
                    raise BagError(f'ROS 1 chunk at byte {info.pos} is cut off')
                raw = chunk.decompressor(data)
                del data
                starts, lengths, conn, time_ns = ros1_message_records(raw)
                sel = np.flatnonzero(np.isin(conn, ids))
                indexed = sum(info.connection_counts.get(int(i), 0) for i in ids)
                if sel.size != indexed:
                    raise BagError(
                        f'ROS 1 chunk at byte {info.pos} holds {sel.size} messages of the topic '
                        f'but its index lists {indexed}')
                sel = sel[np.argsort(time_ns[sel], kind='stable')]
                buf = np.frombuffer(raw, np.uint8)
                for i in range(0, sel.size, block):
                    part = sel[i:i + block]
                    yield buf, starts[part], lengths[part], time_ns[part]

    def _full_ros1_reader(self) -> Ros1Reader:
        """Open rosbags' indexing ROS 1 reader, or raise BagError if its index would not fit."""
        lean = self._ros1_reader()
        count = sum(sum(c.connection_counts.values()) for c in lean.chunk_infos)
        check_ros1_index_fits(self.path, count)
        reader = _full_ros1_reader_class()(lean.path)
        reader.open()
        return reader

    def close(self) -> None:
        """Close the reader (idempotent; never raises)."""
        reader, self.reader = self.reader, None
        if reader is not None:
            try:
                reader.close()
            # closing a half-broken reader must not mask the cause
            except Exception:  # noqa: BLE001, S110
                pass


#: Memory rosbags' ROS 1 reader holds per indexed message (B): an ``IndexData`` named tuple in a
#: sorted list; ``bench/bench_ros1_memory.py`` measured 177 B per message (rounded up).
ROS1_INDEX_BYTES_PER_MESSAGE = 180


def available_memory_bytes() -> int | None:
    """
    Memory the system can give without swapping (``MemAvailable`` of ``/proc/meminfo``).

    Returns
    -------
    int or None
        Bytes, or None where it cannot be read.

    """
    try:
        with open('/proc/meminfo') as fh:
            for line in fh:
                if line.startswith('MemAvailable:'):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def check_ros1_index_fits(path: StrPath, messages: int, *, available: int | None = None) -> None:
    """
    Raise BagError if rosbags' per-message index of a ROS 1 bag would not fit in memory.

    Parameters
    ----------
    path : str or os.PathLike
        The bag (for the message).
    messages : int
        Messages in the bag (all topics).
    available : int, optional
        Bytes available; :func:`available_memory_bytes` if None.

    Raises
    ------
    BagError
        The index (``ROS1_INDEX_BYTES_PER_MESSAGE`` per message) would take more than half of
        the available memory.

    """
    if available is None:
        available = available_memory_bytes()
    need = int(messages) * ROS1_INDEX_BYTES_PER_MESSAGE
    if available is not None and need > available // 2:
        raise BagError(f'ROS 1 bag {str(path)!r} has chunks that overlap in time, so reading '
                       f'it in order needs an index of {messages} messages ({need / 1e9:.1f} GB) '
                       f'but only {available / 1e9:.1f} GB of memory is available; reorder '
                       'it with "rosbag filter" or convert it with "rosbags-convert" on a '
                       'larger machine')


def _full_ros1_reader_class() -> type[Ros1Reader]:
    from rosbags.rosbag1 import Reader

    return Reader


def _lean_ros1_reader_class() -> type[Ros1Reader]:
    """Return rosbags' ROS 1 Reader class without the per-message index (chunk list, counts)."""
    # rosbags is imported when a bag is read, not when the package is
    from ._lean_ros1 import LeanRos1Reader

    return LeanRos1Reader
