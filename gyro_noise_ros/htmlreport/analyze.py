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
The ``report.html`` of gyro_noise_analyze (and so of ``make demo``).

Built from the summary.json document and the arrays the tool holds in memory (per-chunk bias,
variance and orders; the Allan results of the gyro and the accelerometer), never from
summary.md. The verdict line and the datasheet card are :mod:`..analysis.card`'s (summary.md
opens with the same), with the imu.yaml the tool wrote, ready to copy; "In short" is
:func:`..analysis.summary_md.in_short_markdown` of the same document, its glossary folded.
"""

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .figures import allan_figure, series_figure
from .page import Cell, Key, Num, Page, pointer, Table, Unit, Verdict, write_report_html
from ..analysis.card import card_tables, verdict
from ..analysis.figures import allan_curves
from ..analysis.summary_md import glossary_markdown, in_short_markdown
from ..core.allan import AllanResult
from ..units import ACCEL_ADEV, GYRO_ADEV, RAD_TO_DEG as _DEG, time_unit

if TYPE_CHECKING:
    from bokeh.plotting import figure

#: ``{axis: [(label, rows)]}``: per-chunk rows of each bag (see :func:`analyze_page`).
_PerChunk = Mapping[str, Sequence[tuple[str, NDArray[np.float64]]]]
#: ``{(label, axis): (AllanResult, noise terms, readout)}``.
_AllanStore = Mapping[tuple[str, str], tuple[AllanResult, Any, Any]]

METHOD = """\
Each record is cut into chunks; per chunk the bias (mean), the noise variance and the fractional
order alpha of the model of paper 000 (Sierociuk et al., Sensors 2025), `Delta^alpha v = f v + w`,
are identified by two methods (variance and correlation) over the order grid. Across chunks:
offset drift = least-squares slope of the chunk bias over time (Table 3; its standard error is
valid for correlated chunk biases), variances over chunks with ddof = 1 (Tables 4-6). The
overlapping Allan deviation of the whole record is read by the one datasheet readout
(core/readout.py, docs/allan.md) and fitted by the five-term IEEE 952 model; intervals are
68.3 % (1 sigma).
Every option of the run (chunk size, order grid, memory L, gap policy, ...) is in the Options
table; docs/offline_tool.md explains every column.
"""


def _axes(doc: dict[str, Any]) -> list[str]:
    axes: list[str] = []
    for b in doc['bags']:
        for a in b['axes']:
            if a not in axes:
                axes.append(a)
    return axes


def _tables(doc: dict[str, Any]) -> list[Table]:
    """Return the page's tables: per axis the paper's Tables 3-6, Allan and health; then counts."""
    bags = doc['bags']
    tables: list[Table] = []
    for axis in _axes(doc):
        # (bag index, JSON pointer of the bag's axis entry) of the bags that have the axis
        rows = [(i, pointer('bags', i, 'axes', axis)) for i, b in enumerate(bags)
                if axis in b['axes']]
        # an Allan-only bag (shorter than one chunk) has no row in the chunk tables
        chunked = [(i, p) for i, p in rows if not bags[i].get('allan_only')]
        if chunked:
            tables += [_drift_table(axis, chunked), _variance_table(axis, chunked)]
            tables += [_order_table(bags, axis, chunked, num=num, method=method, key=key,
                                    tie=tie)
                       for num, method, key, tie in ((5, 'variance', 'alpha_var', 'ties_var'),
                                                     (6, 'correlation', 'alpha_corr',
                                                      'ties_corr'))]
        tables += _allan_tables(bags, axis, rows)
        tables += _health_tables(bags, axis, rows)
    tables += [_counts_table(bags), _options_table(doc['options'])]
    return tables


def _label(i: int) -> Num:
    return Num(pointer('bags', i, 'label'))


def _drift_table(axis: str, rows: list[tuple[int, str]]) -> Table:
    return Table(
        f'Axis {axis}: how fast the bias moves, offset drift of the chunk bias '
        '(paper 000 Table 3)',
        ('Sequence', 'Offset drift, magnitude ((deg/s)/h)', 'Signed slope ((deg/s)/h)',
         'Std. error ((deg/s)/h)', 'Mean bias (deg/s)', 'Chunks'),
        tuple((_label(i), Num(p + '/offset_drift_abs_deg_s_per_h', '.6f'),
               Num(p + '/offset_drift_deg_s_per_h', '+.6f'),
               Num(p + '/offset_drift_stderr_deg_s_per_h', '.6f'),
               Num(p + '/bias_mean_deg_s', '.6f'), Num(p + '/chunks', 'd'))
              for i, p in rows))


def _variance_table(axis: str, rows: list[tuple[int, str]]) -> Table:
    return Table(
        f'Axis {axis}: how large the noise is, variance within chunks (paper 000 Table 4)',
        ('Sequence', 'Mean noise variance ((deg/s)^2)',
         'Variance of noise variance ((deg/s)^4)'),
        tuple((_label(i), Num(p + '/mean_variance_deg2_s2'),
               Num(p + '/variance_of_variances_deg4_s4')) for i, p in rows))


def _order_table(bags: list[dict[str, Any]], axis: str, rows: list[tuple[int, str]], *,
                 num: int, method: str, key: str, tie: str) -> Table:
    out = []
    for i, p in rows:
        a = bags[i]['axes'][axis]
        order: Cell
        if a.get(key + '_multimodal'):
            # a mean between separate basins is where no chunk is: the modes instead
            order = ('modes: ',)
            for k in range(len(a[key + '_modes'])):
                m = f'{p}/{key}_modes/{k}'
                order += (('; ' if k else ''), Num(m + '/order', '.3f'), ' (',
                          Num(m + '/chunks', 'd'), ' chunks)')
        else:
            order = Num(f'{p}/{key}_mean', '.6f')
        out.append((_label(i), order, Num(f'{p}/{key}_variance', '.6f'),
                    Num(f'{p}/{tie}', 'd')))
    return Table(
        f'Axis {axis}: how much memory the noise has, fractional order, {method} method '
        f'(paper 000 Table {num})',
        ('Sequence', 'Estimated order', 'Variance of estimated order', 'Ties'),
        tuple(out))


def _allan_tables(bags: list[dict[str, Any]], axis: str,
                  rows: list[tuple[int, str]]) -> list[Table]:
    """Return the datasheet table and the model-fit table of the bags that have them (0-2)."""
    tables: list[Table] = []
    sheet_rows = [_datasheet_row(i, p, bags[i]['axes'][axis].get('allan_datasheet'))
                  for i, p in rows if bags[i]['axes'][axis].get('allan_datasheet')]
    if sheet_rows:
        tables.append(Table(
            f'Axis {axis}: Allan deviation, the datasheet numbers (customary units)',
            ('Sequence', 'Bias stability (deg/h)', 'at tau (s)',
             'B = bias stability / 0.664 (deg/h)', 'ARW (deg/sqrt(h))',
             'ARW read over taus (s)', 'K fit (deg/h/sqrt(h))', 'K bound (deg/h/sqrt(h))',
             'Usable from tau (s)'),
            tuple(sheet_rows),
            note='Read off the curve by the one readout (core/readout.py): intervals 68.3 %; '
            '"<=" marks an upper bound.'))
    terms = [(i, p) for i, p in rows if bags[i]['axes'][axis].get('allan')]
    if terms:
        keys: list[str] = []
        for i, _ in terms:
            for k, v in bags[i]['axes'][axis]['allan'].items():
                if k not in keys and not isinstance(v, (dict, list, str, bool)):
                    keys.append(k)
        keys.sort(key=lambda k: list(_TERM_LABELS).index(k) if k in _TERM_LABELS else 99)
        tables.append(Table(
            f'Axis {axis}: Allan deviation, IEEE 952 model fit',
            ('Term', 'Unit', *(bags[i]['label'] for i, _ in terms)),
            tuple((_TERM_LABELS.get(k, (k, ''))[0], Unit(_TERM_LABELS.get(k, (k, ''))[1]),
                   *(Num(f'{p}/allan/{k}', '.4g') if k in bags[i]['axes'][axis]['allan']
                     else 'n/a' for i, p in terms)) for k in keys),
            note='The five-term model fitted to the whole usable curve: a model for '
            'simulation and filters, not the datasheet numbers. SI rows give the values '
            'summary.json holds under the same names.'))
    return tables


#: Readable names and units of the IEEE 952 model's keys (summary.json ``allan``), in order.
_TERM_LABELS = {
    'quantization_deg': ('Q, angle quantization', 'deg'),
    'angle_random_walk_deg_per_sqrt_h': ('N, angle random walk', 'deg/sqrt(h)'),
    'bias_instability_deg_per_h': ('B, bias instability', 'deg/h'),
    'rate_random_walk_deg_per_h_sqrt_h': ('K, rate random walk', 'deg/h/sqrt(h)'),
    'rate_ramp_deg_per_h2': ('R, rate ramp', 'deg/h^2'),
    'quantization_rad': ('Q (SI)', 'rad'),
    'angle_random_walk_rad_per_sqrt_s': ('N (SI)', 'rad/s/sqrt(Hz)'),
    'bias_instability_rad_per_s': ('B (SI)', 'rad/s'),
    'rate_random_walk_rad_per_s_sqrt_s': ('K (SI)', 'rad/s^2/sqrt(Hz)'),
    'rate_ramp_rad_per_s2': ('R (SI)', 'rad/s^2'),
    'tau_min_s': ('Fitted from tau', 's'),
    'tau_max_s': ('Fitted up to tau', 's'),
    'rms_relative_residual': ('RMS relative misfit of the model', '1'),
}


def _datasheet_row(i: int, p: str, d: dict[str, Any]) -> tuple[Cell, ...]:
    """Return one bag's row of the datasheet table (``d``: its ``allan_datasheet`` entry)."""
    q = p + '/allan_datasheet'
    bound = '<= ' if d.get('bias_stability_upper_bound') else ''
    where = ((Num(q + '/arw_tau_range_s/0', '.3g'), ' to ',
              Num(q + '/arw_tau_range_s/1', '.3g'))
             if d.get('arw_from_region') and d.get('arw_tau_range_s')
             else 'ADEV read at one second: no white-noise region')
    k_fit: Cell
    k_fit = Num(q + '/rate_random_walk_deg_per_h_sqrt_h', '.3g')
    if not d.get('rate_random_walk_resolved'):
        k_fit = (k_fit, ' (not resolved)')
    return (
        _label(i),
        (Num(q + '/bias_stability_deg_h', '.4g', bound), ' (',
         Num(q + '/bias_stability_ci_low_deg_h', '.3g'), ' to ',
         Num(q + '/bias_stability_ci_high_deg_h', '.3g'), ')'),
        Num(q + '/bias_stability_tau_s', '.4g'),
        Num(q + '/bias_instability_deg_h', '.4g', bound),
        (Num(q + '/arw_deg_per_sqrt_h', '.4g'), ' (',
         Num(q + '/arw_ci_low_deg_per_sqrt_h', '.3g'), ' to ',
         Num(q + '/arw_ci_high_deg_per_sqrt_h', '.3g'), ')'),
        where, k_fit, Num(q + '/rate_random_walk_bound_deg_per_h_sqrt_h', '.3g'),
        Num(q + '/usable_from_s', '.3g'))


