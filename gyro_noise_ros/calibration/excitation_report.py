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
The files of ``gyro_noise_excitation``, rendered from its document (excitation.json).

Inputs: the dict ``ExcitationResult.as_dict()`` returns (SI, ratios not %; a null is a value that
was not finite) and, for the figures, each record's time (s) and excited channel (m/s^2 or
rad/s). Outputs: :func:`excitation_markdown` (excitation.md: quantities in mg or deg/s,
percentages and the verdicts, paper 001 section 5.3) and :func:`plot_excitation`
(excitation_<side>.png: the whole acquisition and the wave form or the amplitude against
frequency, paper 001 Figures 7-12). :func:`display_unit` is the printed unit of a sensor and
:func:`check_parts` the wording of a verdict, which the HTML page (:mod:`..htmlreport.excitation`)
shares. The workflow that computes the document and writes the files is :mod:`..app.excitation`.
"""

from collections.abc import Callable
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..formatting import cell_text, Num, percent, pointer
from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import ACCEL, GYRO_RATE

__all__ = ['DWELL_CHECKS', 'SWEEP_CHECKS', 'check_parts', 'check_text', 'checks_of',
           'display_unit', 'excitation_markdown', 'plot_excitation', 'sides_of', 'verdict_rule']

#: The records of a check, in the order they are reported.
SIDES = ('before', 'after')


def display_unit(sensor: str) -> tuple[float, str]:
    """
    Return the factor from SI to the printed unit of a sensor, and the unit's name.

    Parameters
    ----------
    sensor : {'accel', 'gyro'}
        The excited sensor.

    Returns
    -------
    (float, str)
        The policy of :mod:`..units`: ``(1000 / 9.80665, 'mg')`` for the accelerometer,
        ``(180 / pi, 'deg/s')`` for the gyro.

    """
    unit = ACCEL if sensor == 'accel' else GYRO_RATE
    return unit.per_si, unit.unit


def sides_of(doc: dict[str, Any]) -> list[str]:
    """Return the records of an excitation document: ``['before']`` or ``['before', 'after']``."""
    return [s for s in SIDES if s in doc]


def what_of(doc: dict[str, Any]) -> str:
    """Return the excitation in words: ``sine dwell at 8 Hz`` or ``sine sweep 5-10 Hz at ...``."""
    nom = doc['nominal']
    if doc['mode'] == 'dwell':
        return f'sine dwell at {nom["frequency_hz"]:g} Hz'
    return f'sine sweep {nom["f0_hz"]:g}-{nom["f1_hz"]:g} Hz at {nom["rate_hz_s"]:g} Hz/s'


def _f(v: float | None) -> float:
    """Return a number of the document for a format spec: a null (not finite) is nan."""
    return math.nan if v is None else v


#: The verdicts of a record: (verdict key, word when True, word when False, p-value key, size
#: key, name), for a dwell and for a sweep.
DWELL_CHECKS = (('steady', 'steady', 'UNSTEADY', 'stability_p', 'amplitude_stability',
                 'stability'),
                ('clean', 'clean', 'DISTORTED', 'distortion_p', 'thd', 'distortion'))
SWEEP_CHECKS = (('matches_reference', 'matches the reference', 'GAIN DIFFERS', 'gain_p',
                 'mean_deviation', 'gain'),
                ('flat', 'flat', 'FREQUENCY-DEPENDENT', 'flatness_p', 'deviation_spread',
                 'flatness'))


def checks_of(doc: dict[str, Any]) -> tuple[tuple[str, ...], ...]:
    """Return the verdicts of an excitation document's mode (:data:`DWELL_CHECKS` or sweep)."""
    return DWELL_CHECKS if doc['mode'] == 'dwell' else SWEEP_CHECKS


