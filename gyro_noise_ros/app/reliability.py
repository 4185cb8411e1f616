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
``reliability.json``, from which (and the static records' Allan curves)
:mod:`..calibration.reliability_report` renders reliability.md, the CSV and the figures, and
:mod:`..htmlreport.reliability` the page. :func:`write_reliability` writes every file through
:func:`..outputs.staged_output`.
"""

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
import json
import math
import os
from typing import Any, cast, Union

import numpy as np

from .calibrate import (CalibrateParams, calibration_files, CalibrationResult, Gravity,
                        run_calibration)
from .. import __version__
from ..calibration import noise_change, records
from ..calibration.calibrate_report import table6_rows
from ..calibration.interval import compare, DEFAULT_ALPHA, DEFAULT_C, DEFAULT_MIN_EDF, overall
from ..calibration.reliability_report import (adev_csv, plot_fig6, reliability_markdown, SENSORS,
                                              SIDES, term_keys)
from ..calibration.static import DetectorSettings
from ..calibration.static_record import CHANNELS, StaticRecord, unit_of
from ..core.segments import left_out_sentence, segment_left_out, StaticSegment, WindowStats
from ..errors import BagError, InputDataError, ParameterError
from ..formatting import finite_or_none as _num
from ..htmlreport.reliability import write_reliability_html
from ..outputs import atomic_write_text, staged_output

PARTS = ('before_calibration', 'before_static', 'after_calibration', 'after_static')
#: Largest relative difference of the two static records' sample rates.
RATE_MATCH = 0.01
#: ``--static``: cut motion by the static-segment rule, or analyse every sample.
STATIC_MODES = ('auto', 'off')
#: Samples per update of the rule's window statistics (its cost grows with batch x windows).
_SEGMENT_CHUNK = 4096


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
        Half-width of the band of the noise verdict's ADEV ratio (default 0.30; paper 001's
        +/-50 % is 0.5). The bias-instability interval, an indicator, keeps the paper's 0.5.
    alpha : float
        Family-wise one-sided level of the noise verdict per sensor, and the one-sided level of
        the interval indicator's tests (0.05).
    taus_s : tuple of float
        The noise verdict's averaging times (s), fixed before the data.
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
    static : str
        'auto': the static records' longest static segment is analysed, motion cut and said
        (``core.segments``, the rule of ``gyro_noise_analyze``); 'off': every sample.

    """

    before_calibration: tuple[str, ...] = ()
    before_static: str | None = None
    after_calibration: tuple[str, ...] = ()
    after_static: str | None = None
    c: float = DEFAULT_C
    tolerance: float = noise_change.DEFAULT_TOLERANCE
    alpha: float = DEFAULT_ALPHA
    taus_s: tuple[float, ...] = noise_change.DEFAULT_TAUS_S
    min_edf: float = DEFAULT_MIN_EDF
    topic: str | None = None
    gravity: Gravity = field(default_factory=Gravity)
    rate_hz: float | None = None
    settings: DetectorSettings = field(default_factory=DetectorSettings)
    figures: bool = True
    static: str = 'auto'

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
        if not (math.isfinite(self.tolerance) and 0 < self.tolerance < 1):
            raise ParameterError(f'--tolerance must be in (0, 1), got {self.tolerance}')
        object.__setattr__(self, 'taus_s', tuple(float(t) for t in self.taus_s))
        try:
            noise_change.fixed_factors(self.taus_s, 1.0)
        except ParameterError as err:
            raise ParameterError(f'--taus: {err}') from err
        if not (math.isfinite(self.alpha) and 0 < self.alpha < 0.5):
            raise ParameterError(f'--alpha must be in (0, 0.5), got {self.alpha}')
        if self.rate_hz is not None and not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ParameterError(f'--rate-hz must be > 0, got {self.rate_hz!r}')
        if self.static not in STATIC_MODES:
            raise ParameterError(f"--static must be one of {', '.join(STATIC_MODES)}, "
                                 f'got {self.static!r}')

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
        Imu samples analysed (the static part: ``left_out`` says what was cut).
    duration_s : float
        Last stamp relative to the first (s).
    check : dict
        The static check (``static_fraction``, ``orientation``, ``problem``,
        ``accel_problem``).
    channels : dict
        ``{channel: ChannelResult}``.
    temperature : dict or None
        :func:`..calibration.records.temperature_stats` of the whole record.
    frame_id : str
        The Imu messages' ``header.frame_id`` ('' when unknown).
    left_out : dict
        What the static-segment rule cut (``motion``: samples; ``static_segment_s``,
        ``static_segments_s``, ``cut_s`` when it cut something: ``core.segments``).
    cut : str
        The sentence saying so ('' when nothing was cut).

    """

    source: str
    rate_hz: float
    samples: int
    duration_s: float
    check: dict[str, Any]
    channels: dict[str, Any]
    temperature: dict[str, Any] | None = None
    frame_id: str = ''
    left_out: dict[str, Any] = field(default_factory=dict)
    cut: str = ''

    def as_dict(self) -> dict[str, Any]:
        """
        Return the record's entry of ``static_records`` in ``reliability.json``.

        Returns
        -------
        dict

        """
        return {'source': self.source, 'rate_hz': self.rate_hz, 'samples': self.samples,
                'duration_s': self.duration_s, 'frame_id': self.frame_id, **self.check,
                'left_out': self.left_out, 'cut': self.cut, 'temperature': self.temperature}


def _temperature(path: str, topic: str | None, t0_ns: int | None = None) -> Any:
    try:
        return records.read_temperature(path, topic=topic, t0_ns=t0_ns)
    except (BagError, InputDataError):
        # the temperature is reported, never required: an unreadable topic is "not recorded"
        return None


#: ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)`` batches of one record, as ``records.iter_imu``.
Batches = Iterable[tuple[float, np.ndarray, np.ndarray, np.ndarray]]


def static_from_batches(batches: Callable[[], Batches], *, source: str, c: float = DEFAULT_C,
                        settings: DetectorSettings | None = None,
                        min_edf: float = DEFAULT_MIN_EDF, alpha: float = DEFAULT_ALPHA,
                        temperature: tuple[np.ndarray, np.ndarray] | None = None,
                        taus_s: Sequence[float] = noise_change.DEFAULT_TAUS_S,
                        static: str = 'auto') -> StaticAnalysis:
    """
    Analyse a static record given as ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)`` batches.

    Two passes: the static-segment rule of ``core.segments`` over the gyro columns (the one rule
    of every tool, fed as ``gyro_noise_analyze`` feeds it, so both cut the same windows of a
    record: a knock is cut, the longest static run analysed on all six channels, what was cut
    said), then the analysis of that part.

    Parameters
    ----------
    batches : callable
        Returns the record's batches afresh at each call, as :func:`..calibration.records.
        iter_imu` yields them (the rate of the first one is the record's).
    source : str, keyword-only
        Record name for messages.
    c, settings, min_edf, alpha, taus_s, static
        As :func:`analyze_static`.
    temperature : tuple, optional, keyword-only
        ``(t_s, temperature_degc)`` of the record (:func:`..calibration.records.read_temperature`).

    Returns
    -------
    StaticAnalysis

    Raises
    ------
    InputDataError
        No channel can give the noise verdict's fixed taus (too short for the longest, or its
        static part is; constant; not static; no samples): one line naming the record and why.

    """
    # 'off': one pass, every sample (total counted below)
    seg, total, last_ns = _static_segment(batches()) if static == 'auto' else (None, -1, 0)
    rec = None
    for rate, t, accel, gyro in batches():
        if rec is None:
            kw: dict[str, Any] = {} if settings is None else {'settings': settings}
            rec = StaticRecord(rate, c=c, source=source, min_edf=min_edf, alpha=alpha,
                               taus_s=taus_s, **kw)
        keep = None
        if seg is not None:
            ns = np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)
            keep = (ns >= seg.start_ns) & (ns < seg.end_ns)
        rec.update(t, accel, gyro, keep=keep)
    if rec is None:
        raise InputDataError(f'static record {source!r} holds no Imu samples')
    total = rec.samples if total < 0 else total
    left_out: dict[str, Any] = {'motion': total - rec.samples}
    said = ''
    if seg is not None:
        left_out.update(segment_left_out(seg, 0, last_ns))
        a, b = left_out['static_segment_s']
        said = left_out_sentence(total, motion=total - rec.samples, segment_s=(a, b),
                                 cuts=seg.cuts(0, last_ns))
    results, check = rec.finish()
    if not any(isinstance(r.fixed, noise_change.FixedTaus) for r in results.values()):
        # not one channel gives the verdict's statistics: a 20 s record, a constant one, a
        # six-position record given as static... six "undetermined" and exit 0 would hide that
        # the record is not what the procedure needs
        why = str(results[CHANNELS[-1]].fixed) + (f' ({said})' if said else '')
        raise InputDataError(f'static record {source!r} ({rec.duration_s:.1f} s, {total} '
                             f'samples) cannot be analysed: {why}')
    return StaticAnalysis(source, rec.rate_hz, rec.samples, rec.duration_s, check, results,
                          records.temperature_stats(temperature), left_out=left_out, cut=said)


def _static_segment(batches: Batches) -> tuple[StaticSegment | None, int, int]:
    """Return the segment to analyse (None: all of it), the samples and the last stamp (ns)."""
    stats = WindowStats()
    total, last_ns = 0, 0
    for _, t, _accel, gyro in batches:
        ns = np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)
        g = np.asarray(gyro, dtype=np.float64)
        for k in range(0, ns.size, _SEGMENT_CHUNK):
            stats.update(ns[k:k + _SEGMENT_CHUNK], g[k:k + _SEGMENT_CHUNK])
        total += ns.size
        last_ns = int(ns[-1]) if ns.size else last_ns
    seg = stats.segment()
    return (None if seg is None or seg.static_throughout else seg), total, last_ns


def analyze_static(path: str, *, topic: str | None = None, rate_hz: float | None = None,
                   c: float = DEFAULT_C, settings: DetectorSettings | None = None,
                   min_edf: float = DEFAULT_MIN_EDF, alpha: float = DEFAULT_ALPHA,
                   taus_s: Sequence[float] = noise_change.DEFAULT_TAUS_S,
                   static: str = 'auto') -> StaticAnalysis:
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
    taus_s : sequence of float, keyword-only
        The noise verdict's fixed averaging times (s).
    static : str, keyword-only
        'auto': analyse the longest static segment (``core.segments``); 'off': every sample.

    Returns
    -------
    StaticAnalysis

    Raises
    ------
    InputDataError
        As :func:`static_from_batches`.

    """
    st = static_from_batches(lambda: records.iter_imu(path, topic=topic, rate_hz=rate_hz),
                             source=str(path), c=c, settings=settings, min_edf=min_edf,
                             alpha=alpha, taus_s=taus_s, static=static)
    return replace(st, temperature=records.temperature_stats(_temperature(path, topic)),
                   frame_id=records.frame_id(path, topic=topic))


def verdicts_of(before: StaticAnalysis | None, after: StaticAnalysis | None, *,
                tolerance: float = noise_change.PAPER_TOLERANCE,
                alpha: float = DEFAULT_ALPHA) -> tuple[dict[str, Any], dict[str, Any]]:
    """
    Return the bias-instability interval indicator of two static records, per channel and sensor.

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


def noise_verdicts_of(before: StaticAnalysis | None, after: StaticAnalysis | None, *,
                      tolerance: float = noise_change.DEFAULT_TOLERANCE,
                      alpha: float = DEFAULT_ALPHA) -> dict[str, Any]:
    """
    Return the noise verdict of each sensor (:func:`..calibration.noise_change.compare_sensor`).

    Parameters
    ----------
    before, after : StaticAnalysis or None
        The records (None: not given).
    tolerance, alpha : float, keyword-only
        Band half-width and family-wise one-sided level.

    Returns
    -------
    dict
        ``{'accel': SensorChange, 'gyro': SensorChange}``; without both records, each
        undetermined with that reason.

    Raises
    ------
    InputDataError
        The two records cannot be compared: different sample rates or sensor frames.

    """
    if before is None or after is None:
        missing = 'the verdict needs a static record before and one after'
        return {s: noise_change.SensorChange(s, 'undetermined', reason=missing) for s in SENSORS}
    _check_pair(before, after)
    return {s: noise_change.compare_sensor(
        s, {ch: before.channels[ch].fixed for ch in CHANNELS if ch.startswith(s)},
        {ch: after.channels[ch].fixed for ch in CHANNELS if ch.startswith(s)},
        tolerance=tolerance, alpha=alpha) for s in SENSORS}


def _check_pair(before: StaticAnalysis, after: StaticAnalysis) -> None:
    """Refuse two static records that are not one sensor in one configuration."""
    if abs(after.rate_hz / before.rate_hz - 1.0) > RATE_MATCH:
        raise InputDataError(
            f'the static records differ in sample rate ({before.rate_hz:.4g} Hz before, '
            f'{after.rate_hz:.4g} Hz after): the noise of one sensor configuration is compared, '
            'record both at one rate')
    fb, fa = before.frame_id, after.frame_id
    if fb and fa and fb != fa:
        raise InputDataError(
            f"the static records come from different sensor frames ('{fb}' before, '{fa}' "
            "after): give the same sensor's records (or --topic)")


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
        ``{channel: Verdict}`` of the width change (the interval indicator).
    sensors : dict
        ``{'accel': SensorVerdict, 'gyro': SensorVerdict}`` of the interval indicator.
    noise : dict
        ``{'accel': SensorChange, 'gyro': SensorChange}``: the verdict
        (:func:`noise_verdicts_of`).
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
    noise: dict[str, Any] = field(default_factory=dict)
    version: str = __version__

    def warnings(self) -> list[str]:
        """
        Return the lines a tool prints on stderr (failed parts, channels without a verdict).

        Returns
        -------
        list of str

        """
        out = [f'{k.replace("_", " ")}: {v}' for k, v in self.errors.items()]
        for side in SIDES:
            st = self.statics.get(side)
            for ch, r in (st.channels.items() if st is not None else ()):
                if isinstance(r.fixed, str):
                    out.append(f'{side} static record, {ch}: {r.fixed} (its sensor cannot be '
                               'judged)')
        return out

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
            'taus_s': list(p.taus_s), 'power': noise_change.POWER,
            'interval_tolerance': noise_change.PAPER_TOLERANCE,
            'sources': {k: (list(v) if isinstance(v, tuple) else v)
                        for k, v in ((q, getattr(p, q) or None) for q in PARTS)},
            'overall': {s: _noise_entry(self.noise[s], p) for s in SENSORS},
            'noise_change': {ch: [t.as_dict() for s in SENSORS for t in self.noise[s].tests
                                  if t.channel == ch] for ch in CHANNELS},
            'interval_indicator': {s: _sensor_entry(self.sensors[s], self.statics)
                                   for s in SENSORS},
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
            settings=params.settings, min_edf=params.min_edf, alpha=params.alpha,
            taus_s=params.taus_s, static=params.static) if bag else None
    if len(errors) == len(given):
        raise InputDataError('nothing could be analysed: ' + '; '.join(
            f'{k}: {v}' for k, v in errors.items()))
    noise = noise_verdicts_of(statics['before'], statics['after'],
                              tolerance=params.tolerance, alpha=params.alpha)
    verdicts, sensors = verdicts_of(statics['before'], statics['after'], alpha=params.alpha)
    return ReliabilityResult(params, statics, cals, verdicts, sensors, temps, errors, noise)


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


def _noise_entry(sc: Any, p: ReliabilityParams) -> dict[str, Any]:
    return {'verdict': sc.verdict,
            'sentence': noise_change.sentence(sc, tolerance=p.tolerance, alpha=p.alpha),
            'decide_record_s': _num(sc.decide_record_s), 'reason': sc.reason,
            'tests': len(sc.tests),
            'tests_beyond': [[t.channel, t.tau_s] for t in sc.tests if t.verdict == 'beyond'],
            'decisive': sc.decisive.as_dict() if sc.decisive is not None else None}


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


def _terms_entry(ch: str, statics: dict[str, Any]) -> dict[str, Any]:
    keys = term_keys(ch)
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
    # the arrays the document leaves out: the Allan curve of each channel of the static records
    curves = {side: (None if st is None else {ch: r.allan for ch, r in st.channels.items()})
              for side, st in result.statics.items()}
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
        atomic_write_text(stage / 'reliability.md', reliability_markdown(doc))
        names += ['reliability.json', 'reliability.md']
        if html:
            write_reliability_html(doc, curves, stage, command=command)
            names.append('report.html')
        for side in SIDES:
            record = curves[side]
            if record is not None:
                atomic_write_text(stage / f'adev_{side}.csv', adev_csv(record))
                names.append(f'adev_{side}.csv')
        if any(result.statics.values()) and result.params.figures:
            for sensor in SENSORS:
                plot_fig6(stage / f'fig6_{sensor}.png', doc, sensor, curves)
                names.append(f'fig6_{sensor}.png')
    return [os.path.join(str(out_dir), n) for n in names]
