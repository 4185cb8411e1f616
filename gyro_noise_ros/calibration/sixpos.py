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
Six-position static calibration (paper 001 eqs. 1-4) and the local gravity model.

Error model (paper 001 eq. 1 with the cross-coupling written as a matrix), for the accelerometer
and likewise for the gyro::

    measured = (I + diag(scale_factor) + misalignment) @ true + bias + noise

``scale_factor`` is dimensionless (-0.0002 = -0.02 %), ``misalignment`` is 3x3 with a zero
diagonal (element [j, i]: how much of the true axis i leaks into measured axis j). A compensator
inverts it: ``true = inv(I + diag(S) + M) @ (measured - bias)``.

In dwell ``+i`` axis i points up and the accelerometer reads ``true = +g e_i`` (REP-103); in ``-i``
``true = -g e_i``. Per axis, paper eqs. 3-4::

    b_i = (l_i(+i) + l_i(-i)) / 2,        S_i = (l_i(+i) - l_i(-i) - 2 g) / (2 g)

and, beyond the paper, the least-squares solution of all 18 equations for the full matrix gives
the cross-axis terms ``M[j, i] = (l_j(+i) - l_j(-i)) / (2 g)`` (j != i): the nominal gravity
directions are orthogonal, so the least squares decouple into these differences.

