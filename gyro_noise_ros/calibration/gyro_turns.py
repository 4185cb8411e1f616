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
Gyro scale factor and misalignment from the turns between static poses (imu_tk's integration).

Static dwells see only the Earth rate, so a static calibration cannot tell the gyro's scale factor
(for a seeker's stabilisation loop the number that matters most). The turns between the dwells
can: the accelerometer, already calibrated, gives the direction of gravity in the sensor frame
before (``f_0``) and after (``f_1``) each turn, and the gyro, integrated over the turn, must turn
one into the other::

    f_1 = R(A_g)' f_0,    R = prod_k exp([inv(A_g) (w_k - b_k) dt_k]x)    (body-frame increments)

with ``A_g = I + diag(S_g) + M_g`` the gyro's matrix (the package's model, paper 001 eq. 2) in
the frame of the accelerometer calibration. ``A_g`` (9 numbers) is fitted by least squares over
all turns (Tedaldi, Pretto, Menegatti, ICRA 2014, as imu_tk does; each turn gives 2 equations).

**Why this and not imucal's Ferraris 360-degree turns**: Ferraris needs turns of exactly known
angle (a turntable or an indexed jig) about each axis, recorded separately; the integration
between poses needs nothing but the recording the accelerometer calibration already has, with
any turns, and the reference is gravity itself. Its limit: a turn about the vertical moves no
gravity and tells nothing, and a 180-degree flip is blind to the part of the misalignment that
tilts its axis in the plane perpendicular to gravity; the multi-pose sequence (tens of turns
about varied axes) determines all nine numbers, the six-position one usually not (the fit says
which terms the turns do not determine and leaves them at 0).

Details that matter at the 0.01 % level:

* the gyro bias during a turn is the straight line between the static means of the dwells
  before and after, which removes the bias and its drift *and* the Earth rate as seen in each
  pose (the Earth rate left is its change during the turn, < 1e-4 rad over a 5 s turn);
* integration by the midpoint rule on the sample stamps, composed as rotations (exact for the
  piecewise-constant rate), not as summed angles;
* each turn's residual is weighed by its own standard deviation: the angle error
  ``T * (turn-mean rate error)`` from the gyro's variogram
  (:mod:`~gyro_noise_ros.calibration.dwell_noise`: white noise and bias wander between the
  dwells' means and the turn, as one contrast), plus the noise of the two gravity directions
  (accelerometer variogram);
* uncertainties: the Gauss-Newton covariance ``inv(J'J)``, scaled up by the reduced chi-square
  when it exceeds 1 (the turns disagree more than the noise says).
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from .dwell_noise import DwellNoise
from .static import Dwell
from ..errors import InputDataError

#: A parameter whose standard uncertainty would exceed this (0.5 %) is not determined by the
#: turns: it is fixed at 0 and named (a MEMS gyro's scale and cross-axis errors are ~0.1-1 %).
MAX_SIGMA = 5e-3
#: Order of the nine parameters: S_x, S_y, S_z, then M[j, i] row by row without the diagonal.
OFF_DIAGONAL = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))
#: A turn shorter than this (s) or turning gravity by less than this (deg) is not used.
MIN_TURN_S = 0.05
MIN_TURN_DEG = 5.0


def _quat(rotvecs: ArrayLike) -> NDArray[np.float64]:
    """Return the unit quaternions (w, x, y, z) of rotation vectors (..., 3)."""
    v = np.asarray(rotvecs, dtype=np.float64)
    angle = np.linalg.norm(v, axis=-1)
    half = angle / 2.0
    # sin(a/2)/a by its series below 1e-4 rad (relative error < 1e-17)
    k = np.where(angle > 1e-4, np.sin(half) / np.where(angle > 0, angle, 1.0),
                 0.5 - angle * angle / 48.0)
    return np.concatenate([np.cos(half)[..., None], v * k[..., None]], axis=-1)


def _qmul(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Hamilton product p q of quaternion arrays (..., 4): the rotation matrix of p times q's."""
    pw, pv = p[..., :1], p[..., 1:]
    qw, qv = q[..., :1], q[..., 1:]
    return np.concatenate([pw * qw - np.sum(pv * qv, axis=-1, keepdims=True),
                           pw * qv + qw * pv + np.cross(pv, qv)], axis=-1)


def compose_quat(rotvecs: ArrayLike) -> NDArray[np.float64]:
    """
    Return ``exp(v_0) exp(v_1) ... exp(v_{n-1})`` along the second-to-last axis, as quaternions.

    Pairwise (tree) reduction in numpy: log2(n) vectorised products; batched over leading axes
    (zero rotation vectors pad shorter turns).

    Parameters
    ----------
    rotvecs : array_like
        (..., n, 3) body-frame rotation increments (rad), in time order.

    Returns
    -------
    numpy.ndarray
        (..., 4) unit quaternions (w, x, y, z).

    """
    q = _quat(rotvecs)
    while q.shape[-2] > 1:
        if q.shape[-2] % 2:
            ident = np.zeros(q.shape[:-2] + (1, 4))
            ident[..., 0] = 1.0
            q = np.concatenate([q, ident], axis=-2)
        q = _qmul(q[..., 0::2, :], q[..., 1::2, :])
    return q[..., 0, :]


def rotate_back(q: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Apply the inverse of the rotations ``q`` (..., 4) to vectors ``v`` (..., 3)."""
    w, u = q[..., :1], -q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def compose(rotvecs: ArrayLike) -> Rotation:
    """
    Return the product of body-frame rotation increments as a scipy Rotation.

    Parameters
    ----------
    rotvecs : array_like
        (n, 3) rotation vectors (rad), in time order.

    Returns
    -------
    scipy.spatial.transform.Rotation

    """
    v = np.asarray(rotvecs, dtype=np.float64).reshape(-1, 3)
    if v.shape[0] == 0:
        return Rotation.identity()
    q = compose_quat(v)
    return Rotation.from_quat(np.r_[q[1:], q[:1]])


@dataclass(frozen=True)
class Turn:
    """
    The samples of one turn between two static poses.

    Attributes
    ----------
    before, after : int
        Indices of the poses (in the list given to :func:`fit_gyro_turns`).
    t_s : numpy.ndarray
        (n,) sample stamps (s), from the end of the dwell before to the start of the one after.
    gyro_rad_s : numpy.ndarray
        (n, 3) measured angular rate (rad/s).

    """

    before: int
    after: int
    t_s: np.ndarray
    gyro_rad_s: np.ndarray

    @property
    def duration_s(self) -> float:
        """float: last minus first stamp (s)."""
        return float(self.t_s[-1] - self.t_s[0]) if self.t_s.size > 1 else 0.0


def _matrix(theta: NDArray[np.float64], free: NDArray[np.intp]) -> NDArray[np.float64]:
    full = np.zeros(9)
    full[free] = theta
    a = np.eye(3) + np.diag(full[:3])
    for k, (j, i) in enumerate(OFF_DIAGONAL):
        a[j, i] = full[3 + k]
    return a


def _increments(turn: Turn, t_b0: float, t_b1: float, bias0: NDArray[np.float64],
                bias1: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    t, w = turn.t_s, turn.gyro_rad_s
    tm = (t[1:] + t[:-1]) / 2.0
    frac = np.clip((tm - t_b0) / max(t_b1 - t_b0, 1e-12), 0.0, 1.0)
    bias = bias0[None, :] + frac[:, None] * (bias1 - bias0)[None, :]
    return (w[1:] + w[:-1]) / 2.0 - bias, np.diff(t)


def _mean_gamma(noise: DwellNoise, ta: NDArray[np.float64], tb: NDArray[np.float64]) -> float:
    return float(noise.variogram(np.abs(ta[:, None] - tb[None, :])).mean())


def _angle_variance(noise: DwellNoise, turn: Turn, before: Dwell, after: Dwell) -> float:
    """Variance (rad^2) of the turn's integrated angle per axis from the gyro's variogram."""
    # the poses come from find_dwells, which keeps their windows
    assert before.window_t_s is not None and after.window_t_s is not None
    w = noise.window_s
    span = turn.duration_s
    tt = turn.t_s[0] + (np.arange(max(1, int(math.ceil(span / w)))) + 0.5) * min(w, span)
    sets = (tt, before.window_t_s, after.window_t_s)
    c = (1.0, -0.5, -0.5)
    var = 0.0
    for i in range(3):
        for j in range(3):
            var -= c[i] * c[j] * _mean_gamma(noise, sets[i], sets[j])
    return max(var, 0.0) * span * span


@dataclass(frozen=True)
class GyroTurnResult:
    """
    Gyro scale factor and misalignment from the turns (module docstring).

    Attributes
    ----------
    scale_factor, scale_factor_sigma : numpy.ndarray
        (3,) dimensionless scale factors and standard uncertainties (NaN where not estimated).
    misalignment, misalignment_sigma : numpy.ndarray
        (3, 3) cross-axis terms (zero diagonal) and standard uncertainties (NaN where not
        estimated).
    estimated : numpy.ndarray
        (3, 3) bool: diagonal = scale factor, off-diagonal = cross-axis term, determined by the
        turns (the others are 0 in ``scale_factor`` / ``misalignment``).
    turns : int
        Turns used.
    chi2, dof : float, int
        Weighted residual sum of squares and its degrees of freedom (2 per turn - parameters).
    residual_deg : numpy.ndarray
        (turns,) angle between the measured and the predicted gravity after each turn (deg).
    rotation_deg : numpy.ndarray
        (turns,) angle each turn moved gravity (deg).

    """

    scale_factor: np.ndarray
    scale_factor_sigma: np.ndarray
    misalignment: np.ndarray
    misalignment_sigma: np.ndarray
    estimated: np.ndarray
    turns: int
    chi2: float
    dof: int
    residual_deg: np.ndarray
    rotation_deg: np.ndarray

    @property
    def matrix(self) -> NDArray[np.float64]:
        """numpy.ndarray: (3, 3) ``I + diag(S) + M``."""
        return np.eye(3) + np.diag(self.scale_factor) + self.misalignment

    @property
    def not_estimated(self) -> list[str]:
        """Names of the terms the turns do not determine (``S_x``, ``M_xy``, ...): list of str."""
        out = [f'S_{a}' for i, a in enumerate('xyz') if not self.estimated[i, i]]
        out += [f'M_{"xyz"[j]}{"xyz"[i]}' for j, i in OFF_DIAGONAL if not self.estimated[j, i]]
        return out


def fit_gyro_turns(turns: Sequence[Turn], directions: ArrayLike, poses: Sequence[Dwell],
                   gyro_noise: DwellNoise, *,
                   direction_variance: NDArray[np.float64] | Sequence[float] | None = None,
                   max_sigma: float = MAX_SIGMA) -> GyroTurnResult:
    """
    Fit the gyro's scale factors and misalignment to the turns between static poses.

    Parameters
    ----------
    turns : sequence of Turn
        Turns between consecutive poses of one recording.
    directions : array_like
        (m, 3) gravity direction of each pose in the calibrated accelerometer frame (unit
        vectors, REP-103: the specific force at rest points up).
    poses : sequence of Dwell
        The m poses (their gyro means are the bias at the ends of each turn; their window stamps
        place them in time for the noise model).
    gyro_noise : DwellNoise
        The gyro's variogram (fitted on the same poses).
    direction_variance : numpy.ndarray or sequence of float, optional, keyword-only
        (len(turns),) variance (rad^2) of the gravity directions' disagreement across each turn
        per component (accelerometer noise); 0 when not given.
    max_sigma : float, keyword-only
        Parameters less well determined than this are fixed at 0 (module docstring).

    Returns
    -------
    GyroTurnResult

    Raises
    ------
    InputDataError
        Fewer than 5 usable turns (2 equations each, 9 unknowns), or turns that determine none
        of the parameters.

    """
    f = np.asarray(directions, dtype=np.float64)
    f = f / np.linalg.norm(f, axis=1, keepdims=True)
    prepared = []
    for k, turn in enumerate(turns):
        if turn.t_s.size < 3 or turn.duration_s < MIN_TURN_S:
            continue
        f0, f1 = f[turn.before], f[turn.after]
        moved = math.degrees(math.acos(float(np.clip(f0 @ f1, -1.0, 1.0))))
        if moved < MIN_TURN_DEG:
            continue
        b, a = poses[turn.before], poses[turn.after]
        rates, dt = _increments(turn, b.t_end_s, a.t_start_s, b.gyro_mean_rad_s,
                                a.gyro_mean_rad_s)
        var = _angle_variance(gyro_noise, turn, b, a)
        if direction_variance is not None:
            var += float(direction_variance[k])
        prepared.append((rates, dt, f0, f1, math.sqrt(max(var, 1e-24)), moved))
    if len(prepared) < 5:
        raise InputDataError(f'the gyro calibration needs at least 5 turns that move gravity by '
                             f'{MIN_TURN_DEG:g} deg or more between static poses, found '
                             f'{len(prepared)}')

    longest = max(p[0].shape[0] for p in prepared)
    rates = np.zeros((len(prepared), longest, 3))
    dts = np.zeros((len(prepared), longest))
    for k, p in enumerate(prepared):
        rates[k, :p[0].shape[0]] = p[0]
        dts[k, :p[1].shape[0]] = p[1]
    f0 = np.array([p[2] for p in prepared])
    f1 = np.array([p[3] for p in prepared])
    sigma = np.array([p[4] for p in prepared])[:, None]

    def predict(theta: NDArray[np.float64], free: NDArray[np.intp]) -> NDArray[np.float64]:
        ainv = np.linalg.inv(_matrix(theta, free))
        return rotate_back(compose_quat((rates @ ainv.T) * dts[..., None]), f0)

    def residual(theta: NDArray[np.float64], free: NDArray[np.intp]) -> NDArray[np.float64]:
        return ((f1 - predict(theta, free)) / sigma).reshape(-1)

    free = np.ones(9, dtype=bool)
    while True:
        idx = np.flatnonzero(free)
        sol = least_squares(residual, np.zeros(idx.size), args=(idx,), method='lm',
                            x_scale=1e-3, diff_step=1e-7, xtol=1e-14, ftol=1e-14)
        jac = sol.jac
        chi2 = float(np.sum(sol.fun ** 2))
        dof = 2 * len(prepared) - idx.size
        try:
            cov = np.linalg.inv(jac.T @ jac)
            sig = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        except np.linalg.LinAlgError:
            sig = np.full(idx.size, np.inf)
        sig = sig * math.sqrt(max(1.0, chi2 / max(dof, 1)))
        worst = int(np.argmax(sig))
        if sig[worst] <= max_sigma:
            break
        free[idx[worst]] = False
        if not free.any():
            raise InputDataError('the turns between the static poses determine none of the gyro '
                                 'scale factors and cross-axis terms: record turns about '
                                 'varied horizontal axes (the multi-pose sequence)')
    full, full_sig = np.zeros(9), np.full(9, np.nan)
    full[idx], full_sig[idx] = sol.x, sig
    scale, scale_sig = full[:3], full_sig[:3]
    mis, mis_sig, est = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3), dtype=bool)
    est[np.arange(3), np.arange(3)] = free[:3]
    for k, (j, i) in enumerate(OFF_DIAGONAL):
        mis[j, i], mis_sig[j, i], est[j, i] = full[3 + k], full_sig[3 + k], free[3 + k]
    pred = predict(sol.x, idx)
    resid_deg = np.degrees(np.arccos(np.clip(np.sum(pred * f1, axis=1), -1.0, 1.0)))
    return GyroTurnResult(scale, scale_sig, mis, mis_sig, est, len(prepared), chi2, dof,
                          resid_deg, np.array([p[5] for p in prepared]))
