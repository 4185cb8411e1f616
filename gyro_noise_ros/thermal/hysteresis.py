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
The play (backlash) operator: the state of a drift that depends on where the temperature turned.

``z[k] = min(max(z[k-1], x[k] - r), x[k] + r)``: z follows x with a play of half-width r, so
``z - x`` is ``-r`` while x rises, ``+r`` while it falls, and holds its value when x turns until
x has moved 2r. A drift term ``h (z - T)`` draws a loop of height ``2 h r`` in bias against
temperature. The simulator's drift law uses it (``thermal.simulate``), the least-squares oracle
and the ``lsq_cv`` method evaluate it on the measured temperature, and the live compensator
carries its state from one temperature message to the next.
"""

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.jit import JIT_OPTIONS
from ..errors import ParameterError

__all__ = ['play_operator']


@numba.njit(**JIT_OPTIONS)
def _play(x: NDArray[np.float64], r: float, z0: float,
          z_out: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """Run the play operator of half-width r: z = min(max(z_prev, x - r), x + r), from z0."""
    zp = z0
    for k in range(x.shape[0]):
        zp = min(max(zp, x[k] - r), x[k] + r)
        z_out[k] = zp


def play_operator(x: ArrayLike, half_width: float, *,
                  start: float | None = None) -> NDArray[np.float64]:
    """
    Apply the play (backlash) operator of half-width ``half_width`` to a sequence.

    ``z[k] = min(max(z[k-1], x[k] - r), x[k] + r)``, ``z[-1] = start`` (default ``x[0]``): the
    hysteresis state of the drift law, here for a measured temperature (the oracle on measured
    inputs).

    Parameters
    ----------
    x : array_like
        Input (n,), e.g. temperature in degC.
    half_width : float
        r (same unit, >= 0).
    start : float, optional, keyword-only
        State before the first sample.

    Returns
    -------
    numpy.ndarray
        z (n,).

    """
    x = np.ascontiguousarray(x, dtype=float).reshape(-1)
    if not (math.isfinite(half_width) and half_width >= 0):
        raise ParameterError(f'half_width must be finite and >= 0, got {half_width!r}')
    out = np.empty_like(x)
    if x.size:
        _play(x, float(half_width), float(x[0] if start is None else start), out)
    return out
