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
What a person reads first of an analysis: the verdict line and the datasheet card.

Both are made from the summary.json document alone and shared by summary.md and report.html:
:func:`verdict` (OK / WARN / ERROR and why), :func:`card_tables` (per bag, one row per gyro and
accelerometer axis: white noise N, bias stability and B, random walk K, each with its interval,
in the customary unit of :mod:`..units` and in SI beside it) and :func:`card_markdown`. A cell is
made of :class:`..formatting.Num` parts (pointers into the document), never of copied numbers.
The rules of the verdict are in ``docs/offline_tool.md`` ("The verdict line").
"""

from collections.abc import Mapping, Sequence
from typing import Any

from ..core.readout import B_FACTOR
from ..formatting import Aside, cell_text, fmt_or_na, Num, pointer, Unit
from ..units import (ACCEL, ACCEL_ADEV, ACCEL_RW, ACCEL_VRW, GYRO_ADEV, GYRO_ARW, GYRO_RRW)

__all__ = ['CARD_COLUMNS', 'card_markdown', 'card_tables', 'verdict']

#: Column headers of the card.
CARD_COLUMNS = ('Sensor, axis', 'White noise N (ARW, VRW)', 'Bias stability',
                'B = bias stability / 0.664', 'Random walk K (RRW, acceleration RW)')

#: The data-quality counters of a bag that make the verdict WARN, and how each is said.
_QUALITY = (('samples_lost', '{} sample(s) lost in {} gap(s)'),
            ('out_of_order_stamps', '{} out-of-order stamp(s)'),
            ('undecodable_messages', '{} undecodable message(s)'))


def _duration(seconds: float | None) -> str:
    """Return a record's length: ``655.1 s``, ``10000 s (2.78 h)``, never ``1e+04 s``."""
    if seconds is None:
        return 'n/a s'
    text = f'{seconds:.4g} s' if seconds < 1000 else f'{seconds:.0f} s'
    return text + (f' ({seconds / 3600:.3g} h)' if seconds >= 3600 else '')


def _bag_problems(b: Mapping[str, Any]) -> tuple[list[str], list[str]]:
    """Return one bag's (errors, warnings) as sentences."""
    errors: list[str] = []
    warns: list[str] = []
    label = b['label']
    for key, text in _QUALITY:
        if b.get(key):
            warns.append(f'{label}: ' + text.format(b[key], b.get('gaps', 0)))
    physical = sum((b.get('non_physical_values') or {}).values())
    if physical:
        warns.append(f'{label}: {physical} non-physical value(s) treated as NaN')
    for axis, a in b['axes'].items():
        bad = (a.get('chunks_nan') or 0) + (a.get('chunks_dropped') or 0) + (
            a.get('chunks_failed') or 0)
        if bad:
            warns.append(f'{label} {axis}: {bad} chunk(s) left out (NaN, loss or not '
                         'identifiable)')
        health = a.get('health')
        if health and health['level'] in ('ERROR', 'WARN'):
            (errors if health['level'] == 'ERROR' else warns).append(
                f"{label} {axis} against the reference: {health['message'].rstrip('.')}")
    return errors, warns


def _notes(doc: Mapping[str, Any]) -> list[str]:
    """Return what limits the numbers without being a fault (said after the level)."""
    notes = []
    bound = {b['label']: [axis for axis, a in b['axes'].items()
                          if (a.get('allan_datasheet') or {}).get('bias_stability_upper_bound')]
             for b in doc['bags']}
    lengths = ', '.join(_duration(b.get('duration_s')) for b in doc['bags']
                        if bound[b['label']])
    every = all(len(v) == len(b['axes']) for v, b in zip(bound.values(), doc['bags']))
    if every and all(bound.values()):
        notes.append('bias stability is only an upper bound on every axis: the Allan curve had '
                     f'not turned up by the end of the record ({lengths})')
    elif any(bound.values()):
        several = len(bound) > 1
        places = [(label + ('' if len(axes) == len(b['axes']) else f" ({', '.join(axes)})"))
                  if several else ', '.join(axes)
                  for (label, axes), b in zip(bound.items(), doc['bags']) if axes]
        where = ' and '.join(places) if len(places) <= 2 else ', '.join(places)
        notes.append(f'bias stability is only an upper bound on {where}: the Allan curve had '
                     f'not turned up by the end of the record ({lengths})')
    for b in doc['bags']:
        if b.get('allan_only'):
            notes.append(f"{b['label']}: Allan deviation only (shorter than one chunk: no "
                         'fractional order, no chunk statistics)')
    return notes


