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
The CDR wire layer both messages share: a ``std_msgs/Header`` followed by float64 fields.

Messages are located in a byte buffer by (start, length) spans, grouped by length, and each group
is read column-wise: a handful of byte columns (encapsulation, stamp, string length, the float64
that are needed) instead of one Python object per message. A message is accepted only if its byte
length matches the layout its string length implies and the string's NUL sits where it must;
everything else goes through rosbags' deserialiser (:func:`slow_decode`), so the bulk path can
never change a value. The message modules (:mod:`.imu`, :mod:`.temperature`) name the float64
fields and their meaning.

Wire layouts (XCDR1; CDR alignment counts from the byte after the 4-byte encapsulation header):

- ROS 2 CDR: encapsulation ``00 01 00 00`` (little-endian; ``00 00`` big-endian), ``int32 sec``,
  ``uint32 nanosec``, ``uint32 L`` (frame_id length including its NUL), ``L`` bytes, zero padding
  to 8, then the float64 tail: ``len = 4 + align8(12 + L) + 8 * tail``.
- ROS 1: ``uint32 seq``, ``uint32 sec``, ``uint32 nsec``, ``uint32 L`` (no NUL), ``L`` bytes, the
  same float64 unaligned: ``len = 16 + L + 8 * tail``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import as_strided

from .stamps import NS_PER_S
from ..errors import BagError, ParameterError

_CDR_LE = b'\x00\x01\x00\x00'

_TYPESTORES: dict[str, Any] = {}

#: ``(first float64 index, count)`` of each tail field to read.
Fields = Sequence[tuple[int, int]]


def typestore(ros1: bool = False) -> Any:
    """
    Return rosbags' typestore, built once per flavour (it costs ~50 ms).

    ROS 1 messages need the Noetic definitions: their ``std_msgs/Header`` starts with ``uint32
    seq``, which the ROS 2 definitions lack.
    """
    key = 'ros1' if ros1 else 'ros2'
    if key not in _TYPESTORES:
        from rosbags.typesys import Stores, get_typestore

        _TYPESTORES[key] = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_JAZZY)
    return _TYPESTORES[key]


# ---------------------------------------------------------------------------------------------
# Decoding


def _align8(value: Any) -> Any:
    # an int or an integer array: the next multiple of 8
    return (value + 7) & ~7


class _Group:
    """``m`` messages of one byte length ``size`` inside ``buf``, read column by column."""

    def __init__(self, buf: np.ndarray, starts: np.ndarray, size: int) -> None:
        self.buf = buf
        self.starts = starts
        self.size = size
        m = starts.shape[0]
        stride = int(starts[1] - starts[0]) if m > 1 else size
        self.view: np.ndarray | None = None
        if stride >= size and (m < 3 or (np.diff(starts) == stride).all()):
            # Evenly spaced messages (a joined list, or one topic's run of records in an MCAP
            # chunk) are one strided 2-D view: column reads then copy only the bytes they need.
            self.view = as_strided(buf[int(starts[0]):], shape=(m, size), strides=(stride, 1),
                                   writeable=False)

    def cols(self, first: int, width: int) -> np.ndarray:
        """Return bytes ``[first, first + width)`` of every message as a contiguous uint8 array."""
        if self.view is not None:
            return np.ascontiguousarray(self.view[:, first:first + width])
        return self.buf[self.starts[:, None] + np.arange(first, first + width)]

    def u32(self, first: int, order: str) -> np.ndarray:
        return self.cols(first, 4).view(order + 'u4')[:, 0].astype(np.int64)

    def i32(self, first: int, order: str) -> np.ndarray:
        return self.cols(first, 4).view(order + 'i4')[:, 0].astype(np.int64)

    def f8(self, first: int, count: int, order: str) -> np.ndarray:
        return self.cols(first, 8 * count).view(order + 'f8').astype(np.float64)

    def subset(self, idx: np.ndarray) -> _Group:
        return _Group(self.buf, self.starts[idx], self.size)


def _ascii(group: _Group, first: int, stop: int) -> np.ndarray:
    """
    Messages whose bytes ``[first, stop)`` (frame_id and its padding) are all ASCII.

    rosbags refuses a frame_id that is not valid UTF-8; non-ASCII names are rare enough to leave
    every such message to rosbags, so both decoders accept and refuse the same messages.
    """
    if stop <= first:
        return np.ones(group.starts.shape[0], bool)
    return np.asarray((group.cols(first, stop - first) < 0x80).all(axis=1))


