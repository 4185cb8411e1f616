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
Benchmark: forward simulation of paper 000 eq. (2) (numba kernel) vs its plain-numpy twin.

Usage:
    python bench/bench_simulate.py [--samples 187159392] [--twin-samples 20000]

Side by side in one process: the numba kernel and the plain-numpy twin of test/test_simulate.py
(one numpy dot product per step) on the same --twin-samples, L = 1000, with the ratio; then the
time to generate --samples (default: a whole 12 h sequence at 6.66 kHz, 187,159,392 samples)
streamed in blocks, with eqs. 10-11 measurement noise and a bias, and its peak resident memory.
"""

import argparse
import os
import resource
import sys
import time

from gyro_noise_ros.core.fractional import gl_coefficients
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np


def twin(w, alpha, f, memory):
    c_rev = gl_coefficients(alpha, memory)[:0:-1]
    buf = np.zeros(memory + len(w))
    for i in range(len(w)):
        buf[memory + i] = f * buf[memory + i - 1] + w[i] - c_rev @ buf[i:i + memory]
    return buf[memory:]


def main():
    p = argparse.ArgumentParser(description='simulation benchmark')
    p.add_argument('--samples', type=int, default=187_159_392)
    p.add_argument('--twin-samples', type=int, default=20_000)
    a = p.parse_args()
    print('command:', ' '.join([os.path.basename(sys.executable)] + sys.argv))
    alpha, f = 1.4, -0.5
    FractionalNoise(alpha, f, 1.0, rng=np.random.default_rng(0)).generate(10)  # JIT / cache load
    w = np.random.default_rng(1).standard_normal(a.twin_samples)
    t = time.perf_counter()
    ref = twin(w, alpha, f, 1000)
    t_twin = time.perf_counter() - t
    t = time.perf_counter()
    fast = FractionalNoise(alpha, f, 1.0, rng=np.random.default_rng(1)).generate(a.twin_samples)
    t_fast = time.perf_counter() - t
    print(f'{a.twin_samples} samples, L = 1000: numpy twin {t_twin:.2f} s, numba {t_fast:.3f} s, '
          f'ratio {t_twin / t_fast:.1f}x, max |difference| {np.max(np.abs(ref - fast)):.1e}')
    gen = FractionalNoise(alpha, f, 1e-3, rng=np.random.default_rng(2), sigma_nu=1e-3, bias=0.01)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    left = a.samples
    total = 0.0
    while left:
        n = min(left, 10_000_000)
        total += gen.generate(n).sum()
        left -= n
    dt = time.perf_counter() - t
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f'{a.samples} samples streamed in blocks of 10 M: {dt:.1f} s ({dt / 60:.2f} min, '
          f'{a.samples / dt / 1e6:.2f} M samples/s), peak RSS growth {(rss1 - rss0) / 1024:.0f} '
          'MiB; ' f'mean {total / a.samples:.4g}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