def _health_tables(bags: list[dict[str, Any]], axis: str,
                   rows: list[tuple[int, str]]) -> list[Table]:
    health = [(i, p) for i, p in rows if 'health' in bags[i]['axes'][axis]]
    if not health:
        return []
    return [Table(
        f'Axis {axis}: health verdict against the reference',
        ('Sequence', 'Level', 'Message'),
        tuple((_label(i), Num(p + '/health/level'), Num(p + '/health/message'))
              for i, p in health))]


def _counts_table(bags: list[dict[str, Any]]) -> Table:
    return Table(
        'Input counts',
        ('Sequence', 'Topic', 'Rate (Hz)', 'Rate method', 'Stamp jitter (s)', 'Duration (s)',
         'Samples', 'Lost', 'Gaps', 'Out-of-order stamps', 'Tail samples'),
        tuple((Num(pointer('bags', i, 'label')), Num(pointer('bags', i, 'topic')),
               Num(pointer('bags', i, 'rate_hz'), '.6g'),
               Num(pointer('bags', i, 'rate_method')),
               Num(pointer('bags', i, 'stamp_jitter_s'), '.3g'),
               Num(pointer('bags', i, 'duration_s'), '.1f'),
               *(Num(pointer('bags', i, k), 'd') for k in (
                   'samples', 'samples_lost', 'gaps', 'out_of_order_stamps', 'tail_samples')))
              for i in range(len(bags))))


