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
The ``report.html`` of ``gyro_noise_reliability``.

Built from the reliability.json document and the Allan curves of the static records held in
memory. "In short" is the plain-language summary reliability.md opens with
(:func:`..calibration.reliability_report.in_short`), followed by each channel's verdict and,
where undetermined, the JSON's reason.
"""

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np

from .figures import allan_figure
from .page import Cell, CellPart, Key, Num, Page, pointer, Table, Verdict, write_report_html
from ..calibration.reliability_report import in_short
from ..units import ACCEL_ADEV, GYRO_ADEV

if TYPE_CHECKING:
    from bokeh.plotting import figure

#: ``{'before'|'after': {channel: AllanResult or None} or None}``: the static records' curves.
_Curves = Mapping[str, Mapping[str, Any] | None]


def _range(p: str, e: dict[str, Any], key: str) -> str | tuple[CellPart, ...]:
    pair = e[key]
    if pair is None:
        return 'not given'
    return tuple(part for k in range(2) for part in (
        (' - ' if k else ''),
        'open' if pair[k] is None else Num(f'{p}/{key}/{k}', '.3g')))


def reliability_page(doc: dict[str, Any], curves: _Curves,
                     command: Sequence[str] | None = None) -> Page:
    """
    Build the page of one reliability run.

    Parameters
    ----------
    doc : dict
        The reliability.json document.
    curves : dict
        ``{'before'|'after': {channel: AllanResult or None}}`` of the static records (drawn).
    command : sequence of str, optional
        The command line.

    Returns
    -------
    Page

    """
    method = ("The verdict: each static record's Allan deviation at averaging times fixed "
              'before the data (taus_s in reliability.json) with its equivalent degrees of '
              'freedom; the ratio after/before has an exact F interval and is tested one-sided '
              'against the band (tolerance) with Holm over the tests of a sensor: beyond, '
              'within, or undetermined with the record length that would detect a change at '
              "the band edge. The indicator: paper 001's bias-instability interval (the "
              'averaging times where the deviation stays below c times its minimum), its width '
              'change tested against +/-50 % (docs/reliability.md).')
    inputs = [p for v in doc['sources'].values() if v
              for p in (v if isinstance(v, list) else [v])]
    tables = _verdict_tables(doc)
    return Page(title='gyro_noise_reliability: before / after', data=doc,
                in_short_markdown=_in_short(doc), verdict=_verdict(doc), card=tuple(tables[:1]),
                card_title='The verdict per sensor', figures=tuple(_figures(curves)),
                tables=tuple(tables[1:] + _noise_term_tables(doc)),
                method_markdown=method,
                command=None if command is None else tuple(command), inputs=tuple(inputs),
                version=doc.get('version', ''))


#: The verdict line's level of each sensor verdict (the worst sensor's is the page's).
_LEVELS = {'within': 'OK', 'undetermined': 'INFO', 'beyond': 'ERROR'}


def _verdict(doc: dict[str, Any]) -> Verdict:
    """Return the verdict line: each sensor's fixed-tau verdict in words, the worst level first."""
    order = ('ERROR', 'INFO', 'OK')
    parts, levels = [], []
    for sensor, e in doc['overall'].items():
        levels.append(_LEVELS.get(e['verdict'], 'INFO'))
        parts.append(f"{sensor}: **{e['verdict']}**. {e['sentence']}")
    level = min(levels, key=order.index) if levels else 'INFO'
    return Verdict(level, ' '.join(parts) or 'no sensor could be judged.')


def _in_short(doc: dict[str, Any]) -> str:
    """Return "In short": reliability.md's sentences, each channel's verdict, what failed."""
    short = ['## In short', '']
    short += [f'* {line}' for line in in_short(doc)]
    short += ['', f'Indicator, bias-instability interval: tau range where ADEV < {doc["c"]:g} '
              f'sigma_min; physiological within +/-{100 * doc["interval_tolerance"]:.0f} % of '
              'the before width (one-sided tests at '
              f'{100 * doc["confidence_one_sided"]:.0f} % confidence).', '']
    for ch, e in doc['bias_instability_interval'].items():
        why = f' ({e["reason"]})' if e['reason'] else ''
        short.append(f'* **{ch}**: {e["verdict"]}{why}')
    if doc['errors']:
        short += ['', 'Parts that could not be analysed:', '']
        short += [f'* {k}: {v}' for k, v in doc['errors'].items()]
    return '\n'.join(short)


