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
Six-position static calibration (paper 001 eqs. 1-4), its consistency test and the local gravity.

Error model (paper 001 eq. 1, cross-coupling as a matrix), accelerometer and gyro alike::

    measured = (I + diag(scale_factor) + misalignment) @ true + bias + noise

``scale_factor`` dimensionless (-0.0002 = -0.02 %), ``misalignment`` 3x3 with a zero diagonal
(``[j, i]``: true axis i leaking into measured axis j); SI inside (m/s^2, rad/s). In dwell ``+i``
axis i points up and reads ``+g e_i`` (REP-103). Per axis, paper eqs. 3-4, and the cross-axis
terms from the least squares of all 18 equations (they decouple into differences)::

    b_i = (l_i(+i) + l_i(-i)) / 2,   S_i = (l_i(+i) - l_i(-i) - 2 g) / (2 g),
    M[j, i] = (l_j(+i) - l_j(-i)) / (2 g)   (j != i)

Gyro bias ``b_g,i = (w_i(+i) + w_i(-i)) / 2`` (the vertical Earth rate cancels in the pair); the
gyro scale factor and misalignment need the turns (:mod:`~gyro_noise_ros.calibration.gyro_turns`).
Uncertainties come from the dwells' variogram (:mod:`~gyro_noise_ros.calibration.dwell_noise`).
**Consistency test**: each pair's sum ``D_i = s_i - (s_k + s_l) / 2`` against F(3, 6) with the
noise fitted on the other two pairs, at ``alpha / 3``; the bad dwell of a failing pair is named.
**Gravity check**: each dwell left out, calibrated from the other five, its norm against g
(Student's t, 6 dof). Derivations, false-alarm and detection rates: docs/reliability.md section 1
(``docs/scripts/calibration_uncertainty.py``).
"""

from collections.abc import Mapping
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2, f as f_dist, t as t_dist

from .apply import SensorCalibration
from .dwell_noise import DwellNoise, DwellNoiseFitter, fit_dwell_noise
from .static import Dwell, dwell_windows, ORIENTATIONS
from ..errors import InputDataError, ParameterError

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
#: False-alarm probability of the consistency test and of the gravity check (per calibration).
DEFAULT_ALPHA = 1e-3
#: Effective degrees of freedom of the variance behind both checks (module docstring): 3 from
#: the other pairs' disagreement, more from the windows; the emulated false-alarm rate of the
#: tests at this value is measured in docs/reliability.md.
CHECK_DOF = 6


def normal_gravity(latitude_deg: float, height_m: float = 0.0) -> float:
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


def _table(values: Mapping[str, ArrayLike] | ArrayLike, name: str) -> NDArray[np.float64]:
    if isinstance(values, dict):
        values = [values[o] for o in ORIENTATIONS]
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape != (6, 3):
        raise ParameterError(f'{name} must hold 6 x 3 values, got shape {arr.shape}')
    return arr


def _nominal(g: float) -> NDArray[np.float64]:
    """(6, 3) true specific force of each dwell, in :data:`ORIENTATIONS` order (m/s^2)."""
    return np.repeat(np.eye(3), 2, axis=0) * np.tile([g, -g], 3)[:, None]


def residual_projector() -> NDArray[np.float64]:
    """
    Return the 6x6 projector onto the residuals of the 18 equations (6 dwells, 4 unknowns).

    Returns
    -------
    numpy.ndarray
        ``I - X pinv(X)`` with ``X = [1, nominal direction]``; its rows sum to zero (contrasts).

    """
    x = np.column_stack([np.ones(6), _nominal(1.0)])
    return np.eye(6) - x @ np.linalg.pinv(x)


def _per_axis(c: NDArray[np.float64], j: int) -> NDArray[np.float64]:
    """(m, 3) loading that applies the dwell weights ``c`` to axis j only."""
    out = np.zeros((len(c), 3))
    out[:, j] = c
    return out


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
        Scatter of the dwell means about the fitted model, sqrt(RSS / 6) over the 18 equations
        and 12 unknowns (m/s^2).

    Notes
    -----
    Uncertainties are NaN without noise models (``six_position`` called on bare means).

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
    def accel_matrix(self) -> NDArray[np.float64]:
        """numpy.ndarray: (3, 3) ``I + diag(scale_factor) + misalignment``."""
        return np.eye(3) + np.diag(self.accel_scale_factor) + self.accel_misalignment

    def compensate_accel(self, measured_m_s2: ArrayLike) -> np.ndarray:
        """
        Apply the calibration to (..., 3) specific forces: ``inv(I + diag(S) + M) @ (l - b)``.

        :meth:`.apply.SensorCalibration.apply` with this result's accelerometer terms; in and out
        in m/s^2.

        """
        return SensorCalibration(self.accel_bias_m_s2, self.accel_scale_factor,
                                 self.accel_misalignment).apply(measured_m_s2)


def six_position(accel_means_m_s2: Mapping[str, ArrayLike] | ArrayLike, gravity_m_s2: float, *,
                 gyro_means_rad_s: Mapping[str, ArrayLike] | ArrayLike | None = None,
                 accel_noise: DwellNoise | None = None,
                 gyro_noise: DwellNoise | None = None) -> SixPositionResult:
    """
    Estimate bias, scale factor and cross-axis terms from the six dwell means.

    Parameters
    ----------
    accel_means_m_s2 : mapping or array_like
        Orientation -> (3,) mean specific force (m/s^2), or a (6, 3) array in the order of
        :data:`~gyro_noise_ros.calibration.static.ORIENTATIONS` (+x, -x, +y, -y, +z, -z).
    gravity_m_s2 : float
        Local gravity (m/s^2).
    gyro_means_rad_s : mapping or array_like, optional, keyword-only
        Gyro dwell means (rad/s); gyro outputs NaN without them.
    accel_noise, gyro_noise : DwellNoise, optional, keyword-only
        Noise models of the six dwells (same order); uncertainties are NaN without them.

    Returns
    -------
    SixPositionResult

    """
    g = float(gravity_m_s2)
    if not (math.isfinite(g) and 5.0 < g < 15.0):
        raise ParameterError(f'gravity must be a plausible value in m/s^2 (5..15), '
                             f'got {gravity_m_s2!r}')
    a = _table(accel_means_m_s2, 'accel_means_m_s2')
    if not np.all(np.isfinite(a)):
        raise InputDataError('a dwell mean of the accelerometer is NaN/Inf')
    w = (np.full((6, 3), np.nan) if gyro_means_rad_s is None
         else _table(gyro_means_rad_s, 'gyro_means_rad_s'))
    plus, minus = a[0::2], a[1::2]            # row i: dwell +i / -i
    resid = residual_projector() @ a
    scatter = float(np.sqrt(np.sum(resid ** 2) / 6.0))
    idx = np.arange(3)
    bias = (plus[idx, idx] + minus[idx, idx]) / 2.0                   # eq. 3
    scale = (plus[idx, idx] - minus[idx, idx] - 2.0 * g) / (2.0 * g)  # eq. 4
    # column i of (I + D + M) is (l(+i) - l(-i)) / 2g; row i of `plus - minus` is that column
    mis = ((plus - minus) / (2.0 * g)).T
    np.fill_diagonal(mis, 0.0)
    gyro = (w[0::2][idx, idx] + w[1::2][idx, idx]) / 2.0
    pair_sum = np.zeros((3, 6))               # row i: weights of the pair +i, -i
    pair_diff = np.zeros((3, 6))
    for i in range(3):
        pair_sum[i, 2 * i] = pair_sum[i, 2 * i + 1] = 0.5
        pair_diff[i, 2 * i], pair_diff[i, 2 * i + 1] = 1.0 / (2.0 * g), -1.0 / (2.0 * g)
    nan3, nan33 = np.full(3, np.nan), np.full((3, 3), np.nan)
    bias_se, scale_se, mis_se, gyro_se = nan3, nan3, nan33, nan3
    if accel_noise is not None:
        bias_se = np.sqrt(np.maximum(accel_noise.variance(pair_sum), 0.0))
        col_se = np.sqrt(np.maximum(accel_noise.variance(pair_diff), 0.0))   # every axis j
        scale_se = col_se.copy()
        mis_se = np.tile(col_se, (3, 1))
        np.fill_diagonal(mis_se, 0.0)
    if gyro_noise is not None:
        gyro_se = np.sqrt(np.maximum(gyro_noise.variance(pair_sum), 0.0))
    return SixPositionResult(g, bias, bias_se, scale, scale_se, mis, mis_se, gyro, gyro_se,
                             scatter)


def noise_models(dwells: Mapping[str, Dwell]) -> tuple[DwellNoise, DwellNoise]:
    """
    Fit the accelerometer and gyro noise models of six dwells (module docstring).

    Parameters
    ----------
    dwells : mapping
        Orientation -> :class:`~gyro_noise_ros.calibration.static.Dwell` (with window means).

    Returns
    -------
    (DwellNoise, DwellNoise)
        Accelerometer (tied to the 6 residual degrees of freedom of the 18 equations) and gyro
        (windows only: the horizontal Earth rate differs between dwells and is no wander).

    """
    dw = [dwells[o] for o in ORIENTATIONS]
    times = dwell_windows(d.window_t_s for d in dw)
    counts = dwell_windows(d.window_n for d in dw)
    a = np.array([d.accel_mean_m_s2 for d in dw])
    p = residual_projector()
    loading = np.concatenate([np.stack([_per_axis(p[r], j) for r in range(6)]) for j in range(3)])
    resid = (p @ a).T.reshape(-1)
    accel = fit_dwell_noise(times, counts, dwell_windows(d.window_accel_m_s2 for d in dw),
                            residual_loading=loading, residuals=resid)
    gyro = fit_dwell_noise(times, counts, dwell_windows(d.window_gyro_rad_s for d in dw))
    return accel, gyro


@dataclass(frozen=True)
class PairCheck:
    """
    Consistency of one pair of opposite dwells with the other two (module docstring).

    Attributes
    ----------
    axis : str
        ``'x'``, ``'y'`` or ``'z'``.
    disagreement_m_s2 : numpy.ndarray
        (3,) ``D_i = s_i - (s_k + s_l) / 2`` (m/s^2).
    sigma_m_s2 : float
        Standard deviation of each component under the noise model of the other pairs (m/s^2).
    chi2 : float
        ``|D_i|^2 / sigma^2``.
    p_value : float
        Upper tail probability of ``chi2 / 3`` under F(3, CHECK_DOF) (or of ``chi2`` under
        chi-square(3) for a pair retested after another failed).
    consistent : bool
        ``p_value >= alpha / 3``.
    suspect : str or None
        The dwell of the pair that does not fit (inconsistent pairs only).
    suspect_tilt_deg : float
        Angle between that dwell's specific force and the direction the rest of the calibration
        predicts for it (deg; NaN when consistent).

    """

    axis: str
    disagreement_m_s2: np.ndarray
    sigma_m_s2: float
    chi2: float
    p_value: float
    consistent: bool
    suspect: str | None = None
    suspect_tilt_deg: float = float('nan')

    def as_dict(self) -> dict[str, Any]:
        """Return JSON-ready values (units in the keys)."""
        return {'axis': self.axis, 'disagreement_m_s2': self.disagreement_m_s2.tolist(),
                'sigma_m_s2': self.sigma_m_s2, 'chi2': self.chi2, 'p_value': self.p_value,
                'consistent': self.consistent, 'suspect': self.suspect,
                'suspect_tilt_deg': (None if not math.isfinite(self.suspect_tilt_deg)
                                     else self.suspect_tilt_deg)}


@dataclass(frozen=True)
class LeaveOneOut:
    """
    Gravity check of one held-out dwell or pose: its calibrated norm against g.

    Attributes
    ----------
    label : str
        The dwell (orientation, or pose number and start time).
    residual_m_s2 : float
        ``|calibrated held-out mean| - g`` with the calibration of the others (m/s^2).
    sigma_m_s2 : float
        Its standard deviation under the noise model (m/s^2).
    z : float
        ``residual / sigma``.
    p_value : float
        Two-sided tail probability of ``z`` under Student's t with the check's degrees of freedom.
    consistent : bool
        ``p_value >= alpha / n`` (Bonferroni over the n dwells).

    """

    label: str
    residual_m_s2: float
    sigma_m_s2: float
    z: float
    p_value: float
    consistent: bool

    def as_dict(self) -> dict[str, Any]:
        """Return JSON-ready values (units in the keys)."""
        return {'dwell': self.label, 'residual_m_s2': self.residual_m_s2,
                'sigma_m_s2': self.sigma_m_s2, 'z': self.z, 'p_value': self.p_value,
                'consistent': self.consistent}


def _pair_weights(i: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    k, l_ = [a for a in range(3) if a != i]
    d = np.zeros(6)
    d[[2 * i, 2 * i + 1]] = 1.0
    d[[2 * k, 2 * k + 1, 2 * l_, 2 * l_ + 1]] = -0.5
    e = np.zeros(6)
    e[[2 * k, 2 * k + 1]] = 1.0
    e[[2 * l_, 2 * l_ + 1]] = -1.0
    return d, e


def _loo_matrix(a: NDArray[np.float64], g: float,
                out: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Calibration (A, b) of the six dwells in ``a`` without dwell index ``out``."""
    i = out // 2
    others = [k for k in range(3) if k != i]
    b = np.mean([a[2 * k] + a[2 * k + 1] for k in others], axis=0) / 2.0
    cols = np.zeros((3, 3))
    for k in others:
        cols[:, k] = (a[2 * k] - a[2 * k + 1]) / (2.0 * g)
    keep = out + 1 if out % 2 == 0 else out - 1          # the opposite dwell
    cols[:, i] = (a[keep] - b) / g * (1.0 if keep % 2 == 0 else -1.0)
    return cols, b


def _standardise(vector: NDArray[np.float64], var: float) -> tuple[float, float]:
    """Return the standard deviation and ``|vector|^2 / var`` (inf without a variance)."""
    if not var > 0:
        return float('nan'), float('inf')
    return math.sqrt(var), float(vector @ vector / var)


def _suspect(a: NDArray[np.float64], g: float, i: int) -> tuple[str, float]:
    """Name the dwell of pair i that does not fit, and its tilt (deg) from the prediction."""
    # the bad dwell is the one whose removal leaves the smaller cross-axis column
    off = [k for k in range(3) if k != i]
    size = []
    for out in (2 * i, 2 * i + 1):
        cols, _ = _loo_matrix(a, g, out)
        size.append(float(np.linalg.norm(cols[off, i])))
    out = 2 * i + int(np.argmin(size))
    cols, b = _loo_matrix(a, g, out)
    sign = 1.0 if out % 2 == 0 else -1.0
    pred = sign * g * cols[:, i]
    meas = a[out] - b
    cosang = pred @ meas / (np.linalg.norm(pred) * np.linalg.norm(meas))
    return ORIENTATIONS[out], float(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))))


