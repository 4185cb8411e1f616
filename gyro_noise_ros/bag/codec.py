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
Bulk numpy codec of ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` (ROS 2 CDR and ROS 1).

Messages are located in a byte buffer by (start, length) spans, grouped by length, and each group
is read column-wise: a handful of byte columns (encapsulation, stamp, string length, the float64
that are needed) instead of one Python object per message. A message is accepted only if its byte
length matches the layout its string length implies and the string's NUL sits where it must;
everything else goes through rosbags' deserialiser, so the bulk path can never change a value.

Wire layouts (XCDR1; CDR alignment counts from the byte after the 4-byte encapsulation header):

- ROS 2 CDR ``sensor_msgs/Imu``: encapsulation ``00 01 00 00`` (little-endian; ``00 00``
  big-endian), ``int32 sec``, ``uint32 nanosec``, ``uint32 L`` (frame_id length including its NUL),
  ``L`` bytes, zero padding to 8, then 37 float64: orientation xyzw, orientation_covariance[9],
  angular_velocity xyz, angular_velocity_covariance[9], linear_acceleration xyz,
  linear_acceleration_covariance[9]. Hence ``len = 4 + align8(12 + L) + 296``.
- ROS 1 ``sensor_msgs/Imu``: ``uint32 seq``, ``uint32 sec``, ``uint32 nsec``, ``uint32 L`` (no
  NUL), ``L`` bytes, the same 37 float64 unaligned: ``len = 16 + L + 296``.
- ``sensor_msgs/Temperature``: the same header, then float64 temperature and variance.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import as_strided

from ..errors import BagError, ParameterError

IMU_MSGTYPE = 'sensor_msgs/msg/Imu'
TEMPERATURE_MSGTYPE = 'sensor_msgs/msg/Temperature'

_NS_PER_S = 1_000_000_000
#: float64 after the header: orientation 4, 9, angular velocity 3, 9, linear acceleration 3, 9.
IMU_TAIL_F8 = 37
TEMPERATURE_TAIL_F8 = 2
#: (first float64, count) of angular_velocity and linear_acceleration within the Imu float block.
IMU_FIELDS = ((13, 3), (25, 3))
TEMPERATURE_FIELDS = ((0, 1),)
_CDR_LE = b'\x00\x01\x00\x00'

_TYPESTORES = {}


def typestore(ros1=False):
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


def _align8(value):
    return (value + 7) & ~7


class _Group:
    """``m`` messages of one byte length ``size`` inside ``buf``, read column by column."""

    def __init__(self, buf, starts, size):
        self.buf = buf
        self.starts = starts
        self.size = size
        m = starts.shape[0]
        stride = int(starts[1] - starts[0]) if m > 1 else size
        self.view = None
        if stride >= size and (m < 3 or (np.diff(starts) == stride).all()):
            # Evenly spaced messages (a joined list, or one topic's run of records in an MCAP
            # chunk) are one strided 2-D view: column reads then copy only the bytes they need.
            self.view = as_strided(buf[int(starts[0]):], shape=(m, size), strides=(stride, 1),
                                   writeable=False)

    def cols(self, first, width):
        """Return bytes ``[first, first + width)`` of every message as a contiguous uint8 array."""
        if self.view is not None:
            return np.ascontiguousarray(self.view[:, first:first + width])
        return self.buf[self.starts[:, None] + np.arange(first, first + width)]

    def u32(self, first, order):
        return self.cols(first, 4).view(order + 'u4')[:, 0].astype(np.int64)

    def i32(self, first, order):
        return self.cols(first, 4).view(order + 'i4')[:, 0].astype(np.int64)

    def f8(self, first, count, order):
        return self.cols(first, 8 * count).view(order + 'f8').astype(np.float64)

    def subset(self, idx):
        return _Group(self.buf, self.starts[idx], self.size)


def _ascii(group, first, stop):
    """
    Messages whose bytes ``[first, stop)`` (frame_id and its padding) are all ASCII.

    rosbags refuses a frame_id that is not valid UTF-8; non-ASCII names are rare enough to leave
    every such message to rosbags, so both decoders accept and refuse the same messages.
    """
    if stop <= first:
        return np.ones(group.starts.shape[0], bool)
    return (group.cols(first, stop - first) < 0x80).all(axis=1)


def _decode_group(group, tail_f8, fields, ros1):
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
        stamp_ns[idx] = sub.u32(4, '<') * _NS_PER_S + sub.u32(8, '<')
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
        stamp_ns[idx] = sub.i32(4, order) * _NS_PER_S + sub.u32(8, order)
        values[idx] = np.hstack([sub.f8(off + 8 * first, count, order) for first, count in fields])
        ok |= good
    return ok, stamp_ns, values


def decode_spans(buf, starts, lengths, tail_f8, fields, ros1):
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


def join_raws(raws):
    """Concatenate raw messages into one buffer; return (buf uint8, starts, lengths)."""
    n = len(raws)
    lengths = np.fromiter(map(len, raws), np.int64, n)
    starts = np.zeros(n, np.int64)
    if n > 1:
        np.cumsum(lengths[:-1], out=starts[1:])
    return np.frombuffer(b''.join(raws), np.uint8), starts, lengths


def slow_decode(raw, msgtype, ros1):
    """Decode one message with rosbags; raise BagError if rosbags cannot."""
    store = typestore(ros1)
    try:
        if ros1:
            return store.deserialize_ros1(raw, msgtype)
        return store.deserialize_cdr(raw, msgtype)
    except Exception as err:  # noqa: BLE001 - rosbags raises many types on corrupt bytes
        raise BagError(f'a {msgtype} message of {len(raw)} bytes cannot be decoded '
                       f'({type(err).__name__}: {err})') from err


def frame_id_of(raw, ros1):
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


def imu_covariances(raws):
    """
    Return the angular-velocity and linear-acceleration covariances of raw ROS 2 CDR Imu messages.

    The covariances are float64 16..24 and 28..36 of the 37-float tail that ends the message (see
    the layout in the module doc), whatever the frame_id length.

    Parameters
    ----------
    raws : list of bytes
        Serialised ``sensor_msgs/Imu`` (ROS 2 CDR, either endianness).

    Returns
    -------
    angular_velocity_covariance, linear_acceleration_covariance : numpy.ndarray, shape (n, 9)
        Row-major, in (rad/s)^2 and (m/s^2)^2.

    """
    n = len(raws)
    tail_bytes = IMU_TAIL_F8 * 8
    tails = np.empty((n, IMU_TAIL_F8))
    lengths = {len(r) for r in raws}
    if len(lengths) == 1 and all(r[1] == 1 for r in raws):
        size = lengths.pop()
        rows = np.frombuffer(b''.join(raws), np.uint8).reshape(n, size)
        tails[:] = np.ascontiguousarray(rows[:, size - tail_bytes:]).view('<f8')
    else:
        for i, raw in enumerate(raws):
            tails[i] = np.frombuffer(raw[-tail_bytes:], '<f8' if raw[1] == 1 else '>f8')
    return tails[:, 16:25], tails[:, 28:37]


def temperature_variances(raws):
    """
    Return the ``variance`` field of raw ROS 2 CDR ``sensor_msgs/Temperature`` messages.

    It is the last float64 of the message (``temperature``, ``variance`` follow the header).

    Parameters
    ----------
    raws : list of bytes
        Serialised ``sensor_msgs/Temperature`` (ROS 2 CDR, either endianness).

    Returns
    -------
    numpy.ndarray
        Variances in degC^2.

    """
    return np.array([np.frombuffer(raw[-8:], '<f8' if raw[1] == 1 else '>f8')[0] for raw in raws])


def _stamp_of(msg):
    return int(msg.header.stamp.sec) * _NS_PER_S + int(msg.header.stamp.nanosec)


def decode_imu_spans(buf, starts, lengths, ros1, skip_undecodable):
    """
    Decode Imu messages located by spans; slow path for the ones the bulk path refuses.

    Returns
    -------
    keep : numpy.ndarray of int64 or None
        Indices of the messages returned (None: all of them).
    stamp_ns : int64 (k,)
    gyro, accel : float64 (k, 3)

    """
    ok, stamp_ns, values = decode_spans(buf, starts, lengths, IMU_TAIL_F8, IMU_FIELDS, ros1)
    dropped = []
    for i in np.flatnonzero(~ok):
        raw = buf[starts[i]:starts[i] + lengths[i]].tobytes()
        try:
            msg = slow_decode(raw, IMU_MSGTYPE, ros1)
        except BagError:
            if not skip_undecodable:
                raise
            dropped.append(i)
            continue
        stamp_ns[i] = _stamp_of(msg)
        av, la = msg.angular_velocity, msg.linear_acceleration
        values[i] = (av.x, av.y, av.z, la.x, la.y, la.z)
    keep = None
    if dropped:
        keep = np.setdiff1d(np.arange(starts.shape[0]), dropped)
        stamp_ns, values = stamp_ns[keep], values[keep]
    return keep, stamp_ns, values[:, 0:3].copy(), values[:, 3:6].copy()


def decode_temperature_spans(buf, starts, lengths, ros1):
    """Decode Temperature messages located by spans; return (stamp_ns, temperature_c)."""
    ok, stamp_ns, values = decode_spans(
        buf, starts, lengths, TEMPERATURE_TAIL_F8, TEMPERATURE_FIELDS, ros1)
    for i in np.flatnonzero(~ok):
        msg = slow_decode(buf[starts[i]:starts[i] + lengths[i]].tobytes(),
                          TEMPERATURE_MSGTYPE, ros1)
        stamp_ns[i] = _stamp_of(msg)
        values[i, 0] = msg.temperature
    return stamp_ns, values[:, 0].copy()


def count_stamp_regressions(stamp_ns, *, previous_ns=None):
    """
    Count stamps that go backwards (strictly earlier than the stamp before them).

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Stamps in ns, in delivery order.
    previous_ns : int, optional
        Last stamp of the preceding batch, so that a stream of batches can be counted piecewise.

    Returns
    -------
    int
        Number of indices ``i`` with ``stamp_ns[i] < stamp_ns[i - 1]``.

    """
    stamps = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
    if previous_ns is not None:
        stamps = np.concatenate(([np.int64(previous_ns)], stamps))
    return int(np.count_nonzero(stamps[1:] < stamps[:-1]))


# ---------------------------------------------------------------------------------------------
# Encoding


def split_stamps(stamp_ns, name):
    """Validate integer ns stamps; return (stamps int64 (n,), sec, nanosec), ROS 2 semantics."""
    stamps = np.asarray(stamp_ns)
    if stamps.dtype.kind not in 'iu':
        if (stamps.dtype.kind == 'f' and np.all(np.isfinite(stamps))
                and np.all(stamps == np.round(stamps))):
            stamps = stamps.astype(np.int64)
        else:
            raise ParameterError(f'{name} must be integer nanoseconds, got dtype {stamps.dtype}')
    stamps = stamps.astype(np.int64).reshape(-1)
    # ROS 2 Time keeps nanosec in [0, 1e9) also for negative times, hence floor division.
    sec = np.floor_divide(stamps, _NS_PER_S)
    nsec = stamps - sec * _NS_PER_S
    if stamps.size and (sec.min() < -(2**31) or sec.max() >= 2**31):
        worst = int(stamps[np.argmax(np.abs(sec))])
        raise ParameterError(
            f'{name} {worst} does not fit builtin_interfaces/Time (int32 seconds)')
    return stamps, sec, nsec


def _vector3(values, n, name):
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape == (3,) and n == 1:
        arr = arr.reshape(1, 3)
    if arr.shape != (n, 3):
        raise ParameterError(
            f'{name} must have shape ({n}, 3) to match the stamps, got {arr.shape}')
    return arr


def _covariance(values, n, name):
    if values is None:
        return np.zeros((n, 9))
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape in ((9,), (3, 3)):
        return np.broadcast_to(arr.reshape(9), (n, 9))
    if arr.shape == (n, 9):
        return arr
    raise ParameterError(
        f'{name} must have 9 values (row-major 3x3) or shape ({n}, 9), got {arr.shape}')


def _encode_cdr(sec, nsec, frame_id, tail):
    """Serialise n messages (header + float64 tail) as little-endian CDR; one bytes object each."""
    rows = _encode_rows(sec, nsec, frame_id, tail)
    size = rows.shape[1]
    blob = rows.tobytes()
    return [blob[i:i + size] for i in range(0, len(blob), size)]


def _encode_rows(sec, nsec, frame_id, tail):
    """Serialise n messages (header + float64 tail) as little-endian CDR; one uint8 row each."""
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


def encode_imu_cdr(stamp_ns, gyro_rad_s, accel_m_s2, *, frame_id='imu_link',
                   angular_velocity_covariance=None, linear_acceleration_covariance=None):
    """
    Serialise ``sensor_msgs/Imu`` messages to little-endian CDR in bulk.

    Byte-identical to rosbags' ``typestore.serialize_cdr``. Orientation is not estimated (REP-145):
    quaternion (0, 0, 0, 1) as in the message default and ``orientation_covariance[0] = -1``.
    The result can be written to a bag or published as a serialised message.

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Header stamps in ns.
    gyro_rad_s : array_like of float, shape (n, 3)
        Angular velocity x, y, z in rad/s.
    accel_m_s2 : array_like of float, shape (n, 3)
        Linear acceleration x, y, z in m/s^2.
    frame_id : str
        ``header.frame_id``.
    angular_velocity_covariance, linear_acceleration_covariance : array_like, shape (9,) or (n, 9)
        Row-major covariance in (rad/s)^2 and (m/s^2)^2; zeros (unknown) if None.

    Returns
    -------
    list of bytes
        One serialised message per stamp.

    """
    return _encode_cdr(*_imu_parts(stamp_ns, gyro_rad_s, accel_m_s2, frame_id,
                                   angular_velocity_covariance, linear_acceleration_covariance))


def encode_imu_rows(stamp_ns, gyro_rad_s, accel_m_s2, *, frame_id='imu_link',
                    angular_velocity_covariance=None, linear_acceleration_covariance=None):
    """
    Serialise ``sensor_msgs/Imu`` messages to little-endian CDR, one row of a byte matrix each.

    Same bytes as :func:`encode_imu_cdr` (``rows[i].tobytes() == encode_imu_cdr(...)[i]``), without
    one Python object per message: for bulk writers.

    Parameters
    ----------
    stamp_ns, gyro_rad_s, accel_m_s2, frame_id : array_like, str
        As in :func:`encode_imu_cdr`.
    angular_velocity_covariance, linear_acceleration_covariance : array_like, optional
        As in :func:`encode_imu_cdr`.

    Returns
    -------
    numpy.ndarray of uint8, shape (n, message size)
        C-contiguous; every message of one frame_id has the same size.

    """
    return _encode_rows(*_imu_parts(stamp_ns, gyro_rad_s, accel_m_s2, frame_id,
                                    angular_velocity_covariance, linear_acceleration_covariance))


def _imu_parts(stamp_ns, gyro_rad_s, accel_m_s2, frame_id, angular_velocity_covariance,
               linear_acceleration_covariance):
    """Return (sec, nsec, frame_id, tail) of Imu messages."""
    _, sec, nsec = split_stamps(stamp_ns, 'stamp_ns')
    n = sec.shape[0]
    tail = np.zeros((n, IMU_TAIL_F8))
    tail[:, 3] = 1.0
    tail[:, 4] = -1.0
    tail[:, 13:16] = _vector3(gyro_rad_s, n, 'gyro_rad_s')
    tail[:, 16:25] = _covariance(angular_velocity_covariance, n, 'angular_velocity_covariance')
    tail[:, 25:28] = _vector3(accel_m_s2, n, 'accel_m_s2')
    tail[:, 28:37] = _covariance(linear_acceleration_covariance, n,
                                 'linear_acceleration_covariance')
    return sec, nsec, frame_id, tail


def encode_temperature_cdr(stamp_ns, temperature_c, *, frame_id='imu_link', variance=0.0):
    """
    Serialise ``sensor_msgs/Temperature`` messages to little-endian CDR in bulk.

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Header stamps in ns.
    temperature_c : array_like of float, shape (n,)
        Temperature in degC.
    frame_id : str
        ``header.frame_id``.
    variance : float or array_like, shape (n,)
        Temperature variance in degC^2 (0 = unknown).

    Returns
    -------
    list of bytes
        One serialised message per stamp.

    """
    return _encode_cdr(*_temperature_parts(stamp_ns, temperature_c, frame_id, variance))


def encode_temperature_rows(stamp_ns, temperature_c, *, frame_id='imu_link', variance=0.0):
    """
    Serialise ``sensor_msgs/Temperature`` messages to little-endian CDR, one byte-matrix row each.

    Parameters
    ----------
    stamp_ns, temperature_c, frame_id, variance
        As in :func:`encode_temperature_cdr`.

    Returns
    -------
    numpy.ndarray of uint8, shape (n, message size)
        ``rows[i].tobytes() == encode_temperature_cdr(...)[i]``.

    """
    return _encode_rows(*_temperature_parts(stamp_ns, temperature_c, frame_id, variance))


def _temperature_parts(stamp_ns, temperature_c, frame_id, variance):
    """Return (sec, nsec, frame_id, tail) of Temperature messages."""
    _, sec, nsec = split_stamps(stamp_ns, 'stamp_ns')
    n = sec.shape[0]
    temps = np.asarray(temperature_c, dtype=np.float64).reshape(-1)
    if temps.shape[0] != n:
        raise ParameterError(f'temperature_c has {temps.shape[0]} values for {n} stamps')
    tail = np.empty((n, TEMPERATURE_TAIL_F8))
    tail[:, 0] = temps
    try:
        tail[:, 1] = np.broadcast_to(np.asarray(variance, dtype=np.float64), (n,))
    except ValueError as err:
        raise ParameterError(
            f'variance must be a float or have {n} values, got {np.shape(variance)}') from err
    return sec, nsec, frame_id, tail


def patch_imu_spans(buf, starts, lengths, gyro_rad_s, accel_m_s2):
    """
    Re-serialise CDR ``sensor_msgs/Imu`` messages with a new angular velocity and acceleration.

    Everything else (encapsulation and byte order, header stamp and frame_id, orientation, the
    covariances) stays byte for byte as received, so the result equals rosbags'
    ``serialize_cdr`` of the message with the two vectors replaced. Messages the bulk decoder
    verifies are patched in place as two 24-byte columns; any other (e.g. a non-ASCII frame_id)
    goes through rosbags' deserialiser and serialiser in its own byte order.

    Parameters
    ----------
    buf : numpy.ndarray of uint8
        Buffer holding the messages (:func:`join_raws`).
    starts, lengths : numpy.ndarray of int64, shape (n,)
        Byte offset and length of each message in ``buf``.
    gyro_rad_s, accel_m_s2 : array_like of float, shape (n, 3)
        The new ``angular_velocity`` and ``linear_acceleration``.

    Returns
    -------
    list of bytes
        One serialised message per span.

    Raises
    ------
    BagError
        A message neither decoder can read.

    """
    n = starts.shape[0]
    gyro = _vector3(gyro_rad_s, n, 'gyro_rad_s')
    accel = _vector3(accel_m_s2, n, 'accel_m_s2')
    if n == 0:
        return []
    ok, _, _ = decode_spans(buf, starts, lengths, IMU_TAIL_F8, ((13, 1),), False)
    out = buf[int(starts[0]):int(starts[-1] + lengths[-1])].copy() if _packed(starts, lengths) \
        else np.array(buf, copy=True)
    base = int(starts[0]) if out.shape[0] != buf.shape[0] else 0
    float_block = starts - base + lengths - 8 * IMU_TAIL_F8
    little = out[np.where(ok, starts - base + 1, 0)] == 1
    cols = np.arange(24)
    for order, sel in (('<', ok & little), ('>', ok & ~little)):
        idx = np.flatnonzero(sel)
        if idx.size == 0:
            continue
        for (first, _), values in zip(IMU_FIELDS, (gyro, accel)):
            pos = float_block[idx, None] + 8 * first + cols
            out[pos] = np.ascontiguousarray(values[idx], dtype=order + 'f8').view(np.uint8)
    blob = out.tobytes()
    result = [blob[s:s + length] for s, length in zip((starts - base).tolist(), lengths.tolist())]
    for i in np.flatnonzero(~ok):
        raw = result[i]
        msg = slow_decode(raw, IMU_MSGTYPE, False)
        av = msg.angular_velocity
        av.x, av.y, av.z = map(float, gyro[i])
        la = msg.linear_acceleration
        la.x, la.y, la.z = map(float, accel[i])
        result[i] = bytes(typestore().serialize_cdr(msg, IMU_MSGTYPE,
                                                    little_endian=len(raw) > 1 and raw[1] == 1))
    return result


def _packed(starts, lengths):
    """Tell whether the spans are back to back in order (a joined list)."""
    return starts.shape[0] < 2 or bool((starts[1:] == starts[:-1] + lengths[:-1]).all())
