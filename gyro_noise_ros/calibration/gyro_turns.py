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

Static dwells see only the Earth rate; the turns between them carry the gyro's scale factor. The
accelerometer, already calibrated, gives the direction of gravity in the sensor frame before
(``f_0``) and after (``f_1``) each turn, and the gyro rate ``w_k`` (rad/s), integrated over the
turn, must turn one into the other::

    f_1 = R(A_g)' f_0,    R = prod_k exp([inv(A_g) (w_k - b_k) dt_k]x)    (body-frame increments)

with ``A_g = I + diag(S_g) + M_g`` the gyro's matrix (paper 001 eq. 2) in the frame of the
accelerometer calibration. ``A_g`` (9 numbers) is fitted by least squares over all turns, 2
equations each (Tedaldi, Pretto, Menegatti, ICRA 2014, as imu_tk does). The bias ``b_k`` during
a turn is the straight line between the static means of the dwells before and after; the
integration is the midpoint rule on the stamps, composed as rotations. Each turn's residual is
whitened by its covariance from the gyro's variogram (:mod:`.dwell_noise`: white noise
isotropic, a slow rate error integrated in the turning body frame) and the accelerometer noise
of the two directions; the Earth rate's horizontal part (and, without the
latitude, all of it) is one nuisance vector common to all turns, fitted under a prior of its
known size. Uncertainties: ``inv(J'J)``, scaled up by the reduced chi-square when it exceeds 1.

A turn about the vertical moves no gravity and tells nothing: terms the turns do not determine
are left at 0 and named. Why this and not imucal's Ferraris turns, and the measured coverage:
docs/reliability.md section 1 (gyro scale factor and misalignment from the turns).
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from .dwell_noise import DwellNoise
from .sixpos import EARTH_RATE_RAD_S
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
                bias1: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    t, w = turn.t_s, turn.gyro_rad_s
    tm = (t[1:] + t[:-1]) / 2.0
    frac = np.clip((tm - t_b0) / max(t_b1 - t_b0, 1e-12), 0.0, 1.0)
    bias = bias0[None, :] + frac[:, None] * (bias1 - bias0)[None, :]
    return (w[1:] + w[:-1]) / 2.0 - bias, np.diff(t), frac


def _mean_gamma(noise: DwellNoise, ta: NDArray[np.float64], tb: NDArray[np.float64]) -> float:
    return float(noise.variogram(np.abs(ta[:, None] - tb[None, :])).mean())


def _angle_variance(noise: DwellNoise, turn: Turn, before: Dwell,
                    after: Dwell) -> tuple[float, float]:
    """
    Return the variances (rad^2 per axis) of the turn's angle error: (white, slow).

    White: the gyro's own white noise during the turn, ``a w T`` (``a`` the variogram's white
    level for window means of w seconds): it turns with the sensor sample by sample and stays
    isotropic. Slow: the rest of ``T^2 var(turn-mean rate - (bias before + bias after) / 2)``
    from the variogram (bias wander between the dwells' means and the turn, and the dwells'
    white noise in those means): nearly constant over a turn of seconds in the body frame, so it
    integrates through the turn's rotation (:func:`_turn_gain`).
    """
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
    total = max(var, 0.0) * span * span
    white = min(total, float(noise.coef[0]) * w * span)
    return white, total - white


def _attitudes(rates: NDArray[np.float64], dt: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 3, 3) attitude ``C(t)`` after each increment, relative to the start of the turn."""
    q = _quat(rates * dt[:, None])
    shift = 1
    while shift < q.shape[0]:
        # Hillis-Steele prefix scan: the product is associative, the earlier factor stays left
        q = np.concatenate([q[:shift], _qmul(q[:-shift], q[shift:])])
        shift *= 2
    return Rotation.from_quat(np.c_[q[:, 1:], q[:, :1]]).as_matrix()


def _whitener(f1: NDArray[np.float64], cov_angle: NDArray[np.float64],
              dir_var: float) -> NDArray[np.float64]:
    """
    Return W with ``W (f1 - predicted)`` of unit covariance on the plane across f1 (rank 2).

    A rotation error ``phi`` of the prediction moves it by ``phi x f1``; the gravity directions'
    own noise adds ``dir_var`` across f1.
    """
    cross = np.array([[0.0, -f1[2], f1[1]], [f1[2], 0.0, -f1[0]], [-f1[1], f1[0], 0.0]])
    across = np.eye(3) - np.outer(f1, f1)
    cov = cross @ cov_angle @ cross.T + dir_var * across
    val, vec = np.linalg.eigh(cov)
    inv = np.where(val > 1e-12 * max(val[-1], 1e-300), 1.0 / np.sqrt(np.maximum(val, 1e-300)),
                   0.0)
    return (vec * inv) @ vec.T


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


@dataclass(frozen=True)
class _Turns:
    """The usable turns, padded to one length (samples past a turn's end have dt = 0)."""

    rates: NDArray[np.float64]        # (K, T, 3) rate minus the interpolated bias (rad/s)
    dts: NDArray[np.float64]          # (K, T) increments' durations (s)
    f0: NDArray[np.float64]           # (K, 3) up before each turn
    f1: NDArray[np.float64]           # (K, 3) up after
    weight: NDArray[np.float64]       # (K, 3, 3) whitener of each turn's residual
    moved_deg: NDArray[np.float64]    # (K,) angle each turn moved gravity (deg)
    earth_load: NDArray[np.float64]   # (K, T, 3, p) rate error per unit of the Earth nuisance
    earth_sd: NDArray[np.float64]     # (p,) prior sd of the Earth nuisance (rad/s)


def _chain(turns: Sequence[Turn], poses: Sequence[Dwell]) -> dict[int, NDArray[np.float64]]:
    """Attitude of each pose the turns reach from the first turn's pose (pose frame -> its)."""
    att: dict[int, NDArray[np.float64]] = {}
    for turn in turns:
        if not att:
            att[turn.before] = np.eye(3)
        if turn.before not in att or turn.t_s.size < 2:
            break
        b, a = poses[turn.before], poses[turn.after]
        rates, dt, _ = _increments(turn, b.t_end_s, a.t_start_s, b.gyro_mean_rad_s,
                                   a.gyro_mean_rad_s)
        att[turn.after] = att[turn.before] @ _attitudes(rates, dt)[-1]
    return att


def _prepare(turns: Sequence[Turn], directions: ArrayLike, poses: Sequence[Dwell],
             gyro_noise: DwellNoise,
             direction_variance: NDArray[np.float64] | Sequence[float] | None,
             latitude_deg: float | None) -> _Turns:
    """
    Integrate-ready turns, their residual weights and the Earth-rate nuisance.

    The horizontal Earth rate (all of it without the latitude) points the same way in space for
    every turn, in a heading the poses do not give: it is a nuisance vector with a prior of its
    known size, carried into each turn's frame by the chain of turns (one nuisance for all, so
    its common effect is not averaged away as noise would be). Turns the chain does not reach
    count it in their own noise instead.
    """
    f = np.asarray(directions, dtype=np.float64)
    f = f / np.linalg.norm(f, axis=1, keepdims=True)
    att = _chain(turns, poses)
    first = f[turns[0].before] if turns else np.array([0.0, 0.0, 1.0])
    basis, sd = _earth_nuisance(first, latitude_deg)
    rows = []
    for k, turn in enumerate(turns):
        f0, f1 = f[turn.before], f[turn.after]
        if turn.t_s.size < 3 or turn.duration_s < MIN_TURN_S:
            continue
        moved = math.degrees(math.acos(float(np.clip(f0 @ f1, -1.0, 1.0))))
        if moved < MIN_TURN_DEG:
            continue
        b, a = poses[turn.before], poses[turn.after]
        rates, dt, frac = _increments(turn, b.t_end_s, a.t_start_s, b.gyro_mean_rad_s,
                                      a.gyro_mean_rad_s)
        mats = _attitudes(rates, dt)
        # rate error per unit of an Earth rate fixed in space, given in the pose's frame
        err = (np.transpose(mats, (0, 2, 1)) - (1.0 - frac)[:, None, None] * np.eye(3)
               - frac[:, None, None] * mats[-1].T)
        if latitude_deg is not None:
            vertical = EARTH_RATE_RAD_S * math.sin(math.radians(latitude_deg)) * f0
            rates = rates - err @ vertical
        white, slow = _angle_variance(gyro_noise, turn, b, a)
        gain = mats[-1].T @ np.einsum('tij,t->ij', mats, dt)
        cov = white * np.eye(3) + slow * gain @ gain.T / max(turn.duration_s, 1e-12) ** 2
        if turn.before in att:
            load = err @ (att[turn.before].T @ basis)
        else:
            earth = mats[-1].T @ np.einsum('tij,tjk,t->ik', mats, err, dt)
            load = np.zeros((dt.size, 3, basis.shape[1]))
            cov = cov + earth @ (basis * sd ** 2) @ basis.T @ earth.T
        dir_var = 0.0 if direction_variance is None else float(direction_variance[k])
        rows.append((rates, dt, f0, f1, _whitener(f1, cov + 1e-24 * np.eye(3), dir_var),
                     moved, load))
    return _pad(rows, sd)


def _pad(rows: list[tuple[Any, ...]], sd: NDArray[np.float64]) -> _Turns:
    k = len(rows)
    longest = max([r[0].shape[0] for r in rows], default=1)
    rates, dts = np.zeros((k, longest, 3)), np.zeros((k, longest))
    load = np.zeros((k, longest, 3, sd.size))
    for j, r in enumerate(rows):
        n = r[0].shape[0]
        rates[j, :n], dts[j, :n], load[j, :n] = r[0], r[1], r[6]
    stack = (lambda i, shape: np.array([r[i] for r in rows]) if rows else np.zeros(shape))
    return _Turns(rates, dts, stack(2, (0, 3)), stack(3, (0, 3)), stack(4, (0, 3, 3)),
                  stack(5, (0,)), load, sd)


def _earth_nuisance(up: NDArray[np.float64],
                    latitude_deg: float | None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    Return the basis (3, p) of the unknown Earth rate in the first pose's frame and its sd.

    With the latitude the vertical part ``Omega_E sin(lat) up`` is known (removed directly) and
    the horizontal ``Omega_E cos(lat)`` has an unknown heading: two components across ``up``,
    each with sd ``Omega_h / sqrt(2)``. Without it, all three of ``Omega_E`` (sd ``Omega_E /
    sqrt(3)`` each).
    """
    if latitude_deg is None:
        return np.eye(3), np.full(3, EARTH_RATE_RAD_S / math.sqrt(3.0))
    u = up / np.linalg.norm(up)
    e1 = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    horizontal = EARTH_RATE_RAD_S * math.cos(math.radians(latitude_deg))
    return np.column_stack([e1, e2]), np.full(2, horizontal / math.sqrt(2.0))


def direction_variances(turns: Sequence[Turn], accel_noise: DwellNoise,
                        accel_index: Sequence[int], gravity_m_s2: float) -> list[float]:
    """
    Return the variance (rad^2) of the two gravity directions' disagreement across each turn.

    Each transverse component: the difference of the two poses' accelerometer means under the
    accelerometer's variogram (white noise and wander between them), over g^2.

    Parameters
    ----------
    turns : sequence of Turn
        The turns.
    accel_noise : DwellNoise
        The accelerometer's variogram on the poses.
    accel_index : sequence of int
        Index of each pose (as the turns number them) among ``accel_noise``'s dwells.
    gravity_m_s2 : float
        Local gravity (m/s^2).

    Returns
    -------
    list of float

    """
    out = []
    for turn in turns:
        c = np.zeros(len(accel_noise.weights))
        c[accel_index[turn.before]] += 1.0
        c[accel_index[turn.after]] -= 1.0
        out.append(float(accel_noise.variance(c)) / gravity_m_s2 ** 2)
    return out


def fit_gyro_turns(turns: Sequence[Turn], directions: ArrayLike, poses: Sequence[Dwell],
                   gyro_noise: DwellNoise, *,
                   direction_variance: NDArray[np.float64] | Sequence[float] | None = None,
                   max_sigma: float = MAX_SIGMA,
                   latitude_deg: float | None = None) -> GyroTurnResult:
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
    latitude_deg : float, optional, keyword-only
        Latitude (deg): the vertical Earth rate is removed during each turn, the horizontal part
        (heading unknown) counted as an error; without it all of the Earth rate is an error.

    Returns
    -------
    GyroTurnResult

    Raises
    ------
    InputDataError
        Fewer than 5 usable turns (2 equations each, 9 unknowns), or turns that determine none
        of the parameters.

    """
    prep = _prepare(turns, directions, poses, gyro_noise, direction_variance, latitude_deg)
    if prep.f0.shape[0] < 5:
        raise InputDataError(f'the gyro calibration needs at least 5 turns that move gravity by '
                             f'{MIN_TURN_DEG:g} deg or more between static poses, found '
                             f'{prep.f0.shape[0]}')
    n_h = prep.earth_load.shape[-1]

    def predict(theta: NDArray[np.float64], free: NDArray[np.intp]) -> NDArray[np.float64]:
        ainv = np.linalg.inv(_matrix(theta[:free.size], free))
        rates = prep.rates - np.einsum('ktip,p->kti', prep.earth_load, theta[free.size:])
        return rotate_back(compose_quat((rates @ ainv.T) * prep.dts[..., None]), prep.f0)

    def residual(theta: NDArray[np.float64], free: NDArray[np.intp]) -> NDArray[np.float64]:
        r = np.einsum('kij,kj->ki', prep.weight, prep.f1 - predict(theta, free)).reshape(-1)
        return np.concatenate([r, theta[free.size:] / prep.earth_sd])

    free = np.ones(9, dtype=bool)
    while True:
        idx = np.flatnonzero(free)
        scale = np.r_[np.full(idx.size, 1e-3), prep.earth_sd]
        sol = least_squares(residual, np.zeros(idx.size + n_h), args=(idx,), method='lm',
                            x_scale=scale, diff_step=1e-7, xtol=1e-14, ftol=1e-14)
        jac = sol.jac
        chi2 = float(np.sum(sol.fun ** 2))
        dof = 2 * prep.f0.shape[0] - idx.size
        try:
            cov = np.linalg.inv(jac.T @ jac)
            sig = np.sqrt(np.clip(np.diag(cov)[:idx.size], 0.0, None))
        except np.linalg.LinAlgError:
            sig = np.full(idx.size, np.inf)
        # the turns disagree more than the noise model says: scale it up (never down)
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
    full[idx], full_sig[idx] = sol.x[:idx.size], sig
    scale, scale_sig = full[:3], full_sig[:3]
    mis, mis_sig, est = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3), dtype=bool)
    est[np.arange(3), np.arange(3)] = free[:3]
    for k, (j, i) in enumerate(OFF_DIAGONAL):
        mis[j, i], mis_sig[j, i], est[j, i] = full[3 + k], full_sig[3 + k], free[3 + k]
    pred = predict(sol.x, idx)
    resid_deg = np.degrees(np.arccos(np.clip(np.sum(pred * prep.f1, axis=1), -1.0, 1.0)))
    return GyroTurnResult(scale, scale_sig, mis, mis_sig, est, prep.f0.shape[0], chi2, dof,
                          resid_deg, prep.moved_deg)
