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
Reading recordings whose writer was killed, without modifying them.

Two storages, two ways a killed writer (``kill -9``, power loss) leaves its file:

* **MCAP without summary and footer.** rosbags (and most MCAP readers) start at the footer, so
  the whole file is refused ("File end magic is invalid"). Everything before the cut is intact:
  the records are walked from the start, by their length fields, up to the first record that runs
  past the end of the file (or a zero-filled tail); each complete Chunk record becomes a chunk
  index entry, with its per-channel message counts from the MessageIndex records that follow it.
  The last complete chunk, and any chunk without an index or with channels not seen yet, is
  decompressed and walked (its Schema and Channel records define the topics; a chunk that does
  not decompress or parse ends the readable part). ``RecoveringMcapReader``
  (:mod:`._recovering_mcap`) is rosbags' ``McapReader`` with that walk in place of the summary,
  so rosbags' iterator and the block reader of :mod:`.storage` read it unchanged.
* **sqlite3 with a hot rollback journal** (rosbags keeps a transaction open between commits).
  rosbags opens the database immutable and would read the half-written pages of the unfinished
  transaction. :func:`rolled_back_copy` copies the ``.db3`` and its ``-journal`` to a temporary
  folder and lets sqlite roll the transaction back there: what was committed is read, the user's
  files are never opened for writing. The copy lives until the process exits.

Each case is said once per process in one line on stderr (:func:`announce`).
"""

from __future__ import annotations

import atexit
from collections.abc import Callable
from dataclasses import dataclass
import functools
import os
from pathlib import Path
import shutil
import struct
import sys
import tempfile
from typing import Any, BinaryIO, NamedTuple, TYPE_CHECKING

import numpy as np

from ..errors import BagError
from ..outputs import StrPath

if TYPE_CHECKING:
    from rosbags.rosbag2 import Reader
    from rosbags.rosbag2.storage_mcap import McapReader

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
_RECORD_HEAD = struct.Struct('<BQ')
_CHUNK_HEAD = struct.Struct('<QQQI')
#: Free space kept beyond the copy itself when a rolled-back copy is made (bytes).
COPY_MARGIN_BYTES = 64 << 20

_announced: set[str] = set()


def announce(text: str) -> None:
    """
    Say ``text`` once per process on stderr, as ``<program>: warning: <text>``.

    Parameters
    ----------
    text : str
        One sentence.

    """
    if text in _announced:
        return
    _announced.add(text)
    prog = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else 'gyro_noise_ros'
    print(f'{prog}: warning: {text}', file=sys.stderr, flush=True)


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


#: What :func:`_walk_chunk` finds: (schemas, channels, counts, start_ns, end_ns).
ChunkWalk = tuple[dict[int, bytes], dict[int, bytes], dict[int, int], int | None, int | None]


def _walk_chunk(raw: bytes) -> ChunkWalk:
    """
    Return (schemas, channels, counts, start_ns, end_ns) of one decompressed chunk.

    Schemas and channels are raw record bodies by id; counts are messages per channel id.
    Raises BagError when a record runs past the chunk.
    """
    from .storage import mcap_message_records

    starts, lengths, channel, log_ns = mcap_message_records(raw)
    counts = {int(c): int(k) for c, k in zip(*np.unique(channel, return_counts=True))}
    start = int(log_ns.min()) if log_ns.size else None
    end = int(log_ns.max()) if log_ns.size else None
    schemas: dict[int, bytes] = {}
    channels: dict[int, bytes] = {}
    if int(lengths.sum()) + 31 * lengths.shape[0] != len(raw):
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


class _RecordWalk(NamedTuple):
    """
    What :func:`_walk_records` found.

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


def _walk_records(bio: BinaryIO, pos: int, size: int, *, on_schema: Callable[[bytes], None],
                  on_channel: Callable[[bytes], None]) -> _RecordWalk:
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
    _RecordWalk

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
    return _RecordWalk(heads, pos, reason, top_messages)