def _verdict_tables(doc: dict[str, Any]) -> list[Table]:
    """Return the verdict per sensor, the interval per channel and the mean widths."""
    overall = Table(
        'Verdict per sensor: the noise at fixed averaging times',
        ('Sensor', 'Verdict', 'In words', 'Records that would decide (s)'),
        tuple((sensor, Num(pointer('overall', sensor, 'verdict')),
               Num(pointer('overall', sensor, 'sentence')),
               Num(pointer('overall', sensor, 'decide_record_s'), '.3g'))
              for sensor in doc['overall']))
    indicator = Table(
        'Indicator per sensor: bias-instability interval (mean change over the three axes)',
        ('Sensor', 'Indicator', 'Basis', 'Mean change (%)', 'Sigma (%)'),
        tuple((sensor, Num(pointer('interval_indicator', sensor, 'verdict')),
               Num(pointer('interval_indicator', sensor, 'basis')),
               Num(pointer('interval_indicator', sensor, 'mean_change'), '+.0f', scale=100.0),
               Num(pointer('interval_indicator', sensor, 'mean_change_sd'), '.0f', scale=100.0))
              for sensor in doc['interval_indicator']))
    rows: list[tuple[Cell, ...]] = []
    for ch, e in doc['bias_instability_interval'].items():
        p = pointer('bias_instability_interval', ch)
        rows.append((ch, _range(p, e, 'before_s'), _range(p, e, 'after_s'),
                     Num(p + '/width_before_s', '.4g'), Num(p + '/width_after_s', '.4g'),
                     Num(p + '/change', '+.0f', scale=100.0),
                     Num(p + '/change_sd', '.0f', scale=100.0), Num(p + '/verdict')))
    tables = [overall] + _fixed_tau_tables(doc)
    tables += [indicator, Table('Bias-instability interval before and after (paper 001)',
                                ('Channel', 'Before (s)', 'After (s)', 'Width before (s)',
                                 'Width after (s)', 'Change (%)', 'Sigma (%)', 'Verdict'),
                                tuple(rows))]
    tables.append(Table(
        'Mean width over the three axes', ('Sensor', 'Before (s)', 'After (s)', 'Change (%)'),
        tuple((sensor, Num(pointer('summary', sensor, 'mean_width_before_s'), '.4g'),
               Num(pointer('summary', sensor, 'mean_width_after_s'), '.4g'),
               Num(pointer('summary', sensor, 'mean_change'), '+.0f', scale=100.0))
              for sensor in doc['summary'])))
    return tables


def _fixed_tau_tables(doc: dict[str, Any]) -> list[Table]:
    """Return the Allan deviation at the fixed taus before/after with its test (none without)."""
    fixed: list[tuple[Cell, ...]] = []
    for ch, tests in doc['noise_change'].items():
        for k in range(len(tests)):
            p = pointer('noise_change', ch, k)
            fixed.append((ch, Num(p + '/tau_s', 'g'), Num(p + '/adev_before', '.4g'),
                          Num(p + '/adev_after', '.4g'), Num(p + '/ratio', '.3f'),
                          (Num(p + '/ci/0', '.3f'), ' - ', Num(p + '/ci/1', '.3f')),
                          Num(p + '/verdict')))
    if not fixed:
        return []
    return [Table('Allan deviation at the fixed taus (SI: m/s^2, rad/s)',
                  ('Channel', 'Tau (s)', 'Before', 'After', 'Ratio',
                   f'{100 * (1 - 2 * doc["alpha"]):.0f} % interval', 'Verdict'), tuple(fixed))]


def _noise_term_tables(doc: dict[str, Any]) -> list[Table]:
    """Return the noise terms of the static records with their intervals (none without)."""
    terms: list[tuple[Cell, ...]] = []
    for ch, e in doc['noise_terms'].items():
        for side in ('before', 'after'):
            if not e.get(side):
                continue
            for key in e[side]:
                if key.endswith(('_sd_log', '_ci68')):
                    continue
                p = pointer('noise_terms', ch, side, key)
                terms.append((ch, side, Key(key), Num(p, '.4g'),
                              (Num(p + '_ci68/0', '.3g'), ' to ', Num(p + '_ci68/1', '.3g'))))
    if not terms:
        return []
    return [Table('Noise terms of the static records (unit in the name)',
                  ('Channel', 'Record', 'Term', 'Value', 'Interval (68 %)'),
                  tuple(terms))]


def _figures(records: _Curves) -> list[tuple[str, 'figure']]:
    """Return per sensor the Allan deviations of the static records before and after."""
    figures: list[tuple[str, figure]] = []
    for sensor, display in (('accel', ACCEL_ADEV), ('gyro', GYRO_ADEV)):
        curves: list[dict[str, Any]] = []
        for side in ('before', 'after'):
            for a in 'xyz':
                allan = (records.get(side) or {}).get(f'{sensor}_{a}')
                if allan is None:
                    continue
                tau = np.asarray(allan.tau_s, dtype=np.float64)
                adev = np.asarray(allan.adev, dtype=np.float64)
                lo = np.asarray(getattr(allan, 'ci_low', np.full_like(adev, np.nan)))
                hi = np.asarray(getattr(allan, 'ci_high', np.full_like(adev, np.nan)))
                ok = np.isfinite(adev) & (adev > 0)
                k = display.per_si
                curves.append({'name': f'{side} {a}', 'tau_s': tau[ok], 'adev': adev[ok] * k,
                               'ci_low': lo[ok] * k, 'ci_high': hi[ok] * k})
        if curves:
            figures.append((f'{sensor}: Allan deviation of the static records before and after '
                            '(cf. paper 001 Fig. 6); the interval bounds are in the table.',
                            allan_figure(curves, title=f'{sensor}: Allan deviation',
                                         unit=display.unit)))
    return figures


def write_reliability_html(doc: dict[str, Any], curves: _Curves, out: Path, *,
                           command: Sequence[str] | None = None) -> Path:
    """
    Write ``report.html`` of a reliability run into the staged folder ``out``; return its path.

    ``doc`` (the reliability.json document), ``curves`` and ``command`` (the command line) are
    those of :func:`reliability_page`.

    """
    return write_report_html(reliability_page(doc, curves, command), out / 'report.html')
