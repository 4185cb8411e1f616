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
The ``report.html`` of ``gyro_noise_calibrate``.

Built from the calibration.json document alone: the JSON is SI, the tables show calibration.md's
units (mg, %, deg/s) through :class:`.page.Num`'s ``scale``, so each cell is still checked
against the JSON value it came from. The verdict line is the two checks (OK when both hold,
ERROR when one fails); the card holds the calibration (biases and scale factors of both sensors);
the cross-axis terms of both follow in the tables. "In short" words the checks as calibration.md.
"""

from collections.abc import Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

from .figures import series_figure
from .page import Cell, Num, Page, plus_minus_cell, pointer, Table, Verdict, write_report_html
from ..calibration.multipose import gravity_check_words
from ..units import MG_TO_M_S2 as _MG, RAD_TO_DEG as _DEG

if TYPE_CHECKING:
    from bokeh.plotting import figure


def calibrate_page(doc: dict[str, Any]) -> Page:
    """
    Build the page of one calibration.

    Parameters
    ----------
    doc : dict
        The calibration.json document.

    Returns
    -------
    Page

    """
    title = ('Six-position calibration (paper 001 Table 6 layout)'
             if doc['mode'] == 'six-position' else 'Multi-pose calibration (|a| = g, imu_tk)')
    accel, accel_cross = _accelerometer_tables()
    card = (accel, _gyro_table(doc))
    tables = [accel_cross, *_gyro_cross_table(doc), *_check_tables(doc), _dwell_table(doc)]
    method = (f'{title}. Model: `{doc["model"]}`; frame: {doc["frame"]}. Gravity used: '
              f'{doc["gravity_source"]} (the value is in calibration.json). Dwells are found by '
              'the static detector (its settings are in calibration.json); the gyro scale factor '
              'and misalignment come from integrating the turns between static poses.')
    return Page(title=f'gyro_noise_calibrate: {title}', data=doc,
                in_short_markdown=_in_short(doc), verdict=_verdict(doc), card=card,
                card_title='The calibration', figures=tuple(_figures(doc)),
                tables=tuple(tables), method_markdown=method, command=None,
                inputs=tuple(doc['sources']), version=doc.get('version', ''))


def _in_short(doc: dict[str, Any]) -> str:
    """Return "In short": the two checks and the gyro note, worded as calibration.md words them."""
    gc, cons = doc['gravity_check'], doc['consistency']
    short = ['## In short', '',
             f'* Gravity check (leave-one-out): {gravity_check_words(gc)}.']
    if cons['pairs']:
        short.append('* Consistency of opposite dwells (a tilt cannot pass silently): '
                     f'{"consistent" if cons["consistent"] else "inconsistent"}.')
    if doc['gyro']['note']:
        short.append(f'* Gyro: {doc["gyro"]["note"]}.')
    short += ['', 'Uncertainties: one standard uncertainty, against the value during the '
              'calibration, from the variogram of the dwells (white noise and bias wander '
              'between dwells).']
    return '\n'.join(short)


def _verdict(doc: dict[str, Any]) -> Verdict:
    """Return the verdict line: both checks hold (OK) or which fails (ERROR), and the gyro."""
    gc, cons = doc['gravity_check'], doc['consistency']
    failed = [d['dwell'] for d in gc['dwells'] if not d['consistent']]
    bad = []
    if not gc['consistent']:
        bad.append('the leave-one-out gravity check fails at '
                   + (', '.join(str(f) for f in failed) or 'a dwell'))
    if cons['pairs'] and not cons['consistent']:
        bad.append('opposite dwells disagree (a tilted fixture?)')
    gyro = f' Gyro: {doc["gyro"]["note"]}.' if doc['gyro']['note'] else ''
    if bad:
        return Verdict('ERROR', 'calibration not trustworthy: ' + '; '.join(bad) + '.' + gyro)
    checks = ('gravity check and opposite dwells consistent' if cons['pairs']
              else 'gravity check consistent')
    return Verdict('OK', f'calibrated from {len(doc["dwells"])} dwells: {checks}.' + gyro)


def _accelerometer_tables() -> tuple[Table, Table]:
    """Return the accelerometer's biases and scale factors, and its cross-axis terms."""
    rows: list[tuple[Cell, ...]]
    rows = [(f'b{ax}', plus_minus_cell(pointer('accel', 'bias_m_s2', i),
                                       pointer('accel', 'bias_sigma_m_s2', i), '.4f',
                                       1.0 / _MG), 'mg')
            for i, ax in enumerate('xyz')]
    rows += [(f'S{ax}', plus_minus_cell(pointer('accel', 'scale_factor', i),
                                        pointer('accel', 'scale_factor_sigma', i), '.4f',
                                        100.0), '%')
             for i, ax in enumerate('xyz')]
    mis = []
    for j, ax in enumerate('xyz'):
        mis.append((ax, *('-' if i == j else plus_minus_cell(
            pointer('accel', 'misalignment', j, i), pointer('accel', 'misalignment_sigma', j, i),
            '.4f', 100.0) for i in range(3))))
    return (Table('Accelerometer (paper 001 Table 6 layout)',
                  ('Parameter', 'Value +/- std. uncertainty', 'Unit'), tuple(rows)),
            Table('Accelerometer cross-axis terms (%)', ('Measured axis', 'x', 'y', 'z'),
                  tuple(mis), note='Row = measured axis, column = true axis.'))