def check_parts(doc: dict[str, Any], side: str, check: tuple[str, ...]) -> tuple[Any, ...]:
    """
    Return one verdict of one record: its word, p-value and, when significant, its size.

    ``clean (p = 0.42)``; ``matches the reference (-0.068 %: significant, within the 1 %
    tolerance; p = 1.3e-15)``; ``GAIN DIFFERS (-2.1 %, beyond the 1 % tolerance; p = 1e-15)``;
    ``n/a`` without a test (no reference record). Numbers are :class:`..formatting.Num` parts
    (pointers into ``doc``): the HTML page shows them as they are, :func:`check_text` as text.

    Parameters
    ----------
    doc : dict
        The ``excitation.json`` document (its ``alpha`` and ``tolerance``).
    side : str
        ``'before'`` or ``'after'``.
    check : tuple
        One of :data:`DWELL_CHECKS` or :data:`SWEEP_CHECKS`.

    Returns
    -------
    tuple
        Text and :class:`..formatting.Num` parts.

    """
    key, yes, no, p_key, size_key, _ = check
    entry = doc[side]
    ok = entry.get(key)
    if ok is None:
        return ('n/a',)
    # a p-value that underflowed to 0 is below any number a double holds: "p ~ 0", not "p = 0"
    p = Num(pointer(side, p_key), '.2g', '= ' if entry.get(p_key) != 0 else '~ ')
    tol = doc.get('tolerance')
    if tol is None or entry.get(size_key) is None or not _f(entry.get(p_key)) < doc['alpha']:
        return (yes if ok else no, ' (p ', p, ')')
    where = ': significant, within the ' if ok else ', beyond the '
    return (yes if ok else no, ' (', Num(pointer(side, size_key), '+.3g' if key ==
                                         'matches_reference' else '.3g', scale=100.0),
            f' %{where}', Num('/tolerance', 'g', scale=100.0), ' % tolerance; p ', p, ')')


def check_text(doc: dict[str, Any], side: str, check: tuple[str, ...]) -> str:
    """Return :func:`check_parts` as text (excitation.md, the printed lines)."""
    return cell_text(doc, check_parts(doc, side, check))


def verdict_rule(doc: dict[str, Any]) -> str:
    """Return the sentence that says how the verdicts of ``doc`` are made (false alarms, size)."""
    rule = ("Verdicts are statistical tests against each record's own noise, false-alarm "
            f'probability {doc["alpha"]:g} each')
    if doc.get('tolerance') is not None:
        rule += (', and flag a defect only when it is also larger than the practical tolerance, '
                 f'{100 * doc["tolerance"]:g} % of the amplitude')
    return rule + ' (docs/reliability.md).'


def excitation_markdown(doc: dict[str, Any]) -> str:
    """
    Return ``excitation.md``: quantities with units, percentages and verdicts.

    Parameters
    ----------
    doc : dict
        The ``excitation.json`` document.

    Returns
    -------
    str

    """
    sides = sides_of(doc)
    out = [f'# Excitation check: {what_of(doc)}, {doc["sensor"]} {doc["axis"]} (paper 001 '
           'section 5.3)', '',
           verdict_rule(doc), '',
           '| quantity | ' + ' | '.join(sides) + ' |', '|---|' + '---|' * len(sides),
           '| record | ' + ' | '.join(doc[s]['source'] for s in sides) + ' |']

    def row(label: str, fn: Callable[[dict[str, Any]], str]) -> None:
        out.append(f'| {label} | ' + ' | '.join(fn(doc[s]) for s in sides) + ' |')

    def checks(label: str, check: tuple[str, ...]) -> None:
        out.append(f'| {label} | ' + ' | '.join(check_text(doc, s, check) for s in sides)
                   + ' |')

    if doc['mode'] == 'dwell':
        _dwell_rows(doc, row, checks)
        change = doc.get('change')
        if change:
            sig = 'significant' if change['amplitude_change_significant'] else 'within noise'
            if change['amplitude_change_significant'] and doc.get('tolerance') is not None:
                beyond = abs(change['amplitude_relative']) > doc['tolerance']
                sig += (f", {'beyond' if beyond else 'within'} the "
                        f"{100 * doc['tolerance']:g} % tolerance")
            out += ['', '## After / before', '',
                    f'- amplitude: {percent(change["amplitude_relative"], ".3f")} +/- '
                    f'{percent(change["amplitude_relative_sigma"], ".3f")} '
                    f'({sig}; p {"~" if change["amplitude_change_p"] == 0 else "="} '
                    f'{change["amplitude_change_p"]:.2g})',
                    f'- frequency: {change["frequency_hz"]:+.5f} Hz',
                    f'- amplitude stability: {100 * change["amplitude_stability"]:+.3f} '
                    f'percentage points',
                    f'- THD: {100 * change["thd"]:+.3f} percentage points']
        return '\n'.join(out) + '\n'
    _sweep_rows(doc, row, checks)
    for s in sides:
        out += _bin_table(doc, s)
    return '\n'.join(out) + '\n'


