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
Tests of the health verdicts (gyro_noise_ros.core.health).

Every level at its documented threshold.
"""

from dataclasses import replace
import json
import math

from gyro_noise_ros.core.chunks import (DriftEstimate, RobustLocation, SequenceSummary,
                                        summarise_sequence)
from gyro_noise_ros.core.engine import StreamCounts
from gyro_noise_ros.core.health import (
    axis_status,
    drift_t_threshold,
    evaluate_health,
    HealthThresholds,
    LEVEL_BYTE,
    load_reference,
    reference_dict,
    reference_per_axis,
    ReferenceStats,
)
from gyro_noise_ros.core.results import AxisSummary
from gyro_noise_ros.errors import InputError, ParameterError
import numpy as np
import pytest

DEG_S_PER_H = math.radians(1.0) / 3600.0  # 1 (deg/s)/h in rad/s^2
REF = ReferenceStats(offset_drift_rad_s2=0.003565 * DEG_S_PER_H, mean_variance_rad2_s2=1e-6,
                     alpha_var_mean=1.4, alpha_corr_mean=1.0, chunks=100)


def summary(*, drift_dph=0.0, stderr_dph=1e-9, chunks=100, variance=1e-6, alpha_var=1.4,
            alpha_corr=1.0, samples=1_000_000, lost=0, gaps=0, out_of_order=0, nan=0, skipped=0):
    seq = SequenceSummary(chunks=chunks, tail_samples=0, bias_mean=0.0,
                          drift=DriftEstimate(drift_dph * DEG_S_PER_H, stderr_dph * DEG_S_PER_H,
                                              0.0, 3600.0), mean_variance=variance,
                          variance_of_variances=1e-14, alpha_var_mean=alpha_var,
                          alpha_var_variance=1e-4, alpha_corr_mean=alpha_corr,
                          alpha_corr_variance=0.1, ties_var=0, ties_corr=0)
    stream = StreamCounts(samples=samples, samples_lost=lost, gaps=gaps, out_of_order=out_of_order,
                          chunks=chunks, tail_samples=0, discarded_samples=0, discarded_partials=0,
                          rate_hz=6660.0, duration_s=150.0)
    return AxisSummary(axis='z', sequence=seq, stream=stream, nan_samples=nan, chunks_ok=chunks,
                       chunks_nan=0, chunks_dropped=0, chunks_failed=0, chunks_skipped=skipped,
                       temperature_mean_c=22.0)


def level(s, **kw):
    return evaluate_health(s, **kw).level


def item_level(verdict, key):
    return next(lv for k, _, lv in verdict.items if k == key)


def test_all_ok_against_reference_and_without():
    v = evaluate_health(summary(drift_dph=0.003565), reference=REF)
    assert v.level == 'OK' and 'against the reference' in v.message and v.level_byte == 0
    assert evaluate_health(summary(drift_dph=0.003565)).level == 'OK'


REF_SE = replace(REF, offset_drift_stderr_rad_s2=0.001 * DEG_S_PER_H)
#: 5 and 10 sigma times the Student-t inflation at 5 sigma with 100 chunks (98 degrees of freedom)
T5 = drift_t_threshold(5.0, 100)
T10 = 2.0 * T5


@pytest.mark.parametrize('z, expected', [(0.99 * T5, 'OK'), (1.01 * T5, 'WARN'),
                                         (0.99 * T10, 'WARN'), (1.01 * T10, 'ERROR')])
def test_drift_against_reference_in_standard_errors_of_both(z, expected):
    # both slopes carry 0.001 (deg/s)/h of error: the difference is judged against 0.00141
    pooled = math.hypot(0.001, 0.001)
    for sign in (1.0, -1.0):
        s = summary(drift_dph=0.003565 + sign * z * pooled, stderr_dph=0.001)
        v = evaluate_health(s, reference=REF_SE)
        assert item_level(v, 'Offset drift deviation (sigma)') == expected
        assert v.level == expected
        if expected != 'OK':
            assert 'standard errors of both' in v.message and v.message.endswith('.')
    assert T5 == pytest.approx(5.35, abs=0.01)


def test_drift_ratio_is_information_and_a_zero_reference_drift_is_still_compared():
    v = evaluate_health(summary(drift_dph=0.003565 * 20, stderr_dph=0.001), reference=REF_SE)
    values = {k: val for k, val, _ in v.items}
    assert values['Offset drift / reference'] == '20' and v.level == 'ERROR'  # 49 errors
    zero = replace(REF_SE, offset_drift_rad_s2=0.0001 * DEG_S_PER_H)  # 0.1 standard errors
    v = evaluate_health(summary(drift_dph=0.0001, stderr_dph=0.001), reference=zero)
    assert {k: val for k, val, _ in v.items}['Offset drift / reference'] == 'n/a'
    assert v.level == 'OK'
    v = evaluate_health(summary(drift_dph=0.03, stderr_dph=0.001), reference=zero)
    assert item_level(v, 'Offset drift deviation (sigma)') == 'ERROR'
    # no standard error for the reference (a hand-made ReferenceStats): not compared, said
    v = evaluate_health(summary(drift_dph=1.0, stderr_dph=0.001), reference=REF)
    assert {k: val for k, val, _ in v.items}['Offset drift deviation (sigma)'] == 'n/a'


@pytest.mark.parametrize('drift, expected', [(0.0199, 'OK'), (0.0201, 'WARN'), (0.0499, 'WARN'),
                                             (0.0501, 'ERROR')])
def test_absolute_drift_thresholds_without_reference(drift, expected):
    assert level(summary(drift_dph=drift)) == expected


def test_insignificant_or_early_drift_is_not_judged():
    # |slope| = 2 stderr < drift_min_sigma = 3: the slope is noise, whatever its size.
    assert level(summary(drift_dph=1.0, stderr_dph=0.5)) == 'OK'
    assert level(summary(drift_dph=1.0, stderr_dph=0.3)) == 'ERROR'
    assert level(summary(drift_dph=1.0, chunks=2)) == 'OK'  # below min_chunks
    # against a reference: 2.0 pooled standard errors is within; 2 chunks are undetermined
    assert level(summary(drift_dph=1.0, stderr_dph=0.5), reference=REF_SE) == 'OK'
    v = evaluate_health(summary(drift_dph=1.0, chunks=2), reference=REF_SE)
    assert {k: val for k, val, _ in v.items}['Offset drift deviation (sigma)'] == 'undetermined'


def robust(location, spread, count=100, **kw):
    return RobustLocation(location, spread, count, count, **kw)


def with_chunk_stats(s, *, bias=0.0, log_var=-13.8, alpha_var=1.4, alpha_corr=1.0, spread=0.01,
                     count=100, **kw):
    seq = replace(s.sequence, bias_robust=robust(bias, spread, count, **kw),
                  log_variance_robust=robust(log_var, spread, count),
                  alpha_var_robust=robust(alpha_var, spread, count, **kw),
                  alpha_corr_robust=robust(alpha_corr, spread, count, **kw))
    return replace(s, sequence=seq)


REF_STATS = replace(REF, bias=robust(0.0, 0.01), log_variance=robust(-13.8, 0.01),
                    alpha_var=robust(1.4, 0.01), alpha_corr=robust(1.0, 0.01))
SPREAD = math.hypot(0.01, 0.01)  # pooled spread of the comparisons below


@pytest.mark.parametrize('field, key', [('bias', 'Bias deviation (deg/s)'),
                                        ('log_var', 'Variance / reference'),
                                        ('alpha_var', 'Order deviation, variance method'),
                                        ('alpha_corr', 'Order deviation, correlation method')])
@pytest.mark.parametrize('spreads, expected', [(4.99, 'OK'), (5.01, 'WARN'), (9.99, 'WARN'),
                                               (10.01, 'ERROR')])
def test_reference_comparisons_in_pooled_chunk_spreads(field, key, spreads, expected):
    # |location - reference location| / hypot(spread, reference spread) against 5 and 10
    base = {'bias': 0.0, 'log_var': -13.8, 'alpha_var': 1.4, 'alpha_corr': 1.0}
    for sign in (1.0, -1.0):
        kw = dict(base, **{field: base[field] + sign * spreads * SPREAD})
        v = evaluate_health(with_chunk_stats(summary(), **kw), reference=REF_STATS)
        assert item_level(v, key) == expected and v.level == expected
        if expected != 'OK':
            assert 'pooled chunk spreads' in v.message and v.message.endswith('.')


COLOUR_KEY = 'Noise colour deviation (ADEV slope, m = 2-64 samples)'


@pytest.mark.parametrize('spreads, expected', [(2.49, 'OK'), (2.51, 'WARN'), (4.99, 'WARN'),
                                               (5.01, 'ERROR')])
def test_noise_colour_in_pooled_chunk_spreads_with_its_own_multipliers(spreads, expected):
    # the same distance as the other items, against reference_colour_warn_sigma (2.5) and
    # reference_colour_error_sigma (5)
    ref = replace(REF_STATS, noise_colour=robust(-0.47, 0.012))
    pooled = math.hypot(0.012, 0.012)
    for sign in (1.0, -1.0):
        s = with_chunk_stats(summary())
        s = replace(s, sequence=replace(s.sequence, noise_colour_robust=robust(
            -0.47 + sign * spreads * pooled, 0.012)))
        v = evaluate_health(s, reference=ref)
        assert item_level(v, COLOUR_KEY) == expected and v.level == expected
        values = {k: val for k, val, _ in v.items}
        assert values[COLOUR_KEY].endswith(f'({spreads:.3g} spreads)')
        colour = -0.47 + sign * spreads * pooled
        assert values['Noise colour (ADEV slope, m = 2-64 samples)'] == f'{colour:.4g}'
        if expected != 'OK':
            assert v.message.startswith(f'Noise colour (ADEV slope) {colour:.3f} (median of 100 '
                                        'chunks) differs from the reference -0.470'), v.message
            assert 'pooled chunk spreads' in v.message
    th = HealthThresholds(reference_colour_warn_sigma=1.0, reference_colour_error_sigma=2.0)
    s = with_chunk_stats(summary())
    s = replace(s, sequence=replace(s.sequence, noise_colour_robust=robust(-0.47 + 1.5 * pooled,
                                                                           0.012)))
    assert item_level(evaluate_health(s, reference=ref, thresholds=th), COLOUR_KEY) == 'WARN'
    # the shared multipliers do not move it
    th = HealthThresholds(reference_warn_sigma=1.0, reference_error_sigma=2.0)
    assert item_level(evaluate_health(s, reference=ref, thresholds=th), COLOUR_KEY) == 'OK'
    with pytest.raises(ParameterError, match='reference_colour_error_sigma'):
        HealthThresholds(reference_colour_warn_sigma=5.0, reference_colour_error_sigma=4.0)


def test_noise_colour_missing_or_not_computed_is_said():
    s = with_chunk_stats(summary())
    s = replace(s, sequence=replace(s.sequence, noise_colour_robust=robust(-0.3, 0.01)))
    # a reference written before the noise colour existed: n/a, the rest still compared
    v = evaluate_health(s, reference=REF_STATS)
    assert {k: val for k, val, _ in v.items}[COLOUR_KEY] == 'n/a' and v.level == 'OK'
    assert item_level(v, 'Order deviation, variance method') == 'OK'
    # chunks shorter than 4 x 64 samples have no colour (all NaN)
    nan = RobustLocation(float('nan'), float('nan'), 0, 0)
    ref = replace(REF_STATS, noise_colour=robust(-0.3, 0.01))
    s = replace(s, sequence=replace(s.sequence, noise_colour_robust=nan))
    v = evaluate_health(s, reference=ref)
    assert {k: val for k, val, _ in v.items}[COLOUR_KEY] == 'n/a' and v.level == 'OK'
    s = replace(s, sequence=replace(s.sequence, noise_colour_robust=robust(-0.3, 0.01, count=9)))
    v = evaluate_health(s, reference=ref)
    assert {k: val for k, val, _ in v.items}[COLOUR_KEY] == 'undetermined'


def test_tolerance_follows_the_spread_of_both_records():
    # One order difference of 0.05, judged against chunk spreads of both records: 0.05 /
    # hypot(s, s_ref) is 1.86 with (0.025, 0.01), 3.54 with (0.01, 0.01), 7.07 with (0.005,
    # 0.005), 11.8 with (0.003, 0.003).
    cases = ((0.025, 0.01, 'OK', '1.86'), (0.01, 0.01, 'OK', '3.54'),
             (0.005, 0.005, 'WARN', '7.07'), (0.003, 0.003, 'ERROR', '11.8'))
    for spread, ref_spread, expected, text in cases:
        ref = replace(REF_STATS, alpha_var=robust(1.4, ref_spread))
        v = evaluate_health(with_chunk_stats(summary(), alpha_var=1.45, spread=spread),
                            reference=ref)
        assert item_level(v, 'Order deviation, variance method') == expected
        assert {k: val for k, val, _ in v.items}[
            'Order deviation, variance method'] == f'+0.0500 ({text} spreads)'


def test_dominant_mode_is_named_in_the_text():
    modes = ((0.02, 5), (1.12, 95))
    s = with_chunk_stats(summary(), alpha_var=1.12, count=95, population='dominant mode',
                         modes=modes)
    v = evaluate_health(s, reference=REF_STATS)
    assert v.level == 'ERROR'  # 1.12 against 1.4: 19.8 spreads
    assert 'median of the dominant mode, 95 of 95 chunks, modes 0.02 x5, 1.12 x95' in v.message


def test_too_few_chunks_is_undetermined_and_missing_statistics_are_said():
    s = with_chunk_stats(summary(), alpha_var=3.0, count=9)
    v = evaluate_health(s, reference=REF_STATS)
    assert item_level(v, 'Order deviation, variance method') == 'OK'
    assert {k: val for k, val, _ in v.items}[
        'Order deviation, variance method'] == 'undetermined'
    v = evaluate_health(summary(alpha_var=3.0), reference=REF)  # no chunk statistics at all
    assert v.level == 'OK' and {k: val for k, val, _ in v.items}[
        'Variance / reference'] == 'n/a'


def test_variance_ratio_is_reported():
    v = evaluate_health(with_chunk_stats(summary(), log_var=-13.8 + math.log(1.25)),
                        reference=REF_STATS)
    value = {k: val for k, val, _ in v.items}['Variance / reference']
    assert value.startswith('1.25 (') and item_level(v, 'Variance / reference') == 'ERROR'
    assert 'differs from the reference' in v.message and 'a factor 1.25' in v.message


def test_order_and_variance_are_only_reported_without_reference():
    v = evaluate_health(summary(alpha_var=0.2, variance=1.0))
    assert v.level == 'OK'
    keys = [k for k, _, _ in v.items]
    assert (
        'Fractional order, variance method' in keys
        and 'Order deviation, variance method' not in keys
    )


@pytest.mark.parametrize(
    'lost, expected', [(0, 'OK'), (100, 'OK'), (102, 'WARN'), (10_000, 'WARN'), (10_200, 'ERROR')])
def test_samples_lost_fractions(lost, expected):
    # lost / (samples + lost) against 1e-4 and 1e-2.
    assert level(summary(samples=1_000_000 - lost, lost=lost, gaps=1 if lost else 0)) == expected


def test_nan_out_of_order_and_skipped():
    assert level(summary(nan=1)) == 'WARN'
    assert level(summary(nan=10_001)) == 'ERROR'
    assert level(summary(out_of_order=1)) == 'WARN'
    # skipped / (ok + skipped): 10 of 110 = 0.091 OK, 12 of 112 = 0.107 WARN, 101 of 201 ERROR.
    assert level(summary(skipped=10)) == 'OK'
    assert level(summary(skipped=12)) == 'WARN'
    assert level(summary(skipped=101)) == 'ERROR'


def test_stale_and_worst_item_message():
    s = summary(chunks=0)
    s = AxisSummary(**{**s.__dict__, 'chunks_ok': 0})
    v = evaluate_health(s)
    assert v.level == 'STALE' and 'No complete chunk' in v.message and LEVEL_BYTE[v.level] == 3
    v = evaluate_health(summary(drift_dph=1.0), seconds_since_data=6.0)
    assert v.level == 'STALE' and v.message == 'No data for 6.0 s.'
    assert evaluate_health(summary(), seconds_since_data=4.0).level == 'OK'
    v = evaluate_health(summary(drift_dph=0.03, out_of_order=3))
    assert v.level == 'WARN' and v.message.startswith('Offset drift')  # first of the worst items


def test_custom_thresholds_and_validation():
    th = HealthThresholds(reference_warn_sigma=2.0, reference_error_sigma=30.0)
    s = summary(drift_dph=0.003565 + 3.0 * math.hypot(0.001, 0.001), stderr_dph=0.001)
    assert level(s, reference=REF_SE, thresholds=th) == 'WARN'
    assert level(s, reference=REF_SE) == 'OK'
    with pytest.raises(ParameterError, match='reference_warn_sigma'):
        HealthThresholds(reference_warn_sigma=-1.0)
    with pytest.raises(ParameterError, match='reference_error_sigma'):
        HealthThresholds(reference_warn_sigma=5.0, reference_error_sigma=4.0)


def write_summary(path, bags):
    path.write_text(json.dumps({'bags': bags}))
    return path


STATS = summarise_sequence(np.arange(12.0), np.linspace(0, 1e-3, 12), np.full(12, 2e-6),
                           [0.02, 0.03] + [1.4] * 10, np.full(12, 1.0), order_step=0.01,
                           noise_colour=np.linspace(-0.5, -0.45, 12))
AXIS = {'offset_drift_rad_s2': 1e-9, 'mean_variance_rad2_s2': 2e-6, 'alpha_var_mean': 1.4,
        'alpha_corr_mean': 1.0, 'chunks': 12, 'reference_statistics': reference_dict(STATS)}


def test_load_reference(tmp_path):
    p = write_summary(tmp_path / 's.json', [{'label': 'ref', 'path': '/b/ref',
                                             'axes': {'z': AXIS}}])
    r = load_reference(p, axis='z')
    assert (r.offset_drift_rad_s2, r.mean_variance_rad2_s2, r.alpha_var_mean, r.chunks) == (
        1e-9, 2e-6, 1.4, 12)
    # the robust statistics survive the JSON round trip, mode structure included
    assert (r.bias, r.log_variance, r.alpha_var, r.alpha_corr, r.noise_colour) == (
        STATS.bias_robust, STATS.log_variance_robust, STATS.alpha_var_robust,
        STATS.alpha_corr_robust, STATS.noise_colour_robust)
    assert r.noise_colour.location == pytest.approx(-0.475) and r.noise_colour.count == 12
    assert r.alpha_var.population == 'dominant mode' and r.alpha_var.count == 10
    with pytest.raises(ParameterError, match="axis 'x'"):
        load_reference(p, axis='x')
    per = reference_per_axis(str(p), ('x', 'y', 'z'))
    assert list(per) == ['z']  # axes the reference lacks fall back to absolute limits
    two = write_summary(tmp_path / 't.json', [{'label': 'a', 'path': 'a', 'axes': {'z': AXIS}},
                                              {'label': 'b', 'path': 'b', 'axes': {'z': AXIS}}])
    with pytest.raises(ParameterError, match='holds 2 bags'):
        load_reference(two)
    assert load_reference(two, bag='b').source.endswith(':b:z')
    # a reference that cannot be read is an unreadable input (exit code 3), as in every tool
    with pytest.raises(InputError, match='cannot be read'):
        load_reference(tmp_path / 'missing.json')
    (tmp_path / 'bad.json').write_text('{')
    with pytest.raises(InputError, match='not JSON'):
        load_reference(tmp_path / 'bad.json')
    broken = write_summary(tmp_path / 'u.json', [{'label': 'a', 'axes': {'z': {
        'chunks': 1, 'reference_statistics': AXIS['reference_statistics']}}}])
    with pytest.raises(InputError, match='missing or bad field'):
        load_reference(broken)
    # one chunk has no offset drift: not a reference, and the message says what to change
    short = write_summary(tmp_path / 'v.json', [{'label': 'a', 'axes': {'z': {
        **AXIS, 'chunks': 1, 'offset_drift_rad_s2': None}}}])
    with pytest.raises(ParameterError, match=r'1 chunk\(s\), too few') as err:
        load_reference(short)
    assert err.value.parameters == ('chunk_size',)


def test_older_reference_summary_is_refused_with_one_line(tmp_path):
    old = {k: v for k, v in AXIS.items() if k != 'reference_statistics'}
    p = write_summary(tmp_path / 'old.json', [{'label': 'ref', 'path': '/b/ref',
                                               'axes': {'z': old}}])
    with pytest.raises(InputError, match='regenerate it with this version') as err:
        load_reference(p, axis='z')
    assert '\n' not in str(err.value) and '/b/ref' in str(err.value)
    with pytest.raises(InputError, match='regenerate'):
        reference_per_axis(str(p), ('x', 'y', 'z'))


def test_drift_significance_uses_student_t_quantile():
    # closed forms: df = 1 is a Cauchy distribution, |t| > tan(pi/2 (1 - p)); large df tends to the
    # normal
    p = math.erfc(3.0 / math.sqrt(2.0))
    assert drift_t_threshold(3.0, 3) == pytest.approx(math.tan(math.pi / 2 * (1 - p)), rel=1e-9)
    assert drift_t_threshold(3.0, 100_000) == pytest.approx(3.0, rel=1e-3)
    assert drift_t_threshold(3.0, 2) == math.inf
    # 10 sigma keeps its digits (1 - p / 2 would round to 1): the normal limit and a finite t
    assert drift_t_threshold(10.0, 10**7) == pytest.approx(10.0, rel=1e-4)
    assert 10.0 < drift_t_threshold(10.0, 100) < 20.0


@pytest.mark.slow  # 20,000 Monte Carlo fits, one at a time (7-15 s)
def test_no_drift_false_alarm_on_white_noise_with_few_chunks():
    """Monte Carlo of the significance rule alone: white chunk biases, 4 chunks, 3-sigma level."""
    from gyro_noise_ros.core.chunks import offset_drift
    rng = np.random.default_rng(0)
    t = np.arange(4) * 1.5
    fires = 0
    for _ in range(20000):
        d = offset_drift(t, rng.standard_normal(4))
        fires += abs(d.slope) / d.stderr > drift_t_threshold(3.0, 4)
    # the level is p = 0.0027: 54 expected of 20,000 (sd ~7); a plain 3-sigma test fires ~1900
    # times
    assert fires < 100


def test_axis_status_adds_refused_batches_and_is_error_only_while_data_is_refused():
    verdict = evaluate_health(summary())
    values = [(k, v) for k, v, _ in verdict.items]
    plain = axis_status(verdict, values)
    assert (plain.level, plain.message, plain.values) == (verdict.level, verdict.message,
                                                          tuple(values))
    refused = axis_status(verdict, values, rejected_batches=2, last_rejection='bad stamps',
                          rejecting=True, seconds_since_data=1.0)
    assert (refused.level, refused.message) == ('ERROR', 'Samples rejected: bad stamps.')
    assert refused.values[-2:] == (('Batches rejected', '2'), ('Last rejection', 'bad stamps'))
    # silent for longer than stale_after_s (5 s): the verdict's own level, the count stays
    silent = axis_status(verdict, values, rejected_batches=2, last_rejection='bad stamps',
                         rejecting=True, seconds_since_data=5.5)
    assert silent.level == verdict.level and silent.values == refused.values
    accepted = axis_status(verdict, values, rejected_batches=2, last_rejection='bad stamps')
    assert accepted.level == 'OK' and accepted.level_byte == 0


def test_axis_status_is_at_least_warn_with_more_than_one_publisher():
    ok = evaluate_health(summary())
    values = [(k, v) for k, v, _ in ok.items]
    assert axis_status(ok, values, publishers=1).level == 'OK'
    mixed = axis_status(ok, values, publishers=2)
    assert (mixed.level, mixed.message) == ('WARN', '2 publishers of the data: their samples '
                                            'are mixed.')
    assert mixed.values == tuple(values)
    # A WARN verdict stays WARN and keeps its own message; worse verdicts are left alone.
    warn = evaluate_health(summary(drift_dph=0.03, out_of_order=3))
    assert axis_status(warn, values, publishers=2).message == warn.message
    for verdict in (evaluate_health(summary(drift_dph=1.0, stderr_dph=0.3)),
                    evaluate_health(summary(), seconds_since_data=6.0)):
        status = axis_status(verdict, values, publishers=3)
        assert (status.level, status.message) == (verdict.level, verdict.message)
    # Refused batches while data arrives: ERROR over the publishers' WARN.
    refused = axis_status(ok, values, publishers=2, rejected_batches=1, last_rejection='bad',
                          rejecting=True, seconds_since_data=0.1)
    assert (refused.level, refused.message) == ('ERROR', 'Samples rejected: bad.')
