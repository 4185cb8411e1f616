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
Full-tool throughput of gyro_noise_analyze on a multi-million-sample 3-axis bag.

Writes one simulated bag (the paper's model, 3 axes, 6660 Hz) into a temporary directory, then:

* without ``--baseline``: runs the whole tool in this process with ``--jobs 1`` and ``--jobs 2``
  and prints samples per second, the ratio and the share of the time spent decoding;
* with ``--baseline PATH`` (a checkout of older code, e.g. ``git worktree add --detach
  /tmp/base <commit>``): runs ``gyro_noise_analyze BAG --no-figures --quiet --jobs J`` of the old
  code (``PYTHONPATH=PATH``) and of this code side by side on the same bag, alternating, each in
  a fresh process (imports, numba cache loads and all), and prints for each the wall time, the
  samples per second, the CPU seconds of the process tree, the ratios, the cores and the load
  average, and whether every output file is bit-identical (chunks.csv, allan.csv, imu.yaml,
  curves.npz arrays, summary.json without its creation time and command line).

Usage::

    .venv/bin/python bench/bench_analyze.py [--samples 2000000] [--storage sqlite3]
        [--baseline PATH] [--jobs 2] [--curves 200] [--rounds 2] [--bag EXISTING_BAG]
"""

import argparse
import json
import os
from pathlib import Path
import resource
import shutil
import subprocess
import sys
import tempfile
import time

from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.core.engine import AXES, EngineConfig, NoiseEngine
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np

RATE_HZ = 6660.0
ROOT = Path(__file__).resolve().parent.parent


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


def run_tool(code_root, bag, out, jobs, curves, workdir):
    """Run gyro_noise_analyze of the code under ``code_root`` in a fresh process; time it."""
    env = dict(os.environ, PYTHONPATH=str(code_root))
    cmd = [sys.executable, '-m', 'gyro_noise_ros.cli.analyze', str(bag), '--out', str(out),
           '--jobs', str(jobs), '--no-figures', '--quiet', '--curves', str(curves)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    # cwd outside both checkouts, so that PYTHONPATH decides which code is imported
    proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f'{code_root}: exit {proc.returncode}: {proc.stderr.strip()}')
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _imported_from(code_root, workdir):
    out = subprocess.run(
        [sys.executable, '-c', 'import gyro_noise_ros; print(gyro_noise_ros.__file__)'],
        cwd=workdir, env=dict(os.environ, PYTHONPATH=str(code_root)), capture_output=True,
        text=True, check=True).stdout.strip()
    return Path(out).resolve().parent.parent


def _json_diff(x, y, path=''):
    """Yield (path, left, right) for every difference between two JSON values."""
    if isinstance(x, dict) and isinstance(y, dict):
        for k in sorted(set(x) | set(y)):
            yield from _json_diff(x.get(k, _MISSING), y.get(k, _MISSING), f'{path}.{k}')
    elif isinstance(x, list) and isinstance(y, list) and len(x) == len(y):
        for i, (u, w) in enumerate(zip(x, y)):
            yield from _json_diff(u, w, f'{path}[{i}]')
    elif x != y or type(x) is not type(y):
        yield path, x, y


_MISSING = object()


def compare_outputs(a, b):
    """
    Return a list of (file, identical, note) for the report files of two runs.

    Every file must be bit-identical, with two stated exceptions that are not results: keys that
    only the new run's summary.json has, holding null (options added since, left unset); and
    the criterion curves of curves.npz, which must equal the oracle to 1e-9 relative (the
    default algorithm returns the fast curves with the exact values where a minimum can be):
    compared to rtol 1e-9, and their minima (the reported values) bit for bit.
    """
    rows = []
    for name in ('chunks.csv', 'allan.csv', 'imu.yaml', 'summary.md'):
        rows.append((name, (a / name).read_bytes() == (b / name).read_bytes(), ''))
    da, db = (json.loads((d / 'summary.json').read_text()) for d in (a, b))
    for d in (da, db):
        d.pop('created_utc', None)
        d.pop('command', None)
    diffs = list(_json_diff(da, db))
    added = [p for p, x, y in diffs if x is _MISSING and y is None]
    rows.append(('summary.json (without created_utc, command)', len(diffs) == len(added),
                 f'new null option key(s) only in the new run: {", ".join(added)}'
                 if added else ''))
    ca, cb = (a / 'curves.npz'), (b / 'curves.npz')
    if ca.exists() or cb.exists():
        same, note = ca.exists() and cb.exists(), ''
        if same:
            with np.load(ca) as za, np.load(cb) as zb:
                same = sorted(za.files) == sorted(zb.files)
                worst, bitwise = 0.0, True
                for k in za.files if same else ():
                    x, y = za[k], zb[k]
                    if x.dtype != y.dtype or x.shape != y.shape:
                        same = False
                        continue
                    if np.array_equal(x, y, equal_nan=x.dtype.kind == 'f'):
                        continue
                    bitwise = False
                    if x.dtype.kind != 'f' or not k.endswith(('var', 'j', 'f')):
                        same = False
                        continue
                    ok = np.isfinite(x)
                    if not np.array_equal(ok, np.isfinite(y)):
                        same = False
                        continue
                    rel = np.abs(x[ok] - y[ok]) / np.maximum(np.abs(x[ok]), 1e-300)
                    worst = max(worst, float(rel.max()))
                    lows = (x.min(axis=-1) if k.endswith(('var', 'j')) else None)
                    if lows is not None and not np.array_equal(lows, y.min(axis=-1)):
                        same = False
                if same and not bitwise:
                    same = worst <= 1e-9
                    note = (f'criterion curves within {worst:.1e} relative (required: 1e-9), '
                            'minima bit-identical')
        rows.append(('curves.npz (every array)', same, note))
    return rows


def side_by_side(args, bag, tmp):
    base = Path(args.baseline).resolve()
    for root in (base, ROOT):
        got = _imported_from(root, tmp)
        if got != root:
            raise SystemExit(f'PYTHONPATH={root} imports gyro_noise_ros from {got}')
    print(f'baseline: {base} (git {_git_head(base)}); new: {ROOT} (git {_git_head(ROOT)})')
    print(f'gyro_noise_analyze BAG --no-figures --quiet --jobs {args.jobs} --curves {args.curves}'
          f' ({args.samples:,} samples x 3 axes, full grid 0:2:0.01, both methods, Allan on)')
    runs = {'baseline': [], 'new': []}
    load = [os.getloadavg()[0]]
    for r in range(args.rounds):
        order = (('baseline', base), ('new', ROOT)) if r % 2 == 0 else (('new', ROOT),
                                                                        ('baseline', base))
        for name, root in order:
            out = tmp / f'out_{name}_{r}'
            wall, cpu = run_tool(root, bag, out, args.jobs, args.curves, tmp)
            runs[name].append((wall, cpu, out))
            load.append(os.getloadavg()[0])
            print(f'  round {r + 1} {name:8s}: {wall:6.1f} s wall, '
                  f'{args.samples / wall:9,.0f} samples/s, {cpu:6.1f} CPU s')
    best = {k: min(v, key=lambda x: x[0]) for k, v in runs.items()}
    cpu = {k: min(x[1] for x in v) for k, v in runs.items()}
    print(f'best of {args.rounds}: baseline {args.samples / best["baseline"][0]:,.0f} samples/s, '
          f'new {args.samples / best["new"][0]:,.0f} samples/s: '
          f'end-to-end speed-up {best["baseline"][0] / best["new"][0]:.2f}x '
          f'(CPU seconds {cpu["baseline"]:.1f} -> {cpu["new"]:.1f}: '
          f'{cpu["baseline"] / cpu["new"]:.2f}x less work)')
    print(f'cores: {os.cpu_count()} ({len(os.sched_getaffinity(0))} usable), --jobs {args.jobs}; '
          f'load average (1 min) from {min(load):.1f} to {max(load):.1f} during the runs '
          '(shared machine: other work competes)')
    identical = True
    for name, same, note in compare_outputs(best['baseline'][2], best['new'][2]):
        identical &= same
        word = ('same' if note else 'bit-identical') if same else 'DIFFERENT'
        print(f'  {name}: {word}' + (f' ({note})' if note else ''))
    print('results bit-identical: ' + ('yes' if identical else 'NO'))
    return 0 if identical else 1


def _git_head(root):
    try:
        return subprocess.run(['git', '-C', str(root), 'rev-parse', '--short', 'HEAD'],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return '?'


def in_process(args, bag, tmp):
    from gyro_noise_ros.app.analyze import analyze_bags, AnalyzeParams

    axes = AXES if args.axis == 'all' else (args.axis,)
    # Load the numba caches (Allan kernels) once here so that neither timed run pays for it.
    warm = NoiseEngine(EngineConfig(axes=axes, chunk_size=2000, memory=100))
    rng = np.random.default_rng(0)
    warm.ingest(np.arange(3000, dtype=np.int64) * 150_150, rng.normal(size=(3000, 3)))
    warm.summary()
    rows = []
    for jobs in (1, 2):
        result = analyze_bags(AnalyzeParams(paths=(bag,), out_dir=tmp / f'out{jobs}',
                                            config=EngineConfig(axes=axes), jobs=jobs,
                                            figures=False, curves=args.curves))
        tm = result.timing
        rows.append((jobs, tm['total_s'], tm['decode_s']))
        chunks = sum(a['chunks'] for a in result.bags[0]['axes'].values())
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
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    p.add_argument('--samples', type=int, default=2_000_000)
    p.add_argument('--storage', default='sqlite3', choices=('sqlite3', 'mcap'))
    p.add_argument('--axis', default='all', choices=[*AXES, 'all'])
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--curves', type=int, default=200,
                   help='--curves of the tool (chunks per axis whose curves are kept; 200)')
    p.add_argument('--baseline', default=None, metavar='PATH',
                   help='checkout of the code to compare with, side by side')
    p.add_argument('--jobs', type=int, default=2, help='--jobs of both runs (--baseline mode)')
    p.add_argument('--rounds', type=int, default=2,
                   help='alternating rounds of baseline and new (--baseline mode)')
    p.add_argument('--bag', type=Path, default=None,
                   help='use this existing bag instead of writing one (--samples: its size)')
    p.add_argument('--workdir', type=Path, default=None,
                   help='where the bag goes (default: a temp dir)')
    args = p.parse_args(argv)
    print('command:', ' '.join([os.path.basename(sys.executable), *sys.argv]))
    print(f'cores: {os.cpu_count()} (shared machine; timings are noisy)')
    tmp = Path(tempfile.mkdtemp(prefix='bench_analyze_', dir=args.workdir))
    try:
        if args.bag is None:
            bag = tmp / 'bag'
            t = time.perf_counter()
            write_bag(bag, args.samples, args.storage, args.seed)
            size_mb = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
            print(f'wrote {args.samples:,} samples ({args.storage}, {size_mb:.0f} MB) in '
                  f'{time.perf_counter() - t:.1f} s')
        else:
            bag = args.bag.resolve()
        n, dt = decode_only(bag)
        args.samples = n
        print(f'decode only (ImuBagReader.iter_batches): {n / dt:,.0f} samples/s ({dt:.1f} s)')
        if args.baseline:
            return side_by_side(args, bag, tmp)
        return in_process(args, bag, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