Gyro bias: ``b_g,i = (w_i(+i) + w_i(-i)) / 2``. Turning axis i from up to down reverses its
share of the vertical Earth rate (Omega_E sin(latitude)), which cancels in the sum. What remains:
a dwell tilted by delta from vertical adds up to Omega_E * sin(delta) (7.3e-5 rad/s times delta in
rad), and gyro cross-axis terms pick up the horizontal Earth rate (Omega_E cos(latitude)) times the
misalignment; both are far below a MEMS bias (~1e-3 rad/s). The gyro scale factor and misalignment
cannot be seen with the Earth rate alone; they are reported as 0 (not estimated).
"""

from dataclasses import dataclass
import math

import numpy as np

from .static import ORIENTATIONS
from ..errors import InputDataError, ParameterError

#: Standard gravity (m/s^2), used with no local value and as the unit "g" of mg.
STANDARD_GRAVITY = 9.80665
#: WGS-84 (NIMA TR8350.2, 3rd ed., ch. 4): equatorial normal gravity (m/s^2), Somigliana constant
#: k, first eccentricity squared, semi-major axis (m), flattening, m = omega^2 a^2 b / GM.
WGS84_GAMMA_E = 9.7803253359
WGS84_K = 0.00193185265241
WGS84_E2 = 0.00669437999013
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_M = 0.00344978650684
#: Earth rotation rate (rad/s), WGS-84.
EARTH_RATE_RAD_S = 7.292115e-5


def normal_gravity(latitude_deg, height_m=0.0):
    """
    Return WGS-84 normal gravity at a geodetic latitude and ellipsoidal height.

    Somigliana's closed formula on the ellipsoid (TR8350.2 eq. 4-1)::

        gamma(phi) = gamma_e (1 + k sin^2 phi) / sqrt(1 - e^2 sin^2 phi)

    and the second-order free-air expansion above it (TR8350.2 eq. 4-3)::

        gamma(phi, h) = gamma(phi) (1 - 2/a (1 + f + m - 2 f sin^2 phi) h + 3 h^2 / a^2)

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude (deg), -90..90.
    height_m : float
        Height above the ellipsoid (m), -1000..20000 (the expansion is good to a few ugal there).

    Returns
    -------
    float
        Normal gravity (m/s^2).

    """
    lat = float(latitude_deg)
    h = float(height_m)
    if not (math.isfinite(lat) and -90.0 <= lat <= 90.0):
        raise ParameterError(f'latitude must be in [-90, 90] deg, got {latitude_deg!r}')
    if not (math.isfinite(h) and -1000.0 <= h <= 20000.0):
        raise ParameterError(f'height must be in [-1000, 20000] m, got {height_m!r}')
    s2 = math.sin(math.radians(lat)) ** 2
    g0 = WGS84_GAMMA_E * (1.0 + WGS84_K * s2) / math.sqrt(1.0 - WGS84_E2 * s2)
    return g0 * (1.0 - 2.0 / WGS84_A * (1.0 + WGS84_F + WGS84_M - 2.0 * WGS84_F * s2) * h
                 + 3.0 * h * h / WGS84_A ** 2)


@dataclass(frozen=True)
class SixPositionResult:
    """
    Accelerometer and gyro calibration from six static dwells.

    Attributes
    ----------
    gravity_m_s2 : float
        Local gravity used (m/s^2).
    accel_bias_m_s2, accel_bias_sigma_m_s2 : numpy.ndarray
        (3,) bias (paper eq. 3) and its standard uncertainty (m/s^2).
    accel_scale_factor, accel_scale_factor_sigma : numpy.ndarray
        (3,) scale factor (paper eq. 4, dimensionless) and its standard uncertainty.
    accel_misalignment, accel_misalignment_sigma : numpy.ndarray
        (3, 3) cross-axis terms, zero diagonal, and their standard uncertainties.
    gyro_bias_rad_s, gyro_bias_sigma_rad_s : numpy.ndarray
        (3,) gyro bias and its standard uncertainty (rad/s).
    accel_residual_m_s2 : float
        Scatter of the dwell means about the fitted model: sqrt(RSS / 6) over the 18 equations
        and 12 unknowns (m/s^2). It holds the dwell-to-dwell wander (flicker, random walk,
        handling) that the within-dwell spread cannot see; the accelerometer uncertainties use
        the larger of the two per dwell.

    """

    gravity_m_s2: float
    accel_bias_m_s2: np.ndarray
    accel_bias_sigma_m_s2: np.ndarray
    accel_scale_factor: np.ndarray
    accel_scale_factor_sigma: np.ndarray
    accel_misalignment: np.ndarray
    accel_misalignment_sigma: np.ndarray
    gyro_bias_rad_s: np.ndarray
    gyro_bias_sigma_rad_s: np.ndarray
    accel_residual_m_s2: float = float('nan')

    @property
    def accel_matrix(self):
        """numpy.ndarray: (3, 3) ``I + diag(scale_factor) + misalignment``."""
        return np.eye(3) + np.diag(self.accel_scale_factor) + self.accel_misalignment

    def compensate_accel(self, measured_m_s2):
        """
        Apply the calibration: ``inv(I + diag(S) + M) @ (measured - bias)``.

        Parameters
        ----------
        measured_m_s2 : array_like
            (..., 3) measured specific force (m/s^2).

        Returns
        -------
        numpy.ndarray
            (..., 3) compensated specific force (m/s^2).

        """
        meas = np.asarray(measured_m_s2, dtype=np.float64)
        return np.linalg.solve(self.accel_matrix, (meas - self.accel_bias_m_s2).T).T


def six_position(accel_means_m_s2, gravity_m_s2, *, accel_sems_m_s2=None, gyro_means_rad_s=None,
                 gyro_sems_rad_s=None):
    """
    Estimate bias, scale factor and cross-axis terms from the six dwell means.

    Parameters
    ----------
    accel_means_m_s2 : mapping or array_like
        Orientation -> (3,) mean specific force (m/s^2), or a (6, 3) array in the order of
        :data:`~gyro_noise_ros.calibration.static.ORIENTATIONS` (+x, -x, +y, -y, +z, -z).
    gravity_m_s2 : float
        Local gravity (m/s^2).
    accel_sems_m_s2 : mapping or array_like, optional, keyword-only
        Standard errors of those means from the spread inside each dwell (m/s^2), raised to the
        dwell-to-dwell scatter of the model residuals; uncertainties are NaN without them.
    gyro_means_rad_s, gyro_sems_rad_s : mapping or array_like, optional, keyword-only
        Gyro dwell means and their standard errors (rad/s); gyro outputs NaN without them.

    Returns
    -------
    SixPositionResult

    """
    g = float(gravity_m_s2)
    if not (math.isfinite(g) and 5.0 < g < 15.0):
        raise ParameterError(f'gravity must be a plausible value in m/s^2 (5..15), '
                             f'got {gravity_m_s2!r}')

    def table(values, name):
        if values is None:
            return np.full((6, 3), np.nan)
        if isinstance(values, dict):
            values = [values[o] for o in ORIENTATIONS]
        arr = np.asarray(values, dtype=np.float64)
        if arr.shape != (6, 3):
            raise ParameterError(f'{name} must hold 6 x 3 values, got shape {arr.shape}')
        return arr

    a = table(accel_means_m_s2, 'accel_means_m_s2')
    if not np.all(np.isfinite(a)):
        raise InputDataError('a dwell mean of the accelerometer is NaN/Inf')
    a_se = table(accel_sems_m_s2, 'accel_sems_m_s2')
    w = table(gyro_means_rad_s, 'gyro_means_rad_s')
    w_se = table(gyro_sems_rad_s, 'gyro_sems_rad_s')
    plus, minus = a[0::2], a[1::2]            # row i: dwell +i / -i
    # least squares of all 18 equations: A[:, i] = (l(+i) - l(-i)) / 2g, b = mean of the six;
    # 6 residual degrees of freedom measure how far the dwell means scatter about the model
    cols = ((plus - minus) / (2.0 * g)).T
    nominal = np.repeat(np.eye(3), 2, axis=0) * np.tile([g, -g], 3)[:, None]
    resid = a - nominal @ cols.T - a.mean(axis=0)
    scatter = float(np.sqrt(np.sum(resid ** 2) / 6.0))
    a_se = np.where(np.isfinite(a_se), np.maximum(a_se, scatter), a_se)
    sp, sm = a_se[0::2], a_se[1::2]
    diff_se = np.sqrt(sp ** 2 + sm ** 2)      # row i, column j: se of l_j(+i) - l_j(-i)
    idx = np.arange(3)
    bias = (plus[idx, idx] + minus[idx, idx]) / 2.0                   # eq. 3
    bias_se = diff_se[idx, idx] / 2.0
    scale = (plus[idx, idx] - minus[idx, idx] - 2.0 * g) / (2.0 * g)  # eq. 4
    scale_se = diff_se[idx, idx] / (2.0 * g)
    # column i of (I + D + M) is (l(+i) - l(-i)) / 2g; row i of `plus - minus` is that column
    mis = ((plus - minus) / (2.0 * g)).T
    mis_se = (diff_se / (2.0 * g)).T
    np.fill_diagonal(mis, 0.0)
    np.fill_diagonal(mis_se, 0.0)
    gyro = (w[0::2][idx, idx] + w[1::2][idx, idx]) / 2.0
    gyro_se = np.sqrt(w_se[0::2][idx, idx] ** 2 + w_se[1::2][idx, idx] ** 2) / 2.0
    return SixPositionResult(g, bias, bias_se, scale, scale_se, mis, mis_se, gyro, gyro_se,
                             scatter)


def uniformity(values):
    """
    Return the paper 001 section 6 uniformity indicator: the sample standard deviation (ddof = 1).

    Parameters
    ----------
    values : array_like
        (3,) per-axis biases or scale factors.

    Returns
    -------
    float
        std(values, ddof=1), in the unit of ``values``.

    """
    return float(np.std(np.asarray(values, dtype=np.float64), ddof=1))


def gravity_check(accel_means_m_s2, result):
    """
    Return the mean |a| over the six dwells, raw and after the calibration (paper 001 section 6).

    The norm of each dwell's mean is used (the mean of per-sample norms would add the noise
    variance / (2 g) to both numbers), averaged with equal weight over the dwells.

    Parameters
    ----------
    accel_means_m_s2 : array_like
        (6, 3) dwell means (m/s^2).
    result : SixPositionResult
        The calibration to apply.

    Returns
    -------
    (float, float)
        Mean norm raw and calibrated (m/s^2).

    """
    a = np.asarray(accel_means_m_s2, dtype=np.float64)
    raw = float(np.mean(np.linalg.norm(a, axis=1)))
    cal = float(np.mean(np.linalg.norm(result.compensate_accel(a), axis=1)))
    return raw, cal
