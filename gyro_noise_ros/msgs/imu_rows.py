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
A live batch of ``sensor_msgs/Imu`` of one layout as rows: decode and patch in a few numpy calls.

One driver's messages all have the same length and header layout (little-endian ROS 2 CDR, one
frame_id), so a joined batch is an ``(n, size)`` byte matrix. :func:`imu_rows` checks that once
per batch (row 0 as :mod:`.cdr`'s bulk decoder checks every message, the other rows equal to it
in the encapsulation and frame_id bytes) and returns the matrix, or None for anything else, which
then goes through :func:`.imu.decode_imu_spans` / :func:`.imu.patch_imu_spans` (same results,
tested). A 16-message batch costs a few microseconds here instead of ~200 us of fixed per-call
work there (the compensator takes one board frame per wake-up).

A node takes ~650 batches a second at 6.66 kHz; :class:`RowLayout` remembers the layout of the
last batch :func:`imu_rows` accepted, so the next batches of it are checked with byte comparisons
in Python (the same bytes, the same rule) instead of a dozen numpy calls: ~3 us instead of ~14 us
for 10 messages. :class:`RowEncoder` is the other direction, for a publisher whose messages
differ only in stamp and vectors (a driver): one template message, the stamps and vectors written
into copies of it (~10 us for 16 messages instead of ~110 us through the general encoder);
:meth:`RowEncoder.rows_scaled` takes raw words and their sensitivities and does the scaling and
the writing in one compiled pass (numba), ~3 us. :class:`RowCorrector` is a compensator's: each
row's two vectors calibrated and offset-corrected in one compiled pass, ~7 us for 16 messages.
"""

from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .cdr import join_raws
from .imu import _vector3, encode_imu_rows, IMU_FIELDS, IMU_TAIL_F8
from .stamps import NS_PER_S, split_stamps
from ..core.jit import JIT_OPTIONS
from ..errors import ParameterError

_TAIL_BYTES = 8 * IMU_TAIL_F8
(_GYRO, _), (_ACCEL, _) = IMU_FIELDS


def imu_rows(buf: NDArray[np.uint8], starts: NDArray[np.int64],
             lengths: NDArray[np.int64], tail_f8: int = IMU_TAIL_F8) -> NDArray[np.uint8] | None:
    """
    View a joined batch of Imu messages as rows when they share one verified layout.

    Parameters
    ----------
    buf : numpy.ndarray of uint8
        Buffer holding the messages (:func:`.cdr.join_raws`).
    starts, lengths : numpy.ndarray of int64, shape (n,)
        Byte offset and length of each message in ``buf``.
    tail_f8 : int
        float64 after the header: :data:`.imu.IMU_TAIL_F8`, or that of another message made of a
        header and a float64 block (``sensor_msgs/Temperature``: ``TEMPERATURE_TAIL_F8``).

    Returns
    -------
    numpy.ndarray of uint8, shape (n, size), or None
        The rows (a view of ``buf``), or None when the batch is empty, not back to back, of
        several lengths, not little-endian ROS 2 CDR, or its header bytes differ from row 0's
        or fail the bulk decoder's checks (frame_id length, NUL, ASCII).

    """
    n = starts.shape[0]
    if n == 0:
        return None
    size = int(lengths[0])
    first = int(starts[0])
    off = size - 8 * tail_f8
    if off < 20 or (off - 4) % 8 or first + n * size > buf.shape[0]:
        return None
    if n > 1 and not ((lengths == size).all() and (np.diff(starts) == size).all()):
        return None
    rows = buf[first:first + n * size].reshape(n, size)
    head = rows[0]
    length = int.from_bytes(head[12:16].tobytes(), 'little')
    # Row 0 as .cdr's bulk decoder checks a message: CDR little-endian, a frame_id of at least
    # its NUL ending where its length says, the float block 8-aligned right after it, ASCII.
    if (head[0] != 0 or head[1] != 1 or length < 1 or 4 + 8 * ((12 + length + 7) // 8) != off
            or head[15 + length] != 0 or max(head[16:off].tobytes(), default=0) >= 0x80):
        return None
    # The other rows: the same encapsulation and frame_id bytes (the stamps in 4:12 differ).
    if n > 1 and not ((rows[1:, :2] == head[:2]).all()
                      and (rows[1:, 12:off] == head[12:off]).all()):
        return None
    return rows


class RowLayout:
    """
    The layout of the last batch :func:`imu_rows` accepted, to accept the next ones cheaply.

    ``tail_f8``: as :func:`imu_rows` (Imu by default; ``TEMPERATURE_TAIL_F8`` for Temperature).

    :meth:`rows` returns the same matrix as ``imu_rows(*join_raws(raws))``: a batch whose
    messages all have the remembered length, encapsulation bytes and header bytes after the
    stamp (frame_id, padding) is what :func:`imu_rows` accepts, since its checks read only those
    bytes of row 0 and compare the other rows with them; anything else goes through
    :func:`imu_rows` itself, whose answer (rows or None) is returned and, for rows, remembered.
    """

    def __init__(self, tail_f8: int = IMU_TAIL_F8) -> None:
        self._tail_f8 = int(tail_f8)
        self._size = 0
        self._encapsulation = b''
        self._header = b''

    def rows(self, raws: Sequence[bytes]) -> NDArray[np.uint8] | None:
        """
        Return ``raws`` as an ``(n, size)`` read-only byte matrix, or None (see :func:`imu_rows`).

        Parameters
        ----------
        raws : sequence of bytes
            Serialised messages (``sensor_msgs/Imu``, or the type of ``tail_f8``).

        """
        n = len(raws)
        size, enc, header = self._size, self._encapsulation, self._header
        if n and size and all(len(raw) == size and raw.startswith(enc)
                              and raw.startswith(header, 12) for raw in raws):
            return np.frombuffer(b''.join(raws), np.uint8).reshape(n, size)
        buf, starts, lengths = join_raws(raws)
        rows = imu_rows(buf, starts, lengths, self._tail_f8)
        if rows is not None:
            head = rows[0].tobytes()
            self._size = rows.shape[1]
            self._encapsulation, self._header = head[:2], head[12:self._size - 8 * self._tail_f8]
        return rows


class RowEncoder:
    """
    Serialise Imu messages of one frame_id and one pair of shared covariances as rows.

    The rows are :func:`.imu.encode_imu_rows`' bytes (tested): a template message (its encoding
    of one sample) copied to every row, with the stamps and the two vectors, the only fields that
    differ between such messages, written in.

    Parameters
    ----------
    frame_id : str
        Header frame_id.
    angular_velocity_covariance, linear_acceleration_covariance : array_like or None
        (9,) or (3, 3), row-major; None: zeros (unknown), as :func:`.imu.encode_imu_cdr`.

    """

    def __init__(self, frame_id: str, angular_velocity_covariance: ArrayLike | None = None,
                 linear_acceleration_covariance: ArrayLike | None = None) -> None:
        for name, cov in (('angular_velocity_covariance', angular_velocity_covariance),
                          ('linear_acceleration_covariance', linear_acceleration_covariance)):
            if cov is not None and np.shape(cov) not in ((9,), (3, 3)):
                raise ParameterError(f'{name} must be shared: 9 values (row-major 3x3), got '
                                     f'shape {np.shape(cov)}')
        zero = np.zeros((1, 3))
        self.template = encode_imu_rows([0], zero, zero, frame_id=frame_id,
                                        angular_velocity_covariance=angular_velocity_covariance,
                                        linear_acceleration_covariance=(
                                            linear_acceleration_covariance))[0]

    def rows(self, stamp_ns: ArrayLike, gyro_rad_s: ArrayLike,
             accel_m_s2: ArrayLike) -> NDArray[np.uint8]:
        """
        Return the messages as an ``(n, size)`` uint8 matrix, one message per row.

        Parameters
        ----------
        stamp_ns : array_like of int
            (n,) header stamps, ns.
        gyro_rad_s, accel_m_s2 : array_like of float
            (n, 3) angular velocity (rad/s) and linear acceleration (m/s^2).

        """
        _, sec, nsec = split_stamps(stamp_ns, 'stamp_ns')
        n, size = sec.shape[0], self.template.shape[0]
        gyro = _vector3(gyro_rad_s, n, 'gyro_rad_s')  # the general encoder's check
        accel = _vector3(accel_m_s2, n, 'accel_m_s2')
        rows = np.empty((n, size), np.uint8)
        rows[:] = self.template
        rows[:, 4:8] = sec.astype('<i4').view(np.uint8).reshape(n, 4)
        rows[:, 8:12] = nsec.astype('<u4').view(np.uint8).reshape(n, 4)
        tail = rows[:, size - _TAIL_BYTES:].view('<f8')
        tail[:, _GYRO:_GYRO + 3] = gyro
        tail[:, _ACCEL:_ACCEL + 3] = accel
        return rows

    def rows_scaled(self, stamp_ns: ArrayLike, gyro_counts: ArrayLike, accel_counts: ArrayLike,
                    gyro_scale: float, accel_scale: float) -> NDArray[np.uint8]:
        """
        Return ``rows(stamp_ns, gyro_counts * gyro_scale, accel_counts * accel_scale)``.

        A driver's raw int16 words and their sensitivities, scaled (float64, as
        :func:`numpy.multiply` rounds) and written in one compiled pass: ~3 us for 16 messages
        instead of ~20 us (tested byte for byte against :meth:`rows`). Other dtypes and shapes,
        and stamps out of ``builtin_interfaces/Time``, go through :meth:`rows` (its refusals).

        Parameters
        ----------
        stamp_ns : array_like of int
            (n,) header stamps, ns (int64 for the compiled pass).
        gyro_counts, accel_counts : array_like
            (n, 3) raw words (int16 for the compiled pass).
        gyro_scale, accel_scale : float
            Value of one count: rad/s, m/s^2.

        """
        stamps, gyro, accel = (np.asarray(stamp_ns), np.asarray(gyro_counts),
                               np.asarray(accel_counts))
        n = stamps.shape[0] if stamps.ndim == 1 else -1
        if (stamps.dtype == np.int64 and gyro.dtype == np.int16 and accel.dtype == np.int16
                and gyro.shape == (n, 3) and accel.shape == (n, 3)):
            out = np.empty((n, self.template.shape[0]), np.uint8)
            if _fill_scaled(self.template, stamps, gyro, accel, float(gyro_scale),
                            float(accel_scale), out):
                return out
        return self.rows(stamps, np.multiply(gyro, gyro_scale, dtype=np.float64),
                         np.multiply(accel, accel_scale, dtype=np.float64))


@numba.njit(**JIT_OPTIONS)
def _fill_scaled(  # pragma: no cover - compiled; tested through RowEncoder.rows_scaled
        template: NDArray[np.uint8], stamps: NDArray[np.int64], gyro: NDArray[np.int16],
        accel: NDArray[np.int16], gyro_scale: float, accel_scale: float,
        out: NDArray[np.uint8]) -> bool:
    """Write :meth:`RowEncoder.rows_scaled`' rows into ``out``; False: a stamp out of range."""
    tail0 = template.shape[0] - _TAIL_BYTES
    for i in range(stamps.shape[0]):
        sec = stamps[i] // NS_PER_S
        if sec < -(1 << 31) or sec >= (1 << 31):
            return False
        nsec = stamps[i] - sec * NS_PER_S
        row = out[i]
        row[:] = template
        for b in range(4):
            row[4 + b] = (sec >> (8 * b)) & 0xFF
            row[8 + b] = (nsec >> (8 * b)) & 0xFF
        tail = out[i, tail0:].view(np.float64)
        for k in range(3):
            tail[_GYRO + k] = np.float64(gyro[i, k]) * gyro_scale
            tail[_ACCEL + k] = np.float64(accel[i, k]) * accel_scale
    return True