#: Adds one row to the table: a label and the cell of each record's entry.
_Row = Callable[[str, Callable[[dict[str, Any]], str]], None]


#: Adds one row of verdicts to the table: a label and the check.
_Checks = Callable[[str, tuple[str, ...]], None]


def _dwell_rows(doc: dict[str, Any], row: _Row, checks: _Checks) -> None:
    """Add the rows of a sine dwell: frequency, amplitude, stability, THD, verdicts."""
    k, unit = display_unit(doc['sensor'])
    u = doc['unit']
    row('frequency (Hz)',
        lambda e: f'{e["frequency_hz"]:.5f} +/- {_f(e["frequency_sigma_hz"]):.1e}')
    row(f'amplitude ({unit})', lambda e: f'{e[f"amplitude_{u}"] * k:.5g} +/- '
        f'{e[f"amplitude_sigma_{u}"] * k:.2g}')
    row(f'offset ({unit})', lambda e: f'{e[f"offset_{u}"] * k:.5g}')
    row(f'per-cycle amplitude mean / min / max ({unit})',
        lambda e: f'{e[f"cycle_amplitude_mean_{u}"] * k:.5g} / '
                  f'{e[f"cycle_amplitude_min_{u}"] * k:.5g} / '
                  f'{e[f"cycle_amplitude_max_{u}"] * k:.5g}')
    row('amplitude stability (std / mean of the cycles)',
        lambda e: percent(e['amplitude_stability'], '.3f'))
    row('stability from noise alone', lambda e: percent(e['amplitude_stability_noise'], '.3f'))
    checks('stability verdict', DWELL_CHECKS[0])
    row('THD (harmonics 2..H over the fundamental)', lambda e: percent(e['thd'], '.3f'))
    row('THD from noise alone', lambda e: percent(e['thd_noise'], '.3f'))
    checks('distortion verdict', DWELL_CHECKS[1])

    def harmonics(e: dict[str, Any]) -> str:
        h = np.asarray(e[f'harmonics_{u}'], dtype=float)
        with np.errstate(divide='ignore', invalid='ignore'):
            ratios = h[1:] / h[0]
        return ', '.join(percent(r, '.3f') for r in ratios) or 'none below Nyquist'

    row('harmonics 2..H (of the fundamental)', harmonics)
    row('excited span analysed (s)', lambda e: f'{e["start_s"]:.2f} + {e["duration_s"]:.2f} '
        f'({e["cycles"]} cycles)')


def _sweep_rows(doc: dict[str, Any], row: _Row, checks: _Checks) -> None:
    """Add the rows of a sine sweep: frequency span, deviation from the reference, verdicts."""
    u = doc['unit']
    row('frequency covered, 5th-95th percentile (Hz)',
        lambda e: f'{_f(e["frequency_range_hz"][0]):.3f} - {_f(e["frequency_range_hz"][1]):.3f}')
    row('mean deviation from the reference', lambda e: (
        'no reference' if f'reference_up_{u}' not in e else
        f'{percent(e["mean_deviation"], ".3f")} +/- '
        f'{percent(e["mean_deviation_sigma"], ".3f")}'))
    checks('gain verdict', SWEEP_CHECKS[0])
    row('deviation noise per bin', lambda e: percent(e.get('bin_deviation_sigma'), '.3f'))
    row('deviation spread over frequency (rms about the mean)',
        lambda e: percent(e.get('deviation_spread'), '.3f'))
    checks('flatness verdict', SWEEP_CHECKS[1])