def _options_table(opts: dict[str, Any]) -> Table:
    return Table(
        'Options', ('Option', 'Value'),
        tuple((Key(k), Num(pointer('options', k), 'g')) for k, v in opts.items()
              if v is None or isinstance(v, (bool, int, float, str))))


def _allan_figures(doc: dict[str, Any], allan_store: _AllanStore,
                   accel_allan: Mapping[tuple[str, str], AllanResult] | None
                   ) -> list[tuple[str, 'figure']]:
    """Return the Allan deviation of the angular rate (deg/h) and of the specific force (mg)."""
    curves = allan_curves(doc, allan_store, accel_allan)
    figures: list[tuple[str, figure]] = []
    readout = ('dashed: N, the -1/2 line, read at 1 s; dotted: the bias-stability floor, B = '
               'floor / 0.664; dash-dot: K, the +1/2 line (K is its value at 3 s); diamonds: the '
               'readout points, hover them for the numbers')
    for sensor, unit, what in (('gyro', GYRO_ADEV.unit, 'angular rate'),
                               ('accelerometer', ACCEL_ADEV.unit, 'specific force')):
        if curves[sensor]:
            figures.append((
                f'Allan deviation of the {what} (band: 68.3 % interval). {readout}. A click on '
                'a legend entry shows or hides it (the IEEE 952 model starts hidden).',
                allan_figure(curves[sensor], title=f'Allan deviation, {sensor}', unit=unit)))
    return figures