class RowCorrector:
    """
    Replace each vector ``v`` of :func:`imu_rows`' rows by ``M (v - b) - o``, in one compiled pass.

    A compensator's usual batch: the calibration (``M`` the inverse of the sensor matrix, ``b``
    the bias; the arithmetic of
    :meth:`~gyro_noise_ros.calibration.apply.SensorCalibration.apply` in the same order, so the
    same bits), fixed here, and each message's thermal offset ``o``, given per batch; everything
    else stays byte for byte, as :func:`patch_rows` of the numpy computation (tested).

    Parameters
    ----------
    gyro_matrix, accel_matrix : array_like of float, shape (3, 3), or None
        ``M`` (None: the identity, ``v - b`` only).
    gyro_bias, accel_bias : array_like of float, shape (3,)
        ``b``, rad/s and m/s^2.

    """

    def __init__(self, gyro_matrix: ArrayLike | None, gyro_bias: ArrayLike,
                 accel_matrix: ArrayLike | None, accel_bias: ArrayLike) -> None:
        matrices = [np.eye(3) if m is None else np.asarray(m, np.float64)
                    for m in (gyro_matrix, accel_matrix)]
        biases = [np.asarray(b, np.float64) for b in (gyro_bias, accel_bias)]
        if any(m.shape != (3, 3) for m in matrices) or any(b.shape != (3,) for b in biases):
            raise ParameterError('each matrix must be (3, 3) and each bias (3,)')
        self._matrix = np.ascontiguousarray(np.stack(matrices))
        self._bias = np.ascontiguousarray(np.stack(biases))
        self._use_matrix = np.array([gyro_matrix is not None, accel_matrix is not None])

    def rows(self, rows: NDArray[np.uint8], gyro_offset: NDArray[np.float64] | None = None,
             accel_offset: NDArray[np.float64] | None = None) -> NDArray[np.uint8]:
        """
        Return the corrected copy of ``rows`` (``(n, size)`` uint8, left unchanged).

        ``gyro_offset``, ``accel_offset``: ``o``, ``(n, 3)`` float64 per message, or None (none).
        :func:`row_messages` makes the result bytes.
        """
        n = rows.shape[0]
        offsets = [_NO_OFFSET if o is None else np.ascontiguousarray(o, np.float64)
                   for o in (gyro_offset, accel_offset)]
        for given, o in zip((gyro_offset, accel_offset), offsets):
            if given is not None and o.shape != (n, 3):
                raise ParameterError(f'offsets must be ({n}, 3), got {o.shape}')
        out = np.empty(rows.shape, np.uint8)
        _correct_rows(rows, self._matrix, self._bias, self._use_matrix, offsets[0], offsets[1],
                      gyro_offset is not None, accel_offset is not None, out)
        return out


