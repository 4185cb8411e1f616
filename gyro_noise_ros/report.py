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
Report writers of the offline tool, ROS-free.

CSV, JSON, Markdown, Kalibr-style YAML and PNG figures.

Units: the engine works in SI (rad/s); every number written here is converted at this edge and its
unit is in the column or key name (``bias_deg_s``, ``variance_deg2_s2``,
``offset_drift_deg_s_per_h``). File formats are documented in ``docs/offline_tool.md``. Figures use
matplotlib's Agg backend (no display).
"""

import csv
import json
import math
from pathlib import Path

import numpy as np

from .core.engine import rad_s2_to_deg_s_per_h
from .core.health import reference_dict, ROBUST_JSON_KEY
from .units import RAD_TO_DEG

_DEG2 = RAD_TO_DEG ** 2

#: Columns of chunks.csv, in order.
CHUNK_COLUMNS = ('bag', 'axis', 'chunk', 'status', 't_start_s', 't_mid_s', 'stamp_start_ns',
                 'samples', 'samples_lost', 'gaps', 'nan_samples', 'bias_deg_s',
                 'variance_deg2_s2', 'alpha_var', 'f_var', 'var_min_deg2_s2', 'alpha_corr',
                 'f_corr', 'j_min_deg2_s2', 'tie_var', 'tie_corr', 'noise_colour_adev_slope',
                 'temperature_c', 'message')

#: Columns of allan.csv, in order.
ALLAN_COLUMNS = ('bag', 'axis', 'tau_s', 'adev_deg_s', 'ci_low_deg_s', 'ci_high_deg_s', 'n')


def _num(value):
    """Format a float losslessly (repr), NaN as 'nan'."""
    value = float(value)
    return repr(value) if math.isfinite(value) else 'nan'


def _json_num(value):
    value = float(value)
    return value if math.isfinite(value) else None


class ChunkCsvWriter:
    """
    Stream ``chunks.csv``: one row per bag, axis and chunk, written as results arrive.

    Parameters
    ----------
    path : str or os.PathLike
        Output file (overwritten).

    """

    def __init__(self, path):
        self._fh = open(path, 'w', newline='')  # noqa: SIM115 - closed in close()
        self._csv = csv.writer(self._fh)
        self._csv.writerow(CHUNK_COLUMNS)
        self.rows = 0

    def write(self, bag, result):
        """
        Append one :class:`.core.engine.ChunkResult` of bag ``bag``.

        Parameters
        ----------
        bag : str
            Bag label.
        result : ChunkResult
            One analysed chunk.

        """
        r = result
        self._csv.writerow((bag, r.axis, r.chunk, r.status, _num(r.t_start_s), _num(r.t_mid_s),
                            r.stamp_start_ns, r.samples, r.samples_lost, r.gaps, r.nan_samples,
                            _num(r.bias_rad_s * RAD_TO_DEG), _num(r.variance_rad2_s2 * _DEG2),
                            _num(r.alpha_var), _num(r.f_var), _num(r.var_min * _DEG2),
                            _num(r.alpha_corr), _num(r.f_corr), _num(r.j_min * _DEG2),
                            int(r.tie_var), int(r.tie_corr), _num(r.noise_colour),
                            _num(r.temperature_c), r.message))
        self.rows += 1

    def close(self):
        """Close the file."""
        self._fh.close()


def axis_summary_dict(summary, *, verdict=None):
    """
    Turn an :class:`.core.engine.AxisSummary` into the per-axis entry of summary.json.

    Parameters
    ----------
    summary : AxisSummary
        The axis' sequence statistics and counts.
    verdict : HealthVerdict, optional, keyword-only
        Added under ``health`` when given.

    Returns
    -------
    dict
        Keys carry their units (module doc); NaN becomes null.

    """
    seq = summary.sequence
    d = seq.drift
    out = {
        'chunks': seq.chunks,
        'chunks_nan': summary.chunks_nan,
        'chunks_dropped': summary.chunks_dropped,
        'chunks_failed': summary.chunks_failed,
        'chunks_skipped': summary.chunks_skipped,
        'nan_samples': summary.nan_samples,
        'tail_samples': seq.tail_samples,
        'bias_mean_deg_s': _json_num(seq.bias_mean * RAD_TO_DEG),
        'offset_drift_deg_s_per_h': _json_num(rad_s2_to_deg_s_per_h(d.slope)),
        'offset_drift_abs_deg_s_per_h': _json_num(abs(rad_s2_to_deg_s_per_h(d.slope))),
        'offset_drift_stderr_deg_s_per_h': _json_num(rad_s2_to_deg_s_per_h(d.stderr)),
        'offset_drift_span_s': _json_num(d.span_s),
        'offset_drift_rad_s2': _json_num(d.slope),
        'offset_drift_stderr_rad_s2': _json_num(d.stderr),
        'mean_variance_deg2_s2': _json_num(seq.mean_variance * _DEG2),
        'variance_of_variances_deg4_s4': _json_num(seq.variance_of_variances * _DEG2**2),
        'mean_variance_rad2_s2': _json_num(seq.mean_variance),
        'variance_of_variances_rad4_s4': _json_num(seq.variance_of_variances),
        'alpha_var_mean': _json_num(seq.alpha_var_mean),
        'alpha_var_variance': _json_num(seq.alpha_var_variance),
        'alpha_corr_mean': _json_num(seq.alpha_corr_mean),
        'alpha_corr_variance': _json_num(seq.alpha_corr_variance),
        'alpha_var_multimodal': bool(getattr(seq, 'alpha_var_modes', ())),
        'alpha_var_modes': [
            {'order': m, 'chunks': c} for m, c in getattr(seq, 'alpha_var_modes', ())
        ],
        'alpha_corr_multimodal': bool(getattr(seq, 'alpha_corr_modes', ())),
        'alpha_corr_modes': [
            {'order': m, 'chunks': c} for m, c in getattr(seq, 'alpha_corr_modes', ())
        ],
        'ties_var': seq.ties_var,
        'ties_corr': seq.ties_corr,
        'temperature_mean_c': _json_num(summary.temperature_mean_c),
        'allan': allan_terms_dict(summary.noise_terms),
        'allan_datasheet': (
            summary.readout.as_dict()
            if getattr(summary, 'readout', None) is not None
            else None
        ),
    }
    # what a later run's --reference check compares with (core/health.py)
    out[ROBUST_JSON_KEY] = reference_dict(seq)
    if verdict is not None:
        out['health'] = {'level': verdict.level, 'message': verdict.message,
                         'items': [{'key': k, 'value': v, 'level': lv} for k, v,
                                   lv in verdict.items]}
    return out


def readout_text(sheet):
    """
    Return the readout's datasheet numbers in one line (the tool's printed summary).

    Parameters
    ----------
    sheet : dict
        ``allan_datasheet`` of summary.json (:meth:`.core.readout.AllanReadout.as_dict`).

    Returns
    -------
    str
        ``bias stability [<=]X deg/h (Y deg/s) at tau = T s, ARW Z deg/sqrt(h)``.

    """
    bound = '<=' if sheet.get('bias_stability_upper_bound') else ''
    return (f"bias stability {bound}{_fmt(sheet.get('bias_stability_deg_h'), '.3g')} deg/h "
            f"({bound}{_fmt(sheet.get('bias_stability_deg_s'), '.3g')} deg/s) at tau = "
            f"{_fmt(sheet.get('bias_stability_tau_s'), '.3g')} s, ARW "
            f"{_fmt(sheet.get('arw_deg_per_sqrt_h'), '.3g')} deg/sqrt(h)")


def accelerometer_readout_dict(readout):
    """
    Return the accelerometer entry of summary.json from an axis' readout (SI, units in keys).

    The readout of specific force in m/s^2 is read exactly as for the angular rate: its "angle
    random walk" is the velocity random walk (m/s/sqrt(s) = m/s^2/sqrt(Hz), Kalibr's
    accelerometer_noise_density), its "rate random walk" the acceleration random walk
    (m/s^3/sqrt(Hz), accelerometer_random_walk).

    Parameters
    ----------
    readout : core.readout.AllanReadout or None
        Readout of one accelerometer axis.

    Returns
    -------
    dict or None

    """
    if readout is None:
        return None
    r = readout
    return {k: (_json_num(v) if isinstance(v, float) else v) for k, v in {
        'velocity_random_walk_m_s2_per_sqrt_hz': r.arw_rad_per_sqrt_s,
        'velocity_random_walk_ci_low_m_s2_per_sqrt_hz': r.arw_ci_low_rad_per_sqrt_s,
        'velocity_random_walk_ci_high_m_s2_per_sqrt_hz': r.arw_ci_high_rad_per_sqrt_s,
        'velocity_random_walk_from_region': r.arw_from_region,
        'bias_stability_m_s2': r.bias_stability_rad_s,
        'bias_stability_tau_s': r.bias_stability_tau_s,
        'bias_stability_upper_bound': r.bias_stability_upper_bound,
        'bias_instability_m_s2': r.bias_instability_rad_s,
        'acceleration_random_walk_m_s3_per_sqrt_hz': r.rate_random_walk_rad_per_s_sqrt_s,
        'acceleration_random_walk_resolved': r.rate_random_walk_resolved,
        'acceleration_random_walk_bound_m_s3_per_sqrt_hz':
            r.rate_random_walk_bound_rad_per_s_sqrt_s,
        'fit_quality': r.fit_quality,
    }.items()}


def allan_terms_dict(terms):
    """
    Return the fitted Allan noise terms as a JSON dict (SI values, units in the keys), or None.

    Parameters
    ----------
    terms : object or None
        The noise-term fit of :mod:`.core.allan`; either a mapping or a dataclass-like object whose
        public float attributes are named with their unit.

    Returns
    -------
    dict or None

    """
    if terms is None:
        return None
    if hasattr(terms, 'as_dict'):
        raw = terms.as_dict()
    elif isinstance(terms, dict):
        raw = terms
    else:
        raw = {k: getattr(terms, k) for k in dir(terms) if not k.startswith('_')}
    out = {}
    for key, value in raw.items():
        if callable(value):
            continue
        if isinstance(value, (bool, int, float, np.floating, np.integer)):
            out[key] = _json_num(value) if isinstance(value, (float, np.floating)) else int(value)
        elif isinstance(value, str):
            out[key] = value
        elif isinstance(value, dict):
            out[key] = {k: (_json_num(v) if isinstance(v, (float, int, np.floating)) else v)
                        for k, v in value.items()}
    return out


def write_json(path, doc):
    """
    Write ``doc`` as indented JSON (NaN must already be None).

    Parameters
    ----------
    path : str or os.PathLike
        File to write.
    doc : dict
        JSON-serialisable document.

    """
    Path(path).write_text(json.dumps(doc, indent=2, allow_nan=False) + '\n')


def _fmt(value, spec):
    if value is None:
        return 'n/a'
    return format(value, spec)


def _modes_text(modes):
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


def _drift_text(a):
    drift, se = a.get('offset_drift_deg_s_per_h'), a.get('offset_drift_stderr_deg_s_per_h')
    if drift is None:
        return None
    from .core.health import drift_t_threshold

    sig = abs(drift) / se if se else float('nan')
    need = drift_t_threshold(3.0, a['chunks'])
    word = 'significant' if sig > need else 'not significant'
    # With few chunks the Student-t quantile is far above 3: "5.9 standard errors, not
    # significant" must say why, or it reads as a contradiction.
    return (f'offset drift {drift:+.3g} +/- {_fmt(se, ".2g")} (deg/s)/h, {_fmt(sig, ".2g")} '
            f'standard errors from zero: {word} (with {a["chunks"]} chunks a 3-sigma test needs '
            f'{_fmt(need, ".2g")} standard errors, the Student-t quantile of the same '
            'false-alarm rate)')


def _plain_summary(b, axis, a):
    """One plain-language paragraph for one bag and axis (people first, tables after)."""
    rate = b.get('rate_hz')
    parts = [f"**{b['label']}, axis {axis}:** {b['samples']} samples over "
             f"{_fmt(b['duration_s'], '.1f')} s at {_fmt(rate, '.4g')} Hz "
             f"(rate from {b.get('rate_method') or 'the stamps'}"
             + (', bursty stamps' if b.get('stamps_bursty') else '') + ')']
    lost = b['samples_lost']
    parts.append(f'{lost} sample(s) lost' if lost else 'no sample lost')
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
            parts.append(f'order ({name}) in separate modes: {_modes_text(a[key + "_modes"])}')
        elif a.get(key + '_mean') is not None:
            parts.append(f"order ({name}) {a[key + '_mean']:.3f}")
    if 'health' in a:
        parts.append(f"health {a['health']['level']}: {a['health']['message']}")
    return '; '.join(parts) + '.'


def in_short_markdown(doc):
    """
    Return the plain-language "In short" section of a summary.json document, as Markdown.

    One line defines each number (bias stability, B, ARW, N, K, offset drift, the two orders)
    and says which to compare with a datasheet; then one paragraph per bag and axis, and the
    bags' warnings.

    Parameters
    ----------
    doc : dict
        The summary.json document.

    Returns
    -------
    str
        Markdown, starting with the ``## In short`` heading.

    """
    lines = ['## In short', '']
    lines += [f'* **{name}**: {text}' for name, text in IN_SHORT_DEFINITIONS]
    lines.append('')
    for b in doc['bags']:
        for axis, a in b['axes'].items():
            lines += [_plain_summary(b, axis, a), '']
        for text in b.get('warnings') or ():
            lines += [f"* warning ({b['label']}): {text}"]
        if b.get('warnings'):
            lines.append('')
    return '\n'.join(lines)


_CUSTOMARY = (
    ('quantization_deg', 'Q (deg)'),
    ('angle_random_walk_deg_per_sqrt_h', 'N (deg/sqrt(h))'),
    ('bias_instability_deg_per_h', 'B (deg/h)'),
    ('rate_random_walk_deg_per_h_sqrt_h', 'K (deg/h/sqrt(h))'),
    ('rate_ramp_deg_per_h2', 'R (deg/h^2)'),
)


def summary_markdown(doc):
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
    opts = doc['options']
    lines = ['# gyro_noise_analyze summary', '', in_short_markdown(doc)]
    lines += [
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
    for axis in axes:
        rows = [(b['label'], b['axes'][axis]) for b in bags if axis in b['axes']]
        lines += [f'## Axis {axis}', '',
                  '### How fast the bias moves: offset drift of the chunk bias '
                  '(paper 000 Table 3)', '',
                  # The paper tabulates magnitudes; the sign is kept beside them so a
                  # reader never has to guess which way the bias moved.
                  '| Sequence | Offset drift, magnitude ((deg/s)/h) | Signed slope ((deg/s)/h) '
                  '| Std. error ((deg/s)/h) | Mean bias (deg/s) | Chunks |',
                  '|---|---:|---:|---:|---:|---:|']
        for label, a in rows:
            lines.append(f"| {label} | {_fmt(a['offset_drift_abs_deg_s_per_h'], '.6f')} | "
                         f"{_fmt(a['offset_drift_deg_s_per_h'], '+.6f')} | "
                         f"{_fmt(a['offset_drift_stderr_deg_s_per_h'], '.6f')} | "
                         f"{_fmt(a['bias_mean_deg_s'], '.6f')} | {a['chunks']} |")
        lines += ['', '### How large the noise is: variance within chunks (paper 000 Table 4)',
                  '',
                  '| Sequence | Mean noise variance ((deg/s)^2) | Variance of noise variance '
                  '((deg/s)^4) |', '|---|---:|---:|']
        for label, a in rows:
            lines.append(f"| {label} | {_fmt(a['mean_variance_deg2_s2'], '.6g')} | "
                         f"{_fmt(a['variance_of_variances_deg4_s4'], '.6g')} |")
        for num, method, key in ((5, 'variance', 'alpha_var'), (6, 'correlation', 'alpha_corr')):
            lines += ['', f'### How much memory the noise has: fractional order, {method} '
                      f'method (paper 000 Table {num})', '',
                      '| Sequence | Estimated order | Variance of estimated order | Ties |',
                      '|---|---:|---:|---:|']
            tie = 'ties_var' if key == 'alpha_var' else 'ties_corr'
            for label, a in rows:
                if a.get(key + '_multimodal'):
                    # A mean between separate basins is where no chunk is: give the modes instead.
                    lines.append(f"| {label} | modes: {_modes_text(a[key + '_modes'])} | "
                                 f"{_fmt(a[key + '_variance'], '.6f')} | {a[tie]} |")
                else:
                    lines.append(f"| {label} | {_fmt(a[key + '_mean'], '.6f')} | "
                                 f"{_fmt(a[key + '_variance'], '.6f')} | {a[tie]} |")
        if any(a.get('allan') or a.get('allan_datasheet') for _, a in rows):
            lines += [
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
                bs = (f"{bound}{_fmt(d.get('bias_stability_deg_h'), '.4g')} "
                      f"({_fmt(d.get('bias_stability_ci_low_deg_h'), '.3g')}"
                      f"-{_fmt(d.get('bias_stability_ci_high_deg_h'), '.3g')})")
                arw = (f"{_fmt(d.get('arw_deg_per_sqrt_h'), '.4g')} "
                       f"({_fmt(d.get('arw_ci_low_deg_per_sqrt_h'), '.3g')}"
                       f"-{_fmt(d.get('arw_ci_high_deg_per_sqrt_h'), '.3g')})")
                span = d.get('arw_tau_range_s') or [None, None]
                where = (f"{_fmt(span[0], '.3g')}-{_fmt(span[1], '.3g')}"
                         if d.get('arw_from_region') else 'ADEV(1 s): no -1/2 region')
                k_fit = _fmt(d.get('rate_random_walk_deg_per_h_sqrt_h'), '.3g')
                if d and not d.get('rate_random_walk_resolved'):
                    k_fit += ' (not resolved)'
                lines.append(
                    f"| {label} | {bs} | {_fmt(d.get('bias_stability_tau_s'), '.4g')} | "
                    f"{bound}{_fmt(d.get('bias_instability_deg_h'), '.4g')} | {arw} | {where} | "
                    f"{k_fit} | {_fmt(d.get('rate_random_walk_bound_deg_per_h_sqrt_h'), '.3g')} "
                    f"| {_fmt(d.get('usable_from_s'), '.3g')} |")
            lines += [
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
                             + ' | '.join(_fmt(t.get(k), '.4g') for k, _ in _CUSTOMARY)
                             + f" | {fit} | {_fmt(d.get('band_limited_below_s'), '.3g')} |")
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
                lines.append(f'| {label} | ' + ' | '.join(_fmt(terms.get(k), '.4g') for k in keys)
                             + ' |')
        if any('health' in a for _, a in rows):
            lines += ['', '### Health verdict against the reference', '',
                      '| Sequence | Level | Message |', '|---|---|---|']
            for label, a in rows:
                h = a.get('health')
                if h:
                    lines.append(f"| {label} | {h['level']} | {h['message']} |")
        lines.append('')
    lines += ['## Input counts', '',
              '| Sequence | Topic | Rate (Hz) | Rate method | Stamp jitter (ms) | Duration (s) | '
              'Samples | Lost | ' 'Gaps | Out-of-order stamps | NaN samples | Tail samples |',
              '|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|']
    for b in bags:
        nan = sum(a['nan_samples'] for a in b['axes'].values())
        jitter = b.get('stamp_jitter_s')
        lines.append(f"| {b['label']} | {b['topic']} | {_fmt(b['rate_hz'], '.6g')} | "
                     f"{b.get('rate_method', '')} | "
                     f"{_fmt(None if jitter is None else 1e3 * jitter, '.3g')} | "
                     f"{_fmt(b['duration_s'], '.1f')} | {b['samples']} | {b['samples_lost']} | "
                     f"{b['gaps']} | "
                     f"{b['out_of_order_stamps']} | {nan} | {b['tail_samples']} |")
    lines.append('')
    return '\n'.join(lines)


def write_allan_csv(path, entries):
    """
    Write allan.csv.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file to write.
    entries : iterable of (bag, axis, tau_s, adev_rad_s, ci_low_rad_s, ci_high_rad_s, n)
        Arrays per (bag, axis); the deviation and its confidence interval in rad/s.

    """
    with open(path, 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(ALLAN_COLUMNS)
        for bag, axis, tau, adev, lo, hi, n in entries:
            for i in range(len(tau)):
                w.writerow((bag, axis, _num(tau[i]), _num(adev[i] * RAD_TO_DEG),
                            _num(lo[i] * RAD_TO_DEG), _num(hi[i] * RAD_TO_DEG), int(n[i])))


#: Topic written into imu.yaml for inputs that have none (CSV tables, PX4 ULogs).
DEFAULT_IMU_TOPIC = '/imu/data_raw'


def kalibr_noise(readouts, *, record_s=None):
    """
    Return one sensor's Kalibr noise parameters from its axes' readouts, with the notes to say.

    Kalibr takes one number per sensor: the largest over the axes (the noisiest axis bounds the
    others). The random walk of each axis is the larger of its fitted K and its bound
    (:meth:`.core.readout.AllanReadout.kalibr`).

    Parameters
    ----------
    readouts : list of core.readout.AllanReadout or None
        The analysed axes (None entries ignored).
    record_s : float, optional, keyword-only
        Record length (s), named in the notes.

    Returns
    -------
    dict
        ``noise_density`` and ``random_walk`` (SI; None when no axis gives one: a zero or
        missing density is never written as a number), ``noise_density_note`` and
        ``random_walk_note`` (empty when there is nothing to say).

    """
    rs = [r for r in readouts if r is not None]
    dens = [r for r in rs if math.isfinite(r.arw_rad_per_sqrt_s) and r.arw_rad_per_sqrt_s > 0]
    walks = [(r.kalibr(), r) for r in rs]
    walks = [(k, r) for k, r in walks if math.isfinite(k['random_walk']) and k['random_walk'] > 0]
    out = {'noise_density': None, 'random_walk': None, 'noise_density_note': '',
           'random_walk_note': ''}
    if dens:
        best = max(dens, key=lambda r: r.arw_rad_per_sqrt_s)
        out['noise_density'] = best.arw_rad_per_sqrt_s
        if not best.arw_from_region:
            out['noise_density_note'] = ('read as ADEV(1 s) x sqrt(1 s): the Allan curve has no '
                                         '-1/2 (white-noise) region')
    else:
        out['noise_density_note'] = ('not measured: no -1/2 region and no tau = 1 s on the Allan '
                                     'curve (record too short); give it from the datasheet')
    if walks:
        k, r = max(walks, key=lambda kr: kr[0]['random_walk'])
        out['random_walk'] = k['random_walk']
        length = f' ({record_s:.4g} s)' if record_s is not None and math.isfinite(record_s) else ''
        bound = 'K <= upper ADEV bound at the longest tau x sqrt(3 / tau)'
        fitted = r.rate_random_walk_rad_per_s_sqrt_s
        fitted = (f'the fitted K, {fitted:.3g}, is smaller' if math.isfinite(fitted) and fitted > 0
                  else 'the fit finds none')
        short = [rr for kk, rr in walks if kk['too_short']]
        if short:
            out['random_walk_note'] = (
                f'record too short{length} for a random walk: the Allan curve is still falling '
                f'at its longest tau ({short[0].bias_stability_tau_s:.3g} s), so this is only an '
                f'upper bound, {bound}')
        elif k['random_walk_is_bound']:
            out['random_walk_note'] = (f'upper bound: the record{length} does not resolve a '
                                       f'random walk; {bound} ({fitted})')
    return out


def write_imu_yaml(path, *, rostopic, update_rate_hz, gyroscope, accelerometer=None,
                   rostopic_note='', source=''):
    """
    Write a Kalibr-style imu.yaml (kalibr ``imu.yaml`` keys, SI units), notes as YAML comments.

    Parameters
    ----------
    path : str or os.PathLike
        YAML file to write.
    rostopic : str
        IMU topic.
    update_rate_hz : float
        Sample rate (Hz).
    gyroscope : dict
        :func:`kalibr_noise` of the gyroscope axes (rad/s/sqrt(Hz), rad/s^2/sqrt(Hz)).
    accelerometer : dict, optional
        The same for the accelerometer (m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)); omitted when None.
    rostopic_note : str
        Comment above ``rostopic`` (e.g. that the input had no topic).
    source : str
        Comment line saying which bag and axes the numbers come from.

    """
    def val(v):
        return 'null' if v is None or not math.isfinite(float(v)) else repr(float(v))

    def entry(key, value, unit, note):
        return ([f'# {key}: {note}'] if note else []) + [f'{key}: {val(value)}  # {unit}']

    lines = [
        '# Kalibr-style IMU noise parameters written by gyro_noise_analyze (continuous-time, SI).']
    if source:
        lines.append(f'# {source}')
    if rostopic_note:
        lines.append(f'# rostopic: {rostopic_note}')
    lines += [f'rostopic: {rostopic}', f'update_rate: {val(update_rate_hz)}  # Hz']
    sensors = [('gyroscope', gyroscope, 'rad/s/sqrt(Hz)', 'rad/s^2/sqrt(Hz)')]
    if accelerometer is not None:
        sensors.append(('accelerometer', accelerometer, 'm/s^2/sqrt(Hz)', 'm/s^3/sqrt(Hz)'))
    for name, noise, u_density, u_walk in sensors:
        lines += entry(f'{name}_noise_density', noise['noise_density'], u_density,
                       noise['noise_density_note'])
        lines += entry(f'{name}_random_walk', noise['random_walk'], u_walk,
                       noise['random_walk_note'])
    Path(path).write_text('\n'.join(lines) + '\n')


# ---- figures
# ---------------------------------------------------------------------------------------------

def _pyplot():
    import matplotlib

    matplotlib.use('Agg', force=True)
    import matplotlib.pyplot as plt

    return plt


def plot_per_chunk(path, series, *, quantity):
    """
    Plot bias or variance per chunk over time, one panel per axis, bags overlaid (paper Figs. 2-5).

    Markers are visible (not single pixels); on the bias figure each bag's least-squares drift line
    (the Table 3 slope) is drawn and named in the legend. A bag with fewer than 2 chunks is not
    plotted (a single point shows nothing over time) and the title says so; when no bag has 2
    chunks no figure is written.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    series : dict
        ``{axis: [(label, t_mid_s array, value array in rad/s or (rad/s)^2), ...]}``.
    quantity : {'bias', 'variance'}, keyword-only
        Which quantity the values are.

    Returns
    -------
    bool
        True when the figure was written.

    """
    def finite(t, v):
        t, v = np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64)
        ok = np.isfinite(t) & np.isfinite(v)
        return t[ok], v[ok]

    axes = list(series)
    if not any(finite(t, v)[0].size >= 2 for a in axes for _, t, v in series[a]):
        return False
    plt = _pyplot()
    fig, panels = plt.subplots(len(axes), 1, figsize=(10, 2.8 * len(axes) + 0.8), squeeze=False,
                               sharex=True)
    scale, unit = (RAD_TO_DEG, 'deg/s') if quantity == 'bias' else (_DEG2, '(deg/s)$^2$')
    skipped = set()
    for ax_name, panel in zip(axes, panels[:, 0]):
        for label, t, v in series[ax_name]:
            t, v = finite(t, v)
            if t.size < 2:
                skipped.add(label)
                continue
            hours = t / 3600.0
            line, = panel.plot(hours, v * scale, 'o-', ms=4, lw=0.6, label=label)
            if quantity == 'bias':
                slope, icpt = np.polyfit(t, v, 1)
                panel.plot(hours, (icpt + slope * t) * scale, '--', lw=1.2, color=line.get_color(),
                           label=f'{label}: drift {slope * RAD_TO_DEG * 3600.0:+.3g} (deg/s)/h')
        panel.set_ylabel(f'{quantity} {ax_name} ({unit})')
        panel.grid(alpha=0.3)
        if panel.get_legend_handles_labels()[1]:
            panel.legend(fontsize=7, ncol=2)
    panels[-1, 0].set_xlabel('time from the first sample (h)')
    title = f'Chunk {quantity} per chunk (markers: chunks'
    title += '; dashed: least-squares drift, Table 3)' if quantity == 'bias' else ')'
    if skipped:
        title += f"\nnot plotted (fewer than 2 chunks): {', '.join(sorted(skipped))}"
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def plot_curves(path, alphas, chunks, var_curves, j_curves, *, title):
    """
    Plot var(alpha) and J(alpha) stacked over chunks as heat maps (paper Figs. 6-9).

    Each chunk's curve is shown as log10(curve / its minimum), so the colour reads "how much worse
    than the best order of that chunk" and the minimum line is visible whatever the chunk's noise
    level; the chosen orders are overlaid as dots.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    alphas : numpy.ndarray
        Order grid.
    chunks : numpy.ndarray
        Chunk indices of the rows.
    var_curves, j_curves : numpy.ndarray
        ``(len(chunks), len(alphas))`` curves.
    title : str
        Figure title.

    """
    plt = _pyplot()
    fig, panels = plt.subplots(1, 2, figsize=(11, 4.2), squeeze=False)
    for panel, curves, name in ((panels[0, 0], var_curves, 'var(w)'),
                                (panels[0, 1], j_curves, 'J')):
        curves = np.asarray(curves, dtype=np.float64)
        low = np.nanmin(curves, axis=1, keepdims=True)
        rel = np.log10(curves / low)
        extent = (alphas[0], alphas[-1], chunks[-1] + 0.5, chunks[0]
                  - 0.5) if len(chunks) else None
        im = panel.imshow(rel, aspect='auto', extent=extent, cmap='viridis',
                          interpolation='nearest')
        best = alphas[np.nanargmin(curves, axis=1)]
        panel.plot(best, chunks, 'r.', ms=3, label='minimum')
        panel.set_xlabel('order alpha')
        panel.set_ylabel('chunk')
        panel.set_title(f'log10({name}(alpha) / min)')
        fig.colorbar(im, ax=panel)
    panels[0, 0].legend(fontsize=7, loc='lower right')
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_allan(path, series, *, confidence=0.683):
    """
    Overlay every bag's Allan deviation with confidence bands and fitted terms (paper Fig. 10).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    series : dict
        ``{axis: [(label, tau_s, adev, ci_low, ci_high, fit_lines), ...]}`` in rad/s; ``fit_lines``
        is a list of ``(name, tau_s, adev)`` model curves (may be empty).
    confidence : float, keyword-only
        Two-sided confidence of the bands (named in the legend).

    """
    plt = _pyplot()
    axes = list(series)
    fig, panels = plt.subplots(1, len(axes), figsize=(max(7.0, 5.5 * len(axes)), 4.8),
                               squeeze=False)
    for ax_name, panel in zip(axes, panels[0]):
        for label, tau, adev, lo, hi, fits in series[ax_name]:
            line, = panel.loglog(tau, np.asarray(adev) * RAD_TO_DEG, 'o-', ms=3, lw=1.3,
                                 label=label)
            panel.fill_between(tau, np.asarray(lo) * RAD_TO_DEG, np.asarray(hi) * RAD_TO_DEG,
                               color=line.get_color(), alpha=0.15, lw=0,
                               label=f'{label}: {100 * confidence:.1f} % interval')
            for k, (name, ftau, fadev) in enumerate(fits):
                panel.loglog(ftau, np.asarray(fadev) * RAD_TO_DEG, ls='--', lw=0.8,
                             color=line.get_color(), label=f'{label}: IEEE 952 fit' if k == 0
                             else None)
        panel.set_xlabel('tau (s)')
        panel.set_ylabel(f'Allan deviation {ax_name} (deg/s)')
        panel.grid(True, which='both', alpha=0.3)
        panel.legend(fontsize=7)
    fig.suptitle(f'Allan deviation (markers: measured; bands: {100 * confidence:.1f} % confidence '
                 'interval; dashed: fitted IEEE 952 noise terms)', fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---- Allan adapters (duck-typed on core.allan's AllanResult and noise-term fit)
# -------------------------

def allan_curve(result):
    """
    Return (tau_s, adev, ci_low, ci_high, n) arrays of an Allan result (rad/s), NaN-free rows only.

    Parameters
    ----------
    result : core.allan.AllanResult
        One analysed chunk.

    Returns
    -------
    tuple of numpy.ndarray

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    lo = np.asarray(getattr(result, 'ci_low', np.full_like(adev, np.nan)), dtype=np.float64)
    hi = np.asarray(getattr(result, 'ci_high', np.full_like(adev, np.nan)), dtype=np.float64)
    n = np.asarray(getattr(result, 'n_terms', np.zeros(adev.shape, np.int64)), dtype=np.int64)
    ok = np.isfinite(adev) & np.isfinite(tau)
    return tau[ok], adev[ok], lo[ok], hi[ok], n[ok]


def allan_fit_lines(terms, tau):
    """
    Return ``[(name, tau_s, adev_rad_s)]`` curves of the fitted noise terms (Allan figure).

    Parameters
    ----------
    terms : object or None
        Noise-term fit of :mod:`.core.allan` (anything with a ``model_adev(tau)`` or ``adev(tau)``
        method, or ``term_adev(name, tau)``); None gives no lines.
    tau : numpy.ndarray
        Averaging times (s).

    Returns
    -------
    list

    """
    if terms is None or len(tau) == 0:
        return []
    lo, hi = getattr(terms, 'tau_min_s', None), getattr(terms, 'tau_max_s', None)
    if lo is not None and hi is not None:
        tau = np.asarray(tau, dtype=np.float64)
        # only where it was fitted: band-limited short taus are left out of the fit
        tau = tau[(tau >= lo * (1 - 1e-9)) & (tau <= hi * (1 + 1e-9))]
        if tau.size == 0:
            return []
    for name in ('model_adev', 'adev'):
        fn = getattr(terms, name, None)
        if callable(fn):
            try:
                return [('fit', tau, np.asarray(fn(tau), dtype=np.float64))]
            except (TypeError, ValueError):
                return []
    return []
