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
rosbags' readers extended to read an MCAP file cut before its summary (a killed writer).

The record walk is :mod:`.mcap_records`; this module holds only the rosbags subclasses that use
it, apart from the rest so that rosbags is imported when a bag is read, not when the package is
(:func:`.recover.recovering_reader_class`). :class:`RecoveringMcapReader` opens a file without
footer in steps: check the header, walk the records (the chunks with the counts of their
MessageIndex records, up to the first cut), believe or decompress each chunk into a chunk index
entry, index the readable part, and recount the messages and times from what was read.
:class:`RecoveringReader` is rosbags' unified ``Reader`` with it for MCAP files and bag folders.
"""

from io import BytesIO
from pathlib import Path
import struct
from typing import Any, cast

from rosbags.interfaces import Connection, ConnectionExtRosbag2
from rosbags.rosbag2 import Reader
from rosbags.rosbag2.errors import ReaderError
from rosbags.rosbag2.reader import DirectoryReader
from rosbags.rosbag2.storage_mcap import Channel as McapChannel
from rosbags.rosbag2.storage_mcap import (ChunkInfo, decompress, get_msgdef, get_qos, McapReader,
                                          read_bytes, read_sized, read_string, Schema, Statistics)

from .mcap_records import (ChunkWalk, mcap_has_footer, MCAP_MAGIC, McapTruncation, RecordWalk,
                           walk_chunk, walk_records)

__all__ = ['RecoveringDirectoryReader', 'RecoveringMcapReader', 'RecoveringReader']


class RecoveringMcapReader(McapReader):
    """rosbags' MCAP reader that also reads a file cut before its summary (see module)."""

    truncation: McapTruncation | None = None

    def _open(self) -> None:
        if mcap_has_footer(cast(Path, self.path)):  # BagSource hands rosbags a Path
            super()._open()
            return
        self._open_truncated()

    def _add_schema(self, body: bytes) -> None:
        rec = BytesIO(body)
        (key,) = struct.unpack('<H', rec.read(2))
        self.schemas[key] = Schema(key, read_string(rec), read_string(rec), read_string(rec))

    def _add_channel(self, body: bytes) -> None:
        rec = BytesIO(body)
        key, schema_id = struct.unpack('<HH', rec.read(4))
        schema = self.schemas.get(schema_id)
        name = schema.name if schema is not None else '__schemaless__'
        channel = McapChannel(key, name, read_string(rec), read_string(rec), read_bytes(rec))
        self.channels[key] = channel
        if all(c.id != key for c in self.connections):
            self.connections.append(Connection(
                key, channel.topic, channel.schema, get_msgdef(schema), '', 0,
                ConnectionExtRosbag2(channel.message_encoding, get_qos(channel.metadata)),
                self))

    def _read_chunk(self, head: dict[str, Any]) -> ChunkWalk | None:
        """Decompress one chunk found by the walk; return its walk or None if unreadable."""
        bio = self.bio
        assert bio is not None  # an open reader
        bio.seek(head['data_offset'])
        data = bio.read(head['compressed_size'])
        try:
            raw = decompress(data, head['compression'], head['uncompressed_size'],
                             head['crc'])
            return walk_chunk(raw)
        except Exception:  # noqa: BLE001 - rosbags, lz4 and zstd raise many types on garbage
            return None

    def _finish(self, head: dict[str, Any], trusted: bool) -> ChunkInfo | None:
        """
        Turn a walked chunk into a ChunkInfo (or None: unreadable, ends the walk).

        ``trusted``: its MessageIndex records are complete (another record follows them).
        """
        known = all(cid in self.channels for cid in head['counts'])
        if trusted and head['counts'] and known:
            counts = head['counts']
        else:
            walked = self._read_chunk(head)
            if walked is None:
                return None
            schemas, channels, counts, start, end = walked
            for body in schemas.values():
                self._add_schema(body)
            for body in channels.values():
                self._add_channel(body)
            if counts and (start < head['start'] or end > head['end']):
                return None  # the chunk header disagrees with its messages: not believed
        return ChunkInfo(head['start'], head['end'], head['offset'], head['length'],
                         head['index_offsets'], head['index_length'], head['compression'],
                         head['compressed_size'], head['uncompressed_size'], dict(counts))

    def _open_truncated(self) -> None:
        self.data_start = self._read_header()
        assert self.bio is not None  # _read_header read it
        size = self.bio.seek(0, 2)
        walk = walk_records(self.bio, self.data_start, size, on_schema=self._add_schema,
                            on_channel=self._add_channel)
        chunks, readable, reason = self._chunk_index(walk)
        self.data_end = readable
        self._index(chunks, walk.top_messages)
        self._recount(readable=readable, size=size, reason=reason)

    def _read_header(self) -> int:
        """Check the magic, the Header record and the ros2 profile; return the data's offset."""
        bio = self.bio
        assert bio is not None  # an open reader
        bio.seek(0)
        if bio.read(8) != MCAP_MAGIC:
            raise ReaderError('File magic is invalid.')
        if bio.read(1) != b'\x01':
            raise ReaderError('Unexpected record.')
        if read_string(BytesIO(read_sized(bio))) != 'ros2':
            raise ReaderError('Profile is not ros2.')
        return bio.tell()

    def _chunk_index(self, walk: RecordWalk) -> tuple[list[ChunkInfo], int, str]:
        """Return the walk's chunks up to the first unreadable one, where reading stops, why."""
        readable, reason = walk.stop, walk.reason
        chunks = []
        for chunk_head, trusted in walk.heads:
            info = self._finish(chunk_head, trusted)
            if info is None:
                readable = chunk_head['offset']
                reason = f'chunk at byte {readable} does not decompress or parse'
                break
            chunks.append(info)
        return chunks, readable, reason

    def _index(self, chunks: list[ChunkInfo], top_messages: int) -> None:
        """Index the readable part by its chunks, or by rosbags' scan if messages are outside."""
        if top_messages:
            # Messages outside chunks: rosbags' own scan of the readable part reads them.
            self.chunks.clear()
            self.meta_scan()
        else:
            self.chunks[:] = [c for c in chunks if sum(c.channel_count.values())]
            self._statistics_from_chunks()

    def _recount(self, *, readable: int, size: int, reason: str) -> None:
        """Set the counts and times of the connections and metadata, and the truncation."""
        stats = self.statistics
        assert stats is not None  # set by _index
        count = stats.message_count
        self.connections = [c._replace(msgcount=stats.channel_message_counts.get(c.id, 0))
                            for c in self.connections]
        self.metadata = self.metadata._replace(
            duration=stats.end_time - stats.start_time + 1 if count else 0,
            start_time=stats.start_time if count else 2**63 - 1,
            end_time=stats.end_time + 1 if count else 0, message_count=count)
        self.truncation = McapTruncation(
            messages=count, chunks=stats.chunk_count, readable_bytes=readable,
            file_bytes=size, start_ns=stats.start_time if count else 0,
            end_ns=stats.end_time if count else 0, stop_reason=reason)

    def _statistics_from_chunks(self) -> None:
        cstats: dict[int, int] = {}
        for chunk in self.chunks:
            for cid, k in chunk.channel_count.items():
                cstats[cid] = cstats.get(cid, 0) + k
        total = sum(cstats.values())
        self.statistics = Statistics(
            total, len(self.schemas), len(self.channels), 0, 0, len(self.chunks),
            min((c.message_start_time for c in self.chunks), default=2**63 - 1),
            max((c.message_end_time for c in self.chunks), default=0), cstats)


class RecoveringDirectoryReader(DirectoryReader):
    """
    rosbags' reader of a bag folder whose MCAP files may lack their footer.

    The counts and time range of ``metadata.yaml`` describe the finished files: when one was
    cut, they are replaced by what its chunks hold.
    """

    STORAGE_PLUGINS = {**DirectoryReader.STORAGE_PLUGINS, 'mcap': RecoveringMcapReader}
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
                       '.mcap': RecoveringMcapReader}
