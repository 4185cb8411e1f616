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

The byte-wise part of :meth:`ScanDecoder._run` is a copy of ``Decoder._run`` with the compiled
loop inserted at each sync marker; a change of the Decoder's rules must be made in both
(``test/test_link_scan.py`` fails when they differ).
"""

import zlib

import numba
import numpy as np

from .protocol import (
    _Collector,
    _CRC,
    _EMPTY_LOST,
    _EMPTY_SAMPLES,
    _HEADER,
    _LENGTH_RULES,
    CRC_SIZE,
    Decoder,
    DecodeResult,
    FRAME_ACK,
    FRAME_CONFIGURE,
    FRAME_LOG_HEADER,
    FRAME_SAMPLES,
    HEADER_SIZE,
    PROTOCOL_VERSION,
    SAMPLE_DTYPE,
    SAMPLE_SIZE,
    SYNC,
)
from .protocol import _decode_ack, _decode_configure, _decode_log_header


def _crc_tables():
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
def _crc32(buf, start, stop, t):  # pragma: no cover - compiled; tested through crc32_numba
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
def _scan_samples(buf, pos, n, out, out_pos, t, version, ftype, min_len, max_len,
                  step):  # pragma: no cover - compiled; tested through ScanDecoder
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
        if _crc32(buf, pos, end, t) != stored:
            break
        out[out_pos:out_pos + length] = buf[pos + HEADER_SIZE:end]
        out_pos += length
        pos = end + CRC_SIZE
        frames += 1
    return pos, out_pos, frames


def crc32_numba(data):
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


_SAMPLES_RULE = _LENGTH_RULES[FRAME_SAMPLES]


class ScanDecoder(Decoder):
    """
    :class:`~gyro_noise_ros.link.protocol.Decoder` that consumes runs of SAMPLES frames compiled.

    Same interface, same results for the same input (see the module docstring). Made for long
    recordings (the SD-log importer); the per-call overhead of the compiled loop is a few
    microseconds, negligible for blocks of kilobytes.
    """

    def _run(self, *, final):
        buf = self._buf
        n = len(buf)
        pos = 0
        res = _Collector()
        c = self._c
        find = buf.find
        unpack_header = _HEADER.unpack_from
        crc_unpack = _CRC.unpack_from
        rules = _LENGTH_RULES
        mv = memoryview(buf)
        arr = np.frombuffer(buf, np.uint8) if n else np.zeros(0, np.uint8)
        out = np.empty(n, np.uint8)
        out_pos = 0
        lo, hi, step = _SAMPLES_RULE
        try:
            while True:
                if n - pos < 2:
                    if final and pos < n:
                        self._discard_to(pos, n)
                        pos = n
                    break
                if buf[pos] != 0xA5 or buf[pos + 1] != 0x5A:
                    nxt = find(SYNC, pos + 1)
                    if nxt < 0:
                        # keep a trailing A5: it may be the first half of the next sync marker
                        nxt = n - 1 if (buf[n - 1] == 0xA5 and not final) else n
                    self._discard_to(pos, nxt)
                    pos = nxt
                    continue
                if self._disc_start is None:
                    # the compiled run; a frame that ends a discarded region goes the byte-wise
                    # way below (it closes the region)
                    new_pos, new_out, frames = _scan_samples(
                        arr, pos, n, out, out_pos, CRC_TABLES, PROTOCOL_VERSION, FRAME_SAMPLES,
                        lo, hi, step)
                    if frames:
                        c['frames_ok'] += frames
                        res.nsamples += (new_out - out_pos) // SAMPLE_SIZE
                        pos, out_pos = new_pos, new_out
                        continue
                if n - pos < HEADER_SIZE:
                    if final:
                        c['frames_truncated'] += 1
                        self._discard_to(pos, pos + 1)
                        pos += 1
                        continue
                    break
                _, version, ftype, length = unpack_header(buf, pos)
                rule = rules.get(ftype)
                if (
                    version != PROTOCOL_VERSION
                    or rule is None
                    or length < rule[0]
                    or length > rule[1]
                    or length % rule[2]
                ):
                    self._discard_to(pos, pos + 1)
                    pos += 1
                    continue
                end = pos + HEADER_SIZE + length
                if end + CRC_SIZE > n:
                    if final:
                        c['frames_truncated'] += 1
                        self._discard_to(pos, pos + 1)
                        pos += 1
                        continue
                    break
                if zlib.crc32(mv[pos:end]) != crc_unpack(buf, end)[0]:
                    c['crc_errors'] += 1
                    self._discard_to(pos, pos + 1)
                    pos += 1
                    continue
                # a valid frame: any discarded region ends here
                if self._disc_start is not None:
                    self._close_region(res, self._base + pos)
                c['frames_ok'] += 1
                payload_start = pos + HEADER_SIZE
                if ftype == FRAME_SAMPLES:
                    out[out_pos:out_pos + length] = arr[payload_start:end]
                    out_pos += length
                    res.nsamples += length // SAMPLE_SIZE
                elif ftype == FRAME_ACK:
                    res.acks.append(_decode_ack(mv[payload_start:end]))
                    res.ack_positions.append(res.nsamples)
                elif ftype == FRAME_CONFIGURE:
                    res.commands.append(_decode_configure(mv[payload_start:end]))
                elif ftype == FRAME_LOG_HEADER:
                    res.headers.append(_decode_log_header(mv[payload_start:end]))
                    res.header_positions.append(res.nsamples)
                pos = end + CRC_SIZE
        finally:
            del arr
            mv.release()
        if final:
            self._close_region(res, self._base + pos)
        # the carry-over (at most one partial frame) goes to a new buffer: ``buf`` may still be
        # exported (numba holds its arguments while it compiles), so it cannot be resized
        self._buf = buf[pos:]
        self._base += pos
        return _result(res, self, out[:out_pos])


def _result(res, dec, payload):
    """Return what ``_Collector.result`` returns, the samples taken from one payload array."""
    c = dec._c
    c['acks'] += len(res.acks)
    c['naks'] += sum(1 for a in res.acks if not a.ok)
    c['commands'] += len(res.commands)
    c['log_headers'] += len(res.headers)
    ack_pos, head_pos = tuple(res.ack_positions), tuple(res.header_positions)
    if payload.size:
        samples = payload.view(SAMPLE_DTYPE)
        samples, lost, ack_pos, head_pos = dec._account_samples(samples, ack_pos, head_pos)
    else:
        samples, lost = _EMPTY_SAMPLES, _EMPTY_LOST
    return DecodeResult(samples=samples, acks=tuple(res.acks), lost_before=lost,
                        ack_positions=ack_pos, commands=tuple(res.commands),
                        headers=tuple(res.headers), header_positions=head_pos,
                        discarded=tuple(res.discarded))
