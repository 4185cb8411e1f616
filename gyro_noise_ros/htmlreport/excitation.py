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
The ``report.html`` of ``gyro_noise_excitation``.

Built from the excitation.json document (SI) and the records held in memory (time and excited
channel of each side); the tables show excitation.md's units (mg or deg/s, %) through
:class:`.page.Num`'s ``scale``. The verdict line says whether any check flags a defect (ERROR:
significant and beyond the practical tolerance); the card holds each record's frequency,
amplitude and verdicts worded as excitation.md words them
(:func:`..calibration.excitation_report.check_parts`).
"""

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .figures import series_figure
from .page import Num, Page, plus_minus_cell, pointer, Table, Verdict, write_report_html
from ..calibration.excitation_report import (check_parts, checks_of, display_unit, sides_of,
                                             verdict_rule, what_of)

if TYPE_CHECKING:
    from bokeh.plotting import figure

#: ``{side: (t_s, x)}``: each record's time (s) and excited channel (SI).
_Records = Mapping[str, tuple[NDArray[np.float64], NDArray[np.float64]]]


def excitation_page(doc: dict[str, Any], records: _Records,
                    command: Sequence[str] | None = None) -> Page:
    """
    Build the page of one excitation check.

    Parameters
    ----------
    doc : dict
        The excitation.json document.
    records : dict
        ``{side: (t_s, x)}`` of each record (s, SI), for the figures.
    command : sequence of str, optional
        The command line.

    Returns
    -------
    Page

    """
    sides = sides_of(doc)
    what = what_of(doc)
    tables = (_dwell_tables(doc, sides, what) if doc['mode'] == 'dwell'
              else _sweep_tables(doc, sides))
    method = (f'Excitation check (paper 001 section 5.3): {what}. A dwell is fitted cycle by '
              'cycle (frequency, amplitude, offset, harmonics); a sweep is binned by the '
              'instantaneous frequency and compared with the reference record when one is '
              'given (docs/reliability.md).')
    return Page(title=f'gyro_noise_excitation: {what}', data=doc,
                in_short_markdown=_in_short(doc, sides), verdict=_verdict(doc, sides),
                card=(_card(doc, sides),), card_title='The checks',
                figures=tuple(_figures(doc, records, sides)),
                tables=tuple(tables), method_markdown=method,
                command=None if command is None else tuple(command),
                inputs=tuple(doc[s]['source'] for s in sides), version=doc.get('version', ''))


def _in_short(doc: dict[str, Any], sides: list[str]) -> str:
    """Return "In short": how the verdicts are made (the card above holds them)."""
    return '\n'.join(['## In short', '', verdict_rule(doc)])


def _verdict(doc: dict[str, Any], sides: list[str]) -> Verdict:
    """Return the verdict line: ERROR when a check flags a defect, INFO when none could run."""
    flagged, judged = [], 0
    for s in sides:
        for check in checks_of(doc):
            ok = doc[s].get(check[0])
            judged += ok is not None
            if ok is False:
                flagged.append(f'{s}: {check[2]}')
    what = f'{doc["sensor"]} {doc["axis"]}, {what_of(doc)}'
    if flagged:
        return Verdict('ERROR', f'{what}: ' + '; '.join(flagged)
                       + ' (significant and beyond the practical tolerance; the card says by how '
                       'much).')
    if not judged:
        return Verdict('INFO', f'{what}: analysed, nothing to judge (a sweep needs the '
                       "reference sensor's record for its verdicts).")
    names = ' and '.join(c[1] for c in checks_of(doc))
    return Verdict('OK', f'{what}: every record {names} (no defect both significant and '
                   'beyond the practical tolerance).')


def _card(doc: dict[str, Any], sides: list[str]) -> Table:
    """Return each record's frequency, amplitude and verdicts: the first screen."""
    k, unit = display_unit(doc['sensor'])
    u = doc['unit']
    checks = checks_of(doc)
    cells: list[tuple[Any, ...]]
    if doc['mode'] == 'dwell':
        head = ('Frequency (Hz)', f'Amplitude ({unit})')
        cells = [(Num(pointer(s, 'frequency_hz'), '.5f'),
                  Num(pointer(s, f'amplitude_{u}'), '.5g', scale=k)) for s in sides]
    else:
        head = ('Frequency covered, 5th-95th percentile (Hz)', 'Mean deviation from the reference')
        cells = [((Num(pointer(s, 'frequency_range_hz', 0), '.3f'), ' to ',
                   Num(pointer(s, 'frequency_range_hz', 1), '.3f')),
                  (Num(pointer(s, 'mean_deviation'), '+.3f', scale=100.0), ' %')
                  if doc[s].get('mean_deviation') is not None else 'no reference')
                 for s in sides]
    return Table('', ('Record', *head, *(f'{c[5].capitalize()} verdict' for c in checks)),
                 tuple((s, *cells[i], *(check_parts(doc, s, c) for c in checks))
                       for i, s in enumerate(sides)))


