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
SD-log import speed and memory: old path, rosbags' writer and the new path, side by side.

Paths, all through ``gyro_noise_ros.app.importer.import_logs`` on the same log files (reading, link
decoding, scaling and writing included):

* ``old``: ``bulk=False``: the byte-wise :class:`Decoder` and the per-message
  :class:`ImuBagWriter` (one ``executemany`` row per message for sqlite3), kept callable in the
  package as this baseline;
* ``rosbags``: the new frame scanner, then :class:`ImuBagWriter` patched to call rosbags'
  ``Writer.write`` once per message (CDR still encoded in bulk: rosbags' own writer at its best);
* ``bulk``: the bulk writer behind the byte-wise Decoder (``scan=False``: the previous session's
  new path, to show what the scanner adds);
* ``new-1t``: :class:`gyro_noise_ros.link.scan.ScanDecoder` and
  :class:`gyro_noise_ros.bag.bulk.BulkImuBagWriter` in one thread (``threads=1``);
* ``new``: the defaults: the same, with the bag written by a second thread while the next blocks
  are decoded (``threads=2`` when two CPUs are usable, as here).

The old, rosbags and bulk paths run in one thread, as the old importer did. Each for sqlite3
and MCAP storage (MCAP is the default). Rounds are interleaved (every path once
per round, the order rotated) so that a change of the machine's load hits every path alike; the
table gives the median time per path and the median over rounds of the per-round ratio. Every
path's bag is checked (first round) to hold the same message bytes. ``disk floor``: the time to
write as many bytes as the new MCAP bag holds, from memory in 1 MiB writes, into the same
directory: what a single thread writing the bytes alone costs. On a virtual machine that hands
freed memory back to its host, writing into page-cache memory not touched for a while costs
several times more than into recently freed memory, so this row (like every row, less visibly)
varies from round to round; each round's time is printed too. ``read only``: iterating
``SdLogReader`` over the log with the byte-wise Decoder or the scanner, nothing written (the
reading share of an import). Peak RSS:
each (path, log size) imports in a fresh process; ``VmHWM`` of that process. ``--baseline PATH``
adds the importer of older code (e.g. ``git worktree add --detach /tmp/base 12f9979``, the code
before the importer's speed-up) run in a fresh process with ``PYTHONPATH=PATH``, in sqlite3 (its
default) and MCAP, in the same rounds; its second ``import_logs`` call is timed (the first warms
up, as the warm-up below does for this code).

Run: ``.venv/bin/python bench/bench_import.py [--samples 1000000] [--rounds 3] [--out-dir DIR]
[--rss-samples 250000,1000000,4000000] [--baseline PATH]``
"""

import argparse
import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

from gyro_noise_ros.app import importer
from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.link import protocol as p
from gyro_noise_ros.link.sdlog import SdLogReader, SdLogWriter
import numpy as np


def make_logs(directory, n, seed=0):
    """Write ``n`` samples at 6.66 kHz (random, 16 per frame) in 64 MB logs; return paths."""
    os.makedirs(directory, exist_ok=True)
    rng = np.random.default_rng(seed)
    with SdLogWriter(directory, sequence_id=1, odr_hz=6667.0, gyro_fs_dps=500, accel_fs_g=8,
                     max_file_bytes=64 << 20, rtc_unix_s=1_700_000_000) as writer:
        for start in range(0, n, 1 << 18):
            k = min(1 << 18, n - start)
            s = np.zeros(k, p.SAMPLE_DTYPE)
            s['seq'] = np.arange(start, start + k)
            s['t_us'] = (np.arange(start, start + k) * 150) % (1 << 32)
            s['gyro'] = rng.integers(-30000, 30000, (k, 3))
            s['accel'] = rng.integers(-30000, 30000, (k, 3))
            s['temp'] = rng.integers(-500, 500, k)
            writer.write_samples(s)
        return list(writer.paths)


@contextlib.contextmanager
def rosbags_per_message():
    """Make ImuBagWriter call rosbags' Writer.write once per message."""
    original = ImuBagWriter._write

    def per_message(self, conn, log_ns, blobs):
        for t, blob in zip(log_ns.tolist(), blobs):
            self._writer.write(conn, t, blob)

    ImuBagWriter._write = per_message
    try:
        yield
    finally:
        ImuBagWriter._write = original


PATHS = {
    'old': {'bulk': False, 'scan': False, 'threads': 1},
    'rosbags': {'bulk': False, 'scan': True, 'threads': 1},
    'bulk': {'bulk': True, 'scan': False, 'threads': 1},
    'new-1t': {'threads': 1},
    'new': {},
}


def run_path(name, files, out, storage):
    """Import with one path; return (wall seconds, CPU seconds of the process, all threads)."""
    ctx = rosbags_per_message() if name == 'rosbags' else contextlib.nullcontext()
    with ctx:
        cpu, start = time.process_time(), time.perf_counter()
        importer.import_logs(files, out, storage=storage, **PATHS[name])
        return time.perf_counter() - start, time.process_time() - cpu


BASELINE_SCRIPT = """
import os, sys, time
try:
    from gyro_noise_ros.app import importer
except ImportError:  # a baseline from before the application layer
    from gyro_noise_ros.cli import importer
files, out, storage = sys.argv[1].split(os.pathsep), sys.argv[2], sys.argv[3]
importer.import_logs(files, out + '_warm', storage=storage)  # imports, caches, as for 'new'
cpu, start = time.process_time(), time.perf_counter()
importer.import_logs(files, out, storage=storage)
print(time.perf_counter() - start, time.process_time() - cpu)
"""


def run_baseline(root, files, out, storage):
    """
    Import with the code under ``root`` (e.g. a worktree of older code) in a fresh process.

    Returns (wall seconds, CPU seconds) of its second ``import_logs`` call (the first warms up).
    """
    env = dict(os.environ, PYTHONPATH=root)
    proc = subprocess.run([sys.executable, '-c', BASELINE_SCRIPT, os.pathsep.join(files), out,
                           storage], env=env, cwd=os.path.dirname(out), capture_output=True,
                          text=True)
    if proc.returncode != 0:
        raise SystemExit(f'baseline {root}: exit {proc.returncode}: {proc.stderr.strip()}')
    shutil.rmtree(out + '_warm', ignore_errors=True)
    wall, cpu = (float(v) for v in proc.stdout.split())
    return wall, cpu


def _git_head(root):
    out = subprocess.run(['git', '-C', root, 'rev-parse', '--short', 'HEAD'],
                         capture_output=True, text=True)
    return out.stdout.strip() or '?'


def read_only(files, scan):
    """Iterate the logs with SdLogReader; return (wall seconds, CPU seconds)."""
    cpu, start = time.process_time(), time.perf_counter()
    for _ in SdLogReader(files, scan=scan):
        pass
    return time.perf_counter() - start, time.process_time() - cpu


def disk_floor(directory, nbytes):
    """Write ``nbytes`` from memory in 1 MiB writes to a new file in ``directory``; seconds."""
    block = np.full(1 << 20, 7, np.uint8)
    path = os.path.join(directory, 'floor.bin')
    cpu, start = time.process_time(), time.perf_counter()
    with open(path, 'wb') as fh:
        for _ in range(nbytes >> 20):
            fh.write(block)
        fh.write(block[:nbytes & ((1 << 20) - 1)])
    seconds = time.perf_counter() - start, time.process_time() - cpu
    os.remove(path)
    return seconds


def bag_bytes(bag):
    return sum(os.path.getsize(os.path.join(bag, f)) for f in os.listdir(bag))


def gyro_of(bag):
    with ImuBagReader(bag) as reader:
        return np.concatenate([b.gyro for b in reader.iter_batches()])


HWM = ("\nprint(next(int(line.split()[1]) for line in open('/proc/self/status') "
       "if line.startswith('VmHWM:')))")


def peak_rss_mb(files, out, storage, bulk):
    """Import in a fresh process; return its peak RSS in MB."""
    code = ('import sys; from gyro_noise_ros.app import importer; '
            'importer.import_logs(sys.argv[3:], sys.argv[1], storage=sys.argv[2], '
            f'bulk={bulk!r})' + HWM)
    # VmHWM of the child's own image (ru_maxrss would include the forking parent's peak)
    res = subprocess.run([sys.executable, '-c', code, out, storage, *files], check=True,
                         capture_output=True, text=True)
    return int(res.stdout.split()[-1]) / 1024.0


def _x(value):
    return '-' if np.isnan(value) else f'{value:.1f}x'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--samples', type=int, default=1_000_000, help='samples in the speed log')
    parser.add_argument('--rounds', type=int, default=3, help='interleaved rounds')
    parser.add_argument('--out-dir', default=None,
                        help='where logs and bags go (default: a temporary directory)')
    parser.add_argument('--rss-samples', default='250000,1000000,4000000',
                        help='comma-separated log sizes (samples) for the peak-RSS table '
                        '(empty: skip)')
    parser.add_argument('--baseline', default=None, metavar='PATH',
                        help='also time the importer of the code under PATH (a worktree of older '
                        'code, e.g. the commit the issue was filed against) in a fresh process, '
                        'sqlite3 and MCAP, in the same rounds')
    args = parser.parse_args(argv)
    cores = len(os.sched_getaffinity(0))
    print(f'bench_import: {args.samples} samples, 1 process (one thread, or two for "new"), on '
          f'{cores} visible core(s); load average {os.getloadavg()[0]:.1f} at the start (other '
          'work on the machine slows every path)')
    tmp = tempfile.mkdtemp(prefix='bench_import_', dir=args.out_dir)
    try:
        files = make_logs(os.path.join(tmp, 'logs'), args.samples)
        size_mb = sum(os.path.getsize(f) for f in files) / 1e6
        print(f'log: {len(files)} file(s), {size_mb:.1f} MB; bags in {tmp}')
        # warm-up: imports, numba kernels, page cache of the log files
        importer.import_logs(files, os.path.join(tmp, 'warm'), storage='mcap')
        shutil.rmtree(os.path.join(tmp, 'warm'))
        runs = [(name, storage) for storage in ('sqlite3', 'mcap') for name in PATHS]
        if args.baseline:
            base = os.path.abspath(args.baseline)
            print(f'baseline: {base} (git {_git_head(base)}), run in a fresh process; its '
                  'second import_logs call is timed')
            runs += [('baseline', 'sqlite3'), ('baseline', 'mcap')]
        runs += [('disk floor', 'mcap'), ('read only', 'Decoder'), ('read only', 'scanner')]
        times = {run: [] for run in runs}
        loads = []
        reference, mcap_bytes = None, None
        for rnd in range(args.rounds):
            shift = rnd % len(runs)
            for name, storage in runs[shift:] + runs[:shift]:
                if name == 'read only':
                    times[name, storage].append(read_only(files, storage == 'scanner'))
                    continue
                if name == 'disk floor':
                    if mcap_bytes is not None:
                        times[name, storage].append(disk_floor(tmp, mcap_bytes))
                    continue
                out = os.path.join(tmp, f'{name}_{storage}')
                if name == 'baseline':
                    times[name, storage].append(run_baseline(base, files, out, storage))
                else:
                    times[name, storage].append(run_path(name, files, out, storage))
                if name == 'new-1t' and storage == 'mcap':
                    mcap_bytes = bag_bytes(out)
                if rnd == 0:
                    gyro = gyro_of(out)
                    if reference is None:
                        reference = gyro
                    elif not np.array_equal(gyro.view(np.uint64), reference.view(np.uint64)):
                        raise SystemExit(f'{name} {storage}: messages differ from the first path')
                shutil.rmtree(out)
            loads.append(os.getloadavg()[0])
        if not times['disk floor', 'mcap']:
            times['disk floor', 'mcap'].append(disk_floor(tmp, mcap_bytes))
        print(f'{args.rounds} interleaved round(s); load average after each: '
              + ', '.join(f'{v:.1f}' for v in loads))
        med = {run: float(np.median([w for w, _ in v])) for run, v in times.items()}
        cpu = {run: float(np.median([c for _, c in v])) for run, v in times.items()}

        def ratio(a, b):
            """Median over rounds of wall time(b) / wall time(a) (nan: no such path)."""
            if b not in times:
                return float('nan')
            k = min(len(times[a]), len(times[b]))
            return float(np.median([times[b][i][0] / times[a][i][0] for i in range(k)]))

        print(f'{"path":<11s} {"storage":<8s} {"samples/s":>11s} {"vs old sqlite3":>15s} '
              f'{"vs old, same storage":>21s} {"vs rosbags Writer, same storage":>32s}')
        for name, storage in runs:
            run = (name, storage)
            cells = [ratio(run, ('old', 'sqlite3')), ratio(run, ('old', storage)),
                     ratio(run, ('rosbags', storage))]
            print(f'{name:<11s} {storage:<8s} {args.samples / med[run]:>11,.0f} '
                  f'{_x(cells[0]):>15s} {_x(cells[1]):>21s} {_x(cells[2]):>32s}')
        if args.baseline:
            b_sql, b_mcap = ('baseline', 'sqlite3'), ('baseline', 'mcap')
            for name in ('new', 'new-1t'):
                print(f'{name} mcap against the baseline: {_x(ratio((name, "mcap"), b_sql))} '
                      f'(its sqlite3), {_x(ratio((name, "mcap"), b_mcap))} (its MCAP); {name} '
                      f'sqlite3 against its sqlite3: {_x(ratio((name, "sqlite3"), b_sql))}; CPU '
                      f'{_x(cpu[b_sql] / cpu[name, "mcap"])}, '
                      f'{_x(cpu[b_mcap] / cpu[name, "mcap"])}, '
                      f'{_x(cpu[b_sql] / cpu[name, "sqlite3"])}')
        floor = [w for w, _ in times['disk floor', 'mcap']]
        print(f'(disk floor: {mcap_bytes / 1e6:.0f} MB, the size of the MCAP bag, in '
              + ', '.join(f'{w:.3f}' for w in floor) + ' s by round; median seconds: '
              + ', '.join(f'{n} {s} {med[n, s]:.3f}' for n, s in runs) + ')')
        print('\nCPU seconds of the importing process (all threads, system time included; less '
              'sensitive to the load than wall time)')
        print(f'{"path":<11s} {"storage":<8s} {"CPU s":>7s} {"vs old sqlite3":>15s} '
              f'{"vs old, same storage":>21s} {"vs rosbags Writer, same storage":>32s}')
        for name, storage in runs:
            run = (name, storage)
            print(f'{name:<11s} {storage:<8s} {cpu[run]:>7.3f} '
                  f'{_x(cpu["old", "sqlite3"] / cpu[run]):>15s} '
                  f'{_x(cpu.get(("old", storage), float("nan")) / cpu[run]):>21s} '
                  f'{_x(cpu.get(("rosbags", storage), float("nan")) / cpu[run]):>32s}')
        if not args.rss_samples:
            return 0
        print('\npeak RSS of one import process (MB) against log size')
        print(f'{"samples":>10s} {"log MB":>8s} {"old sqlite3":>12s} {"new sqlite3":>12s} '
              f'{"new mcap":>10s}   (new: default threads)')
        for n in (int(v) for v in args.rss_samples.split(',')):
            logs = make_logs(os.path.join(tmp, f'rss{n}'), n)
            mb = sum(os.path.getsize(f) for f in logs) / 1e6
            cells = []
            for storage, bulk in (('sqlite3', False), ('sqlite3', True), ('mcap', True)):
                out = os.path.join(tmp, f'rss_bag_{n}_{storage}_{bulk}')
                cells.append(peak_rss_mb(logs, out, storage, bulk))
                shutil.rmtree(out)
            shutil.rmtree(os.path.join(tmp, f'rss{n}'))
            print(f'{n:>10d} {mb:>8.1f} {cells[0]:>12.0f} {cells[1]:>12.0f} {cells[2]:>10.0f}')
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
