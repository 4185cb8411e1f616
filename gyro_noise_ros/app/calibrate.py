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
The static calibration workflow: recordings in, one :class:`CalibrationResult` out, files written.

Shared by ``gyro_noise_calibrate`` and the calibration parts of ``gyro_noise_reliability``.

Steps (``docs/reliability.md`` section 1):

1. every recording is streamed through the static-dwell detector (constant memory);
2. ``six-position`` (paper 001 eqs. 3-4): one dwell per orientation, the consistency test (a
   tilted dwell is named and refused) and the estimate with uncertainties from the dwells' own
   variogram; ``multi-pose`` (imu_tk): every dwell a pose, |a| = g fit;
3. the gyro's scale factor and misalignment from the turns between consecutive dwells of one
   recording (a second pass reads only the turns), when the turns determine them;
4. the leave-one-out gravity check.

:func:`write_calibration` writes ``calibration.json`` (:meth:`CalibrationResult.as_dict`) and,
rendered from it by :mod:`..calibration.calibrate_report` and :mod:`..htmlreport.calibrate`,
``calibration.yaml`` (a ROS 2 parameter file ``imu_compensator`` loads), ``calibration.md`` and
``report.html``.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
import datetime
import json
import math
import os
from typing import Any

import numpy as np

from .. import __version__
from ..calibration import records
from ..calibration.calibrate_report import calibration_markdown, calibration_yaml
from ..calibration.dwell_noise import fit_dwell_noise
from ..calibration.gyro_turns import (direction_variances, fit_gyro_turns, GyroTurnResult,
                                      Turn)
from ..calibration.multipose import calibrate_poses, NO_GRAVITY_CHECK
from ..calibration.sixpos import (calibrate_six, consistency, DEFAULT_ALPHA, EARTH_RATE_RAD_S,
                                  mean_norm, normal_gravity, uniformity)
from ..calibration.static import (DetectorSettings, Dwell, find_dwells, ORIENTATIONS,
                                  select_poses, select_six, WindowAccumulator)
from ..errors import InputDataError, ParameterError
from ..formatting import finite_list
from ..htmlreport.calibrate import write_calibrate_html
from ..outputs import atomic_write_text, staged_output, StrPath
from ..units import MG_TO_M_S2, STANDARD_GRAVITY_M_S2

MODEL = 'measured = (I + diag(scale_factor) + misalignment) @ true + bias'
MODES = ('six-position', 'multi-pose')
GYRO_TURNS = ('auto', 'off')
FILES = ('calibration.json', 'calibration.yaml', 'calibration.md')
FRAMES = {
    'six-position': 'the fixture: gravity along +x, +y, +z in the six dwells',
    'multi-pose': "the accelerometer's: x along its x sensing axis, y in the plane of its x and "
                  'y axes (imu_tk)',
}


@dataclass(frozen=True)
class Gravity:
    """
    The local gravity of a calibration and how it was obtained.

    Attributes
    ----------
    value_m_s2 : float
        Gravity (m/s^2).
    source : str
        How it was obtained (one phrase).
    warning : str or None
        A line to print (standard gravity used for want of a local value).
    latitude_deg : float or None
        Geodetic latitude when given (deg; the Earth rate in the multi-pose gyro bias).

    """

    value_m_s2: float = STANDARD_GRAVITY_M_S2
    source: str = 'standard gravity 9.80665 (no local value given)'
    warning: str | None = None
    latitude_deg: float | None = None


def resolve_gravity(gravity: float | None = None, latitude: float | None = None,
                    height: float = 0.0) -> Gravity:
    """
    Return the gravity to use and how it was obtained.

    Parameters
    ----------
    gravity : float, optional
        Explicit local gravity (m/s^2).
    latitude : float, optional
        Geodetic latitude (deg) for WGS-84 normal gravity.
    height : float
        Ellipsoidal height (m), with ``latitude`` only.

    Returns
    -------
    Gravity

    """
    if height != 0.0 and latitude is None:
        raise ParameterError('--height needs --latitude')
    if gravity is not None:
        if not (math.isfinite(gravity) and 5.0 < gravity < 15.0):
            raise ParameterError(f'--gravity must be in m/s^2 (5..15), got {gravity!r}')
        return Gravity(float(gravity), 'given (--gravity)')
    if latitude is not None:
        g = normal_gravity(latitude, height)
        return Gravity(g, f'WGS-84 normal gravity at latitude {latitude:g} deg, height '
                          f'{height:g} m', None, float(latitude))
    return Gravity(warning='no --gravity or --latitude: using standard gravity 9.80665 m/s^2; '
                           'the scale factors then carry the local gravity anomaly (up to '
                           '+/-0.3 %)')


