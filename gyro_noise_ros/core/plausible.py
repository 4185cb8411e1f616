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
Magnitudes no inertial sensor reports: corrupt records, not measurements.

A finite value such as 1e300 rad/s is not a noise sample but a broken record (a mis-decoded
field, a wrong unit, a sentinel): kept, its square overflows every moment and Allan sum to
``inf`` (numpy warnings, NaN results, a static-segment search that finds nothing). The limits sit
far above every sensor and far below overflow:

* angular rate: 1e6 rad/s (5.7e7 deg/s). The widest MEMS gyro ranges are about +-5e4 deg/s
  (873 rad/s), so the limit is over 1000 times any full scale; a sum of squares of 1e10 such
  samples is 1e22, far from the float64 limit of 1.8e308.
* specific force: 1e8 m/s^2 (about 1e7 g), 50 times the +-2e5 g of shock accelerometers.

The tools treat a sample beyond its limit as unusable, like NaN: ``gyro_noise_analyze`` counts it
and leaves its chunk out, ``gyro_noise_explain`` refuses the record (exit code 4) as it does NaN.
"""

import numpy as np
from numpy.typing import ArrayLike

#: Largest angular rate magnitude (rad/s) taken as a measurement.
MAX_RATE_RAD_S = 1e6
#: Largest specific force magnitude (m/s^2) taken as a measurement.
MAX_SPECIFIC_FORCE_M_S2 = 1e8


def non_physical(values: ArrayLike, limit: float) -> np.ndarray:
    """
    Mark finite values whose magnitude exceeds ``limit``.

    Parameters
    ----------
    values : array_like
        Samples (NaN and Inf are not marked: they are counted as such elsewhere).
    limit : float
        Largest plausible magnitude, in the unit of ``values``.

    Returns
    -------
    numpy.ndarray of bool
        Same shape as ``values``.

    """
    v = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid='ignore'):
        return np.isfinite(v) & (np.abs(v) > limit)


def mask_non_physical(values: ArrayLike, limit: float) -> tuple[np.ndarray, int]:
    """
    Replace values beyond ``limit`` by NaN (so they count as unusable samples).

    Parameters
    ----------
    values : array_like
        Samples.
    limit : float
        Largest plausible magnitude, in the unit of ``values``.

    Returns
    -------
    tuple
        ``(values, count)``: the input itself when nothing is beyond the limit, else a copy with
        NaN in place of each value beyond it; ``count`` is how many were replaced.

    """
    v = np.asarray(values, dtype=np.float64)
    bad = non_physical(v, limit)
    count = int(np.count_nonzero(bad))
    if not count:
        return v, 0
    v = v.copy()
    v[bad] = np.nan
    return v, count