def consistency(dwells: Mapping[str, Dwell], gravity_m_s2: float, *, alpha: float = DEFAULT_ALPHA
                ) -> tuple[tuple[PairCheck, ...], tuple[LeaveOneOut, ...]]:
    """
    Test the six dwells against the model and run the leave-one-out gravity check.

    Parameters
    ----------
    dwells : mapping
        Orientation -> :class:`~gyro_noise_ros.calibration.static.Dwell`.
    gravity_m_s2 : float
        Local gravity (m/s^2).
    alpha : float, keyword-only
        False-alarm probability of each of the two tests over the whole calibration.

    Returns
    -------
    (tuple of PairCheck, tuple of LeaveOneOut)
        One check per pair (x, y, z), one gravity check per dwell (:data:`ORIENTATIONS` order).

    """
    if not 0.0 < alpha < 1.0:
        raise ParameterError(f'alpha must be in (0, 1), got {alpha!r}')
    g = float(gravity_m_s2)
    dw = [dwells[o] for o in ORIENTATIONS]
    a = np.array([d.accel_mean_m_s2 for d in dw])
    times = dwell_windows(d.window_t_s for d in dw)
    fitter = DwellNoiseFitter(times, dwell_windows(d.window_n for d in dw),
                              dwell_windows(d.window_accel_m_s2 for d in dw))
    tests: list[tuple[NDArray[np.float64], float, float, float]] = []
    loo: list[tuple[int, LeaveOneOut]] = []
    for i in range(3):
        dvec, evec = _pair_weights(i)
        disagreement = dvec @ a
        loading = np.stack([_per_axis(evec, j) for j in range(3)])
        noise = fitter.fit(residual_loading=loading, residuals=evec @ a)
        # one weight vector: variance() returns a float
        sigma, stat = _standardise(disagreement, float(noise.variance(dvec)))
        tests.append((disagreement, sigma, stat, float(f_dist.sf(stat / 3.0, 3, CHECK_DOF))))
        for out in (2 * i, 2 * i + 1):
            cols, b = _loo_matrix(a, g, out)
            resid = float(np.linalg.norm(np.linalg.solve(cols, a[out] - b)) - g)
            z = resid / sigma if sigma > 0 else float('inf')
            pz = float(2.0 * t_dist.sf(abs(z), CHECK_DOF))
            loo.append((out, LeaveOneOut(ORIENTATIONS[out], resid, sigma, z, pz,
                                         pz >= alpha / 6.0)))
    worst = int(np.argmax([t[2] for t in tests]))
    bad = tests[worst][3] < alpha / 3.0
    pairs = []
    for i in range(3):
        disagreement, sigma, stat, p = tests[i]
        ok = True
        if bad and i == worst:
            ok = False
        elif bad:
            # a bad pair also moves the mean the other two are compared with: test those
            # against each other alone, with the noise of the windows (no residual is clean)
            other = 3 - i - worst
            cvec = np.zeros(6)
            cvec[[2 * i, 2 * i + 1]] = 1.0
            cvec[[2 * other, 2 * other + 1]] = -1.0
            disagreement = cvec @ a
            sigma, stat = _standardise(disagreement, float(fitter.fit().variance(cvec)))
            p = float(chi2.sf(stat, 3))
            ok = p >= alpha / 3.0
        suspect, tilt = (None, float('nan')) if ok else _suspect(a, g, i)
        pairs.append(PairCheck('xyz'[i], disagreement, sigma, stat, p, ok, suspect, tilt))
    loo.sort(key=lambda item: item[0])
    return tuple(pairs), tuple(item[1] for item in loo)