@functools.lru_cache(maxsize=None)
def recovering_mcap_reader_class() -> type[McapReader]:
    """
    Return rosbags' ``McapReader`` extended to read a file without summary and footer.

    Returns
    -------
    type
        ``RecoveringMcapReader``: with a footer it is rosbags' reader unchanged; without one,
        its ``truncation`` attribute is a :class:`McapTruncation` and its chunk index is built
        by walking the file (module docstring).

    """
    # rosbags is imported when a bag is read, not when the package is
    from ._recovering_mcap import RecoveringMcapReader

    return RecoveringMcapReader


@functools.lru_cache(maxsize=None)
def recovering_reader_class() -> type[Reader]:
    """
    Return rosbags' unified ``Reader`` with :func:`recovering_mcap_reader_class` for bare files.

    Returns
    -------
    type

    """
    from rosbags.rosbag2 import Reader
    from rosbags.rosbag2.reader import DirectoryReader

    mcap_reader = recovering_mcap_reader_class()

    class RecoveringDirectoryReader(DirectoryReader):
        """
        rosbags' reader of a bag folder whose MCAP files may lack their footer.

        The counts and time range of ``metadata.yaml`` describe the finished files: when one was
        cut, they are replaced by what its chunks hold.
        """

        STORAGE_PLUGINS = {**DirectoryReader.STORAGE_PLUGINS, 'mcap': mcap_reader}
        truncation: McapTruncation | None = None

        def open(self) -> None:  # noqa: A003 - overrides rosbags DirectoryReader.open
            """Open the bag; recount from the storages if an MCAP file was cut."""
            super().open()
            found = (getattr(s, 'truncation', None) for s in self.storages)
            cut: list[McapTruncation] = [t for t in found if t]
            if not cut:
                return
            self.truncation = cut[0] if len(cut) == 1 else McapTruncation(
                messages=sum(c.messages for c in cut), chunks=sum(c.chunks for c in cut),
                readable_bytes=sum(c.readable_bytes for c in cut),
                file_bytes=sum(c.file_bytes for c in cut),
                start_ns=min(c.start_ns for c in cut), end_ns=max(c.end_ns for c in cut),
                stop_reason=cut[0].stop_reason)
            counts: dict[tuple[str, str], int] = {}
            for storage in self.storages:
                for conn in storage.connections:
                    key = (conn.topic, conn.msgtype)
                    counts[key] = counts.get(key, 0) + conn.msgcount
            self.connections = [c._replace(msgcount=counts.get((c.topic, c.msgtype), 0))
                                for c in self.connections]
            metas = [s.metadata for s in self.storages if s.metadata.message_count]
            start = min((m.start_time for m in metas), default=2**63 - 1)
            end = max((m.end_time for m in metas), default=0)
            total = sum(m.message_count for m in metas)
            self.metadata = self.metadata._replace(
                duration=end - start if total else 0, start_time=start, end_time=end,
                message_count=total)

    class RecoveringReader(Reader):
        """rosbags' Reader; an MCAP file without footer is read by its chunks."""

        STORAGE_PLUGINS = {**Reader.STORAGE_PLUGINS, 'dir': RecoveringDirectoryReader,
                           '.mcap': mcap_reader}

    return RecoveringReader


def truncation_note(path: StrPath, truncation: McapTruncation) -> str:
    """
    Return the one-line note on a truncated MCAP file.

    Parameters
    ----------
    path : str or os.PathLike
        The bag as the user named it.
    truncation : McapTruncation
        What the walk found.

    Returns
    -------
    str

    """
    return (f'truncated MCAP {str(path)!r} (no summary/footer: its writer was killed): read '
            f'{truncation.messages} messages up to t = {truncation.span_s:.3f} s by its '
            f'{truncation.chunks} chunks, {truncation.lost_bytes} bytes after them lost '
            f'({truncation.stop_reason}); `gyro_noise_record repair {path}` writes a complete '
            'bag')


