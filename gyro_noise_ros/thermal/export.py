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
A fitted temperature polynomial as PX4 and ArduPilot parameters.

Both autopilots compensate a sensor offset with a cubic in temperature, held at the ends of the
calibrated range, but write it differently:

**PX4** (https://docs.px4.io/main/en/advanced_config/sensor_thermal_calibration.html,
"Calibration Parameter Usage")::

    delta  = clip(T, TC_G0_TMIN, TC_G0_TMAX) - TC_G0_TREF
    offset = X0 + X1 delta + X2 delta^2 + X3 delta^3        (TC_G0_X<n>_<axis>, axis 0 1 2)
    corrected = raw - offset

in rad/s for the gyro (``TC_G0_*``) and m/s^2 for the accelerometer (``TC_A0_*``), enabled by
``TC_G_ENABLE`` / ``TC_A_ENABLE`` = 1, matched to the sensor by ``TC_G0_ID`` / ``TC_A0_ID`` (the
device id PX4 reports; 0 here unless given). The file is a QGroundControl parameter file, as
PX4's own ``Tools/process_sensor_caldata.py`` writes it: ``#`` comments, then one line per
parameter ``vehicle-id <tab> component-id <tab> name <tab> value <tab> type`` (type 6 int32,
9 float). This package's ``poly3`` is this form exactly (T_ref the middle of the range).

**ArduPilot** (https://ardupilot.org/copter/docs/common-imutempcal.html; parameters
``INS_TCAL1_ENABLE``, ``INS_TCAL1_TMIN``, ``INS_TCAL1_TMAX``, ``INS_TCAL1_GYR<k>_<X|Y|Z>``,
``INS_TCAL1_ACC<k>_<X|Y|Z>``): a fixed reference of 35 degC, no constant term, coefficients
stored times 1e6 (SI per degC^k)::

    P(u)  = (c1 u + c2 u^2 + c3 u^3),   c_k = INS_TCAL1_GYR<k>_<axis> / 1e6
    corrected = raw - OFFS - P(clip(T) - 35) + P(clip(CALTEMP) - 35)