def calibrate_six(dwells: Mapping[str, Dwell],
                  gravity_m_s2: float) -> tuple[SixPositionResult, DwellNoise, DwellNoise]:
    """
    Run the six-position estimator with the noise models of its dwells.

    Parameters
    ----------
    dwells : mapping
        Orientation -> :class:`~gyro_noise_ros.calibration.static.Dwell`.
    gravity_m_s2 : float
        Local gravity (m/s^2).

    Returns
    -------
    (SixPositionResult, DwellNoise, DwellNoise)
        Estimate with uncertainties, accelerometer and gyro noise models.

    """
    dw = [dwells[o] for o in ORIENTATIONS]
    accel_noise, gyro_noise = noise_models(dwells)
    res = six_position([d.accel_mean_m_s2 for d in dw], gravity_m_s2,
                       gyro_means_rad_s=[d.gyro_mean_rad_s for d in dw],
                       accel_noise=accel_noise, gyro_noise=gyro_noise)
    return res, accel_noise, gyro_noise


def uniformity(values: ArrayLike) -> float:
    """
    Return the paper 001 section 6 uniformity indicator: the sample standard deviation (ddof = 1).

    ``values`` are the (3,) per-axis biases or scale factors; the result is in their unit.

    """
    return float(np.std(np.asarray(values, dtype=np.float64), ddof=1))


def mean_norm(accel_means_m_s2: ArrayLike) -> float:
    """
    Return the mean |a| over dwells, raw (paper 001 section 6: 9.848 m/s^2 before calibration).

    The norm of each dwell's mean is used (the mean of per-sample norms would add the noise
    variance / (2 g)), averaged with equal weight over the dwells.

    Parameters
    ----------
    accel_means_m_s2 : array_like
        (n, 3) dwell means (m/s^2).

    Returns
    -------
    float
        Mean norm (m/s^2).

    """
    a = np.asarray(accel_means_m_s2, dtype=np.float64)
    return float(np.mean(np.linalg.norm(a, axis=1)))