def _gyro_cross_table(doc: dict[str, Any]) -> list[Table]:
    """Return the gyro's cross-axis terms (%), each +/- its uncertainty where estimated."""
    gyro = doc['gyro']
    est = gyro.get('estimated') or [[False] * 3] * 3
    rows = []
    for j, ax in enumerate('xyz'):
        cells: list[Cell] = []
        for i in range(3):
            if i == j:
                cells.append('-')
            elif not est[j][i]:
                cells.append('not estimated')
            else:
                cells.append(plus_minus_cell(pointer('gyro', 'misalignment', j, i),
                                             pointer('gyro', 'misalignment_sigma', j, i),
                                             '.4f', 100.0))
        rows.append((ax, *cells))
    note = 'Row = measured axis, column = true axis; from the turns between the dwells.'
    if gyro['note']:
        note += f' {gyro["note"]}.'
    return [Table('Gyro cross-axis terms (%)', ('Measured axis', 'x', 'y', 'z'), tuple(rows),
                  note=note)]


def _gyro_table(doc: dict[str, Any]) -> Table:
    gyro = doc['gyro']
    est = gyro.get('estimated') or [[False] * 3] * 3
    grows = []
    for i, ax in enumerate('xyz'):
        scale: Cell
        scale = (plus_minus_cell(pointer('gyro', 'scale_factor', i),
                                 pointer('gyro', 'scale_factor_sigma', i), '.4f', 100.0)
                 if est[i][i] else 'not estimated')
        bias = plus_minus_cell(pointer('gyro', 'bias_rad_s', i),
                               pointer('gyro', 'bias_sigma_rad_s', i), '.5f', _DEG)
        grows.append((ax, bias, scale))
    return Table('Gyro', ('Axis', 'Bias (deg/s)', 'Scale factor (%)'), tuple(grows))


