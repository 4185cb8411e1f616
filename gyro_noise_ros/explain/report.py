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
Outputs of the discrepancy workflow.

explain.json, report.md and PNG figures (see docs/discrepancy.md).

Figures show each signature in its natural units: the measurement (black) against the ensemble band
``mu +/- T_s sd`` of the model before a step (grey) and after it (blue), transformed back from the
comparison domain of :mod:`.signatures`.
"""

from collections.abc import Mapping, Sequence
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import signatures as sig
from .effects import public_params
from .signatures import Comparison, FloatArray, Layout
from .uncertainty import format_value, PARAMETERS
from .workflow import ExplainResult, Step
from ..errors import OutputError
from ..outputs import StrPath
from ..units import GYRO_ADEV, RAD_TO_DEG

_LOG_X = {'allan', 'psd', 'psd_peak'}
_LOG_Y = {'allan', 'psd', 'psd_peak', 'chunk_variance'}
# The units of every report (units.py): the angular rate in deg/s, its Allan deviation in deg/h;
# the unit in every axis label.
_TITLES = {'allan': 'Allan deviation', 'psd': 'power spectral density',
           'psd_peak': 'band peak / band mean', 'chunk_bias': 'chunk bias',
           'chunk_variance': 'chunk variance', 'histogram': 'value histogram',
           'stamps': 'stamp intervals', 'temperature': 'corr(bias, T), corr(bias, dT/dt)'}
_YLABELS = {'allan': 'ADEV (deg/h)', 'psd': 'PSD ((deg/s)^2/Hz)', 'psd_peak': 'peak / mean (1)',
            'chunk_bias': 'bias (deg/s)', 'chunk_variance': 'variance ((deg/s)^2)',
            'histogram': 'samples (count)', 'stamps': 'intervals (count)',
            'temperature': 'correlation (1)'}


def _untransform(name: str, values: FloatArray) -> FloatArray:
    kind = sig.TRANSFORM[name]
    if kind == 'log10':
        return 10.0 ** values
    if kind == 'sqrt':
        return np.maximum(values, 0.0) ** 2
    return values


def _scale(name: str) -> float:
    if name == 'allan':
        return GYRO_ADEV.per_si
    if name == 'chunk_bias':
        return RAD_TO_DEG
    return RAD_TO_DEG ** 2 if name in ('psd', 'chunk_variance') else 1.0


def _plot_one(ax: Any, layout: Layout, name: str, comparisons: Sequence[Comparison | None],
              labels: Sequence[str], colours: Sequence[str]) -> None:
    xs: NDArray[Any]  # bin numbers on a lattice histogram, else the signature's points
    label, unit, xs = sig.points(layout, name)
    scale = _scale(name)
    if name == 'histogram' and layout.lattice is not None:
        xs = np.arange(xs.size)
        xlabel = 'bin (value bins, then lattice phase) (1)'
    elif name == 'histogram':
        xs = xs * RAD_TO_DEG
        xlabel = 'angular rate (deg/s)'
    else:
        xlabel = f'{label} ({unit or "1"})' if not unit.startswith('(') else f'{label} {unit}'
    first = None
    for comp, label, colour in zip(comparisons, labels, colours):
        if comp is None:
            continue
        lo = _untransform(name, comp.mu - comp.threshold * comp.sd) * scale
        hi = _untransform(name, comp.mu + comp.threshold * comp.sd) * scale
        ax.fill_between(xs, lo, hi, color=colour, alpha=0.35, lw=0, label=f'{label} band')
        first = comp
    assert first is not None  # the first band (the model before) is always there
    y = _untransform(name, first.y) * scale
    out = np.zeros(xs.size, dtype=bool) if comparisons[-1] is None else comparisons[-1].outside
    ax.plot(xs, y, 'k.-', ms=3, lw=0.8, label='measurement')
    if out.any():
        ax.plot(xs[out], y[out], 'o', mfc='none', mec='red', ms=6, label='outside')
    if name in _LOG_X:
        ax.set_xscale('log')
    if name in _LOG_Y:
        ax.set_yscale('log')
    ax.set_title(_TITLES[name], fontsize=10)
    ax.set_xlabel(xlabel, fontsize=9)
    ax.set_ylabel(_YLABELS.get(name, ''), fontsize=9)
    ax.tick_params(labelsize=8)


def plot_signatures(path: StrPath, layout: Layout, names: Sequence[str],
                    comparisons: Sequence[Mapping[str, Comparison] | None], labels: Sequence[str],
                    colours: Sequence[str], title: str) -> None:
    """
    Write one PNG with a panel per signature.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file to write.
    layout : Layout
        Where each signature is evaluated.
    names : list of str
        Signatures to draw.
    comparisons : list of dict or None
        One dict (name -> Comparison) per band to draw (None: no band); the last one marks the
        outside points.
    labels, colours : list of str
        Legend label and colour per band.
    title : str
        Figure title.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    cols = min(4, len(names))
    rows = int(np.ceil(len(names) / cols))
    # 4.5 in per panel at 100 dpi: 1800 px for the 4 columns of 7-8 signatures (issue 11: >= 1600).
    fig, axes = plt.subplots(rows, cols, figsize=(4.5 * cols, 3.6 * rows), squeeze=False)
    for ax, name in zip(axes.ravel(), names):
        _plot_one(ax, layout, name, [c.get(name) if c else None for c in comparisons], labels,
                  colours)
    for ax in axes.ravel()[len(names):]:
        ax.axis('off')
    axes.ravel()[0].legend(fontsize=8, loc='best')
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _loud(note: str) -> str:
    return 'UNRESOLVED' + note[len('unresolved'):] if note.startswith('unresolved') else note


