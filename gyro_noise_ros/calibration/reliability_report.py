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
The files of ``gyro_noise_reliability``, rendered from its document (reliability.json).

Inputs: the dict ``ReliabilityResult.as_dict()`` returns (SI, units in the keys, changes as
ratios; null where a part was not given or a value not finite) and, for the CSV and the figures,
the Allan deviation curves of the static records (per channel: ``tau_s``, ``adev``, ``ci_low``,
``ci_high``, ``edf``; rad/s or m/s^2). Outputs: :func:`in_short` (the plain-language summary
that reliability.md and report.html open with), :func:`reliability_markdown` (reliability.md:
the verdicts, then the evidence in %, mg and deg/s), :func:`adev_csv` (adev_<side>.csv) and
:func:`plot_fig6` (fig6_<sensor>.png, paper 001 Figure 6: ADEV before and after with the level
c sigma_min and the bias-instability interval). :func:`term_keys` names the noise terms' keys of
the document. The workflow is :mod:`..app.reliability`; the page, :mod:`..htmlreport.reliability`.
"""

from collections.abc import Iterable, Mapping, Sequence
import io
import math
from typing import Any

import numpy as np

from .static_record import CHANNELS, TERMS, unit_of
from ..formatting import fmt_or_na, percent, plus_minus
from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import MG_TO_M_S2, RAD_TO_DEG

__all__ = ['SENSORS', 'SIDES', 'adev_csv', 'in_short', 'plot_fig6', 'reliability_markdown',
           'term_keys']

#: The two records of each part, in the order they are reported.
SIDES = ('before', 'after')
#: The sensors, each with three channels (:data:`.static_record.CHANNELS`).
SENSORS = ('accel', 'gyro')
#: Printed unit and SI-to-printed factor of each channel family.
UNITS = {'m_s2': ('m/s^2', 1.0), 'rad_s': ('deg/s', RAD_TO_DEG)}
#: Per noise term: its key in the document (``{u}``: the term and channel unit) and its printed
#: unit (``{p}``: the channel's printed unit).
TERM_UNITS = {
    'white_noise': ('{u}_per_sqrt_hz', '{p}/sqrt(Hz)'),
    'bias_stability': ('{u}', '{p}'),
    'random_walk': ('{u}_per_sqrt_s', '{p}/sqrt(s)'),
}
#: An Allan deviation result of a channel (``tau_s``, ``adev``, ``ci_low``, ``ci_high``, ``edf``)
#: or None; per channel.
Curves = Mapping[str, Any]


def term_keys(ch: str) -> dict[str, str]:
    """
    Return the document's key of each noise term of a channel.

    Parameters
    ----------
    ch : str
        A channel (:data:`.static_record.CHANNELS`), e.g. ``gyro_x``.

    Returns
    -------
    dict
        ``{term: key}``, e.g. ``{'white_noise': 'white_noise_rad_s_per_sqrt_hz', ...}``.

    """
    u = unit_of(ch)
    return {t: TERM_UNITS[t][0].format(u=f'{t}_{u}') for t in TERMS}


NAMES = {'accel': 'accelerometer', 'gyro': 'gyroscope'}


def _pct(v: float | None) -> str:
    """Return a change of the width as a signed whole percentage (``+125 %``)."""
    return percent(v, '+.0f')


def _hours(seconds: float | None) -> str:
    return 'n/a' if seconds is None else f'{seconds / 3600:.3g} h'


def _longest(values: Iterable[float | None] | None) -> float | None:
    vals = [v for v in (values or []) if v is not None]
    return max(vals) if vals else None


def _sensor_sentence(name: str, e: dict[str, Any], doc: dict[str, Any]) -> str:
    tol = f'+/-{100 * doc["interval_tolerance"]:.0f} %'
    conf = f'{100 * doc["confidence_one_sided"]:.0f} %'
    m, sd = e['mean_change'], e['mean_change_sd']
    if m is not None:
        how = 'widened' if m >= 0 else 'narrowed'
        change = (f"the {name}'s bias-instability interval (the span of averaging times where "
                  f'the noise floor is flat) {how} by {abs(100 * m):.0f} % +/- {100 * sd:.0f} % '
                  'on average over the three axes')
    else:
        change = (f"the {name}'s bias-instability interval could not be compared on all "
                  'three axes')
    if e['verdict'] == 'beyond':
        axes = (f' ({", ".join(e["axes_beyond"])} beyond on their own)' if e['axes_beyond']
                else '')
        return (f'Indicator (paper 001, not the verdict): {change}, more than {tol} at {conf} '
                f'confidence{axes}.')
    if e['verdict'] == 'physiological':
        return (f'Indicator (paper 001, not the verdict): {change}, within {tol} at {conf} '
                'confidence.')
    decide = _longest(e['decide_record_s'])
    longer = (f'; static records of about {_hours(decide)} each would decide it'
              if decide is not None else '')
    record_s = _longest([(r or {}).get('duration_s') for r in doc['static_records'].values()])
    now = (f' (these are {_hours(record_s)})' if record_s is not None and decide is not None
           else '')
    ci = e['ci']
    if m is not None and ci:
        return (f'Indicator (paper 001, not the verdict): {change}; its '
                f'{100 * (1 - 2 * doc["alpha"]):.0f} % interval ({_pct(ci[0])} .. '
                f'{_pct(ci[1])}) straddles {tol}{longer}{now}.')
    return f'Indicator (paper 001, not the verdict): the {name}\'s interval: {e["basis"]}.'


def _floor_sentences(doc: dict[str, Any]) -> list[str]:
    out = []
    for s in SENSORS:
        logs: list[float] = []
        var = 0.0
        for a in 'xyz':
            ch = f'{s}_{a}'
            r = (doc['noise_terms'][ch].get('ratio_after_before') or {}).get(
                term_keys(ch)['bias_stability'])
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
        The ``reliability.json`` document.

    Returns
    -------
    list of str

    """
    out = []
    statics = doc['static_records']
    for side in SIDES:
        if statics[side] and statics[side].get('cut'):
            out.append(f'The {side} static record: {statics[side]["cut"]}')
    if statics['before'] and statics['after']:
        for s in SENSORS:
            out.append(doc['overall'][s]['sentence'])
        for s in SENSORS:
            out.append(_sensor_sentence(NAMES[s], doc['interval_indicator'][s], doc))
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
        if gc is not None and gc['consistent'] is False:
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
            f'{plus_minus(e["width_before_s"], e["width_sigma_before_s"], ".4g")} | '
            f'{plus_minus(e["width_after_s"], e["width_sigma_after_s"], ".4g")} | '
            f'{plus_minus(e["change"], e["change_sd"], "+.0f", 100)} % | '
            f'{"n/a" if not ci else f"{_pct(ci[0])} .. {_pct(ci[1])}"} | {e["verdict"]} |')
    return out


