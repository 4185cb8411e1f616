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
summary.md of an analysis: the verdict and the datasheet card first, then the rest.

After them: "In short" in plain words, the paper's Tables 3-6 and the Allan tables.

Rendered from the summary.json document (:mod:`.summary_json`), never from the engine's
objects, so the Markdown cannot say a number the JSON does not hold. The verdict and the card are
:mod:`.card`'s; :func:`in_short_markdown` and :func:`glossary_markdown` are reused by the HTML
report; :func:`readout_text` is the tool's printed one-line readout.
"""

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from .card import card_markdown, verdict
from ..core.health import drift_t_threshold
from ..units import UNIT_POLICY

#: The rows of one axis' tables: (bag label, that axis' entry of summary.json).
Rows = Sequence[tuple[str, Mapping[str, Any]]]

__all__ = ['IN_SHORT_DEFINITIONS', 'fmt', 'glossary_markdown', 'in_short_markdown', 'modes_text',
           'readout_text', 'summary_markdown']


def readout_text(sheet: Mapping[str, Any]) -> str:
    """
    Return the readout's datasheet numbers in one line (the tool's printed summary).

    Parameters
    ----------
    sheet : dict
        ``allan_datasheet`` of summary.json (:meth:`..core.readout.AllanReadout.as_dict`).

    Returns
    -------
    str
        ``bias stability [<=]X deg/h (Y deg/s) at tau = T s, ARW Z deg/sqrt(h)``.

    """
    bound = '<=' if sheet.get('bias_stability_upper_bound') else ''
    return (f"bias stability {bound}{fmt(sheet.get('bias_stability_deg_h'), '.3g')} deg/h "
            f"({bound}{fmt(sheet.get('bias_stability_deg_s'), '.3g')} deg/s) at tau = "
            f"{fmt(sheet.get('bias_stability_tau_s'), '.3g')} s, ARW "
            f"{fmt(sheet.get('arw_deg_per_sqrt_h'), '.3g')} deg/sqrt(h)")


def fmt(value: object, spec: str) -> str:
    """Format ``value`` with ``spec``, None as 'n/a' (a table cell or a printed number)."""
    if value is None:
        return 'n/a'
    return format(value, spec)


def modes_text(modes: Iterable[Mapping[str, Any]]) -> str:
    """Return separate modes of the fractional order as ``0.123 (4 chunks), ...``."""
    return ', '.join(f"{m['order']:.3f} ({m['chunks']} chunks)" for m in modes)


#: One line per number: what it is and which to compare with a datasheet (the "In short"
#: definitions of summary.md, reused by any other report of the same document).
IN_SHORT_DEFINITIONS = (
    ('Bias stability', 'the level where the Allan deviation stops falling (deg/h, or deg/s): how '
     'steady the bias stays at the best averaging time. Compare it with a datasheet\'s "in-run '
     'bias stability". "<=" marks an upper bound: the record ended before the curve turned up.'),
    ('B', 'bias stability / 0.664, the IEEE 952 bias-instability coefficient (deg/h). Some '
     'datasheets quote B instead of the bias stability: check which one they mean.'),
    ('ARW', 'angle random walk, the white-noise level: the -1/2 slope line of the Allan deviation '
     'read at 1 s (deg/sqrt(h)). Compare it with a datasheet\'s "angle random walk"; a rate noise '
     'density in deg/s/sqrt(Hz) is ARW / 60.'),
    ('N', 'the same angle random walk in SI units (rad/s/sqrt(Hz)), the '
     'gyroscope_noise_density of imu.yaml (Kalibr).'),
    ('K', 'rate random walk, the +1/2 slope at long averaging times (deg/h/sqrt(h)); most records '
     'only bound it from above. In SI it is the gyroscope_random_walk of imu.yaml.'),
    ('Offset drift', 'the least-squares slope of the per-chunk bias over time ((deg/s)/h), with '
     'its standard error and whether it is significant.'),
    ('Order, variance method / correlation method', 'the fractional order alpha of the noise '
     'model of paper 000 (Delta^alpha v = f v + w), identified chunk by chunk by two methods: 0 '
     'is white noise, 1 a random walk, in between noise with memory. A property of the noise, '
     'not a datasheet number.'),
)


def _drift_text(a: Mapping[str, Any]) -> str | None:
    drift, se = a.get('offset_drift_deg_s_per_h'), a.get('offset_drift_stderr_deg_s_per_h')
    if drift is None:
        return None
    sig = abs(drift) / se if se else float('nan')
    need = drift_t_threshold(3.0, a['chunks'])
    word = 'significant' if sig > need else 'not significant'
    # With few chunks the Student-t quantile is far above 3: "5.9 standard errors, not
    # significant" must say why, or it reads as a contradiction.
    return (f'offset drift {drift:+.3g} +/- {fmt(se, ".2g")} (deg/s)/h, {fmt(sig, ".2g")} '
            f'standard errors from zero: {word} (with {a["chunks"]} chunks a 3-sigma test needs '
            f'{fmt(need, ".2g")} standard errors, the Student-t quantile of the same '
            'false-alarm rate)')


def _plain_summary(b: Mapping[str, Any], axis: str, a: Mapping[str, Any]) -> str:
    """One plain-language paragraph for one bag and axis (people first, tables after)."""
    rate = b.get('rate_hz')
    parts = [f"**{b['label']}, axis {axis}:** {b['samples']} samples over "
             f"{fmt(b['duration_s'], '.1f')} s at {fmt(rate, '.4g')} Hz "
             f"(rate from {b.get('rate_method') or 'the stamps'}"
             + (', bursty stamps' if b.get('stamps_bursty') else '') + ')']
    lost = b['samples_lost']
    parts.append(f'{lost} sample(s) lost' if lost else 'no sample lost')
    if b.get('allan_only'):
        parts.append(f"**Allan deviation only**: {b['allan_only']}")
    left = sum(v for k, v in (b.get('left_out') or {}).items() if isinstance(v, int))
    if left:
        parts.append(f'{left} sample(s) left out (window or motion)')
    sheet = a.get('allan_datasheet') or {}
    if sheet.get('bias_stability_deg_h') is not None:
        bound = '<= ' if sheet.get('bias_stability_upper_bound') else ''
        why = (' (an upper bound: the curve had not turned up by the end of the record)'
               if bound else '')
        parts.append(f"bias stability {bound}{sheet['bias_stability_deg_h']:.3g} deg/h "
                     f"({sheet['bias_stability_deg_s']:.3g} deg/s) at tau = "
                     f"{sheet['bias_stability_tau_s']:.3g} s{why}, B {bound}"
                     f"{sheet['bias_instability_deg_h']:.3g} deg/h")
    if sheet.get('arw_deg_per_sqrt_h') is not None:
        source = ('' if sheet.get('arw_from_region')
                  else ', read at 1 s: the curve has no -1/2 region')
        parts.append(
            f"ARW {sheet['arw_deg_per_sqrt_h']:.3g} deg/sqrt(h) "
            f"({sheet['arw_ci_low_deg_per_sqrt_h']:.3g}-"
            f"{sheet['arw_ci_high_deg_per_sqrt_h']:.3g}{source})")
    if sheet.get('fit_quality') == 'poor':
        parts.append('the IEEE 952 model fit misses the Allan curve (see the Allan tables)')
    drift = _drift_text(a)
    if drift:
        parts.append(drift)
    for key, name in (('alpha_var', 'variance method'), ('alpha_corr', 'correlation method')):
        if a.get(key + '_multimodal'):
            parts.append(f'order ({name}) in separate modes: {modes_text(a[key + "_modes"])}')
        elif a.get(key + '_mean') is not None:
            parts.append(f"order ({name}) {a[key + '_mean']:.3f}")
    if 'health' in a:
        parts.append(f"**health {a['health']['level']}**: {a['health']['message']}")
    return '; '.join(parts) + '.'


def glossary_markdown() -> str:
    """
    Return the definitions of the numbers, one line each, as a Markdown list.

    Returns
    -------
    str
        What each number is and which to compare with a datasheet (:data:`IN_SHORT_DEFINITIONS`).

    """
    return '\n'.join(f'* **{name}**: {text}' for name, text in IN_SHORT_DEFINITIONS)


def in_short_markdown(doc: Mapping[str, Any], *, glossary: bool = True) -> str:
    """
    Return the plain-language "In short" section of a summary.json document, as Markdown.

    One paragraph per bag and axis, and the bags' warnings; then (``glossary``) one line
    defining each number (bias stability, B, ARW, N, K, offset drift, the two orders) that says
    which to compare with a datasheet.

    Parameters
    ----------
    doc : dict
        The summary.json document.
    glossary : bool, keyword-only
        Add the definitions (:func:`glossary_markdown`); the HTML page folds them instead.

    Returns
    -------
    str
        Markdown, starting with the ``## In short`` heading.

    """
    lines = ['## In short', '']
    for b in doc['bags']:
        for axis, a in b['axes'].items():
            lines += [_plain_summary(b, axis, a), '']
        for text in b.get('warnings') or ():
            lines += [f"* warning ({b['label']}): {text}"]
        if b.get('warnings'):
            lines.append('')
    if glossary:
        lines += ['What the numbers mean:', '', glossary_markdown(), '']
    return '\n'.join(lines)


_CUSTOMARY = (
    ('quantization_deg', 'Q (deg)'),
    ('angle_random_walk_deg_per_sqrt_h', 'N (deg/sqrt(h))'),
    ('bias_instability_deg_per_h', 'B (deg/h)'),
    ('rate_random_walk_deg_per_h_sqrt_h', 'K (deg/h/sqrt(h))'),
    ('rate_ramp_deg_per_h2', 'R (deg/h^2)'),
)


def summary_markdown(doc: Mapping[str, Any]) -> str:
    """
    Render a plain-language summary, the paper's Tables 3-6 and the counts as Markdown.

    Parameters
    ----------
    doc : dict
        The summary.json document.

    Returns
    -------
    str

    """
    bags = doc['bags']
    axes = []
    for b in bags:
        for a in b['axes']:
            if a not in axes:
                axes.append(a)
    level, text = verdict(doc)
    lines = ['# gyro_noise_analyze summary', '', f'**Verdict: {level}**. {text}', '',
             UNIT_POLICY, '']
    card = card_markdown(doc)
    if card:
        lines += ['## Datasheet numbers', '',
                  'Read off the Allan deviation by the one readout (core/readout.py): '
                  'value (68.3 % interval) in the customary unit, then where it was read and SI; '
                  '"<=" marks an upper bound. Kalibr\'s values are in imu.yaml beside this '
                  'file.', '', card]
    lines.append(in_short_markdown(doc))
    lines += _method_lines(doc)
    for axis in axes:
        rows = [(b['label'], b['axes'][axis]) for b in bags if axis in b['axes']]
        # an Allan-only bag (shorter than one chunk) has no row in the chunk tables
        chunked = [(b['label'], b['axes'][axis]) for b in bags
                   if axis in b['axes'] and not b.get('allan_only')]
        lines += [f'## Axis {axis}', '']
        if chunked:
            lines += _drift_lines(chunked)
            lines += _variance_lines(chunked)
            for num, method, key in ((5, 'variance', 'alpha_var'),
                                     (6, 'correlation', 'alpha_corr')):
                lines += _order_lines(chunked, num=num, method=method, key=key)
        if any(a.get('allan') or a.get('allan_datasheet') for _, a in rows):
            lines += _datasheet_lines(rows)
            lines += _model_fit_lines(rows)
        lines += _health_lines(rows)
        lines.append('')
    lines += _counts_lines(bags)
    return '\n'.join(lines)


def _method_lines(doc: Mapping[str, Any]) -> list[str]:
    opts = doc['options']
    return [
        '## Method',
        '',
        f"Tool {doc['tool']} {doc['version']}; chunk size {opts['chunk_size']} samples; order "
        'grid '
        f"{opts['order_grid']['start']:g}:{opts['order_grid']['stop']:g}:"
        f"{opts['order_grid']['step']:g}; "
        f"memory L = {opts['memory']}; gap policy {opts['gap_policy']}. Tables follow paper 000 "
        '(Sierociuk et al., Sensors 2025): offset drift = least-squares slope of the chunk bias '
        'over time '
        '(Table 3, standard error valid for correlated chunk biases); variances over chunks with '
        'ddof = 1. Confidence intervals are 68.3 % (1 sigma).',
        '',
    ]


def _drift_lines(rows: Rows) -> list[str]:
    lines = ['### How fast the bias moves: offset drift of the chunk bias '
             '(paper 000 Table 3)', '',
             # The paper tabulates magnitudes; the sign is kept beside them so a
             # reader never has to guess which way the bias moved.
             '| Sequence | Offset drift, magnitude ((deg/s)/h) | Signed slope ((deg/s)/h) '
             '| Std. error ((deg/s)/h) | Mean bias (deg/s) | Chunks |',
             '|---|---:|---:|---:|---:|---:|']
    for label, a in rows:
        lines.append(f"| {label} | {fmt(a['offset_drift_abs_deg_s_per_h'], '.6f')} | "
                     f"{fmt(a['offset_drift_deg_s_per_h'], '+.6f')} | "
                     f"{fmt(a['offset_drift_stderr_deg_s_per_h'], '.6f')} | "
                     f"{fmt(a['bias_mean_deg_s'], '.6f')} | {a['chunks']} |")
    return lines


def _variance_lines(rows: Rows) -> list[str]:
    lines = ['', '### How large the noise is: variance within chunks (paper 000 Table 4)',
             '',
             '| Sequence | Mean noise variance ((deg/s)^2) | Variance of noise variance '
             '((deg/s)^4) |', '|---|---:|---:|']
    for label, a in rows:
        lines.append(f"| {label} | {fmt(a['mean_variance_deg2_s2'], '.6g')} | "
                     f"{fmt(a['variance_of_variances_deg4_s4'], '.6g')} |")
    return lines


def _order_lines(rows: Rows, *, num: int, method: str, key: str) -> list[str]:
    lines = ['', f'### How much memory the noise has: fractional order, {method} '
             f'method (paper 000 Table {num})', '',
             '| Sequence | Estimated order | Variance of estimated order | Ties |',
             '|---|---:|---:|---:|']
    tie = 'ties_var' if key == 'alpha_var' else 'ties_corr'
    for label, a in rows:
        if a.get(key + '_multimodal'):
            # A mean between separate basins is where no chunk is: give the modes instead.
            lines.append(f"| {label} | modes: {modes_text(a[key + '_modes'])} | "
                         f"{fmt(a[key + '_variance'], '.6f')} | {a[tie]} |")
        else:
            lines.append(f"| {label} | {fmt(a[key + '_mean'], '.6f')} | "
                         f"{fmt(a[key + '_variance'], '.6f')} | {a[tie]} |")
    return lines


def _datasheet_lines(rows: Rows) -> list[str]:
    lines = [
        '', '### Allan deviation: the datasheet numbers (customary units)', '',
        'Read off the curve by the one readout (core/readout.py, docs/allan.md): '
        'intervals at the stated confidence; "<=" an upper bound.', '',
        '| Sequence | Bias stability (deg/h) | at tau (s) | B = bias stability / 0.664 '
        '(deg/h) | ARW (deg/sqrt(h)) | ARW read over taus (s) | K fit (deg/h/sqrt(h)) '
        '| K bound (deg/h/sqrt(h)) | Usable from tau (s) |',
        '|---|---:|---:|---:|---:|---|---:|---:|---:|']
    for label, a in rows:
        d = a.get('allan_datasheet') or {}
        bound = '<= ' if d.get('bias_stability_upper_bound') else ''
        bs = (f"{bound}{fmt(d.get('bias_stability_deg_h'), '.4g')} "
              f"({fmt(d.get('bias_stability_ci_low_deg_h'), '.3g')}"
              f"-{fmt(d.get('bias_stability_ci_high_deg_h'), '.3g')})")
        arw = (f"{fmt(d.get('arw_deg_per_sqrt_h'), '.4g')} "
               f"({fmt(d.get('arw_ci_low_deg_per_sqrt_h'), '.3g')}"
               f"-{fmt(d.get('arw_ci_high_deg_per_sqrt_h'), '.3g')})")
        span = d.get('arw_tau_range_s') or [None, None]
        where = (f"{fmt(span[0], '.3g')}-{fmt(span[1], '.3g')}"
                 if d.get('arw_from_region') else 'ADEV(1 s): no -1/2 region')
        k_fit = fmt(d.get('rate_random_walk_deg_per_h_sqrt_h'), '.3g')
        if d and not d.get('rate_random_walk_resolved'):
            k_fit += ' (not resolved)'
        lines.append(
            f"| {label} | {bs} | {fmt(d.get('bias_stability_tau_s'), '.4g')} | "
            f"{bound}{fmt(d.get('bias_instability_deg_h'), '.4g')} | {arw} | {where} | "
            f"{k_fit} | {fmt(d.get('rate_random_walk_bound_deg_per_h_sqrt_h'), '.3g')} "
            f"| {fmt(d.get('usable_from_s'), '.3g')} |")
    return lines


def _model_fit_lines(rows: Rows) -> list[str]:
    """Return the IEEE 952 model fit in customary units, then its every term in SI."""
    lines = [
        '', '### Allan deviation: IEEE 952 model fit (customary units)', '',
        'The five-term model fitted to the whole usable curve (band-limited short taus '
        'left out): a model for simulation and filters, not the datasheet numbers above.',
        '', '| Sequence | ' + ' | '.join(name for _, name in _CUSTOMARY)
        + ' | Fit | Short taus excluded below (s) |',
        '|---|' + '---:|' * len(_CUSTOMARY) + '---|---:|']
    for label, a in rows:
        t = a.get('allan') or {}
        d = a.get('allan_datasheet') or {}
        fit = d.get('fit_quality', '')
        if fit:
            fit += f" (max error {100 * (d.get('fit_max_relative_error') or 0):.0f} %)"
        lines.append(f'| {label} | '
                     + ' | '.join(fmt(t.get(k), '.4g') for k, _ in _CUSTOMARY)
                     + f" | {fit} | {fmt(d.get('band_limited_below_s'), '.3g')} |")
    keys = []
    for _, a in rows:
        for k, v in (a.get('allan') or {}).items():
            if (k not in keys and not isinstance(v, (dict, str))
                    and not any(k == c for c, _ in _CUSTOMARY)):
                keys.append(k)
    lines += ['', '### Allan deviation: IEEE 952 model fit (SI, unit in the name)', '',
              '| Sequence | ' + ' | '.join(keys) + ' |', '|---|' + '---:|' * len(keys)]
    for label, a in rows:
        terms = a.get('allan') or {}
        lines.append(f'| {label} | ' + ' | '.join(fmt(terms.get(k), '.4g') for k in keys)
                     + ' |')
    return lines


def _health_lines(rows: Rows) -> list[str]:
    if not any('health' in a for _, a in rows):
        return []
    lines = ['', '### Health verdict against the reference', '',
             '| Sequence | Level | Message |', '|---|---|---|']
    for label, a in rows:
        h = a.get('health')
        if h:
            lines.append(f"| {label} | {h['level']} | {h['message']} |")
    return lines


def _counts_lines(bags: Sequence[Mapping[str, Any]]) -> list[str]:
    lines = ['## Input counts', '',
             '| Sequence | Topic | Rate (Hz) | Rate method | Stamp jitter (ms) | Duration (s) | '
             'Samples | Lost | ' 'Gaps | Out-of-order stamps | NaN samples | Tail samples |',
             '|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|']
    for b in bags:
        nan = sum(a['nan_samples'] for a in b['axes'].values())
        jitter = b.get('stamp_jitter_s')
        lines.append(f"| {b['label']} | {b['topic']} | {fmt(b['rate_hz'], '.6g')} | "
                     f"{b.get('rate_method', '')} | "
                     f"{fmt(None if jitter is None else 1e3 * jitter, '.3g')} | "
                     f"{fmt(b['duration_s'], '.1f')} | {b['samples']} | {b['samples_lost']} | "
                     f"{b['gaps']} | "
                     f"{b['out_of_order_stamps']} | {nan} | {b['tail_samples']} |")
    lines.append('')
    return lines
