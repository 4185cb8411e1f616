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
The Markdown and CSV of ``gyro_noise_thermal``, rendered from its documents.

Inputs: training.json (``fit``), metrics.json (``apply``) and compare.json (``compare``): the
``as_dict()`` of the workflow's result (deg/s, deg/h, deg/sqrt(h), Hz, s, mg as the keys say;
null where a value is not finite), and the list of the report's figures (:data:`.figures.Figures`).
Outputs: :func:`training_markdown` (training.md), :func:`apply_markdown` (report.md),
:func:`compare_markdown` (compare.md) and :func:`compare_csv` (compare.csv), each table through
:func:`table_markdown`; :func:`figures_markdown` is the figure section naming, for each of paper
002's result figures 10-19 (:data:`PAPER_FIGURES`), its analogue or why the method has none.
The workflows that compute the documents and write the files are :mod:`..app.thermal`; the HTML
pages, :mod:`..htmlreport.thermal`.
"""

from collections.abc import Iterable, Mapping, Sequence
import csv
import io
import math
from pathlib import Path
import re
from typing import Any

from .figures import Figures
from .methods import MAX_OUTSIDE_SHARE
from ..outputs import StrPath

__all__ = ['AXIS_HEADER', 'AXIS_SPECS', 'COMPARE_HEADER', 'COMPARE_SPECS', 'PAPER_FIGURES',
           'apply_markdown', 'apply_verdict', 'axis_rows', 'bandwidth_cell',
           'bias_stability_cell', 'compare_csv', 'compare_markdown', 'compare_rows',
           'compare_verdict', 'figure_numbers',
           'figures_markdown', 'table_cells', 'table_markdown', 'training_markdown']

#: Paper 002's result figures: number -> (what it shows, why a method may have no analogue;
#: None for the generic figures every method gets). Figures 1-9 show the device, the algorithms
#: and the test rig.
PAPER_FIGURES = {
    10: ('temperature and gyro output against time', None),
    11: ('MOPSO particles and the Pareto front of (K, alpha)',
         'it chooses no VMD parameters by MOPSO'),
    12: ('the VMD modes (IMFs) of the output', 'it does not decompose the output into modes'),
    13: ('sample entropy and class of each IMF', 'it has no modes classified by sample entropy'),
    14: ('the mixed modes before and after TFPF', 'it has no mixed part filtered by TFPF'),
    15: ('the output before and after denoising alone',
         'it has no separate denoising stage (its whole output is the Fig. 18 analogue)'),
    16: ("the Elman network's prediction before and after BAS",
         'it has no network whose weights beetle antennae search optimises'),
    17: ('the drift part, its prediction and its compensation', None),
    18: ('the final output after denoising and compensation', None),
    19: ('Allan deviation before and after processing', None),
}

_FIG_REF = re.compile(r'\bFigs?\.\s*(\d+(?:\s*(?:,|-|and)\s*\d+)*)')


def figure_numbers(caption: str) -> list[int]:
    """
    Return the paper figure numbers a caption cites ('Fig. 12', 'Figs. 15, 18', 'Figs. 12-14').

    Parameters
    ----------
    caption : str
        Figure caption.

    Returns
    -------
    list of int
        Sorted, without repeats.

    """
    found: set[int] = set()
    for group in _FIG_REF.findall(caption):
        for part in re.split(r'\s*(?:,|and)\s*', group):
            ends = [int(v) for v in re.split(r'\s*-\s*', part) if v]
            found.update(range(ends[0], ends[-1] + 1))
    return sorted(found)


def figures_markdown(figs: Iterable[tuple[str, StrPath | None]], out: Path, *, method: str) -> str:
    """
    Write a report's figure section: paper figures 10-19 and their analogues, then the images.

    Parameters
    ----------
    figs : list of (str, path or None)
        (caption, PNG path) per figure; a caption cites the paper figures it mirrors as 'Fig. N'
        or 'Figs. N, M' (:func:`figure_numbers`). A None path is a figure the method has no
        analogue for, the caption saying why.
    out : pathlib.Path
        Report directory (image links are relative to it).
    method : str
        Method name, for the lines about missing analogues.

    Returns
    -------
    str
        Markdown.

    """
    drawn = [(cap, Path(p)) for cap, p in figs if p is not None]
    said = [cap for cap, p in figs if p is None]
    rows = []
    for num, (shows, missing) in PAPER_FIGURES.items():
        files = [f'`{p.relative_to(out)}`' for cap, p in drawn if num in figure_numbers(cap)]
        why = [cap for cap in said if num in figure_numbers(cap)]
        if files:
            here = ', '.join(files)
        elif why:
            here = f'none: {why[0]}'
        elif missing is None:
            here = 'not drawn in this report' + ('' if num != 19 else ' (`apply` draws the '
                                                 'Allan deviations of a held-out run)')
        else:
            here = f'no analogue for `{method}`: {missing}'
        rows.append(f'| {num} | {shows} | {here} |')
    order = sorted(range(len(drawn)), key=lambda i: (min(figure_numbers(drawn[i][0]) or [99]),
                                                     i))
    images = ''.join(f'\n![{drawn[i][0]}]({drawn[i][1].relative_to(out)})\n\n*{drawn[i][0]}*\n'
                     for i in order)
    return ('\n## Figures\n\nPaper 002 shows its results in Figures 10-19 (1-9 are the device, '
            f'the algorithms and the rig). Their analogues for `{method}` on this run:\n\n'
            '| paper figure | shows | here |\n|---|---|---|\n' + '\n'.join(rows) + '\n'
            + images)


def bias_stability_cell(metrics: Mapping[str, Any], spec: str = '.4g') -> str:
    """
    Format a bias stability: the value, or '<= value' when the readout gives an upper bound.

    Parameters
    ----------
    metrics : dict
        ``bias_stability_deg_h`` and ``bias_stability_upper_bound`` (metrics.json keys).
    spec : str
        Number format.

    Returns
    -------
    str

    """
    value = metrics.get('bias_stability_deg_h')
    if value is None or not math.isfinite(value):
        return 'n/a'
    return ('<= ' if metrics.get('bias_stability_upper_bound') else '') + format(value, spec)


def _cell(value: Any, spec: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, str):
        return value
    return format(value, spec)


def table_markdown(header: Sequence[str], rows: Iterable[Sequence[Any]],
                   specs: Sequence[str]) -> str:
    """
    Format a Markdown table.

    Parameters
    ----------
    header : sequence of str
        Column titles (with units).
    rows : sequence of sequence
        Cell values (None/NaN shown as n/a, bools as yes/no).
    specs : sequence of str
        Format spec per column for numbers.

    Returns
    -------
    str

    """
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for row in rows:
        lines.append('| ' + ' | '.join(_cell(v, s) for v, s in zip(row, specs)) + ' |')
    return '\n'.join(lines) + '\n'


def _accel_table(accel: dict[str, Any]) -> str:
    """Return the accelerometer's residual drift per axis, raw and compensated (mg)."""
    rows = [(axis, v['raw_residual_drift_mg'], v['processed_residual_drift_mg'])
            for axis, v in accel['axes'].items()]
    return table_markdown(['axis', 'raw residual drift (mg)', 'compensated residual drift (mg)'],
                          rows, ['', '.4g', '.4g'])


