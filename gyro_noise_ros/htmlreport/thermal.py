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
The ``report.html`` of ``gyro_noise_thermal compare`` and ``gyro_noise_thermal apply``.

Built from the compare.json / metrics.json document and the arrays the workflow's result holds
(the Allan curves of the scoring; for apply, the run and the processed output, rad/s). "In
short" is the verdicts as compare.md / report.md word them: each verdict text is the JSON's, and
the best held-out line uses the JSON's rule and method. The verdict line is the one compare.md /
report.md open with (``thermal.report.compare_verdict``, ``apply_verdict``); the card, the
methods ranked by their residual drift over the noise floor (compare) or the method's numbers
with that yardstick (apply).
"""

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .figures import allan_figure, series_figure
from .page import Cell, Num, Page, pointer, Table, Verdict, write_report_html
from ..thermal.metrics import DRIFT_WINDOW_S
from ..thermal.report import apply_verdict, compare_verdict
from ..units import RAD_TO_DEG as _DEG, S_PER_H, time_unit

if TYPE_CHECKING:
    from bokeh.plotting import figure

_DEG_H = _DEG * S_PER_H
AXES = ('x', 'y', 'z')


def _bias_stability(doc: dict[str, Any], p: str) -> Num:
    """Cell of a bias stability: '<= ' before an upper bound."""
    bound = '<= ' if _lookup(doc, p + '/bias_stability_upper_bound') else ''
    return Num(p + '/bias_stability_deg_h', '.4g', bound)


def _bandwidth(doc: dict[str, Any], p: str) -> Cell:
    """-3 dB cell: the frequency when measured, else the bound in words."""
    bw = _lookup(doc, p)
    if bw is None:
        return ''
    if bw['minus_3db_bound'] == 'measured':
        return Num(p + '/minus_3db_hz', '.3g')
    return '< band' if bw['minus_3db_bound'] == 'below' else '> band'


def _yardstick_table(doc: dict[str, Any], parts: tuple[str, ...], title: str) -> Table:
    """Per axis: the noise floor, the residual drift over it and over poly3's."""
    yard = _lookup(doc, pointer(*parts)) or {}
    kind = ("the test run's own noise" if yard.get('floor') == 'noise' else
            "the run's white-noise level, ARW / sqrt(60 s)")
    rows = []
    for a, axis in enumerate(AXES):
        poly3: Cell = (Num(pointer(*parts, 'over_poly3', a), '.3g')
                       if yard.get('over_poly3') else 'n/a')
        rows.append((axis, Num(pointer(*parts, 'floor_deg_s', a), '.4g'),
                     Num(pointer(*parts, 'over_floor', a), '.3g'), poly3))
    return Table(f'{title}: residual drift against the noise floor ({kind}) and poly3',
                 ('Axis', 'Noise floor (deg/s)', 'x noise floor', 'x poly3'), tuple(rows))


def _ranking_table(doc: dict[str, Any]) -> list[Table]:
    """Rank the methods by their mean residual drift over the noise floor (compare.json)."""
    if not doc.get('ranking'):
        return []
    rows = tuple((r['method'], Num(pointer('ranking', i, 'mean_over_floor'), '.3g'),
                  Num(pointer('ranking', i, 'mean_over_poly3'), '.3g')
                  if r.get('mean_over_poly3') is not None else 'n/a',
                  'yes' if r['live_capable'] else 'no')
                 for i, r in enumerate(doc['ranking']))
    return [Table('The methods, best first: residual drift over the noise floor (mean over the '
                  'axes; 1 is what a perfect drift model would leave) and over poly3',
                  ('Method', 'x noise floor', 'x poly3', 'Live-capable'), rows)]


def _raw_table(doc: dict[str, Any]) -> list[Table]:
    """Tabulate the test run's own numbers, before any method (compare.json)."""
    first = next(iter(doc['methods']), None)
    if first is None:
        return []
    base = ('methods', first, 'axes')
    raw = tuple((axis, Num(pointer(*base, axis, 'raw', 'arw_deg_sqrt_h'), '.4g'),
                 _bias_stability(doc, pointer(*base, axis, 'raw')),
                 Num(pointer(*base, axis, 'raw', 'residual_drift_deg_s'), '.4g'))
                for axis in doc['methods'][first]['axes'])
    return [Table('The test run before any method (raw input)',
                  ('Axis', 'ARW (deg/sqrt(h))', 'Bias stability (deg/h)',
                   'Residual drift (deg/s)'), raw)]


