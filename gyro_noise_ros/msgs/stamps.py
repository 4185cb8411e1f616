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
Header stamps: integer nanoseconds to and from ``builtin_interfaces/Time``, and their order.

Every stamp inside the package is an int64 count of nanoseconds; ``sec`` and ``nanosec`` exist
only on the wire (ROS 2 keeps ``nanosec`` in [0, 1e9) also for negative times).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError

NS_PER_S = 1_000_000_000

#: ``(sec, nsec, frame_id, tail)`` of messages to encode (:func:`.cdr.encode_cdr`).
Parts = tuple[np.ndarray, np.ndarray, str, np.ndarray]


def split_stamps(stamp_ns: ArrayLike, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
    sec = np.floor_divide(stamps, NS_PER_S)
    nsec = stamps - sec * NS_PER_S
    if stamps.size and (sec.min() < -(2**31) or sec.max() >= 2**31):
        worst = int(stamps[np.argmax(np.abs(sec))])
        raise ParameterError(
            f'{name} {worst} does not fit builtin_interfaces/Time (int32 seconds)')
    return stamps, sec, nsec


def stamp_ns_of(msg: Any) -> int:
    """Return ``header.stamp`` of a deserialised message in ns."""
    return int(msg.header.stamp.sec) * NS_PER_S + int(msg.header.stamp.nanosec)


def count_stamp_regressions(stamp_ns: ArrayLike, *, previous_ns: int | None = None) -> int:
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