def training_markdown(doc: dict[str, Any], figs: Figures, out: Path) -> str:
    """
    Return ``training.md`` of a fit: the training data, the in-sample numbers, the figures.

    Parameters
    ----------
    doc : dict
        The training.json document.
    figs : Figures
        The report's figures, in ``out`` (empty: no figure section).
    out : pathlib.Path
        The report folder (image links are relative to it).

    Returns
    -------
    str

    """
    t = doc['training']
    rows = [(axis, v['raw_residual_drift_deg_s'], v['processed_residual_drift_deg_s'],
             v['raw_arw_deg_sqrt_h'], v['processed_arw_deg_sqrt_h'])
            for axis, v in doc['in_sample'].items()]
    rate = ('not available (the run is shorter than the rate window)'
            if t['temperature_rate_min_c_s'] is None else
            f'{t["temperature_rate_min_c_s"]:.4g}..{t["temperature_rate_max_c_s"]:.4g} degC/s')
    accel = ''
    if doc.get('accel'):
        accel = ('\nAccelerometer: a cubic in T relative to T_ref = '
                 f'{doc["accel"]["t_ref_c"]:.2f} degC (in-sample).\n\n'
                 + _accel_table(doc['accel']))
    return (f'# Training report: {doc["method"]}\n\n'
            f'Trained on {", ".join(t["sources"])}: {t["samples"]} samples at '
            f'{t["rate_hz"]:.6g} Hz, temperature {t["temperature_min_c"]:.2f}..'
            f'{t["temperature_max_c"]:.2f} degC, rate {rate} ({t["rate_window_s"]:g}-s '
            f'window, filled windows only). Causal (live-capable): '
            f'{"yes" if doc["causal"] else "no (offline only)"}. Fit time '
            f'{doc["fit_time_s"]:.1f} s. Beyond the trained range: {doc["out_of_range"]}.\n\n'
            + (f'Terms chosen by cross-validation on the training run: '
               f'{", ".join(doc["terms"])} (model.json `parameters.cv`: every candidate).\n\n'
               if doc.get('terms') else '')
            + ''.join(f'**Warning: {w}.**\n\n' for w in doc.get('warnings') or ())
            + ''.join(f'**Note: {n}.**\n\n' for n in doc['notes'])
            + f'**In-sample only** ({doc["note"]}).\n\n'
            + table_markdown(
                ['axis', 'raw residual drift (deg/s)', 'processed residual drift (deg/s)',
                 'raw ARW (deg/sqrt(h))', 'processed ARW (deg/sqrt(h))'],
                rows, ['', '.4g', '.4g', '.4g', '.4g'])
            + accel
            + (figures_markdown(figs, out, method=doc['method']) if figs else ''))