@dataclass(frozen=True)
class CalibrateParams:
    """
    What to calibrate and how.

    Attributes
    ----------
    paths : tuple of str
        Recordings: one holding every dwell (with the turns between them), or one per dwell.
    gravity : Gravity
        Local gravity.
    mode : str
        ``'six-position'`` (paper 001) or ``'multi-pose'`` (imu_tk, >= 9 arbitrary poses).
    topic : str or None
        ``sensor_msgs/Imu`` topic (the single one when None).
    rate_hz : float or None
        Nominal rate (Hz); from the stamps when None.
    settings : DetectorSettings
        Static-dwell detector.
    alpha : float
        False-alarm probability of the consistency test and of the gravity check.
    gyro_turns : str
        ``'auto'``: estimate the gyro scale factor and misalignment from the turns when they
        determine them; ``'off'``: never (they stay 0).

    """

    paths: tuple[str, ...]
    gravity: Gravity = field(default_factory=Gravity)
    mode: str = 'six-position'
    topic: str | None = None
    rate_hz: float | None = None
    settings: DetectorSettings = field(default_factory=DetectorSettings)
    alpha: float = DEFAULT_ALPHA
    gyro_turns: str = 'auto'

    def __post_init__(self) -> None:
        object.__setattr__(self, 'paths', tuple(str(p) for p in self.paths))
        if not self.paths:
            raise ParameterError('give at least one recording')
        if self.mode not in MODES:
            raise ParameterError(f'--mode must be one of {", ".join(MODES)}, got {self.mode!r}')
        if self.gyro_turns not in GYRO_TURNS:
            raise ParameterError(f'--gyro-turns must be one of {", ".join(GYRO_TURNS)}, got '
                                 f'{self.gyro_turns!r}')
        if not (math.isfinite(self.alpha) and 0.0 < self.alpha < 0.5):
            raise ParameterError(f'--alpha must be in (0, 0.5), got {self.alpha!r}')
        if self.rate_hz is not None and not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ParameterError(f'--rate-hz must be > 0, got {self.rate_hz!r}')


def _mat(v: Any) -> list[list[float | None]]:
    return [finite_list(row) for row in np.asarray(v, dtype=np.float64)]


