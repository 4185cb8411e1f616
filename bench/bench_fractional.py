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
Benchmark: fractional-order identification, fast path vs the per-order numpy.convolve oracle.

Usage:
    python bench/bench_fractional.py [--ref-chunks 2] [--repeat 5] [--chunks 200] [--jobs 2]
        [--full]

Prints, side by side on the same 10,000-sample chunks (full grid 0:2:0.01, L = 1000, both methods):
the oracle's time per chunk (test/_fractional_reference.py: numpy.convolve + numpy.correlate per
order) and the CPU time per chunk of each algorithm of OrderIdentifier ('exact': the released
blocked FFT algorithm; 'fast'; 'auto', the default: fast location + exact values), their speed-up
per core against the oracle and against 'exact', the largest relative curve difference of 'fast'
and 'exact' from the oracle, and whether 'auto' gave the results of 'exact' bit for bit.
Then the throughput with 1 and --jobs processes over --chunks chunks, extrapolated to a 12 h 6.66
kHz sequence (187,159,392 samples = 18,715 chunks); --full simulates and analyses the whole 12 h
sequence for real.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
import os
import platform
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))
from _fractional_reference import curves_ref  # noqa: E402
from gyro_noise_ros.core.fractional import OrderIdentifier  # noqa: E402
from gyro_noise_ros.core.simulate import FractionalNoise  # noqa: E402
import numpy as np  # noqa: E402

SEQ_SAMPLES = 187_159_392
CHUNK = 10_000
_IDENT = None


def _analyse(chunk):
    global _IDENT
    if _IDENT is None:
        _IDENT = OrderIdentifier(CHUNK)
    r = _IDENT(chunk)
    return r.alpha_var, r.alpha_corr


def _cpu():
    try:
        with open('/proc/cpuinfo') as fh:
            for line in fh:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or 'unknown'