def bandwidth_cell(bw: dict[str, Any] | None) -> str:
    """
    Return the -3 dB cell of a table: the frequency, ``< band`` or ``> band``.

    Parameters
    ----------
    bw : dict or None
        A ``bandwidth`` block of metrics.json (None, e.g. no small-signal block: empty).

    Returns
    -------
    str

    """
    if bw is None:
        return ''
    if bw['minus_3db_bound'] == 'measured':
        return f'{bw["minus_3db_hz"]:.3g}'
    return '< band' if bw['minus_3db_bound'] == 'below' else '> band'


AXIS_HEADER = ['axis', 'ARW raw (deg/sqrt(h))', 'ARW processed (deg/sqrt(h))',
               'ARW gain, noise path', 'bias stability raw (deg/h)',
               'bias stability processed (deg/h)',
               'residual drift raw (deg/s)', 'residual drift processed (deg/s)',
               '-3 dB, 1 deg/s motion (Hz)', '-3 dB, noise-sized motion (Hz)',
               'small-signal min gain 0.1-1 Hz', 'step delay 50 % (s)',
               'look-ahead before a step (s)', 'live-capable']
AXIS_SPECS = ['', '.4g', '.4g', '.3g', '', '', '.4g', '.4g', '', '', '.3g', '.3g', '.3g', '']


def axis_rows(axes: dict[str, Any]) -> list[tuple[Any, ...]]:
    """
    Return the per-axis rows of the apply report (:data:`AXIS_HEADER`).

    Parameters
    ----------
    axes : dict
        ``axes`` of metrics.json.

    Returns
    -------
    list of tuple

    """
    rows = []
    for axis, v in axes.items():
        raw, proc, bw = v['raw'], v['processed'], v['bandwidth']
        rows.append((axis, raw['arw_deg_sqrt_h'], proc['arw_deg_sqrt_h'],
                     (v.get('noise_path') or {}).get('arw_gain'),
                     bias_stability_cell(raw), bias_stability_cell(proc),
                     raw['residual_drift_deg_s'], proc['residual_drift_deg_s'],
                     bandwidth_cell(bw), bandwidth_cell(v.get('bandwidth_small_signal')),
                     v['verdict']['small_signal_low_band_min_gain'],
                     bw['step_delay_50_s'], bw.get('step_lead_s'),
                     v['verdict']['live_capable']))
    return rows