@dataclass(frozen=True)
class CalibrationResult:
    """
    Everything a calibration reports (``calibration.json`` is :meth:`as_dict`).

    Attributes
    ----------
    params : CalibrateParams
        What was asked.
    dwells : tuple of Dwell
        The dwells used, in recording and time order.
    short_dwells : tuple of Dwell
        Static stretches shorter than ``--min-static-s`` (reported, not used).
    accel_bias_m_s2, accel_bias_sigma_m_s2 : numpy.ndarray
        (3,) bias and standard uncertainty (m/s^2).
    accel_scale_factor, accel_scale_factor_sigma : numpy.ndarray
        (3,) dimensionless.
    accel_misalignment, accel_misalignment_sigma : numpy.ndarray
        (3, 3) zero diagonal (multi-pose: lower triangular, the frame fixes the rest).
    accel_residual_rms_m_s2 : float
        Scatter of the dwell means about the fitted model (m/s^2).
    gyro_bias_rad_s, gyro_bias_sigma_rad_s : numpy.ndarray
        (3,) gyro bias and standard uncertainty (rad/s).
    gyro : GyroTurnResult or None
        Scale factor and misalignment from the turns (None: not estimated, see ``gyro_note``).
    gyro_note : str
        Why the gyro scale/misalignment are (partly) not estimated; '' when all are.
    consistency : tuple of PairCheck
        Six-position consistency test (empty for multi-pose).
    gravity_check : tuple of LeaveOneOut
        Leave-one-out gravity check, one per dwell.
    mean_norm_raw_m_s2 : float
        Mean |a| of the raw dwell means (paper 001 section 6).
    noise : dict
        ``{'accel': DwellNoise, 'gyro': DwellNoise}``.
    non_finite_samples : int
        Samples dropped for NaN/Inf over all recordings.
    left_out : tuple of str
        Multi-pose: poses the gravity check rejected, left out of the fit.

    """

    params: CalibrateParams
    dwells: tuple[Any, ...]
    short_dwells: tuple[Any, ...]
    accel_bias_m_s2: np.ndarray
    accel_bias_sigma_m_s2: np.ndarray
    accel_scale_factor: np.ndarray
    accel_scale_factor_sigma: np.ndarray
    accel_misalignment: np.ndarray
    accel_misalignment_sigma: np.ndarray
    accel_residual_rms_m_s2: float
    gyro_bias_rad_s: np.ndarray
    gyro_bias_sigma_rad_s: np.ndarray
    gyro: GyroTurnResult | None
    gyro_note: str
    consistency: tuple[Any, ...]
    gravity_check: tuple[Any, ...]
    mean_norm_raw_m_s2: float
    noise: dict[str, Any]
    non_finite_samples: int
    left_out: tuple[str, ...] = ()
    version: str = __version__

    @property
    def gravity_m_s2(self) -> float:
        """float: the gravity used (m/s^2)."""
        return self.params.gravity.value_m_s2

    @property
    def gyro_scale_factor(self) -> np.ndarray:
        """numpy.ndarray: (3,) gyro scale factors (0 where not estimated)."""
        return np.zeros(3) if self.gyro is None else self.gyro.scale_factor

    @property
    def gyro_misalignment(self) -> np.ndarray:
        """numpy.ndarray: (3, 3) gyro cross-axis terms (0 where not estimated)."""
        return np.zeros((3, 3)) if self.gyro is None else self.gyro.misalignment

    @property
    def gravity_check_consistent(self) -> bool | None:
        """Every held-out dwell used agrees with g: bool; None when no check could run."""
        if not self.gravity_check:
            return None
        return all(c.consistent for c in self.gravity_check if c.label not in self.left_out)

    def warnings(self) -> list[str]:
        """
        Return the lines a tool prints on stderr (standard gravity, NaN dropped, failed check).

        Returns
        -------
        list of str

        """
        out: list[str] = []
        if self.params.gravity.warning:
            out.append(self.params.gravity.warning)
        for d in self.dwells:
            if d.non_finite_samples:
                where = f' in {d.source}' if d.source else ''
                out.append(f'dwell {d.orientation} at t={d.t_start_s:.1f} s{where}: '
                           f'{d.non_finite_samples} NaN/Inf samples dropped')
        if self.left_out:
            out.append('left out of the fit, the gravity check rejects them: '
                       + '; '.join(self.left_out))
        bad = [c for c in self.gravity_check
               if not c.consistent and c.label not in self.left_out]
        if bad:
            out.append('gravity check failed (leave-one-out, false-alarm '
                       f'{self.params.alpha:g}): ' + '; '.join(
                           f'{c.label}: |a| - g = {c.residual_m_s2 / MG_TO_M_S2:+.3f} mg '
                           f'({c.z:+.1f} sigma)' for c in bad))
        if self.gyro_note:
            out.append(f'gyro: {self.gyro_note}')
        return out

    def as_dict(self) -> dict[str, Any]:
        """
        Return the ``calibration.json`` document (SI, units in the keys).

        Returns
        -------
        dict

        """
        p = self.params
        gyro = self.gyro
        gyro_doc: dict[str, Any] = {
            'bias_rad_s': finite_list(self.gyro_bias_rad_s),
            'bias_sigma_rad_s': finite_list(self.gyro_bias_sigma_rad_s),
            'scale_factor': finite_list(self.gyro_scale_factor),
            'misalignment': _mat(self.gyro_misalignment),
            'scale_factor_estimated': bool(gyro is not None and gyro.estimated.diagonal().all()),
            'method': 'integration of the turns between static poses (imu_tk), bias '
                      'interpolated between the poses',
            'note': self.gyro_note,
        }
        if gyro is not None:
            gyro_doc.update({
                'scale_factor_sigma': finite_list(gyro.scale_factor_sigma),
                'misalignment_sigma': _mat(gyro.misalignment_sigma),
                'estimated': gyro.estimated.tolist(),
                'turns': gyro.turns, 'chi2': gyro.chi2, 'dof': gyro.dof,
                'turn_residual_deg': finite_list(gyro.residual_deg),
                'turn_rotation_deg': finite_list(gyro.rotation_deg)})
        loo = self.gravity_check
        noise = {k: {'window_s': n.window_s, 'white': float(n.coef[0]),
                     'flicker': float(n.coef[1]), 'walk': float(n.coef[2]),
                     'unit': 'm_s2^2' if k == 'accel' else 'rad_s^2'}
                 for k, n in self.noise.items()}
        return {
            'mode': p.mode,
            'gravity_m_s2': self.gravity_m_s2,
            'gravity_source': p.gravity.source,
            'model': MODEL,
            'frame': FRAMES[p.mode],
            'sources': list(p.paths),
            'dwells': [d.as_dict() for d in self.dwells],
            'accel': {
                'bias_m_s2': finite_list(self.accel_bias_m_s2),
                'bias_sigma_m_s2': finite_list(self.accel_bias_sigma_m_s2),
                'scale_factor': finite_list(self.accel_scale_factor),
                'scale_factor_sigma': finite_list(self.accel_scale_factor_sigma),
                'misalignment': _mat(self.accel_misalignment),
                'misalignment_sigma': _mat(self.accel_misalignment_sigma),
                'residual_rms_m_s2': self.accel_residual_rms_m_s2,
            },
            'gyro': gyro_doc,
            'uncertainty': 'one standard uncertainty against the value during the calibration, '
                           'from the variogram of the dwells (white noise and bias wander)',
            'uniformity': {
                'accel_bias_std_m_s2': uniformity(self.accel_bias_m_s2),
                'accel_scale_factor_std': uniformity(self.accel_scale_factor),
                'gyro_bias_std_rad_s': uniformity(self.gyro_bias_rad_s),
            },
            'consistency': {
                'alpha': p.alpha,
                'consistent': all(c.consistent for c in self.consistency),
                'pairs': [c.as_dict() for c in self.consistency],
            },
            'gravity_check': {
                'method': 'leave-one-out: each dwell calibrated by the others, |a| - g',
                'alpha': p.alpha,
                'mean_norm_raw_m_s2': self.mean_norm_raw_m_s2,
                'loo_mean_norm_m_s2': float(np.mean([self.gravity_m_s2 + c.residual_m_s2
                                                     for c in loo])) if loo else None,
                'consistent': self.gravity_check_consistent,
                'note': '' if loo else NO_GRAVITY_CHECK,
                'left_out': list(self.left_out),
                'dwells': [c.as_dict() for c in loo],
            },
            'noise_model': noise,
            'detector': {k: getattr(p.settings, k) for k in p.settings.__dataclass_fields__},
            'non_finite_samples': self.non_finite_samples,
            'short_dwells': [d.as_dict() for d in self.short_dwells],
            'version': self.version,
        }


