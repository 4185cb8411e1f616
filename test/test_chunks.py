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

import math

from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.chunks import (chunk_moments, Chunker, drift_stderr, noise_colour,
                                        NOISE_COLOUR_FACTORS,
                                        offset_drift, robust_location, summarise_sequence)
from gyro_noise_ros.core.fractional import gl_coefficients, gl_difference
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


def _drift_stderr_twin(t, b):
    """drift_stderr written as its docstring states it: the n x n sum over the variogram."""
    tc = t - t.mean()
    sxx = tc @ tc
    w = tc / sxx
    resid = b - b.mean() - (w @ (b - b.mean())) * tc
    u = tc * resid
    n, lags = t.size, int(np.ceil(t.size ** (1 / 3)))
    s = u @ u + sum(2 * (1 - m / (lags + 1)) * (u[m:] @ u[:-m])
                    for m in range(1, min(lags, n - 1) + 1))
    nw = np.sqrt(max(s, 0.0) * n / (n - 2)) / sxx
    half = max(1, n // 2)
    d = [np.mean((resid[m:] - resid[:-m]) ** 2) for m in range(1, half + 1)]
    d = np.concatenate(([0.0], d, np.full(n - 1 - half, d[-1])))
    var = -0.5 * sum(w[j] * w[k] * d[abs(j - k)] for j in range(n) for k in range(n))
    return max(nw, np.sqrt(var) if var > 0 else 0.0)


@pytest.mark.parametrize('n', [3, 4, 17, 250])
def test_drift_stderr_equals_its_variogram_twin(n):
    rng = np.random.default_rng(n)
    t = 100.0 + 1.5 * np.arange(n)
    e = rng.standard_normal(n)
    ar = np.zeros(n)
    for k in range(1, n):
        ar[k] = 0.9 * ar[k - 1] + e[k]
    for b in (1e-4 * e, 1e-5 * np.cumsum(e), 1e-6 * t + 1e-5 * e, ar):
        # the same sums in another order (an FFT autocorrelation for the n x n double sum):
        # 3e-15 relative seen up to 3000 chunks
        assert drift_stderr(t, b) == pytest.approx(_drift_stderr_twin(t, b), rel=1e-12)


def test_drift_stderr_memory_does_not_grow_with_the_square_of_the_chunks():
    # the paper's sequence has 18,715 chunks per axis: an n x n matrix of them is 2.8 GB (here
    # 8,000 chunks: 512 MB)
    import tracemalloc
    n = 8_000
    b = np.cumsum(np.random.default_rng(2).standard_normal(n))
    tracemalloc.start()
    drift_stderr(np.arange(n) * 1.5, b)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 50 * n * 8  # a few dozen arrays of n, not n x n


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


def _colour_twin(chunk, factors=NOISE_COLOUR_FACTORS):
    """Plain-numpy twin of noise_colour: overlapping ADEV from the phase, then a line fit."""
    theta = np.concatenate([[0.0], np.cumsum(chunk - chunk.mean())])
    adev = [math.sqrt(np.mean((theta[2 * m:] - 2 * theta[m:-m] + theta[:-2 * m]) ** 2)
                      / (2.0 * m * m)) for m in factors]
    return float(np.polyfit(np.log(factors), np.log(adev), 1)[0])


def test_noise_colour_equals_its_plain_numpy_twin_and_the_allan_estimator():
    rng = np.random.default_rng(7)
    chunk = 0.4 + 1e-3 * gl_difference(rng.standard_normal(10_000), -0.3, memory=200)
    got = noise_colour(chunk)
    # two summation orders of the same sums (compensated numba kernel, numpy cumsum): 1e-12
    assert got == pytest.approx(_colour_twin(chunk), abs=1e-12)
    adev = allan_deviation(chunk, 100.0, taus=np.array(NOISE_COLOUR_FACTORS)).adev
    assert got == pytest.approx(np.polyfit(np.log(NOISE_COLOUR_FACTORS), np.log(adev), 1)[0],
                                abs=1e-12)
    # dimensionless: the rate does not enter; scale and mean do not change it
    assert noise_colour(5.0 * chunk - 3.0) == pytest.approx(got, abs=1e-12)
    assert noise_colour(chunk, factors=(4, 16)) == pytest.approx(
        _colour_twin(chunk, (4, 16)), abs=1e-12)


def _expected_colour(order, memory, factors=NOISE_COLOUR_FACTORS):
    """Exact ADEV slope of white noise filtered by the truncated GL difference of ``order``."""
    c = gl_coefficients(order, memory)
    # the phase second difference at m is the rate filtered by m ones then m minus-ones: its
    # variance for unit white noise is the squared norm of that kernel convolved with c
    avar = [np.sum(np.convolve(np.r_[np.ones(m), -np.ones(m)], c) ** 2) / (2.0 * m * m)
            for m in factors]
    return float(np.polyfit(np.log(factors), 0.5 * np.log(avar), 1)[0])


@pytest.mark.parametrize('order', [0.0, 0.1, -0.1])
def test_noise_colour_follows_a_fractional_filter(order):
    # white noise: ADEV ~ m^-1/2 exactly; a GL difference of order d tilts the PSD by
    # |2 sin(pi f)|^(2d), and the slope moves by about -d (closed form of the filtered AVAR)
    expected = _expected_colour(order, 1000)
    if order == 0.0:
        assert expected == pytest.approx(-0.5, abs=1e-12)
    else:
        assert -1.0 < (expected + 0.5) / order < -0.8
    rng = np.random.default_rng(11)
    x = gl_difference(rng.standard_normal(601_000), order, memory=1000)[1000:]
    colours = np.array([noise_colour(c) for c in x.reshape(60, 10_000)])
    # chunk spread ~0.012 (docs/verdicts.md): the mean of 60 chunks has a standard error of
    # 0.0016; the log of an estimated ADEV is biased by about -1 / (2 EDF), at most -0.002 at
    # m = 64, which tilts the slope by less than 0.001. 0.006 is > 3 standard errors beyond that.
    assert np.mean(colours) == pytest.approx(expected, abs=0.006)
    assert 0.008 < np.std(colours, ddof=1) < 0.02


def test_noise_colour_degenerate_and_bad_input():
    assert math.isnan(noise_colour(np.ones(1000)))  # zero ADEV
    assert math.isnan(noise_colour(np.random.default_rng(0).standard_normal(255)))  # < 4 x 64
    assert math.isfinite(noise_colour(np.random.default_rng(0).standard_normal(256)))
    with pytest.raises(InputDataError, match='NaN'):
        noise_colour(np.r_[np.zeros(500), np.nan])
    with pytest.raises(InputDataError, match='1-D'):
        noise_colour(np.zeros((300, 2)))
    with pytest.raises(ParameterError, match='two distinct'):
        noise_colour(np.zeros(1000), factors=(4, 4))


def test_summarise_sequence_noise_colour_is_optional():
    t = np.arange(20.0)
    args = (t, np.zeros(20), np.ones(20), np.full(20, 1.0), np.full(20, 1.0))
    assert summarise_sequence(*args).noise_colour_robust is None
    colours = np.r_[np.linspace(-0.52, -0.48, 19), np.nan]
    loc = summarise_sequence(*args, noise_colour=colours).noise_colour_robust
    assert loc == robust_location(colours) and loc.count == 19 and loc.total == 19