def _small_text(inj: dict[str, Any]) -> str:
    """Return the clause on the noise-sized injection ('' when there was none)."""
    amp = inj.get('small_signal_amplitude_deg_s')
    return '' if amp is None else f', and again at {amp:.3g} deg/s (the size of the noise)'


def yardstick_markdown(yard: Mapping[str, Any] | None) -> str:
    """
    Return the per-axis table of the residual drift against the noise floor and poly3.

    Parameters
    ----------
    yard : dict or None
        A ``yardstick`` block (``thermal.metrics.yardstick``); None: ''.

    Returns
    -------
    str

    """
    if not yard:
        return ''
    kind = ("the test run's own noise" if yard['floor'] == 'noise' else
            "the run's white-noise level, ARW / sqrt(60 s): slow noise is not in it")
    p3 = yard.get('over_poly3') or [None] * 3
    rows = [(axis, yard['floor_deg_s'][a], yard['over_floor'][a], p3[a])
            for a, axis in enumerate('xyz')]
    return (f'Residual drift against the noise floor ({kind}) and against poly3 (the form PX4 '
            'and ArduPilot evaluate; 0.2 is five times better):\n\n'
            + table_markdown(['axis', 'noise floor (deg/s)', 'x noise floor', 'x poly3'], rows,
                             ['', '.4g', '.3g', '.3g']))


def _ratios(values: Sequence[float | None], spec: str) -> str:
    """Format per-axis ratios as 'a, b, c' ('n/a' where missing)."""
    return ', '.join('n/a' if v is None else format(v, spec) for v in values)


def apply_verdict(doc: Mapping[str, Any]) -> tuple[str, str]:
    """
    Return the verdict line of an applied model: its level and its text.

    The text gives each axis's residual drift over the noise floor and over poly3 (metrics.json
    ``yardstick``), then what weakens the numbers. The level is ``'WARN'`` when the document
    carries a warning (more than ``methods.MAX_OUTSIDE_SHARE`` of the run outside the trained
    range; a kelvin stream), when the run is one the model was trained on (in-sample), when
    its rate differs from the training rate, or when the residual drift exceeds the raw one on
    an axis; else ``'OK'``.

    Parameters
    ----------
    doc : dict
        The metrics.json document.

    Returns
    -------
    (str, str)
        Level (``'OK'`` or ``'WARN'``) and text (Markdown: bold, code).

    """
    yard = doc.get('yardstick') or {}
    text = f'`{doc["method"]}` applied'
    if yard:
        kind = "the run's own noise" if yard.get('floor') == 'noise' else "the run's white noise"
        text += (f': residual drift **{_ratios(yard["over_floor"], ".2g")} x the noise floor**'
                 f' ({kind}) on x, y, z')
        if yard.get('over_poly3'):
            text += f', {_ratios(yard["over_poly3"], ".2g")} x poly3'
    worse = [axis for axis, v in doc['axes'].items()
             if (v['verdict'].get('residual_drift_ratio') or 0.0) > 1.0]
    cautions = [f'**{w}**' for w in doc.get('warnings') or ()]
    if doc.get('in_sample'):
        cautions.append('**in-sample**: the model was trained on this bag')
    if doc.get('rate_mismatch'):
        cautions.append('the sample rate differs from the training rate')
    if worse:
        cautions.append(f'residual drift above the raw one on {", ".join(worse)}')
    return ('WARN' if cautions else 'OK'), text + ''.join(f'; {c}' for c in cautions) + '.'


