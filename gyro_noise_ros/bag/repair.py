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
Repair a killed recording: write the complete rosbag2 its writer would have left at its last flush.

The input is read as every tool reads it (:class:`~gyro_noise_ros.bag.storage.BagSource`: an MCAP
file without footer by its chunks, an sqlite3 file with a hot journal through a rolled-back copy)
and never opened for writing. Every topic is copied, with its type, message definition and QoS, in
recording order (sqlite3 row order, MCAP chunk order), into a new bag (same storage unless another
is asked for) that is built under a hidden name and renamed only when it is complete
(:func:`gyro_noise_ros.outputs.staged_new_dir`), with its ``metadata.yaml``. The copy is checked:
the new bag holds exactly the messages read, per topic.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
import itertools
from pathlib import Path
import sys
from typing import Any, cast, TYPE_CHECKING

import numpy as np

from .mcap_records import mcap_message_records, read_mcap_chunk
from .storage import BagSource, describe, STORAGES
from .writer import write_raw
from ..errors import BagError, OutputError, ParameterError
from ..msgs import typestore
from ..outputs import check_new_dir, is_disk_full, staged_new_dir, StrPath

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

#: Messages handed to the writer at once.
BLOCK = 16384


@dataclass(frozen=True)
class RepairResult:
    """
    What :func:`repair_bag` wrote.

    Attributes
    ----------
    source : str
        The input bag.
    out : str
        The new bag.
    storage : str
        Its storage ('sqlite3' or 'mcap').
    topics : tuple of (str, str, int)
        (topic, message type, messages written) of every topic, sorted by topic.
    messages : int
        Messages written, all topics.
    start_ns, end_ns : int or None
        First and last bag (receive) time written, ns.
    recovery : str or None
        How the input was read (the note said on stderr), None for a finished input.

    """

    source: str
    out: str
    storage: str
    topics: tuple[tuple[str, str, int], ...]
    messages: int
    start_ns: int | None
    end_ns: int | None
    recovery: str | None

    def as_dict(self) -> dict[str, Any]:
        """Return the result as plain JSON-able types."""
        return {'source': self.source, 'out': self.out, 'storage': self.storage,
                'topics': [{'topic': t, 'msgtype': m, 'messages': n} for t, m, n in self.topics],
                'messages': self.messages, 'start_ns': self.start_ns, 'end_ns': self.end_ns,
                'recovery': self.recovery}


def default_repaired_path(path: StrPath) -> Path:
    """
    Return where ``repair`` writes by default: ``<bag>_repaired`` beside the input.

    Parameters
    ----------
    path : str or os.PathLike
        The input (a bag folder or a storage file).

    Returns
    -------
    pathlib.Path

    """
    path = Path(path)
    if path.name == 'metadata.yaml':
        path = path.parent
    name = path.name if path.is_dir() else path.stem
    return path.parent / f'{name}_repaired'


def _connection_args(conn: Connection) -> dict[str, Any]:
    """Keyword arguments of rosbags' ``Writer.add_connection`` reproducing ``conn``."""
    qos = list(getattr(conn.ext, 'offered_qos_profiles', []) or [])
    data = getattr(conn.msgdef, 'data', '') or ''
    if data and conn.digest:
        return {'msgdef': data, 'rihs01': conn.digest, 'offered_qos_profiles': qos}
    store = typestore()
    if conn.msgtype not in store.fielddefs:
        if not data:
            raise BagError(f'topic {conn.topic!r} ({conn.msgtype}) carries no message definition '
                           'and its type is not a standard one: it cannot be copied')
        from rosbags.typesys import get_types_from_idl, get_types_from_msg, get_typestore, Stores

        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_idl(data) if data.startswith('=' * 80 + '\nIDL: ')
                       else get_types_from_msg(data, conn.msgtype))
    return {'typestore': store, 'offered_qos_profiles': qos}


def _storage_order_blocks(
        source: BagSource,
) -> Iterator[tuple[Connection, np.ndarray, Sequence[bytes | memoryview]]]:
    """
    Yield ``(storage connection id, log_ns, blobs)`` runs in recording order.

    sqlite3 rows by insertion order and MCAP chunks in file order, records in chunk order; any
    other layout (message compression, ROS 1) through rosbags' time-ordered iterator.
    """
    storages = source._storages() if source.fast and not source.ros1 else None
    if storages is None:
        stream = source._open_reader().messages(connections=source.connections)
        while block := list(itertools.islice(stream, BLOCK)):
            for _, group in itertools.groupby(block, key=lambda m: id(m[0])):
                run = list(group)
                yield run[0][0], np.array([m[1] for m in run], np.int64), [m[2] for m in run]
        return
    for storage in storages:
        conns = {c.id: c for c in storage.connections}
        # the storage kind names the rosbags storage reader class
        if source.storage == 'sqlite3':
            dbconn = cast('Sqlite3Reader', storage).dbconn
            assert dbconn is not None  # an open storage
            cursor = dbconn.execute(
                'SELECT topic_id, timestamp, data FROM messages ORDER BY id')
            while rows := list(itertools.islice(cursor, BLOCK)):
                for cid, group in itertools.groupby(rows, key=lambda r: r[0]):
                    run = list(group)
                    if cid in conns:
                        yield (conns[cid], np.array([r[1] for r in run], np.int64),
                               [r[2] for r in run])
            continue
        mcap = cast('McapReader', storage)
        chunks = sorted(mcap.chunks, key=lambda c: c.chunk_start_offset)
        if not chunks and mcap.statistics and mcap.statistics.message_count:
            stream = mcap.messages(list(conns.values()))
            while block := list(itertools.islice(stream, BLOCK)):
                for _, group in itertools.groupby(block, key=lambda m: id(m[0])):
                    run = list(group)
                    yield run[0][0], np.array([m[1] for m in run], np.int64), [m[2] for m in run]
            continue
        with open(cast(Path, mcap.path), 'rb') as fh:
            for info in chunks:
                raw = read_mcap_chunk(fh, info)
                starts, lengths, channel, log_ns = mcap_message_records(raw)
                if channel.size == 0:
                    continue
                view = memoryview(raw)
                bounds = np.flatnonzero(np.diff(channel)) + 1
                for a, b in zip(np.r_[0, bounds], np.r_[bounds, channel.shape[0]]):
                    cid = int(channel[a])
                    if cid in conns:
                        yield conns[cid], log_ns[a:b], [
                            view[s:s + n] for s, n in zip(starts[a:b].tolist(),
                                                          lengths[a:b].tolist())]