def verdict(doc: Mapping[str, Any]) -> tuple[str, str]:
    """
    Return the verdict line of an analysis: the level and why.

    ERROR when an axis' health verdict against a ``--reference`` is ERROR; WARN when one is
    WARN or a bag lost samples, had out-of-order stamps, undecodable messages, non-physical
    values, or chunks left out; else OK. What limits the numbers without being a fault (a bias
    stability that is only an upper bound, an Allan-only analysis) follows the level.

    Parameters
    ----------
    doc : dict
        The summary.json document.

    Returns
    -------
    tuple of str
        ``(level, text)``: level 'OK', 'WARN' or 'ERROR'; text in plain words (Markdown subset).

    """
    errors: list[str] = []
    warns: list[str] = []
    for b in doc['bags']:
        e, w = _bag_problems(b)
        errors += e
        warns += w
    level = 'ERROR' if errors else 'WARN' if warns else 'OK'
    bags = doc['bags']
    what = (f'{len(bags)} recordings' if len(bags) > 1 else
            f"{bags[0]['label']}, {_duration(bags[0].get('duration_s'))} at "
            f"{fmt_or_na(bags[0].get('rate_hz'), '.5g')} Hz")
    axes = sorted({a for b in bags for a in b['axes']})
    accel = any(b.get('accelerometer_allan') for b in bags)
    head = (f"gyro{' and accelerometer' if accel else ''} axes {', '.join(axes)} "
            f'characterised ({what})')
    reasons = errors + warns
    if reasons:
        shown = reasons[:3] + ([f'{len(reasons) - 3} more in the tables'] if len(reasons) > 3
                               else [])
        text = f"{head}; {'; '.join(shown)}."
    else:
        reference = any('health' in a for b in bags for a in b['axes'].values())
        text = (f'{head}; no sample lost'
                + ('; no axis differs from the reference.' if reference else '.'))
    notes = _notes(doc)
    if notes:
        text += ' Note: ' + '; '.join(notes) + '.'
    return level, text


def _interval(lo: str, hi: str, scale: float = 1.0) -> tuple[Any, ...]:
    return (' (', Num(lo, '.3g', scale=scale), ' to ', Num(hi, '.3g', scale=scale), ') ')


def _si(*parts: Any) -> Aside:
    return Aside(parts)


def _gyro_row(axis: str, q: str, d: Mapping[str, Any]) -> tuple[Any, ...]:
    """One gyro axis of the card (``q``: pointer of its ``allan_datasheet``)."""
    bound = '<= ' if d.get('bias_stability_upper_bound') else ''
    lo, hi = q + '/bias_stability_ci_low_deg_h', q + '/bias_stability_ci_high_deg_h'
    n = (Num(q + '/arw_deg_per_sqrt_h', '.3g'),
         *_interval(q + '/arw_ci_low_deg_per_sqrt_h', q + '/arw_ci_high_deg_per_sqrt_h'),
         Unit(GYRO_ARW.unit),
         _si(Num(q + '/arw_rad_per_sqrt_s', '.3g'), ' ', Unit('rad/s/sqrt(Hz)'),
             '' if d.get('arw_from_region') else '; read at one second: no white-noise region'))
    stab = (Num(q + '/bias_stability_deg_h', '.3g', bound), *_interval(lo, hi),
            Unit(GYRO_ADEV.unit),
            _si('at ', Num(q + '/bias_stability_tau_s', '.4g'), ' s; ',
                Num(q + '/bias_stability_rad_s', '.3g', bound), ' ', Unit('rad/s')))
    b = (Num(q + '/bias_instability_deg_h', '.3g', bound), *_interval(lo, hi, 1.0 / B_FACTOR),
         Unit(GYRO_ADEV.unit),
         _si(Num(q + '/bias_instability_rad_s', '.3g', bound), ' ', Unit('rad/s')))
    k = _k_cell(d.get('rate_random_walk_resolved'), d.get('bias_stability_upper_bound'),
                (q + '/rate_random_walk_deg_per_h_sqrt_h',
                 q + '/rate_random_walk_rad_per_s_sqrt_s'),
                (q + '/rate_random_walk_bound_deg_per_h_sqrt_h',
                 q + '/rate_random_walk_bound_rad_per_s_sqrt_s'),
                (1.0, GYRO_RRW.unit, 'rad/s^2/sqrt(Hz)'))
    return (f'gyro {axis}', n, stab, b, k)


def _k_cell(resolved: bool | None, never_turned: bool | None, fit: tuple[str, str],
            bound: tuple[str, str], units: tuple[float, str, str]) -> tuple[Any, ...]:
    """Return the random-walk cell: the fitted K when resolved, else its bound and why."""
    scale, unit, si_unit = units
    if resolved:
        return (Num(fit[0], '.3g', scale=scale), ' ', Unit(unit), ' fitted',
                _si(Num(fit[1], '.3g'), ' ', Unit(si_unit)))
    why = ('the curve never turned up' if never_turned
           else 'no random-walk slope resolved in the record')
    return (Num(bound[0], '.3g', '<= ', scale=scale), ' ', Unit(unit), ' bound',
            _si(Num(bound[1], '.3g', '<= '), ' ', Unit(si_unit), f'; {why}'))