def compare_verdict(summary: Mapping[str, Any]) -> tuple[str, str]:
    """
    Return the verdict line of a held-out comparison: its level and its text.

    The text names the best live-capable full-bandwidth method with its mean ratio to the noise
    floor and to poly3, then the ranking by the mean ratio to the floor (compare.json
    ``best_held_out``, ``ranking``). The level is ``'WARN'`` when the document carries a
    warning (a method extrapolating over more than ``methods.MAX_OUTSIDE_SHARE`` of the test
    run; a kelvin stream), a method was not scored, or no method qualifies as best; else
    ``'INFO'`` (a ranking, not a pass or fail).

    Parameters
    ----------
    summary : dict
        The compare.json document.

    Returns
    -------
    (str, str)
        Level (``'INFO'`` or ``'WARN'``) and text (Markdown: bold, code).

    """
    best = summary['best_held_out']['method']
    rank = {r['method']: r for r in summary.get('ranking') or ()}
    if best is None:
        text = 'no live-capable full-bandwidth method was scored'
    else:
        text = f'best on the held-out run: **`{best}`**'
        if best in rank and rank[best]['mean_over_floor'] is not None:
            text += f', {rank[best]["mean_over_floor"]:.2g} x the noise floor'
            if rank[best].get('mean_over_poly3') is not None:
                text += f', {rank[best]["mean_over_poly3"]:.2g} x poly3'
            text += ' (mean over the axes)'
    if rank:
        text += '; ranked by x noise floor: ' + ', '.join(
            f'{i + 1}. {r["method"]}' for i, r in enumerate(rank.values()))
    far = {name: m['range']['fraction_outside'] for name, m in summary['methods'].items()
           if m['range'].get('warning')}
    ranged = {f'{name}: {summary["methods"][name]["range"]["warning"]}' for name in far}
    cautions = [f'**{w}**' for w in summary.get('warnings') or () if w not in ranged]
    if far:
        cautions.append('**extrapolating** over more than '
                        f'{100 * MAX_OUTSIDE_SHARE:g} % of the test run (outside the trained '
                        'range of T or dT): ' + ', '.join(f'{name} {100 * share:.0f} %'
                                                          for name, share in far.items()))
    if summary.get('errors'):
        cautions.append(f'not scored: {", ".join(summary["errors"])}')
    level = 'WARN' if cautions or best is None else 'INFO'
    return level, text + ''.join(f'; {c}' for c in cautions) + '.'