where ``OFFS`` is the ordinary offset (``INS_GYROFFS_<axis>``, rad/s) measured at ``CALTEMP``
(``INS_GYR1_CALTEMP``). The polynomial is re-expanded about 35 degC; written with
``INS_GYROFFS_*`` = the model's offset at ``CALTEMP`` (the model's T_ref unless given) the
ArduPilot formula gives back the model exactly. ArduPilot re-measures the gyro offsets at boot
by default (``INS_GYRO_CAL``), and then only the temperature-dependent part matters. For the
accelerometer only the coefficients are written: its offset and scale are the six-position
calibration's (``INS_ACCOFFS``, ``INS_ACC1_CALTEMP``), and the compensated change is relative to
that calibration's temperature, which is what a relative polynomial (``fit_accel``) describes.
The file is an ArduPilot ``.parm`` file: ``NAME VALUE`` per line (``#`` comments), as Mission
Planner and MAVProxy load.
"""

from collections.abc import Iterable
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from ..outputs import atomic_write_text, StrPath

__all__ = ['ARDUPILOT_SCALE', 'ARDUPILOT_TREF_C', 'CubicCalibration', 'ardupilot_parameters',
           'calibration_of', 'px4_parameters', 'write_ardupilot_parm', 'write_px4_params']

#: ArduPilot's fixed reference temperature of INS_TCAL (degC).
ARDUPILOT_TREF_C = 35.0
#: ArduPilot stores the INS_TCAL coefficients times this.
ARDUPILOT_SCALE = 1.0e6
#: MAVLink parameter types in a QGroundControl file.
PX4_INT32, PX4_FLOAT = 6, 9
AXES = 'XYZ'


@dataclass(frozen=True)
class CubicCalibration:
    """
    An offset cubic in temperature, held outside its range: what both autopilots evaluate.

    Attributes
    ----------
    coef : numpy.ndarray
        (3, 4) per axis, lowest power first: offset = sum_i coef[axis, i] (T - t_ref_c)^i, in
        the sensor's SI unit per degC^i.
    t_ref_c, t_min_c, t_max_c : float
        Reference temperature and the calibrated range (degC).
    unit : str
        'rad/s' (gyro) or 'm/s^2' (accelerometer).

    """

    coef: np.ndarray
    t_ref_c: float
    t_min_c: float
    t_max_c: float
    unit: str = 'rad/s'

    def offset(self, temperature_c: ArrayLike) -> NDArray[np.float64]:
        """
        Return the offset at temperatures (degC), the temperature held within the range.

        Parameters
        ----------
        temperature_c : array_like
            (n,) degC.

        Returns
        -------
        numpy.ndarray
            (n, 3).

        """
        d = np.clip(np.asarray(temperature_c, dtype=float).reshape(-1), self.t_min_c,
                    self.t_max_c) - self.t_ref_c
        return np.polynomial.polynomial.polyval(d, self.coef.T).T.reshape(-1, 3)

    def about(self, t_ref_c: float) -> NDArray[np.float64]:
        """
        Return the coefficients re-expanded about another reference temperature.

        ``sum_i a_i (T - r)^i = sum_j b_j (T - s)^j`` with ``T - r = (T - s) + (s - r)``:
        ``b_j = sum_{i >= j} a_i C(i, j) (s - r)^(i - j)``.

        Parameters
        ----------
        t_ref_c : float
            The new reference s (degC).

        Returns
        -------
        numpy.ndarray
            (3, 4), lowest power first.

        """
        shift = float(t_ref_c) - self.t_ref_c
        out = np.zeros_like(self.coef)
        for i in range(4):
            for j in range(i + 1):
                out[:, j] += self.coef[:, i] * math.comb(i, j) * shift ** (i - j)
        return out


def calibration_of(poly: Any, *, unit: str = 'rad/s') -> CubicCalibration:
    """
    Turn a fitted ``poly3`` (order <= 3) into a :class:`CubicCalibration`.

    Parameters
    ----------
    poly : TemperaturePolynomial
        The fitted polynomial (gyro, or the accelerometer's relative one).
    unit : str, keyword-only
        Its output unit.

    Returns
    -------
    CubicCalibration

    Raises
    ------
    ParameterError
        Not a fitted polynomial of T of order <= 3 (a method using dT cannot be exported: the
        autopilots evaluate a polynomial of T only).

    """
    name = getattr(poly, 'name', type(poly).__name__)
    if name != 'poly3' or getattr(poly, 'coef', None) is None:
        raise ParameterError(f"method '{name}' cannot be exported to PX4 or ArduPilot: they "
                             'evaluate a cubic in temperature only; fit with {method} poly3',
                             parameters=('method',))
    if poly.order > 3:
        raise ParameterError(f'a polynomial of order {poly.order} cannot be exported (PX4 and '
                             'ArduPilot evaluate order 3)')
    coef = np.zeros((3, 4))
    coef[:, :poly.order + 1] = poly.coef
    return CubicCalibration(coef=coef, t_ref_c=float(poly.t_ref_c), t_min_c=float(poly.t_min_c),
                            t_max_c=float(poly.t_max_c), unit=unit)


def _check_range(cal: CubicCalibration, low: float, high: float, who: str) -> None:
    if not (low <= cal.t_min_c and cal.t_max_c <= high):
        raise ParameterError(f'{who} accepts {low:g}..{high:g} degC; the calibration spans '
                             f'{cal.t_min_c:.2f}..{cal.t_max_c:.2f} degC')


def px4_parameters(gyro: CubicCalibration | None, accel: CubicCalibration | None = None, *,
                   instance: int = 0, gyro_device_id: int = 0,
                   accel_device_id: int = 0) -> list[tuple[str, float, int]]:
    """
    Return the PX4 thermal-compensation parameters of a gyro (and accelerometer) calibration.

    Parameters
    ----------
    gyro : CubicCalibration or None
        rad/s.
    accel : CubicCalibration, optional
        m/s^2.
    instance : int, keyword-only
        Sensor instance 0..2 (the ``0`` of ``TC_G0_*``).
    gyro_device_id, accel_device_id : int, keyword-only
        ``TC_G<i>_ID`` / ``TC_A<i>_ID``: the device id PX4 reports for the sensor (its
        ``CAL_GYRO<i>_ID`` / ``CAL_ACC<i>_ID``); 0 unknown.

    Returns
    -------
    list of (str, float or int, int)
        (name, value, MAVLink type) in file order.

    """
    if not (isinstance(instance, (int, np.integer)) and 0 <= instance <= 2):
        raise ParameterError(f'PX4 sensor instance must be 0, 1 or 2, got {instance!r}')
    out: list[tuple[str, float, int]] = []
    for letter, cal, dev in (('G', gyro, gyro_device_id), ('A', accel, accel_device_id)):
        if cal is None:
            continue
        p = f'TC_{letter}{instance}_'
        out.append((f'TC_{letter}_ENABLE', 1, PX4_INT32))
        out.append((p + 'ID', int(dev), PX4_INT32))
        out += [(p + 'TMIN', cal.t_min_c, PX4_FLOAT), (p + 'TMAX', cal.t_max_c, PX4_FLOAT),
                (p + 'TREF', cal.t_ref_c, PX4_FLOAT)]
        out += [(f'{p}X{i}_{axis}', float(cal.coef[axis, i]), PX4_FLOAT)
                for i in range(4) for axis in range(3)]
    if not out:
        raise ParameterError('nothing to export: no gyro and no accelerometer calibration')
    return out


def write_px4_params(path: StrPath, parameters: Iterable[tuple[str, float, int]], *,
                     comment: str = '') -> str:
    """
    Write PX4 parameters as a QGroundControl ``.params`` file (atomically).

    Parameters
    ----------
    path : str or os.PathLike
        File to write.
    parameters : list of (str, value, int)
        From :func:`px4_parameters`.
    comment : str, keyword-only
        Extra ``#`` lines (e.g. where the model came from).

    Returns
    -------
    str
        The text written.

    """
    lines = ['# Sensor thermal compensation parameters (gyro_noise_thermal export)']
    lines += [f'# {c}' for c in comment.splitlines() if c.strip()]
    lines += ['#', '# Vehicle-Id Component-Id Name Value Type']
    for name, value, kind in parameters:
        text = str(int(value)) if kind == PX4_INT32 else repr(float(value))
        lines.append(f'1\t1\t{name}\t{text}\t{kind}')
    text = '\n'.join(lines) + '\n'
    atomic_write_text(path, text)
    return text


def ardupilot_parameters(gyro: CubicCalibration | None, accel: CubicCalibration | None = None, *,
                         imu: int = 1, cal_temp_c: float | None = None,
                         gyro_offsets: bool = True) -> list[tuple[str, float]]:
    """
    Return the ArduPilot ``INS_TCAL<imu>_*`` parameters of a gyro (and accelerometer) calibration.

    Parameters
    ----------
    gyro : CubicCalibration or None
        rad/s.
    accel : CubicCalibration, optional
        m/s^2 (relative: its constant term is not exportable and must be 0).
    imu : int, keyword-only
        IMU number 1..3 (``INS_TCAL1``).
    cal_temp_c : float, optional, keyword-only
        ``INS_GYR<imu>_CALTEMP`` written with the gyro offsets (default: the gyro's T_ref).
    gyro_offsets : bool, keyword-only
        Also write ``INS_GYROFFS_*`` (``INS_GYR<imu>OFFS_*`` for imu > 1) and the CALTEMP, so the
        whole model (its constant included) is reproduced; ArduPilot overwrites both at boot
        when it calibrates the gyro then (``INS_GYRO_CAL``).

    Returns
    -------
    list of (str, float)
        (name, value) in file order.

    """
    if not (isinstance(imu, (int, np.integer)) and 1 <= imu <= 3):
        raise ParameterError(f'ArduPilot IMU number must be 1, 2 or 3, got {imu!r}')
    cals = [c for c in (gyro, accel) if c is not None]
    if not cals:
        raise ParameterError('nothing to export: no gyro and no accelerometer calibration')
    t_min, t_max = cals[0].t_min_c, cals[0].t_max_c
    cal: CubicCalibration | None
    for cal in cals:
        _check_range(cal, -70.0, 80.0, 'ArduPilot INS_TCAL')
        if (cal.t_min_c, cal.t_max_c) != (t_min, t_max):
            raise ParameterError('ArduPilot has one temperature range per IMU; the gyro and '
                                 'accelerometer calibrations span different ranges')
    p = f'INS_TCAL{imu}_'
    out = [(p + 'ENABLE', 1), (p + 'TMIN', t_min), (p + 'TMAX', t_max)]
    for tag, cal in (('ACC', accel), ('GYR', gyro)):
        if cal is None:
            continue
        c = cal.about(ARDUPILOT_TREF_C)
        out += [(f'{p}{tag}{k}_{AXES[axis]}', float(c[axis, k] * ARDUPILOT_SCALE))
                for k in (1, 2, 3) for axis in range(3)]
    if gyro is not None and gyro_offsets:
        cal_temp = gyro.t_ref_c if cal_temp_c is None else float(cal_temp_c)
        if not math.isfinite(cal_temp):
            raise ParameterError(f'CALTEMP must be finite, got {cal_temp_c!r}')
        offs = gyro.offset([cal_temp])[0]
        stem = 'INS_GYROFFS_' if imu == 1 else f'INS_GYR{imu}OFFS_'
        out += [(stem + AXES[axis], float(offs[axis])) for axis in range(3)]
        out.append((f'INS_GYR{imu}_CALTEMP', cal_temp))
    return out


def write_ardupilot_parm(path: StrPath, parameters: Iterable[tuple[str, float]], *,
                         comment: str = '') -> str:
    """
    Write ArduPilot parameters as a ``.parm`` file (``NAME VALUE`` lines, atomically).

    Parameters
    ----------
    path : str or os.PathLike
        File to write.
    parameters : list of (str, float)
        From :func:`ardupilot_parameters`.
    comment : str, keyword-only
        Extra ``#`` lines.

    Returns
    -------
    str
        The text written.

    """
    lines = ['# IMU temperature calibration (gyro_noise_thermal export)']
    lines += [f'# {c}' for c in comment.splitlines() if c.strip()]
    for name, value in parameters:
        text = str(int(value)) if name.endswith('_ENABLE') else repr(float(value))
        lines.append(f'{name} {text}')
    text = '\n'.join(lines) + '\n'
    atomic_write_text(path, text)
    return text