def _dwell_tables(doc: dict[str, Any], sides: list[str], what: str) -> list[Table]:
    """Return the dwell's quantities per side and, with two sides, the change after / before."""
    k, unit = display_unit(doc['sensor'])
    u = doc['unit']
    rows = [
        ('Frequency (Hz)', 'frequency_hz', '.5f', 1.0),
        ('Frequency sigma (Hz)', 'frequency_sigma_hz', '.1e', 1.0),
        (f'Amplitude ({unit})', f'amplitude_{u}', '.5g', k),
        (f'Amplitude sigma ({unit})', f'amplitude_sigma_{u}', '.2g', k),
        (f'Offset ({unit})', f'offset_{u}', '.5g', k),
        (f'Per-cycle amplitude mean ({unit})', f'cycle_amplitude_mean_{u}', '.5g', k),
        (f'Per-cycle amplitude min ({unit})', f'cycle_amplitude_min_{u}', '.5g', k),
        (f'Per-cycle amplitude max ({unit})', f'cycle_amplitude_max_{u}', '.5g', k),
        ('Amplitude stability (std / mean of the cycles, %)', 'amplitude_stability', '.3f',
         100.0),
        ('Stability from noise alone (%)', 'amplitude_stability_noise', '.3f', 100.0),
        ('Stability test p', 'stability_p', '.2g', 1.0),
        ('THD, harmonics over the fundamental (%)', 'thd', '.3f', 100.0),
        ('THD from noise alone (%)', 'thd_noise', '.3f', 100.0),
        ('Distortion test p', 'distortion_p', '.2g', 1.0),
        ('Excited span start (s)', 'start_s', '.2f', 1.0),
        ('Excited span duration (s)', 'duration_s', '.2f', 1.0),
        ('Cycles', 'cycles', 'd', 1.0)]
    tables = [Table(f'Excitation check: {what}, {doc["sensor"]} {doc["axis"]}',
                    ('Quantity', *sides),
                    tuple((label, *(Num(pointer(s, key), fmt, scale=scale)
                                    for s in sides))
                          for label, key, fmt, scale in rows))]
    if 'change' in doc:
        tables.append(Table('After / before', ('Quantity', 'Change'), (
            ('Amplitude (%)', plus_minus_cell('/change/amplitude_relative',
                                              '/change/amplitude_relative_sigma', '.3f', 100.0)),
            ('Amplitude change p', Num('/change/amplitude_change_p', '.2g')),
            ('Amplitude change significant', Num('/change/amplitude_change_significant')),
            ('Frequency (Hz)', Num('/change/frequency_hz', '+.5f')),
            ('Amplitude stability (percentage points)',
             Num('/change/amplitude_stability', '+.3f', scale=100.0)),
            ('THD (percentage points)', Num('/change/thd', '+.3f', scale=100.0)))))
    return tables


def _sweep_tables(doc: dict[str, Any], sides: list[str]) -> list[Table]:
    """Return each side's amplitude per frequency bin (with the reference when there is one)."""
    k, unit = display_unit(doc['sensor'])
    u = doc['unit']
    tables: list[Table] = []
    for s in sides:
        cols = [('Rising', f'amplitude_up_{u}', k, '.5g'),
                ('Falling', f'amplitude_down_{u}', k, '.5g')]
        if doc[s].get(f'reference_up_{u}') is not None:
            cols += [('Reference rising', f'reference_up_{u}', k, '.5g'),
                     ('Reference falling', f'reference_down_{u}', k, '.5g'),
                     ('Deviation rising (%)', 'deviation_up', 100.0, '.3f'),
                     ('Deviation falling (%)', 'deviation_down', 100.0, '.3f')]
        tables.append(Table(
            f'{s}: amplitude per frequency bin ({unit})',
            ('f (Hz)', *(c[0] for c in cols)),
            tuple((Num(pointer(s, 'bin_hz', i), '.3f'),
                   *(Num(pointer(s, key, i), fmt, scale=scale)
                     for _, key, scale, fmt in cols))
                  for i in range(len(doc[s]['bin_hz'])))))
    return tables


def _figures(doc: dict[str, Any], records: _Records,
             sides: list[str]) -> list[tuple[str, 'figure']]:
    """Return the whole acquisition and, for a sweep, the amplitude against frequency."""
    k, unit = display_unit(doc['sensor'])
    what = f'{doc["sensor"]} {doc["axis"]}'
    figures: list[tuple[str, figure]] = []
    series = [(s, records[s][0], records[s][1] * k) for s in sides]
    figures.append((f'The whole acquisition of {what} (min/max envelope for display; zoom in '
                    'for the wave form).',
                    series_figure(series, title='Whole acquisition', x_label='time (s)',
                                  y_label=f'{what} ({unit})')))
    if doc['mode'] != 'dwell':
        u = doc['unit']
        amp = []
        for s in sides:
            e = doc[s]
            # a null of the document (a value that was not finite) is NaN again
            f, up, down = (np.asarray(e[key], dtype=float)
                           for key in ('bin_hz', f'amplitude_up_{u}', f'amplitude_down_{u}'))
            amp += [(f'{s} rising', f, up * k), (f'{s} falling', f, down * k)]
            if f'reference_up_{u}' in e:
                ref = np.asarray(e[f'reference_up_{u}'], dtype=float)
                amp.append((f'{s} reference', f, ref * k))
        figures.append(('Amplitude against the instantaneous frequency.',
                        series_figure(amp, title='Amplitude against frequency',
                                      x_label='frequency (Hz)', y_label=f'amplitude ({unit})')))
    return figures


def write_excitation_html(doc: dict[str, Any], records: _Records, out: Path, *,
                          command: Sequence[str] | None = None) -> Path:
    """
    Write ``report.html`` of an excitation check into the staged folder ``out``; return its path.

    ``doc`` (the excitation.json document), ``records`` (``{side: (t_s, x)}``, s and SI) and
    ``command`` (the command line) are those of :func:`excitation_page`.

    """
    return write_report_html(excitation_page(doc, records, command), out / 'report.html')
