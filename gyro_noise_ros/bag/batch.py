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
Decoded ``sensor_msgs/Imu`` batches, and the decoding of lists of raw messages into them.

A list of raw messages is what a ``raw=True`` rclpy subscription delivers; the bag reader and the
table reader serve the same :class:`ImuBatch`. The bytes are read by :mod:`gyro_noise_ros.msgs`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError
from ..msgs import decode_imu_spans, decode_temperature_spans, frame_id_of, join_raws


@dataclass(frozen=True)
class ImuBatch:
    """
    Consecutive ``sensor_msgs/Imu`` messages of one topic, decoded to arrays.

    Attributes
    ----------
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns (``sec * 1e9 + nanosec``), in recorded order (not sorted).
    log_ns : numpy.ndarray of int64, shape (n,)
        Time the recorder received each message (bag time), in ns.
    gyro : numpy.ndarray of float64, shape (n, 3)
        ``angular_velocity`` x, y, z in rad/s; NaN stays NaN.
    accel : numpy.ndarray of float64, shape (n, 3)
        ``linear_acceleration`` x, y, z in m/s^2.
    frame_id : str
        ``header.frame_id`` of the batch's first message.

    """

    stamp_ns: np.ndarray
    log_ns: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    frame_id: str

    def __len__(self) -> int:
        return int(self.stamp_ns.shape[0])


def decode_imu(raws: Sequence[bytes], *, log_ns: ArrayLike | None = None, ros1: bool = False,
               skip_undecodable: bool = False) -> ImuBatch:
    """
    Decode raw ``sensor_msgs/Imu`` messages in bulk.

    Parameters
    ----------
    raws : sequence of bytes-like
        Serialised messages: ROS 2 CDR (either endianness), or ROS 1 with ``ros1=True``.
    log_ns : array_like of int, shape (n,), optional
        Receive times in ns; the header stamps if None.
    ros1 : bool
        Messages use the ROS 1 serialisation.
    skip_undecodable : bool
        Drop messages neither the bulk nor rosbags' decoder can read instead of raising.

    Returns
    -------
    ImuBatch
        ``len(batch) < len(raws)`` only when messages were skipped.

    Raises
    ------
    BagError
        A message cannot be decoded and ``skip_undecodable`` is False.

    """
    buf, starts, lengths = join_raws(raws)
    keep, stamp_ns, gyro, accel = decode_imu_spans(buf, starts, lengths, ros1, skip_undecodable)
    if log_ns is None:
        log = stamp_ns.copy()
    else:
        log = np.asarray(log_ns, dtype=np.int64).reshape(-1)
        if log.shape[0] != len(raws):
            raise ParameterError(f'log_ns has {log.shape[0]} values for {len(raws)} messages')
        log = log if keep is None else log[keep]
    first = 0 if keep is None else (int(keep[0]) if keep.size else None)
    frame_id = (frame_id_of(raws[first], ros1) or '') if first is not None and len(raws) else ''
    return ImuBatch(stamp_ns, log, gyro, accel, frame_id)


def decode_temperature(raws: Sequence[bytes], *,
                       ros1: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """
    Decode raw ``sensor_msgs/Temperature`` messages in bulk (ROS 2 CDR, or ROS 1 with ``ros1``).

    Returns ``(stamp_ns, temperature_c)``, shape (n,) each: the header stamps (int64 ns) and the
    ``temperature`` fields (float64 degC). Raises BagError when a message cannot be decoded.
    """
    return decode_temperature_spans(*join_raws(raws), ros1)