def _lookup(doc: dict[str, Any], p: str) -> Any:
    from .page import resolve_pointer

    try:
        return resolve_pointer(doc, p)
    except KeyError:
        return None


def _allan_figures(curves_by_label: Mapping[str, Mapping[str, Sequence[ArrayLike]]],
                   title: str) -> list[tuple[str, 'figure']]:
    """One Allan figure per axis: ``{label: {axis: (tau_s, adev_rad_s)}}`` in deg/h."""
    figures: list[tuple[str, figure]] = []
    for axis in AXES:
        curves = []
        for label, per_axis in curves_by_label.items():
            if axis not in per_axis:
                continue
            tau, adev = (np.asarray(v, dtype=np.float64) for v in per_axis[axis])
            nan = np.full(tau.shape, np.nan)
            curves.append({'name': label, 'tau_s': tau, 'adev': adev * _DEG_H, 'ci_low': nan,
                           'ci_high': nan})
        if curves:
            figures.append((f'Allan deviation, axis {axis}: {title}. Hover a point for tau and '
                            'the deviation.',
                            allan_figure(curves, title=f'Allan deviation, axis {axis}',
                                         unit='deg/h')))
    return figures


def _window_means(t_s: ArrayLike, x: ArrayLike,
                  window_s: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    t_s = np.asarray(t_s, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    n = int(round(window_s / np.median(np.diff(t_s)))) if t_s.size > 1 else 0
    k = x.shape[0] // n if n >= 1 else 0
    if k < 1:
        return np.zeros(0), np.zeros((0,) + x.shape[1:])
    tm = t_s[:k * n].reshape(k, n).mean(axis=1)
    return tm, x[:k * n].reshape((k, n) + x.shape[1:]).mean(axis=1)


def _residual_figure(run: Any, processed: NDArray[np.float64],
                     label: str) -> list[tuple[str, 'figure']]:
    tm, raw = _window_means(run.t_s, run.gyro_rad_s, DRIFT_WINDOW_S)
    _, proc = _window_means(run.t_s, processed, DRIFT_WINDOW_S)
    if tm.size < 2:
        return []
    clock = time_unit(float(tm[-1] - run.t_s[0]))
    when = (tm - run.t_s[0]) * clock.per_si
    series = []
    for a, axis in enumerate(AXES):
        series.append((f'{axis} raw', when, raw[:, a] * _DEG))
        series.append((f'{axis} residual ({label})', when, proc[:, a] * _DEG))
    return [(f'Thermal residuals: {DRIFT_WINDOW_S:g}-s means of the raw and of the processed '
             f'output ({label}); the residual drift of the tables is the standard deviation of '
             'the processed means.',
             series_figure(series, title='Raw output and residual after compensation',
                           x_label=f'time from the first sample ({clock.unit})',
                           y_label='60-s mean of the angular rate (deg/s)'))]


def _axis_rows(doc: dict[str, Any], base: str) -> list[tuple[Cell, ...]]:
    rows: list[tuple[Cell, ...]] = []
    for axis in doc_axes(doc, base):
        p = f'{base}/axes/{axis}'
        rows.append((axis, Num(p + '/raw/arw_deg_sqrt_h', '.4g'),
                     Num(p + '/processed/arw_deg_sqrt_h', '.4g'),
                     Num(p + '/noise_path/arw_gain', '.3g')
                     if _lookup(doc, p + '/noise_path/arw_gain') is not None else 'n/a',
                     _bias_stability(doc, p + '/raw'), _bias_stability(doc, p + '/processed'),
                     Num(p + '/raw/residual_drift_deg_s', '.4g'),
                     Num(p + '/processed/residual_drift_deg_s', '.4g'),
                     _bandwidth(doc, p + '/bandwidth'),
                     Num(p + '/bandwidth/step_delay_50_s', '.3g'),
                     Num(p + '/verdict/live_capable')))
    return rows


def doc_axes(doc: dict[str, Any], base: str) -> list[str]:
    """Return the axes of the block at ``base`` (a JSON Pointer) of ``doc``."""
    return list((_lookup(doc, base + '/axes') or {}).keys())


_AXIS_COLUMNS = ('Axis', 'ARW raw (deg/sqrt(h))', 'ARW processed (deg/sqrt(h))',
                 'ARW gain, noise path', 'Bias stability raw (deg/h)',
                 'Bias stability processed (deg/h)', 'Residual drift raw (deg/s)',
                 'Residual drift processed (deg/s)', '-3 dB, 1 deg/s motion (Hz)',
                 'Step delay 50 % (s)', 'Live-capable')


def _definitions_md(doc: dict[str, Any]) -> str:
    return '\n'.join(f'* `{k}`: {v}' for k, v in (doc.get('definitions') or {}).items())


def compare_page(doc: dict[str, Any], curves: Mapping[str, Any]) -> Page:
    """
    Build the page of ``gyro_noise_thermal compare``.

    Parameters
    ----------
    doc : dict
        The compare.json document.
    curves : dict
        Per method, per axis the scoring's Allan curves (``allan_raw``, ``allan_processed``:
        tau_s, adev_rad_s).

    Returns
    -------
    Page

    """
    best = doc['best_held_out']
    short = ['## In short', '',
             f'Best held-out ({best["rule"]}): **{best["method"]}**.', '']
    if doc.get('ranking'):
        short += ['Ranked by the mean residual drift over the noise floor: '
                  + ', '.join(f'{i + 1}. {r["method"]}' for i, r in enumerate(doc['ranking']))
                  + '.', '']
    short += [f'* **Warning: {w}.**' for w in doc.get('warnings') or ()]
    short += [f'* **Note: {n}.**' for n in doc.get('notes') or ()]
    short += [f'* **{name}** {axis}: {v["verdict"]["text"]}'
              for name, m in doc['methods'].items() for axis, v in m['axes'].items()]
    if doc.get('errors'):
        short += ['', 'Not scored:', ''] + [f'* {k}: {v}' for k, v in doc['errors'].items()]
    tables = _ranking_table(doc) + _raw_table(doc)
    card = len(tables)
    for name in doc['methods']:
        tables.append(Table(f'{name}, trained on the training run, scored on the test run',
                            _AXIS_COLUMNS, tuple(_axis_rows(doc, pointer('methods', name)))))
        if doc['methods'][name].get('yardstick'):
            tables.append(_yardstick_table(doc, ('methods', name, 'yardstick'), name))
    if doc.get('oracle'):
        tables.append(Table(
            "Oracle: least squares on the simulator's own drift terms",
            ('Terms', 'Axis', 'Residual drift (deg/s)'),
            tuple((key.replace('_', ' '), axis, Num(pointer('oracle', key, 'axes', axis), '.4g'))
                  for key in ('true_terms', 'measured_terms')
                  for axis in doc['oracle'][key]['axes'])))
    tables.append(Table('Outside the trained range', ('Method', 'Samples outside',
                                                      'Of samples', 'Fraction'),
                        tuple((name, Num(pointer('methods', name, 'range', 'outside'), 'd'),
                               Num(pointer('methods', name, 'range', 'samples'), 'd'),
                               Num(pointer('methods', name, 'range', 'fraction_outside'),
                                   '.2%')) for name in doc['methods'])))
    allan: dict[str, dict[str, Any]] = {}
    if curves:
        firstc = next(iter(curves.values()))
        allan['raw'] = {axis: c['allan_raw'] for axis, c in firstc.items()}
        for name, cur in curves.items():
            allan[name] = {axis: c['allan_processed'] for axis, c in cur.items()}
    figures = _allan_figures(allan, 'every method on the held-out test run')
    method = ('Every method is trained on the training run and scored on the test run it never '
              'saw (app/thermal.py, docs/thermal.md): ARW and bias stability from the Allan '
              'deviation of the output, residual drift the standard deviation of its 60-s '
              'means, the bandwidth cost from a chirp and steps injected into the run.\n\n'
              'Definitions:\n\n' + _definitions_md(doc))
    inputs = [s.split(' [')[0] for s in (doc.get('train'), doc.get('test')) if s]
    return Page(title=f'gyro_noise_thermal compare: {doc["test"]}', data=doc,
                in_short_markdown='\n'.join(short), figures=tuple(figures),
                verdict=Verdict(*compare_verdict(doc)), card=tuple(tables[:card]),
                card_title='The methods ranked, and the raw run',
                tables=tuple(tables[card:]), method_markdown=method, command=doc.get('command'),
                inputs=tuple(dict.fromkeys(inputs)), version=doc.get('package_version', ''))


def apply_page(doc: dict[str, Any], run: Any, processed: NDArray[np.float64],
               curves: Mapping[str, Any] | None) -> Page:
    """
    Build the page of ``gyro_noise_thermal apply``.

    Parameters
    ----------
    doc : dict
        The metrics.json document.
    run : ThermalRun
        The run the model was applied to (``t_s``, ``gyro_rad_s``).
    processed : numpy.ndarray
        The method's output (n, 3), rad/s.
    curves : dict or None
        Per axis the scoring's Allan curves (``allan_raw``, ``allan_processed``).

    Returns
    -------
    Page

    """
    short = ['## In short', '']
    if doc['in_sample']:
        short += ['**Warning: this bag is one the model was trained on; the numbers are '
                  'in-sample and flatter the method.**', '']
    short += [f'* **Warning: {warning}.**' for warning in doc.get('warnings') or ()]
    short += [f'* **Note: {note}.**' for note in doc.get('notes') or ()]
    short += [f'* **{axis}**: {v["verdict"]["text"]}' for axis, v in doc['axes'].items()]
    tables = [Table(f'{doc["method"]} on the run', _AXIS_COLUMNS, tuple(_axis_rows(doc, '')))]
    if doc.get('yardstick'):
        tables.append(_yardstick_table(doc, ('yardstick',), doc['method']))
    card = len(tables)
    tables.append(Table('Trained range and this run', ('Quantity', 'Value'), (
        ('Samples outside the trained range', Num('/range/outside', 'd')),
        ('Samples', Num('/range/samples', 'd')),
        ('Fraction outside', Num('/range/fraction_outside', '.2%')),
        ('Treatment there', Num('/range/treatment')))))
    if doc.get('accel'):
        tables.append(Table('Accelerometer', ('Axis', 'Raw residual drift (mg)',
                                              'Compensated residual drift (mg)'),
                            tuple((axis, Num(pointer('accel', 'axes', axis,
                                                     'raw_residual_drift_mg'), '.4g'),
                                   Num(pointer('accel', 'axes', axis,
                                               'processed_residual_drift_mg'), '.4g'))
                                  for axis in doc['accel']['axes'])))
    figures = _residual_figure(run, processed, doc['method'])
    curves = curves or {}
    allan = {'raw': {a: c['allan_raw'] for a, c in curves.items()},
             doc['method']: {a: c['allan_processed'] for a, c in curves.items()}}
    figures += _allan_figures(allan, f'raw and {doc["method"]}') if curves else []
    method = ('The model of `gyro_noise_thermal fit` applied to this run (app/thermal.py, '
              'docs/thermal.md): ARW and bias stability from the Allan deviation of the output, '
              'residual drift the standard deviation of its 60-s means, the bandwidth cost from a '
              'chirp and steps injected into the run.\n\nDefinitions:\n\n'
              + _definitions_md(doc))
    return Page(title=f'gyro_noise_thermal apply: {doc["method"]} on {doc["bag"]}', data=doc,
                in_short_markdown='\n'.join(short), figures=tuple(figures),
                verdict=Verdict(*apply_verdict(doc)), card=tuple(tables[:card]),
                card_title='The method on this run, against the noise floor and poly3',
                tables=tuple(tables[card:]), method_markdown=method, command=doc.get('command'),
                inputs=(doc['bag'], doc['model']['path']),
                version=doc.get('package_version', ''))


def write_compare_html(doc: dict[str, Any], curves: Mapping[str, Any], out: Path) -> Path:
    """
    Write ``report.html`` of a comparison into the staged folder ``out``; return its path.

    ``doc`` (the compare.json document) and ``curves`` are those of :func:`compare_page`.

    """
    return write_report_html(compare_page(doc, curves), out / 'report.html')


def write_apply_html(doc: dict[str, Any], run: Any, processed: NDArray[np.float64],
                     curves: Mapping[str, Any] | None, out: Path) -> Path:
    """
    Write ``report.html`` of an applied model into the staged folder ``out``; return its path.

    ``doc`` (the metrics.json document), ``run``, ``processed`` and ``curves`` are those of
    :func:`apply_page`.

    """
    return write_report_html(apply_page(doc, run, processed, curves), out / 'report.html')
