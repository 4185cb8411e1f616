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
The pieces the streaming engine composes, each alone: the one Chunker, stamp accounting, jobs.

The engine's own behaviour is tested in test_engine.py; here each piece is held to its own job,
and the Chunker is shown to do both of its jobs (plain arrays for the scripts, the engine's
aligned stamp, loss, temperature and rate columns) exactly as slicing the whole stream would.
"""

from collections import deque
from dataclasses import replace

from gyro_noise_ros.core.chunks import chunk_moments, Chunker
from gyro_noise_ros.core.engine import (_RowStore, analyze_chunk, chunk_jobs, EngineConfig,
                                        NoiseEngine, SequenceBook)
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.core.stamps import StampAccountant
from gyro_noise_ros.errors import InputDataError, ParameterError
import numpy as np
import pytest

PERIOD_NS = 1_000_000  # 1 kHz


def test_chunker_cuts_aligned_columns_like_slicing_the_whole_stream():
    rng = np.random.default_rng(40)
    n, size = 5_321, 500
    rel = np.arange(n, dtype=np.int64) * PERIOD_NS
    lost = rng.integers(0, 3, n).astype(np.int64)
    temp = rng.normal(25.0, 1.0, n)
    gyro = rng.standard_normal((n, 2))
    chunker = Chunker(size)
    out, pos = [], 0
    while pos < n:
        step = int(rng.integers(0, 1_300))
        out += chunker.push_columns(rel[pos:pos + step], lost[pos:pos + step],
                                    temp[pos:pos + step], gyro[pos:pos + step])
        pos += step
    assert len(out) == n // size == chunker.chunks_out
    for k, (r, lo, t, g) in enumerate(out):
        sl = slice(k * size, (k + 1) * size)
        assert r.dtype == np.int64 and lo.dtype == np.int64  # dtypes kept, stamps exact
        np.testing.assert_array_equal(r, rel[sl])
        np.testing.assert_array_equal(lo, lost[sl])
        np.testing.assert_array_equal(t, temp[sl])
        np.testing.assert_array_equal(g, gyro[sl])
        assert not any(np.shares_memory(a, b) for a in (r, lo, t, g)
                       for b in (rel, lost, temp, gyro))
    assert chunker.tail_samples == n % size
    np.testing.assert_array_equal(chunker.tail[3], gyro[n - n % size:])


def test_chunker_discard_and_refusals():
    chunker = Chunker(4)
    assert chunker.push_columns(np.arange(3), np.zeros(3)) == []
    assert chunker.discard() == 3 and chunker.tail_samples == 0 and chunker.discard() == 0
    (a, b), = chunker.push_columns(np.arange(10, 14), np.ones(4))
    assert a.tolist() == [10, 11, 12, 13] and b.tolist() == [1, 1, 1, 1]
    with pytest.raises(InputDataError, match='equal lengths'):
        chunker.push_columns(np.arange(3), np.zeros(2))
    with pytest.raises(InputDataError, match='shape changed'):
        chunker.push_columns(np.arange(3), np.zeros((3, 2)))


def test_stamp_accountant_finds_the_gap_and_carries_the_payload_unchanged():
    n, at, missing = 3_000, 1_700, 3
    stamps = np.arange(n + missing, dtype=np.int64) * PERIOD_NS + 10 ** 18
    stamps = np.delete(stamps, np.arange(at + 1, at + 1 + missing))
    payload = np.arange(n, dtype=np.float64)
    acc = StampAccountant(None, 1.5, 1_000)
    batches = []
    for i in range(0, n, 333):
        batches += acc.add(stamps[i:i + 333], (payload[i:i + 333],))
    batches += acc.flush()
    rel = np.concatenate([b.rel_ns for b in batches])
    lost = np.concatenate([b.lost for b in batches])
    np.testing.assert_array_equal(rel, stamps - stamps[0])
    np.testing.assert_array_equal(np.concatenate([b.payload[0] for b in batches]), payload)
    assert lost[at + 1] == missing and lost.sum() == missing
    counts = acc.counts(chunks=0, tail_samples=0, discarded_samples=0, discarded_partials=0)
    assert (counts.samples, counts.samples_lost, counts.gaps) == (n, missing, 1)
    assert counts.rate_hz == pytest.approx(1e9 / PERIOD_NS)
    assert counts.longest_gaps[0][2] == missing


def test_chunk_jobs_moments_are_chunk_moments_and_nan_is_per_axis():
    rng = np.random.default_rng(41)
    gyro = rng.standard_normal((100, 2))
    gyro[5, 1] = np.nan
    rel = np.arange(100, dtype=np.int64) * PERIOD_NS
    x, y = chunk_jobs(7, rel, 2, 1, np.full(100, np.nan), gyro, axes=('x', 'y'), first_ns=5,
                      dropped=False, identifier_key=())
    m = chunk_moments(gyro[:, 0])
    assert (x.bias_rad_s, x.variance_rad2_s2, x.status) == (m.bias, m.variance, 'ok')
    assert (x.chunk, x.stamp_start_ns, x.samples_lost, x.gaps) == (7, 5, 2, 1)
    assert y.status == 'nan' and y.nan_samples == 1 and np.isnan(y.bias_rad_s)
    assert np.isnan(x.temperature_c)


def test_sequence_book_counts_every_status_and_keeps_only_ok_rows():
    config = EngineConfig(chunk_size=300, memory=20, alphas=make_grid(0.0, 2.0, 0.5),
                          allan=False, axes=('x',), rate_hz=1000.0)
    engine = NoiseEngine(config)
    rng = np.random.default_rng(42)
    stamps = np.arange(1_500, dtype=np.int64) * PERIOD_NS
    jobs = engine.ingest(stamps, rng.standard_normal((1_500, 3))) + engine.flush()
    book = SequenceBook(('x',), 0)
    book.record(analyze_chunk(jobs[0]))
    book.record(engine.skip(jobs[1], 'behind'))
    seq, _ = book.sequence('x', tail_samples=0, order_step=0.5)
    assert seq.chunks == 1 and book.by_status['x']['skipped'] == 1
    with pytest.raises(ParameterError, match='not analysed'):
        book.record(replace(analyze_chunk(jobs[0]), axis='z'))


@pytest.mark.parametrize('history', [0, 1, 5, 64, 65, 100, 100_000_000])
def test_row_store_keeps_what_a_bounded_deque_of_tuples_keeps(history):
    # The oracle: the deque of tuples the store replaced (rows oldest first, newest `history`).
    rng = np.random.default_rng(history)
    store, oracle = _RowStore(3, history), deque(maxlen=history or None)
    assert store.rows().shape == (0, 3)
    for n in range(1, 300):
        row = tuple(rng.standard_normal(3))
        store.append(row)
        oracle.append(row)
        if n % 7 == 0 or n < 10:
            np.testing.assert_array_equal(store.rows(), np.array(list(oracle)).reshape(-1, 3))
            assert len(store) == len(oracle)
    # A copy: the caller may not change the store through it.
    rows = store.rows()
    rows[:] = 0.0
    assert np.any(store.rows() != 0.0)
