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
LSM6DSO32 scaling of raw output words to SI units.

ST datasheet, "Mechanical characteristics" and "Temperature sensor characteristics" tables.

================  ============================  =============================
full scale        sensitivity (typ.)            one LSB in SI
================  ============================  =============================
gyro +/-125 dps   4.375 mdps/LSB                7.6358e-5 rad/s
gyro +/-250 dps   8.75 mdps/LSB                 1.5272e-4 rad/s
gyro +/-500 dps   17.50 mdps/LSB                3.0543e-4 rad/s
gyro +/-1000 dps  35 mdps/LSB                   6.1087e-4 rad/s
gyro +/-2000 dps  70 mdps/LSB                   1.2217e-3 rad/s
accel +/-4 g      0.122 mg/LSB                  1.19641e-3 m/s^2
accel +/-8 g      0.244 mg/LSB                  2.39282e-3 m/s^2
accel +/-16 g     0.488 mg/LSB                  4.78565e-3 m/s^2
accel +/-32 g     0.976 mg/LSB                  9.57129e-3 m/s^2
temperature       256 LSB/degC, 0 LSB = 25 degC
================  ============================  =============================

with g = 9.80665 m/s^2 (standard gravity). Gyro rate noise density in high-performance mode: 3.8
mdps/sqrt(Hz) typical, the LSM6DSO family figure (LSM6DSO datasheet DS12140, table 2, "independent
of the ODR and FS"); ``emulator.BoardModel`` derives its default noise level from it (see there).
"""

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError
from ..units import STANDARD_GRAVITY_M_S2

GYRO_FULL_SCALES_DPS = (125, 250, 500, 1000, 2000)
ACCEL_FULL_SCALES_G = (4, 8, 16, 32)
#: Output data rates of CTRL1_XL/CTRL2_G in high-performance mode (Hz). The datasheet labels them
#: 12.5, 26, 52, 104, 208, 416, 833, 1666, 3332, 6664 (or 1.66k, 3.33k, 6.66k); the values here are
#: ST's driver names (``LSM6DSO32_GY_ODR_6667Hz``...). The sensor's own oscillator sets the true
#: rate (+/- a few %).
ODRS_HZ = (12.5, 26.0, 52.0, 104.0, 208.0, 417.0, 833.0, 1667.0, 3333.0, 6667.0)

_GYRO_MDPS_PER_LSB = {125: 4.375, 250: 8.75, 500: 17.5, 1000: 35.0, 2000: 70.0}
_ACCEL_MG_PER_LSB = {4: 0.122, 8: 0.244, 16: 0.488, 32: 0.976}
TEMPERATURE_LSB_PER_C = 256.0
TEMPERATURE_OFFSET_C = 25.0
#: Typical gyro rate noise density, high-performance mode (mdps/sqrt(Hz)).
GYRO_NOISE_DENSITY_MDPS_RTHZ = 3.8
#: Relative tolerance when matching a requested ODR to the table (416 and 1660 name 417 and 1667).
ODR_REL_TOL = 0.005


def _as_int_choice(name: str, value: Any, choices: tuple[int, ...]) -> int:
    try:
        as_float = float(value)
    except (TypeError, ValueError) as err:
        raise ParameterError(f'{name} must be one of {choices}, got {value!r}') from err
    if not np.isfinite(as_float) or as_float != int(as_float) or int(as_float) not in choices:
        raise ParameterError(f'{name} must be one of {choices}, got {value!r}')
    return int(as_float)


def check_gyro_fs(fs_dps: Any) -> int:
    """Return gyro full scale ``fs_dps`` (deg/s) as an int; ParameterError if not offered."""
    return _as_int_choice('gyro_fs_dps', fs_dps, GYRO_FULL_SCALES_DPS)


def check_accel_fs(fs_g: Any) -> int:
    """Return accelerometer full scale ``fs_g`` (g) as an int; ParameterError if not offered."""
    return _as_int_choice('accel_fs_g', fs_g, ACCEL_FULL_SCALES_G)


def check_odr(odr_hz: Any) -> float:
    """
    Match an output data rate to the datasheet table.

    Parameters
    ----------
    odr_hz : float
        Requested rate (Hz); within 0.5 % of a table entry.

    Returns
    -------
    float
        The table value.

    """
    try:
        value = float(odr_hz)
    except (TypeError, ValueError) as err:
        raise ParameterError(f'odr_hz must be one of {ODRS_HZ}, got {odr_hz!r}') from err
    for rate in ODRS_HZ:
        if np.isfinite(value) and abs(value - rate) <= ODR_REL_TOL * rate:
            return rate
    raise ParameterError(f'odr_hz must be one of {ODRS_HZ} (within 0.5 %), got {odr_hz!r}')


def gyro_sensitivity_rad_s_per_lsb(fs_dps: int) -> float:
    """
    Return the gyro sensitivity (rad/s per LSB) of full scale ``fs_dps`` (125-2000 deg/s).

    The datasheet's mdps/LSB times pi/180000.
    """
    return _GYRO_MDPS_PER_LSB[check_gyro_fs(fs_dps)] * 1e-3 * np.pi / 180.0


def accel_sensitivity_m_s2_per_lsb(fs_g: int) -> float:
    """
    Return the accelerometer sensitivity (m/s^2 per LSB) of full scale ``fs_g`` (4, 8, 16 or 32 g).

    The datasheet's mg/LSB times 9.80665e-3.
    """
    return _ACCEL_MG_PER_LSB[check_accel_fs(fs_g)] * 1e-3 * STANDARD_GRAVITY_M_S2


def temperature_c(raw: ArrayLike) -> np.ndarray:
    """Convert raw OUT_TEMP words (int16) to degC, float64: 25 + raw / 256."""
    return TEMPERATURE_OFFSET_C + np.asarray(raw, dtype=np.float64) / TEMPERATURE_LSB_PER_C


@dataclass(frozen=True)
class Scaled:
    """
    Samples in SI units.

    Attributes
    ----------
    gyro_rad_s : numpy.ndarray
        (n, 3) float64 angular rate (rad/s).
    accel_m_s2 : numpy.ndarray
        (n, 3) float64 specific force (m/s^2).
    temperature_c : numpy.ndarray
        (n,) float64 die temperature (degC).

    """

    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    temperature_c: np.ndarray


def to_si(samples: np.ndarray, *, gyro_fs_dps: int, accel_fs_g: int) -> 'Scaled':
    """
    Scale raw samples to SI units.

    Parameters
    ----------
    samples : numpy.ndarray
        Records with int16 fields ``gyro`` (n, 3), ``accel`` (n, 3) and ``temp`` (n,)
        (``protocol.SAMPLE_DTYPE``).
    gyro_fs_dps : int, keyword-only
        Gyro full scale in force when the samples were taken (deg/s).
    accel_fs_g : int, keyword-only
        Accelerometer full scale in force (g).

    Returns
    -------
    Scaled

    """
    g_lsb = gyro_sensitivity_rad_s_per_lsb(gyro_fs_dps)
    a_lsb = accel_sensitivity_m_s2_per_lsb(accel_fs_g)
    samples = np.asarray(samples)
    try:
        # one pass each: int16 -> float64 is exact, so this rounds as astype() then multiply
        gyro = np.multiply(samples['gyro'], g_lsb, dtype=np.float64)
        accel = np.multiply(samples['accel'], a_lsb, dtype=np.float64)
        temp = temperature_c(samples['temp'])
    except (ValueError, KeyError, IndexError) as err:
        raise ParameterError(
            f'samples must have fields gyro, accel, temp, got dtype {samples.dtype}') from err
    return Scaled(gyro.reshape(-1, 3), accel.reshape(-1, 3), temp.reshape(-1))


def quantise(values: ArrayLike, lsb: float) -> np.ndarray:
    """
    Quantise physical values to int16 output words, clipped to the full scale.

    Parameters
    ----------
    values : array_like
        Physical values in the unit of ``lsb``.
    lsb : float
        Value of one LSB (same unit).

    Returns
    -------
    numpy.ndarray
        int16 words, round to nearest, saturating at -32768 and 32767 like the sensor.

    """
    words = np.rint(np.asarray(values, dtype=np.float64) / lsb)
    return np.clip(words, -32768, 32767).astype(np.int16)