def _accel_row(axis: str, r: str, e: Mapping[str, Any]) -> tuple[Any, ...]:
    """One accelerometer axis (``r``: pointer of its ``accelerometer_allan`` entry, SI)."""
    bound = '<= ' if e.get('bias_stability_upper_bound') else ''
    vrw = r + '/velocity_random_walk'
    n = (Num(vrw + '_m_s2_per_sqrt_hz', '.3g', scale=ACCEL_VRW.per_si),
         *_interval(vrw + '_ci_low_m_s2_per_sqrt_hz', vrw + '_ci_high_m_s2_per_sqrt_hz',
                    ACCEL_VRW.per_si),
         Unit(ACCEL_VRW.unit),
         _si(Num(vrw + '_m_s2_per_sqrt_hz', '.3g'), ' ', Unit('m/s^2/sqrt(Hz)'),
             '' if e.get('velocity_random_walk_from_region') else
             '; read at one second: no white-noise region'))
    ci = ((r + '/bias_stability_ci_low_m_s2', r + '/bias_stability_ci_high_m_s2')
          if 'bias_stability_ci_low_m_s2' in e else None)
    stab = (Num(r + '/bias_stability_m_s2', '.3g', bound, ACCEL_ADEV.per_si),
            *(_interval(*ci, ACCEL_ADEV.per_si) if ci else (' ',)), Unit(ACCEL_ADEV.unit),
            _si('at ', Num(r + '/bias_stability_tau_s', '.4g'), ' s; ',
                Num(r + '/bias_stability_m_s2', '.3g', bound), ' ', Unit('m/s^2')))
    b = (Num(r + '/bias_instability_m_s2', '.3g', bound, ACCEL.per_si),
         *(_interval(*ci, ACCEL_ADEV.per_si / B_FACTOR) if ci else (' ',)), Unit(ACCEL.unit),
         _si(Num(r + '/bias_instability_m_s2', '.3g', bound), ' ', Unit('m/s^2')))
    walk = r + '/acceleration_random_walk'
    k = _k_cell(e.get('acceleration_random_walk_resolved'), e.get('bias_stability_upper_bound'),
                (walk + '_m_s3_per_sqrt_hz',) * 2, (walk + '_bound_m_s3_per_sqrt_hz',) * 2,
                (ACCEL_RW.per_si, ACCEL_RW.unit, 'm/s^3/sqrt(Hz)'))
    return (f'accel {axis}', n, stab, b, k)


#: One card table: title, column headers, rows of cells.
CardTable = tuple[str, tuple[str, ...], list[tuple[Any, ...]]]


def card_tables(doc: Mapping[str, Any]) -> list[CardTable]:
    """
    Return the datasheet card: per bag, one row per gyro and accelerometer axis.

    Parameters
    ----------
    doc : dict
        The summary.json document.

    Returns
    -------
    list of tuple
        ``(title, columns, rows)`` per bag with an Allan readout; each cell a tuple of parts
        (text, :class:`..formatting.Num`, :class:`..formatting.Unit`,
        :class:`..formatting.Aside`: the SI value).

    """
    out: list[CardTable] = []
    reference = any('health' in a for b in doc['bags'] for a in b['axes'].values())
    for i, b in enumerate(doc['bags']):
        rows = [_gyro_row(axis, pointer('bags', i, 'axes', axis, 'allan_datasheet'),
                          a['allan_datasheet'])
                for axis, a in b['axes'].items() if a.get('allan_datasheet')]
        rows += [_accel_row(axis, pointer('bags', i, 'accelerometer_allan', axis), e)
                 for axis, e in (b.get('accelerometer_allan') or {}).items() if e]
        columns: tuple[str, ...] = CARD_COLUMNS
        if reference:
            # the health verdict of each gyro axis against --reference beside its numbers
            columns += ('Against the reference',)
            rows = [(*row, Num(pointer('bags', i, 'axes', row[0].split()[1], 'health', 'level'))
                     if row[0].startswith('gyro') and 'health' in b['axes'][row[0].split()[1]]
                     else '-') for row in rows]
        if rows:
            out.append((f"{b['label']}, {_duration(b.get('duration_s'))} at "
                        f"{fmt_or_na(b.get('rate_hz'), '.5g')} Hz", columns, rows))
    return out


def card_markdown(doc: Mapping[str, Any], tables: Sequence[Any] | None = None) -> str:
    """
    Return the card as Markdown tables (the same cells as report.html's, SI after ``=``).

    Parameters
    ----------
    doc : dict
        The summary.json document.
    tables : list, optional
        :func:`card_tables` of ``doc`` (computed when None).

    Returns
    -------
    str
        Markdown, one ``###`` table per bag; empty when no bag has an Allan readout.

    """
    lines = []
    for title, columns, rows in card_tables(doc) if tables is None else tables:
        lines += [f'### {title}', '', '| ' + ' | '.join(columns) + ' |',
                  '|---|' + '---|' * (len(columns) - 1)]
        lines += ['| ' + ' | '.join(cell_text(dict(doc), c) for c in row) + ' |' for row in rows]
        lines.append('')
    return '\n'.join(lines)
