#!/usr/bin/env python3
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
Full-tool throughput of gyro_noise_analyze on a multi-million-sample bag: --jobs 1 vs --jobs 2.

Writes one simulated bag (the paper's model, 3 axes, 6660 Hz) into a temporary directory, then runs
the whole tool (decode, chunking, identification of every chunk by both methods on the full grid,
Allan deviation, report files without figures) with ``--jobs 1`` and ``--jobs 2`` on the same bag,
side by side in this process, and prints samples per second, the ratio, and the share of the time
spent decoding (bag reading + bulk ``sensor_msgs/Imu`` decode, timed inside the tool); plus a
decode-only pass as the baseline of that share.

Usage::

    .venv/bin/python bench/bench_analyze.py [--samples 2000000] [--storage sqlite3] [--axis all]
"""

import argparse
import os
from pathlib import Path
import shutil
import sys
import tempfile
import time

from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.cli.analyze import analyze_bags
from gyro_noise_ros.core.engine import AXES, EngineConfig, NoiseEngine
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np

RATE_HZ = 6660.0


def write_bag(path, n, storage, seed):
    rng = np.random.default_rng(seed)
    noises = [FractionalNoise(1.4, -1.0, 1e-3, rng=rng) for _ in range(3)]
    stamps = 1_760_000_000 * 10**9 + np.round(np.arange(n) * (1e9 / RATE_HZ)).astype(np.int64)
    block = 500_000
    with ImuBagWriter(path, storage=storage) as writer:
        for i in range(0, n, block):
            m = min(block, n - i)
            gyro = np.stack([nz.generate(m) for nz in noises], axis=1)
            writer.write_imu(stamps[i:i + m], gyro, np.tile([0.0, 0.0, 9.80665], (m, 1)))


def decode_only(path):
    t = time.perf_counter()
    n = 0
    with ImuBagReader(path) as reader:
        for batch in reader.iter_batches(65536):
            n += len(batch)
    return n, time.perf_counter() - t


def _identify(seed):
    from gyro_noise_ros.core.engine import EngineConfig, identifier_for

    ident = identifier_for(*EngineConfig().identifier_key())
    return ident(np.random.default_rng(seed).normal(size=10_000)).alpha_var


def available_speedup(count=40):
    """
    Time the same chunk identifications in 1 and in 2 processes, no bag.

    This is the speed-up the machine gives right now.
    """
    from concurrent.futures import ProcessPoolExecutor

    _identify(0)
    t = time.perf_counter()
    for i in range(count):
        _identify(i)
    serial = time.perf_counter() - t
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(_identify, range(4)))
        t = time.perf_counter()
        list(pool.map(_identify, range(count)))
        parallel = time.perf_counter() - t
    return serial / parallel


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    p.add_argument('--samples', type=int, default=2_000_000)
    p.add_argument('--storage', default='sqlite3', choices=('sqlite3', 'mcap'))
    p.add_argument('--axis', default='all', choices=[*AXES, 'all'])
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--workdir', type=Path, default=None,
                   help='where the bag goes (default: a temp dir)')
    args = p.parse_args(argv)
    print('command:', ' '.join([os.path.basename(sys.executable), *sys.argv]))
    print(f'cores: {os.cpu_count()} (shared machine; timings are noisy)')
    tmp = Path(tempfile.mkdtemp(prefix='bench_analyze_', dir=args.workdir))
    try:
        bag = tmp / 'bag'
        t = time.perf_counter()
        write_bag(bag, args.samples, args.storage, args.seed)
        size_mb = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
        print(f'wrote {args.samples:,} samples ({args.storage}, {size_mb:.0f} MB) in '
              f'{time.perf_counter() - t:.1f} s')
        n, dt = decode_only(bag)
        print(f'decode only (ImuBagReader.iter_batches): {n / dt:,.0f} samples/s ({dt:.1f} s)')
        axes = AXES if args.axis == 'all' else (args.axis,)
        # Load the numba caches (Allan kernels) once here so that neither timed run pays for it.
        warm = NoiseEngine(EngineConfig(axes=axes, chunk_size=2000, memory=100))
        rng = np.random.default_rng(0)
        warm.ingest(np.arange(3000, dtype=np.int64) * 150_150, rng.normal(size=(3000, 3)))
        warm.summary()
        rows = []
        for jobs in (1, 2):
            doc = analyze_bags([bag], out_dir=tmp / f'out{jobs}', config=EngineConfig(axes=axes),
                               jobs=jobs, figures=False, curves=0)
            tm = doc['_timing']
            rows.append((jobs, tm['total_s'], tm['decode_s']))
            chunks = sum(a['chunks'] for a in doc['bags'][0]['axes'].values())
            print(f'--jobs {jobs}: {tm["total_s"]:.1f} s, {args.samples / tm["total_s"]:,.0f} '
                  'samples/s, ' f'{chunks} chunk identifications ({len(axes)} axes), decode '
                  f'{tm["decode_s"]:.1f} s '
                  f'({100 * tm["decode_s"] / tm["total_s"]:.0f} %), main process waiting for '
                  'workers ' f'{tm["wait_s"]:.1f} s')
        (_, t1, _), (_, t2, _) = rows
        print(f'speed-up --jobs 2 / --jobs 1: {t1 / t2:.2f}x (the bare identification in 2 '
              'processes vs 1, '
              f'no bag, measured just after: {available_speedup():.2f}x; load average '
              f'{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)')
        print(f'equivalent: a 12 h 6.66 kHz sequence (187,159,392 samples, {len(axes)} axes) in '
              f'{187_159_392 / (args.samples / t2) / 60:.0f} min at --jobs 2')
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
