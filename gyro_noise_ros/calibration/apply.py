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
Apply a six-position calibration (bias, scale factor, misalignment) to accelerometer and gyro.

Sensor model, per sensor (paper 001 eqs. 3-4 extended by the cross-axis terms)::

    measured = (I + diag(S) + M) @ true + b

with ``b`` the bias (m/s^2 or rad/s), ``S`` the dimensionless scale-factor errors and ``M`` the
3x3 misalignment (cross-axis) matrix with a zero diagonal. Hence::

    true = inv(I + diag(S) + M) @ (measured - b)

The inverse is computed once; applying it to an (n, 3) batch is one subtraction and one 3x3
matrix product. The calibration comes from the ``calibration.yaml`` that ``gyro_noise_calibrate``
writes, a ROS parameter file (``/**: ros__parameters:``) with the keys of :data:`KEYS`, or from a
dict of the same keys (the node's parameters). No ROS is imported here.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError, ParameterError
from ..outputs import StrPath
from ..units import STANDARD_GRAVITY_M_S2

#: Key -> (number of values, unit); the keys of ``calibration.yaml`` and of the node parameters.
KEYS = {
    'accel_bias_m_s2': (3, 'm/s^2'),
    'accel_scale_factor': (3, ''),
    'accel_misalignment': (9, ''),
    'gyro_bias_rad_s': (3, 'rad/s'),
    'gyro_scale_factor': (3, ''),
    'gyro_misalignment': (9, ''),
    'calibration_gravity_m_s2': (1, 'm/s^2'),
}

#: Largest accepted 2-norm condition number of ``I + diag(S) + M``. A real MEMS matrix is within a
#: few percent of the identity (condition number about 1.1 at most); 10 already means scale errors
#: of tens of percent, i.e. a wrong file, not a sensor.
MAX_CONDITION = 10.0


@dataclass(frozen=True)
class SensorCalibration:
    """
    Bias, scale factor and misalignment of one three-axis sensor.

    Attributes
    ----------
    bias : numpy.ndarray
        (3,), in the sensor's unit (m/s^2 or rad/s).
    scale_factor : numpy.ndarray
        (3,), dimensionless (-0.0002 = -0.02 %).
    misalignment : numpy.ndarray
        (3, 3), dimensionless, zero diagonal.

    """

    bias: np.ndarray
    scale_factor: np.ndarray
    misalignment: np.ndarray

    @property
    def matrix(self) -> np.ndarray:
        """``I + diag(S) + M``: true -> measured (before the bias)."""
        return np.eye(3) + np.diag(self.scale_factor) + self.misalignment

    @cached_property
    def inverse(self) -> np.ndarray:
        """``inv(I + diag(S) + M)``: measured - bias -> true (computed once)."""
        return np.linalg.inv(self.matrix)

    @cached_property
    def is_identity(self) -> bool:
        """Tell whether applying the calibration changes nothing (all zeros)."""
        return not (self.bias.any() or self.scale_factor.any() or self.misalignment.any())

    def apply(self, measured: ArrayLike) -> np.ndarray:
        """
        Correct a batch of samples.

        Parameters
        ----------
        measured : array_like
            (n, 3) or (3,) samples in the sensor's unit.

        Returns
        -------
        numpy.ndarray
            The corrected samples, same shape, float64.

        """
        x = np.asarray(measured, dtype=np.float64)
        if self.is_identity:
            return x.copy()
        # inv @ (x - b) for every row at once, each element summed in column order: the same
        # operations as the compensator's compiled pass (msgs.imu_rows.RowCorrector), so the
        # two agree bit for bit (a BLAS matrix product may fuse or reorder them: 1-2 ulp apart).
        d, inv = x - self.bias, self.inverse
        return (d[..., 0:1] * inv[:, 0] + d[..., 1:2] * inv[:, 1]) + d[..., 2:3] * inv[:, 2]


@dataclass(frozen=True)
class Calibration:
    """
    Accelerometer and gyro calibration, with the gravity the accelerometer was calibrated against.

    Attributes
    ----------
    accel : SensorCalibration
    gyro : SensorCalibration
    gravity_m_s2 : float

    """

    accel: SensorCalibration
    gyro: SensorCalibration
    gravity_m_s2: float = STANDARD_GRAVITY_M_S2

    def apply(self, gyro_rad_s: ArrayLike,
              accel_m_s2: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """
        Correct a batch: (n, 3) angular rates (rad/s) and specific forces (m/s^2), same shapes out.

        Each sensor's :meth:`SensorCalibration.apply`.

        """
        return self.gyro.apply(gyro_rad_s), self.accel.apply(accel_m_s2)


def identity() -> Calibration:
    """Return the calibration that changes nothing (the node's default)."""
    zero = SensorCalibration(np.zeros(3), np.zeros(3), np.zeros((3, 3)))
    return Calibration(zero, zero)


def _values(params: Mapping[str, Any], key: str, source: str) -> np.ndarray:
    count, _ = KEYS[key]
    value = params[key]
    arr = np.asarray(value, dtype=object).reshape(-1)
    if arr.size != count:
        raise ParameterError(f"{source}: '{key}' must have {count} values, got {arr.size}")
    try:
        out = np.array([float(v) for v in arr], dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"{source}: '{key}' must hold numbers, got {value!r}") from err
    if not np.isfinite(out).all():
        raise ParameterError(f"{source}: '{key}' holds a non-finite value: {value!r}")
    return out


def _sensor(params: Mapping[str, Any], prefix: str, bias_key: str,
            source: str) -> SensorCalibration:
    bias = _values(params, bias_key, source)
    scale = _values(params, f'{prefix}_scale_factor', source)
    mis = _values(params, f'{prefix}_misalignment', source).reshape(3, 3)
    if np.diag(mis).any():
        raise ParameterError(f"{source}: '{prefix}_misalignment' must have a zero diagonal (the "
                             f"diagonal is '{prefix}_scale_factor'), got {np.diag(mis).tolist()}")
    cal = SensorCalibration(bias, scale, mis)
    cond = np.linalg.cond(cal.matrix)
    if not math.isfinite(cond) or cond > MAX_CONDITION:
        raise ParameterError(
            f"{source}: '{prefix}_scale_factor' with '{prefix}_misalignment' give a singular or "
            f'ill-conditioned matrix I + diag(S) + M (condition number {cond:.3g} > '
            f'{MAX_CONDITION:g}); scale factors are dimensionless (-0.0002 = -0.02 %)')
    return cal


def calibration_from_parameters(params: Mapping[str, Any], *,
                                source: str = 'calibration') -> Calibration:
    """
    Build a :class:`Calibration` from a dict with the keys of :data:`KEYS`.

    Parameters
    ----------
    params : mapping
        Key -> value (lists of floats; ``calibration_gravity_m_s2`` a float). Missing keys take
        the identity's values (zeros; standard gravity).
    source : str, keyword-only
        Where the values come from, named in error messages (a file, 'parameter').

    Returns
    -------
    Calibration

    Raises
    ------
    ParameterError
        Wrong count, non-numeric or non-finite values, non-zero misalignment diagonal, or a
        singular / ill-conditioned matrix; the message names the key.

    """
    full: dict[str, Any] = {key: [0.0] * count for key, (count, _) in KEYS.items()}
    full['calibration_gravity_m_s2'] = STANDARD_GRAVITY_M_S2
    full.update({k: v for k, v in params.items() if k in KEYS})
    gravity = float(_values(full, 'calibration_gravity_m_s2', source)[0])
    if not gravity > 0:
        raise ParameterError(f"{source}: 'calibration_gravity_m_s2' must be > 0, got {gravity!r}")
    return Calibration(accel=_sensor(full, 'accel', 'accel_bias_m_s2', source),
                       gyro=_sensor(full, 'gyro', 'gyro_bias_rad_s', source),
                       gravity_m_s2=gravity)


def load_calibration(path: StrPath) -> Calibration:
    """
    Read a ``calibration.yaml`` (ROS parameter file) as written by ``gyro_noise_calibrate``.

    The file holds one node key (``/**`` or a node name) with ``ros__parameters`` holding the keys
    of :data:`KEYS`; other parameters under it are ignored.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    Calibration

    Raises
    ------
    InputError
        A missing or unreadable file (binary, not YAML), not a parameter file, an unknown layout
        or a missing key (exit code 3, as for every unreadable input).
    ParameterError
        Bad values (naming the key).

    """
    import yaml

    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding='utf-8'))
    except FileNotFoundError as err:
        raise InputError(f'calibration file {str(path)!r} does not exist') from err
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        why = getattr(err, 'strerror', None) or str(err).splitlines()[0]
        raise InputError(f'calibration file {str(path)!r} cannot be read as YAML: {why}') from err
    blocks = [v['ros__parameters'] for v in (doc or {}).values()
              if isinstance(v, dict) and isinstance(v.get('ros__parameters'), dict)] \
        if isinstance(doc, dict) else []
    if len(blocks) != 1:
        raise InputError(f'calibration file {path}: expected one node key (e.g. /**) with '
                         f'ros__parameters, found {len(blocks)}')
    params = blocks[0]
    missing = [k for k in KEYS if k != 'calibration_gravity_m_s2' and k not in params]
    if missing:
        raise InputError(f'calibration file {path}: missing {", ".join(missing)}')
    return calibration_from_parameters(params, source=f'calibration file {path}')
