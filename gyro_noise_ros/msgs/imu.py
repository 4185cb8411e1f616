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
``sensor_msgs/Imu``: bulk decode, encode and in-place patching of CDR (and ROS 1) messages.

After the header (see :mod:`.cdr`) come 37 float64: orientation xyzw, orientation_covariance[9],
angular_velocity xyz, angular_velocity_covariance[9], linear_acceleration xyz,
linear_acceleration_covariance[9]. Hence ``len = 4 + align8(12 + L) + 296`` in ROS 2 CDR and
``len = 16 + L + 296`` in ROS 1.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .cdr import decode_spans, encode_cdr, encode_cdr_rows, slow_decode, typestore
from .stamps import Parts, split_stamps, stamp_ns_of
from ..errors import BagError, ParameterError

IMU_MSGTYPE = 'sensor_msgs/msg/Imu'
#: float64 after the header: orientation 4, 9, angular velocity 3, 9, linear acceleration 3, 9.
IMU_TAIL_F8 = 37
#: (first float64, count) of angular_velocity and linear_acceleration within the Imu float block.
IMU_FIELDS = ((13, 3), (25, 3))


def decode_imu_spans(buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray, ros1: bool,
                     skip_undecodable: bool
                     ) -> tuple[np.ndarray | None, np.ndarray, np.ndarray, np.ndarray]:
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
        stamp_ns[i] = stamp_ns_of(msg)
        av, la = msg.angular_velocity, msg.linear_acceleration
        values[i] = (av.x, av.y, av.z, la.x, la.y, la.z)
    keep = None
    if dropped:
        keep = np.setdiff1d(np.arange(starts.shape[0]), dropped)
        stamp_ns, values = stamp_ns[keep], values[keep]
    return keep, stamp_ns, values[:, 0:3].copy(), values[:, 3:6].copy()


def imu_covariances(raws: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray]:
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


# ---------------------------------------------------------------------------------------------
# Encoding


def _vector3(values: ArrayLike, n: int, name: str) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape == (3,) and n == 1:
        arr = arr.reshape(1, 3)
    if arr.shape != (n, 3):
        raise ParameterError(
            f'{name} must have shape ({n}, 3) to match the stamps, got {arr.shape}')
    return arr


def _covariance(values: ArrayLike | None, n: int, name: str) -> np.ndarray:
    if values is None:
        return np.zeros((n, 9))
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape in ((9,), (3, 3)):
        return np.broadcast_to(arr.reshape(9), (n, 9))
    if arr.shape == (n, 9):
        return arr
    raise ParameterError(
        f'{name} must have 9 values (row-major 3x3) or shape ({n}, 9), got {arr.shape}')


def encode_imu_cdr(stamp_ns: ArrayLike, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, *,
                   frame_id: str = 'imu_link',
                   angular_velocity_covariance: ArrayLike | None = None,
                   linear_acceleration_covariance: ArrayLike | None = None) -> list[bytes]:
    """
    Serialise ``sensor_msgs/Imu`` messages to little-endian CDR in bulk, one bytes object each.

    Byte-identical to rosbags' ``typestore.serialize_cdr``; orientation is not estimated (REP-145:
    quaternion (0, 0, 0, 1), ``orientation_covariance[0] = -1``). ``stamp_ns`` (n,) are the header
    stamps in ns, ``gyro_rad_s`` and ``accel_m_s2`` (n, 3) in rad/s and m/s^2, the covariances (9,)
    or (n, 9), row-major, in (rad/s)^2 and (m/s^2)^2 (zeros, unknown, if None).

    """
    return encode_cdr(*_imu_parts(stamp_ns, gyro_rad_s, accel_m_s2, frame_id,
                                  angular_velocity_covariance, linear_acceleration_covariance))


def encode_imu_rows(stamp_ns: ArrayLike, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, *,
                    frame_id: str = 'imu_link',
                    angular_velocity_covariance: ArrayLike | None = None,
                    linear_acceleration_covariance: ArrayLike | None = None) -> np.ndarray:
    """
    Serialise ``sensor_msgs/Imu`` messages to CDR as the rows of a C-contiguous uint8 matrix.

    Arguments and bytes as :func:`encode_imu_cdr` (``rows[i].tobytes() ==
    encode_imu_cdr(...)[i]``), without one Python object per message: for bulk writers. Every
    message of one ``frame_id`` has the same size, the row length.

    """
    return encode_cdr_rows(*_imu_parts(
        stamp_ns, gyro_rad_s, accel_m_s2, frame_id, angular_velocity_covariance,
        linear_acceleration_covariance))


def _imu_parts(stamp_ns: ArrayLike, gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike, frame_id: str,
               angular_velocity_covariance: ArrayLike | None,
               linear_acceleration_covariance: ArrayLike | None) -> Parts:
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


def patch_imu_spans(buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
                    gyro_rad_s: ArrayLike, accel_m_s2: ArrayLike) -> list[bytes]:
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


def _packed(starts: np.ndarray, lengths: np.ndarray) -> bool:
    """Tell whether the spans are back to back in order (a joined list)."""
    return starts.shape[0] < 2 or bool((starts[1:] == starts[:-1] + lengths[:-1]).all())