def apply_markdown(doc: dict[str, Any], figs: Figures, out: Path) -> str:
    """
    Return ``report.md`` of an applied model: warnings, trained range, per-axis table, verdicts.

    Parameters
    ----------
    doc : dict
        The metrics.json document.
    figs, out
        As :func:`training_markdown`.

    Returns
    -------
    str

    """
    inj = doc['injection']
    warn = ''
    if doc['in_sample']:
        warn += ('\n**Warning: this bag is one the model was trained on; the numbers are '
                 'in-sample and flatter the method.**\n')
    if doc['rate_mismatch']:
        warn += (f'\n**Warning: sample rate {doc["rate_hz"]:.6g} Hz differs from the training '
                 f'rate {doc["model"]["training"]["rate_hz"]:.6g} Hz.**\n')
    for note in doc['notes']:
        warn += f'\n**Note: {note}.**\n'
    for warning in doc.get('warnings') or ():
        warn += f'\n**Warning: {warning}.**\n'
    rng = doc['range']
    rate = ('(no trained dT range: the training run was shorter than the rate window)'
            if rng['rate_range_c_s'] is None else
            f'dT {rng["rate_range_c_s"][0]:.4g}..{rng["rate_range_c_s"][1]:.4g} degC/s')
    range_text = (f'\nTrained range: T {rng["temperature_range_c"][0]:.2f}..'
                  f'{rng["temperature_range_c"][1]:.2f} degC, {rate}. This run: '
                  f'{rng["outside"]} of {rng["samples"]} samples '
                  f'({100 * rng["fraction_outside"]:.3g} %) lie outside it '
                  f'({rng["temperature_below"]} samples with T below the range, '
                  f'{rng["temperature_above"]} above; {rng["rate_below"]} with dT below, '
                  f'{rng["rate_above"]} above). There the method: {rng["treatment"]}.\n')
    range_text += '\n' + yardstick_markdown(doc.get('yardstick'))
    accel = ''
    if doc.get('accel'):
        accel = ('\n## Accelerometer\n\nThe change of the offset from T_ref = '
                 f'{doc["accel"]["t_ref_c"]:.2f} degC (a cubic in T) is subtracted; beyond the '
                 f'trained range: {doc["accel"]["out_of_range"]}.\n\n'
                 + _accel_table(doc['accel']))
    verdicts = ''.join(f'- **{axis}**: {v["verdict"]["text"]}\n'
                       for axis, v in doc['axes'].items())
    level, line = apply_verdict(doc)
    return (f'# {doc["method"]} on {doc["bag"]}\n\n**{level}**: {line}\n\n'
            f'{doc["samples"]} samples at {doc["rate_hz"]:.6g} Hz '
            f'({doc["duration_s"] / 3600:.3g} h), temperature {doc["temperature_min_c"]:.2f}..'
            f'{doc["temperature_max_c"]:.2f} degC; model trained on '
            f'{", ".join(doc["model"]["training"]["sources"])}. Method causal (live-capable): '
            f'{"yes" if doc["causal"] else "no (offline only)"}.\n{warn}{range_text}\n'
            + table_markdown(AXIS_HEADER, axis_rows(doc['axes']), AXIS_SPECS)
            + f'\nBandwidth cost measured with a chirp {inj["f_lo_hz"]:g}..'
              f'{inj["f_hi_hz"]:.3g} Hz and steps of {inj["amplitude_deg_s"]:.3g} deg/s added '
              f'to the run{_small_text(inj)}.\n'
            + accel + '\n## Verdicts\n\n' + verdicts + '\n## Definitions\n\n'
            + ''.join(f'- `{k}`: {v}\n' for k, v in doc['definitions'].items())
            + (figures_markdown(figs, out, method=doc['method']) if figs else ''))


COMPARE_HEADER = ['method', 'axis', 'ARW of the output (deg/sqrt(h))', 'ARW gain, noise path',
                  'bias stability (deg/h; <= upper bound)', 'residual drift (deg/s)',
                  'x noise floor', 'x poly3', '-3 dB, 1 deg/s motion (Hz)',
                  '-3 dB, noise-sized motion (Hz)', 'small-signal min gain 0.1-1 Hz',
                  'step delay 50 % (s)', 'look-ahead before a step (s)', 'settled step gain',
                  'outside trained range', 'live-capable', 'ARW from removed bandwidth']
COMPARE_SPECS = ['', '', '.4g', '.3g', '', '.4g', '.3g', '.3g', '', '', '.3g', '.3g', '.3g',
                 '.3g', '.2%', '', '']
#: compare.csv: the table's columns with numbers for numbers (the bias stability as a number
#: and its upper-bound flag beside it).
_CSV_KEYS = ['method', 'axis', 'arw_deg_sqrt_h', 'arw_gain_noise_path', 'bias_stability_deg_h',
             'residual_drift_deg_s', 'residual_drift_over_floor', 'residual_drift_over_poly3',
             'minus_3db_hz',
             'small_signal_minus_3db_hz', 'small_signal_low_band_min_gain', 'step_delay_50_s',
             'step_lead_s', 'step_settled_gain', 'fraction_outside_trained_range',
             'live_capable', 'arw_from_bandwidth', 'bias_stability_upper_bound']