def bound_text(bound: Mapping[str, float | None], unit: str) -> str:
    """
    Return an unresolved time scale as the bound the record gives (never as a value).

    Parameters
    ----------
    bound : dict
        ``{'lower': float or None, 'upper': float or None}`` in the parameter's unit.
    unit : str
        The parameter's unit.

    Returns
    -------
    str
        ``>= lower unit``, ``<= upper unit``, both, or ``not resolved``.

    """
    lo, hi = bound.get('lower'), bound.get('upper')
    if lo is not None and hi is not None:
        return f'{lo:.3g} to {hi:.3g} {unit}'
    if lo is not None:
        return f'>= {lo:.3g} {unit}'
    if hi is not None:
        return f'<= {hi:.3g} {unit}'
    return 'not resolved'


def _fmt_params(params: Mapping[str, Any],
                time_scales: Mapping[str, Mapping[str, Any]] | None = None) -> str:
    parts = []
    for k, v in public_params(params).items():
        check = (time_scales or {}).get(k)
        if check is not None and not check['resolved']:
            unit = PARAMETERS.get(k, ('', ''))[0]
            parts.append(f'{k} {bound_text(check["bound"], unit)} [{_loud(check["note"])}]')
        else:
            parts.append(f'{k} = {v:.4g}' if isinstance(v, float) else f'{k} = {v}')
    return ', '.join(parts)


def _uncertainty_text(entry: Mapping[str, Any]) -> str:
    if entry.get('bound') is not None:
        return f'{bound_text(entry["bound"], entry["unit"])} [{_loud(entry["note"])}]'
    text = format_value(entry)
    note = entry['note']
    return f'{text} [{_loud(note)}]' if note and not entry['resolved'] else text


def parameter_lines(result: ExplainResult) -> list[str]:
    """
    One line per accepted effect: its parameters as ``value ± stderr unit``.

    Parameters flagged unresolved say so (docs/discrepancy.md); without a bootstrap the point
    values are given with "(no uncertainty: --bootstrap 0)".
    """
    lines = []
    for step in result.steps:
        entries = result.uncertainty.get(step.effect)
        if entries:
            # a bound reads 'name >= 50 s', a value 'name = 1.2 ± 0.1 s'
            parts = [f'{name}{" " if entry.get("bound") is not None else " = "}'
                     f'{_uncertainty_text(entry)}' for name, entry in entries.items()]
        else:
            parts = [_fmt_params(step.params, step.time_scales)
                     + ' (no uncertainty: bootstrap off)']
        lines.append(f'{step.effect}: ' + '; '.join(parts))
    return lines