_NO_OFFSET = np.zeros((1, 3))


@numba.njit(**JIT_OPTIONS)
def _correct_rows(  # pragma: no cover - compiled; tested through RowCorrector.rows
        rows: NDArray[np.uint8], matrix: NDArray[np.float64], bias: NDArray[np.float64],
        use_matrix: NDArray[np.bool_], gyro_offset: NDArray[np.float64],
        accel_offset: NDArray[np.float64], use_gyro_offset: bool, use_accel_offset: bool,
        out: NDArray[np.uint8]) -> None:
    """Write :meth:`RowCorrector.rows`' rows into ``out``."""
    tail0 = rows.shape[1] - _TAIL_BYTES
    for i in range(rows.shape[0]):
        out[i] = rows[i]
        src = rows[i, tail0:].view(np.float64)
        dst = out[i, tail0:].view(np.float64)
        for s, k, o, use_o in ((0, _GYRO, gyro_offset, use_gyro_offset),
                               (1, _ACCEL, accel_offset, use_accel_offset)):
            d0, d1, d2 = src[k] - bias[s, 0], src[k + 1] - bias[s, 1], src[k + 2] - bias[s, 2]
            m = matrix[s]
            for r in range(3):
                # summed as SensorCalibration.apply sums it
                y = (d0 * m[r, 0] + d1 * m[r, 1]) + d2 * m[r, 2] if use_matrix[s] else (
                    d0, d1, d2)[r]
                dst[k + r] = y - o[i, r] if use_o else y