def _figures(doc: dict[str, Any], per_chunk: _PerChunk, allan_store: _AllanStore,
             accel_allan: Mapping[tuple[str, str], AllanResult] | None
             ) -> list[tuple[str, 'figure']]:
    figures = _allan_figures(doc, allan_store, accel_allan)
    # per_chunk rows: (t_mid_s, bias_rad_s, variance_rad2_s2, alpha_var, alpha_corr)
    series = [(f'{label} {axis}' if len(doc['bags']) > 1 else axis, r)
              for axis, v in per_chunk.items() for label, r in v if r.shape[0]]
    if series:
        clock = time_unit(max(float(np.nanmax(r[:, 0])) for _, r in series))
        when = [(name, r[:, 0] * clock.per_si, r) for name, r in series]
        x_label = f'time from the first sample ({clock.unit})'
        figures.append(('Chunk bias over time (one point per chunk; the least-squares slope of '
                        'these points is the offset drift of the tables).',
                        series_figure([(n, t, r[:, 1] * _DEG) for n, t, r in when],
                                      title='Bias per chunk', x_label=x_label,
                                      y_label='bias (deg/s)')))
        figures.append(('Noise variance within each chunk.',
                        series_figure([(n, t, r[:, 2] * _DEG ** 2) for n, t, r in when],
                                      title='Noise variance per chunk', x_label=x_label,
                                      y_label='variance ((deg/s)^2)')))
        if series[0][1].shape[1] >= 5:
            orders = [(f'{n}, {m}', t, r[:, c]) for n, t, r in when
                      for m, c in (('variance method', 3), ('correlation method', 4))]
            figures.append(('Fractional order alpha per chunk by both methods (0: white noise, '
                            '1: random walk; dimensionless).',
                            series_figure(orders, title='Fractional order per chunk',
                                          x_label=x_label,
                                          y_label='order alpha (dimensionless)')))
    return figures


def analyze_page(doc: dict[str, Any], *, per_chunk: _PerChunk, allan_store: _AllanStore,
                 accel_allan: Mapping[tuple[str, str], AllanResult] | None = None,
                 imu_yaml: str | None = None) -> Page:
    """
    Build the page of one gyro_noise_analyze run.

    Parameters
    ----------
    doc : dict
        The summary.json document (as written).
    per_chunk : dict
        ``{axis: [(label, rows)]}`` with rows ``(t_mid_s, bias_rad_s, variance_rad2_s2,
        alpha_var, alpha_corr)`` per analysed chunk.
    allan_store : dict
        ``{(label, axis): (AllanResult, noise terms, readout)}``.
    accel_allan : dict, optional, keyword-only
        ``{(label, axis): AllanResult}`` of the accelerometer (m/s^2).
    imu_yaml : str, optional, keyword-only
        The imu.yaml the tool wrote, shown with the card.

    Returns
    -------
    Page

    """
    import numba
    import scipy

    level, text = verdict(doc)
    card = tuple(Table(title, columns, tuple(rows)) for title, columns, rows in card_tables(doc))
    blocks = (('imu.yaml (Kalibr, SI; written beside this page)', imu_yaml),) if imu_yaml else ()
    return Page(
        title='gyro_noise_analyze report: ' + ', '.join(b['label'] for b in doc['bags']),
        data=doc, in_short_markdown=in_short_markdown(doc, glossary=False),
        verdict=Verdict(level, text), card=card, card_title='Datasheet numbers',
        card_blocks=blocks, glossary_markdown=glossary_markdown(),
        figures=tuple(_figures(doc, per_chunk, allan_store, accel_allan)),
        tables=tuple(_tables(doc)),
        method_markdown=METHOD, command=doc.get('command'),
        inputs=tuple(b['path'] for b in doc['bags']), version=doc.get('version', ''),
        extra_versions=(('scipy', scipy.__version__), ('numba', numba.__version__)))


def write_analyze_html(out: Path, doc: dict[str, Any], per_chunk: _PerChunk,
                       allan_store: _AllanStore, *,
                       accel_allan: Mapping[tuple[str, str], AllanResult] | None = None,
                       imu_yaml: str | None = None) -> Path:
    """
    Write ``report.html`` of a gyro_noise_analyze run into the staged folder ``out``; return it.

    ``doc`` is the summary.json document; the other arguments are those of :func:`analyze_page`.

    """
    return write_report_html(analyze_page(doc, per_chunk=per_chunk, allan_store=allan_store,
                                          accel_allan=accel_allan, imu_yaml=imu_yaml),
                             out / 'report.html')


__all__ = ['analyze_page', 'write_analyze_html']