def _uncertainty_table(step: Step, result: ExplainResult) -> list[str]:
    entries = result.uncertainty.get(step.effect)
    if not entries:
        return [f'Parameters: {_fmt_params(step.params, step.time_scales)} (no uncertainty: the '
                'bootstrap was off).', '']
    lines = ['| parameter | value ± stderr | 95 % interval | method | note |',
             '|---|---|---|---|---|']
    for name, entry in entries.items():
        ci = entry['ci95']
        interval = '-' if ci is None else f'[{ci[0]:.6g}, {ci[1]:.6g}] {entry["unit"]}'
        value = format_value(entry)
        if entry.get('bound') is not None:
            # a time scale the record does not resolve: the bound, not a value
            value = interval = bound_text(entry['bound'], entry['unit'])
        note = entry['note'] if entry['note'] else 'resolved'
        if not entry['resolved'] and entry['note'].startswith('unresolved'):
            note = '**UNRESOLVED**' + entry['note'][len('unresolved'):]
        lines.append(f'| {name} | {value} | {interval} | {entry["method"]} | {note} |')
    return lines + ['']


def verdict(result: ExplainResult) -> str:
    """One-paragraph verdict printed by the command line tool."""
    over = ''
    if result.quieter:
        over = ('; the baseline over-estimates the noise (the measurement is quieter than the '
                'model, which no added effect can explain): ' + '; '.join(result.quieter[:3]))
    if not result.steps and not result.unexplained:
        return ('consistent with the baseline model (fractional noise '
                f'alpha={result.baseline.alpha:.2f}): '
                f'gap {result.gap_final:.3f}, nothing named' + over)
    named = ', '.join(s.effect for s in result.steps) or 'nothing'
    text = f'added {named}; gap {result.gap_initial:.3f} -> {result.gap_final:.3f}'
    if result.unexplained:
        limit = (f' (stopped at the limit of {len(result.steps)} effects)'
                 if result.stopped_at_limit else '')
        louder = [w for w in result.where_final if w not in result.quieter]
        text += f'; UNEXPLAINED{limit}: ' + ('; '.join(louder[:3]) or 'outside the band')
    elif result.quieter:
        text += '; inside the ensemble band where an effect could show'
    else:
        text += '; the measurement is inside the ensemble band'
    return text + over


def write_files(result: ExplainResult, folder: StrPath, *,
                data: dict[str, Any] | None = None) -> list[str]:
    """
    Write explain.json, report.md and the figures into an existing (staging) folder.

    Parameters
    ----------
    result : ExplainResult
        The workflow's result.
    folder : pathlib.Path
        Where to write; a caller that stages several results (one per axis) publishes them.
    data : dict, optional, keyword-only
        The explain.json document (default ``result.to_dict()``; the application layer adds
        what it knows about the input).

    Returns
    -------
    list of str
        The names written.

    Raises
    ------
    OutputError
        A file cannot be written.

    """
    try:
        return _write_files(result, Path(folder), result.to_dict() if data is None else data)
    except OSError as err:  # disk full, quota, a folder removed under the run
        where = f' ({err.filename})' if err.filename else ''
        raise OutputError(f'cannot write the results: {err.strerror or err}{where}') from err


def _write_files(result: ExplainResult, folder: Path,
                 data: dict[str, Any]) -> list[str]:
    (folder / 'explain.json').write_text(
        json.dumps(data, indent=2, default=_json_default) + '\n')
    layout = result.layout
    names = list(result.comparisons_initial)
    files = ['explain.json']
    plot_signatures(folder / 'overview.png', layout, names,
                    [result.comparisons_initial, result.comparisons_final if result.steps
                     else None], ['baseline', 'final model'], ['0.6', 'tab:blue'],
                    f'measurement vs ensemble: baseline (grey), final model (blue); gap '
                    f'{result.gap_initial:.3f} -> {result.gap_final:.3f}')
    files.append('overview.png')
    for i, step in enumerate(result.steps, 1):
        assert step.before is not None and step.after is not None  # the workflow sets both
        changed = [n for n in names if step.before[n].g > 1 or step.after[n].g > 1] or names[:4]
        name = f'step{i}_{step.effect}.png'
        plot_signatures(folder / name, layout, changed[:4], [step.before, step.after],
                        ['before', 'after'], ['0.6', 'tab:blue'],
                        f'step {i}: + {step.effect} (gap {step.gap_before:.3f} -> '
                        f'{step.gap_after:.3f})')
        files.append(name)
    (folder / 'report.md').write_text(_markdown(result))
    files.append('report.md')
    return files


def _json_default(value: object) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f'not JSON serialisable: {type(value).__name__}')


