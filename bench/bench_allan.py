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
Benchmark.

Overlapping Allan deviation of a 12 h, 6.66 kHz record (187,159,392 samples), octave taus.

Usage:
    python bench/bench_allan.py [--samples N] [--rate-hz 6660] [--no-baseline] [--accumulator]

Side by side on the same white-noise data (numpy, seeded):

* ``allan_deviation`` (numba: compensated integration into one float64 phase array, cache-blocked
  sums of squares, noise identification, EDF, bounds);
* the plain-numpy baseline: ``x = cumsum(y - mean)``, then per tau
  ``d = x[2m:] - 2 x[m:-m] + x[:-2m]; avar = d @ d / (2 m^2 len(d))``.

Prints the wall and CPU time of each (the machine may be shared: CPU time is the steadier), their
ratios, the peak of numpy allocations during each call (tracemalloc; the input itself excluded),
the process max RSS, and the largest relative ADEV difference between the two. ``--accumulator``
also times AllanAccumulator fed in 1 s batches.
"""

import argparse
import os
import resource
import shlex
import sys
import time
import tracemalloc

from gyro_noise_ros.core.allan import allan_deviation, AllanAccumulator, octave_factors
import numpy as np

SEQ_SAMPLES = 187_159_392


def numpy_baseline(y):
    """Plain numpy overlapping AVAR at octave factors (the textbook vectorised formula)."""
    ms = octave_factors(y.size)
    x = np.empty(y.size + 1)
    x[0] = 0.0
    np.cumsum(y - y.mean(), out=x[1:])
    avar = np.empty(ms.size)
    for j, m in enumerate(ms):
        d = x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m]
        avar[j] = np.dot(d, d) / (2.0 * m * m * d.size)
    return ms, avar


def _measure(fn, *args):
    tracemalloc.start()
    tracemalloc.reset_peak()
    t0 = time.perf_counter()
    c0 = time.process_time()
    out = fn(*args)
    cpu = time.process_time() - c0
    dt = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return out, (dt, cpu), peak


def _maxrss_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main(argv=None):
    """Run the benchmark; returns 0."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument(
        '--samples', type=int, default=SEQ_SAMPLES,
        help=f'number of rate samples (default {SEQ_SAMPLES:,} = 12 h at 6.66 kHz)')
    parser.add_argument('--rate-hz', type=float, default=6660.0, help='sample rate (Hz)')
    parser.add_argument('--no-baseline', action='store_true', help='skip the numpy baseline')
    parser.add_argument('--accumulator', action='store_true', help='also time AllanAccumulator')
    args = parser.parse_args(argv)
    if args.samples < 16:
        parser.error('--samples must be >= 16')

    print('command:', ' '.join(shlex.quote(a) for a in [sys.executable] + sys.argv))
    rng = np.random.default_rng(2026)
    # warm the numba kernels (cache=True; first call of a fresh checkout compiles them)
    allan_deviation(rng.standard_normal(4096), args.rate_hz)
    t0 = time.perf_counter()
    y = rng.standard_normal(args.samples)
    y *= 1e-3
    y += 0.01   # a bias of 10 mrad/s, as a real gyro has
    print(f'data: {args.samples:,} float64 samples ({y.nbytes / 2**20:,.0f} MiB), generated in '
          f'{time.perf_counter() - t0:.1f} s; rate {args.rate_hz:g} Hz; '
          f'{octave_factors(args.samples).size} octave taus')
    rss0 = _maxrss_mib()

    res, (t_fast, c_fast), peak_fast = _measure(lambda v: allan_deviation(v, args.rate_hz), y)
    rss1 = _maxrss_mib()
    print(f'allan_deviation : {t_fast:8.2f} s wall {c_fast:8.2f} s cpu   '
          f'peak numpy alloc {peak_fast / 2**20:8,.0f} MiB '
          f'({peak_fast / y.nbytes:.2f} x input)   maxrss {rss1:,.0f} MiB (+{rss1 - rss0:,.0f})')

    if not args.no_baseline:
        (ms, avar_np), (t_np, c_np), peak_np = _measure(numpy_baseline, y)
        rss2 = _maxrss_mib()
        print(f'numpy baseline  : {t_np:8.2f} s wall {c_np:8.2f} s cpu   '
              f'peak numpy alloc {peak_np / 2**20:8,.0f} MiB '
              f'({peak_np / y.nbytes:.2f} x input)   maxrss {rss2:,.0f} MiB')
        assert np.array_equal(ms, res.m)
        diff = np.max(np.abs(np.sqrt(avar_np) / res.adev - 1))
        print(
            f'ratio numpy / allan_deviation: wall {t_np / t_fast:.2f}x, cpu {c_np / c_fast:.2f}x; '
            f'memory {peak_np / max(peak_fast, 1):.2f}x; max |ADEV rel diff| {diff:.2e}')
        print(f'load average (1, 5, 15 min) at the end: {os.getloadavg()}')

    if args.accumulator:
        batch = int(round(args.rate_hz))
        acc = AllanAccumulator(args.rate_hz, offset_rad_per_s=0.01)
        t0 = time.perf_counter()
        for i in range(0, y.size, batch):
            acc.update(y[i:i + batch])
        r_acc = acc.result()
        t_acc = time.perf_counter() - t0
        exact = r_acc.m <= 2 ** 15
        diff = np.max(np.abs(r_acc.adev / res.adev - 1)[exact])
        print(f'AllanAccumulator: {t_acc:8.2f} s in {batch}-sample batches '
              f'({y.size / t_acc / 1e6:.1f} Msamples/s), state {acc.nbytes / 2**20:.2f} MiB; '
              f'max |rel diff| vs batch on exact taus {diff:.1e}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