def _bin_table(doc: dict[str, Any], side: str) -> list[str]:
    """Return one record's amplitude per frequency bin, with the reference when there is one."""
    k, unit = display_unit(doc['sensor'])
    u = doc['unit']
    e = doc[side]
    out = ['', f'## {side}: amplitude per frequency bin ({unit})', '',
           '| f (Hz) | rising | falling | reference rising | reference falling | '
           'deviation rising | deviation falling |', '|---|---|---|---|---|---|---|']

    def cell(key: str, i: int) -> str:
        values = e.get(key)
        if values is None or values[i] is None:
            return 'n/a'
        return f'{values[i] * k:.5g}'

    def dev(key: str, i: int) -> str:
        values = e.get(key)
        return percent(None if values is None else values[i], '.3f')

    for i, f in enumerate(e['bin_hz']):
        out.append(f'| {_f(f):.3f} | {cell(f"amplitude_up_{u}", i)} | '
                   f'{cell(f"amplitude_down_{u}", i)} | {cell(f"reference_up_{u}", i)} | '
                   f'{cell(f"reference_down_{u}", i)} | {dev("deviation_up", i)} | '
                   f'{dev("deviation_down", i)} |')
    return out


def plot_excitation(path: StrPath, doc: dict[str, Any], side: str, t_s: NDArray[np.float64],
                    x: NDArray[np.float64]) -> None:
    """
    Draw the whole acquisition and the waveform detail (paper 001 Figures 7-12).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    doc : dict
        The ``excitation.json`` document.
    side : {'before', 'after'}
        Which record.
    t_s, x : numpy.ndarray
        The record's time (s) and excited channel (SI).

    """
    plt = pyplot()
    scale, unit = display_unit(doc['sensor'])
    e, u = doc[side], doc['unit']
    fig, (pa, pb) = plt.subplots(1, 2, figsize=(11, 4.2))
    pa.plot(t_s, x * scale, lw=0.5)
    pa.set_xlabel('time (s)')
    pa.set_ylabel(f'{doc["sensor"]} {doc["axis"]} ({unit})')
    pa.set_title(f'(a) whole acquisition, {side}')
    if doc['mode'] == 'dwell':
        lo = int(e['start_s'] * e['rate_hz'])
        n = int(4 * e['rate_hz'] / e['frequency_hz'])
        pb.plot(t_s[lo:lo + n], x[lo:lo + n] * scale, '.-', lw=0.8, ms=3)
        pb.set_xlabel('time (s)')
        pb.set_title(f'(b) wave form: {e["frequency_hz"]:.3f} Hz, amplitude '
                     f'{e[f"amplitude_{u}"] * scale:.4g} {unit}, THD {100 * e["thd"]:.2f} %',
                     fontsize=9)
    else:
        # a null of the document (a value that was not finite) is NaN again
        f, up, down = (np.asarray(e[k], dtype=float)
                       for k in ('bin_hz', f'amplitude_up_{u}', f'amplitude_down_{u}'))
        pb.plot(f, up * scale, 'o-', label='rising frequency')
        pb.plot(f, down * scale, 's-', label='falling frequency')
        if f'reference_up_{u}' in e:
            ref = np.asarray(e[f'reference_up_{u}'], dtype=float)
            pb.plot(f, ref * scale, 'k--', lw=1, label='reference')
        pb.set_xlabel('instantaneous frequency (Hz)')
        pb.set_ylabel(f'amplitude ({unit})')
        pb.set_title('(b) amplitude against frequency', fontsize=9)
        # below the panel: the reference runs along the top, where a legend would cover it
        pb.legend(fontsize=8, loc='upper center', bbox_to_anchor=(0.5, -0.16), ncol=3)
    for panel in (pa, pb):
        panel.grid(True, alpha=0.3)
    save_figure(fig, path, dpi=110, tight=True)