def _term_rows(doc: dict[str, Any]) -> list[str]:
    out = ['| channel | term | unit | before (68 % interval) | after (68 % interval) | '
           'after / before |', '|---|---|---|---|---|---|']
    labels = {'white_noise': 'white noise (N)', 'bias_stability': 'bias stability',
              'random_walk': 'random walk (K)'}
    for ch, e in doc['noise_terms'].items():
        printed, scale = UNITS[unit_of(ch)]
        for t, key in term_keys(ch).items():
            unit = TERM_UNITS[t][1].format(p=printed)

            def cell(side: str) -> str:
                d = e[side]
                if d is None or d[key] is None:
                    return 'n/a'
                lo, hi = d[key + '_ci68']
                hi_txt = 'unresolved' if hi is None else f'{hi * scale:.3g}'
                return f'{d[key] * scale:.4g} ({fmt_or_na(lo and lo * scale, ".3g")} .. {hi_txt})'

            r = (e.get('ratio_after_before') or {}).get(key)
            ratio = 'n/a' if not r else plus_minus(r['ratio'], r['ratio_sd'], '.3f')
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
            out.append(f'| {r["parameter"]} ({u}) | '
                       f'{plus_minus(r["before"], r["before_sigma"], ".3f")} | '
                       f'{plus_minus(r["after"], r["after_sigma"], ".3f")} | '
                       f'{plus_minus(r["change"], r["change_sigma"], "+.3f")} |')
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
                             plus_minus(d['bias_rad_s'][i], d['bias_sigma_rad_s'][i], '.5f',
                                        RAD_TO_DEG))
            ch = g.get('bias_change_rad_s')
            cells.append('n/a' if not ch else plus_minus(ch[i], g['bias_change_sigma_rad_s'][i],
                                                         '+.5f', RAD_TO_DEG))
            for side in SIDES:
                d = g[side]
                est = d is not None and d['estimated'] is not None and d['estimated'][i][i]
                sigma = (d['scale_factor_sigma'] or [None] * 3)[i] if est else None
                cells.append(plus_minus(d['scale_factor'][i], sigma, '.4f', 100) if est
                             else 'not estimated')
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
                cells = [('not estimated' if v is None else plus_minus(v[0], v[1], '.4f', 100))
                         for v in vals]
                if vals[0] is not None and vals[1] is not None:
                    sd = (math.hypot(vals[0][1], vals[1][1])
                          if vals[0][1] is not None and vals[1][1] is not None else None)
                    cells.append(plus_minus(vals[1][0] - vals[0][0], sd, '+.4f', 100))
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
        if gc is None:
            return 'not given'
        if gc['consistent'] is None:
            return 'not possible (9 poses)'
        return 'consistent' if gc['consistent'] else 'inconsistent'

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
                   f'{fmt_or_na(r["static_fraction"], ".3f")} | {r["orientation"]} | '
                   f'{_temp(r["temperature"])} |')
    dw = [(side, d) for side in SIDES for d in (doc['dwell_temperatures'].get(side) or [])]
    if dw:
        out += ['', '| calibration | dwell | start (s) | duration (s) | temperature (degC): mean '
                '(min .. max) | recording |', '|---|---|---|---|---|---|']
        for side, d in dw:
            out.append(f'| {side} | {d["orientation"]} | {d["t_start_s"]:.1f} | '
                       f'{d["duration_s"]:.1f} | {_temp(d["temperature"])} | {d["source"]} |')
    return out


