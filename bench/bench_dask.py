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
gyro_noise_analyze on a Dask LocalCluster against local worker processes, same bag, same machine.

Writes one simulated bag (the paper's model, 3 axes, 6660 Hz) and runs the whole tool (full grid,
both methods, Allan deviation, no figures) side by side in this process:

1. overhead: ``--jobs N`` (a ProcessPoolExecutor of N processes, started inside the run as the
   tool does) against ``--scheduler`` on a LocalCluster of N worker processes x 1 thread (started
   before, as a standing cluster is; warmed by one small run), once with Dask's default worker
   environment (``MALLOC_TRIM_THRESHOLD_=65536``) and once without it (docs/scale.md advises
   it). Ratio = Dask time / local time;
2. throughput against the number of workers (without that variable): LocalClusters of 1, 2, 4
   worker processes x 1 thread, and the same ``--jobs`` locally (``--jobs 1``: in-process). On a
   2-core machine the 4-worker row shows oversubscription, not scaling.

Every Dask run's chunks.csv is compared with the in-process run's (must be byte-identical).
Each row is the best of two local and two Dask runs, alternated, to damp the load of a shared
machine.

Usage::

    .venv/bin/python bench/bench_dask.py [--samples 1000000] [--workers 1,2,4] [--jobs 2]
"""

import argparse
import os
from pathlib import Path
import shutil
import sys
import tempfile
import time

from gyro_noise_ros.app.analyze import analyze_bags, AnalyzeParams
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.core.engine import EngineConfig
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np

RATE_HZ = 6660.0


def write_bag(path, n, seed):
    rng = np.random.default_rng(seed)
    noises = [FractionalNoise(1.4, -1.0, 1e-3, rng=rng) for _ in range(3)]
    stamps = 1_760_000_000 * 10**9 + np.round(np.arange(n) * (1e9 / RATE_HZ)).astype(np.int64)
    block = 500_000
    with ImuBagWriter(path, storage='mcap') as writer:
        for i in range(0, n, block):
            m = min(block, n - i)
            gyro = np.stack([nz.generate(m) for nz in noises], axis=1)
            writer.write_imu(stamps[i:i + m], gyro, np.tile([0.0, 0.0, 9.80665], (m, 1)))


def run(bag, out, *, jobs=1, scheduler=None):
    """Analyse ``bag`` into ``out``; return (seconds, chunk identifications)."""
    t = time.perf_counter()
    result = analyze_bags(AnalyzeParams(paths=(bag,), out_dir=out, config=EngineConfig(),
                                        jobs=jobs, scheduler=scheduler, figures=False, curves=0,
                                        static='off'))
    seconds = time.perf_counter() - t
    return seconds, sum(a['chunks'] for a in result.bags[0]['axes'].values())


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    p.add_argument('--samples', type=int, default=600_000)
    p.add_argument('--jobs', type=int, default=2, help='workers of the overhead comparison')
    p.add_argument('--workers', default='1,2,4', help='LocalCluster sizes of the scaling rows')
    p.add_argument('--seed', type=int, default=1)
    args = p.parse_args(argv)
    import dask
    from distributed import LocalCluster

    sizes = [int(v) for v in args.workers.split(',')]
    print('command:', ' '.join([os.path.basename(sys.executable), *sys.argv]))
    print(f'cores: {os.cpu_count()}; load average at start {os.getloadavg()[0]:.1f} (shared '
          'machine: absolute rates are noisy, ratios come from runs side by side)')
    tmp = Path(tempfile.mkdtemp(prefix='bench_dask_'))
    try:
        bag, small = tmp / 'bag', tmp / 'small'
        write_bag(bag, args.samples, args.seed)
        write_bag(small, 40_000, args.seed + 1)
        n = args.samples

        def cluster(workers, dask_default_env=False):
            # A LocalCluster's nannies live in this process and export their pre-spawn
            # environment here too: drop it before a cluster that must not have it.
            os.environ.pop('MALLOC_TRIM_THRESHOLD_', None)
            value = '65536' if dask_default_env else None
            with dask.config.set({'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_':
                                  value}):
                c = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                 dashboard_address=None, silence_logs=40)
            os.environ.pop('MALLOC_TRIM_THRESHOLD_', None)
            run(small, tmp / 'warm', scheduler=c.scheduler_address)  # imports, numba, identifier
            return c

        def side_by_side(workers, dask_default_env=False, tag=''):
            """Return the best of 2 local and of 2 Dask runs, alternated; and identical?."""
            local, remote, same = [], [], True
            with cluster(workers, dask_default_env) as c:
                for k in range(2):
                    local.append(run(bag, tmp / f'l{tag}{k}', jobs=workers)[0])
                    remote.append(run(bag, tmp / f'd{tag}{k}', scheduler=c.scheduler_address)[0])
                    same &= (tmp / f'd{tag}{k}' / 'chunks.csv').read_bytes() == reference
            return min(local), min(remote), same

        print(f'\n1. overhead, {args.jobs} workers, {n:,} samples x 3 axes (best of 2 runs each, '
              'local and Dask alternated)')
        _, chunks = run(bag, tmp / 'local', jobs=1)
        reference = (tmp / 'local' / 'chunks.csv').read_bytes()
        for default_env, what in ((True, "Dask's default worker env (MALLOC_TRIM_THRESHOLD_="
                                         '65536)'),
                                  (False, 'MALLOC_TRIM_THRESHOLD_ unset (docs/scale.md)')):
            ls, ds, same = side_by_side(args.jobs, default_env, tag=f'o{int(default_env)}')
            print(f'  {what}: local --jobs {args.jobs} {ls:.1f} s ({n / ls:,.0f} samples/s), '
                  f'Dask {args.jobs} x 1 thread {ds:.1f} s ({n / ds:,.0f} samples/s): ratio '
                  f'Dask / local time {ds / ls:.2f}; chunks.csv identical to --jobs 1: {same}')
        print(f'  ({chunks} chunk identifications; load average now {os.getloadavg()[0]:.1f})')

        print('\n2. throughput against workers (LocalCluster, 1 thread per worker process, '
              'MALLOC_TRIM_THRESHOLD_ unset; best of 2 alternated runs)')
        print('  | workers | local --jobs s | local samples/s | Dask s | Dask samples/s | '
              'Dask/local |')
        print('  |---:|---:|---:|---:|---:|---:|')
        for w in sizes:
            ls, ds, same = side_by_side(w, tag=f'w{w}')
            print(f'  | {w} | {ls:.1f} | {n / ls:,.0f} | {ds:.1f} | {n / ds:,.0f} | '
                  f'{ds / ls:.2f} |' + ('' if same else ' (chunks.csv DIFFERS)'))
        print(f'  (load average at the end {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)')
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