def _first_stamp_ns(path: str, topic: str | None) -> int:
    stamp = records.first_stamp_ns(path, topic=topic)
    assert stamp is not None  # _detect refused a recording without samples
    return stamp


def _shifted(dwell: Dwell, dt_s: float) -> Dwell:
    assert dwell.window_t_s is not None  # find_dwells fills the windows
    return replace(dwell, window_t_s=dwell.window_t_s + dt_s)


def _detect(params: CalibrateParams) -> list[Any]:
    out = []
    for path in params.paths:
        acc = None
        for rate, t, accel, gyro in records.iter_imu(path, topic=params.topic,
                                                     rate_hz=params.rate_hz):
            if acc is None:
                acc = WindowAccumulator(rate, window_s=params.settings.window_s, source=path)
            acc.update(t, accel, gyro)
        if acc is None:
            raise InputDataError(f'recording {path!r} holds no Imu samples')
        out.append(find_dwells(acc.result(), params.settings))
    if len(params.paths) > 1:
        # dwells of separate recordings: the noise model needs their real distance in time
        # (stamps; messages keep each recording's own t = 0)
        first = [_first_stamp_ns(p, params.topic) for p in params.paths]
        t0 = min(first)
        out = [replace(det, dwells=tuple(_shifted(d, (f - t0) * 1e-9) for d in det.dwells))
               for det, f in zip(out, first)]
    return out


def _refuse_inconsistent(pairs: Sequence[Any], chosen: dict[str, Any], alpha: float) -> None:
    bad = [c for c in pairs if not c.consistent]
    if not bad:
        return
    parts = []
    for c in bad:
        d = chosen[c.suspect]
        off = float(np.linalg.norm(c.disagreement_m_s2)) / MG_TO_M_S2
        parts.append(f'dwell {d.describe()} does not fit the other five: its pair disagrees '
                     f'with the others by {off:.2f} mg ({math.sqrt(c.chi2):.0f} sigma), the '
                     f'direction of gravity in it is {c.suspect_tilt_deg:.2f} deg off what they '
                     f'predict (a tilted fixture, or a bump)')
    raise InputDataError('; '.join(parts) + f' [consistency test, false-alarm {alpha:g}]: '
                         're-seat and re-record it, or record >= 9 poses for --mode multi-pose')


