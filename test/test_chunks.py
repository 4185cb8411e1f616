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

"""Chunker, chunk moments and sequence summaries (paper 000 Tables 3-6)."""

from gyro_noise_ros.core.chunks import (chunk_moments, Chunker, offset_drift, robust_location,
                                        summarise_sequence)
from gyro_noise_ros.errors import InputDataError, ParameterError
import numpy as np
import pytest


def test_chunker_splits_any_batching_exactly():
    rng = np.random.default_rng(0)
    data = rng.standard_normal(10_357)
    chunker = Chunker(1000)
    chunks = []
    pos = 0
    while pos < data.size:
        step = int(rng.integers(0, 2500))
        chunks += chunker.push(data[pos:pos + step])
        pos += step
    assert len(chunks) == 10
    np.testing.assert_array_equal(np.concatenate(chunks), data[:10_000])
    np.testing.assert_array_equal(chunker.tail, data[10_000:])
    assert chunker.tail_samples == 357 and chunker.samples_in == data.size


def test_chunker_two_dimensional_and_copies():
    chunker = Chunker(3)
    buf = np.arange(12.0).reshape(6, 2)
    out = chunker.push(buf)
    buf[:] = -1
    assert [c.tolist() for c in out] == [[[0, 1], [2, 3], [4, 5]], [[6, 7], [8, 9], [10, 11]]]
    with pytest.raises(InputDataError):
        chunker.push(np.zeros((2, 3)))
    with pytest.raises(ParameterError):
        Chunker(1)


def test_chunk_moments():
    m = chunk_moments([1.0, 2.0, 3.0, 4.0])
    assert m.bias == 2.5 and m.variance == pytest.approx(5 / 3)
    with pytest.raises(InputDataError):
        chunk_moments([1.0, np.nan, 2.0])


def test_offset_drift_recovers_line_and_stderr():
    t = np.arange(100) * 1.5
    rng = np.random.default_rng(1)
    b = 0.3 + 2e-4 * t + rng.normal(0, 1e-3, t.size)
    d = offset_drift(t, b)
    # the OLS slope standard error is 1e-3 / sqrt(sum (t - mean t)^2) = 2.3e-6; 5e-6 is ~2 of
    # them...
    assert d.slope == pytest.approx(2e-4, abs=1e-5)
    assert d.stderr == pytest.approx(1e-3 / np.sqrt(np.sum((t - t.mean()) ** 2)), rel=0.3)
    assert d.magnitude == abs(d.slope)
    exact = offset_drift([0.0, 1.0, 2.0], [1.0, 0.5, 0.0])
    assert exact.slope == -0.5 and exact.intercept == 1.0 and exact.stderr == 0.0
    assert np.isnan(offset_drift([1.0], [2.0]).slope)


def test_summarise_sequence_tables():
    s = summarise_sequence([0, 1, 2, 3], [1.0, 1.1, 1.2, 1.3], [2.0, 4.0, 2.0, 4.0],
                           [1.4, 1.4, 1.39, 1.41], [1.0, np.nan, 0.9, 1.1], tail_samples=12,
                           ties_var=1)
    assert s.chunks == 4 and s.tail_samples == 12 and s.ties_var == 1
    assert s.mean_variance == 3.0 and s.variance_of_variances == pytest.approx(4 / 3)
    assert s.alpha_var_mean == pytest.approx(
        1.4) and s.alpha_var_variance == pytest.approx(2e-4 / 3)
    assert s.alpha_corr_mean == pytest.approx(1.0) and s.alpha_corr_variance == pytest.approx(0.01)
    assert s.drift.slope == pytest.approx(0.1)


def test_robust_location_is_normal_consistent_and_ignores_outliers():
    rng = np.random.default_rng(30)
    # Spread of 100 normal values: 2000 repeats give its mean within 1 % of sigma (the estimator
    # has ~8 % scatter per record, so the mean of 2000 is known to 0.2 %; its small-sample bias is
    # +0.7 %).
    spreads = [robust_location(rng.normal(5.0, 2.0, 100)).spread for _ in range(2000)]
    assert np.mean(spreads) == pytest.approx(2.0, rel=0.01)
    x = rng.normal(0.0, 1.0, 100)
    clean = robust_location(x)
    x[:4] = 1e6  # 4 wild chunks (under the 5 % trimmed on each side) move neither number much
    dirty = robust_location(x)
    assert abs(dirty.location - clean.location) < 0.1 and dirty.spread < 1.3 * clean.spread
    assert (dirty.count, dirty.total, dirty.population) == (100, 100, 'all chunks')


def test_robust_location_dominant_mode_floor_and_degenerate_input():
    orders = np.array([0.02, 0.03, 0.01] + [1.04] * 50 + [1.05] * 47)
    loc = robust_location(orders, resolution=0.01, modes=True)
    assert loc.population == 'dominant mode' and loc.count == 97 and loc.total == 100
    assert loc.location == pytest.approx(1.04) and loc.modes[0][1] == 3
    # two equal basins: the higher order, as for exact ties of the identification
    tie = robust_location([0.02, 0.03, 0.02, 1.01, 1.02, 1.01], modes=True)
    assert tie.location == pytest.approx(1.01)
    # identical values: the grid's own spread, step / sqrt(12), not zero
    assert robust_location([1.5] * 20, resolution=0.01).spread == pytest.approx(0.01 / 12 ** 0.5)
    assert robust_location([1.5] * 20).spread == 0.0
    assert np.isnan(robust_location([np.nan, np.inf]).location)
    one = robust_location([0.3])
    assert one.location == 0.3 and np.isnan(one.spread) and one.count == 1
    # small records are not trimmed: 3 values give their plain standard deviation
    assert robust_location([1.0, 2.0, 3.0]).spread == pytest.approx(1.0)