def _markdown(result: ExplainResult) -> str:
    meas, base = result.measurement, result.baseline
    lines = [
        '# Discrepancy report', '',
        f'Input: `{meas.source}`, axis {meas.axis}, {meas.n} samples at {meas.rate_hz:.6g} Hz '
        f'({meas.duration_s:.1f} '
        f's){", with temperature" if meas.temperature_c is not None else ""}.',
        f'Ensemble: {result.ensemble} members, seed {result.seed}. Run time '
        f'{result.seconds["total"]:.1f} s.', '', f'**Verdict:** {verdict(result)}', '',
    ]
    if result.steps:
        lines += ['Effects named (value ± standard error):', '']
        lines += [f'- {line}' for line in parameter_lines(result)] + ['']
        lines += [
            'Standard errors and 95 % intervals: parametric bootstrap of the final model '
            f'({result.bootstrap} simulated records, each effect refitted; the lattice by least '
            'squares; docs/discrepancy.md, "Uncertainties"); conditional on the fitted baseline.'
            if result.bootstrap else 'Point values only: the bootstrap was off.', '']
    lines += [
        '## Baseline model (paper 000 eqs. 2, 10, 11)', '', '| parameter | value |', '|---|---|',
        f'| bias | {base.bias_rad_s:.6g} rad/s ({base.bias_rad_s * RAD_TO_DEG:.5g} deg/s) |',
        f'| order alpha (variance method) | {base.alpha:.3f} |', f'| f | {base.f:.5g} |',
        f'| sigma_w | {base.sigma_w_rad_s:.4g} rad/s |',
        f'| sigma_nu (white measurement noise) | {base.sigma_nu_rad_s:.4g} rad/s |',
        f'| memory L (fit / simulation) | {base.memory_fit} / {base.memory_sim} |',
        f'| chunks identified (size) | {base.chunks_identified} ({base.chunk_size}) |',
        f'| PSD misfit above fs/100 (rms dex) | {base.psd_misfit:.3f} |', '',
        f'Initial gap G = {result.gap_initial:.3f} (definition: docs/discrepancy.md; 0 = inside '
        'every band).', '',]
    if result.where_final or result.steps:
        first = result.steps[0].where if result.steps else result.where_final
        lines += ['Where the baseline leaves the band:', ''] + [f'- {w}' for w in first] + ['']
    lines += ['![overview](overview.png)', '']
    for i, step in enumerate(result.steps, 1):
        lines += [
            f'## Step {i}: {step.effect}', ''] + _uncertainty_table(step, result) + [
            f'Gap {step.gap_before:.3f} -> {step.gap_after:.3f}. Candidates tried (gap after): '
            + ', '.join(f'{k} {v:.3f}' for k, v in step.candidates.items()) + '.', '']
        if step.where_after:
            lines += [
                'Still outside after this step:', ''] + [f'- {w}' for w in step.where_after] + ['']
        lines += [f'![step {i}](step{i}_{step.effect}.png)', '']
    lines += ['## Result', '']
    if result.unexplained:
        lines += ['**Unexplained**: ' + (
            'the loop stopped at its limit of effects.' if result.stopped_at_limit else
            'no catalogue effect shrinks the gap by the 0.1 the rule asks for.')
            + ' Still outside:', '']
        lines += [f'- {w}' for w in result.where_final if w not in result.quieter] + ['']
        if result.tried_last:
            lines += ['Rejected candidates of the last round (gap after): '
                      + ', '.join(f'{k} {v:.3f}' for k, v in result.tried_last.items()) + '.', '']
    else:
        lines += ['Inside the ensemble band wherever an added effect could show (gap '
                  f'{result.gap_unexplained:.3f} <= 0.1, the tolerance).', '']
    if result.quieter:
        lines += ['**The baseline over-estimates the noise** here: the measurement is quieter '
                  'than the model (below the band only; no effect of the catalogue removes '
                  'noise, so this is not a missing effect):', '']
        lines += [f'- {w}' for w in result.quieter] + ['']
    lines += ['| signature | g (worst point / band edge) | band half-width (z) |', '|---|---|---|']
    for name, comp in result.comparisons_final.items():
        lines.append(f'| {name} | {comp.g:.3f} | {comp.threshold:.2f} |')
    return '\n'.join(lines) + '\n'