def _turn_spans(dwells: Sequence[Any]) -> dict[str, list[tuple[int, float, float]]]:
    spans: dict[str, list[tuple[int, float, float]]] = {}
    for k in range(len(dwells) - 1):
        a, b = dwells[k], dwells[k + 1]
        if a.source == b.source:
            spans.setdefault(a.source, []).append((k, a.t_end_s, b.t_start_s))
    return spans


def _read_turns(params: CalibrateParams, dwells: Sequence[Any]) -> list[Turn]:
    out = []
    for path, spans in _turn_spans(dwells).items():
        parts: dict[int, tuple[list[np.ndarray], list[np.ndarray]]] = {
            k: ([], []) for k, _, _ in spans}
        for _, t, _, gyro in records.iter_imu(path, topic=params.topic, rate_hz=params.rate_hz):
            for k, lo, hi in spans:
                if t.size and (t[-1] < lo or t[0] > hi):
                    continue
                sel = (t >= lo - 1e-9) & (t <= hi + 1e-9)
                if np.any(sel):
                    parts[k][0].append(t[sel])
                    parts[k][1].append(gyro[sel])
        for k, _, _ in spans:
            ts, gs = parts[k]
            if ts:
                tt, gg = np.concatenate(ts), np.concatenate(gs)
                good = np.all(np.isfinite(gg), axis=1)
                out.append(Turn(k, k + 1, tt[good], gg[good]))
    return out


def _gyro_from_turns(params: CalibrateParams, dwells: Sequence[Any], directions: np.ndarray,
                     accel_noise: Any, accel_index: Sequence[int],
                     gyro_noise: Any) -> tuple[GyroTurnResult | None, str]:
    if params.gyro_turns == 'off':
        return None, 'not estimated (--gyro-turns off)'
    turns = _read_turns(params, dwells)
    if not turns:
        return None, ('not estimated: the dwells come from separate recordings, so no turn '
                      'between them was recorded')
    dvar = direction_variances(turns, accel_noise, accel_index, params.gravity.value_m_s2)
    try:
        res = fit_gyro_turns(turns, directions, dwells, gyro_noise, direction_variance=dvar,
                             latitude_deg=params.gravity.latitude_deg)
    except InputDataError as err:
        return None, f'not estimated: {err}'
    missing = res.not_estimated
    note = (f'{", ".join(missing)} not determined by the {res.turns} turns (left at 0): '
            'record the multi-pose sequence (turns about varied axes)' if missing else '')
    return res, note


def _time_order(dwells: Iterable[Any], params: CalibrateParams) -> list[Any]:
    rank = {p: k for k, p in enumerate(params.paths)}
    return sorted(dwells, key=lambda d: (rank.get(d.source, 0), d.t_start_s))


def _multi_pose_gyro_bias(dwells: Sequence[Any], directions: np.ndarray,
                          latitude_deg: float | None) -> tuple[np.ndarray, np.ndarray]:
    w = np.array([d.samples for d in dwells], dtype=np.float64)
    w /= w.sum()
    gm = np.array([d.gyro_mean_rad_s for d in dwells])
    up = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    bias = w @ gm
    if latitude_deg is not None:
        lat = math.radians(latitude_deg)
        # the vertical Earth rate is known in each pose (up = the specific force at rest)
        bias = bias - EARTH_RATE_RAD_S * math.sin(lat) * (w @ up)
        horiz = EARTH_RATE_RAD_S * math.cos(lat)
        # the horizontal part's heading is unknown: random per pose, variance (1 - u_j^2) / 2
        var = horiz ** 2 * (w ** 2 @ (1.0 - up ** 2)) / 2.0
    else:
        var = EARTH_RATE_RAD_S ** 2 * np.sum(w ** 2) / 3.0 * np.ones(3)
    return bias, np.sqrt(var)