# ---------------------------------------------------------------------------------------------
# sqlite3: a hot rollback journal, rolled back in a copy

_COPIES: dict[tuple[tuple[int, int, int, int], tuple[int, int, int, int]], Path] = {}


def journal_is_hot(db3: Path) -> bool:
    """
    Tell whether a ``.db3`` has a non-empty rollback journal beside it (a writer died mid-way).

    Parameters
    ----------
    db3 : pathlib.Path
        The sqlite3 file.

    Returns
    -------
    bool

    """
    journal = db3.with_name(db3.name + '-journal')
    try:
        return journal.stat().st_size > 0
    except OSError:
        return False


def _identity(path: Path) -> tuple[int, int, int, int]:
    st = path.stat()
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def rolled_back_copy(db3: StrPath) -> Path:
    """
    Copy an sqlite3 file and its hot journal to a temporary folder and roll the journal back there.

    The originals are only read. The copy is made once per process (cached by the files' identity,
    size and modification time) and removed when the process exits; ``TMPDIR`` chooses where.

    Parameters
    ----------
    db3 : str or os.PathLike
        The sqlite3 file; ``<name>-journal`` beside it is the journal.

    Returns
    -------
    pathlib.Path
        The rolled-back copy (committed transactions only).

    Raises
    ------
    BagError
        The files cannot be read, the temporary folder lacks the space for the copy, or sqlite
        cannot roll the journal back.

    """
    import sqlite3

    db3 = Path(db3)
    journal = db3.with_name(db3.name + '-journal')
    try:
        key = (_identity(db3), _identity(journal))
        need = key[0][2] + key[1][2]
    except OSError as err:
        raise BagError(f'sqlite3 file {str(db3)!r} cannot be read: '
                       f'{err.strerror or err}') from err
    hit = _COPIES.get(key)
    if hit is not None and hit.exists():
        return hit
    root = tempfile.gettempdir()
    free = shutil.disk_usage(root).free
    if free < need + COPY_MARGIN_BYTES:
        raise BagError(
            f'sqlite3 file {str(db3)!r} has an unfinished transaction ({journal.name}) and '
            f'reading it needs a rolled-back copy of {need / 1e9:.2f} GB, but {root!r} has '
            f'{free / 1e9:.2f} GB free: set TMPDIR to a folder with room, or write a '
            f'complete bag elsewhere with `gyro_noise_record repair {db3.parent}`')
    folder = Path(tempfile.mkdtemp(prefix='gyro_noise_rollback-', dir=root))
    atexit.register(shutil.rmtree, folder, True)
    copy = folder / db3.name
    try:
        shutil.copyfile(db3, copy)
        shutil.copyfile(journal, folder / journal.name)
        con = sqlite3.connect(copy)
        try:
            # The first read of a database with a hot journal rolls the journal back.
            con.execute('SELECT count(*) FROM sqlite_master').fetchone()
        finally:
            con.close()
    except (OSError, sqlite3.Error) as err:
        shutil.rmtree(folder, ignore_errors=True)
        raise BagError(f'sqlite3 file {str(db3)!r}: its unfinished transaction '
                       f'({journal.name}) cannot be rolled back in a copy: {err}') from err
    # A journal sqlite did not judge hot (a zeroed header) stays; it holds nothing to roll back,
    # and rosbags opens the copy immutable, ignoring it.
    _COPIES[key] = copy
    return copy


def rollback_note(path: StrPath, db3: Path) -> str:
    """
    Return the one-line note on an sqlite3 file read through a rolled-back copy.

    Parameters
    ----------
    path : str or os.PathLike
        The bag as the user named it.
    db3 : pathlib.Path
        Its sqlite3 file.

    Returns
    -------
    str

    """
    return (f'sqlite3 bag {str(path)!r} has an unfinished transaction ({db3.name}-journal: its '
            'writer was killed): reading what was committed, through a rolled-back copy (the '
            f'files are left as they are); `gyro_noise_record repair {path}` writes a complete '
            'bag')