def main():
    p = argparse.ArgumentParser(description='fractional identification benchmark')
    p.add_argument('--ref-chunks', type=int, default=2)
    p.add_argument('--repeat', type=int, default=5,
                   help='timed passes over the --ref-chunks chunks per algorithm')
    p.add_argument('--chunks', type=int, default=200,
                   help='chunks of the throughput runs (0: none, the CPU times per chunk only)')
    p.add_argument('--jobs', type=int, default=2)
    p.add_argument('--full', action='store_true',
                   help='simulate and analyse a whole 12 h sequence')
    a = p.parse_args()
    print('command:', ' '.join([os.path.basename(sys.executable)] + sys.argv))
    print(f'cpu: {_cpu()}; cores usable: {len(os.sched_getaffinity(0))}; jobs: {a.jobs}')
    gen = FractionalNoise(1.4, -0.5, 1e-3, rng=np.random.default_rng(0), sigma_nu=1e-3)
    chunks = [gen.generate(CHUNK) for _ in range(a.ref_chunks)]
    idents = {name: OrderIdentifier(CHUNK, algorithm=name) for name in ('exact', 'fast', 'auto')}
    for ident in idents.values():
        ident(chunks[0])  # warm-up (FFT plans, numba kernels)
    cpu = {name: [] for name in idents}
    results = {name: [] for name in idents}
    for _ in range(a.repeat):
        for name, ident in idents.items():  # interleaved, so load changes hit all alike
            for c in chunks:
                t = time.process_time()
                results[name].append(ident(c, curves=name != 'auto'))
                cpu[name].append(time.process_time() - t)
    per = {name: float(np.median(v)) for name, v in cpu.items()}
    t = time.process_time()
    ref = [curves_ref(c, idents['exact'].alphas, 1000) for c in chunks]
    t_ref = (time.process_time() - t) / len(chunks)

    def worst(name):
        out = 0.0
        for fr, (vc, jc, fc) in zip(results[name], ref):
            out = max(out, np.max(np.abs(fr.var_curve / vc - 1)),
                      np.max(np.abs(fr.j_curve / jc - 1)),
                      np.max(np.abs(fr.f_curve - fc) / np.maximum(np.abs(fc), 1e-300)))
        return out

    fields = ('alpha_var', 'f_var', 'var_min', 'alpha_corr', 'f_corr', 'j_min',
              'tied_alphas_var', 'tied_alphas_corr')
    same = all(getattr(x, f) == getattr(y, f) for x, y in zip(results['auto'], results['exact'])
               for f in fields)
    print(f'CPU time per chunk, one core (median of {a.repeat} x {len(chunks)}; load average '
          f'{os.getloadavg()[0]:.1f}): oracle {t_ref * 1e3:.0f} ms')
    for name in ('exact', 'fast', 'auto'):
        extra = (f', max relative curve difference from the oracle {worst(name):.1e}'
                 if name != 'auto' else
                 f', results bit-identical to exact: {"yes" if same else "NO"}')
        print(f'  {name:5s} {per[name] * 1e3:6.1f} ms: {t_ref / per[name]:6.1f}x the oracle, '
              f'{per["exact"] / per[name]:.2f}x exact{extra}')

    if a.chunks <= 0:
        return 0  # the per-chunk CPU times only
    work = [gen.generate(CHUNK) for _ in range(a.chunks)]
    t = time.perf_counter()
    for c in work:
        _analyse(c)
    t1 = (time.perf_counter() - t) / len(work)
    with ProcessPoolExecutor(a.jobs) as pool:
        list(pool.map(_analyse, work[:a.jobs * 2]))  # warm the workers
        t = time.perf_counter()
        list(pool.map(_analyse, work, chunksize=8))
        tj = (time.perf_counter() - t) / len(work)
    n_chunks = SEQ_SAMPLES // CHUNK
    print(
        f'{a.chunks} chunks: {t1 * 1e3:.1f} ms/chunk with 1 process, {tj * 1e3:.1f} ms/chunk with '
        f'{a.jobs} ({t1 / tj:.2f}x)')
    print(f'the paper\'s "12 h" sequence ({n_chunks} chunks), extrapolated: '
          f'{n_chunks * t1 / 60:.1f} min with '
          f'1 process, {n_chunks * tj / 60:.1f} min with {a.jobs} (target <= 10 min)')
    true_12h = int(12 * 3600 * 6660) // CHUNK
    print(f'(a true 12 h at 6.66 kHz is {true_12h} chunks: {true_12h * tj / 60:.1f} min with '
          f"{a.jobs}; the paper's "
          f'187,159,392 samples are 7.8 h at 6.66 kHz, see docs/analysis.md)')
    if a.full:
        # Simulate first (timed apart, 1.5 GB in memory), then time the analysis alone, as a user
        # analysing a recorded sequence would run it.
        n_full = n_chunks * CHUNK
        t = time.perf_counter()
        seq = FractionalNoise(1.4, -0.5, 1e-3, rng=np.random.default_rng(1),
                              sigma_nu=1e-3).generate(n_full)
        t_sim = time.perf_counter() - t
        with ProcessPoolExecutor(a.jobs) as pool:
            list(pool.map(_analyse, [seq[:CHUNK]] * (2 * a.jobs)))  # warm the workers
            t = time.perf_counter()
            results = list(pool.map(_analyse, (seq[i:i + CHUNK] for i in range(0, n_full, CHUNK)),
                                    chunksize=16))
            t_an = time.perf_counter() - t
        av = np.array([r[0] for r in results])
        ac = np.array([r[1] for r in results])
        print(f'full run: {n_full:,} samples simulated in {t_sim / 60:.1f} min; {len(results)} '
              'chunks analysed '
              f'(both methods, full grid) in {t_an / 60:.1f} min with {a.jobs} processes (target '
              '<= 10 min); '
              f'mean order: variance method {av.mean():.3f}, correlation method {ac.mean():.3f} '
              '(simulated 1.4)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