def compare_rows(summary: dict[str, Any]) -> list[tuple[Any, ...]]:
    """
    Return the values of the comparison table, raw input and oracles first.

    Parameters
    ----------
    summary : dict
        The compare.json document.

    Returns
    -------
    list of tuple
        One row per method (or raw input, oracle) and axis: the columns of compare.csv
        (:data:`COMPARE_HEADER` plus the bias-stability upper-bound flag last; numbers as
        numbers, :func:`table_cells` formats them as compare.md shows them).

    """
    rows: list[tuple[Any, ...]] = []
    results = summary['methods']
    oracle = summary.get('oracle')
    floor = dict(zip('xyz', (summary.get('floor') or {}).get('deg_s') or [None] * 3))
    poly3 = dict(zip('xyz', summary.get('poly3_deg_s') or [None] * 3))
    first = next(iter(results.values()))

    def ratio(value: float | None, base: dict[str, float | None], axis: str) -> float | None:
        b = base.get(axis)
        return None if value is None or not b else value / b

    def row(label: str, axis: str, value: float | None, *rest: Any) -> tuple[Any, ...]:
        return (label, axis, *rest[:3], value, ratio(value, floor, axis),
                ratio(value, poly3, axis), *rest[3:])

    for axis, v in first['axes'].items():
        raw = v['raw']
        rows.append(row('(raw input)', axis, raw['residual_drift_deg_s'],
                        raw['arw_deg_sqrt_h'], None, raw['bias_stability_deg_h'], '', '', None,
                        None, None, None, None, None, None, raw.get('bias_stability_upper_bound')))
    if oracle:
        for key, label in (('true_terms', '(oracle: true terms)'),
                           ('measured_terms', '(oracle: measured T, dT)')):
            for axis, value in oracle[key]['axes'].items():
                rows.append(row(label, axis, value, None, None, None, '', '', None, None, None,
                                None, None, None, None, None))
    for name, doc in results.items():
        for axis, v in doc['axes'].items():
            proc, bw, vd = v['processed'], v['bandwidth'], v['verdict']
            rows.append(row(name, axis, proc['residual_drift_deg_s'], proc['arw_deg_sqrt_h'],
                            (v.get('noise_path') or {}).get('arw_gain'),
                            proc['bias_stability_deg_h'], bandwidth_cell(bw),
                            bandwidth_cell(v.get('bandwidth_small_signal')),
                            vd['small_signal_low_band_min_gain'], bw['step_delay_50_s'],
                            bw.get('step_lead_s'), bw['step_settled_gain'],
                            doc['range']['fraction_outside'], vd['live_capable'],
                            vd['arw_from_bandwidth'], proc.get('bias_stability_upper_bound')))
    return rows