def run_calibration(params: CalibrateParams) -> CalibrationResult:
    """
    Run the whole calibration on recordings (module docstring).

    Parameters
    ----------
    params : CalibrateParams
        What to calibrate and how.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InputDataError
        The dwells do not give a calibration (missing, duplicate, tilted or inconsistent, too
        short, never static, all-zero accelerometer, NaN), with one line naming the dwell.
    BagError
        A recording cannot be read.

    """
    detections = _detect(params)
    g = params.gravity.value_m_s2
    short = tuple(d for det in detections for d in det.short)
    nonfinite = int(sum(det.non_finite_samples for det in detections))
    if params.mode == 'six-position':
        chosen = select_six(detections, params.settings)
        pairs, loo = consistency(chosen, g, alpha=params.alpha)
        _refuse_inconsistent(pairs, chosen, params.alpha)
        res, accel_noise, gyro_noise = calibrate_six(chosen, g)
        dwells = _time_order(chosen.values(), params)
        index = {id(d): ORIENTATIONS.index(d.orientation) for d in dwells}
        accel_index = [index[id(d)] for d in dwells]
        means = np.array([d.accel_mean_m_s2 for d in dwells])
        directions = res.compensate_accel(means)
        accel = (res.accel_bias_m_s2, res.accel_bias_sigma_m_s2, res.accel_scale_factor,
                 res.accel_scale_factor_sigma, res.accel_misalignment,
                 res.accel_misalignment_sigma, res.accel_residual_m_s2)
        gyro_bias, gyro_sigma = res.gyro_bias_rad_s, res.gyro_bias_sigma_rad_s
        raw = mean_norm([d.accel_mean_m_s2 for d in chosen.values()])
        left_out: tuple[str, ...] = ()
    else:
        dwells = _time_order(select_poses(detections, params.settings), params)
        mp, loo, accel_noise = calibrate_poses(dwells, g, alpha=params.alpha)
        gyro_noise = fit_dwell_noise([d.window_t_s for d in dwells],
                                     [d.window_n for d in dwells],
                                     [d.window_gyro_rad_s for d in dwells])
        pairs = ()
        left_out = mp.left_out
        if left_out:
            # the rest of the workflow sees only the poses the fit used
            labels = [c.label for c in loo]
            dwells = [d for d, lab in zip(dwells, labels) if lab not in left_out]
        accel_index = list(range(len(dwells)))
        means = np.array([d.accel_mean_m_s2 for d in dwells])
        directions = mp.compensate(means)
        accel = (mp.bias_m_s2, mp.bias_sigma_m_s2, mp.scale_factor, mp.scale_factor_sigma,
                 mp.misalignment, mp.misalignment_sigma, mp.rms_residual_m_s2)
        gyro_bias, gyro_sigma = _multi_pose_gyro_bias(dwells, directions,
                                                      params.gravity.latitude_deg)
        raw = mean_norm(means)
    gyro, note = _gyro_from_turns(params, dwells, directions, accel_noise, accel_index,
                                  gyro_noise)
    return CalibrationResult(params, tuple(dwells), short, *accel, gyro_bias, gyro_sigma, gyro,
                             note, tuple(pairs), tuple(loo), raw,
                             {'accel': accel_noise, 'gyro': gyro_noise}, nonfinite, left_out)


def calibration_files(result: CalibrationResult) -> dict[str, str]:
    """
    Return the text files of a calibration, rendered from its document: name -> text.

    Parameters
    ----------
    result : CalibrationResult
        The calibration.

    Returns
    -------
    dict
        calibration.json, calibration.yaml (stamped with the time now, UTC) and calibration.md.

    """
    doc = result.as_dict()
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ')
    return {'calibration.json': json.dumps(doc, indent=2) + '\n',
            'calibration.yaml': calibration_yaml(doc, written_utc=stamp),
            'calibration.md': calibration_markdown(doc)}


def write_calibration(result: CalibrationResult, out_dir: StrPath, *, html: bool = True,
                      command: Sequence[str] | None = None) -> list[str]:
    """
    Write calibration.json, .yaml, .md and report.html (published together or not at all).

    Parameters
    ----------
    result : CalibrationResult
        The calibration.
    out_dir : str or os.PathLike
        Output folder (created).
    html : bool, keyword-only
        Write report.html (:mod:`..htmlreport.calibrate`).
    command : sequence of str, optional, keyword-only
        The command line, shown on report.html.

    Returns
    -------
    list of str
        The files written.

    """
    with staged_output(out_dir) as stage:
        for name, text in calibration_files(result).items():
            atomic_write_text(stage / name, text)
        if html:
            write_calibrate_html(result.as_dict(), stage, command=command)
    return [os.path.join(str(out_dir), name)
            for name in FILES + (('report.html',) if html else ())]
