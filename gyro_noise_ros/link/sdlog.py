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
SD-card log files of the Portenta board: writer and constant-memory streaming reader.

A log file is the wire stream itself (``docs/portenta_link.md``): it starts with a LOG_HEADER frame
(sequence id, file index, configuration at file open, first seq, device time, RTC time) followed by
SAMPLES frames, and an ACK frame wherever the configuration changed. One acquisition sequence (one
power-on recording) is split across files named ``S<sss>F<fff>.GNL`` (8.3 names for FAT32, ``sss``
= sequence id modulo 1000, ``fff`` = file index), each below the FAT32 limit of 4 GiB - 1 bytes; a
file ends at a frame boundary and the next one continues the same sequence counter and device
clock.

The reader orders files by (sequence id, file index) from their headers (by name when a header is
unreadable), feeds them through one :class:`~gyro_noise_ros.link.protocol.Decoder` (so counter gaps
across file boundaries are counted), flushes it at the end of every file (a frame cut by the end of
a file is discarded, not glued to the next file), and reports every corrupt region by file and
offset.
"""

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
import os
import re
from typing import BinaryIO

import numpy as np
from numpy.typing import NDArray

from .protocol import (
    Ack,
    Decoder,
    DecodeResult,
    encode_ack,
    encode_log_header,
    encode_samples,
    LinkStats,
    LogHeader,
    MAX_FRAME_SIZE,
    MAX_SAMPLES_PER_FRAME,
)
from .scan import ScanDecoder
from .sequence import wrapped_delta
from ..errors import InputDataError, ParameterError

#: FAT32 file-size limit (bytes); the paper's board stopped a sequence there (~12 h at 6.66 kHz).
FAT32_MAX_FILE_BYTES = (1 << 32) - 1
FILE_NAME_FORMAT = 'S{sequence:03d}F{index:03d}.GNL'
FILE_NAME_RE = re.compile(r'^S(\d{3})F(\d{3})\.GNL$', re.IGNORECASE)
#: Corrupt regions kept in a report (the total count is always exact).
MAX_REPORTED_REGIONS = 1000
#: Largest read size (bytes): a block of log is decoded into about 2.4 times its size of arrays
#: and a few blocks are in flight, so 64 MiB keeps an import under about 1 GB; a larger value
#: is refused up front instead of failing half-way with a memory error.
MAX_CHUNK_BYTES = 64 << 20

#: (odr_hz, gyro_fs_dps, accel_fs_g) in force, None before the first header or ACK.
_Config = tuple[float | None, int | None, int | None]


def log_file_name(sequence_id: int, file_index: int) -> str:
    """
    Return the 8.3 file name of one log file.

    Parameters
    ----------
    sequence_id : int
        Recording sequence number.
    file_index : int
        0 .. 999.

    Returns
    -------
    str

    """
    if not 0 <= int(file_index) <= 999:
        raise ParameterError(f'file_index must be in 0..999 for an 8.3 name, got {file_index}')
    return FILE_NAME_FORMAT.format(sequence=int(sequence_id) % 1000, index=int(file_index))


class SdLogWriter:
    """
    Write one acquisition sequence as SD log files, as the board firmware does.

    Parameters
    ----------
    directory : str or os.PathLike
        Existing directory.
    sequence_id : int, keyword-only
    odr_hz : float, keyword-only
        Configuration at power-on (Hz).
    gyro_fs_dps, accel_fs_g : int, keyword-only
        Full scales at power-on (deg/s, g).
    max_file_bytes : int, keyword-only
        Roll over to the next file before a frame would make a file larger than this.
    batch : int, keyword-only
        Samples per SAMPLES frame.
    rtc_unix_s : int, keyword-only
        RTC time at power-on (UNIX s, 0 = not set); each header gets it advanced by the device
        time.
    corrupt : callable, optional, keyword-only
        ``bytes -> bytes`` applied to everything written (fault injection).

    """

    def __init__(self, directory: str | os.PathLike[str], *, sequence_id: int, odr_hz: float,
                 gyro_fs_dps: int, accel_fs_g: int, max_file_bytes: int = FAT32_MAX_FILE_BYTES,
                 batch: int = 16, rtc_unix_s: int = 0,
                 corrupt: Callable[[bytes], bytes] | None = None) -> None:
        self.directory = os.fspath(directory)
        if not os.path.isdir(self.directory):
            raise ParameterError(f'directory must exist, got {self.directory!r}')
        if not 1 <= int(batch) <= MAX_SAMPLES_PER_FRAME:
            raise ParameterError(f'batch must be in 1..{MAX_SAMPLES_PER_FRAME}, got {batch}')
        if int(max_file_bytes) < 2 * MAX_FRAME_SIZE:
            raise ParameterError(
                f'max_file_bytes must be >= {2 * MAX_FRAME_SIZE}, got {max_file_bytes}')
        self.sequence_id = int(sequence_id)
        self.config = (float(odr_hz), int(gyro_fs_dps), int(accel_fs_g))
        self.max_file_bytes = int(max_file_bytes)
        self.batch = int(batch)
        self.rtc_unix_s = int(rtc_unix_s)
        self._t_origin_us: int | None = None
        self._corrupt = corrupt
        self._file: BinaryIO | None = None
        self._size = 0
        self.paths: list[str] = []

    def __enter__(self) -> 'SdLogWriter':
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _open_next(self, first_seq: int, t_us: int) -> None:
        if self._file is not None:
            self._file.close()
        index = len(self.paths)
        path = os.path.join(self.directory, log_file_name(self.sequence_id, index))
        self._file = open(path, 'wb')
        self.paths.append(path)
        self._size = 0
        if self._t_origin_us is None:
            self._t_origin_us = t_us
        rtc = 0
        if self.rtc_unix_s:
            rtc = self.rtc_unix_s + ((t_us - self._t_origin_us) % (1 << 32)) // 1_000_000
        odr, gfs, afs = self.config
        self._write(encode_log_header(LogHeader(sequence_id=self.sequence_id, file_index=index,
                                                odr_hz=odr, gyro_fs_dps=gfs, accel_fs_g=afs,
                                                first_seq=first_seq, t_us=t_us, rtc_unix_s=rtc)))

    def _write(self, data: bytes) -> None:
        if self._corrupt is not None:
            data = self._corrupt(data)
        assert self._file is not None  # _frame_out opened it
        self._file.write(data)
        self._size += len(data)

    def _frame_out(self, frame: bytes, first_seq: int, t_us: int) -> None:
        if self._file is None or self._size + len(frame) > self.max_file_bytes:
            self._open_next(first_seq, t_us)
        self._write(frame)

    def write_samples(self, samples: NDArray[np.void]) -> None:
        """
        Append samples (SAMPLES frames of ``batch`` samples).

        Parameters
        ----------
        samples : numpy.ndarray
            SAMPLE_DTYPE records.

        """
        for start in range(0, samples.size, self.batch):
            part = samples[start:start + self.batch]
            self._frame_out(encode_samples(part), int(part['seq'][0]), int(part['t_us'][0]))

    def write_ack(self, ack: Ack, *, next_seq: int = 0, t_us: int = 0) -> None:
        """
        Record a configuration change (an ACK frame) before the samples that follow it.

        Parameters
        ----------
        ack : Ack
            The acknowledgement to log.
        next_seq, t_us : int, keyword-only
            Used for the header if this opens a new file.

        """
        if ack.ok:
            self.config = (float(ack.odr_hz), int(ack.gyro_fs_dps), int(ack.accel_fs_g))
        self._frame_out(encode_ack(ack), int(next_seq), int(t_us))

    def close(self) -> None:
        """Close the current file."""
        if self._file is not None:
            self._file.close()
            self._file = None


@dataclass(frozen=True)
class LogBlock:
    """
    Consecutive samples of one file under one configuration.

    Attributes
    ----------
    path : str
    samples : numpy.ndarray
        SAMPLE_DTYPE records.
    lost_before : numpy.ndarray
        int64 per sample (counter gaps, across files).
    odr_hz : float or None
    gyro_fs_dps, accel_fs_g : int or None
        Configuration in force (None when neither a header nor an ack has said it yet).

    """

    path: str
    samples: np.ndarray
    lost_before: np.ndarray
    odr_hz: float | None
    gyro_fs_dps: int | None
    accel_fs_g: int | None


@dataclass(frozen=True)
class CorruptRegion:
    """
    Bytes of a file that were not part of any valid frame.

    Attributes
    ----------
    path : str
    offset : int
        Byte offset in the file.
    length : int

    """

    path: str
    offset: int
    length: int


@dataclass(frozen=True)
class LogFileInfo:
    """
    One input file.

    Attributes
    ----------
    path : str
    size_bytes : int
    header : LogHeader or None
        None when the file's first frame is not a readable LOG_HEADER.

    """

    path: str
    size_bytes: int
    header: LogHeader | None


@dataclass(frozen=True)
class LogReport:
    """
    Summary of a read.

    Attributes
    ----------
    files : tuple of LogFileInfo
        In reading order.
    stats : LinkStats
        Decoder counters over all files.
    corrupt_regions : tuple of CorruptRegion
        The first MAX_REPORTED_REGIONS regions.
    corrupt_region_count : int
        All regions.
    missing_file_indices : tuple of int
        Gaps in the file indices of the headers.
    sequence_id : int or None
    samples_without_config : int
        Samples read before any header or ack gave the configuration.

    """

    files: tuple[LogFileInfo, ...]
    stats: LinkStats
    corrupt_regions: tuple[CorruptRegion, ...]
    corrupt_region_count: int
    missing_file_indices: tuple[int, ...]
    sequence_id: int | None
    samples_without_config: int = 0
    warnings: tuple[str, ...] = field(default=())


def read_header(path: str | os.PathLike[str]) -> LogHeader | None:
    """
    Return the LOG_HEADER of a log file, or None when its start is unreadable.

    Parameters
    ----------
    path : str
        Log file.

    Returns
    -------
    LogHeader or None

    """
    with open(path, 'rb') as fh:
        head = fh.read(2 * MAX_FRAME_SIZE)
    dec = Decoder()
    res = dec.feed(head)
    # the header must be the very first frame: nothing discarded at offset 0, no sample before it
    if res.headers and res.header_positions[
            0] == 0 and not (res.discarded and res.discarded[0][0] == 0):
        return res.headers[0]
    return None


def sample_span(path: str | os.PathLike[str]) -> tuple[int, int] | None:
    """
    Return the sample counters at the start and at the end of a log file.

    Only the first and the last ``2 * MAX_FRAME_SIZE`` bytes are decoded (a frame cut by the end
    of the file is skipped, so the last counter is that of the last complete frame).

    Parameters
    ----------
    path : str
        Log file.

    Returns
    -------
    tuple of (int, int) or None
        (first, last) sample counter, or None when either end holds no valid SAMPLES frame.

    """
    window = 2 * MAX_FRAME_SIZE
    with open(path, 'rb') as fh:
        head = fh.read(window)
        size = fh.seek(0, 2)
        fh.seek(max(0, size - window))
        tail = fh.read()
    first = Decoder().feed(head).samples
    last = Decoder().feed(tail).samples
    if first.size == 0 or last.size == 0:
        return None
    return int(first['seq'][0]), int(last['seq'][-1])


def _check_distinct(infos: Sequence['LogFileInfo']) -> None:
    """Refuse a file named twice (ParameterError), two files of the same data (InputDataError)."""
    seen: dict[str, tuple[str, tuple[int, int]]] = {}
    for info in infos:
        try:
            key = os.path.realpath(info.path)
            st = os.stat(info.path)
            ident = (st.st_dev, st.st_ino)
        except OSError as err:
            raise InputDataError(f'cannot read log file {info.path!r}: {err}') from err
        for other, (other_key, other_ident) in seen.items():
            if key == other_key or ident == other_ident:
                raise ParameterError(f'log file {info.path!r} is given twice (also as '
                                     f'{other!r}); give each file once')
        seen[info.path] = (key, ident)
    heads: dict[tuple[int, int], str] = {}
    for info in infos:
        if info.header is None:
            continue
        file_key = (info.header.sequence_id, info.header.file_index)
        if file_key in heads:
            raise InputDataError(
                f'log files {heads[file_key]!r} and {info.path!r} both hold file {file_key[1]} of '
                f'sequence {file_key[0]} (the same log twice?); give each file once')
        heads[file_key] = info.path


def _check_overlaps(files: Iterable['LogFileInfo']) -> None:
    """Refuse consecutive files whose sample counters overlap (InputDataError naming both)."""
    previous = None
    for info in files:
        try:
            span = sample_span(info.path)
        except OSError as err:
            raise InputDataError(f'cannot read log file {info.path!r}: {err}') from err
        if span is None:
            continue
        if previous is not None and int(wrapped_delta(span[0], previous[1][1])) <= 0:
            raise InputDataError(
                f'log files {previous[0]!r} (samples {previous[1][0]}..{previous[1][1]}) and '
                f'{info.path!r} (samples {span[0]}..{span[1]}) overlap: the same samples '
                'twice; give each part of the sequence once')
        previous = (info.path, span)


def _name_key(path: str) -> tuple[int, int] | None:
    m = FILE_NAME_RE.match(os.path.basename(path))
    return (int(m.group(1)), int(m.group(2))) if m else None


class SdLogReader:
    """
    Stream samples out of the log files of one sequence in constant memory.

    Parameters
    ----------
    paths : sequence of str
        Log files, in any order.
    chunk_bytes : int, keyword-only
        Read size (bytes).
    scan : bool, keyword-only
        Decode with the compiled :class:`~gyro_noise_ros.link.scan.ScanDecoder` (default) or,
        False, with the byte-wise :class:`~gyro_noise_ros.link.protocol.Decoder` (the reference
        it is tested against, and the baseline of ``bench/bench_import.py``). Same blocks, same
        report.

    Notes
    -----
    Iterate to get :class:`LogBlock` objects; :attr:`report` is complete when the iteration ends.
    Raises before reading: ParameterError when a file is named twice or ``chunk_bytes`` is
    outside 1 .. :data:`MAX_CHUNK_BYTES`; InputDataError when a file cannot be read, the headers
    name different sequences, two files hold the same file of the sequence, or the sample
    counters of two consecutive files overlap (the same samples twice).

    """

    def __init__(self, paths: Iterable[str | os.PathLike[str]], *, chunk_bytes: int = 1 << 20,
                 scan: bool = True) -> None:
        names = [os.fspath(p) for p in paths]
        if not names:
            raise ParameterError('paths must name at least one log file')
        if not 1 <= int(chunk_bytes) <= MAX_CHUNK_BYTES:
            raise ParameterError(f'chunk_bytes must be in 1..{MAX_CHUNK_BYTES} (64 MiB), got '
                                 f'{chunk_bytes}')
        self.chunk_bytes = int(chunk_bytes)
        self._decoder_class = ScanDecoder if scan else Decoder
        infos = []
        for path in names:
            try:
                size = os.path.getsize(path)
                header = read_header(path)
            except OSError as err:
                raise InputDataError(f'cannot read log file {path!r}: {err}') from err
            infos.append(LogFileInfo(path=path, size_bytes=size, header=header))
        seqs = {i.header.sequence_id for i in infos if i.header is not None}
        if len(seqs) > 1:
            raise InputDataError(
                f'log files belong to different sequences {sorted(seqs)}; import one sequence '
                'at a time')
        self.sequence_id = seqs.pop() if seqs else None

        def key(item: tuple[int, LogFileInfo]) -> tuple[int, int, int]:
            pos, info = item
            if info.header is not None:
                return (0, info.header.file_index, pos)
            named = _name_key(info.path)
            return (0, named[1], pos) if named else (1, pos, pos)

        self.files = tuple(info for _, info in sorted(enumerate(infos), key=key))
        _check_distinct(self.files)
        _check_overlaps(self.files)
        indices = sorted(i.header.file_index for i in self.files if i.header is not None)
        missing = []
        if indices:
            missing = sorted(set(range(indices[0], indices[-1] + 1)) - set(indices))
        self.missing_file_indices = tuple(missing)
        self._report: LogReport | None = None
        self._warnings: list[str] = []

    @property
    def report(self) -> LogReport | None:
        """Return the LogReport once the iteration has finished, else None."""
        return self._report

    def __iter__(self) -> Iterator[LogBlock]:
        dec = self._decoder_class()
        config: _Config = (None, None, None)
        regions: list[CorruptRegion] = []
        region_count = 0
        no_config = 0
        file_starts = []
        for info in self.files:
            start = dec.stats.bytes_total
            file_starts.append(start)
            try:
                fh = open(info.path, 'rb')
            except OSError as err:
                raise InputDataError(f'cannot read log file {info.path!r}: {err}') from err
            with fh:
                while True:
                    data = fh.read(self.chunk_bytes)
                    res = dec.feed(data) if data else dec.flush()
                    for off, length in res.discarded:
                        region_count += 1
                        if len(regions) < MAX_REPORTED_REGIONS:
                            regions.append(CorruptRegion(info.path, off - start, length))
                    blocks, config = self._split(info.path, res, config)
                    for block in blocks:
                        if block.gyro_fs_dps is None:
                            no_config += block.samples.size
                        yield block
                    if not data:
                        break
        self._report = LogReport(files=self.files, stats=dec.stats, corrupt_regions=tuple(regions),
                                 corrupt_region_count=region_count,
                                 missing_file_indices=self.missing_file_indices,
                                 sequence_id=self.sequence_id, samples_without_config=no_config,
                                 warnings=tuple(self._warnings))

    @staticmethod
    def _split(path: str, res: DecodeResult, config: _Config) -> tuple[list[LogBlock], _Config]:
        """
        Cut a DecodeResult at configuration changes.

        Return (blocks, configuration after them).
        """
        events = []
        for pos, head in zip(res.header_positions, res.headers):
            events.append((pos, (head.odr_hz, head.gyro_fs_dps, head.accel_fs_g)))
        for pos, ack in zip(res.ack_positions, res.acks):
            if ack.ok:
                events.append((pos, (ack.odr_hz, ack.gyro_fs_dps, ack.accel_fs_g)))
        events.sort(key=lambda e: e[0])
        blocks = []
        start = 0
        for pos, new_config in events + [(res.samples.size, None)]:
            if pos > start:
                blocks.append(LogBlock(path, res.samples[start:pos], res.lost_before[start:pos],
                                       *config))
                start = pos
            if new_config is not None:
                config = new_config
        return blocks, config