def table_cells(rows: Sequence[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    """
    Return compare rows as the Markdown table shows them (an upper bound of bias stability '<=').

    Parameters
    ----------
    rows : list of tuple
        :attr:`CompareResult.rows`.

    Returns
    -------
    list of tuple
        One cell per :data:`COMPARE_HEADER` column.

    """
    cells = []
    for row in rows:
        bs = '' if row[4] is None else bias_stability_cell(
            {'bias_stability_deg_h': row[4], 'bias_stability_upper_bound': row[-1]})
        cells.append(row[:4] + (bs,) + row[5:-1])
    return cells


def compare_csv(summary: dict[str, Any]) -> str:
    """
    Return ``compare.csv``: the comparison table with numbers for numbers.

    Parameters
    ----------
    summary : dict
        The compare.json document.

    Returns
    -------
    str
        Header :data:`_CSV_KEYS`, then :func:`compare_rows` (None as an empty cell).

    """
    rows = compare_rows(summary)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator='\n')
    w.writerow(_CSV_KEYS)
    for row in rows:
        w.writerow(['' if v is None else v for v in row])
    return buf.getvalue()


def _yardstick_text(summary: Mapping[str, Any]) -> str:
    """Say what "x noise floor" and "x poly3" divide by."""
    floor = summary.get('floor')
    if not floor:
        return ''
    p3 = summary.get('poly3_deg_s')
    poly3 = ('' if p3 is None else '; "x poly3" divides by the residual drift of poly3 (the form '
             'PX4 and ArduPilot evaluate) on the same test run: 0.2 is five times better')
    values = ', '.join('n/a' if v is None else f'{v:.4g}' for v in floor['deg_s'])
    return (f'"x noise floor" divides each residual drift by the noise floor, the '
            f'{floor["definition"]} ({values} deg/s on x, y, z){poly3}.\n\n')


def _ranking_markdown(summary: Mapping[str, Any]) -> str:
    """Rank the scored methods by their mean ratio to the noise floor."""
    ranking = summary.get('ranking') or []
    if not ranking:
        return ''
    rows = [(i + 1, r['method'], r['mean_over_floor'], r['mean_over_poly3'],
             'yes' if r['live_capable'] else 'no') for i, r in enumerate(ranking)]
    return ('## Ranking\n\nBy the mean over the axes of the residual drift over the noise floor '
            '(1 is what a perfect drift model would leave):\n\n'
            + table_markdown(['rank', 'method', 'x noise floor', 'x poly3', 'live-capable'],
                             rows, ['', '', '.3g', '.3g', '']) + '\n')


def compare_markdown(summary: dict[str, Any], figs: Sequence[tuple[str, StrPath]],
                     out: Path) -> str:
    """
    Return ``compare.md``: the held-out table, the best method, the trained range, verdicts.

    Parameters
    ----------
    summary : dict
        The compare.json document.
    figs : list of (str, path)
        The report's figures (caption, PNG file in ``out``).
    out : pathlib.Path
        The report folder (image links are relative to it).

    Returns
    -------
    str

    """
    rows = compare_rows(summary)
    errs = ''.join(f'- {k}: {v}\n' for k, v in summary['errors'].items())
    best = summary['best_held_out']
    verdicts = ''.join(f'- **{name}** {axis}: {v["verdict"]["text"]}\n'
                       for name, doc in summary['methods'].items()
                       for axis, v in doc['axes'].items())
    ranges = ''.join(f'- **{name}**: {doc["range"]["outside"]} of {doc["range"]["samples"]} '
                     f'test samples ({100 * doc["range"]["fraction_outside"]:.3g} %) outside '
                     f'the trained range of T or dT; there: {doc["range"]["treatment"]}\n'
                     for name, doc in summary['methods'].items())
    oracle = ''
    if summary.get('oracle'):
        o = summary['oracle']
        oracle = ('The bags come from `gyro_noise_thermal simulate`: the oracle rows are least '
                  "squares on the simulator's own drift terms fitted on the training run "
                  f'(true terms: mean {o["true_terms"]["mean_residual_drift_deg_s"]:.4g} deg/s; '
                  'computed from the measured temperature and its 10-s slope: '
                  f'{o["measured_terms"]["mean_residual_drift_deg_s"]:.4g} deg/s), for scale; '
                  'they are no bound (their terms also absorb the slow noise of the training '
                  'run).\n\n')
    level, line = compare_verdict(summary)
    return (f'# Held-out comparison\n\n**{level}**: {line}\n\nTrained on {summary["train"]} '
            f'({summary["train_temperature_c"][0]:.2f}..{summary["train_temperature_c"][1]:.2f}'
            f' degC), scored on {summary["test"]} ({summary["test_temperature_c"][0]:.2f}..'
            f'{summary["test_temperature_c"][1]:.2f} degC), seed {summary["seed"]}.\n\n'
            + (f'**One recording split in time at {summary["split"]["fraction"]:g} of its '
               f'length: {summary["split"]["note"]}.**\n\n' if summary.get('split') else '')
            + ''.join(f'**Note: {n}.**\n\n' for n in summary.get('notes') or ())
            + ''.join(f'**Warning: {w}.**\n\n' for w in summary.get('warnings') or ())
            + _yardstick_text(summary) + oracle
            + table_markdown(COMPARE_HEADER, table_cells(rows), COMPARE_SPECS)
            + f'\nBest held-out ({best["rule"]}): **{best["method"]}**.\n\n'
            + _ranking_markdown(summary)
            + (f'Not scored:\n\n{errs}\n' if errs else '')
            + '## Outside the trained range\n\n' + ranges
            + '\n## Verdicts\n\n' + verdicts + '\n## Definitions\n\n'
            + ''.join(f'- `{k}`: {v}\n' for k, v in summary['definitions'].items())
            + ''.join(f'\n![{cap}]({Path(p).relative_to(out)})\n\n*{cap}*\n' for cap, p in figs))
