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
Health verdicts of one gyro axis.

The same logic in the analyzer node and the offline tool (issue 4).

A verdict compares a run's sequence statistics (paper 000 Tables 3-6) with a *reference
characterisation* (the offline tool's ``summary.json`` of a reference recording, like the paper's
"sequence ref") and with absolute limits. Every limit is a field of :class:`HealthThresholds`; the
defaults are read off the paper:

* offset drift (Table 3): helium raised it ~20x over the reference in H1/H2 and it was still ~6x at
  the end of exposure (H5), ~4x right after (AH1) and back to ~1x after 30 days (LAH). With a
  reference the ratio |drift| / |reference drift| is judged: WARN above ``drift_ratio_warn`` (5x),
  ERROR above ``drift_ratio_error`` (15x). Without a reference, absolute limits in (deg/s)/h: WARN
  above 0.02, ERROR above 0.05 (the paper's reference is 0.0036, H1 0.065, H5 0.022). A drift is
  only judged once ``min_chunks`` chunks are in and when it is significant: the t statistic |slope|
  / standard error must exceed the Student-t quantile (n - 2 degrees of freedom for n chunks) at
  the same two-sided level as ``drift_min_sigma`` standard deviations of a normal (3 sigma: p =
  0.0027), because a short run's slope is mostly chunk-mean noise and with few chunks the t
  statistic has heavy tails (a plain 3-sigma test fires on ~20 % of 3-chunk white-noise runs, ~10 %
  of 4-chunk runs).
* order (Tables 5, 6): the paper saw no change. WARN when the mean chunk order of the variance
  method differs from the reference mean by more than ``alpha_var_tolerance`` (0.05, i.e. 5 grid
  steps; the paper's spread over sequences is 0.009), of the correlation method by more than
  ``alpha_corr_tolerance`` (0.25; its chunk spread is ~0.4 and sequence means moved by 0.13); ERROR
  at twice the tolerance.
* variance (Table 4): WARN when the mean chunk variance is outside ``1 +/-
  variance_ratio_tolerance`` (0.5, the +/-50 % "physiological" band of paper 001) times the
  reference, ERROR outside ``1 +/- 2x`` that tolerance (lower bound clipped at 0).
* samples lost (from stamps) as a fraction of expected samples: WARN above ``lost_fraction_warn``
  (1e-4), ERROR above ``lost_fraction_error`` (1e-2). NaN/Inf samples: WARN if any, ERROR above
  ``lost_fraction_error`` as a fraction. Out-of-order stamps: WARN if any.
* chunks skipped by a node that fell behind: WARN above ``skipped_fraction_warn`` (0.1) of the
  chunks, ERROR above ``skipped_fraction_error`` (0.5).
* STALE: no complete chunk yet, or no data for more than ``stale_after_s`` (5 s) when the caller
  says so.

Levels are ordered OK < WARN < ERROR < STALE (as diagnostic_msgs: 0, 1, 2, 3); the verdict is the
worst item and its message is one sentence naming that item.
"""

from dataclasses import dataclass, field, fields
import json
import math
from pathlib import Path

from scipy.special import stdtrit

from .items import DEG as _DEG
from .items import fmt as _fmt
from ..errors import InputDataError, ParameterError

#: Levels in increasing severity, with diagnostic_msgs/DiagnosticStatus byte values.
LEVELS = ('OK', 'WARN', 'ERROR', 'STALE')
LEVEL_BYTE = {'OK': 0, 'WARN': 1, 'ERROR': 2, 'STALE': 3}


def _threshold(default, description, unit=''):
    # One source for the node's parameter table, its YAML file and the docs (field metadata).
    return field(default=default, metadata={'description': description, 'unit': unit})


@dataclass(frozen=True)
class HealthThresholds:
    """
    Documented thresholds of the health verdicts (module doc gives the reasoning).

    Attributes
    ----------
    drift_ratio_warn, drift_ratio_error : float
        |offset drift| / |reference offset drift| limits (dimensionless).
    drift_abs_warn_deg_s_per_h, drift_abs_error_deg_s_per_h : float
        Absolute |offset drift| limits ((deg/s)/h), used when there is no reference.
    drift_min_sigma : float
        A drift is judged only when |slope| exceeds this many standard errors.
    min_chunks : int
        Chunks needed before drift, order and variance are judged.
    alpha_var_tolerance, alpha_corr_tolerance : float
        Limits on |mean order - reference mean order| (WARN; ERROR at twice).
    variance_ratio_tolerance : float
        Limit on |mean variance / reference - 1| (WARN; ERROR at twice).
    lost_fraction_warn, lost_fraction_error : float
        Limits on lost / expected samples (also NaN samples / samples for ERROR).
    skipped_fraction_warn, skipped_fraction_error : float
        Limits on skipped / all chunks.
    stale_after_s : float
        Seconds without data after which the verdict is STALE (s).

    """

    drift_ratio_warn: float = _threshold(
        5.0, 'WARN when |offset drift| exceeds this multiple of the reference drift', 'x')
    drift_ratio_error: float = _threshold(
        15.0, 'ERROR when |offset drift| exceeds this multiple of the reference drift', 'x')
    drift_abs_warn_deg_s_per_h: float = _threshold(
        0.02, 'WARN above this |offset drift| when there is no reference', '(deg/s)/h')
    drift_abs_error_deg_s_per_h: float = _threshold(
        0.05, 'ERROR above this |offset drift| when there is no reference', '(deg/s)/h')
    drift_min_sigma: float = _threshold(
        3.0, 'Judge the drift only when |slope| exceeds this many standard errors', 'sigma')
    min_chunks: int = _threshold(
        3, 'Chunks needed before drift, order and variance are judged', 'chunks')
    alpha_var_tolerance: float = _threshold(
        0.05, 'WARN when the mean variance-method order leaves the reference by more (ERROR at '
        'twice)')
    alpha_corr_tolerance: float = _threshold(
        0.25, 'WARN when the mean correlation-method order leaves the reference by more (ERROR '
        'at twice)')
    variance_ratio_tolerance: float = _threshold(
        0.5, 'WARN when mean variance / reference leaves 1 +/- this (ERROR at twice)')
    lost_fraction_warn: float = _threshold(
        1e-4, 'WARN above this fraction of samples lost (from stamps)')
    lost_fraction_error: float = _threshold(
        1e-2, 'ERROR above this fraction of samples lost (from stamps)')
    skipped_fraction_warn: float = _threshold(
        0.1, 'WARN above this fraction of chunks skipped (analysis behind)')
    skipped_fraction_error: float = _threshold(
        0.5, 'ERROR above this fraction of chunks skipped (analysis behind)')
    stale_after_s: float = _threshold(5.0, 'STALE after this long without data', 's')

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ParameterError(
                    f'health threshold {f.name} must be a finite number >= 0, got {value!r}')
        if self.drift_ratio_error < self.drift_ratio_warn:
            raise ParameterError(
                f'drift_ratio_error ({self.drift_ratio_error}) must be >= drift_ratio_warn '
                f'({self.drift_ratio_warn})')
        if self.drift_abs_error_deg_s_per_h < self.drift_abs_warn_deg_s_per_h:
            raise ParameterError(
                'drift_abs_error_deg_s_per_h must be >= drift_abs_warn_deg_s_per_h, got '
                f'{self.drift_abs_error_deg_s_per_h} < {self.drift_abs_warn_deg_s_per_h}')
        if self.lost_fraction_error < self.lost_fraction_warn:
            raise ParameterError(f'lost_fraction_error ({self.lost_fraction_error}) must be >= '
                                 f'lost_fraction_warn ({self.lost_fraction_warn})')
        if self.skipped_fraction_error < self.skipped_fraction_warn:
            raise ParameterError(
                f'skipped_fraction_error ({self.skipped_fraction_error}) must be >= '
                f'skipped_fraction_warn ({self.skipped_fraction_warn})')


@dataclass(frozen=True)
class ReferenceStats:
    """
    Reference characterisation of one axis (from a summary.json of the offline tool).

    Attributes
    ----------
    offset_drift_rad_s2 : float
        Signed offset drift (rad/s per s).
    mean_variance_rad2_s2 : float
        Mean chunk variance ((rad/s)^2).
    alpha_var_mean, alpha_corr_mean : float
        Mean chunk orders of both methods.
    chunks : int
        Chunks behind these numbers.
    source : str
        Where it came from (file, bag, axis), for messages.
    offset_drift_stderr_rad_s2 : float
        Standard error of the reference drift (rad/s per s); NaN when unknown (old summaries).

    """

    offset_drift_rad_s2: float
    mean_variance_rad2_s2: float
    alpha_var_mean: float
    alpha_corr_mean: float
    chunks: int = 0
    source: str = ''
    offset_drift_stderr_rad_s2: float = float('nan')


@dataclass(frozen=True)
class HealthVerdict:
    """
    Verdict of one axis.

    Attributes
    ----------
    level : str
        'OK', 'WARN', 'ERROR' or 'STALE'.
    message : str
        One sentence naming the worst item.
    items : tuple of (str, str, str)
        (readable key with unit, formatted value, level) for every check, in a stable order.

    """

    level: str
    message: str
    items: tuple

    @property
    def level_byte(self):
        """Return the level as a DiagnosticStatus byte (0 OK, 1 WARN, 2 ERROR, 3 STALE)."""
        return LEVEL_BYTE[self.level]


def _worse(a, b):
    return a if LEVELS.index(a) >= LEVELS.index(b) else b


def _band(deviation, tolerance):
    if not math.isfinite(deviation):
        return 'OK'
    if deviation > 2.0 * tolerance:
        return 'ERROR'
    if deviation > tolerance:
        return 'WARN'
    return 'OK'


def drift_t_threshold(min_sigma, chunks):
    """
    Return the |t| a drift slope over ``chunks`` chunks must exceed to be significant.

    Parameters
    ----------
    min_sigma : float
        Significance expressed as standard deviations of a normal distribution (two-sided).
    chunks : int
        Number of chunks in the least-squares fit (>= 3 for a finite standard error).

    Returns
    -------
    float
        The Student-t quantile with ``chunks - 2`` degrees of freedom at the same two-sided level;
        infinity with fewer than 3 chunks.

    """
    if chunks < 3:
        return math.inf
    p_two_sided = math.erfc(min_sigma / math.sqrt(2.0))
    return float(stdtrit(chunks - 2, 1.0 - p_two_sided / 2.0))


def evaluate_health(summary, *, reference=None, thresholds=None, seconds_since_data=None):
    """
    Judge one axis summary against a reference and the thresholds (module doc).

    Parameters
    ----------
    summary : engine.AxisSummary
        The axis' sequence statistics and counts.
    reference : ReferenceStats, optional, keyword-only
        Reference characterisation; without it drift is judged by absolute limits and order and
        variance are only reported.
    thresholds : HealthThresholds, optional, keyword-only
        Limits of the verdicts (default: :class:`HealthThresholds()`).
    seconds_since_data : float, optional, keyword-only
        Time since the last sample (s); STALE above ``thresholds.stale_after_s``.

    Returns
    -------
    HealthVerdict

    """
    th = thresholds if thresholds is not None else HealthThresholds()
    seq = summary.sequence
    stream = summary.stream
    items = []  # (key, value, level, sentence)

    def add(key, value, level, sentence):
        items.append((key, value, level, sentence))

    judged = seq.chunks >= th.min_chunks
    drift = seq.drift
    drift_dph = drift.slope * _DEG * 3600.0
    sigma = abs(drift.slope) / drift.stderr if drift.stderr and math.isfinite(
        drift.stderr) else float('nan')
    significant = judged and math.isfinite(drift.slope) and (
        not math.isfinite(sigma) or sigma > drift_t_threshold(th.drift_min_sigma, seq.chunks))
    drift_item = len(items)
    add('Offset drift ((deg/s)/h)', _fmt(drift_dph), 'OK', '')
    ref_usable = (reference is not None and math.isfinite(reference.offset_drift_rad_s2)
                  and reference.offset_drift_rad_s2 != 0.0)
    differs = significant
    if ref_usable:
        # Both drifts carry an error: a ratio to a reference drift that is itself statistically
        # zero means nothing, and a large ratio only counts when the two drifts differ
        # significantly (errors added in quadrature).
        ref_se = reference.offset_drift_stderr_rad_s2
        ref_chunks = reference.chunks or seq.chunks
        if math.isfinite(ref_se) and ref_se > 0:
            ref_usable = (abs(reference.offset_drift_rad_s2) / ref_se
                          > drift_t_threshold(th.drift_min_sigma, ref_chunks))
            se = drift.stderr if math.isfinite(drift.stderr) else 0.0
            z = abs(drift.slope - reference.offset_drift_rad_s2) / math.hypot(se, ref_se)
            differs = significant and z > drift_t_threshold(th.drift_min_sigma,
                                                            min(seq.chunks, ref_chunks))
        if not ref_usable:
            add('Offset drift / reference', 'n/a', 'OK',
                'the reference drift is statistically zero: no ratio')
    if ref_usable:
        ratio = abs(drift.slope) / abs(reference.offset_drift_rad_s2)
        level = 'OK'
        if differs:
            level = ('ERROR' if ratio > th.drift_ratio_error else
                     'WARN' if ratio > th.drift_ratio_warn else 'OK')
        limit = th.drift_ratio_error if level == 'ERROR' else th.drift_ratio_warn
        add('Offset drift / reference', _fmt(ratio, 3), level,
            f'offset drift {abs(drift_dph):.4g} (deg/s)/h is {ratio:.3g}x the reference '
            f'({"above" if level != "OK" else "within"} {limit:g}x)')
    else:
        level = 'OK'
        if significant:
            level = ('ERROR' if abs(drift_dph) > th.drift_abs_error_deg_s_per_h else
                     'WARN' if abs(drift_dph) > th.drift_abs_warn_deg_s_per_h else 'OK')
        limit = (
            th.drift_abs_error_deg_s_per_h if level == 'ERROR' else th.drift_abs_warn_deg_s_per_h
        )
        items[drift_item] = ('Offset drift ((deg/s)/h)', _fmt(drift_dph), level,
                             f'offset drift {abs(drift_dph):.4g} (deg/s)/h is '
                             f'{"above" if level != "OK" else "within"} the limit '
                             f'{limit:g} (deg/s)/h')
    add('Offset drift significance (sigma)', _fmt(sigma, 3), 'OK', '')

    add('Fractional order, variance method', _fmt(seq.alpha_var_mean, 4), 'OK', '')
    add('Fractional order, correlation method', _fmt(seq.alpha_corr_mean, 4), 'OK', '')
    var_deg = seq.mean_variance * _DEG ** 2
    add('Mean variance ((deg/s)^2)', _fmt(var_deg), 'OK', '')
    if reference is not None and judged:
        for key, mean, ref, tol, name in (('Order deviation, variance method', seq.alpha_var_mean,
                                           reference.alpha_var_mean, th.alpha_var_tolerance,
                                           'variance-method order'),
                                          ('Order deviation, correlation method',
                                           seq.alpha_corr_mean, reference.alpha_corr_mean,
                                           th.alpha_corr_tolerance, 'correlation-method order')):
            dev = abs(mean - ref)
            level = _band(dev, tol)
            add(key, _fmt(mean - ref, 4), level,
                f'{name} {mean:.3f} differs from the reference {ref:.3f} by {dev:.3f} '
                f'(tolerance {tol:g})')
        if reference.mean_variance_rad2_s2 > 0:
            ratio = seq.mean_variance / reference.mean_variance_rad2_s2
            level = _band(abs(ratio - 1.0), th.variance_ratio_tolerance)
            add('Variance / reference', _fmt(ratio, 4), level,
                f'mean variance is {ratio:.3g}x the reference (tolerance '
                f'+/-{th.variance_ratio_tolerance:.0%})')

    expected = stream.samples + stream.samples_lost
    lost_frac = stream.samples_lost / expected if expected else 0.0
    level = ('ERROR' if lost_frac > th.lost_fraction_error else
             'WARN' if lost_frac > th.lost_fraction_warn else 'OK')
    add('Samples lost', f'{stream.samples_lost} ({lost_frac:.3g})', level,
        f'{stream.samples_lost} samples lost in {stream.gaps} gap(s) ({lost_frac:.3g} of '
        'expected)')
    nan_frac = summary.nan_samples / stream.samples if stream.samples else 0.0
    level = (
        'ERROR' if nan_frac > th.lost_fraction_error else 'WARN' if summary.nan_samples else 'OK'
    )
    add('NaN samples', str(summary.nan_samples), level,
        f'{summary.nan_samples} NaN/Inf samples ({summary.chunks_nan} chunk(s) not analysed)')
    add('Out-of-order stamps', str(stream.out_of_order), 'WARN' if stream.out_of_order else 'OK',
        f'{stream.out_of_order} stamps not later than their predecessor')
    total = (
        summary.chunks_ok
        + summary.chunks_nan
        + summary.chunks_dropped
        + summary.chunks_failed
        + summary.chunks_skipped
    )
    skip_frac = summary.chunks_skipped / total if total else 0.0
    level = ('ERROR' if skip_frac > th.skipped_fraction_error else
             'WARN' if skip_frac > th.skipped_fraction_warn else 'OK')
    add('Chunks skipped', f'{summary.chunks_skipped} of {total}', level,
        f'{summary.chunks_skipped} of {total} chunks skipped because analysis fell behind')
    add('Chunks analysed', str(summary.chunks_ok), 'OK', '')

    if seconds_since_data is not None and seconds_since_data > th.stale_after_s:
        add('Seconds since data', _fmt(seconds_since_data, 3), 'STALE',
            f'no data for {seconds_since_data:.1f} s')
    elif seq.chunks == 0 and total == 0:
        add('Complete chunks', '0', 'STALE',
            f'no complete chunk yet ({stream.samples} samples received)')

    worst = 'OK'
    for item in items:
        worst = _worse(item[2], worst)
    if worst == 'OK':
        basis = 'the reference' if reference is not None else 'the absolute limits'
        message = f'All checks within thresholds against {basis} ({seq.chunks} chunks).'
    else:
        sentence = next(i[3] for i in items if i[2] == worst)
        message = sentence[0].upper() + sentence[1:] + '.'
    return HealthVerdict(worst, message, tuple((k, v, lvl) for k, v, lvl, _ in items))


def load_reference(summary_json_path, *, bag=None, axis='z'):
    """
    Read one bag's and axis' reference from a ``summary.json`` of gyro_noise_analyze.

    Parameters
    ----------
    summary_json_path : str or os.PathLike
        The file.
    bag : str, optional, keyword-only
        Bag label or path inside the summary; None when the summary holds exactly one bag.
    axis : str, keyword-only
        'x', 'y' or 'z'.

    Returns
    -------
    ReferenceStats

    Raises
    ------
    ParameterError
        Missing/unreadable file, unknown or ambiguous bag, missing axis.

    """
    path = Path(summary_json_path)
    try:
        data = json.loads(path.read_text())
    except OSError as err:
        raise ParameterError(
            f'reference summary {str(path)!r} cannot be read: {err.strerror or err}') from err
    except ValueError as err:
        raise ParameterError(f'reference summary {str(path)!r} is not JSON: {err}') from err
    bags = data.get('bags') if isinstance(data, dict) else None
    if not isinstance(bags, list) or not bags:
        raise ParameterError(
            f'reference summary {str(path)!r} has no "bags" list (not a gyro_noise_analyze '
            'summary.json?)')
    if bag is None:
        if len(bags) != 1:
            names = ', '.join(str(b.get('label')) for b in bags)
            raise ParameterError(
                f'reference summary {str(path)!r} holds {len(bags)} bags ({names}); ' 'choose one')
        entry = bags[0]
    else:
        matches = [b for b in bags if bag in (b.get('label'), b.get('path'),
                                              Path(str(b.get('path'))).name)]
        if not matches:
            raise ParameterError(f'bag {bag!r} is not in reference summary {str(path)!r}')
        entry = matches[0]
    axes = entry.get('axes', {})
    if axis not in axes:
        raise ParameterError(f'axis {axis!r} is not in reference summary {str(path)!r} '
                             f'(axes: {", ".join(axes) or "none"})')
    a = axes[axis]
    try:
        return ReferenceStats(
            offset_drift_rad_s2=float(a['offset_drift_rad_s2']),
            mean_variance_rad2_s2=float(a['mean_variance_rad2_s2']),
            alpha_var_mean=float(a['alpha_var_mean']), alpha_corr_mean=float(a['alpha_corr_mean']),
            chunks=int(a.get('chunks', 0)), source=f'{path}:{entry.get("label")}:{axis}',
            offset_drift_stderr_rad_s2=float(a.get('offset_drift_stderr_rad_s2') or 'nan'))
    except (KeyError, TypeError, ValueError) as err:
        raise ParameterError(
            f'reference summary {str(path)!r}, axis {axis!r}: missing or bad field {err}') from err


def reference_per_axis(reference, axes, *, bag=None):
    """
    Normalise the ``reference`` argument of the engine to ``{axis: ReferenceStats}``.

    Parameters
    ----------
    reference : None, str, os.PathLike, ReferenceStats or dict
        A summary.json path (loaded per axis; its single bag), one ReferenceStats for all axes, or
        a dict.
    axes : tuple of str
        Axis names to return references for.
    bag : str, optional, keyword-only
        Bag label or path inside a summary.json holding several bags.

    Returns
    -------
    dict

    """
    if reference is None:
        return {}
    if isinstance(reference, ReferenceStats):
        return dict.fromkeys(axes, reference)
    if isinstance(reference, dict):
        bad = [k for k, v in reference.items() if not isinstance(v, ReferenceStats)]
        if bad:
            raise ParameterError(f'reference for axes {bad} is not a ReferenceStats')
        return dict(reference)
    if isinstance(reference, (str, Path)):
        # Axes the reference lacks are judged by absolute limits; at least one must match.
        out = {}
        for a in axes:
            try:
                out[a] = load_reference(reference, bag=bag, axis=a)
            except ParameterError as err:
                if 'is not in reference summary' not in str(err) or 'axis' not in str(err):
                    raise
        if not out:
            raise ParameterError(
                f'reference summary {str(reference)!r} has none of the axes {list(axes)}')
        return out
    raise InputDataError(
        f'reference must be a path, ReferenceStats or dict, got {type(reference).__name__}')
