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
The ``report.html`` of ``gyro_noise_explain``, one per analysed axis beside its explain.json.

Built from explain.json (``ExplainResult.to_dict()`` as written) and the result in memory.
The verdict line is :func:`..explain.report.verdict` (OK when the measurement ends inside the
ensemble band, WARN when it stays outside: unexplained); the card holds the gap and the effects
named; "In short" the named effects with their uncertainties, made by the same function as
report.md (:func:`..explain.report.parameter_lines`). The PNG figures report.md shows
(``overview.png``, one per step) are embedded in the page as data.
"""

from collections.abc import Sequence
import json
from pathlib import Path
from typing import Any, TYPE_CHECKING

from .figures import series_figure
from .page import Key, Num, Page, pointer, Table, Verdict, write_report_html
from ..units import RAD_TO_DEG as _DEG

if TYPE_CHECKING:
    from bokeh.plotting import figure

    from ..explain.workflow import ExplainResult

_BASELINE = (('Bias (deg/s)', 'bias_rad_s', '.5g', _DEG),
             ('Order alpha (variance method)', 'alpha', '.3f', 1.0),
             ('f', 'f', '.5g', 1.0),
             ('sigma_w (deg/s)', 'sigma_w_rad_s', '.4g', _DEG),
             ('sigma_nu, white measurement noise (deg/s)', 'sigma_nu_rad_s', '.4g', _DEG),
             ('Memory L, fit', 'memory_fit', 'd', 1.0),
             ('Memory L, simulation', 'memory_sim', 'd', 1.0),
             ('Chunks identified', 'chunks_identified', 'd', 1.0),
             ('Chunk size', 'chunk_size', 'd', 1.0),
             ('PSD misfit above a hundredth of the rate (rms dex)', 'psd_misfit', '.3f', 1.0))


def explain_page(result: 'ExplainResult', command: Sequence[str] | None = None,
                 data: dict[str, Any] | None = None,
                 images: Sequence[tuple[str, bytes]] = ()) -> Page:
    """
    Build the page of one explained axis.

    Parameters
    ----------
    result : explain.workflow.ExplainResult
        The workflow's result.
    command : sequence of str, optional
        The command line.
    data : dict, optional
        The axis' explain.json document as the tool writes it (default:
        ``result.to_dict()``); the page embeds exactly this.
    images : sequence of tuple
        ``(caption, png bytes)`` of the tool's PNG figures, embedded in the page.

    Returns
    -------
    Page

    """
    from ..explain.report import _json_default, parameter_lines, verdict

    # exactly the explain.json document (numpy values as explain/report.py writes them)
    doc = json.loads(json.dumps(result.to_dict() if data is None else data,
                                default=_json_default))
    text = verdict(result)
    level = 'WARN' if result.unexplained else 'OK'
    short = ['## In short', '']
    if result.steps:
        short += ['Effects named (value ± standard error):', '']
        short += [f'- {line}' for line in parameter_lines(result)]
    else:
        short += ['No effect named: the baseline model (bias, fractional noise, white noise) '
                  'holds the measurement.']
    card = [Table('Gap of the measurement to the ensemble band (0: inside every band)',
                  ('Quantity', 'Gap'), (('Initial (baseline)', Num('/gap_initial', '.3f')),
                                        ('Final model', Num('/gap_final', '.3f'))))]
    if doc['steps']:
        card.append(Table('Steps: the effects named, in order', ('Step effect', 'Gap before',
                                                                 'Gap after'),
                          tuple((Num(pointer('steps', i, 'effect')),
                                 Num(pointer('steps', i, 'gap_before'), '.3f'),
                                 Num(pointer('steps', i, 'gap_after'), '.3f'))
                                for i in range(len(doc['steps'])))))
    tables = [Table('Baseline model (paper 000 eqs. 2, 10, 11)', ('Parameter', 'Value'),
                    tuple((label, Num(pointer('baseline', key), fmt, scale=scale))
                          for label, key, fmt, scale in _BASELINE))]
    sig = doc['signatures_final']
    tables.append(Table('Signatures of the final model', ('Signature',
                                                          'g (worst point / band edge)',
                                                          'Band half-width (z)'),
                        tuple((Key(name), Num(pointer('signatures_final', name, 'g'), '.3f'),
                               Num(pointer('signatures_final', name, 'threshold_z'), '.2f'))
                              for name in sig)))
    figures: list[tuple[str, figure]] = []
    if sig:
        k = list(range(len(sig)))
        figures.append((
            'Each signature of the final model: g, its worst point over the edge of the '
            'ensemble band (above one: outside), in the order of the table.',
            series_figure([('g', k, [v['g'] for v in sig.values()]),
                           ('band edge', k, [1.0] * len(k))],
                          title='Signatures of the final model',
                          x_label='signature number (table order)',
                          y_label='g (worst point / band edge, dimensionless)')))
    method = ('The baseline model (fractional noise, paper 000) is fitted to the measurement; an '
              'ensemble simulated from it gives a band per signature (Allan deviation, spectrum, '
              'distribution, ...); effects from the catalogue are added one at a time while the '
              'gap shrinks (docs/discrepancy.md).')
    inp = doc['input']
    return Page(title=f"gyro_noise_explain: {inp['source']}, axis {inp['axis']}", data=doc,
                in_short_markdown='\n'.join(short), verdict=Verdict(level, text),
                card=tuple(card), card_title='The gap and the effects named',
                figures=tuple(figures), images=tuple(images),
                tables=tuple(tables), method_markdown=method,
                command=None if command is None else tuple(command), inputs=(inp['source'],),
                version=_version())


def _version() -> str:
    from .. import __version__

    return __version__


def write_explain_html(result: 'ExplainResult', folder: Path, *,
                       command: Sequence[str] | None = None,
                       data: dict[str, Any] | None = None) -> Path:
    """
    Write ``report.html`` of one explained axis into ``folder`` (beside its explain.json).

    Parameters
    ----------
    result : explain.workflow.ExplainResult
        The workflow's result.
    folder : pathlib.Path
        The (staged) folder of that axis.
    command : sequence of str, optional, keyword-only
        The command line.
    data : dict, optional, keyword-only
        The axis' explain.json document (:func:`explain_page`).

    Returns
    -------
    pathlib.Path

    """
    names = ['overview.png'] + [f'step{i}_{step.effect}.png'
                                for i, step in enumerate(result.steps, 1)]
    captions = ['Measurement against the ensemble band of every signature: the baseline '
                '(grey) and the final model (blue); red circles: points outside the band.']
    captions += [f'Step {i}: + {step.effect}, the signatures it changed, before (grey) and '
                 'after (blue).' for i, step in enumerate(result.steps, 1)]
    images = [(c, (folder / n).read_bytes()) for c, n in zip(captions, names)
              if (folder / n).is_file()]
    return write_report_html(explain_page(result, command, data, images), folder / 'report.html')
