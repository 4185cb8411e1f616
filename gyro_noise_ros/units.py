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

The display policy of every report (:class:`Display` constants, :data:`UNIT_POLICY`, stated on
each page) names one unit per quantity, so a number reads the same on every page.
"""

from dataclasses import dataclass
import math

__all__ = ['ACCEL', 'ACCEL_ADEV', 'ACCEL_RW', 'ACCEL_VRW', 'DEG_TO_RAD', 'Display', 'GYRO_ADEV',
           'GYRO_ARW', 'GYRO_RATE', 'GYRO_RRW', 'MG_TO_M_S2', 'RAD_TO_DEG', 'S_PER_H',
           'STANDARD_GRAVITY_M_S2', 'UNIT_POLICY', 'time_unit']

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


@dataclass(frozen=True)
class Display:
    """
    How one quantity is shown at an edge: its unit and the factor from its SI value.

    Attributes
    ----------
    unit : str
        The unit's name as printed (``'deg/h'``).
    per_si : float
        Displayed value per SI value (``value_si * per_si`` is shown).

    """

    unit: str
    per_si: float


#: Angular rate, a bias, a time series of it (rad/s -> deg/s).
GYRO_RATE = Display('deg/s', RAD_TO_DEG)
#: Allan deviation of the angular rate, bias stability, B (rad/s -> deg/h).
GYRO_ADEV = Display('deg/h', RAD_TO_DEG * S_PER_H)
#: Angle random walk N (rad/sqrt(s) -> deg/sqrt(h): sqrt(3600 s) = 60 sqrt(s) per sqrt(h)).
GYRO_ARW = Display('deg/sqrt(h)', RAD_TO_DEG * 60.0)
#: Rate random walk K (rad/s/sqrt(s) -> deg/h/sqrt(h)).
GYRO_RRW = Display('deg/h/sqrt(h)', RAD_TO_DEG * S_PER_H * 60.0)
#: Specific force, an accelerometer bias or residual (m/s^2 -> mg).
ACCEL = Display('mg', 1.0 / MG_TO_M_S2)
#: Allan deviation of the specific force, its bias stability and B (m/s^2 -> mg).
ACCEL_ADEV = ACCEL
#: Velocity random walk (m/s^2/sqrt(Hz) = m/s/sqrt(s) -> m/s/sqrt(h)).
ACCEL_VRW = Display('m/s/sqrt(h)', 60.0)
#: Acceleration random walk (m/s^3/sqrt(Hz) = m/s^2/sqrt(s) -> m/s/h/sqrt(h)).
ACCEL_RW = Display('m/s/h/sqrt(h)', S_PER_H * 60.0)

#: The display policy in one sentence, stated on every report page.
UNIT_POLICY = (
    'Units: angular rate in deg/s; its Allan deviation, bias stability and B in deg/h; angle '
    'random walk in deg/sqrt(h); rate random walk in deg/h/sqrt(h); specific force, its Allan '
    'deviation and bias stability in mg; velocity random walk in m/s/sqrt(h); SI beside them '
    'where a program reads them (imu.yaml, the JSON files); time in s, min or h to fit the '
    'record.')


def time_unit(span_s: float) -> Display:
    """
    Return the unit of a time axis that fits a record: s up to 10 min, min up to 3 h, else h.

    Parameters
    ----------
    span_s : float
        The time the axis spans (s); NaN gives seconds.

    Returns
    -------
    Display
        ``per_si`` turns seconds into the unit (1, 1/60 or 1/3600).

    """
    if not span_s <= 3 * S_PER_H:
        return Display('h', 1.0 / S_PER_H) if math.isfinite(span_s) else Display('s', 1.0)
    if span_s > 600.0:
        return Display('min', 1.0 / 60.0)
    return Display('s', 1.0)
