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
Benchmark of the static-segment rule (core/segments.py): cost against record length.

    .venv/bin/python bench/bench_segments.py [--samples 1000000] [--rate-hz 10]

Times ``static_part`` (the rule on a whole record) and ``WindowStats`` fed in 5000-sample batches
(analyze) on records of n/100, n/10 and n samples, and the slow per-window-mask accumulation the
rule had (test/_segments_oracle.py) on the whole record as ``static_part`` fed it, on the shortest
two (quadratic: 100x the time for 10x the length). Printed side by side: seconds, and each
time over the time of the shortest record against the length ratio (linear growth: equal ratios).
The machine is shared: read the ratios, not the third digit.
"""

import argparse
import pathlib
import sys
import time

import numpy as np


def record(n, rate_hz, seed=0):
    """Return stamps (ns) and 3-axis static rates (rad/s) with one knock on y."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    gyro = rng.normal(0.0, 2e-3, (n, 3))
    gyro[(t > t[-1] / 3) & (t < t[-1] / 3 + 3.0), 1] += 0.2
    return np.rint(t * 1e9).astype(np.int64), gyro


def timed(fn):
    """Return the wall time of fn() (s)."""
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def fed(cls, stamps, gyro, batch):
    """Feed batches of ``batch`` samples to a WindowStats-like class and judge."""
    stats = cls()
    for lo in range(0, stamps.size, batch):
        stats.update(stamps[lo:lo + batch], gyro[lo:lo + batch])
    return stats.segment()


def main(argv=None):
    """Run the benchmark and print the table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--samples', type=int, default=1_000_000, help='longest record, samples')
    p.add_argument('--rate-hz', type=float, default=10.0)
    a = p.parse_args(argv)
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'test'))
    from _segments_oracle import SlowWindowStats
    from gyro_noise_ros.core.segments import static_part, WindowStats
    import scipy.ndimage  # noqa: F401  imported by the first judgement: not timed

    sizes = [a.samples // 100, a.samples // 10, a.samples]
    base = {}
    print(f'{"samples":>9} {"length":>6} {"static_part s":>13} {"ratio":>6} {"stream s":>9} '
          f'{"ratio":>6} {"slow whole s":>13} {"ratio":>6}')
    for n in sizes:
        stamps, gyro = record(n, a.rate_hz)
        row = [timed(lambda: static_part(stamps, gyro)),
               timed(lambda: fed(WindowStats, stamps, gyro, 5000)),
               timed(lambda: fed(SlowWindowStats, stamps, gyro, n)) if n < a.samples
               else float('nan')]
        base = base or dict(enumerate(row))
        cells = ' '.join(f'{v:>{w}.3f} {v / base[i]:>6.1f}'
                         for i, (v, w) in enumerate(zip(row, (13, 9, 13))))
        print(f'{n:>9} {n / sizes[0]:>6.0f} {cells}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
