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
Health verdicts of one gyro axis: the same logic in the analyzer node and the offline tool.

:func:`evaluate_health` compares a run's sequence statistics (paper 000 Tables 3-6, an
:class:`.results.AxisSummary`) with a reference characterisation (:class:`ReferenceStats`, read by
:func:`load_reference` from the offline tool's ``summary.json`` of a reference recording, like the
paper's "sequence ref") and with absolute limits, each a field of :class:`HealthThresholds`:

* offset drift (Table 3): without a reference against absolute limits in (deg/s)/h, judged only
  once significant (the Student-t quantile of :func:`drift_t_threshold`); with one, as
  ``|slope - reference slope|`` in standard errors of both, with the Student-t inflation;
* bias, variance (log scale), both orders and the noise colour against a reference: the distance
  of robust locations (:func:`.chunks.robust_location`) in pooled chunk spreads
  (:func:`spread_distance`), "undetermined" below ``reference_min_chunks`` chunks;
* samples lost, NaN/Inf samples, out-of-order stamps, chunks skipped by a node behind the stream;
* STALE: no complete chunk yet, or no data for ``stale_after_s`` when the caller says so.

Levels are ordered OK < WARN < ERROR < STALE (diagnostic_msgs 0-3); the verdict
(:class:`HealthVerdict`) is the worst item, its message one sentence naming it;
:func:`axis_status` makes the node's :class:`.items.TaskStatus` of it. The defaults, how the
multipliers were chosen and their false-alarm and detection rates: docs/verdicts.md and
docs/offline_tool.md ("Health verdicts").
"""

from collections.abc import Sequence
from dataclasses import dataclass, field, fields
import json
import math
import os
from pathlib import Path
from typing import Any

from scipy.special import stdtrit

from .chunks import DriftEstimate, NOISE_COLOUR_FACTORS, RobustLocation, SequenceSummary
from .items import fmt as _fmt
from .items import LEVEL_BYTE, LEVELS, TaskStatus
from .results import AxisSummary
from ..errors import InputDataError, InputError, ParameterError
from ..units import RAD_TO_DEG


def _threshold(default: float, description: str, unit: str = '') -> Any:
    # One source for the node's parameter table, its YAML file and the docs (field metadata).
    return field(default=default, metadata={'description': description, 'unit': unit})


@dataclass(frozen=True)
class HealthThresholds:
    """
    Documented thresholds of the health verdicts (module doc gives the reasoning).

    Attributes
    ----------
    drift_abs_warn_deg_s_per_h, drift_abs_error_deg_s_per_h : float
        Absolute |offset drift| limits ((deg/s)/h), used when there is no reference.
    drift_min_sigma : float
        Without a reference, a drift is judged only when |slope| exceeds this many standard
        errors (Student-t equivalent).
    min_chunks : int
        Chunks needed before the drift is judged (in each record, with a reference).
    reference_warn_sigma, reference_error_sigma : float
        Limits on a difference from the reference: in pooled chunk spreads for bias, variance and
        both orders, in pooled standard errors for the offset drift (its Student-t equivalent).
    reference_colour_warn_sigma, reference_colour_error_sigma : float
        Limits on the difference of the noise colour from the reference, in pooled chunk spreads.
    reference_min_chunks : int
        Chunks each record needs before bias, variance, orders and noise colour are compared.
    lost_fraction_warn, lost_fraction_error : float
        Limits on lost / expected samples (also NaN samples / samples for ERROR).
    skipped_fraction_warn, skipped_fraction_error : float
        Limits on skipped / all chunks.
    stale_after_s : float
        Seconds without data after which the verdict is STALE (s).

    """

    drift_abs_warn_deg_s_per_h: float = _threshold(
        0.02, 'WARN above this |offset drift| when there is no reference', '(deg/s)/h')
    drift_abs_error_deg_s_per_h: float = _threshold(
        0.05, 'ERROR above this |offset drift| when there is no reference', '(deg/s)/h')
    drift_min_sigma: float = _threshold(
        3.0, 'Without a reference, judge the drift only when |slope| exceeds this many standard '
        'errors', 'sigma')
    min_chunks: int = _threshold(
        3, 'Chunks needed before the drift is judged (in each record with a reference)', 'chunks')
    reference_warn_sigma: float = _threshold(
        5.0, 'WARN when bias, variance, an order or the drift differs from the reference by more '
        'than this many sigma (pooled chunk spreads; for the drift pooled standard errors; '
        'docs/verdicts.md)', 'sigma')
    reference_error_sigma: float = _threshold(
        10.0, 'ERROR when bias, variance, an order or the drift differs from the reference by '
        'more than this many sigma', 'sigma')
    reference_colour_warn_sigma: float = _threshold(
        2.5, 'WARN when the noise colour (ADEV log-log slope, m = 2-64 samples) differs from the '
        'reference by more than this many pooled chunk spreads (docs/verdicts.md)', 'sigma')
    reference_colour_error_sigma: float = _threshold(
        5.0, 'ERROR when the noise colour differs from the reference by more than this many '
        'pooled chunk spreads', 'sigma')
    reference_min_chunks: int = _threshold(
        10, 'Chunks each record needs before bias, variance, orders and noise colour are '
        'compared with the reference (fewer: undetermined)', 'chunks')
    lost_fraction_warn: float = _threshold(
        1e-4, 'WARN above this fraction of samples lost (from stamps)')
    lost_fraction_error: float = _threshold(
        1e-2, 'ERROR above this fraction of samples lost (from stamps)')
    skipped_fraction_warn: float = _threshold(
        0.1, 'WARN above this fraction of chunks skipped (analysis behind)')
    skipped_fraction_error: float = _threshold(
        0.5, 'ERROR above this fraction of chunks skipped (analysis behind)')
    stale_after_s: float = _threshold(5.0, 'STALE after this long without data', 's')

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ParameterError(
                    f'health threshold {f.name} must be a finite number >= 0, got {value!r}')
        if self.drift_abs_error_deg_s_per_h < self.drift_abs_warn_deg_s_per_h:
            raise ParameterError(
                'drift_abs_error_deg_s_per_h must be >= drift_abs_warn_deg_s_per_h, got '
                f'{self.drift_abs_error_deg_s_per_h} < {self.drift_abs_warn_deg_s_per_h}')
        if self.reference_error_sigma < self.reference_warn_sigma:
            raise ParameterError(
                f'reference_error_sigma ({self.reference_error_sigma}) must be >= '
                f'reference_warn_sigma ({self.reference_warn_sigma})')
        if self.reference_colour_error_sigma < self.reference_colour_warn_sigma:
            raise ParameterError(
                f'reference_colour_error_sigma ({self.reference_colour_error_sigma}) must be >= '
                f'reference_colour_warn_sigma ({self.reference_colour_warn_sigma})')
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
        Standard error of the reference drift (rad/s per s); NaN when unknown.
    bias, log_variance, alpha_var, alpha_corr, noise_colour : chunks.RobustLocation or None
        Robust location and spread of the reference's chunk biases (rad/s), natural log of chunk
        variances (of (rad/s)^2), orders and noise colours: what bias, variance, orders and
        noise colour are compared with. None: those comparisons are not made (said in the items).

    """

    offset_drift_rad_s2: float
    mean_variance_rad2_s2: float
    alpha_var_mean: float
    alpha_corr_mean: float
    chunks: int = 0
    source: str = ''
    offset_drift_stderr_rad_s2: float = float('nan')
    bias: RobustLocation | None = None
    log_variance: RobustLocation | None = None
    alpha_var: RobustLocation | None = None
    alpha_corr: RobustLocation | None = None
    noise_colour: RobustLocation | None = None

    @classmethod
    def from_sequence(cls, sequence: SequenceSummary, *, source: str = '') -> 'ReferenceStats':
        """
        Build the reference of a sequence summary (what its summary.json entry would load as).

        ``sequence`` holds the reference's statistics (:class:`.chunks.SequenceSummary`),
        ``source`` where it came from, for messages.

        """
        return cls(offset_drift_rad_s2=sequence.drift.slope,
                   mean_variance_rad2_s2=sequence.mean_variance,
                   alpha_var_mean=sequence.alpha_var_mean,
                   alpha_corr_mean=sequence.alpha_corr_mean, chunks=sequence.chunks,
                   source=source, offset_drift_stderr_rad_s2=sequence.drift.stderr,
                   bias=sequence.bias_robust, log_variance=sequence.log_variance_robust,
                   alpha_var=sequence.alpha_var_robust, alpha_corr=sequence.alpha_corr_robust,
                   noise_colour=getattr(sequence, 'noise_colour_robust', None))


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
    items: tuple[tuple[str, str, str], ...]

    @property
    def level_byte(self) -> int:
        """Return the level as a DiagnosticStatus byte (0 OK, 1 WARN, 2 ERROR, 3 STALE)."""
        return LEVEL_BYTE[self.level]


def _worse(a: str, b: str) -> str:
    return a if LEVELS.index(a) >= LEVELS.index(b) else b


def drift_t_threshold(min_sigma: float, chunks: int) -> float:
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
    # the lower tail keeps its digits at 10 sigma, where 1 - p / 2 rounds to 1
    return float(-stdtrit(chunks - 2, p_two_sided / 2.0))


def evaluate_health(summary: AxisSummary, *, reference: ReferenceStats | None = None,
                    thresholds: HealthThresholds | None = None,
                    seconds_since_data: float | None = None) -> HealthVerdict:
    """
    Judge one axis summary against a reference and the thresholds (module doc).

    Parameters
    ----------
    summary : results.AxisSummary
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
    # (key, value, level, sentence) of every check, in a stable order
    items = [*_drift_items(seq, reference, th), *_sequence_items(seq, reference, th),
             *_data_items(summary, th)]
    items += _chunk_items(summary, th, seconds_since_data)
    worst_level = 'OK'
    for item in items:
        worst_level = _worse(item[2], worst_level)
    if worst_level == 'OK':
        basis = 'the reference' if reference is not None else 'the absolute limits'
        message = f'All checks within thresholds against {basis} ({seq.chunks} chunks).'
    else:
        sentence = next(i[3] for i in items if i[2] == worst_level)
        message = sentence[0].upper() + sentence[1:] + '.'
    return HealthVerdict(worst_level, message, tuple((k, v, lvl) for k, v, lvl, _ in items))


def _drift_items(seq: SequenceSummary, reference: ReferenceStats | None,
                 th: HealthThresholds) -> list[tuple[str, str, str, str]]:
    """Return the offset drift items: absolute limits, or the comparison with the reference."""
    items = []
    judged = seq.chunks >= th.min_chunks
    drift = seq.drift
    drift_dph = drift.slope * RAD_TO_DEG * 3600.0
    sigma = abs(drift.slope) / drift.stderr if drift.stderr and math.isfinite(
        drift.stderr) else float('nan')
    significant = judged and math.isfinite(drift.slope) and (
        not math.isfinite(sigma) or sigma > drift_t_threshold(th.drift_min_sigma, seq.chunks))
    if reference is None:
        level = 'OK'
        if significant:
            level = ('ERROR' if abs(drift_dph) > th.drift_abs_error_deg_s_per_h else
                     'WARN' if abs(drift_dph) > th.drift_abs_warn_deg_s_per_h else 'OK')
        limit = (
            th.drift_abs_error_deg_s_per_h if level == 'ERROR' else th.drift_abs_warn_deg_s_per_h
        )
        items.append(('Offset drift ((deg/s)/h)', _fmt(drift_dph), level,
                      f'offset drift {abs(drift_dph):.4g} (deg/s)/h is '
                      f'{"above" if level != "OK" else "within"} the limit {limit:g} (deg/s)/h'))
    else:
        items.append(('Offset drift ((deg/s)/h)', _fmt(drift_dph), 'OK', ''))
        items.append(_drift_ratio(drift, reference, th))
        items.append(_compare_drift(seq, reference, th))
    items.append(('Offset drift significance (sigma)', _fmt(sigma, 3), 'OK', ''))
    return items


def _sequence_items(seq: SequenceSummary, reference: ReferenceStats | None,
                    th: HealthThresholds) -> list[tuple[str, str, str, str]]:
    """Return the orders, variance and colour of the run and their comparisons (reference)."""
    items = [('Fractional order, variance method', _fmt(seq.alpha_var_mean, 4), 'OK', ''),
             ('Fractional order, correlation method', _fmt(seq.alpha_corr_mean, 4), 'OK', ''),
             ('Mean variance ((deg/s)^2)', _fmt(seq.mean_variance * RAD_TO_DEG ** 2), 'OK', '')]
    colour = getattr(seq, 'noise_colour_robust', None)
    if colour is not None:
        items.append((COLOUR_NAME, _fmt(colour.location, 4), 'OK', ''))
    if reference is not None:
        items += [_compare(spec, getattr(seq, spec[1], None), getattr(reference, spec[2], None),
                           th) for spec in _COMPARISONS]
    return items


def _data_items(summary: AxisSummary,
                th: HealthThresholds) -> list[tuple[str, str, str, str]]:
    """Return the items of the samples: lost (from stamps), NaN, stamp order."""
    stream = summary.stream
    expected = stream.samples + stream.samples_lost
    lost_frac = stream.samples_lost / expected if expected else 0.0
    lost_level = ('ERROR' if lost_frac > th.lost_fraction_error else
                  'WARN' if lost_frac > th.lost_fraction_warn else 'OK')
    nan_frac = summary.nan_samples / stream.samples if stream.samples else 0.0
    nan_level = (
        'ERROR' if nan_frac > th.lost_fraction_error else 'WARN' if summary.nan_samples else 'OK'
    )
    return [
        ('Samples lost', f'{stream.samples_lost} ({lost_frac:.3g})', lost_level,
         f'{stream.samples_lost} samples lost in {stream.gaps} gap(s) ({lost_frac:.3g} of '
         'expected)'),
        ('NaN samples', str(summary.nan_samples), nan_level,
         f'{summary.nan_samples} NaN/Inf samples ({summary.chunks_nan} chunk(s) not analysed)'),
        ('Out-of-order stamps', str(stream.out_of_order),
         'WARN' if stream.out_of_order else 'OK',
         f'{stream.out_of_order} stamps earlier than the latest stamp before them'),
        ('Equal stamps', str(getattr(stream, 'equal_stamps', 0)), 'OK', ''),
    ]


def _chunk_items(summary: AxisSummary, th: HealthThresholds,
                 seconds_since_data: float | None) -> list[tuple[str, str, str, str]]:
    """Return the items of the chunks (skipped, analysed) and of staleness."""
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
    items = [('Chunks skipped', f'{summary.chunks_skipped} of {total}', level,
              f'{summary.chunks_skipped} of {total} chunks skipped because analysis fell behind'),
             ('Chunks analysed', str(summary.chunks_ok), 'OK', '')]
    if seconds_since_data is not None and seconds_since_data > th.stale_after_s:
        items.append(('Seconds since data', _fmt(seconds_since_data, 3), 'STALE',
                      f'no data for {seconds_since_data:.1f} s'))
    elif summary.sequence.chunks == 0 and total == 0:
        items.append(('Complete chunks', '0', 'STALE',
                      f'no complete chunk yet ({summary.stream.samples} samples received)'))
    return items


def axis_status(verdict: HealthVerdict, values: list, *, rejected_batches: int = 0,
                last_rejection: str = '', rejecting: bool = False,
                seconds_since_data: float | None = None,
                thresholds: HealthThresholds | None = None, publishers: int = 1) -> TaskStatus:
    """
    Return the analyzer's status of one axis: the verdict, the publishers, the refused batches.

    The analyzer's diagnostics task on its timer: the engine's counters (ticked while ingesting)
    are judged by :func:`evaluate_health`. More than one publisher of the data means a second
    sensor's samples are mixed into the chunks and every number is suspect: an OK or WARN verdict
    becomes WARN, and an OK one's message names the publishers (a worse verdict's message
    leads). Refused batches add their count and reason to the values, and while data arrives but
    is refused the level is ERROR (rather than STALE for 'no chunk yet'); once batches are
    accepted again only the count stays.

    Parameters
    ----------
    verdict : HealthVerdict
        The axis' verdict.
    values : list of (str, str)
        The key/values of the status (the verdict's items first), in order.
    rejected_batches : int, keyword-only
        Batches the engine refused so far.
    last_rejection : str, keyword-only
        Why the last one was refused.
    rejecting : bool, keyword-only
        The latest batch was refused.
    seconds_since_data : float, optional, keyword-only
        Time since the last message arrived (s); None before any.
    thresholds : HealthThresholds, optional, keyword-only
        Their ``stale_after_s``: no data for longer is silence, not refusal.
    publishers : int, keyword-only
        Publishers of the data that delivered recently (the node's count).

    Returns
    -------
    TaskStatus

    """
    th = thresholds if thresholds is not None else HealthThresholds()
    values = list(values)
    level, message = verdict.level, verdict.message
    if publishers > 1 and level in ('OK', 'WARN'):
        if level == 'OK':
            message = f'{publishers} publishers of the data: their samples are mixed.'
        level = 'WARN'
    if rejected_batches:
        values += [('Batches rejected', str(rejected_batches)), ('Last rejection', last_rejection)]
        silent = seconds_since_data is not None and seconds_since_data > th.stale_after_s
        if rejecting and not silent:
            level, message = 'ERROR', f'Samples rejected: {last_rejection}.'
    return TaskStatus(level, message, tuple(values))


#: Item key of the run's noise colour (robust location of the chunk values, informative).
COLOUR_NAME = 'Noise colour (ADEV slope, m = 2-64 samples)'
#: The like-with-like comparisons with a reference: (item key, SequenceSummary field,
#: ReferenceStats field, name in sentences, kind of quantity).
_COMPARISONS = (
    ('Bias deviation (deg/s)', 'bias_robust', 'bias', 'bias', 'rate'),
    ('Variance / reference', 'log_variance_robust', 'log_variance', 'variance', 'log'),
    ('Order deviation, variance method', 'alpha_var_robust', 'alpha_var',
     'variance-method order', 'order'),
    ('Order deviation, correlation method', 'alpha_corr_robust', 'alpha_corr',
     'correlation-method order', 'order'),
    ('Noise colour deviation (ADEV slope, m = 2-64 samples)', 'noise_colour_robust',
     'noise_colour', 'noise colour (ADEV slope)', 'colour'),
)


def _limits(kind: str, th: HealthThresholds) -> tuple[float, float]:
    """Return the (WARN, ERROR) multipliers of a comparison of ``kind`` (module doc)."""
    if kind == 'colour':
        return th.reference_colour_warn_sigma, th.reference_colour_error_sigma
    return th.reference_warn_sigma, th.reference_error_sigma


def _drift_ratio(drift: DriftEstimate, reference: ReferenceStats,
                 th: HealthThresholds) -> tuple[str, str, str, str]:
    """Return the informative item |drift| / |reference drift| (n/a when that is zero)."""
    ref = reference.offset_drift_rad_s2
    ref_se = reference.offset_drift_stderr_rad_s2
    zero = not (math.isfinite(ref) and ref != 0.0) or (
        math.isfinite(ref_se) and ref_se > 0 and abs(ref) / ref_se
        <= drift_t_threshold(th.drift_min_sigma, reference.chunks or 3))
    if zero:
        return ('Offset drift / reference', 'n/a', 'OK',
                'the reference drift is statistically zero: no ratio')
    return 'Offset drift / reference', _fmt(abs(drift.slope) / abs(ref), 3), 'OK', ''


def _compare_drift(seq: SequenceSummary, reference: ReferenceStats,
                   th: HealthThresholds) -> tuple[str, str, str, str]:
    """
    Return the item comparing the drift with the reference's, like with like (module doc).

    ``z = |slope - reference slope| / hypot(stderr, reference stderr)`` against
    ``reference_warn_sigma`` and ``reference_error_sigma``, both multiplied by the Student-t
    inflation at the WARN level: the Student-t quantile (fewer chunks of the two records, minus 2
    degrees of freedom) at the two-sided level of ``reference_warn_sigma`` standard deviations of
    a normal, over ``reference_warn_sigma`` (1.07 with 100 chunks, 4.4 with 8), because a
    standard error from few chunks is itself uncertain.
    """
    key = 'Offset drift deviation (sigma)'
    drift = seq.drift
    ref, ref_se = reference.offset_drift_rad_s2, reference.offset_drift_stderr_rad_s2
    chunks = min(seq.chunks, reference.chunks or seq.chunks)
    if chunks < th.min_chunks:
        return (key, 'undetermined', 'OK',
                f'offset drift undetermined: {seq.chunks} chunks here and {reference.chunks} in '
                f'the reference, {th.min_chunks} needed in each')
    pooled = math.hypot(drift.stderr, ref_se)
    if not (math.isfinite(drift.slope) and math.isfinite(ref) and math.isfinite(pooled)
            and pooled > 0):
        return key, 'n/a', 'OK', 'offset drift: no standard error of one of the slopes'
    z = abs(drift.slope - ref) / pooled
    inflation = (drift_t_threshold(th.reference_warn_sigma, chunks) / th.reference_warn_sigma
                 if th.reference_warn_sigma > 0 else 1.0)
    warn = th.reference_warn_sigma * inflation
    error = th.reference_error_sigma * inflation
    level = 'ERROR' if z > error else 'WARN' if z > warn else 'OK'
    limit = error if level == 'ERROR' else warn
    per_h = RAD_TO_DEG * 3600.0
    return (key, _fmt(z, 3), level,
            f'offset drift {drift.slope * per_h:+.4g} (deg/s)/h differs from the reference '
            f'{ref * per_h:+.4g} (deg/s)/h by {z:.3g} standard errors of both '
            f'({"above" if level != "OK" else "within"} {limit:.3g}: '
            f'{th.reference_error_sigma if level == "ERROR" else th.reference_warn_sigma:g} '
            f'sigma x {inflation:.3g} for {chunks} chunks)')


def _describe(loc: RobustLocation, kind: str) -> str:
    if kind == 'rate':
        value = f'{loc.location * RAD_TO_DEG:.4g} deg/s'
    elif kind == 'log':
        value = f'{math.exp(loc.location) * RAD_TO_DEG ** 2:.4g} (deg/s)^2'
    else:
        value = f'{loc.location:.3f}'
    if loc.population == 'dominant mode':
        return (f'{value} (median of the dominant mode, {loc.count} of {loc.total} chunks, modes '
                + ', '.join(f'{m:.2f} x{c}' for m, c in loc.modes) + ')')
    return f'{value} (median of {loc.count} chunks)'


def spread_distance(mine: RobustLocation, ref: RobustLocation) -> float:
    """
    Return the distance of two robust locations in pooled chunk spreads (module doc).

    Parameters
    ----------
    mine, ref : chunks.RobustLocation
        This record's and the reference's location and spread of one quantity.

    Returns
    -------
    float
        ``|mine.location - ref.location| / hypot(mine.spread, ref.spread)``; infinity for a
        difference over zero spread, 0 for none, NaN when a location or spread is unknown.

    """
    diff = mine.location - ref.location
    scale = math.hypot(mine.spread, ref.spread)
    if not (math.isfinite(diff) and math.isfinite(scale)):
        return float('nan')
    if scale == 0.0:
        return math.inf if diff != 0.0 else 0.0
    return abs(diff) / scale


def _compare(spec: tuple[str, str, str, str, str], mine: RobustLocation | None,
             ref: RobustLocation | None, th: HealthThresholds) -> tuple[str, str, str, str]:
    """Return the item (key, value, level, sentence) of one like-with-like comparison."""
    key, _, _, name, kind = spec
    if mine is None or ref is None:
        side = 'this run' if mine is None else 'the reference'
        older = ' (a summary.json of an older gyro_noise_analyze)' if kind == 'colour' else ''
        return key, 'n/a', 'OK', f'{name}: no chunk statistics for {side}{older}'
    if kind == 'colour' and 0 in (mine.total, ref.total):
        side = 'this run' if not mine.total else 'the reference'
        return (key, 'n/a', 'OK', f'{name}: not computed for {side} (chunks of fewer than '
                f'{4 * max(NOISE_COLOUR_FACTORS)} samples)')
    need = int(th.reference_min_chunks)
    if mine.count < need or ref.count < need:
        return (key, 'undetermined', 'OK',
                f'{name} undetermined: {mine.count} chunks here and {ref.count} in the '
                f'reference, {need} needed in each')
    d = spread_distance(mine, ref)
    if math.isnan(d):
        return key, 'n/a', 'OK', f'{name}: no finite chunk values'
    diff = mine.location - ref.location
    if kind == 'rate':
        value, by = f'{diff * RAD_TO_DEG:+.4g}', f'{abs(diff) * RAD_TO_DEG:.3g} deg/s'
    elif kind == 'log':
        value, by = f'{math.exp(diff):.4g}', f'a factor {math.exp(diff):.3g}'
    else:
        value, by = f'{diff:+.4f}', f'{abs(diff):.3f}'
    warn, error = _limits(kind, th)
    level = 'ERROR' if d > error else 'WARN' if d > warn else 'OK'
    limit = error if level == 'ERROR' else warn
    return (key, f'{value} ({d:.3g} spreads)', level,
            f'{name} {_describe(mine, kind)} differs from the reference {_describe(ref, kind)} by '
            f'{by}, {d:.3g} pooled chunk spreads ({"above" if level != "OK" else "within"} '
            f'{limit:g})')


def reference_dict(sequence: SequenceSummary) -> dict[str, dict[str, Any] | None]:
    """
    Return what a reference needs from one axis' sequence statistics, for its summary.json.

    Parameters
    ----------
    sequence : chunks.SequenceSummary
        The axis' statistics.

    Returns
    -------
    dict
        ``{'bias_rad_s', 'log_variance_rad2_s2', 'alpha_var', 'alpha_corr',
        'noise_colour_adev_slope'}``, each the :meth:`.chunks.RobustLocation.as_dict` of that
        quantity (the variance as the natural log of the chunk variances in (rad/s)^2, the noise
        colour dimensionless); None where not computed.

    """
    out = {}
    for key, field_name in ROBUST_KEYS:
        loc = getattr(sequence, field_name, None)
        out[key] = loc.as_dict() if loc is not None else None
    return out


#: summary.json keys of the robust chunk statistics and the SequenceSummary fields they hold.
ROBUST_KEYS = (('bias_rad_s', 'bias_robust'), ('log_variance_rad2_s2', 'log_variance_robust'),
               ('alpha_var', 'alpha_var_robust'), ('alpha_corr', 'alpha_corr_robust'),
               ('noise_colour_adev_slope', 'noise_colour_robust'))
#: The per-axis key of summary.json holding :func:`reference_dict`.
ROBUST_JSON_KEY = 'reference_statistics'


def load_reference(summary_json_path: str | os.PathLike[str], *, bag: str | None = None,
                   axis: str = 'z') -> ReferenceStats:
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
    InputError
        Missing or unreadable file, not JSON, not a summary.json of this version (exit code 3,
        as every unreadable input).
    ParameterError
        Unknown or ambiguous bag, missing axis.

    """
    path = Path(summary_json_path)
    try:
        data = json.loads(path.read_text())
    except OSError as err:
        raise InputError(
            f'reference summary {str(path)!r} cannot be read: {err.strerror or err}') from err
    except ValueError as err:
        raise InputError(f'reference summary {str(path)!r} is not JSON: {err}') from err
    bags = data.get('bags') if isinstance(data, dict) else None
    if not isinstance(bags, list) or not bags:
        raise InputError(
            f'reference summary {str(path)!r} has no "bags" list (not a gyro_noise_analyze '
            'summary.json?)')
    if bag is None:
        if len(bags) != 1:
            names = ', '.join(str(b.get('label')) for b in bags)
            raise ParameterError(
                f'reference summary {str(path)!r} holds {len(bags)} bags ({names}): choose '
                'one with {bag}', parameters=('bag',))
        entry = bags[0]
    else:
        matches = [b for b in bags if bag in (b.get('label'), b.get('path'),
                                              Path(str(b.get('path'))).name)]
        if not matches:
            names = ', '.join(str(b.get('label')) for b in bags)
            raise ParameterError(f'{{bag}} {bag!r} is not in reference summary {str(path)!r} '
                                 f'(its bags: {names})', parameters=('bag',))
        entry = matches[0]
    axes = entry.get('axes', {})
    if axis not in axes:
        raise ParameterError(f'axis {axis!r} is not in reference summary {str(path)!r} '
                             f'(axes: {", ".join(axes) or "none"})')
    a = axes[axis]
    if isinstance(a, dict) and 'offset_drift_rad_s2' in a and (
            a['offset_drift_rad_s2'] is None or a.get('chunks', 0) < 2):
        raise ParameterError(
            f"reference summary {str(path)!r}, bag {entry.get('label')!r}, axis {axis!r}: "
            f"{a.get('chunks', 0)} chunk(s), too few for a reference (its offset drift needs 2 "
            'or more): analyse the reference record again with a smaller {chunk_size}, or '
            'record it longer', parameters=('chunk_size',))
    robust = a.get(ROBUST_JSON_KEY) if isinstance(a, dict) else None
    if not isinstance(robust, dict):
        raise InputError(
            f'reference summary {str(path)!r}, axis {axis!r}, has no "{ROBUST_JSON_KEY}" (written '
            'by an older gyro_noise_analyze): regenerate it with this version from '
            f'{entry.get("path") or "the reference recording"}')
    try:
        stats = {field_name: RobustLocation.from_dict(robust[key])
                 if robust.get(key) is not None else None for key, field_name in ROBUST_KEYS}
        return ReferenceStats(
            offset_drift_rad_s2=float(a['offset_drift_rad_s2']),
            mean_variance_rad2_s2=float(a['mean_variance_rad2_s2']),
            alpha_var_mean=float(a['alpha_var_mean']), alpha_corr_mean=float(a['alpha_corr_mean']),
            chunks=int(a.get('chunks', 0)), source=f'{path}:{entry.get("label")}:{axis}',
            offset_drift_stderr_rad_s2=float(a.get('offset_drift_stderr_rad_s2') or 'nan'),
            bias=stats['bias_robust'], log_variance=stats['log_variance_robust'],
            alpha_var=stats['alpha_var_robust'], alpha_corr=stats['alpha_corr_robust'],
            noise_colour=stats['noise_colour_robust'])
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(
            f'reference summary {str(path)!r}, axis {axis!r}: missing or bad field {err}') from err


def reference_per_axis(reference: str | Path | ReferenceStats | dict[str, ReferenceStats] | None,
                       axes: Sequence[str], *,
                       bag: str | None = None) -> dict[str, ReferenceStats]:
    """
    Normalise the ``reference`` argument of the engine to ``{axis: ReferenceStats}``.

    Parameters
    ----------
    reference : None, str, pathlib.Path, ReferenceStats or dict
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
