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
RSS of the live analysis without ROS: LiveAnalysis fed white noise, chunk after chunk.

The ``noise_analyzer`` node's RSS rose about 90-100 kB per analysed chunk in the soak
(docs/scale.md). This runs the same analysis in one process, with the node's default parameters,
6.66 kHz stamps in 2,000-sample batches, the node's summary and health calls, and prints the RSS
every 25 chunks: what grows here is the analysis, what grows only in the node is the ROS side.

Run: ``.venv/bin/python bench/bench_live_memory.py --chunks 600`` (one core; ~10 min).
"""

import argparse
import time

from gyro_noise_ros.app.live import engine_config_from, LiveAnalysis
from gyro_noise_ros.nodes.analyzer import PARAMETERS
import numpy as np


def rss_mb():
    """Return this process's resident set size (MB)."""
    with open('/proc/self/status') as fh:
        for line in fh:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    return float('nan')


def main(argv=None):
    """Feed --chunks chunks per axis and print the RSS every 25."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--chunks', type=int, default=600, help='chunks (per axis) to analyse')
    parser.add_argument('--rate-hz', type=float, default=6667.0, help='sample rate of the stamps')
    args = parser.parse_args(argv)
    params = {p.name: p.default for p in PARAMETERS}
    live = LiveAnalysis(engine_config_from(params))
    rng = np.random.default_rng(1)
    batch, next_ns, done, calls, mark = 2000, 0, 0, 0, 0
    print('chunks  RSS (MB)')
    while done < args.chunks:
        stamps = next_ns + (np.arange(batch) * (1e9 / args.rate_hz)).astype(np.int64)
        next_ns = int(stamps[-1] + 1e9 / args.rate_hz)
        live.ingest(stamps, rng.normal(0.0, 0.01, (batch, 3)))
        calls += 1
        if calls % 5 == 0:  # the node: a diagnostics period
            live.engine.health(seconds_since_data=0.0, summaries=live.engine.summary(allan=False))
        if calls % 50 == 0:  # the node: the Allan period
            live.engine.summary(allan=True)
        done += len(live.collect()[1])
        while live.queue_size > 2:  # never skip: wait for the worker
            time.sleep(0.01)
            done += len(live.collect()[1])
        if done // 25 > mark:
            mark = done // 25
            print(f'{done:6d}  {rss_mb():8.1f}', flush=True)
    live.stop()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
