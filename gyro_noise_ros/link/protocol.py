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
Portenta link wire protocol: frame codec with resynchronisation and loss counters (pure, no I/O).

The contract a firmware author implements is ``docs/portenta_link.md``; this module is its
reference implementation. In short, every frame is little-endian::

    offset size field
    0      2    sync marker A5 5A
    2      1    protocol version (1)
    3      1    frame type (SAMPLES 0x01, CONFIGURE 0x02, ACK 0x03, LOG_HEADER 0x04)
    4      2    payload length in bytes (uint16)
    6      N    payload
    6+N    4    CRC-32 (IEEE 802.3: poly 0x04C11DB7 reflected, init 0xFFFFFFFF, xorout 0xFFFFFFFF)
                over bytes 0 .. 6+N-1 (sync, header and payload); check value of b"123456789" is
                0xCBF43926 (= zlib.crc32)

A SAMPLES payload is 1..MAX_SAMPLES_PER_FRAME records of :data:`SAMPLE_DTYPE` (24 bytes each).

The :class:`Decoder` never raises on bad bytes: it checks the header (version, type, length bounds
of the type) and then the CRC before it decodes anything, and on any failure it drops one byte and
searches for the next sync marker. Counters (:class:`LinkStats`) say what happened.
"""

from dataclasses import dataclass, field
import struct
from typing import Any
import zlib

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from .sequence import consecutive
from ..errors import ParameterError

SYNC = b'\xa5\x5a'
PROTOCOL_VERSION = 1

FRAME_SAMPLES = 0x01
FRAME_CONFIGURE = 0x02
FRAME_ACK = 0x03
FRAME_LOG_HEADER = 0x04

HEADER_SIZE = 6
CRC_SIZE = 4
FRAME_OVERHEAD = HEADER_SIZE + CRC_SIZE

#: One sample as it travels on the wire and sits on the SD card (24 bytes, little-endian, packed).
SAMPLE_DTYPE = np.dtype([
    # per-sample counter, +1 per sample the board read from the sensor, wraps at 2**32
    ('seq', '<u4'),
    ('t_us', '<u4'),       # board time of the sample in microseconds, wraps at 2**32 (71.6 min)
    ('gyro', '<i2', (3,)),   # raw OUTX/Y/Z_G
    ('accel', '<i2', (3,)),  # raw OUTX/Y/Z_A
    ('temp', '<i2'),       # raw OUT_TEMP
    ('flags', 'u1'),       # FLAG_* bits
    ('reserved', 'u1'),    # 0 on send, ignored on receive
])
SAMPLE_SIZE = SAMPLE_DTYPE.itemsize
assert SAMPLE_SIZE == 24

#: The sensor FIFO overran before this sample: the sensor dropped samples the board never saw (not
#: in seq).
FLAG_FIFO_OVERRUN = 0x01
#: The board dropped samples just before this one (buffer full, SD busy); the seq gap says how
#: many.
FLAG_SAMPLE_LOST = 0x02

MAX_SAMPLES_PER_FRAME = 128
MAX_MESSAGE_BYTES = 64

_CONFIGURE = struct.Struct('<IIHBB')      # command_id, odr_mhz, gyro_fs_dps, accel_fs_g, reserved
_ACK = struct.Struct('<IBBHI')            # command_id, status, accel_fs_g, gyro_fs_dps, odr_mhz
# sequence_id, file_index, odr_mhz, gyro_fs, accel_fs, reserved,
_LOG_HEADER = struct.Struct('<IIIHBBIII')
#                                           first_seq, t_us, rtc_unix_s
_HEADER = struct.Struct('<2sBBH')
_CRC = struct.Struct('<I')

#: ACK status codes (0 = accepted; anything else is a NAK and the configuration is unchanged).
ACK_OK = 0
NAK_BAD_ODR = 1
NAK_BAD_GYRO_FS = 2
NAK_BAD_ACCEL_FS = 3
NAK_BUSY = 4
NAK_UNSPECIFIED = 255

#: Payload length bounds (inclusive) and granularity per frame type.
_LENGTH_RULES = {
    FRAME_SAMPLES: (SAMPLE_SIZE, SAMPLE_SIZE * MAX_SAMPLES_PER_FRAME, SAMPLE_SIZE),
    FRAME_CONFIGURE: (_CONFIGURE.size, _CONFIGURE.size, 1),
    FRAME_ACK: (_ACK.size, _ACK.size + MAX_MESSAGE_BYTES, 1),
    FRAME_LOG_HEADER: (_LOG_HEADER.size, _LOG_HEADER.size, 1),
}
_SAMPLES_RULE = _LENGTH_RULES[FRAME_SAMPLES]
MAX_FRAME_SIZE = FRAME_OVERHEAD + max(rule[1] for rule in _LENGTH_RULES.values())
_BULK_MAX_FRAME = FRAME_OVERHEAD + 32 * SAMPLE_SIZE


def _mhz(odr_hz: float) -> int:
    return int(round(float(odr_hz) * 1000.0))


@dataclass(frozen=True)
class Ack:
    """
    Board answer to a CONFIGURE command, and the configuration in force after it.

    Attributes
    ----------
    command_id : int
        Echo of the command's id (uint32).
    ok : bool
        True for an ACK (applied), False for a NAK (configuration unchanged).
    odr_hz : float
        Output data rate in force (Hz).
    gyro_fs_dps : int
        Gyro full scale in force (deg/s).
    accel_fs_g : int
        Accelerometer full scale in force (g).
    message : str
        Human-readable reason (ASCII, at most 64 bytes on the wire); empty for a plain ACK.
    status : int
        Wire status code (ACK_OK or a NAK_* code). 0 with ``ok=False`` is sent as NAK_UNSPECIFIED.

    """

    command_id: int
    ok: bool
    odr_hz: float
    gyro_fs_dps: int
    accel_fs_g: int
    message: str = ''
    status: int = 0


@dataclass(frozen=True)
class Configure:
    """
    Host-to-board request to set the output data rate and the full scales.

    Attributes
    ----------
    command_id : int
        Chosen by the host (uint32), echoed in the Ack.
    odr_hz : float
        Requested output data rate (Hz), one of ``lsm6dso32.ODRS_HZ``.
    gyro_fs_dps : int
        Requested gyro full scale (deg/s).
    accel_fs_g : int
        Requested accelerometer full scale (g).

    """

    command_id: int
    odr_hz: float
    gyro_fs_dps: int
    accel_fs_g: int


@dataclass(frozen=True)
class LogHeader:
    """
    First frame of every SD log file.

    Attributes
    ----------
    sequence_id : int
        Acquisition sequence (one power-on recording) this file belongs to.
    file_index : int
        0, 1, 2, ... within the sequence.
    odr_hz : float
        Output data rate at file open (Hz).
    gyro_fs_dps, accel_fs_g : int
        Full scales at file open (deg/s, g).
    first_seq : int
        ``seq`` of the first sample written to this file.
    t_us : int
        Board time (us, same clock as the samples) when the file was opened.
    rtc_unix_s : int
        Real-time clock (UNIX seconds) at ``t_us``; 0 when the board's RTC is not set.

    """

    sequence_id: int
    file_index: int
    odr_hz: float
    gyro_fs_dps: int
    accel_fs_g: int
    first_seq: int
    t_us: int
    rtc_unix_s: int = 0


@dataclass(frozen=True)
class LinkStats:
    """
    Cumulative decoder counters (a frozen snapshot).

    Attributes
    ----------
    frames_ok : int
        Frames with a valid header and CRC (any type).
    crc_errors : int
        Candidate frames with a plausible header whose CRC did not match.
    resyncs : int
        Contiguous regions of discarded bytes (each time alignment was lost and found again).
    bytes_discarded : int
        Bytes that were not part of any valid frame.
    samples_ok : int
        Samples delivered.
    samples_lost : int
        Samples missing according to the sequence counter (gaps, across wrap-around).
    samples_flagged_lost : int
        Part of ``samples_lost`` the board reported itself (gaps before samples with
        FLAG_SAMPLE_LOST).
    acks : int
        ACK/NAK frames received.
    naks : int
        Of those, NAKs.
    loss_flags : int
        Samples carrying FLAG_SAMPLE_LOST.
    fifo_overruns : int
        Samples carrying FLAG_FIFO_OVERRUN.
    duplicates : int
        Samples dropped because their seq equals the previous sample's.
    sequence_resets : int
        Backward jumps of seq (board restart); no loss is counted for them.
    frames_truncated : int
        Candidate frames cut by the end of input at :meth:`Decoder.flush`.
    commands : int
        CONFIGURE frames decoded (board side).
    log_headers : int
        LOG_HEADER frames decoded.
    bytes_total : int
        Bytes fed.

    """

    frames_ok: int = 0
    crc_errors: int = 0
    resyncs: int = 0
    bytes_discarded: int = 0
    samples_ok: int = 0
    samples_lost: int = 0
    samples_flagged_lost: int = 0
    acks: int = 0
    naks: int = 0
    loss_flags: int = 0
    fifo_overruns: int = 0
    duplicates: int = 0
    sequence_resets: int = 0
    frames_truncated: int = 0
    commands: int = 0
    log_headers: int = 0
    bytes_total: int = 0


_EMPTY_SAMPLES = np.zeros(0, dtype=SAMPLE_DTYPE)
_EMPTY_LOST = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class DecodeResult:
    """
    What one :meth:`Decoder.feed` produced.

    Attributes
    ----------
    samples : numpy.ndarray
        Decoded samples (:data:`SAMPLE_DTYPE`), in arrival order, duplicates removed.
    acks : tuple of Ack
        ACK/NAK frames in arrival order.
    lost_before : numpy.ndarray
        int64, one per sample: samples missing just before it according to the counter.
    ack_positions : tuple of int
        For each ack, how many of ``samples`` arrived before it (where the configuration changed).
    commands : tuple of Configure
        CONFIGURE frames (what a board receives).
    headers : tuple of LogHeader
        LOG_HEADER frames (SD log files).
    header_positions : tuple of int
        For each header, how many of ``samples`` came before it.
    discarded : tuple of (int, int)
        ``(offset, length)`` of each discarded region that ended during this call; offsets count
        bytes fed to this decoder since it was created.

    """

    samples: np.ndarray = field(default_factory=lambda: _EMPTY_SAMPLES)
    acks: tuple[Ack, ...] = ()
    lost_before: np.ndarray = field(default_factory=lambda: _EMPTY_LOST)
    ack_positions: tuple[int, ...] = ()
    commands: tuple[Configure, ...] = ()
    headers: tuple[LogHeader, ...] = ()
    header_positions: tuple[int, ...] = ()
    discarded: tuple[tuple[int, int], ...] = ()


def _frame(frame_type: int, payload: bytes) -> bytes:
    head = _HEADER.pack(SYNC, PROTOCOL_VERSION, frame_type, len(payload))
    body = head + payload
    return body + _CRC.pack(zlib.crc32(body))


def encode_samples(samples: npt.ArrayLike) -> bytes:
    """
    Encode samples as SAMPLES frames.

    Parameters
    ----------
    samples : numpy.ndarray
        Records with the fields of :data:`SAMPLE_DTYPE` (1-D).

    Returns
    -------
    bytes
        One frame, or consecutive frames of at most MAX_SAMPLES_PER_FRAME samples each when more
        are given; empty for no samples.

    """
    arr = np.asarray(samples)
    if arr.ndim != 1:
        raise ParameterError(f'samples must be 1-D, got shape {arr.shape}')
    if arr.dtype != SAMPLE_DTYPE:
        try:
            conv = np.zeros(arr.shape, dtype=SAMPLE_DTYPE)
            for name in SAMPLE_DTYPE.names or ():  # a structured dtype: never None
                if name in (arr.dtype.names or ()):
                    conv[name] = arr[name]
        except (TypeError, ValueError) as err:
            raise ParameterError(
                f'samples must have the fields of SAMPLE_DTYPE, got {arr.dtype}') from err
        arr = conv
    out = []
    for start in range(0, arr.size, MAX_SAMPLES_PER_FRAME):
        out.append(_frame(FRAME_SAMPLES, arr[start:start + MAX_SAMPLES_PER_FRAME].tobytes()))
    return b''.join(out)


def _check_u32(name: str, value: int) -> int:
    value = int(value)
    if not 0 <= value < 2 ** 32:
        raise ParameterError(f'{name} must fit in uint32, got {value}')
    return value


def encode_configure(*, command_id: int, odr_hz: float, gyro_fs_dps: int,
                     accel_fs_g: int) -> bytes:
    """
    Encode a host-to-board CONFIGURE frame.

    Parameters
    ----------
    command_id : int
        uint32 chosen by the host; the board echoes it in the Ack.
    odr_hz : float
        Output data rate (Hz); sent in millihertz (uint32).
    gyro_fs_dps : int
        Gyro full scale (deg/s), uint16.
    accel_fs_g : int
        Accelerometer full scale (g), uint8.

    Returns
    -------
    bytes

    """
    command_id = _check_u32('command_id', command_id)
    odr_mhz = _check_u32('odr_hz (in mHz)', _mhz(odr_hz))
    if not 0 <= int(gyro_fs_dps) < 2 ** 16:
        raise ParameterError(f'gyro_fs_dps must fit in uint16, got {gyro_fs_dps}')
    if not 0 <= int(accel_fs_g) < 2 ** 8:
        raise ParameterError(f'accel_fs_g must fit in uint8, got {accel_fs_g}')
    return _frame(FRAME_CONFIGURE, _CONFIGURE.pack(command_id, odr_mhz, int(gyro_fs_dps),
                                                   int(accel_fs_g), 0))


def encode_ack(ack: Ack) -> bytes:
    """
    Encode a board-to-host ACK (``ack.ok``) or NAK frame.

    Parameters
    ----------
    ack : Ack
        The acknowledgement to encode.

    Returns
    -------
    bytes

    """
    status = ACK_OK if ack.ok else (int(ack.status) or NAK_UNSPECIFIED)
    msg = str(ack.message).encode('ascii', 'replace')[:MAX_MESSAGE_BYTES]
    payload = _ACK.pack(_check_u32('command_id', ack.command_id), status, int(ack.accel_fs_g)
                        & 0xFF, int(ack.gyro_fs_dps) & 0xFFFF,
                        _check_u32('odr_hz (in mHz)', _mhz(ack.odr_hz)))
    return _frame(FRAME_ACK, payload + msg)


def encode_log_header(header: LogHeader) -> bytes:
    """
    Encode the LOG_HEADER frame that starts every SD log file.

    Parameters
    ----------
    header : LogHeader
        The header to encode.

    Returns
    -------
    bytes

    """
    payload = _LOG_HEADER.pack(
        _check_u32('sequence_id', header.sequence_id), _check_u32('file_index', header.file_index),
        _check_u32('odr_hz (in mHz)', _mhz(header.odr_hz)), int(header.gyro_fs_dps) & 0xFFFF,
        int(header.accel_fs_g) & 0xFF, 0, _check_u32('first_seq', header.first_seq),
        _check_u32('t_us', header.t_us), _check_u32('rtc_unix_s', header.rtc_unix_s))
    return _frame(FRAME_LOG_HEADER, payload)


def crc32(data: bytes | bytearray | memoryview) -> int:
    """Return the frame CRC of ``data`` (CRC-32/IEEE, see the module docstring)."""
    return zlib.crc32(data) & 0xFFFFFFFF


_STAT_FIELDS = tuple(LinkStats.__dataclass_fields__)


class Decoder:
    """
    Incremental frame decoder: feed it bytes in any pieces, get samples, acks and counters.

    ``feed`` never raises, whatever the bytes. A candidate frame is accepted only when the sync
    marker, version, type and the type's length bounds are right *and* the CRC matches; otherwise
    one byte is dropped and the search for the next sync marker goes on, so a valid frame is never
    lost behind a corrupt one. A frame cut by the end of the input stays buffered until more bytes
    come or :meth:`flush` declares the input finished.

    The sequence counter is tracked across calls (and across :meth:`reset_stream`): the gap between
    consecutive samples, modulo 2**32, minus one, is the number of samples lost; a backward jump
    (gap of 2**31 or more) is a board restart and counts no loss; an equal seq is a duplicate and
    is dropped.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self._base = 0          # stream offset of self._buf[0]
        # stream offset where the current discarded region began
        self._disc_start: int | None = None
        self._last_seq: int | None = None
        self._c = dict.fromkeys(_STAT_FIELDS, 0)

    @property
    def stats(self) -> LinkStats:
        """LinkStats: frozen snapshot of the cumulative counters."""
        return LinkStats(**self._c)

    def counters(self) -> dict[str, int]:
        """Return the cumulative counters as a new dict (LinkStats' fields; cheaper per read)."""
        return dict(self._c)

    @property
    def last_seq(self) -> int | None:
        """Return the seq of the last delivered sample, or None."""
        return self._last_seq

    @property
    def buffered(self) -> int:
        """int: bytes held waiting for the rest of a frame."""
        return len(self._buf)

    def reset_stream(self) -> DecodeResult:
        """
        Drop buffered bytes (new connection) but keep the counters and the sequence continuity.

        Returns
        -------
        DecodeResult
            The discarded partial region, if any (counted in bytes_discarded).

        """
        try:
            return self._finish(truncate=True, drop_all=True)
        except Exception:  # pragma: no cover - defensive: never raise
            self._buf = bytearray()
            return DecodeResult()

    def flush(self) -> DecodeResult:
        """
        Declare the end of the input: decode what can be decoded and discard the rest.

        Returns
        -------
        DecodeResult

        """
        try:
            return self._finish(truncate=True, drop_all=False)
        except Exception:  # pragma: no cover - defensive: never raise
            self._buf = bytearray()
            return DecodeResult()

    def feed(self, data: bytes | bytearray | memoryview | None) -> DecodeResult:
        """
        Add received bytes and decode every complete frame.

        Parameters
        ----------
        data : bytes-like
            Any bytes (any length, any content).

        Returns
        -------
        DecodeResult

        Raises
        ------
        ParameterError
            Only when ``data`` is not bytes-like at all (a programming error, not bad input bytes).

        """
        if data is not None and not isinstance(data, (bytes, bytearray, memoryview)):
            raise ParameterError(f'data must be bytes-like, got {type(data).__name__}')
        try:
            if type(data) is bytes and not self._buf:
                one = self._one_frame(data)
                if one is not None:
                    return one
            if data:
                mv = memoryview(data).cast('B')
                self._buf += mv
                self._c['bytes_total'] += len(mv)
            return self._run(final=False)
        except Exception:  # pragma: no cover - defensive: the contract is never to raise
            self._c['bytes_discarded'] += len(self._buf)
            self._base += len(self._buf)
            self._buf = bytearray()
            return DecodeResult()

    def _one_frame(self, data: bytes) -> DecodeResult | None:
        """
        Decode the usual live read: exactly one valid SAMPLES frame, nothing buffered before it.

        Returns what :meth:`_run` returns for it (tested on random streams against the decoder
        without this path), or None for anything else, which then goes the general way.
        """
        n = len(data)
        if n < FRAME_OVERHEAD or self._disc_start is not None:
            return None
        sync, version, ftype, length = _HEADER.unpack_from(data)
        end = HEADER_SIZE + length
        lo, hi, step = _SAMPLES_RULE
        if (n != end + CRC_SIZE or sync != SYNC or version != PROTOCOL_VERSION
                or ftype != FRAME_SAMPLES or length < lo or length > hi or length % step
                or zlib.crc32(memoryview(data)[:end]) != _CRC.unpack_from(data, end)[0]):
            return None
        c = self._c
        c['bytes_total'] += n
        c['frames_ok'] += 1
        self._base += n
        samples = np.frombuffer(data, SAMPLE_DTYPE, length // SAMPLE_SIZE, HEADER_SIZE).copy()
        samples, lost, _, _ = self._account_samples(samples, (), ())
        return DecodeResult(samples=samples, lost_before=lost)

    def _finish(self, *, truncate: bool, drop_all: bool) -> DecodeResult:
        if drop_all:
            res = _Collector()
            n = len(self._buf)
            if n:
                self._discard_to(0, n)
                del self._buf[:]
                self._base += n
            self._close_region(res, self._base)
            return res.result(self)
        return self._run(final=truncate)

    def _discard_to(self, pos: int, new_pos: int) -> None:
        if self._disc_start is None:
            self._disc_start = self._base + pos
        self._c['bytes_discarded'] += new_pos - pos

    def _close_region(self, res: '_Collector', end_offset: int) -> None:
        if self._disc_start is not None:
            res.discarded.append((self._disc_start, end_offset - self._disc_start))
            self._c['resyncs'] += 1
            self._disc_start = None

    def _run(self, *, final: bool) -> DecodeResult:
        buf = self._buf
        n = len(buf)
        pos = 0
        res = _Collector()
        c = self._c
        unpack_header = _HEADER.unpack_from
        crc_unpack = _CRC.unpack_from
        rules = _LENGTH_RULES
        mv = memoryview(buf)
        run = self._start_run(buf, n)
        try:
            while True:
                if n - pos < 2:
                    if final and pos < n:
                        self._discard_to(pos, n)
                        pos = n
                    break
                if buf[pos] != 0xA5 or buf[pos + 1] != 0x5A:
                    pos = self._resync(buf, pos, n, final=final)
                    continue
                if run is not None and self._disc_start is None:
                    # a subclass's bulk path at each sync marker; a frame that ends a discarded
                    # region goes the byte-wise way below (it closes the region)
                    new_pos = self._run_frames(run, pos, n, res)
                    if new_pos != pos:
                        pos = new_pos
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
                if ftype == FRAME_SAMPLES:
                    pos = self._samples_frame(run, mv, pos, end, n, res)
                    continue
                _control_frame(res, ftype, mv[pos + HEADER_SIZE:end])
                pos = end + CRC_SIZE
        finally:
            mv.release()
        if final:
            self._close_region(res, self._base + pos)
        return self._finish_run(run, buf, pos, res)

    def _resync(self, buf: bytearray, pos: int, n: int, *, final: bool) -> int:
        """Discard from ``pos`` to the next sync marker (or the end); return where it starts."""
        nxt = buf.find(SYNC, pos + 1)
        if nxt < 0:
            # keep a trailing A5: it may be the first half of the next sync marker
            nxt = n - 1 if (buf[n - 1] == 0xA5 and not final) else n
        self._discard_to(pos, nxt)
        return nxt

    # Hooks of _run: this class decodes frame by frame; link.scan.ScanDecoder overrides them to
    # consume runs of SAMPLES frames in a compiled loop, with the byte-wise rules above unchanged.

    def _start_run(self, buf: bytearray, n: int) -> Any:
        """Return the state of a bulk path for one ``_run`` over ``buf[:n]``; None: none."""
        return None

    def _run_frames(self, run: Any, pos: int, n: int, res: '_Collector') -> int:
        """Consume complete valid frames from the sync marker at ``pos``; return the new pos."""
        return pos

    def _samples_frame(self, run: Any, mv: memoryview, pos: int, end: int, n: int,
                       res: '_Collector') -> int:
        """Take the valid SAMPLES frame at ``pos`` (payload up to ``end``); return the next pos."""
        length = end - pos - HEADER_SIZE
        res.payloads.append(bytes(mv[pos + HEADER_SIZE:end]))
        res.nsamples += length // SAMPLE_SIZE
        pos = end + CRC_SIZE
        size = FRAME_OVERHEAD + length
        # bulk path for small frames only: there the per-frame Python work dominates (2-5x
        # faster at 1-16 samples per frame); for large frames the CRC does and it gains nothing
        if size <= _BULK_MAX_FRAME and n - pos >= 4 * size:
            good = self._same_size_run(mv, pos, n, size, res)
            self._c['frames_ok'] += good
            pos += good * size
        return pos

    def _finish_run(self, run: Any, buf: bytearray, pos: int, res: '_Collector') -> DecodeResult:
        """Drop the consumed bytes from the buffer; return the DecodeResult of the run."""
        if pos:
            del buf[:pos]
            self._base += pos
        return res.result(self)

    @staticmethod
    def _same_size_run(mv: memoryview, pos: int, n: int, size: int, res: '_Collector') -> int:
        """
        Accept in bulk the valid SAMPLES frames at ``pos`` with the header just accepted.

        In a synchronised stream every frame of one batch size has the same 6 header bytes, so the
        header check runs on a (frames, size) byte matrix and only the CRC stays per frame. Stops
        at the first frame that differs or fails its CRC (the byte-wise path then deals with it).
        Returns the number of frames accepted.
        """
        m = (n - pos) // size
        block = np.frombuffer(mv, np.uint8, count=m * size, offset=pos).reshape(m, size)
        head = np.frombuffer(mv, np.uint8, count=HEADER_SIZE, offset=pos - size)
        same = (block[:, :HEADER_SIZE] == head).all(axis=1)
        k = m if same.all() else int(same.argmin())
        if k == 0:
            return 0
        stored = block[:k, size - CRC_SIZE:].copy().view('<u4').ravel()
        body = size - CRC_SIZE
        calc = np.fromiter((zlib.crc32(mv[q:q + body]) for q in range(pos, pos + k * size, size)),
                           dtype=np.uint32, count=k)
        ok = calc == stored
        good = k if ok.all() else int(ok.argmin())
        if good:
            res.payloads.append(block[:good, HEADER_SIZE:body].tobytes())
            res.nsamples += good * ((size - FRAME_OVERHEAD) // SAMPLE_SIZE)
        return good

    def _account_samples(self, samples: NDArray[np.void], ack_positions: tuple[int, ...],
                         header_positions: tuple[int, ...]
                         ) -> tuple[NDArray[np.void], NDArray[np.int64], tuple[int, ...],
                                    tuple[int, ...]]:
        """
        Counter bookkeeping over the decoded samples.

        Returns (kept samples, lost_before, positions).
        """
        c = self._c
        seq = samples['seq']
        n = seq.shape[0]
        last = self._last_seq
        # The usual read: the next counters in order, no flag set. The result is what the
        # general path below gives for it (tested on random batches).
        if (n and last is not None and (int(seq[0]) - last) % 2**32 == 1
                and (int(seq[-1]) - int(seq[0])) % 2**32 == n - 1
                and not samples['flags'].any() and consecutive(seq)):
            c['samples_ok'] += n
            self._last_seq = int(seq[-1])
            return samples, np.zeros(n, np.int64), ack_positions, header_positions
        return self._account_general(samples, ack_positions, header_positions)

    def _account_general(self, samples: NDArray[np.void], ack_positions: tuple[int, ...],
                         header_positions: tuple[int, ...]
                         ) -> tuple[NDArray[np.void], NDArray[np.int64], tuple[int, ...],
                                    tuple[int, ...]]:
        """:meth:`_account_samples` for any batch (gaps, repeats, restarts, flags)."""
        c = self._c
        seq = samples['seq']
        prev = np.empty_like(seq)
        prev[1:] = seq[:-1]
        first_known = self._last_seq is not None
        prev[0] = self._last_seq if first_known else seq[0]
        gap = (seq - prev).astype(np.uint32)  # modulo 2**32
        dup = gap == 0
        if not first_known:
            dup[0] = False
        lost = gap.astype(np.int64) - 1
        lost[lost < 0] = 0
        backward = gap >= np.uint32(2 ** 31)
        lost[backward] = 0
        if not first_known:
            lost[0] = 0
        c['sequence_resets'] += int(np.count_nonzero(backward))
        if dup.any():
            keep = ~dup
            c['duplicates'] += int(np.count_nonzero(dup))
            kept_before = np.concatenate(([0], np.cumsum(keep)))
            ack_positions = tuple(int(kept_before[p]) for p in ack_positions)
            header_positions = tuple(int(kept_before[p]) for p in header_positions)
            samples = samples[keep]
            lost = lost[keep]
        flags = samples['flags']
        flagged = (flags & FLAG_SAMPLE_LOST) != 0
        c['samples_ok'] += int(samples.size)
        c['samples_lost'] += int(lost.sum())
        c['samples_flagged_lost'] += int(lost[flagged].sum())
        c['loss_flags'] += int(np.count_nonzero(flagged))
        c['fifo_overruns'] += int(np.count_nonzero(flags & FLAG_FIFO_OVERRUN))
        if samples.size:
            self._last_seq = int(samples['seq'][-1])
        return samples, lost, ack_positions, header_positions


class _Collector:

    __slots__ = ('payloads', 'nsamples', 'acks', 'ack_positions', 'commands', 'headers',
                 'header_positions', 'discarded')

    def __init__(self) -> None:
        self.payloads: list[bytes] = []
        self.nsamples = 0
        self.acks: list[Ack] = []
        self.ack_positions: list[int] = []
        self.commands: list[Configure] = []
        self.headers: list[LogHeader] = []
        self.header_positions: list[int] = []
        self.discarded: list[tuple[int, int]] = []

    def result(self, dec: Decoder, payload: NDArray[np.uint8] | None = None) -> DecodeResult:
        """
        Count, account and return the DecodeResult.

        ``payload``: the samples' bytes when they were gathered in one uint8 array rather than
        in ``payloads``.
        """
        c = dec._c
        c['acks'] += len(self.acks)
        c['naks'] += sum(1 for a in self.acks if not a.ok)
        c['commands'] += len(self.commands)
        c['log_headers'] += len(self.headers)
        ack_pos, head_pos = tuple(self.ack_positions), tuple(self.header_positions)
        if payload is not None and payload.size:
            samples = payload.view(SAMPLE_DTYPE)
        elif payload is None and self.payloads:
            samples = np.frombuffer(b''.join(self.payloads), dtype=SAMPLE_DTYPE).copy()
        else:
            samples = None
        if samples is not None:
            samples, lost, ack_pos, head_pos = dec._account_samples(samples, ack_pos, head_pos)
        else:
            samples, lost = _EMPTY_SAMPLES, _EMPTY_LOST
        return DecodeResult(samples=samples, acks=tuple(self.acks), lost_before=lost,
                            ack_positions=ack_pos, commands=tuple(self.commands),
                            headers=tuple(self.headers), header_positions=head_pos,
                            discarded=tuple(self.discarded))


def _control_frame(res: _Collector, ftype: int, payload: memoryview) -> None:
    """Decode a valid frame other than SAMPLES (ACK, CONFIGURE, LOG_HEADER) into ``res``."""
    if ftype == FRAME_ACK:
        res.acks.append(_decode_ack(payload))
        res.ack_positions.append(res.nsamples)
    elif ftype == FRAME_CONFIGURE:
        res.commands.append(_decode_configure(payload))
    elif ftype == FRAME_LOG_HEADER:
        res.headers.append(_decode_log_header(payload))
        res.header_positions.append(res.nsamples)


def _decode_ack(payload: memoryview) -> Ack:
    command_id, status, accel_fs, gyro_fs, odr_mhz = _ACK.unpack_from(payload, 0)
    message = bytes(payload[_ACK.size:]).decode('ascii', 'replace')
    return Ack(command_id=command_id, ok=status == ACK_OK, odr_hz=odr_mhz / 1000.0,
               gyro_fs_dps=gyro_fs, accel_fs_g=accel_fs, message=message, status=status)


def _decode_configure(payload: memoryview) -> Configure:
    command_id, odr_mhz, gyro_fs, accel_fs, _ = _CONFIGURE.unpack_from(payload, 0)
    return Configure(command_id=command_id, odr_hz=odr_mhz / 1000.0, gyro_fs_dps=gyro_fs,
                     accel_fs_g=accel_fs)


def _decode_log_header(payload: memoryview) -> LogHeader:
    (sequence_id, file_index, odr_mhz, gyro_fs, accel_fs, _, first_seq, t_us,
     rtc) = _LOG_HEADER.unpack_from(payload, 0)
    return LogHeader(sequence_id=sequence_id, file_index=file_index, odr_hz=odr_mhz / 1000.0,
                     gyro_fs_dps=gyro_fs, accel_fs_g=accel_fs, first_seq=first_seq, t_us=t_us,
                     rtc_unix_s=rtc)
