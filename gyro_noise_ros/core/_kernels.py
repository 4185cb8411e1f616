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
numba kernels of the core (private).

Every kernel here is called only through a public wrapper that validates its input (finite values,
shapes, dtypes); each has a plain-numpy twin in ``test/`` it is checked against. All kernels share
one set of compilation flags, :data:`gyro_noise_ros.core.jit.JIT_OPTIONS`.
"""

import numba
import numpy as np
from numpy.typing import NDArray

from .jit import JIT_OPTIONS


@numba.njit(**JIT_OPTIONS)
def _fractional_recursion(  # pragma: no cover - compiled
        w: NDArray[np.float64], history: NDArray[np.float64], c_rev: NDArray[np.float64], f: float,
        out: NDArray[np.float64]) -> NDArray[np.float64]:
    """
    Run the recursion of paper 000 eq. (2) for ``len(w)`` steps.

    ``history`` holds the last ``L`` outputs (oldest first, zeros before the start, which is how
    the truncation L(k) = min(k, L) of eq. (5) enters); ``c_rev`` is (c_L, ..., c_1), the GL
    coefficients of eq. (4) without c_0 = 1, reversed so the inner product runs over contiguous
    memory. v[k+1] = f v[k] + w[k] - sum_{j=1}^{L} c_j v[k+1-j]. Returns the updated history.
    """
    big_l = c_rev.shape[0]
    n = w.shape[0]
    buf = np.empty(big_l + n, dtype=np.float64)
    buf[:big_l] = history
    for i in range(n):
        # buf[i + L - 1] is v[k] (the newest value before the one being produced)
        # four independent partial sums break the add-latency chain without fastmath
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        t = 0
        while t + 3 < big_l:
            s0 += c_rev[t] * buf[i + t]
            s1 += c_rev[t + 1] * buf[i + t + 1]
            s2 += c_rev[t + 2] * buf[i + t + 2]
            s3 += c_rev[t + 3] * buf[i + t + 3]
            t += 4
        while t < big_l:
            s0 += c_rev[t] * buf[i + t]
            t += 1
        s = (s0 + s1) + (s2 + s3)
        v_next = f * buf[i + big_l - 1] + w[i] - s
        buf[i + big_l] = v_next
        out[i] = v_next
    return buf[n:].copy()