def _decode_group(group: _Group, tail_f8: int, fields: Fields,
                  ros1: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Decode one length group.

    Returns
    -------
    ok : bool (m,)
        Messages whose layout was verified; the rest need the slow path.
    stamp_ns : int64 (m,)
    values : float64 (m, sum of field counts)
        The selected float64 fields, in ``fields`` order; undefined where not ok.

    """
    m, size = group.starts.shape[0], group.size
    width = sum(count for _, count in fields)
    ok = np.zeros(m, bool)
    stamp_ns = np.zeros(m, np.int64)
    values = np.zeros((m, width))
    off = size - 8 * tail_f8
    idx: slice | np.ndarray
    if ros1:
        if off < 16:
            return ok, stamp_ns, values
        ok = (16 + group.u32(12, '<') == off) & _ascii(group, 16, off)
        if ok.all():
            sub, idx = group, slice(None)
        else:
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                return ok, stamp_ns, values
            sub = group.subset(idx)
        stamp_ns[idx] = sub.u32(4, '<') * NS_PER_S + sub.u32(8, '<')
        values[idx] = np.hstack([sub.f8(off + 8 * first, count, '<') for first, count in fields])
        return ok, stamp_ns, values
    # CDR: frame_id holds at least its NUL, so the float block starts at 4 + 16 at the earliest,
    # and it is 8-aligned relative to the byte after the encapsulation header.
    if off < 20 or (off - 4) % 8:
        return ok, stamp_ns, values
    head = group.cols(0, 2)
    for order, second in (('<', 1), ('>', 0)):
        good = (head[:, 0] == 0) & (head[:, 1] == second)
        if not good.any():
            continue
        length = group.u32(12, order)
        good &= (length >= 1) & (4 + _align8(12 + length) == off)
        # The string must end with its NUL exactly where its length says; anything else is a
        # different layout or corruption, which rosbags will judge.
        nul_at = group.starts + np.where(good, 15 + length, 0)
        good &= (group.buf[nul_at] == 0) & _ascii(group, 16, off)
        if good.all():
            sub, idx = group, slice(None)
        else:
            idx = np.flatnonzero(good)
            if idx.size == 0:
                continue
            sub = group.subset(idx)
        stamp_ns[idx] = sub.i32(4, order) * NS_PER_S + sub.u32(8, order)
        values[idx] = np.hstack([sub.f8(off + 8 * first, count, order) for first, count in fields])
        ok |= good
    return ok, stamp_ns, values


def decode_spans(buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray, tail_f8: int,
                 fields: Fields, ros1: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Bulk-decode messages located by spans in one buffer.

    Parameters
    ----------
    buf : numpy.ndarray of uint8
        Buffer holding the messages.
    starts, lengths : numpy.ndarray of int64, shape (n,)
        Byte offset and length of each message in ``buf``.
    tail_f8 : int
        float64 after the header (``IMU_TAIL_F8`` or ``TEMPERATURE_TAIL_F8``).
    fields : tuple of (int, int)
        (first float64, count) of the fields to return.
    ros1 : bool
        ROS 1 serialisation instead of ROS 2 CDR.

    Returns
    -------
    ok : numpy.ndarray of bool, shape (n,)
        Messages decoded here; the others must go through :func:`slow_decode`.
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns.
    values : numpy.ndarray of float64, shape (n, k)
        The selected fields.

    """
    n = starts.shape[0]
    width = sum(count for _, count in fields)
    if n == 0:
        return np.zeros(0, bool), np.zeros(0, np.int64), np.zeros((0, width))
    first = int(lengths[0])
    if (lengths == first).all():
        return _decode_group(_Group(buf, starts, first), tail_f8, fields, ros1)
    ok = np.zeros(n, bool)
    stamp_ns = np.zeros(n, np.int64)
    values = np.zeros((n, width))
    for size in np.unique(lengths):
        idx = np.flatnonzero(lengths == size)
        g_ok, g_stamp, g_values = _decode_group(
            _Group(buf, starts[idx], int(size)), tail_f8, fields, ros1)
        ok[idx] = g_ok
        stamp_ns[idx] = g_stamp
        values[idx] = g_values
    return ok, stamp_ns, values


def join_raws(raws: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Concatenate raw messages into one buffer; return (buf uint8, starts, lengths)."""
    n = len(raws)
    lengths = np.fromiter(map(len, raws), np.int64, n)
    starts = np.zeros(n, np.int64)
    if n > 1:
        np.cumsum(lengths[:-1], out=starts[1:])
    return np.frombuffer(b''.join(raws), np.uint8), starts, lengths


def slow_decode(raw: bytes, msgtype: str, ros1: bool) -> Any:
    """Decode one message with rosbags; raise BagError if rosbags cannot."""
    store = typestore(ros1)
    try:
        if ros1:
            return store.deserialize_ros1(raw, msgtype)
        return store.deserialize_cdr(raw, msgtype)
    except Exception as err:  # noqa: BLE001 - rosbags raises many types on corrupt bytes
        raise BagError(f'a {msgtype} message of {len(raw)} bytes cannot be decoded '
                       f'({type(err).__name__}: {err})') from err


def frame_id_of(raw: bytes | np.ndarray, ros1: bool) -> str | None:
    """``header.frame_id`` of one raw message, or None if its header does not parse."""
    raw = bytes(raw)
    if len(raw) < 16:
        return None
    if ros1:
        length = int.from_bytes(raw[12:16], 'little')
        return raw[16:16 + length].decode('utf-8', 'replace') if 16 + length <= len(raw) else None
    length = int.from_bytes(raw[12:16], 'little' if raw[1] == 1 else 'big')
    if length < 1 or 16 + length > len(raw):
        return None
    return raw[16:16 + length - 1].decode('utf-8', 'replace')


# ---------------------------------------------------------------------------------------------
# Encoding


def encode_cdr(sec: np.ndarray, nsec: np.ndarray, frame_id: str,
               tail: np.ndarray) -> list[bytes]:
    """
    Serialise n messages (header + float64 tail) as little-endian CDR; one bytes object each.

    Parameters
    ----------
    sec, nsec, frame_id, tail
        As in :func:`encode_cdr_rows`.

    Returns
    -------
    list of bytes
        ``encode_cdr(...)[i] == encode_cdr_rows(...)[i].tobytes()``.

    """
    rows = encode_cdr_rows(sec, nsec, frame_id, tail)
    size = rows.shape[1]
    blob = rows.tobytes()
    return [blob[i:i + size] for i in range(0, len(blob), size)]


def encode_cdr_rows(sec: np.ndarray, nsec: np.ndarray, frame_id: str,
                    tail: np.ndarray) -> np.ndarray:
    """
    Serialise n messages (header + float64 tail) as little-endian CDR; one uint8 row each.

    Parameters
    ----------
    sec, nsec : numpy.ndarray of int64, shape (n,)
        ``header.stamp`` (see :func:`~gyro_noise_ros.msgs.stamps.split_stamps`).
    frame_id : str
        ``header.frame_id`` of every message (no NUL).
    tail : numpy.ndarray of float64, shape (n, k)
        The float64 fields that follow the header, in wire order.

    Returns
    -------
    numpy.ndarray of uint8, shape (n, message size)
        C-contiguous.

    Raises
    ------
    ParameterError
        ``frame_id`` is not a str or holds a NUL.

    """
    if not isinstance(frame_id, str) or '\x00' in frame_id:
        raise ParameterError(f'frame_id must be a str without NUL, got {frame_id!r}')
    name = frame_id.encode('utf-8')
    n, k = tail.shape
    head = 4 + _align8(12 + len(name) + 1)
    size = head + 8 * k
    rows = np.zeros((n, size), np.uint8)
    rows[:, 0:4] = np.frombuffer(_CDR_LE, np.uint8)
    rows[:, 4:8] = sec.astype('<i4').view(np.uint8).reshape(n, 4)
    rows[:, 8:12] = nsec.astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 12:16] = np.frombuffer(np.array(len(name) + 1, '<u4').tobytes(), np.uint8)
    rows[:, 16:16 + len(name)] = np.frombuffer(name, np.uint8)
    rows[:, head:] = np.ascontiguousarray(tail, dtype='<f8').view(np.uint8).reshape(n, 8 * k)
    return rows
