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
Compiled frame scanner: the :class:`~gyro_noise_ros.link.protocol.Decoder` for long streams.

:class:`ScanDecoder` is a :class:`~gyro_noise_ros.link.protocol.Decoder` whose results are the
same, call for call: same samples, positions, discarded regions and counters for any bytes fed
in any pieces (``test/test_link_scan.py`` checks it against the Decoder on corrupted streams and
under hypothesis). It differs only in how a clean stretch of SAMPLES frames is consumed: one
compiled loop (numba) walks frame after frame over the whole buffered block, checks sync marker,
version, type, length bounds and CRC-32 (slicing-by-8 table CRC of the protocol's polynomial,
checked against ``zlib.crc32``) and copies the payloads into one sample array, with no Python
step per frame. The loop stops at the first byte that is not the start of a complete valid
SAMPLES frame; from there the Decoder's own byte-wise rules run unchanged (other frame types,
bad CRCs, junk, resynchronisation, truncated frames) until the next sync marker, where the loop
takes over again.

The scanner keeps no more than the Decoder does: the bytes of the frame cut by the end of a
block wait for the next block (the carry-over).

The byte-wise rules are the Decoder's own ``_run``: the scanner overrides only its hooks (the
bulk path at each sync marker, where a SAMPLES frame's payload goes, how the run ends), so a
change of the rules applies to both (``test/test_link_scan.py`` checks them call for call).
"""

import numba
import numpy as np
from numpy.typing import NDArray

from .protocol import (
    _Collector,
    _SAMPLES_RULE,
    CRC_SIZE,
    Decoder,
    DecodeResult,
    FRAME_SAMPLES,
    HEADER_SIZE,
    PROTOCOL_VERSION,
    SAMPLE_SIZE,
)


def _crc_tables() -> NDArray[np.uint32]:
    """Slicing-by-8 tables of the reflected CRC-32 polynomial 0xEDB88320, shape (8, 256)."""
    table = np.zeros((8, 256), np.uint32)
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0xEDB88320 if c & 1 else c >> 1
        table[0, i] = c
    for k in range(1, 8):
        prev = table[k - 1]
        table[k] = (prev >> np.uint32(8)) ^ table[0][prev & np.uint32(0xFF)]
    return table


CRC_TABLES = _crc_tables()


@numba.njit(cache=True, nogil=True)
def _crc32(  # pragma: no cover - compiled; tested through crc32_numba
        buf: NDArray[np.uint8], start: int, stop: int, t: NDArray[np.uint32]) -> np.uint32:
    crc = np.uint32(0xFFFFFFFF)
    p = start
    while p + 8 <= stop:
        one = crc ^ (np.uint32(buf[p]) | (np.uint32(buf[p + 1]) << np.uint32(8))
                     | (np.uint32(buf[p + 2]) << np.uint32(16))
                     | (np.uint32(buf[p + 3]) << np.uint32(24)))
        crc = (t[7, one & np.uint32(0xFF)] ^ t[6, (one >> np.uint32(8)) & np.uint32(0xFF)]
               ^ t[5, (one >> np.uint32(16)) & np.uint32(0xFF)] ^ t[4, one >> np.uint32(24)]
               ^ t[3, buf[p + 4]] ^ t[2, buf[p + 5]] ^ t[1, buf[p + 6]] ^ t[0, buf[p + 7]])
        p += 8
    while p < stop:
        crc = t[0, (crc ^ np.uint32(buf[p])) & np.uint32(0xFF)] ^ (crc >> np.uint32(8))
        p += 1
    return crc ^ np.uint32(0xFFFFFFFF)


@numba.njit(cache=True, nogil=True)
def _scan_samples(  # pragma: no cover - compiled; tested through ScanDecoder
        buf: NDArray[np.uint8], pos: int, n: int, out: NDArray[np.uint8], out_pos: int,
        t: NDArray[np.uint32], version: int, ftype: int, min_len: int, max_len: int,
        step: int) -> tuple[int, int, int]:
    """
    Consume the complete valid SAMPLES frames that follow each other from ``pos``.

    Returns (position after the last one, new out_pos, frames).
    """
    frames = 0
    while n - pos >= HEADER_SIZE:
        if (buf[pos] != 0xA5 or buf[pos + 1] != 0x5A or buf[pos + 2] != version
                or buf[pos + 3] != ftype):
            break
        length = np.int64(buf[pos + 4]) | (np.int64(buf[pos + 5]) << 8)
        if length < min_len or length > max_len or length % step != 0:
            break
        end = pos + HEADER_SIZE + length
        if end + CRC_SIZE > n:
            break
        stored = (np.uint32(buf[end]) | (np.uint32(buf[end + 1]) << np.uint32(8))
                  | (np.uint32(buf[end + 2]) << np.uint32(16))
                  | (np.uint32(buf[end + 3]) << np.uint32(24)))
        # numba types these int64 (the np.int64 of ``length``) and boxes them as int on return
        if _crc32(buf, pos, end, t) != stored:  # type: ignore[arg-type]
            break
        out[out_pos:out_pos + length] = buf[pos + HEADER_SIZE:end]
        out_pos += length  # type: ignore[assignment]
        pos = end + CRC_SIZE  # type: ignore[assignment]
        frames += 1
    return pos, out_pos, frames


def crc32_numba(data: bytes | bytearray | memoryview) -> int:
    """
    Return the frame CRC of ``data`` computed by the compiled table CRC (equals ``zlib.crc32``).

    Parameters
    ----------
    data : bytes-like
        Bytes to checksum.

    Returns
    -------
    int

    """
    arr = np.frombuffer(data, np.uint8)
    return int(_crc32(arr, 0, arr.size, CRC_TABLES))


class ScanDecoder(Decoder):
    """
    :class:`~gyro_noise_ros.link.protocol.Decoder` that consumes runs of SAMPLES frames compiled.

    Same interface, same results for the same input (see the module docstring). Made for long
    recordings (the SD-log importer); the per-call overhead of the compiled loop is a few
    microseconds, negligible for blocks of kilobytes.
    """

    def _start_run(self, buf: bytearray, n: int) -> '_ScanRun':
        # the samples of the run are copied into one array (no more bytes than the buffer holds)
        return _ScanRun(np.frombuffer(buf, np.uint8) if n else np.zeros(0, np.uint8),
                        np.empty(n, np.uint8))

    def _run_frames(self, run: '_ScanRun', pos: int, n: int, res: _Collector) -> int:
        lo, hi, step = _SAMPLES_RULE
        assert run.arr is not None  # released only when the run ends
        new_pos, new_out, frames = _scan_samples(
            run.arr, pos, n, run.out, run.out_pos, CRC_TABLES, PROTOCOL_VERSION, FRAME_SAMPLES,
            lo, hi, step)
        if frames:
            self._c['frames_ok'] += frames
            res.nsamples += (new_out - run.out_pos) // SAMPLE_SIZE
            run.out_pos = new_out
        return new_pos

    def _samples_frame(self, run: '_ScanRun', mv: memoryview, pos: int, end: int, n: int,
                       res: _Collector) -> int:
        start = pos + HEADER_SIZE
        assert run.arr is not None  # released only when the run ends
        run.out[run.out_pos:run.out_pos + end - start] = run.arr[start:end]
        run.out_pos += end - start
        res.nsamples += (end - start) // SAMPLE_SIZE
        return end + CRC_SIZE

    def _finish_run(self, run: '_ScanRun', buf: bytearray, pos: int,
                    res: _Collector) -> DecodeResult:
        # the carry-over (at most one partial frame) goes to a new buffer: ``buf`` may still be
        # exported (numba holds its arguments while it compiles), so it cannot be resized
        run.arr = None
        self._buf = buf[pos:]
        self._base += pos
        return res.result(self, run.out[:run.out_pos])


class _ScanRun:
    """State of one ``ScanDecoder._run``: the buffer as an array, the samples gathered so far."""

    __slots__ = ('arr', 'out', 'out_pos')

    def __init__(self, arr: NDArray[np.uint8], out: NDArray[np.uint8]) -> None:
        self.arr: NDArray[np.uint8] | None = arr
        self.out = out
        self.out_pos = 0