def _check_tables(doc: dict[str, Any]) -> list[Table]:
    """Return the indicators, the gravity check and, when there are pairs, the consistency."""
    gc, cons = doc['gravity_check'], doc['consistency']
    tables = [Table('Indicators (paper 001 section 6)', ('Indicator', 'Value', 'Unit'), (
        ('Uniformity of the biases (std, ddof = one)',
         Num('/uniformity/accel_bias_std_m_s2', '.4f', scale=1.0 / _MG), 'mg'),
        ('Uniformity of the scale factors (std, ddof = one)',
         Num('/uniformity/accel_scale_factor_std', '.4f', scale=100.0), '%')))]
    tables.append(Table(
        'Gravity check (leave-one-out)',
        ('Dwell', 'abs(a) - g (mg)', 'Sigma (mg)', 'z', 'Consistent'),
        tuple((Num(pointer('gravity_check', 'dwells', k, 'dwell')),
               Num(pointer('gravity_check', 'dwells', k, 'residual_m_s2'), '+.4f',
                   scale=1.0 / _MG),
               Num(pointer('gravity_check', 'dwells', k, 'sigma_m_s2'), '.4f', scale=1.0 / _MG),
               Num(pointer('gravity_check', 'dwells', k, 'z'), '+.2f'),
               Num(pointer('gravity_check', 'dwells', k, 'consistent')))
              for k in range(len(gc['dwells']))),
        note='Each dwell calibrated by the others; |a| - g against its standard deviation.'))
    if cons['pairs']:
        tables.append(Table(
            'Consistency of opposite dwells',
            ('Pair', 'Sigma (mg)', 'p', 'Consistent'),
            tuple((Num(pointer('consistency', 'pairs', k, 'axis'), prefix='+/-'),
                   Num(pointer('consistency', 'pairs', k, 'sigma_m_s2'), '.4f', scale=1.0 / _MG),
                   Num(pointer('consistency', 'pairs', k, 'p_value'), '.3g'),
                   Num(pointer('consistency', 'pairs', k, 'consistent')))
                  for k in range(len(cons['pairs'])))))
    return tables


def _dwell_table(doc: dict[str, Any]) -> Table:
    return Table(
        'Dwells', ('Dwell', 'Start (s)', 'Duration (s)', 'Samples', 'NaN/Inf dropped',
                   'Tilt (deg)', 'Recording'),
        tuple((Num(pointer('dwells', k, 'orientation')),
               Num(pointer('dwells', k, 't_start_s'), '.2f'),
               Num(pointer('dwells', k, 'duration_s'), '.2f'),
               Num(pointer('dwells', k, 'samples'), 'd'),
               Num(pointer('dwells', k, 'non_finite_samples'), 'd'),
               Num(pointer('dwells', k, 'tilt_deg'), '.2f'),
               Num(pointer('dwells', k, 'source'))) for k in range(len(doc['dwells']))))


def _figures(doc: dict[str, Any]) -> list[tuple[str, 'figure']]:
    """Return the leave-one-out gravity check per dwell (none without dwells)."""
    gc = doc['gravity_check']
    figures: list[tuple[str, figure]] = []
    if gc['dwells']:
        k = list(range(len(gc['dwells'])))
        figures.append((
            'Leave-one-out gravity check per dwell: |a| - g of each dwell calibrated by the '
            'others, and its standard deviation (the check fails where the residual leaves '
            'a few sigma).',
            series_figure([('abs(a) - g', k, [d['residual_m_s2'] / _MG for d in gc['dwells']]),
                           ('sigma', k, [d['sigma_m_s2'] / _MG for d in gc['dwells']])],
                          title='Gravity check per dwell', x_label='dwell number (in order)',
                          y_label='acceleration (mg)')))
    return figures


def write_calibrate_html(doc: dict[str, Any], out: Path, *,
                         command: Sequence[str] | None = None) -> Path:
    """
    Write ``report.html`` of a calibration into the staged folder ``out``.

    Parameters
    ----------
    doc : dict
        The calibration.json document.
    out : pathlib.Path
        The staged ``--out`` folder.
    command : sequence of str, optional, keyword-only
        The command line (calibration.json does not record it).

    Returns
    -------
    pathlib.Path

    """
    from dataclasses import replace

    page = calibrate_page(doc)
    if command is not None:
        page = replace(page, command=tuple(command))
    return write_report_html(page, out / 'report.html')