def reliability_markdown(doc: dict[str, Any]) -> str:
    """
    Return ``reliability.md`` of a reliability document: the verdict first, then the evidence.

    Parameters
    ----------
    doc : dict
        The ``reliability.json`` document.

    Returns
    -------
    str

    """
    tol = f'+/-{100 * doc["tolerance"]:.0f} %'
    paper = f'+/-{100 * doc["interval_tolerance"]:.0f} %'
    one = f'{100 * doc["confidence_one_sided"]:.0f} %'
    two = f'{100 * (1 - 2 * doc["alpha"]):.0f} %'
    out = ['# Reliability test (paper 001): before / after', '', '## In short', '']
    out += [f'- {line}' for line in in_short(doc)]
    out += _verdict_rows(doc, tol, two)
    out += ['', '## Indicator: the bias-instability interval (paper 001 section 6)', '',
            'Not the verdict: the width of one record scatters too much to decide at hours '
            f'(docs/reliability.md). Per sensor: **beyond** when an axis is beyond at the '
            f'Bonferroni level (one-sided {100 * (1 - doc["alpha"] / 3):.1f} %) or the three-axis '
            f'mean change of the interval width is beyond {paper} at one-sided {one}; '
            f'**physiological** when the mean is inside {paper} at one-sided {one} on both sides; '
            'otherwise **undetermined**.', '',
            f'| sensor | indicator | mean change of the width (three axes) | {two} interval | '
            'records that would decide | basis |', '|---|---|---|---|---|---|']
    for s in SENSORS:
        e = doc['interval_indicator'][s]
        ci = e['ci']
        out.append(f'| {NAMES[s]} | {e["verdict"]} | '
                   f'{plus_minus(e["mean_change"], e["mean_change_sd"], "+.0f", 100)} % | '
                   f'{"n/a" if not ci else f"{_pct(ci[0])} .. {_pct(ci[1])}"} | '
                   f'{_hours(_longest(e["decide_record_s"]))} | {e["basis"]} |')
    out += ['',
            f'Tau range where ADEV < {doc["c"]:g} sigma_min (sigma_min: the bias stability of '
            'the Allan readout, over taus up to a tenth of the record). Width +/- one standard '
            'deviation propagated from the equivalent degrees of freedom of the Allan variance '
            f'at the crossings; **beyond** when the change is outside {paper} at one-sided {one}, '
            f'**physiological** when the {two} interval lies inside {paper}, else '
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
        out.append(f'- {NAMES[sensor]}: {fmt_or_na(e["mean_width_before_s"], ".4g")} s -> '
                   f'{fmt_or_na(e["mean_width_after_s"], ".4g")} s, change '
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


def _verdict_rows(doc: dict[str, Any], tol: str, two: str) -> list[str]:
    """Return the verdict per sensor and the fixed-tau table it rests on."""
    taus = ', '.join(f'{t:g}' for t in doc['taus_s'])
    out = ['', '## Verdict: the noise at fixed averaging times', '',
           f'The Allan deviation at {taus} s (fixed before the data), after over before, with the '
           f'interval of the F law of the two variances (their EDFs). **beyond**: a ratio outside '
           f'{tol} under the Holm procedure over the tests of the sensor at family-wise one-sided '
           f'{100 * doc["alpha"]:g} %; **within**: every {two} interval inside {tol}; otherwise '
           f'**undetermined**, with the record length (each) that detects a change of '
           f'x{1 + doc["tolerance"]:g} with {100 * doc["power"]:.0f} % probability (from the '
           'noise model, not the estimate).', '',
           '| sensor | verdict | in words | records that would decide |', '|---|---|---|---|']
    for s in SENSORS:
        e = doc['overall'][s]
        out.append(f'| {NAMES[s]} | **{e["verdict"]}** | {e["sentence"]} | '
                   f'{_hours(e["decide_record_s"])} |')
    rows = [t for ch in CHANNELS for t in doc['noise_change'][ch]]
    if rows:
        out += ['', f'| channel | tau (s) | ADEV before | ADEV after | unit | EDF before / after '
                f'| ratio | {two} interval | verdict |', '|---|---|---|---|---|---|---|---|---|']
        for t in rows:
            unit, k = UNITS[unit_of(t['channel'])]
            out.append(f'| {t["channel"]} | {t["tau_s"]:g} | {k * t["adev_before"]:.4g} | '
                       f'{k * t["adev_after"]:.4g} | {unit} | {t["edf_before"]:.0f} / '
                       f'{t["edf_after"]:.0f} | x{t["ratio"]:.3f} | {t["ci"][0]:.3f} - '
                       f'{t["ci"][1]:.3f} | {t["verdict"]} |')
    return out


def adev_csv(curves: Curves) -> str:
    """
    Return the Allan deviation curves of a static record as CSV text (Figure 6 data).

    Parameters
    ----------
    curves : dict
        ``{channel: AllanResult or None}`` of the record.

    Returns
    -------
    str
        Columns ``tau_s`` and, per channel, ``<ch>_adev_<unit>``, ``<ch>_ci_low_<unit>``,
        ``<ch>_ci_high_<unit>`` (68.3 % interval) and ``<ch>_edf``; empty cells where a channel
        has no value at that tau.

    """
    taus = sorted({float(t) for a in curves.values() if a is not None
                   for t in np.asarray(a.tau_s)})
    index = {t: k for k, t in enumerate(taus)}
    cols = ['tau_s']
    data = [np.array(taus)]
    for ch in CHANNELS:
        u = unit_of(ch)
        names = [f'{ch}_adev_{u}', f'{ch}_ci_low_{u}', f'{ch}_ci_high_{u}', f'{ch}_edf']
        block = np.full((len(taus), 4), np.nan)
        a = curves[ch]
        if a is not None:
            rows = [index[float(t)] for t in np.asarray(a.tau_s)]
            block[rows] = np.column_stack([a.adev, a.ci_low, a.ci_high, a.edf])
        cols += names
        data += list(block.T)
    buf = io.StringIO()
    buf.write(','.join(cols) + '\n')
    for row in zip(*data):
        buf.write(','.join('' if not math.isfinite(v) else repr(float(v)) for v in row) + '\n')
    return buf.getvalue()


def _interval_marks(panel: Any, doc: dict[str, Any], ch: str, side: str, tau_s: Any,
                    col: str) -> None:
    """Draw a channel's level c sigma_min and its bias-instability interval on a panel."""
    e = doc['bias_instability_interval'][ch]
    sigma_min = e[f'sigma_min_{side}_{unit_of(ch)}']
    if sigma_min is None:
        return
    level = doc['c'] * sigma_min
    if not math.isfinite(level):
        return
    lo_s, hi_s = e[f'{side}_s']
    panel.axhline(level, color=col, ls=':', lw=0.9)
    lo = lo_s if lo_s is not None else tau_s[0]
    hi = hi_s if hi_s is not None else tau_s[-1]
    panel.plot([lo, hi], [level, level], color=col, lw=4, alpha=0.35, solid_capstyle='butt')
    for val in (lo_s, hi_s):
        if val is not None:
            panel.axvline(val, color=col, ls='--', lw=0.8)
    ambiguous = e[f'ambiguous_{side}']
    if ambiguous:
        a0, b0 = ambiguous['fallback_s']
        panel.axvspan(a0, b0, color=col, alpha=0.08)


def plot_fig6(path: StrPath, doc: dict[str, Any], sensor: str,
              curves: Mapping[str, Curves | None]) -> None:
    """
    Draw paper 001 Figure 6 for one sensor: ADEV per axis before and after, level and interval.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    doc : dict
        The ``reliability.json`` document (the level factor c, each interval).
    sensor : {'accel', 'gyro'}
        Which sensor.
    curves : dict
        ``{'before'|'after': {channel: AllanResult or None} or None}`` of the static records.

    """
    plt = pyplot()
    unit = '(m/s^2)' if sensor == 'accel' else '(rad/s)'
    fig, panels = plt.subplots(1, 2, figsize=(11, 4.6), sharey=True)
    colors = {'x': 'tab:blue', 'y': 'tab:orange', 'z': 'tab:green'}
    for panel, side in zip(panels, SIDES):
        panel.set_title(f'({"a" if side == "before" else "b"}) {side}')
        panel.set_xlabel('cluster time tau (s)')
        panel.grid(True, which='both', alpha=0.3)
        record = curves.get(side)
        if record is None:
            panel.text(0.5, 0.5, 'not given', transform=panel.transAxes, ha='center')
            continue
        for a in 'xyz':
            allan = record[f'{sensor}_{a}']
            if allan is None:
                continue
            col = colors[a]
            panel.loglog(allan.tau_s, allan.adev, color=col, lw=1.3, label=f'{a} axis')
            _interval_marks(panel, doc, f'{sensor}_{a}', side, allan.tau_s, col)
        panel.legend(fontsize=8)
    panels[0].set_ylabel(f'Allan deviation {unit}')
    fig.suptitle(f'{sensor}: Allan deviation before/after; dotted: {doc["c"]:g} sigma_min, bar '
                 'and dashed lines: bias-instability interval (bar to the edge = open end; '
                 'shaded: the curve falls back under the level, an ambiguous upper crossing)',
                 fontsize=8)
    save_figure(fig, path, dpi=110, tight=True)