def row_messages(rows: NDArray[np.uint8]) -> list[bytes]:
    """Return the rows of a uint8 matrix as one bytes object per row (one message each)."""
    n, size = rows.shape
    blob = rows.tobytes()
    return [blob[i:i + size] for i in range(0, n * size, size)]


def rows_stamps(rows: NDArray[np.uint8]) -> NDArray[np.int64]:
    """
    Return the header stamps of :func:`imu_rows`' rows.

    Parameters
    ----------
    rows : numpy.ndarray of uint8, shape (n, size)
        Messages, one per row.

    Returns
    -------
    numpy.ndarray of int64, shape (n,)
        ``sec * 1e9 + nanosec`` (ns).

    """
    sec = np.ascontiguousarray(rows[:, 4:8]).view('<i4')[:, 0].astype(np.int64)
    nsec = np.ascontiguousarray(rows[:, 8:12]).view('<u4')[:, 0].astype(np.int64)
    return sec * NS_PER_S + nsec


def rows_tail(rows: NDArray[np.uint8], tail_f8: int) -> NDArray[np.float64]:
    """Return the float64 block of :func:`imu_rows`' rows, ``(n, tail_f8)``, a copy."""
    return np.ascontiguousarray(rows[:, rows.shape[1] - 8 * tail_f8:]).view('<f8').copy()