def _copy_error(path: StrPath, out: Path, err: BaseException) -> BagError | OutputError:
    """Return the error of a failed copy: the output's when the disk is full, else the input's."""
    # an OS error on the stage (named .<out>.partial-...) is the output's, whatever its errno
    if is_disk_full(err) or (isinstance(err, OSError) and err.filename is not None
                             and f'.{out.name}.partial-' in str(err.filename)):
        return OutputError(f'{{out}} {str(out)!r} cannot be written: {describe(err)}',
                           parameters=('out',))
    return BagError(f'bag {str(path)!r} cannot be copied: {describe(err)}')


def repair_bag(path: StrPath, out: StrPath | None = None, *,
               storage: str | None = None, overwrite: bool = False) -> RepairResult:
    """
    Write a complete rosbag2 from a killed (or any readable rosbag2) recording.

    Parameters
    ----------
    path : str or os.PathLike
        The recording: a rosbag2 folder (with or without ``metadata.yaml``) or its ``.db3`` /
        ``.mcap`` file.
    out : str or os.PathLike, optional
        The new bag folder (must not exist); :func:`default_repaired_path` if None.
    storage : {'sqlite3', 'mcap'}, optional, keyword-only
        Storage of the new bag; the input's if None.
    overwrite : bool, keyword-only
        An existing bag at ``out`` is replaced once the new one is complete.

    Returns
    -------
    RepairResult

    Raises
    ------
    BagError
        The input cannot be read (exit code 3).
    ParameterError
        Unknown storage, or a ROS 1 input (exit code 2).
    OutputError
        ``out`` exists (without ``overwrite``), cannot be written, or the disk is full (exit
        code 6).

    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    if storage is not None and storage not in STORAGES:
        raise ParameterError(f"{{storage}} must be 'sqlite3' or 'mcap', got {storage!r}",
                             parameters=('storage',))
    out = Path(out) if out is not None else default_repaired_path(path)
    if out.resolve() == Path(path).resolve():
        raise OutputError(f'{{out}} {str(out)!r} is the input: the recording is never replaced',
                          parameters=('out',))
    check_new_dir(out, parameter='out', overwrite=overwrite)
    source = BagSource(path)
    try:
        if source.ros1:
            raise ParameterError(f'bag {str(path)!r} is a ROS 1 bag: it has no rosbag2 '
                                 'metadata to repair')
        kind = storage or source.storage
        plugin = StoragePlugin.SQLITE3 if kind == 'sqlite3' else StoragePlugin.MCAP
        written: dict[tuple[str, str], int] = {}
        first: int | None = None
        last: int | None = None
        with staged_new_dir(out, parameter='out', overwrite=overwrite) as stage:
            writer = Writer(stage, version=9, storage_plugin=plugin)
            try:
                writer.open()
                made = {}
                for conn in source.connections:
                    key = (conn.topic, conn.msgtype)
                    if key not in made:
                        made[key] = writer.add_connection(conn.topic, conn.msgtype,
                                                          **_connection_args(conn))
                for conn, log_ns, blobs in _storage_order_blocks(source):
                    key = (conn.topic, conn.msgtype)
                    write_raw(writer, made[key], log_ns, blobs, out)
                    written[key] = written.get(key, 0) + len(blobs)
                    lo, hi = int(log_ns.min()), int(log_ns.max())
                    first = lo if first is None else min(first, lo)
                    last = hi if last is None else max(last, hi)
            except (BagError, ParameterError):
                raise
            except Exception as err:  # noqa: BLE001 - rosbags, zstd and sqlite errors
                raise _copy_error(path, out, err) from err
            finally:
                try:
                    writer.close()
                except Exception as err:  # noqa: BLE001 - rosbags, zstd and sqlite errors
                    if sys.exc_info()[0] is None:  # else the first error is the one to report
                        raise _copy_error(path, out, err) from err
            expected = {}
            for name, (msgtype, count) in source.topics().items():
                if msgtype is not None:
                    expected[(name, msgtype)] = count
            got = {key: written.get(key, 0) for key in expected}
            if got != expected:
                raise BagError(f'bag {str(path)!r}: the copy holds {got} messages per topic but '
                               f'the input lists {expected}')
        topics = tuple(sorted((t, m, n) for (t, m), n in got.items()))
        return RepairResult(source=str(path), out=str(out), storage=kind, topics=topics,
                            messages=sum(got.values()), start_ns=first, end_ns=last,
                            recovery=source.recovery)
    finally:
        source.close()
