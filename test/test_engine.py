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
Tests of the streaming engine (gyro_noise_ros.core.engine).

Chunking, gaps, NaN, tail, equality with the core.
"""

import math
import pickle

from gyro_noise_ros.core.chunks import (chunk_moments, noise_colour, RobustLocation,
                                        summarise_sequence)
from gyro_noise_ros.core.engine import analyze_chunk, EngineConfig, NoiseEngine
from gyro_noise_ros.core.fractional import make_grid, OrderIdentifier
from gyro_noise_ros.core.health import HealthThresholds, ReferenceStats
from gyro_noise_ros.core.results import AxisSummary, ChunkResult, rad_s2_to_deg_s_per_h
from gyro_noise_ros.core.simulate import simulate_fractional_noise
from gyro_noise_ros.errors import InputDataError, ParameterError
import numpy as np
import pytest

# Small chunks, short memory and a coarse grid keep each identification at ~1 ms; the logic under
# test does not depend on the sizes.
SIZE = 600
MEMORY = 50
GRID = make_grid(0.0, 2.0, 0.1)
PERIOD_NS = 150_150  # 6660 Hz
T0 = 1_700_000_000_000_000_000


def config(**kw):
    base = {'chunk_size': SIZE, 'memory': MEMORY, 'alphas': GRID, 'allan': False}
    base.update(kw)
    return EngineConfig(**base)


def data(n, seed=0):
    rng = np.random.default_rng(seed)
    gyro = np.stack([simulate_fractional_noise(n, a, -0.3, 1e-3, rng=rng, memory=MEMORY)
                     for a in (0.8, 1.2, 1.4)], axis=1)
    stamps = T0 + np.arange(n, dtype=np.int64) * PERIOD_NS
    return stamps, gyro


def run(engine, stamps, gyro, batch=1000, temperature=None):
    jobs = []
    for i in range(0, len(stamps), batch):
        t = None if temperature is None else temperature[i:i + batch]
        jobs += engine.ingest(stamps[i:i + batch], gyro[i:i + batch], t)
    jobs += engine.flush()
    results = [analyze_chunk(j) for j in jobs]
    for r in results:
        engine.record(r)
    return jobs, results


def test_per_chunk_numbers_equal_the_core_called_directly():
    stamps, gyro = data(3 * SIZE + 123)
    engine = NoiseEngine(config())
    jobs, results = run(engine, stamps, gyro, batch=257)
    assert [(r.chunk, r.axis) for r in results] == [(c, a) for c in range(3) for a in 'xyz']
    ident = OrderIdentifier(SIZE, alphas=GRID, memory=MEMORY)
    for r in results:
        k = 'xyz'.index(r.axis)
        chunk = gyro[r.chunk * SIZE:(r.chunk + 1) * SIZE, k]
        direct = ident(chunk)
        moments = chunk_moments(chunk)
        # Same function on the same float64 data: bit-identical, not just close.
        assert r.bias_rad_s == moments.bias and r.variance_rad2_s2 == moments.variance
        assert (r.alpha_var, r.f_var, r.var_min) == (direct.alpha_var, direct.f_var,
                                                     direct.var_min)
        assert (r.alpha_corr, r.f_corr, r.j_min) == (direct.alpha_corr, direct.f_corr,
                                                     direct.j_min)
        assert r.noise_colour == noise_colour(chunk) and math.isfinite(r.noise_colour)
        assert r.status == 'ok' and r.samples == SIZE and r.samples_lost == 0
        assert r.stamp_start_ns == stamps[r.chunk * SIZE]
        assert r.t_start_s == pytest.approx(r.chunk * SIZE * PERIOD_NS / 1e9, abs=1e-12)
        assert r.t_mid_s == pytest.approx((r.chunk * SIZE + (SIZE - 1) / 2) * PERIOD_NS / 1e9,
                                          abs=1e-12)
    counts = engine.counts()
    assert counts.chunks == 3 and counts.tail_samples == 123 and counts.samples == len(stamps)
    assert counts.rate_hz == pytest.approx(1e9 / PERIOD_NS)
    s = engine.summary()['y']
    ys = [r for r in results if r.axis == 'y']
    expected = summarise_sequence([r.t_mid_s for r in ys], [r.bias_rad_s for r in ys],
                                  [r.variance_rad2_s2 for r in ys], [r.alpha_var for r in ys],
                                  [r.alpha_corr for r in ys], tail_samples=123,
                                  order_step=0.1, noise_colour=[r.noise_colour for r in ys])
    assert s.sequence == expected
    assert s.sequence.tail_samples == 123
    assert s.offset_drift_deg_s_per_h == rad_s2_to_deg_s_per_h(expected.drift.slope)


def test_batch_boundaries_do_not_change_results():
    stamps, gyro = data(4 * SIZE + 10, seed=1)
    outs = []
    for batch in (1, 97, SIZE, 10_000):
        engine = NoiseEngine(config(axes=('z',)))
        _, results = run(engine, stamps, gyro, batch=batch)
        outs.append(results)
    assert all(o == outs[0] for o in outs[1:])
    assert len(outs[0]) == 4


def test_results_survive_pickling_for_worker_processes():
    stamps, gyro = data(SIZE, seed=2)
    engine = NoiseEngine(config(axes=('x',)))
    (job,) = engine.ingest(stamps, gyro) + engine.flush()
    job2 = pickle.loads(pickle.dumps(job))
    result = analyze_chunk(job2, curves=True)
    assert pickle.loads(pickle.dumps(result)) == analyze_chunk(job)
    assert result.var_curve.shape == GRID.shape and result.j_curve.shape == GRID.shape
    assert np.min(result.var_curve) == result.var_min


def with_gap(n, at, missing):
    """Return stamps with ``missing`` samples removed after ``at`` (step: missing + 1 periods)."""
    stamps, gyro = data(n + missing, seed=3)
    keep = np.r_[0:at + 1, at + 1 + missing:n + missing]
    return stamps[keep], gyro[keep]


def test_gap_policy_flag_keeps_and_counts():
    stamps, gyro = with_gap(3 * SIZE, at=SIZE + 100, missing=7)
    engine = NoiseEngine(config(axes=('x',), gap_policy='flag'))
    _, results = run(engine, stamps, gyro)
    assert [r.samples_lost for r in results] == [0, 7, 0]
    assert [r.gaps for r in results] == [0, 1, 0]
    assert all(r.status == 'ok' for r in results)
    c = engine.counts()
    assert (c.samples_lost, c.gaps, c.chunks, c.discarded_samples) == (7, 1, 3, 0)
    assert engine.summary()['x'].sequence.chunks == 3


def test_gap_factor_threshold():
    # One missing sample = a step of 2 periods: a gap at gap_factor 1.5, not at 2.5.
    stamps, gyro = with_gap(2 * SIZE, at=10, missing=1)
    for factor, lost in ((1.5, 1), (2.5, 0)):
        engine = NoiseEngine(config(axes=('x',), gap_factor=factor))
        run(engine, stamps, gyro)
        assert engine.counts().samples_lost == lost


def test_clock_corrections_are_not_lost_samples():
    # The demo's driver stamps (device clock mapped to host time) showed steps of 0.45 and 1.53
    # periods, 0.32 and 1.68, 0 and 2.17: the map re-anchoring, paid back within the record. The
    # grid never moves, so nothing is lost; one real loss (a step of exactly 2 periods) is.
    rng = np.random.default_rng(3)
    n = 4 * SIZE
    grid = np.arange(n, dtype=np.float64)
    offset = np.zeros(n)
    for start, stop, shift in ((700, 780, -0.55), (1300, 1390, -0.68), (1900, 1990, -0.83)):
        offset[start:stop] = shift  # stamps early by a fraction of a period, then back
    t = grid + offset + rng.normal(0.0, 0.002, n)  # 0.3 us jitter at 6.66 kHz
    stamps = T0 + np.rint(t * PERIOD_NS).astype(np.int64)
    keep = np.ones(n, dtype=bool)
    keep[2200] = False  # one lost sample
    _, gyro = data(n)
    engine = NoiseEngine(config(axes=('x',), rate_hz=1e9 / PERIOD_NS))
    run(engine, stamps[keep], gyro[keep])
    c = engine.counts()
    assert (c.samples_lost, c.gaps) == (1, 1)
    # Three long steps of 1.55, 1.68 and 1.83 periods: clock steps. (A correction of exactly a
    # whole period cannot be told from a loss by its steps; the run's deficit in core.timebase
    # still reports no loss then.)
    assert c.clock_steps == 3


def test_gap_policy_split_discards_the_partial_chunk():
    stamps, gyro = with_gap(3 * SIZE, at=SIZE + 100, missing=7)
    engine = NoiseEngine(config(axes=('x',), gap_policy='split'))
    jobs, results = run(engine, stamps, gyro)
    # Chunk 0 complete; 101 samples before the gap thrown away; then chunk 1 starts right after the
    # gap.
    assert len(results) == 2
    assert all(r.samples_lost == 0 and r.gaps == 0 and r.status == 'ok' for r in results)
    assert results[1].stamp_start_ns == stamps[SIZE + 101]
    np.testing.assert_array_equal(jobs[1].samples, gyro[SIZE + 101:2 * SIZE + 101, 0])
    c = engine.counts()
    assert (c.discarded_samples, c.discarded_partials, c.samples_lost, c.gaps) == (101, 1, 7, 1)
    assert c.tail_samples == 3 * SIZE - (2 * SIZE + 101)


def test_gap_policy_drop_reports_and_excludes():
    stamps, gyro = with_gap(3 * SIZE, at=SIZE + 100, missing=7)
    engine = NoiseEngine(config(axes=('x',), gap_policy='drop'))
    _, results = run(engine, stamps, gyro)
    assert [r.status for r in results] == ['ok', 'dropped', 'ok']
    assert np.isnan(results[1].alpha_var) and results[1].samples_lost == 7
    s = engine.summary()['x']
    assert s.sequence.chunks == 2 and s.chunks_dropped == 1


def test_gap_on_a_chunk_boundary_is_counted_but_not_inside_a_chunk():
    stamps, gyro = with_gap(2 * SIZE, at=SIZE - 1, missing=4)
    engine = NoiseEngine(config(axes=('x',), gap_policy='drop'))
    _, results = run(engine, stamps, gyro)
    assert [r.status for r in results] == ['ok', 'ok']
    assert engine.counts().samples_lost == 4


def test_nan_samples_are_counted_per_axis_and_never_crash():
    stamps, gyro = data(3 * SIZE, seed=4)
    gyro[SIZE + 5, 1] = np.nan
    gyro[SIZE + 9, 1] = np.inf
    engine = NoiseEngine(config())
    _, results = run(engine, stamps, gyro)
    by = {(r.chunk, r.axis): r for r in results}
    assert by[(1, 'y')].status == 'nan' and by[(1, 'y')].nan_samples == 2
    assert np.isnan(by[(1, 'y')].bias_rad_s) and np.isnan(by[(1, 'y')].alpha_corr)
    assert by[(1, 'x')].status == 'ok' and by[(1, 'z')].status == 'ok'
    s = engine.summary()
    assert s['y'].nan_samples == 2 and s['y'].chunks_nan == 1 and s['y'].sequence.chunks == 2
    assert s['x'].nan_samples == 0 and s['x'].sequence.chunks == 3
    assert np.isfinite(s['y'].sequence.mean_variance)


def test_constant_chunk_fails_cleanly():
    stamps, _ = data(SIZE)
    gyro = np.zeros((SIZE, 3))
    engine = NoiseEngine(config(axes=('z',)))
    _, (r,) = run(engine, stamps, gyro)
    assert r.status == 'failed' and 'constant' in r.message
    assert engine.summary()['z'].chunks_failed == 1


def test_out_of_order_stamps_are_counted_not_reordered():
    stamps, gyro = data(2 * SIZE, seed=5)
    stamps = stamps.copy()
    stamps[[100, 101]] = stamps[[101, 100]]  # one regression (101 -> 100), steps stay < gap
    stamps[300] = stamps[299]  # a repeated stamp: 299 and 300 stamped once, like one packet
    engine = NoiseEngine(config(axes=('x',)))
    jobs, _ = run(engine, stamps, gyro, batch=100)  # the swap straddles a batch boundary
    # Only the regression is out of order; the equal stamp is a normal time base.
    assert (engine.counts().out_of_order, engine.counts().equal_stamps) == (1, 1)
    # The swap leaves a 2-period step from the latest stamp: one sample counted lost (engine doc).
    # The 2-period step after the repeated stamp is paid by the sample sharing its stamp.
    assert (engine.counts().samples_lost, engine.counts().gaps) == (1, 1)
    np.testing.assert_array_equal(jobs[0].samples, gyro[:SIZE, 0])


def test_rate_is_estimated_or_configured():
    stamps, gyro = data(SIZE + 50, seed=6)
    engine = NoiseEngine(config(axes=('x',)))
    assert engine.ingest(stamps[:50], gyro[:50]) == []
    assert np.isnan(engine.counts().rate_hz)  # still held back for the estimate
    # Held until RATE_ESTIMATE_SAMPLES (1025) stamps or flush().
    assert engine.ingest(stamps[50:], gyro[50:]) == []
    assert len(engine.flush()) == 1
    engine = NoiseEngine(config(axes=('x',), rate_hz=1000.0))
    run(engine, stamps, gyro)
    # At a configured 1 kHz the 6.66 kHz stamps are 0.15 periods apart: never a gap.
    assert engine.counts().rate_hz == 1000.0 and engine.counts().samples_lost == 0
    # A short stream is released by flush() and stays in the tail.
    engine = NoiseEngine(config(axes=('x',)))
    engine.ingest(stamps[:20], gyro[:20])
    assert engine.flush() == [] and engine.counts().tail_samples == 20


def test_temperature_mean_per_chunk():
    stamps, gyro = data(2 * SIZE, seed=7)
    temp = np.linspace(20.0, 30.0, 2 * SIZE)
    temp[3] = np.nan
    engine = NoiseEngine(config(axes=('x',)))
    _, results = run(engine, stamps, gyro, temperature=temp)
    first = temp[:SIZE]
    assert results[0].temperature_c == pytest.approx(np.nanmean(first), rel=1e-12)
    assert results[1].temperature_c == pytest.approx(temp[SIZE:].mean(), rel=1e-12)
    engine = NoiseEngine(config(axes=('x',)))
    _, results = run(engine, stamps, gyro)
    assert np.isnan(results[0].temperature_c)


def test_skip_is_recorded_and_history_is_bounded():
    stamps, gyro = data(5 * SIZE, seed=8)
    engine = NoiseEngine(config(axes=('x',), history_chunks=2))
    jobs = engine.ingest(stamps, gyro)
    skipped = engine.skip(jobs[0], 'analysis fell behind')
    assert isinstance(skipped, ChunkResult) and skipped.status == 'skipped'
    for j in jobs[1:]:
        engine.record(analyze_chunk(j))
    s = engine.summary()['x']
    assert s.chunks_skipped == 1 and s.chunks_ok == 4
    assert s.sequence.chunks == 2  # only the last two kept for the statistics


def test_health_verdicts_come_from_the_engine():
    stamps, gyro = data(4 * SIZE, seed=9)
    ref = ReferenceStats(offset_drift_rad_s2=1e-12, mean_variance_rad2_s2=1.0, alpha_var_mean=0.0,
                         alpha_corr_mean=0.0, log_variance=RobustLocation(0.0, 0.1, 100, 100))
    engine = NoiseEngine(config(axes=('x',)), reference=ref,
                         thresholds=HealthThresholds(reference_min_chunks=3))
    assert engine.health()['x'].level == 'STALE'
    run(engine, stamps, gyro)
    verdict = engine.health()['x']
    # The variance (~1e-5 (rad/s)^2 here) is far below the reference's 1.0 (log 0, chunk spread
    # 0.1 in log units): ERROR on variance at least.
    assert verdict.level == 'ERROR'
    assert {k: lv for k, _, lv in verdict.items}['Variance / reference'] == 'ERROR'
    assert engine.health(seconds_since_data=60.0)['x'].level == 'STALE'


def test_bad_input_and_options():
    engine = NoiseEngine(config(axes=('x',)))
    with pytest.raises(InputDataError, match='gyro must have shape'):
        engine.ingest(np.arange(5), np.zeros((5, 2)))
    with pytest.raises(InputDataError, match='integer nanoseconds'):
        engine.ingest(np.arange(5.0), np.zeros((5, 3)))
    assert engine.ingest(np.zeros(0, np.int64), np.zeros((0, 3))) == []
    with pytest.raises(ParameterError, match='gap_policy'):
        config(gap_policy='ignore')
    with pytest.raises(ParameterError, match='axes'):
        config(axes=('q',))
    with pytest.raises(ParameterError, match='chunk_size'):
        config(chunk_size=MEMORY)
    with pytest.raises(ParameterError, match='gap_factor'):
        config(gap_factor=1.0)
    engine = NoiseEngine(config(axes=('x',)))
    with pytest.raises(InputDataError, match='sample rate'):
        engine.ingest(np.zeros(2000, np.int64), np.zeros((2000, 3)))


def test_summary_is_an_axis_summary_with_counts():
    stamps, gyro = data(2 * SIZE + 1, seed=10)
    engine = NoiseEngine(config(axes=('z', 'x')))
    run(engine, stamps, gyro)
    s = engine.summary()
    assert list(s) == ['z', 'x'] and isinstance(s['z'], AxisSummary)
    assert s['z'].stream.tail_samples == 1 and s['z'].stream.duration_s == pytest.approx(
        2 * SIZE * PERIOD_NS / 1e9)


def test_result_equality_treats_nan_as_equal_and_sees_any_difference():
    stamps, gyro = data(SIZE, seed=11)
    engine = NoiseEngine(config(axes=('x',)))
    (job,) = engine.ingest(stamps, gyro) + engine.flush()
    a = analyze_chunk(job)
    b = pickle.loads(pickle.dumps(a))
    assert np.isnan(a.temperature_c) and a == b
    from dataclasses import replace
    assert a != replace(a, alpha_var=a.alpha_var + 0.01)
    assert a != replace(a, temperature_c=20.0)


def test_allan_deviation_of_the_run_matches_the_batch_estimator():
    from gyro_noise_ros.core.allan import allan_deviation

    stamps, gyro = data(3 * SIZE, seed=12)
    gyro[7, 2] = np.nan  # left out of the Allan deviation, counted elsewhere
    engine = NoiseEngine(config(axes=('x', 'z'), allan=True))
    run(engine, stamps, gyro, batch=333)
    s = engine.summary()
    for axis, col in (('x', 0), ('z', 2)):
        finite = gyro[:, col][np.isfinite(gyro[:, col])]
        ref = allan_deviation(finite, engine.counts().rate_hz, taus=engine.config.allan_taus)
        # The accumulator removes the first batch's mean, the batch estimator the global mean: the
        # module documents agreement to ~1e-12 relative; 1e-9 leaves room for the summation order.
        np.testing.assert_allclose(s[axis].allan.adev, ref.adev, rtol=1e-9)
        assert s[axis].noise_terms is not None
    assert engine.allan_status == ''
    assert NoiseEngine(config(axes=('x',))).summary()['x'].allan is None  # allan off in config()
