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
Multi-pose accelerometer calibration: any number (>= 9) of static poses fitted by |a| = g.

The method users of imu_tk know (Tedaldi, Pretto, Menegatti, ICRA 2014): at rest the calibrated
specific force has the norm of local gravity whatever the attitude, so poses need not be aligned
with anything (a hand-held box on a table will do); only the **norms** are used, so a tilt cannot
fool it. Model (the package's one, paper 001 eq. 1)::

    measured = A @ true + b,      A = I + diag(S) + M

A rotation of the reference frame leaves every norm unchanged, so only 9 of the 12 numbers are
seen: the frame is fixed the way imu_tk fixes it, **x along the accelerometer's x sensing axis,
y in the plane of its x and y axes**, i.e. ``A`` is lower triangular (``M[0, 1] = M[0, 2] =
M[1, 2] = 0``; the three free cross-axis terms are the non-orthogonality). The compensator and
the gyro calibration (:mod:`~gyro_noise_ros.calibration.gyro_turns`) work in that frame.
:func:`triangular` turns any ``A`` (an emulator's truth) into it.

Fit: Levenberg-Marquardt (scipy ``least_squares``) on ``r_d = |inv(A) (l_d - b)| - g`` from
``A = I, b = 0``, with the analytic Jacobian. Uncertainties: the estimate is linear in the pose
means to first order, ``theta - theta_true = L e`` with ``L = -(J'J)^-1 J' D`` and
``D_d = dr_d / dl_d``; its covariance comes from the sensor's variogram
(:mod:`~gyro_noise_ros.calibration.dwell_noise`, tied to the fit's residuals), against the bias
during the calibration. Gravity check that can fail: each pose left out in turn, the calibration
of the others predicts its norm (:func:`leave_one_out`).
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.stats import norm
from scipy.stats import t as t_dist

from .apply import SensorCalibration
from .dwell_noise import DwellNoise, DwellNoiseFitter
from .sixpos import DEFAULT_ALPHA, LeaveOneOut
from .static import Dwell, dwell_windows, MIN_POSES
from ..errors import InputDataError, ParameterError

#: Parameters: b (3), S (3), then the lower cross-axis terms M[1, 0], M[2, 0], M[2, 1].
LOWER = ((1, 0), (2, 0), (2, 1))
PARAMETERS = 9
#: The noise model is tied to the fit's residuals from this many residual degrees of freedom
#: on; with fewer it rests on the windows inside the dwells (a sum of squares of 1-5 degrees of
#: freedom scatters by a factor 1.6-4, and a bad pose among them inflates it).
MIN_RESIDUAL_DOF = 6
#: Largest accepted 2-norm condition number of the fit's Jacobian: the poses must point in
#: enough directions (all upright or all on one side leaves a scale factor undetermined).
MAX_CONDITION = 1e6


#: The gravity check of a multi-pose calibration of exactly 9 poses.
NO_GRAVITY_CHECK = ('not possible: the 9 poses determine the 9 calibration numbers exactly, none '
                    'is left over to be predicted by the others (record 10 or more poses)')


def gravity_check_words(gc: dict[str, Any]) -> str:
    """
    Return the gravity check's verdict in words from its ``calibration.json`` entry.

    Parameters
    ----------
    gc : dict
        ``calibration.json['gravity_check']``.

    Returns
    -------
    str
        ``'consistent'``, ``'INCONSISTENT'`` or the note why no check was possible.

    """
    if gc['consistent'] is None:
        return gc.get('note') or 'not possible'
    return 'consistent' if gc['consistent'] else 'INCONSISTENT'


def triangular(matrix: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    Return the lower-triangular form of a sensor matrix and the rotation into its frame.

    ``A = L @ Q`` (an LQ decomposition with a positive diagonal): ``measured = L @ (Q @ true)``,
    so ``L`` is the same sensor seen in the frame of :mod:`this module's <.multipose>` fit and
    ``Q`` rotates true vectors into that frame.

    Parameters
    ----------
    matrix : array_like
        (3, 3) ``I + diag(S) + M`` in any frame.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``L`` (lower triangular) and ``Q`` (rotation, det +1).

    """
    a = np.asarray(matrix, dtype=np.float64)
    q, r = np.linalg.qr(a.T)
    sign = np.sign(np.diag(r))
    sign[sign == 0] = 1.0
    lower = (r * sign[:, None]).T
    rot = (q * sign[None, :]).T
    return lower, rot


def _unpack(theta: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    b = theta[:3]
    a = np.eye(3) + np.diag(theta[3:6])
    for k, (j, i) in enumerate(LOWER):
        a[j, i] = theta[6 + k]
    return a, b


def _residual(theta: NDArray[np.float64], means: NDArray[np.float64],
              g: float) -> NDArray[np.float64]:
    a, b = _unpack(theta)
    u = np.linalg.solve(a, (means - b).T).T
    return np.linalg.norm(u, axis=1) - g


def _jacobian(theta: NDArray[np.float64], means: NDArray[np.float64],
              g: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    a, b = _unpack(theta)
    ainv = np.linalg.inv(a)
    u = (means - b) @ ainv.T
    nrm = np.linalg.norm(u, axis=1)
    v = (u / nrm[:, None]) @ ainv          # row d: n_d' inv(A) = dr_d / dl_d
    jac = np.empty((means.shape[0], 9))
    jac[:, :3] = -v
    for i in range(3):
        jac[:, 3 + i] = -v[:, i] * u[:, i]
    for k, (j, i) in enumerate(LOWER):
        jac[:, 6 + k] = -v[:, j] * u[:, i]
    return jac, v


def _solve(means: NDArray[np.float64], g: float,
           theta0: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    x0 = np.zeros(9) if theta0 is None else theta0
    sol = least_squares(_residual, x0, jac=lambda t, m, gg: _jacobian(t, m, gg)[0],
                        args=(means, g), method='lm', xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        max_nfev=2000)
    return sol.x


@dataclass(frozen=True)
class MultiPoseResult:
    """
    Accelerometer calibration from static poses by |a| = g.

    Attributes
    ----------
    gravity_m_s2 : float
        Local gravity used (m/s^2).
    bias_m_s2, bias_sigma_m_s2 : numpy.ndarray
        (3,) bias and its standard uncertainty (m/s^2, against the bias during the calibration).
    scale_factor, scale_factor_sigma : numpy.ndarray
        (3,) scale factors (dimensionless) and their standard uncertainties.
    misalignment, misalignment_sigma : numpy.ndarray
        (3, 3) lower-triangular cross-axis terms (zero diagonal and upper part) and their
        standard uncertainties (0 where fixed by the frame).
    residual_m_s2 : numpy.ndarray
        (n,) ``|calibrated pose| - g`` of each pose kept (m/s^2).
    rms_residual_m_s2 : float
        sqrt(RSS / (n - 9)) (m/s^2).
    covariance : numpy.ndarray
        (9, 9) covariance of (b, S, M[1,0], M[2,0], M[2,1]).
    left_out : tuple of str
        Poses the gravity check rejected, not used in the fit.

    """

    gravity_m_s2: float
    bias_m_s2: np.ndarray
    bias_sigma_m_s2: np.ndarray
    scale_factor: np.ndarray
    scale_factor_sigma: np.ndarray
    misalignment: np.ndarray
    misalignment_sigma: np.ndarray
    residual_m_s2: np.ndarray
    rms_residual_m_s2: float
    covariance: np.ndarray
    left_out: tuple[str, ...] = ()

    @property
    def matrix(self) -> NDArray[np.float64]:
        """numpy.ndarray: (3, 3) ``I + diag(S) + M``."""
        return np.eye(3) + np.diag(self.scale_factor) + self.misalignment

    def compensate(self, measured_m_s2: ArrayLike) -> np.ndarray:
        """
        Apply the calibration to (..., 3) specific forces: ``inv(I + diag(S) + M) @ (l - b)``.

        :meth:`.apply.SensorCalibration.apply` with this result's terms; in and out in m/s^2.

        """
        return SensorCalibration(self.bias_m_s2, self.scale_factor,
                                 self.misalignment).apply(measured_m_s2)


def _check_means(means: ArrayLike, g: float) -> tuple[NDArray[np.float64], float]:
    a = np.asarray(means, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ParameterError(f'pose means must be (n, 3), got shape {a.shape}')
    if a.shape[0] < MIN_POSES:
        raise InputDataError(f'multi-pose calibration needs at least {MIN_POSES} poses, got '
                             f'{a.shape[0]}')
    if not np.all(np.isfinite(a)):
        raise InputDataError('a pose mean of the accelerometer is NaN/Inf')
    g = float(g)
    if not (math.isfinite(g) and 5.0 < g < 15.0):
        raise ParameterError(f'gravity must be a plausible value in m/s^2 (5..15), got {g!r}')
    return a, g


def multi_pose(means_m_s2: ArrayLike, gravity_m_s2: float) -> NDArray[np.float64]:
    """
    Fit bias, scale factors and non-orthogonality to pose means by |a| = g (no uncertainties).

    Parameters
    ----------
    means_m_s2 : array_like
        (n, 3) mean specific force of each static pose (m/s^2), n >= 9.
    gravity_m_s2 : float
        Local gravity (m/s^2).

    Returns
    -------
    numpy.ndarray
        (9,) ``theta``: b (m/s^2), S, M[1, 0], M[2, 0], M[2, 1].

    Raises
    ------
    InputDataError
        Too few poses, or poses that do not determine the 9 numbers (too few directions).

    """
    a, g = _check_means(means_m_s2, gravity_m_s2)
    theta = _solve(a, g)
    jac, _ = _jacobian(theta, a, g)
    cond = np.linalg.cond(jac)
    if not math.isfinite(cond) or cond > MAX_CONDITION:
        raise InputDataError(f'the {a.shape[0]} poses do not determine the calibration (Jacobian '
                             f'condition number {cond:.3g}): they must point gravity along '
                             f'enough different directions (both signs of every axis)')
    return theta


def _loading(theta: NDArray[np.float64], means: NDArray[np.float64],
             g: float) -> NDArray[np.float64]:
    """(9, n, 3) first-order loading of theta on the pose means."""
    jac, v = _jacobian(theta, means, g)
    core = -np.linalg.solve(jac.T @ jac, jac.T)          # (9, n)
    return core[:, :, None] * v[None, :, :]


def calibrate_poses(dwells: Sequence[Dwell], gravity_m_s2: float, *, alpha: float = DEFAULT_ALPHA
                    ) -> tuple[MultiPoseResult, tuple[LeaveOneOut, ...], DwellNoise]:
    """
    Run the multi-pose fit on dwells, with uncertainties and the leave-one-out gravity check.

    A pose the gravity check rejects (a knock, a pose that moved) also bends the fit of every
    other pose's check, so the worst rejected pose is set aside and the checks are run again,
    until none is rejected; the calibration is then fitted without the poses set aside (named in
    ``MultiPoseResult.left_out``), as long as 9 remain.

    Parameters
    ----------
    dwells : sequence of Dwell
        The static poses (with window means).
    gravity_m_s2 : float
        Local gravity (m/s^2).
    alpha : float, keyword-only
        False-alarm probability of the gravity check over all poses.

    Returns
    -------
    (MultiPoseResult, tuple of LeaveOneOut, DwellNoise)
        The calibration, one check per pose (in the order given), the accelerometer's noise
        model (of the poses kept).

    Raises
    ------
    InputDataError
        Too few poses, or too few left once the rejected ones are set aside.

    """
    means, g = _check_means([d.accel_mean_m_s2 for d in dwells], gravity_m_s2)
    n = len(dwells)
    theta = multi_pose(means, g)
    fitter = DwellNoiseFitter(dwell_windows(d.window_t_s for d in dwells),
                              dwell_windows(d.window_n for d in dwells),
                              dwell_windows(d.window_accel_m_s2 for d in dwells))
    out: list[int] = []
    while True:
        checks = leave_one_out(dwells, g, theta, fitter, alpha=alpha, exclude=out)
        bad = [k for k in range(len(checks)) if k not in out and not checks[k].consistent]
        if not bad or n - len(out) - 1 < MIN_POSES + 1:
            break
        out.append(max(bad, key=lambda k: abs(checks[k].z)))
        keep = [k for k in range(n) if k not in out]
        theta = _solve(means[keep], g, theta)
    keep = [k for k in range(n) if k not in out]
    if len(keep) < MIN_POSES:
        raise InputDataError(f'multi-pose calibration: only {len(keep)} poses pass the gravity '
                             f'check (need {MIN_POSES})')
    kept = [dwells[k] for k in keep]
    means = means[keep]
    theta = multi_pose(means, g)
    fitter = DwellNoiseFitter(dwell_windows(d.window_t_s for d in kept),
                              dwell_windows(d.window_n for d in kept),
                              dwell_windows(d.window_accel_m_s2 for d in kept))
    resid = _residual(theta, means, g)
    noise = _noise_of_fit(fitter, theta, means, g)
    cov = noise.covariance(_loading(theta, means, g))
    sig = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    a, b = _unpack(theta)
    mis = a - np.diag(np.diag(a))
    mis_sig = np.zeros((3, 3))
    for k, (j, i) in enumerate(LOWER):
        mis_sig[j, i] = sig[6 + k]
    result = MultiPoseResult(g, b, sig[:3], theta[3:6], sig[3:6], mis, mis_sig, resid,
                             float(np.sqrt(np.sum(resid ** 2) / max(len(kept) - 9, 1))), cov,
                             tuple(checks[k].label for k in sorted(out)))
    return result, checks, noise


def _noise_of_fit(fitter: DwellNoiseFitter, theta: NDArray[np.float64],
                  means: NDArray[np.float64], g: float, *,
                  columns: NDArray[np.intp] | None = None, n_all: int = 0) -> DwellNoise:
    """
    Fit the variogram to the dwells' windows, tied to the fit's residuals when it has any.

    With exactly 9 poses the fit has no residual (9 equations, 9 numbers); its projector is zero
    to rounding, and tying the model to those rounding residuals made every uncertainty ~1e-14.
    ``columns``/``n_all``: the poses of ``means`` among ``n_all`` dwells of the fitter.
    """
    if means.shape[0] - PARAMETERS < MIN_RESIDUAL_DOF:
        return fitter.fit()
    jac, v = _jacobian(theta, means, g)
    proj = np.eye(means.shape[0]) - jac @ np.linalg.solve(jac.T @ jac, jac.T)
    loading = proj[:, :, None] * v[None, :, :]
    if columns is not None:
        full = np.zeros((means.shape[0], n_all, 3))
        full[:, columns, :] = loading
        loading = full
    return fitter.fit(residual_loading=loading, residuals=proj @ _residual(theta, means, g))


def _label(k: int, d: Dwell) -> str:
    return f'pose {k + 1} ({d.orientation} at t={d.t_start_s:.1f} s)'


def leave_one_out(dwells: Sequence[Dwell], gravity_m_s2: float, theta: NDArray[np.float64],
                  fitter: DwellNoiseFitter, *, alpha: float = DEFAULT_ALPHA,
                  exclude: Sequence[int] = ()) -> tuple[LeaveOneOut, ...]:
    """
    Refit without each pose in turn and compare its calibrated norm with g.

    The noise model of each check is refitted to the residuals of the other poses' fit, so a bad
    pose cannot hide itself by inflating the noise.

    Parameters
    ----------
    dwells : sequence of Dwell
        The poses.
    gravity_m_s2 : float
        Local gravity (m/s^2).
    theta : numpy.ndarray
        A fit (starting point of the refits).
    fitter : DwellNoiseFitter
        Of the same dwells.
    alpha : float, keyword-only
        False-alarm probability over all poses (Bonferroni, two-sided; z read against Student's t
        with n - 10 degrees of freedom, those of the residuals the noise model leans on).
    exclude : sequence of int, keyword-only
        Poses left out of every refit (already rejected).

    Returns
    -------
    tuple of LeaveOneOut

    """
    means = np.array([d.accel_mean_m_s2 for d in dwells])
    g = float(gravity_m_s2)
    n = means.shape[0]
    if n - len(set(exclude)) <= PARAMETERS:
        # each check refits the other poses: with 9 poses in all that leaves 8 for 9 numbers
        return ()
    out = []
    for k in range(n):
        keep = np.flatnonzero((np.arange(n) != k) & ~np.isin(np.arange(n), list(exclude)))
        dof = keep.size - PARAMETERS if keep.size - PARAMETERS >= MIN_RESIDUAL_DOF else 0
        th = _solve(means[keep], g, theta)
        resid_k = float(_residual(th, means[k:k + 1], g)[0])
        jac, v = _jacobian(th, means[keep], g)
        core = -np.linalg.solve(jac.T @ jac, jac.T)        # theta error per kept residual
        # loading of the held-out residual: its own mean, plus its response to the refit
        jk, vk = _jacobian(th, means[k:k + 1], g)
        load = np.zeros((n, 3))
        load[k] = vk[0]
        load[keep] += (jk[0] @ core)[:, None] * v
        noise = _noise_of_fit(fitter, th, means[keep], g, columns=keep, n_all=n)
        var = float(noise.covariance(load[None])[0, 0])
        sigma = math.sqrt(var) if var > 0 else float('nan')
        z = resid_k / sigma if sigma > 0 else float('inf')
        # the noise model leans on the other poses' residuals (Student's t with their n - 9
        # degrees of freedom) when they have MIN_RESIDUAL_DOF or more; otherwise it rests on
        # the windows inside the dwells alone, read as normal (rates: docs/reliability.md)
        p = float(2.0 * (t_dist.sf(abs(z), dof) if dof else norm.sf(abs(z))))
        out.append(LeaveOneOut(_label(k, dwells[k]), resid_k, sigma, z, p, p >= alpha / n))
    return tuple(out)