def rows_vectors(rows: NDArray[np.uint8]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    Return ``angular_velocity`` and ``linear_acceleration`` of :func:`imu_rows`' rows.

    Parameters
    ----------
    rows : numpy.ndarray of uint8, shape (n, size)
        Messages, one per row.

    Returns
    -------
    gyro, accel : numpy.ndarray of float64, shape (n, 3)
        rad/s and m/s^2, copies.

    """
    tail = np.ascontiguousarray(rows[:, rows.shape[1] - _TAIL_BYTES:]).view('<f8')
    return tail[:, _GYRO:_GYRO + 3].astype(np.float64), tail[:, _ACCEL:_ACCEL + 3].astype(
        np.float64)


def patch_rows(rows: NDArray[np.uint8], gyro_rad_s: ArrayLike,
               accel_m_s2: ArrayLike) -> list[bytes]:
    """
    Re-serialise :func:`imu_rows`' rows with a new angular velocity and linear acceleration.

    Everything else stays byte for byte, as :func:`.imu.patch_imu_spans` does.

    Parameters
    ----------
    rows : numpy.ndarray of uint8, shape (n, size)
        Messages, one per row (left unchanged).
    gyro_rad_s : array_like of float, shape (n, 3)
        New angular velocity (rad/s).
    accel_m_s2 : array_like of float, shape (n, 3)
        New linear acceleration (m/s^2).

    Returns
    -------
    list of bytes
        One message per row.

    """
    size = rows.shape[1]
    out = rows.copy()
    tail = out[:, size - _TAIL_BYTES:].view('<f8')
    tail[:, _GYRO:_GYRO + 3] = gyro_rad_s
    tail[:, _ACCEL:_ACCEL + 3] = accel_m_s2
    return row_messages(out)
