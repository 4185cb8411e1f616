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

import json
import math

from gyro_noise_ros.core.chunks import DriftEstimate, SequenceSummary
from gyro_noise_ros.core.engine import AxisSummary, StreamCounts
from gyro_noise_ros.core.health import (
    evaluate_health,
    HealthThresholds,
    LEVEL_BYTE,
    load_reference,
    reference_per_axis,
    ReferenceStats,
)
from gyro_noise_ros.errors import ParameterError
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


@pytest.mark.parametrize(
    'ratio, expected', [(4.99, 'OK'), (5.01, 'WARN'), (14.99, 'WARN'), (15.01, 'ERROR')])
def test_drift_ratio_thresholds(ratio, expected):
    # the sign does not matter
    v = evaluate_health(summary(drift_dph=-0.003565 * ratio), reference=REF)
    assert v.level == expected
    assert item_level(v, 'Offset drift / reference') == expected
    if expected != 'OK':
        assert 'offset drift' in v.message.lower() and v.message.endswith('.')


def test_paper_table3_sequences_against_sequence_ref():
    # Table 3 of paper 000 judged against its sequence ref with the default thresholds (5x, 15x).
    table3 = {'H1': 0.064995, 'H2': 0.072974, 'H3': 0.047426, 'H4': 0.035417, 'H5': 0.021916,
              'AH1': 0.013351, 'AH2': 0.009225, 'AH3': 0.007388, 'LAH': 0.004292}
    levels = {k: level(summary(drift_dph=v), reference=REF) for k, v in table3.items()}
    assert levels == {'H1': 'ERROR', 'H2': 'ERROR', 'H3': 'WARN', 'H4': 'WARN', 'H5': 'WARN',
                      'AH1': 'OK', 'AH2': 'OK', 'AH3': 'OK', 'LAH': 'OK'}


@pytest.mark.parametrize('drift, expected', [(0.0199, 'OK'), (0.0201, 'WARN'), (0.0499, 'WARN'),
                                             (0.0501, 'ERROR')])
def test_absolute_drift_thresholds_without_reference(drift, expected):
    assert level(summary(drift_dph=drift)) == expected


def test_insignificant_or_early_drift_is_not_judged():
    # |slope| = 2 stderr < drift_min_sigma = 3: the slope is noise, whatever its size.
    assert level(summary(drift_dph=1.0, stderr_dph=0.5), reference=REF) == 'OK'
    assert level(summary(drift_dph=1.0, stderr_dph=0.3), reference=REF) == 'ERROR'
    assert level(summary(drift_dph=1.0, chunks=2)) == 'OK'  # below min_chunks


@pytest.mark.parametrize('delta, expected', [(0.049, 'OK'), (0.051, 'WARN'), (0.099, 'WARN'),
                                             (0.101, 'ERROR')])
def test_order_tolerance_variance_method(delta, expected):
    v = evaluate_health(summary(alpha_var=1.4 + delta), reference=REF)
    assert item_level(v, 'Order deviation, variance method') == expected and v.level == expected


@pytest.mark.parametrize(
    'delta, expected', [(0.24, 'OK'), (0.26, 'WARN'), (0.49, 'WARN'), (0.51, 'ERROR')])
def test_order_tolerance_correlation_method(delta, expected):
    assert level(summary(alpha_corr=1.0 - delta), reference=REF) == expected


@pytest.mark.parametrize(
    'ratio, expected', [(1.49, 'OK'), (1.51, 'WARN'), (0.51, 'OK'), (0.49, 'WARN'), (1.99, 'WARN'),
                        (2.01, 'ERROR'), (0.0, 'WARN')])
def test_variance_ratio_tolerance(ratio, expected):
    # The ERROR band is |ratio - 1| > 1.0, so a variance collapse to 0 is WARN-level at most by
    # this item.
    assert level(summary(variance=1e-6 * ratio), reference=REF) == expected


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
    th = HealthThresholds(drift_ratio_warn=2.0, drift_ratio_error=3.0)
    assert level(summary(drift_dph=0.003565 * 2.5), reference=REF, thresholds=th) == 'WARN'
    with pytest.raises(ParameterError, match='drift_ratio_error'):
        HealthThresholds(drift_ratio_warn=10.0, drift_ratio_error=5.0)
    with pytest.raises(ParameterError, match='alpha_var_tolerance'):
        HealthThresholds(alpha_var_tolerance=-1.0)


def write_summary(path, bags):
    path.write_text(json.dumps({'bags': bags}))
    return path


AXIS = {'offset_drift_rad_s2': 1e-9, 'mean_variance_rad2_s2': 2e-6, 'alpha_var_mean': 1.4,
        'alpha_corr_mean': 1.0, 'chunks': 12}


def test_load_reference(tmp_path):
    p = write_summary(tmp_path / 's.json', [{'label': 'ref', 'path': '/b/ref',
                                             'axes': {'z': AXIS}}])
    r = load_reference(p, axis='z')
    assert (r.offset_drift_rad_s2, r.mean_variance_rad2_s2, r.alpha_var_mean, r.chunks) == (
        1e-9, 2e-6, 1.4, 12)
    with pytest.raises(ParameterError, match="axis 'x'"):
        load_reference(p, axis='x')
    per = reference_per_axis(str(p), ('x', 'y', 'z'))
    assert list(per) == ['z']  # axes the reference lacks fall back to absolute limits
    two = write_summary(tmp_path / 't.json', [{'label': 'a', 'path': 'a', 'axes': {'z': AXIS}},
                                              {'label': 'b', 'path': 'b', 'axes': {'z': AXIS}}])
    with pytest.raises(ParameterError, match='holds 2 bags'):
        load_reference(two)
    assert load_reference(two, bag='b').source.endswith(':b:z')
    with pytest.raises(ParameterError, match='cannot be read'):
        load_reference(tmp_path / 'missing.json')
    (tmp_path / 'bad.json').write_text('{')
    with pytest.raises(ParameterError, match='not JSON'):
        load_reference(tmp_path / 'bad.json')
    broken = write_summary(tmp_path / 'u.json', [{'label': 'a', 'axes': {'z': {'chunks': 1}}}])
    with pytest.raises(ParameterError, match='missing or bad field'):
        load_reference(broken)


def test_drift_significance_uses_student_t_quantile():
    from gyro_noise_ros.core.health import drift_t_threshold

    # closed forms: df = 1 is a Cauchy distribution, |t| > tan(pi/2 (1 - p)); large df tends to the
    # normal
    p = math.erfc(3.0 / math.sqrt(2.0))
    assert drift_t_threshold(3.0, 3) == pytest.approx(math.tan(math.pi / 2 * (1 - p)), rel=1e-9)
    assert drift_t_threshold(3.0, 100_000) == pytest.approx(3.0, rel=1e-3)
    assert drift_t_threshold(3.0, 2) == math.inf


def test_no_drift_false_alarm_on_white_noise_with_few_chunks():
    """Monte Carlo of the significance rule alone: white chunk biases, 4 chunks, 3-sigma level."""
    from gyro_noise_ros.core.chunks import offset_drift
    from gyro_noise_ros.core.health import drift_t_threshold
    rng = np.random.default_rng(0)
    t = np.arange(4) * 1.5
    fires = 0
    for _ in range(20000):
        d = offset_drift(t, rng.standard_normal(4))
        fires += abs(d.slope) / d.stderr > drift_t_threshold(3.0, 4)
    # the level is p = 0.0027: 54 expected of 20,000 (sd ~7); a plain 3-sigma test fires ~1900
    # times
    assert fires < 100
