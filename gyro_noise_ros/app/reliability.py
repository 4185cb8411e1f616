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
The reliability workflow of paper 001: before/after recordings in, one verdict a lab can sign out.

Shared by ``gyro_noise_reliability`` (and later an HTML report). Steps (``docs/reliability.md``
section 2):

1. each static record is streamed through :class:`..calibration.static_record.StaticRecord`:
   per channel the dense Allan deviation, its one readout, the bias-instability interval with
   the uncertainty of its width, and the noise terms with theirs; its temperature from the
   recording's ``sensor_msgs/Temperature``;
2. each calibration runs the calibration workflow (:func:`..app.calibrate.run_calibration`), and
   each dwell gets its temperature;
3. per channel the width change is tested against the +/- tolerance band
   (:func:`..calibration.interval.compare`: beyond, physiological or undetermined with the record
   length that would decide), and per sensor the three axes give one verdict
   (:func:`..calibration.interval.overall`).

:class:`ReliabilityResult` carries every number; :meth:`ReliabilityResult.as_dict` is exactly
``reliability.json``; :func:`markdown` and :func:`in_short` render a document of that form, so
a report generator needs only the JSON. :func:`write_reliability` writes every file through
:func:`..outputs.staged_output`.
"""

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
import io
import json
import math
import os
from typing import Any, cast, Union

import numpy as np

from .calibrate import (CalibrateParams, calibration_files, CalibrationResult, Gravity,
                        run_calibration)
from .. import __version__
from ..calibration import records
from ..calibration.calibrate_report import table6_rows
from ..calibration.interval import (compare, DEFAULT_ALPHA, DEFAULT_C, DEFAULT_MIN_EDF,
                                    DEFAULT_TOLERANCE, overall)
from ..calibration.static import DetectorSettings
from ..calibration.static_record import CHANNELS, StaticRecord, TERMS, unit_of
from ..errors import BagError, InputDataError, ParameterError
from ..formatting import finite_or_none as _num
from ..htmlreport.reliability import write_reliability_html
from ..outputs import atomic_write_text, staged_output
from ..units import MG_TO_M_S2, RAD_TO_DEG

PARTS = ('before_calibration', 'before_static', 'after_calibration', 'after_static')
SIDES = ('before', 'after')
SENSORS = ('accel', 'gyro')
#: Printed unit and SI-to-printed factor of each channel family.
UNITS = {'m_s2': ('m/s^2', 1.0), 'rad_s': ('deg/s', RAD_TO_DEG)}
TERM_UNITS = {
    'white_noise': ('{u}_per_sqrt_hz', '{p}/sqrt(Hz)'),
    'bias_stability': ('{u}', '{p}'),
    'random_walk': ('{u}_per_sqrt_s', '{p}/sqrt(s)'),
}


@dataclass(frozen=True)
class ReliabilityParams:
    """
    What to compare and how.

    Attributes
    ----------
    before_calibration, after_calibration : tuple of str
        Six-position recording(s) of each side (one with six dwells, or six); empty: not given.
    before_static, after_static : str or None
        Long static recording of each side.
    c : float
        Level factor of the interval (paper 001: 2).
    tolerance : float
        Half-width of the physiological band of the width change (paper 001: 0.5).
    alpha : float
        One-sided level of each test of a verdict (0.05: 95 % one-sided bounds).
    min_edf : float
        Least EDF of a tau that may hold sigma_min on top of the readout's rule (0: none).
    topic : str or None
        ``sensor_msgs/Imu`` topic (the single one when None).
    gravity : Gravity
        Local gravity of the calibrations.
    rate_hz : float or None
        Nominal sample rate (Hz); from the stamps when None.
    settings : DetectorSettings
        Static-dwell detector.
    figures : bool
        Draw the Figure 6 PNGs.

    """

    before_calibration: tuple[str, ...] = ()
    before_static: str | None = None
    after_calibration: tuple[str, ...] = ()
    after_static: str | None = None
    c: float = DEFAULT_C
    tolerance: float = DEFAULT_TOLERANCE
    alpha: float = DEFAULT_ALPHA
    min_edf: float = DEFAULT_MIN_EDF
    topic: str | None = None
    gravity: Gravity = field(default_factory=Gravity)
    rate_hz: float | None = None
    settings: DetectorSettings = field(default_factory=DetectorSettings)
    figures: bool = True

    def __post_init__(self) -> None:
        for name in ('before_calibration', 'after_calibration'):
            object.__setattr__(self, name, tuple(str(p) for p in (getattr(self, name) or ())))
        for name in ('before_static', 'after_static'):
            v = getattr(self, name)
            object.__setattr__(self, name, None if v is None else str(v))
        if not self.given():
            raise ParameterError('nothing to analyse: give at least one of --before-calibration, '
                                 '--before-static, --after-calibration, --after-static')
        if not (math.isfinite(self.c) and self.c > 1):
            raise ParameterError(f'--c must be > 1, got {self.c}')
        if not (math.isfinite(self.min_edf) and self.min_edf >= 0):
            raise ParameterError(f'--min-edf must be >= 0, got {self.min_edf}')
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0):
            raise ParameterError(f'--tolerance must be >= 0, got {self.tolerance}')
        if not (math.isfinite(self.alpha) and 0 < self.alpha < 0.5):
            raise ParameterError(f'--alpha must be in (0, 0.5), got {self.alpha}')
        if self.rate_hz is not None and not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ParameterError(f'--rate-hz must be > 0, got {self.rate_hz!r}')

    def given(self) -> dict[str, Any]:
        """
        Return the parts given, name -> path(s).

        Returns
        -------
        dict

        """
        return {p: getattr(self, p) for p in PARTS if getattr(self, p)}


@dataclass(frozen=True)
class StaticAnalysis:
    """
    One static record analysed.

    Attributes
    ----------
    source : str
        The recording.
    rate_hz : float
        Sample rate (Hz).
    samples : int
        Imu samples.
    duration_s : float
        Last stamp relative to the first (s).
    check : dict
        The static check (``static_fraction``, ``orientation``, ``problem``,
        ``accel_problem``).
    channels : dict
        ``{channel: ChannelResult}``.
    temperature : dict or None
        :func:`..calibration.records.temperature_stats` of the whole record.

    """

    source: str
    rate_hz: float
    samples: int
    duration_s: float
    check: dict[str, Any]
    channels: dict[str, Any]
    temperature: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        """
        Return the record's entry of ``static_records`` in ``reliability.json``.

        Returns
        -------
        dict

        """
        return {'source': self.source, 'rate_hz': self.rate_hz, 'samples': self.samples,
                'duration_s': self.duration_s, **self.check, 'temperature': self.temperature}


def _temperature(path: str, topic: str | None, t0_ns: int | None = None) -> Any:
    try:
        return records.read_temperature(path, topic=topic, t0_ns=t0_ns)
    except (BagError, InputDataError):
        # the temperature is reported, never required: an unreadable topic is "not recorded"
        return None


def static_from_batches(batches: Iterable[tuple[float, np.ndarray, np.ndarray, np.ndarray]], *,
                        source: str, c: float = DEFAULT_C,
                        settings: DetectorSettings | None = None,
                        min_edf: float = DEFAULT_MIN_EDF, alpha: float = DEFAULT_ALPHA,
                        temperature: tuple[np.ndarray, np.ndarray] | None = None
                        ) -> StaticAnalysis:
    """
    Analyse a static record given as ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)`` batches.

    Parameters
    ----------
    batches : iterable
        Batches as :func:`..calibration.records.iter_imu` yields them (the rate of the first
        one is the record's).
    source : str, keyword-only
        Record name for messages.
    c, settings, min_edf, alpha
        As :func:`analyze_static`.
    temperature : tuple, optional, keyword-only
        ``(t_s, temperature_degc)`` of the record (:func:`..calibration.records.read_temperature`).

    Returns
    -------
    StaticAnalysis

    Raises
    ------
    InputDataError
        No channel can give its interval (too short, constant, not static, no samples): one
        line naming the record.

    """
    rec = None
    for rate, t, accel, gyro in batches:
        if rec is None:
            kw: dict[str, Any] = {} if settings is None else {'settings': settings}
            rec = StaticRecord(rate, c=c, source=source, min_edf=min_edf, alpha=alpha, **kw)
        rec.update(t, accel, gyro)
    if rec is None:
        raise InputDataError(f'static record {source!r} holds no Imu samples')
    results, check = rec.finish()
    if not any(r.interval.closed for r in results.values()):
        # not one channel can give its bias-instability interval: a 20 s record, a constant
        # one, a six-position record given as static... six "undetermined" and exit 0 would
        # hide that the record is not what the procedure needs
        reasons = [r.interval.reason for r in results.values()
                   if not math.isfinite(r.interval.sigma_min) and r.interval.reason]
        if reasons:
            why = reasons[0]
        else:
            longest = max(float(np.asarray(r.allan.tau_s)[-1]) for r in results.values()
                          if r.allan is not None)
            why = ('record too short: no channel has a bias-instability interval that closes '
                   f'inside it (longest tau {longest:.3g} s); a static record must be several '
                   'times longer than the interval (hours for a MEMS sensor)')
        raise InputDataError(f'static record {source!r} ({rec.duration_s:.1f} s, '
                             f'{rec.samples} samples) cannot be analysed: {why}')
    return StaticAnalysis(source, rec.rate_hz, rec.samples, rec.duration_s, check, results,
                          records.temperature_stats(temperature))


def analyze_static(path: str, *, topic: str | None = None, rate_hz: float | None = None,
                   c: float = DEFAULT_C, settings: DetectorSettings | None = None,
                   min_edf: float = DEFAULT_MIN_EDF, alpha: float = DEFAULT_ALPHA
                   ) -> StaticAnalysis:
    """
    Stream a static recording through :class:`..calibration.static_record.StaticRecord`.

    Parameters
    ----------
    path : str or os.PathLike
        Recording.
    topic : str, optional, keyword-only
        Imu topic.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz).
    c : float, keyword-only
        Level factor.
    settings : DetectorSettings, optional, keyword-only
        Static-window thresholds.
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min.
    alpha : float, keyword-only
        One-sided level of the fall-back test (ambiguous crossings).

    Returns
    -------
    StaticAnalysis

    Raises
    ------
    InputDataError
        As :func:`static_from_batches`.

    """
    batches = records.iter_imu(path, topic=topic, rate_hz=rate_hz)
    st = static_from_batches(batches, source=str(path), c=c, settings=settings,
                             min_edf=min_edf, alpha=alpha)
    return replace(st, temperature=records.temperature_stats(_temperature(path, topic)))


def verdicts_of(before: StaticAnalysis | None, after: StaticAnalysis | None, *,
                tolerance: float = DEFAULT_TOLERANCE,
                alpha: float = DEFAULT_ALPHA) -> tuple[dict[str, Any], dict[str, Any]]:
    """
    Return the per-channel and per-sensor verdicts of two static records.

    Parameters
    ----------
    before, after : StaticAnalysis or None
        The records (None: not given).
    tolerance, alpha : float, keyword-only
        Band half-width and one-sided level (:func:`..calibration.interval.compare`).

    Returns
    -------
    (dict, dict)
        ``{channel: Verdict}`` and ``{'accel': SensorVerdict, 'gyro': SensorVerdict}``.

    """
    verdicts: dict[str, Any] = {}
    for ch in CHANNELS:
        ivs = [st.channels[ch].interval if st else None for st in (before, after)]
        verdicts[ch] = compare(*ivs, tolerance=tolerance, alpha=alpha)
    sensors = {s: overall({ch: verdicts[ch] for ch in CHANNELS if ch.startswith(s)},
                          tolerance=tolerance, alpha=alpha) for s in SENSORS}
    return verdicts, sensors


def _dwell_temperatures(cal: CalibrationResult, topic: str | None) -> list[dict[str, Any]]:
    out = []
    cache: dict[str, Any] = {}
    for d in cal.dwells:
        if d.source not in cache:
            cache[d.source] = _temperature(d.source, topic)
        out.append({'orientation': d.orientation, 'source': d.source,
                    't_start_s': float(d.t_start_s), 'duration_s': float(d.duration_s),
                    'temperature': records.temperature_stats(cache[d.source], d.t_start_s,
                                                             d.t_end_s)})
    return out


@dataclass(frozen=True)
class ReliabilityResult:
    """
    Everything ``gyro_noise_reliability`` reports (``reliability.json`` is :meth:`as_dict`).

    Attributes
    ----------
    params : ReliabilityParams
        What was asked.
    statics : dict
        ``{'before': StaticAnalysis or None, 'after': ...}``.
    calibrations : dict
        ``{'before': CalibrationResult or None, 'after': ...}``.
    verdicts : dict
        ``{channel: Verdict}`` of the width change.
    sensors : dict
        ``{'accel': SensorVerdict, 'gyro': SensorVerdict}``.
    dwell_temperatures : dict
        ``{'before': list or None, 'after': ...}``: each dwell with its temperature.
    errors : dict
        Parts that could not be analysed: part name -> why.

    """

    params: ReliabilityParams
    statics: dict[str, Any]
    calibrations: dict[str, Any]
    verdicts: dict[str, Any]
    sensors: dict[str, Any]
    dwell_temperatures: dict[str, list[dict[str, Any]] | None]
    errors: dict[str, str]
    version: str = __version__

    def warnings(self) -> list[str]:
        """
        Return the lines a tool prints on stderr (failed parts).

        Returns
        -------
        list of str

        """
        return [f'{k.replace("_", " ")}: {v}' for k, v in self.errors.items()]

    def as_dict(self) -> dict[str, Any]:
        """
        Return the ``reliability.json`` document (SI, units in the keys).

        Returns
        -------
        dict

        """
        p = self.params
        cals: dict[str, Any] = {
            s: (self.calibrations[s].as_dict() if self.calibrations[s] else None) for s in SIDES}
        intervals = {ch: _interval_entry(ch, self.statics, self.verdicts[ch]) for ch in CHANNELS}
        return {
            'c': p.c, 'tolerance': p.tolerance, 'alpha': p.alpha,
            'confidence_one_sided': 1.0 - p.alpha, 'min_edf': p.min_edf,
            'sources': {k: (list(v) if isinstance(v, tuple) else v)
                        for k, v in ((q, getattr(p, q) or None) for q in PARTS)},
            'overall': {s: _sensor_entry(self.sensors[s], self.statics) for s in SENSORS},
            'bias_instability_interval': intervals,
            'summary': _summary(intervals),
            'noise_terms': {ch: _terms_entry(ch, self.statics) for ch in CHANNELS},
            'table6': _table6(cals['before'], cals['after']),
            'gyro_calibration': _gyro_entry(cals['before'], cals['after']),
            'accel_cross_axis': _cross_axis(cals['before'], cals['after'], 'accel'),
            'uniformity': _uniformity(cals['before'], cals['after']),
            'calibration': {s: _calibration_entry(cals[s]) for s in SIDES},
            'gravity_check': {s: (cals[s]['gravity_check'] if cals[s] else None) for s in SIDES},
            'static_records': {s: (self.statics[s].as_dict() if self.statics[s] else None)
                               for s in SIDES},
            'dwell_temperatures': self.dwell_temperatures,
            'errors': dict(self.errors),
            'version': self.version,
        }


def run_reliability(params: ReliabilityParams) -> ReliabilityResult:
    """
    Run the whole comparison (module docstring).

    Parameters
    ----------
    params : ReliabilityParams
        What to compare.

    Returns
    -------
    ReliabilityResult

    Raises
    ------
    InputDataError
        A static record that cannot be analysed at all, or every given part failed.
    BagError
        A recording cannot be read.

    """
    given = params.given()
    errors: dict[str, str] = {}
    cals: dict[str, Any] = {}
    statics: dict[str, Any] = {}
    temps: dict[str, list[dict[str, Any]] | None] = {}
    for side in SIDES:
        bags = getattr(params, f'{side}_calibration')
        cals[side] = temps[side] = None
        if bags:
            try:
                cals[side] = run_calibration(CalibrateParams(
                    paths=bags, gravity=params.gravity, topic=params.topic,
                    rate_hz=params.rate_hz, settings=params.settings))
            except InputDataError as err:
                errors[f'{side}_calibration'] = str(err)
            else:
                temps[side] = _dwell_temperatures(cals[side], params.topic)
        bag = getattr(params, f'{side}_static')
        # a static record that cannot be analysed at all is refused (one line, exit 4)
        statics[side] = analyze_static(
            bag, topic=params.topic, rate_hz=params.rate_hz, c=params.c,
            settings=params.settings, min_edf=params.min_edf,
            alpha=params.alpha) if bag else None
    if len(errors) == len(given):
        raise InputDataError('nothing could be analysed: ' + '; '.join(
            f'{k}: {v}' for k, v in errors.items()))
    verdicts, sensors = verdicts_of(statics['before'], statics['after'],
                                    tolerance=params.tolerance, alpha=params.alpha)
    return ReliabilityResult(params, statics, cals, verdicts, sensors, temps, errors)


# ---- the JSON document ---------------------------------------------------------------------

def _record_lengths(statics: dict[str, Any]) -> list[float | None]:
    return [statics[s].duration_s if statics[s] else None for s in SIDES]


def _interval_entry(ch: str, statics: dict[str, Any], v: Any) -> dict[str, Any]:
    u = unit_of(ch)
    out: dict[str, Any] = {}
    for side in SIDES:
        st = statics[side]
        iv = st.channels[ch].interval if st else None
        w = iv.width_s if iv else None
        sd = _num(iv.width_sd_log) if iv else None
        out[f'{side}_s'] = [iv.lo_s, iv.hi_s] if iv else None
        out[f'width_{side}_s'] = w
        out[f'width_sd_log_{side}'] = sd
        out[f'width_sigma_{side}_s'] = w * sd if (w is not None and sd is not None) else None
        out[f'tau_min_{side}_s'] = _num(iv.tau_min_s) if iv else None
        out[f'sigma_min_{side}_{u}'] = _num(iv.sigma_min) if iv else None
        out[f'reason_{side}'] = iv.reason if iv else 'not given'
        out[f'ambiguous_{side}'] = ({
            'fallback_s': list(iv.fallback_s), 'significant': iv.fallback_significant,
            'hi_last_s': iv.hi_last_s, 'note': iv.fallback_note()}
            if iv is not None and iv.ambiguous else None)
    out.update({
        'change': v.change, 'change_sd': _num(v.change_sd), 'log_ratio': _num(v.log_ratio),
        'log_ratio_sd': _num(v.log_ratio_sd),
        'ci': [_num(x) for x in v.ci] if v.ci else None,
        'verdict': v.verdict, 'reason': v.reason,
        'decide_record_s': list(v.decide_record_s) if v.decide_record_s else None,
        'notes': list(v.notes)})
    return out


def _sensor_entry(sv: Any, statics: dict[str, Any]) -> dict[str, Any]:
    lengths = _record_lengths(statics)
    decide = ([sv.decide_factor * t if t else None for t in lengths]
              if sv.decide_factor is not None else None)
    return {'verdict': sv.verdict, 'basis': sv.basis, 'mean_change': _num(sv.mean_change),
            'mean_change_sd': _num(sv.mean_change_sd),
            'ci': [_num(x) for x in sv.ci] if sv.ci else None,
            'axes_beyond': list(sv.axes_beyond), 'decide_record_s': decide}


def _summary(intervals: dict[str, dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for sensor in SENSORS:
        rows = [intervals[f'{sensor}_{a}'] for a in 'xyz']
        wb = [r['width_before_s'] for r in rows if r['width_before_s'] is not None]
        wa = [r['width_after_s'] for r in rows if r['width_after_s'] is not None]
        mb = float(np.mean(wb)) if len(wb) == 3 else None
        ma = float(np.mean(wa)) if len(wa) == 3 else None
        out[sensor] = {
            'mean_width_before_s': mb, 'mean_width_after_s': ma,
            'mean_change': (ma / mb - 1.0) if (mb and ma) else None,
            'verdicts': [r['verdict'] for r in rows]}
    return out


def _term_keys(ch: str) -> dict[str, str]:
    u = unit_of(ch)
    return {t: TERM_UNITS[t][0].format(u=f'{t}_{u}') for t in TERMS}


def _terms_entry(ch: str, statics: dict[str, Any]) -> dict[str, Any]:
    keys = _term_keys(ch)
    out: dict[str, Any] = {}
    for side in SIDES:
        st = statics[side]
        res = st.channels[ch] if st else None
        if res is None or res.terms is None:
            out[side] = None
            continue
        out[side] = {}
        for t, key in keys.items():
            term = res.terms[t]
            lo, hi = term.bracket
            out[side][key] = _num(term.value)
            out[side][key + '_sd_log'] = _num(term.sd_log)
            out[side][key + '_ci68'] = [_num(lo), _num(hi)]
    if out['before'] and out['after']:
        ratio: dict[str, Any] = {}
        for t, key in keys.items():
            b = statics['before'].channels[ch].terms[t]
            a = statics['after'].channels[ch].terms[t]
            if b.value > 0 and a.value > 0:
                r = a.value / b.value
                sd = math.hypot(b.sd_log, a.sd_log)
                ratio[key] = {'ratio': r, 'ratio_sd': _num(r * sd), 'log_ratio_sd': _num(sd)}
            else:
                ratio[key] = None
        out['ratio_after_before'] = ratio
    return out


def _table6(cb: dict[str, Any] | None,
            ca: dict[str, Any] | None) -> list[dict[str, Any]] | None:
    if not (cb or ca):
        return None
    rows_b = table6_rows(cb) if cb else None
    rows_a = table6_rows(ca) if ca else None
    out = []
    for k in range(6):
        # cb or ca is given, so one of the two is
        name = cast(list[tuple[str, float, float]], rows_b or rows_a)[k][0]
        unit = 'mg' if name.startswith('b') else '%'
        row: dict[str, Any] = {'parameter': name, 'unit': unit}
        for side, rows in (('before', rows_b), ('after', rows_a)):
            row[side] = rows[k][1] if rows else None
            row[f'{side}_sigma'] = rows[k][2] if rows else None
        if rows_b and rows_a:
            row['change'] = rows_a[k][1] - rows_b[k][1]
            row['change_sigma'] = math.hypot(rows_a[k][2], rows_b[k][2])
        else:
            row['change'] = row['change_sigma'] = None
        out.append(row)
    return out


def _pair(cb: Any, ca: Any, get: Callable[[Any], Any]) -> tuple[Any, Any]:
    vb = get(cb) if cb else None
    va = get(ca) if ca else None
    return vb, va


def _vec_change(vb: Any, sb: Any, va: Any, sa: Any) -> tuple[Any, Any]:
    if vb is None or va is None:
        return None, None
    ch = [(a - b) if (a is not None and b is not None) else None for a, b in zip(va, vb)]
    sd = [math.hypot(x, y) if (x is not None and y is not None) else None
          for x, y in zip(sa or [None] * len(va), sb or [None] * len(vb))]
    return ch, sd


def _gyro_entry(cb: dict[str, Any] | None,
                ca: dict[str, Any] | None) -> dict[str, Any] | None:
    if not (cb or ca):
        return None
    out: dict[str, Any] = {}
    for side, doc in (('before', cb), ('after', ca)):
        if doc is None:
            out[side] = None
            continue
        g = doc['gyro']
        out[side] = {'bias_rad_s': g['bias_rad_s'], 'bias_sigma_rad_s': g['bias_sigma_rad_s'],
                     'scale_factor': g['scale_factor'],
                     'scale_factor_sigma': g.get('scale_factor_sigma'),
                     'misalignment': g['misalignment'],
                     'misalignment_sigma': g.get('misalignment_sigma'),
                     'estimated': g.get('estimated'), 'note': g['note']}
    if cb and ca:
        b, a = out['before'], out['after']
        ch, sd = _vec_change(b['bias_rad_s'], b['bias_sigma_rad_s'], a['bias_rad_s'],
                             a['bias_sigma_rad_s'])
        out['bias_change_rad_s'], out['bias_change_sigma_rad_s'] = ch, sd
    return out


def _cross_axis(cb: dict[str, Any] | None, ca: dict[str, Any] | None,
                sensor: str) -> dict[str, Any] | None:
    if not (cb or ca):
        return None
    out: dict[str, Any] = {}
    for side, doc in (('before', cb), ('after', ca)):
        out[side] = None if doc is None else {
            'misalignment': doc[sensor]['misalignment'],
            'misalignment_sigma': doc[sensor]['misalignment_sigma']}
    return out


def _calibration_entry(doc: dict[str, Any] | None) -> dict[str, Any] | None:
    if doc is None:
        return None
    keep = ('gravity_m_s2', 'accel', 'gyro', 'uniformity', 'gravity_check', 'dwells', 'sources')
    return {k: doc[k] for k in keep}


def _uniformity(cb: dict[str, Any] | None,
                ca: dict[str, Any] | None) -> dict[str, Any]:
    out: dict[str, Any] = {'before': cb['uniformity'] if cb else None,
                           'after': ca['uniformity'] if ca else None}
    if cb and ca:
        out['ratio_after_before'] = {
            k: (ca['uniformity'][k] / cb['uniformity'][k] if cb['uniformity'][k] > 0 else None)
            for k in cb['uniformity']}
    return out


# ---- plain language, Markdown, CSV, figures ------------------------------------------------

NAMES = {'accel': 'accelerometer', 'gyro': 'gyroscope'}


def _pct(v: float | None, spec: str = '+.0f') -> str:
    return 'n/a' if v is None else f'{format(100 * v, spec)} %'


def _hours(seconds: float | None) -> str:
    return 'n/a' if seconds is None else f'{seconds / 3600:.3g} h'


def _longest(values: Iterable[float | None] | None) -> float | None:
    vals = [v for v in (values or []) if v is not None]
    return max(vals) if vals else None


def _sensor_sentence(name: str, e: dict[str, Any], doc: dict[str, Any]) -> str:
    tol = f'+/-{100 * doc["tolerance"]:.0f} %'
    conf = f'{100 * doc["confidence_one_sided"]:.0f} %'
    m, sd = e['mean_change'], e['mean_change_sd']
    if m is not None:
        how = 'widened' if m >= 0 else 'narrowed'
        change = (f'its bias-instability interval (the span of averaging times where the noise '
                  f'floor is flat) {how} by {abs(100 * m):.0f} % +/- {100 * sd:.0f} % on average '
                  'over the three axes')
    else:
        change = 'its bias-instability interval could not be compared on all three axes'
    if e['verdict'] == 'beyond':
        axes = (f' ({", ".join(e["axes_beyond"])} beyond on their own)' if e['axes_beyond']
                else '')
        return (f'The {name} changed beyond what paper 001 calls physiological: {change}, '
                f'more than {tol} at {conf} confidence{axes}.')
    if e['verdict'] == 'physiological':
        return (f'The {name} did not change beyond the physiological band: {change}, within '
                f'{tol} at {conf} confidence.')
    decide = _longest(e['decide_record_s'])
    longer = (f'; static records of about {_hours(decide)} each would decide it'
              if decide is not None else '')
    record_s = _longest([(r or {}).get('duration_s') for r in doc['static_records'].values()])
    now = (f' (these are {_hours(record_s)})' if record_s is not None and decide is not None
           else '')
    ci = e['ci']
    if m is not None and ci:
        return (f'These records cannot tell whether the {name} changed beyond the '
                f'physiological band: {change}, and its {100 * (1 - 2 * doc["alpha"]):.0f} % '
                f'interval ({_pct(ci[0])} .. {_pct(ci[1])}) straddles {tol}{longer}{now}.')
    return f'These records cannot tell whether the {name} changed: {e["basis"]}.'


def _floor_sentences(doc: dict[str, Any]) -> list[str]:
    out = []
    for s in SENSORS:
        logs: list[float] = []
        var = 0.0
        for a in 'xyz':
            ch = f'{s}_{a}'
            r = (doc['noise_terms'][ch].get('ratio_after_before') or {}).get(
                _term_keys(ch)['bias_stability'])
            if not r or r['log_ratio_sd'] is None:
                break
            logs.append(math.log(r['ratio']))
            var += r['log_ratio_sd'] ** 2
        else:
            m = math.exp(sum(logs) / 3)
            sd = m * math.sqrt(var) / 3
            out.append(f"The {NAMES[s]}'s noise floor (bias stability, the minimum of the Allan "
                       f'deviation) changed by x{m:.2f} +/- {sd:.2f} (mean of the three axes).')
    return out


def in_short(doc: dict[str, Any]) -> list[str]:
    """
    Return the plain-language summary of a reliability document, one sentence per item.

    Parameters
    ----------
    doc : dict
        The ``reliability.json`` document (:meth:`ReliabilityResult.as_dict`).

    Returns
    -------
    list of str

    """
    out = []
    statics = doc['static_records']
    if statics['before'] and statics['after']:
        for s in SENSORS:
            out.append(_sensor_sentence(NAMES[s], doc['overall'][s], doc))
    else:
        out.append('No verdict on the noise: it needs a static record before and one after '
                   f'(given: {", ".join(s for s in SIDES if statics[s]) or "none"}).')
    if statics['before'] and statics['after']:
        out += _floor_sentences(doc)
    u = doc['uniformity']
    if u['before'] and u['after']:
        b = u['before']['accel_bias_std_m_s2'] / MG_TO_M_S2
        a = u['after']['accel_bias_std_m_s2'] / MG_TO_M_S2
        out.append(f'Calibration: the spread of the accelerometer biases across the axes went '
                   f'from {b:.2f} mg to {a:.2f} mg (x{a / b:.1f}); paper 001 reads a loss of '
                   'uniformity as damage (0.25 -> 2.96 mg in its IMU).' if b > 0 else
                   f'Calibration: accelerometer bias spread {b:.2f} -> {a:.2f} mg.')
        rows = doc['table6'] or []
        big = [r for r in rows if r['change'] is not None and r['change_sigma']
               and abs(r['change']) > 3 * r['change_sigma']]
        if big:
            out.append('Changed by more than 3 standard uncertainties: ' + ', '.join(
                f'{r["parameter"]} {r["change"]:+.3f} +/- {r["change_sigma"]:.3f} {r["unit"]}'
                for r in big) + '.')
    for side in SIDES:
        gc = doc['gravity_check'][side]
        if gc is not None and not gc['consistent']:
            out.append(f'The {side} calibration fails its gravity check (leave-one-out): a '
                       'dwell disagrees with the others; see the calibration report.')
    amb = [(ch, side, e[f'ambiguous_{side}']) for ch, e in
           doc['bias_instability_interval'].items() for side in SIDES
           if e.get(f'ambiguous_{side}')]
    for ch, side, a in amb:
        out.append(f'{ch} {side}: {a["note"]}.')
    temps = []
    for side in SIDES:
        r = statics[side]
        if r and r.get('temperature'):
            temps.append(f'{side} static record {r["temperature"]["mean_degc"]:.1f} degC')
        dw = [d['temperature'] for d in (doc['dwell_temperatures'].get(side) or [])
              if d['temperature']]
        if dw:
            temps.append(f'{side} dwells {min(t["mean_degc"] for t in dw):.1f}-'
                         f'{max(t["mean_degc"] for t in dw):.1f} degC')
    if temps:
        out.append('Temperatures: ' + '; '.join(temps) + '.')
    for k, v in doc['errors'].items():
        out.append(f'Not analysed: {k.replace("_", " ")}: {v}')
    return out


def _fmt(v: float | None, spec: str) -> str:
    return 'n/a' if v is None else format(v, spec)


def _pm(v: float | None, sd: float | None, spec: str, scale: float = 1.0) -> str:
    if v is None:
        return 'n/a'
    if sd is None:
        return format(v * scale, spec)
    return f'{format(v * scale, spec)} +/- {format(sd * scale, spec.lstrip("+"))}'


def _interval_rows(doc: dict[str, Any]) -> list[str]:
    out = ['| channel | interval before (s) | interval after (s) | width before (s) | '
           'width after (s) | change | ' f'{100 * (1 - 2 * doc["alpha"]):.0f} % interval | '
           'verdict |', '|---|---|---|---|---|---|---|---|']

    def rng(pair: Sequence[float | None] | None) -> str:
        if pair is None:
            return 'not given'
        return ' - '.join('open' if v is None else f'{v:.3g}' for v in pair)

    for ch, e in doc['bias_instability_interval'].items():
        flags = ''.join(' (ambiguous)' for side in SIDES if e[f'ambiguous_{side}'])
        ci = e['ci']
        out.append(
            f'| {ch}{flags} | {rng(e["before_s"])} | {rng(e["after_s"])} | '
            f'{_pm(e["width_before_s"], e["width_sigma_before_s"], ".4g")} | '
            f'{_pm(e["width_after_s"], e["width_sigma_after_s"], ".4g")} | '
            f'{_pm(e["change"], e["change_sd"], "+.0f", 100)} % | '
            f'{"n/a" if not ci else f"{_pct(ci[0])} .. {_pct(ci[1])}"} | {e["verdict"]} |')
    return out


def _term_rows(doc: dict[str, Any]) -> list[str]:
    out = ['| channel | term | unit | before (68 % interval) | after (68 % interval) | '
           'after / before |', '|---|---|---|---|---|---|']
    labels = {'white_noise': 'white noise (N)', 'bias_stability': 'bias stability',
              'random_walk': 'random walk (K)'}
    for ch, e in doc['noise_terms'].items():
        printed, scale = UNITS[unit_of(ch)]
        for t, key in _term_keys(ch).items():
            unit = TERM_UNITS[t][1].format(p=printed)

            def cell(side: str) -> str:
                d = e[side]
                if d is None or d[key] is None:
                    return 'n/a'
                lo, hi = d[key + '_ci68']
                hi_txt = 'unresolved' if hi is None else f'{hi * scale:.3g}'
                return f'{d[key] * scale:.4g} ({_fmt(lo and lo * scale, ".3g")} .. {hi_txt})'

            r = (e.get('ratio_after_before') or {}).get(key)
            ratio = 'n/a' if not r else _pm(r['ratio'], r['ratio_sd'], '.3f')
            out.append(f'| {ch} | {labels[t]} | {unit} | {cell("before")} | {cell("after")} | '
                       f'{ratio} |')
    return out


def _calibration_rows(doc: dict[str, Any]) -> list[str]:
    out: list[str] = []
    rows = doc['table6']
    if rows:
        out += ['', '## Six-position calibration (paper 001 Table 6)', '',
                'Values +/- one standard uncertainty; change = after - before, its uncertainty '
                'the root sum of squares.', '',
                '| parameter | before | after | change |', '|---|---|---|---|']
        for r in rows:
            u = r['unit']
            out.append(f'| {r["parameter"]} ({u}) | {_pm(r["before"], r["before_sigma"], ".3f")}'
                       f' | {_pm(r["after"], r["after_sigma"], ".3f")} | '
                       f'{_pm(r["change"], r["change_sigma"], "+.3f")} |')
    g = doc['gyro_calibration']
    if g:
        out += ['', '## Gyro bias and scale factors (from the calibrations)', '',
                '| axis | bias before (deg/s) | bias after (deg/s) | change (deg/s) | '
                'scale factor before (%) | scale factor after (%) |', '|---|---|---|---|---|---|']
        for i, ax in enumerate('xyz'):
            cells: list[str] = []
            for side in SIDES:
                d = g[side]
                cells.append('not given' if d is None else
                             _pm(d['bias_rad_s'][i], d['bias_sigma_rad_s'][i], '.5f', RAD_TO_DEG))
            ch = g.get('bias_change_rad_s')
            cells.append('n/a' if not ch else _pm(ch[i], g['bias_change_sigma_rad_s'][i],
                                                  '+.5f', RAD_TO_DEG))
            for side in SIDES:
                d = g[side]
                est = d is not None and d['estimated'] is not None and d['estimated'][i][i]
                cells.append(_pm(d['scale_factor'][i], (d['scale_factor_sigma'] or [None] * 3)[i],
                                 '.4f', 100) if est else 'not estimated')
            out.append(f'| {ax} | ' + ' | '.join(cells) + ' |')
    for sensor, title in (('accel', 'Accelerometer'), ('gyro', 'Gyro')):
        src = doc['accel_cross_axis'] if sensor == 'accel' else g
        if not src:
            continue
        out += ['', f'{title} cross-axis terms (%; [j, i]: true axis i into measured axis j; '
                '+/- one standard uncertainty):', '',
                '| term | before | after | change |', '|---|---|---|---|']
        for j in range(3):
            for i in range(3):
                if i == j:
                    continue
                vals: list[tuple[Any, Any] | None] = []
                for side in SIDES:
                    d = src[side]
                    if d is None or (sensor == 'gyro' and not (d['estimated'] or [[0] * 3] * 3)
                                     [j][i]):
                        vals.append(None)
                        continue
                    sig = d['misalignment_sigma'][j][i] if d['misalignment_sigma'] else None
                    vals.append((d['misalignment'][j][i], sig))
                cells = [('not estimated' if v is None else _pm(v[0], v[1], '.4f', 100))
                         for v in vals]
                if vals[0] is not None and vals[1] is not None:
                    sd = (math.hypot(vals[0][1], vals[1][1])
                          if vals[0][1] is not None and vals[1][1] is not None else None)
                    cells.append(_pm(vals[1][0] - vals[0][0], sd, '+.4f', 100))
                else:
                    cells.append('n/a')
                out.append(f'| {"xyz"[j]}{"xyz"[i]} | ' + ' | '.join(cells) + ' |')
    return out


def _indicator_rows(doc: dict[str, Any]) -> list[str]:
    ub, ua = doc['uniformity']['before'], doc['uniformity']['after']
    if not (ub or ua):
        return []

    def u(d: dict[str, Any] | None, key: str, scale: float, spec: str) -> str:
        return 'not given' if d is None else format(d[key] * scale, spec)

    gb, ga = doc['gravity_check']['before'], doc['gravity_check']['after']

    def verdict(gc: dict[str, Any] | None) -> str:
        return 'not given' if gc is None else ('consistent' if gc['consistent']
                                               else 'inconsistent')

    return ['', '## Indicators (paper 001 section 6)', '',
            '| indicator | before | after |', '|---|---|---|',
            f'| std of the accelerometer biases across axes (mg) | '
            f'{u(ub, "accel_bias_std_m_s2", 1 / MG_TO_M_S2, ".3f")} | '
            f'{u(ua, "accel_bias_std_m_s2", 1 / MG_TO_M_S2, ".3f")} |',
            f'| std of the accelerometer scale factors (%) | '
            f'{u(ub, "accel_scale_factor_std", 100, ".3f")} | '
            f'{u(ua, "accel_scale_factor_std", 100, ".3f")} |',
            f'| std of the gyro biases across axes (deg/s) | '
            f'{u(ub, "gyro_bias_std_rad_s", RAD_TO_DEG, ".5f")} | '
            f'{u(ua, "gyro_bias_std_rad_s", RAD_TO_DEG, ".5f")} |',
            f'| gravity check, mean abs(a) of the raw dwells (m/s^2) | '
            f'{u(gb, "mean_norm_raw_m_s2", 1, ".4f")} | {u(ga, "mean_norm_raw_m_s2", 1, ".4f")} |',
            f'| gravity check, mean abs(a) of each dwell calibrated by the others (m/s^2) | '
            f'{u(gb, "loo_mean_norm_m_s2", 1, ".5f")} | {u(ga, "loo_mean_norm_m_s2", 1, ".5f")} |',
            f'| gravity check verdict | {verdict(gb)} | {verdict(ga)} |']


def _temp(t: dict[str, Any] | None) -> str:
    if not t:
        return 'not recorded'
    return f'{t["mean_degc"]:.2f} ({t["min_degc"]:.2f} .. {t["max_degc"]:.2f})'


def _record_rows(doc: dict[str, Any]) -> list[str]:
    out = ['', '## Records and temperatures', '',
           '| record | side | length (h) | rate (Hz) | samples | static fraction | orientation '
           '| temperature (degC): mean (min .. max) |', '|---|---|---|---|---|---|---|---|']
    for side in SIDES:
        r = doc['static_records'][side]
        if r is None:
            continue
        out.append(f'| {r["source"]} | {side} static | {r["duration_s"] / 3600:.3f} | '
                   f'{r["rate_hz"]:.4g} | {r["samples"]} | '
                   f'{_fmt(r["static_fraction"], ".3f")} | {r["orientation"]} | '
                   f'{_temp(r["temperature"])} |')
    dw = [(side, d) for side in SIDES for d in (doc['dwell_temperatures'].get(side) or [])]
    if dw:
        out += ['', '| calibration | dwell | start (s) | duration (s) | temperature (degC): mean '
                '(min .. max) | recording |', '|---|---|---|---|---|---|']
        for side, d in dw:
            out.append(f'| {side} | {d["orientation"]} | {d["t_start_s"]:.1f} | '
                       f'{d["duration_s"]:.1f} | {_temp(d["temperature"])} | {d["source"]} |')
    return out


def markdown(doc: dict[str, Any]) -> str:
    """
    Return ``reliability.md`` of a reliability document: the verdict first, then the evidence.

    Parameters
    ----------
    doc : dict
        The ``reliability.json`` document (:meth:`ReliabilityResult.as_dict`).

    Returns
    -------
    str

    """
    tol = f'+/-{100 * doc["tolerance"]:.0f} %'
    one = f'{100 * doc["confidence_one_sided"]:.0f} %'
    two = f'{100 * (1 - 2 * doc["alpha"]):.0f} %'
    out = ['# Reliability test (paper 001): before / after', '', '## In short', '']
    out += [f'- {line}' for line in in_short(doc)]
    out += ['', '## Overall verdict', '',
            f'Per sensor: **beyond** when an axis is beyond at the Bonferroni level (one-sided '
            f'{100 * (1 - doc["alpha"] / 3):.1f} %) or the three-axis mean change of the '
            f'interval width is beyond {tol} at one-sided {one}; **physiological** when the mean '
            f'is inside {tol} at one-sided {one} on both sides; otherwise **undetermined**.', '',
            f'| sensor | verdict | mean change of the width (three axes) | {two} interval | '
            'records that would decide | basis |', '|---|---|---|---|---|---|']
    for s in SENSORS:
        e = doc['overall'][s]
        ci = e['ci']
        out.append(f'| {NAMES[s]} | **{e["verdict"]}** | '
                   f'{_pm(e["mean_change"], e["mean_change_sd"], "+.0f", 100)} % | '
                   f'{"n/a" if not ci else f"{_pct(ci[0])} .. {_pct(ci[1])}"} | '
                   f'{_hours(_longest(e["decide_record_s"]))} | {e["basis"]} |')
    out += ['', '## Bias-instability interval (paper 001 section 6)', '',
            f'Tau range where ADEV < {doc["c"]:g} sigma_min (sigma_min: the bias stability of '
            'the Allan readout, over taus up to a tenth of the record). Width +/- one standard '
            'deviation propagated from the equivalent degrees of freedom of the Allan variance '
            f'at the crossings; **beyond** when the change is outside {tol} at one-sided {one}, '
            f'**physiological** when the {two} interval lies inside {tol}, else '
            '**undetermined**.', '']
    out += _interval_rows(doc)
    reasons = [(ch, e['reason']) for ch, e in doc['bias_instability_interval'].items()
               if e['reason']]
    if reasons:
        out += ['', 'Undetermined because:', '']
        out += [f'- {ch}: {r}' for ch, r in reasons]
    amb = [(ch, side, e[f'ambiguous_{side}']['note'])
           for ch, e in doc['bias_instability_interval'].items() for side in SIDES
           if e[f'ambiguous_{side}']]
    if amb:
        out += ['', 'Ambiguous upper crossings (not silently closed):', '']
        out += [f'- {ch} {side}: {n}' for ch, side, n in amb]
    s = doc['summary']
    out += ['', 'Mean width over the three axes (the paper: 420 s -> 945 s, +125 %):', '']
    for sensor, e in s.items():
        out.append(f'- {NAMES[sensor]}: {_fmt(e["mean_width_before_s"], ".4g")} s -> '
                   f'{_fmt(e["mean_width_after_s"], ".4g")} s, change '
                   f'{_pct(e["mean_change"])}')
    out += ['', '## Noise terms (the one Allan readout)', '',
            'The numbers gyro_noise_analyze prints for the same curves; the 68 % intervals '
            'from the equivalent degrees of freedom (docs/reliability.md).', '']
    out += _term_rows(doc)
    out += _calibration_rows(doc)
    out += _indicator_rows(doc)
    out += _record_rows(doc)
    out += ['', '## Files', '',
            '- `reliability.json`: every number above (SI, units in the keys)',
            '- `fig6_accel.png`, `fig6_gyro.png`: paper 001 Figure 6, Allan deviation before '
            'and after with the level and the interval',
            '- `adev_before.csv`, `adev_after.csv`: the curves behind Figure 6 (tau_s, ADEV, '
            'its 68 % interval and EDF per channel)',
            '- `before/`, `after/`: the calibration files of each side']
    if doc['errors']:
        out += ['', '## Parts that could not be analysed', '']
        out += [f'- {k}: {v}' for k, v in doc['errors'].items()]
    return '\n'.join(out) + '\n'


def adev_csv(static: StaticAnalysis) -> str:
    """
    Return the Allan deviation curves of a static record as CSV text (Figure 6 data).

    Parameters
    ----------
    static : StaticAnalysis
        The record.

    Returns
    -------
    str
        Columns ``tau_s`` and, per channel, ``<ch>_adev_<unit>``, ``<ch>_ci_low_<unit>``,
        ``<ch>_ci_high_<unit>`` (68.3 % interval) and ``<ch>_edf``; empty cells where a channel
        has no value at that tau.

    """
    taus = sorted({float(t) for r in static.channels.values() if r.allan is not None
                   for t in np.asarray(r.allan.tau_s)})
    index = {t: k for k, t in enumerate(taus)}
    cols = ['tau_s']
    data = [np.array(taus)]
    for ch in CHANNELS:
        u = unit_of(ch)
        names = [f'{ch}_adev_{u}', f'{ch}_ci_low_{u}', f'{ch}_ci_high_{u}', f'{ch}_edf']
        block = np.full((len(taus), 4), np.nan)
        r = static.channels[ch]
        if r.allan is not None:
            rows = [index[float(t)] for t in np.asarray(r.allan.tau_s)]
            block[rows] = np.column_stack([r.allan.adev, r.allan.ci_low, r.allan.ci_high,
                                           r.allan.edf])
        cols += names
        data += list(block.T)
    buf = io.StringIO()
    buf.write(','.join(cols) + '\n')
    for row in zip(*data):
        buf.write(','.join('' if not math.isfinite(v) else repr(float(v)) for v in row) + '\n')
    return buf.getvalue()


def plot_fig6(path: Union[str, 'os.PathLike[str]'], sensor: str,
              before: StaticAnalysis | None, after: StaticAnalysis | None,
              c: float) -> None:
    """
    Draw paper 001 Figure 6 for one sensor: ADEV per axis before and after, level and interval.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    sensor : {'accel', 'gyro'}
        Which sensor.
    before, after : StaticAnalysis or None
        The static records.
    c : float
        Level factor.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    unit = '(m/s^2)' if sensor == 'accel' else '(rad/s)'
    fig, panels = plt.subplots(1, 2, figsize=(11, 4.6), sharey=True)
    colors = {'x': 'tab:blue', 'y': 'tab:orange', 'z': 'tab:green'}
    for panel, (side, st) in zip(panels, (('before', before), ('after', after))):
        panel.set_title(f'({"a" if side == "before" else "b"}) {side}')
        panel.set_xlabel('cluster time tau (s)')
        panel.grid(True, which='both', alpha=0.3)
        if st is None:
            panel.text(0.5, 0.5, 'not given', transform=panel.transAxes, ha='center')
            continue
        for a in 'xyz':
            r = st.channels[f'{sensor}_{a}']
            if r.allan is None:
                continue
            col = colors[a]
            panel.loglog(r.allan.tau_s, r.allan.adev, color=col, lw=1.3, label=f'{a} axis')
            iv = r.interval
            if math.isfinite(iv.level):
                panel.axhline(iv.level, color=col, ls=':', lw=0.9)
                lo = iv.lo_s if iv.lo_s is not None else r.allan.tau_s[0]
                hi = iv.hi_s if iv.hi_s is not None else r.allan.tau_s[-1]
                panel.plot([lo, hi], [iv.level, iv.level], color=col, lw=4, alpha=0.35,
                           solid_capstyle='butt')
                for val in (iv.lo_s, iv.hi_s):
                    if val is not None:
                        panel.axvline(val, color=col, ls='--', lw=0.8)
                if iv.ambiguous:
                    a0, b0 = iv.fallback_s
                    panel.axvspan(a0, b0, color=col, alpha=0.08)
        panel.legend(fontsize=8)
    panels[0].set_ylabel(f'Allan deviation {unit}')
    fig.suptitle(f'{sensor}: Allan deviation before/after; dotted: {c:g} sigma_min, bar and '
                 'dashed lines: bias-instability interval (bar to the edge = open end; shaded: '
                 'the curve falls back under the level, an ambiguous upper crossing)', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_reliability(result: ReliabilityResult, out_dir: Union[str, 'os.PathLike[str]'], *,
                      html: bool = True,
                      command: Sequence[str] | None = None) -> list[str]:
    """
    Write every file of a comparison (published together or not at all).

    Parameters
    ----------
    result : ReliabilityResult
        The comparison.
    out_dir : str or os.PathLike
        Output folder (created).
    html : bool, keyword-only
        Write report.html (:mod:`..htmlreport.reliability`).
    command : sequence of str, optional, keyword-only
        The command line, shown in report.html.

    Returns
    -------
    list of str
        The files written, relative to ``out_dir``.

    """
    doc = result.as_dict()
    names: list[str] = []
    with staged_output(out_dir) as stage:
        for side in SIDES:
            cal = result.calibrations[side]
            if cal is None:
                continue
            (stage / side).mkdir()
            for name, text in calibration_files(cal).items():
                atomic_write_text(stage / side / name, text)
                names.append(f'{side}/{name}')
        atomic_write_text(stage / 'reliability.json', json.dumps(doc, indent=2) + '\n')
        atomic_write_text(stage / 'reliability.md', markdown(doc))
        names += ['reliability.json', 'reliability.md']
        if html:
            write_reliability_html(
                doc, {side: (st.channels if st is not None else None)
                      for side, st in result.statics.items()},
                stage, command=command, in_short=in_short(doc))
            names.append('report.html')
        for side in SIDES:
            st = result.statics[side]
            if st is not None:
                atomic_write_text(stage / f'adev_{side}.csv', adev_csv(st))
                names.append(f'adev_{side}.csv')
        if any(result.statics.values()) and result.params.figures:
            for sensor in SENSORS:
                plot_fig6(stage / f'fig6_{sensor}.png', sensor, result.statics['before'],
                          result.statics['after'], result.params.c)
                names.append(f'fig6_{sensor}.png')
    return [os.path.join(str(out_dir), n) for n in names]
