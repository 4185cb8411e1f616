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
``sensor_msgs/Temperature``: bulk decode and encode of CDR (and ROS 1) messages.

After the header (see :mod:`.cdr`) come two float64: ``temperature`` (degC) and ``variance``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .cdr import decode_spans, encode_cdr, encode_cdr_rows, slow_decode
from .stamps import Parts, split_stamps, stamp_ns_of
from ..errors import ParameterError

TEMPERATURE_MSGTYPE = 'sensor_msgs/msg/Temperature'
#: float64 after the header: temperature, variance.
TEMPERATURE_TAIL_F8 = 2
#: (first float64, count) of temperature within the Temperature float block.
TEMPERATURE_FIELDS = ((0, 1),)


def decode_temperature_spans(buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
                             ros1: bool) -> tuple[np.ndarray, np.ndarray]:
    """Decode Temperature messages located by spans; return (stamp_ns, temperature_c)."""
    ok, stamp_ns, values = decode_spans(
        buf, starts, lengths, TEMPERATURE_TAIL_F8, TEMPERATURE_FIELDS, ros1)
    for i in np.flatnonzero(~ok):
        msg = slow_decode(buf[starts[i]:starts[i] + lengths[i]].tobytes(),
                          TEMPERATURE_MSGTYPE, ros1)
        stamp_ns[i] = stamp_ns_of(msg)
        values[i, 0] = msg.temperature
    return stamp_ns, values[:, 0].copy()


def temperature_variances(raws: Sequence[bytes]) -> np.ndarray:
    """
    Return the ``variance`` fields (degC^2) of raw ROS 2 CDR ``sensor_msgs/Temperature`` messages.

    It is the last float64 of a message (``temperature``, ``variance`` follow the header); either
    endianness.
    """
    return np.array([np.frombuffer(raw[-8:], '<f8' if raw[1] == 1 else '>f8')[0] for raw in raws])


# ---------------------------------------------------------------------------------------------
# Encoding


def encode_temperature_cdr(stamp_ns: ArrayLike, temperature_c: ArrayLike, *,
                           frame_id: str = 'imu_link', variance: ArrayLike = 0.0) -> list[bytes]:
    """
    Serialise ``sensor_msgs/Temperature`` messages to little-endian CDR in bulk: one per stamp.

    ``stamp_ns`` are the header stamps (int ns, shape (n,)), ``temperature_c`` the temperatures
    (degC), ``variance`` their variance (degC^2, scalar or per message; 0 = unknown).
    """
    return encode_cdr(*_temperature_parts(stamp_ns, temperature_c, frame_id, variance))


def encode_temperature_rows(stamp_ns: ArrayLike, temperature_c: ArrayLike, *,
                            frame_id: str = 'imu_link', variance: ArrayLike = 0.0) -> np.ndarray:
    """
    Serialise like :func:`encode_temperature_cdr`, as a uint8 matrix of one message per row.

    ``rows[i].tobytes() == encode_temperature_cdr(...)[i]``; shape (n, message size).
    """
    return encode_cdr_rows(*_temperature_parts(stamp_ns, temperature_c, frame_id, variance))


def _temperature_parts(stamp_ns: ArrayLike, temperature_c: ArrayLike, frame_id: str,
                       variance: ArrayLike) -> Parts:
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
