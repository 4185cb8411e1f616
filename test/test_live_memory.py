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

"""The live analysis' Python objects level off within minutes (docs/scale.md, memory)."""

import gc
import pickle
import sys
import time

from gyro_noise_ros.app.live import LiveAnalysis, RECENT_RESULTS
from gyro_noise_ros.core import allan
from gyro_noise_ros.core.engine import EngineConfig
from gyro_noise_ros.core.fractional import make_grid
import numpy as np

RATE_HZ = 6667.0
CHUNK = 2000
#: Chunks after which the objects must be flat: 3 minutes of the node's 10,000-sample chunks at
#: 6.66 kHz, half the warm-up of the 30-minute soak (bench/bench_soak.py), which judges the rest.
SETTLED = 120
#: Chunks over which they must stay flat.
WINDOW = 120


def _run(live, rng, start, chunks):
    """Feed ``chunks`` chunks with the node's cadence of summary, health and Allan reads."""
    period = 1e9 / RATE_HZ
    for k in range(start, start + chunks):
        stamps = np.rint((k * CHUNK + np.arange(CHUNK)) * period).astype(np.int64)
        live.ingest(stamps, rng.normal(0.0, 0.01, (CHUNK, 3)))
        # the node's summary and health (every 1 s, after each chunk) every 3rd chunk, here to
        # save time; an Allan read every 7 chunks: the node's 10 s allan_period_s at 6.66 kHz
        if k % 3 == 0 or k % 7 == 0:
            summaries = live.engine.summary(allan=k % 7 == 0)
            live.engine.health(seconds_since_data=0.0, summaries=summaries)
        live.collect()
        while live.queue_size:
            time.sleep(0.001)
            live.collect()
    deadline = time.monotonic() + 10.0
    while len(live.results) < min(RECENT_RESULTS, 3 * (start + chunks)):
        assert time.monotonic() < deadline, 'the worker did not finish'
        time.sleep(0.001)
        live.collect()


def test_python_objects_flat_once_the_caches_are_full():
    # Small chunks so that they cost little; the same state and caches as the node's run.
    config = EngineConfig(chunk_size=CHUNK, memory=100, alphas=make_grid(0.0, 2.0, 0.1),
                          rate_hz=RATE_HZ)
    live = LiveAnalysis(config)
    rng = np.random.default_rng(7)
    try:
        _run(live, rng, 0, SETTLED)
        gc.collect()
        before = sys.getallocatedblocks()
        _run(live, rng, SETTLED, WINDOW)
        gc.collect()
        grown = sys.getallocatedblocks() - before
    finally:
        live.stop()
    assert len(live.results) == RECENT_RESULTS
    # What filled too slowly before (docs/scale.md): a 1,000-result history still growing here
    # added 5,695 blocks over these 120 chunks x 3 axes, the 4,096-entry EDF cache (every read
    # has a new record length, so new keys) 4,566; now 461-499 (the small caches' last entries
    # and objects alive at the second count only: arrays, a job in flight).
    assert grown < 1000, grown


def test_allan_rows_reserved_once_and_pickled_as_written():
    # The accumulator reserves every level's ring row up front (untouched pages); a pickle holds
    # only the rows in use, and the copy goes on bit for bit like the original.
    rng = np.random.default_rng(11)
    rate = rng.normal(0.0, 0.01, 300_000)
    acc = allan.AllanAccumulator(100.0, taus='dense')  # rows of 2**16 + 1 points, 0.5 MB
    ring = acc._ring
    acc.update(rate[:200_000])
    assert acc._ring is ring  # never reallocated as levels are added
    blob = pickle.dumps(acc)
    # 3 levels reached (from 2**15, 2**16 and 2**17 samples) of the 25 reserved
    assert len(blob) < 5 * (2 ** 16 + 1) * 8 < ring.nbytes / 4
    copy = pickle.loads(blob)
    for a in (acc, copy):
        a.update(rate[200_000:])
    mine, theirs = acc.result(), copy.result()
    assert np.array_equal(mine.adev, theirs.adev) and np.array_equal(mine.edf, theirs.edf)
