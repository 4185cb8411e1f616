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
A fitted temperature polynomial as PX4 and ArduPilot parameters, and what each firmware applies.

Both autopilots subtract a cubic in temperature, held at the ends of the calibrated range.
**PX4** (``TC_G<i>_*``, ``TC_A<i>_*``, i = 0..3): ``offset = X0 + X1 d + X2 d^2 + X3 d^3`` with
``d = clip(T, TMIN, TMAX) - TREF`` (rad/s, m/s^2), enabled by ``TC_G_ENABLE``/``TC_A_ENABLE``
and matched to a sensor by its 24-bit device id (:func:`px4_device_id`; without one the block
is written disabled: id 0 matches no sensor). Its ``temperature_compensation`` module evaluates
the offset at 1 Hz and publishes it only when the temperature moved more than 1 degC
(:func:`px4_applied_offset`). The file is a QGroundControl ``.params`` file as PX4's
``Tools/process_sensor_caldata.py`` writes it (type 6 int32, 9 float). **ArduPilot**
(``INS_TCAL<k>_*``): a fixed reference of 35 degC, no constant term, coefficients times 1e6;
``corrected = raw - OFFS - P(clip(T) - 35) + P(clip(CALTEMP) - 35)``, OFFS the ordinary offset
(``INS_GYROFFS_*``) measured at ``INS_GYR<k>_CALTEMP``, applied to every sample
(:func:`ardupilot_applied_offset`); written with OFFS = the model's offset at CALTEMP it gives
back the whole model. TMIN/TMAX have a documented range of -70..80 degC that the firmware does
not enforce (:func:`ardupilot_notes`). The accelerometer's polynomial is relative (its offset at
one temperature is the six-position calibration's). References, the steps on the vehicle and the
measured residual under each firmware's rule: ``docs/thermal.md``, "Export to PX4 and
ArduPilot".
"""

from collections.abc import Iterable
from dataclasses import dataclass, replace
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from ..outputs import atomic_write_text, StrPath

__all__ = ['ARDUPILOT_SCALE', 'ARDUPILOT_TREF_C', 'CubicCalibration', 'ardupilot_applied_offset',
           'ardupilot_notes', 'ardupilot_parameters', 'calibration_of', 'firmware_residuals',
           'px4_applied_offset', 'px4_device_id', 'px4_parameters', 'remap_axes',
           'write_ardupilot_parm', 'write_px4_params']

#: ArduPilot's fixed reference temperature of INS_TCAL (degC).
ARDUPILOT_TREF_C = 35.0
#: ArduPilot stores the INS_TCAL coefficients times this.
ARDUPILOT_SCALE = 1.0e6
#: ArduPilot's documented (not enforced) range of INS_TCAL<k>_TMIN/TMAX (degC).
ARDUPILOT_RANGE_C = (-70.0, 80.0)
#: MAVLink parameter types in a QGroundControl file.
PX4_INT32, PX4_FLOAT = 6, 9
#: PX4 thermal-compensation instances (TC_G0 .. TC_G3; GYRO_COUNT_MAX).
PX4_INSTANCES = 4
#: PX4 evaluates the offsets this often (s) and publishes them when the temperature moved more
#: than this (degC) since the last publication (``TemperatureCompensationModule``, 1 Hz;
#: ``TemperatureCompensation::update_offsets_gyro``).
PX4_PERIOD_S, PX4_THRESHOLD_C = 1.0, 1.0
#: PX4 device-id bus types (``DeviceBusType``): I2C, SPI, UAVCAN, SIMULATION, SERIAL, MAVLINK.
PX4_BUS_TYPES = {1: 'I2C', 2: 'SPI', 3: 'UAVCAN', 4: 'SIMULATION', 5: 'SERIAL', 6: 'MAVLINK'}
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


def remap_axes(cal: CubicCalibration, spec: str) -> CubicCalibration:
    """
    Express a calibration in the autopilot's sensor axes.

    Both autopilots subtract the offsets after their driver has turned the chip's axes into the
    flight controller's (the IMU's orientation on the board; an external sensor's own rotation):
    ``spec`` says, for the autopilot's X, Y and Z in turn, which of the recording's axes it is,
    with its sign, e.g. ``'-y,x,z'`` (X = -y, Y = x, Z = z: the chip turned 90 degrees about z).

    Parameters
    ----------
    cal : CubicCalibration
        In the recording's axes.
    spec : str
        Three comma-separated entries, a signed permutation of ``x``, ``y``, ``z``.

    Returns
    -------
    CubicCalibration

    Raises
    ------
    ParameterError
        Not a signed permutation.

    """
    parts = [p.strip().lower() for p in str(spec).split(',')]
    axes = [p.lstrip('+-') for p in parts]
    if len(parts) != 3 or sorted(axes) != ['x', 'y', 'z'] or any(
            len(p) - len(a) > 1 for p, a in zip(parts, axes)):
        raise ParameterError(f'{{axes}} must name x, y and z once each, signed, e.g. -y,x,z; '
                             f'got {spec!r}', parameters=('axes',))
    sign = np.array([-1.0 if p.startswith('-') else 1.0 for p in parts])
    coef = cal.coef[['xyz'.index(a) for a in axes]] * sign[:, None]
    return replace(cal, coef=coef)


def firmware_residuals(cal: CubicCalibration, t_s: ArrayLike, gyro_rad_s: ArrayLike,
                       temperature_c: ArrayLike, *,
                       cal_temp_c: float | None = None) -> dict[str, list[float]]:
    """
    Return the residual drift each firmware would leave on a run, per axis (deg/s).

    Parameters
    ----------
    cal : CubicCalibration
        The exported gyro calibration (rad/s), in the run's axes.
    t_s, gyro_rad_s, temperature_c : array_like
        The run: times (n,) s, gyro (n, 3) rad/s, temperature (n,) degC.
    cal_temp_c : float, optional, keyword-only
        ArduPilot's CALTEMP (default the calibration's T_ref).

    Returns
    -------
    dict
        ``raw``, ``model`` (the cubic evaluated at every sample), ``px4``
        (:func:`px4_applied_offset`), ``ardupilot`` (:func:`ardupilot_applied_offset`): the std
        of 60-s means per axis, deg/s (NaN with fewer than two windows).

    """
    from .metrics import residual_drift_deg_s

    t = np.asarray(t_s, dtype=float)
    gyro = np.asarray(gyro_rad_s, dtype=float)
    temp = np.asarray(temperature_c, dtype=float)
    rate_hz = (t.size - 1) / (t[-1] - t[0]) if t.size > 1 and t[-1] > t[0] else 1.0
    runs = {'raw': gyro, 'model': gyro - cal.offset(temp),
            'px4': gyro - px4_applied_offset(cal, t, temp),
            'ardupilot': gyro - ardupilot_applied_offset(cal, temp, cal_temp_c=cal_temp_c)}
    return {k: [float(v) for v in residual_drift_deg_s(x, rate_hz)] for k, x in runs.items()}


def px4_device_id(value: Any, parameter: str = 'px4_gyro_id') -> dict[str, Any]:
    """
    Check a PX4 device id and decode it.

    PX4 stores a device id in an INT32 parameter (``CAL_GYRO0_ID``, ``TC_G0_ID``), but the id
    itself is 24 bits: bus type (3 bits, 1..6), bus (5), address (8), device type (8), lowest
    first. An id outside 1..16777215 or with an unknown bus type matches no sensor.

    Parameters
    ----------
    value : int
        The id as given.
    parameter : str
        The parameter the id was given as (named in braces in the message).

    Returns
    -------
    dict
        ``id``, ``bus_type`` (name), ``bus``, ``address``, ``devtype``.

    Raises
    ------
    ParameterError
        Not an integer, outside 1..16777215, or an unknown bus type.

    """
    name = '{' + parameter + '}'
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ParameterError(f'{name} must be an integer device id, got {value!r}',
                             parameters=(parameter,))
    dev = int(value)
    if not 1 <= dev <= 0xFFFFFF:
        raise ParameterError(f'{name} {dev}: a PX4 device id is 24 bits (1..16777215, as '
                             'CAL_GYRO0_ID shows it); this one matches no sensor',
                             parameters=(parameter,))
    bus_type = dev & 0x7
    if bus_type not in PX4_BUS_TYPES:
        raise ParameterError(f"{name} {dev}: bus type {bus_type} (the id's low 3 bits) is "
                             f"none of PX4's ({', '.join(PX4_BUS_TYPES.values())})",
                             parameters=(parameter,))
    return {'id': dev, 'bus_type': PX4_BUS_TYPES[bus_type], 'bus': (dev >> 3) & 0x1F,
            'address': (dev >> 8) & 0xFF, 'devtype': (dev >> 16) & 0xFF}


def px4_parameters(gyro: CubicCalibration | None, accel: CubicCalibration | None = None, *,
                   instance: int = 0, gyro_device_id: int | None = None,
                   accel_device_id: int | None = None) -> list[tuple[str, float, int]]:
    """
    Return the PX4 thermal-compensation parameters of a gyro (and accelerometer) calibration.

    Parameters
    ----------
    gyro : CubicCalibration or None
        rad/s.
    accel : CubicCalibration, optional
        m/s^2.
    instance : int, keyword-only
        Calibration instance 0..3 (the ``0`` of ``TC_G0_*``).
    gyro_device_id, accel_device_id : int or None, keyword-only
        ``TC_G<i>_ID`` / ``TC_A<i>_ID``: the device id PX4 reports for the sensor (its
        ``CAL_GYRO<i>_ID`` / ``CAL_ACC<i>_ID``, :func:`px4_device_id`). None or 0 (PX4's "no
        sensor"): that sensor's block is written with ``TC_G_ENABLE`` / ``TC_A_ENABLE`` 0.

    Returns
    -------
    list of (str, float or int, int)
        (name, value, MAVLink type) in file order.

    """
    if not (isinstance(instance, (int, np.integer)) and 0 <= instance < PX4_INSTANCES):
        raise ParameterError(f'PX4 calibration instance must be 0..{PX4_INSTANCES - 1} '
                             f'(TC_G0..TC_G{PX4_INSTANCES - 1}), got {instance!r}')
    out: list[tuple[str, float, int]] = []
    for letter, cal, dev, option in (('G', gyro, gyro_device_id, 'px4_gyro_id'),
                                     ('A', accel, accel_device_id, 'px4_accel_id')):
        if cal is None:
            continue
        ident = 0 if dev is None or dev == 0 else px4_device_id(dev, option)['id']
        p = f'TC_{letter}{instance}_'
        out.append((f'TC_{letter}_ENABLE', int(ident != 0), PX4_INT32))
        out.append((p + 'ID', ident, PX4_INT32))
        out += [(p + 'TMIN', cal.t_min_c, PX4_FLOAT), (p + 'TMAX', cal.t_max_c, PX4_FLOAT),
                (p + 'TREF', cal.t_ref_c, PX4_FLOAT)]
        out += [(f'{p}X{i}_{axis}', float(cal.coef[axis, i]), PX4_FLOAT)
                for i in range(4) for axis in range(3)]
    if not out:
        raise ParameterError('nothing to export: no gyro and no accelerometer calibration')
    return out


def px4_applied_offset(cal: CubicCalibration, t_s: ArrayLike, temperature_c: ArrayLike, *,
                       period_s: float = PX4_PERIOD_S,
                       threshold_c: float = PX4_THRESHOLD_C) -> NDArray[np.float64]:
    """
    Return the offset PX4 subtracts from each sample, under its own update rule.

    PX4's ``temperature_compensation`` runs every ``period_s`` (1 s): it evaluates the cubic, in
    float32, at the temperature of the newest gyro report and publishes the offsets only when
    that temperature differs by more than ``threshold_c`` (1 degC) from the one it last
    published with (the first evaluation always publishes). The gyro driver subtracts the last
    published offset from every sample until the next publication.

    Parameters
    ----------
    cal : CubicCalibration
        The exported calibration.
    t_s : array_like
        Sample times (n,), s, increasing; the module's first run is at ``t_s[0]``.
    temperature_c : array_like
        The temperature at each sample (n,), degC.
    period_s, threshold_c : float, keyword-only
        The module's period (s) and publication threshold (degC).

    Returns
    -------
    numpy.ndarray
        (n, 3), the calibration's unit.

    """
    t = np.asarray(t_s, dtype=float).reshape(-1)
    temp = np.asarray(temperature_c, dtype=float).reshape(-1)
    ticks = t[0] + period_s * np.arange(int(np.floor((t[-1] - t[0]) / period_s)) + 1)
    newest = np.searchsorted(t, ticks, side='right') - 1    # the latest report at each tick
    published = np.zeros(t.size, dtype=np.int64) - 1
    last = np.float32(-100.0)        # PerSensorData: last_temperature starts at -100 degC
    starts, values = [], []
    for k, i in enumerate(newest):
        reading = np.float32(temp[i])
        if abs(reading - last) > np.float32(threshold_c):
            last = reading
            starts.append(ticks[k])
            values.append(float(reading))
    first = np.searchsorted(t, starts, side='left')
    published[first] = np.arange(len(starts))
    np.maximum.accumulate(published, out=published)
    offsets = _float32_offset(cal, np.asarray(values, dtype=float))
    return np.where((published >= 0)[:, None], offsets[np.maximum(published, 0)], 0.0)


def _float32_offset(cal: CubicCalibration,
                    temperature_c: NDArray[np.float64]) -> NDArray[np.float64]:
    """Evaluate the cubic as PX4's ``calc_thermal_offsets_3D`` does, in float32."""
    f32 = np.float32
    delta = (np.clip(temperature_c.astype(f32), f32(cal.t_min_c), f32(cal.t_max_c))
             - f32(cal.t_ref_c))[:, None]
    delta2 = delta * delta
    c = cal.coef.astype(f32)[None, :, :]
    out = c[..., 0] + c[..., 1] * delta + c[..., 2] * delta2 + c[..., 3] * (delta2 * delta)
    return out.astype(np.float64)


def ardupilot_applied_offset(cal: CubicCalibration, temperature_c: ArrayLike, *,
                             cal_temp_c: float | None = None) -> NDArray[np.float64]:
    """
    Return the offset ArduPilot removes from each sample with the exported parameters.

    ``OFFS + P(clip(T) - 35) - P(clip(CALTEMP) - 35)`` in float32 at every sample, OFFS the
    model's offset at CALTEMP as :func:`ardupilot_parameters` writes it (the backend's low-pass
    filter on the temperature, ~1 Hz in the Invensense driver, is left out: its fraction of a
    second of delay does not matter at thermal time scales).

    Parameters
    ----------
    cal : CubicCalibration
        The exported calibration.
    temperature_c : array_like
        (n,) degC.
    cal_temp_c : float, optional, keyword-only
        ``INS_GYR1_CALTEMP`` (default the calibration's T_ref, as exported).

    Returns
    -------
    numpy.ndarray
        (n, 3).

    """
    f32 = np.float32
    cal_temp = cal.t_ref_c if cal_temp_c is None else float(cal_temp_c)
    scaled = (cal.about(ARDUPILOT_TREF_C) * ARDUPILOT_SCALE).astype(f32)   # as stored
    lo, hi = f32(cal.t_min_c), f32(cal.t_max_c)

    def poly(temp: NDArray[np.float32]) -> NDArray[np.float32]:
        u = (np.clip(temp, lo, hi) - f32(ARDUPILOT_TREF_C))[:, None]
        c = scaled[None, :, 1:]
        return (c[..., 0] + (c[..., 1] + c[..., 2] * u) * u) * u * f32(1.0 / ARDUPILOT_SCALE)

    temp = np.asarray(temperature_c, dtype=float).reshape(-1).astype(f32)
    offs = cal.offset([cal_temp])[0].astype(f32)
    out = offs[None, :] + poly(temp) - poly(np.array([cal_temp], dtype=f32))
    return out.astype(np.float64)


def ardupilot_notes(cal: CubicCalibration) -> tuple[str, ...]:
    """
    Say when a calibration leaves ArduPilot's documented TMIN/TMAX range (-70..80 degC).

    The firmware does not enforce it (``correct_sensor`` clips the temperature to TMIN..TMAX
    whatever they are); a ground station may flag the values.

    Parameters
    ----------
    cal : CubicCalibration
        The calibration.

    Returns
    -------
    tuple of str

    """
    lo, hi = ARDUPILOT_RANGE_C
    if lo <= cal.t_min_c and cal.t_max_c <= hi:
        return ()
    return (f'INS_TCAL TMIN/TMAX {cal.t_min_c:.2f}..{cal.t_max_c:.2f} degC leave the documented '
            f'{lo:g}..{hi:g} degC range; the firmware uses them as given, a ground station may '
            'warn',)


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
