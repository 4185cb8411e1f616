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
Unit factors: the one home of every conversion constant the package uses (pure, no ROS).

SI inside, other units only at the edges (reports, CSV columns, parameters named with the unit);
the conversion at an edge multiplies by one of these names, so a factor reads as what it does
(``x_rad_s * RAD_TO_DEG`` is deg/s) and never means the opposite in two modules.

The expressions are the ones the modules used before they shared them, so every value is the
same double: ``180.0 / math.pi`` (equal to ``180.0 / numpy.pi``) and ``math.pi / 180.0`` (equal to
``numpy.pi / 180.0`` and to ``math.radians(1.0)``). ``numpy.degrees(x)`` may differ from
``x * RAD_TO_DEG`` in the last bit; the modules that call it keep calling it.
"""

import math

__all__ = ['DEG_TO_RAD', 'MG_TO_M_S2', 'RAD_TO_DEG', 'S_PER_H', 'STANDARD_GRAVITY_M_S2']

#: Degrees per radian (rad -> deg).
RAD_TO_DEG: float = 180.0 / math.pi

#: Radians per degree (deg -> rad).
DEG_TO_RAD: float = math.pi / 180.0

#: Seconds per hour (h -> s; per-second rates times this are per-hour rates).
S_PER_H: float = 3600.0

#: Standard gravity (m/s^2 per g), the conventional value of CGPM 1901 (datasheets' g).
STANDARD_GRAVITY_M_S2: float = 9.80665

#: Milli-g (mg -> m/s^2), in standard gravity.
MG_TO_M_S2: float = STANDARD_GRAVITY_M_S2 * 1e-3
