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
SD-log import speed and memory: the bulk writer against the per-message path, side by side.

Paths, all through ``gyro_noise_ros.cli.importer.import_logs`` on the same log files (reading, link
decoding and scaling included):

* ``old``: ``bulk=False`` (the per-message :class:`ImuBagWriter` path of the current main, kept
  callable in the package for this comparison; one ``executemany`` row per message for sqlite3);
* ``rosbags``: ``bulk=False`` with :class:`ImuBagWriter`'s writes patched to call rosbags'
  ``Writer.write`` once per message (CDR still encoded in bulk: rosbags' own writer at its best);
* ``new``: ``bulk=True`` (:class:`gyro_noise_ros.bag.bulk.BulkImuBagWriter`).

Each for sqlite3 and MCAP storage; every path's bag is checked to hold the same message bytes.
Peak RSS: each (path, log size) imports in a fresh process; ``VmHWM`` of that process.

Run: ``.venv/bin/python bench/bench_import.py [--samples 400000]
[--rss-samples 100000,400000,1600000]``
"""

import argparse
import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.cli import importer
from gyro_noise_ros.link import protocol as p
from gyro_noise_ros.link.sdlog import SdLogWriter
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


def run_path(name, files, out, storage):
    """Import with one path; return seconds."""
    ctx = rosbags_per_message() if name == 'rosbags' else contextlib.nullcontext()
    with ctx:
        start = time.perf_counter()
        importer.import_logs(files, out, storage=storage, bulk=(name == 'new'))
        return time.perf_counter() - start


def gyro_of(bag):
    with ImuBagReader(bag) as reader:
        return np.concatenate([b.gyro for b in reader.iter_batches()])


HWM = ("\nprint(next(int(line.split()[1]) for line in open('/proc/self/status') "
       "if line.startswith('VmHWM:')))")


def peak_rss_mb(files, out, storage, bulk):
    """Import in a fresh process; return its peak RSS in MB."""
    code = ('import sys; from gyro_noise_ros.cli import importer; '
            'importer.import_logs(sys.argv[3:], sys.argv[1], storage=sys.argv[2], '
            f'bulk={bulk!r})' + HWM)
    # VmHWM of the child's own image (ru_maxrss would include the forking parent's peak)
    res = subprocess.run([sys.executable, '-c', code, out, storage, *files], check=True,
                         capture_output=True, text=True)
    return int(res.stdout.split()[-1]) / 1024.0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--samples', type=int, default=400_000, help='samples in the speed log')
    parser.add_argument('--rss-samples', default='100000,400000,1600000',
                        help='comma-separated log sizes (samples) for the peak-RSS table')
    args = parser.parse_args(argv)
    cores = len(os.sched_getaffinity(0))
    print(f'bench_import: {args.samples} samples, 1 process on {cores} visible core(s); '
          f'load average {os.getloadavg()[0]:.1f} '
          '(other work on the machine slows every path alike)')
    tmp = tempfile.mkdtemp(prefix='bench_import_')
    try:
        files = make_logs(os.path.join(tmp, 'logs'), args.samples)
        size_mb = sum(os.path.getsize(f) for f in files) / 1e6
        print(f'log: {len(files)} file(s), {size_mb:.1f} MB')
        # warm-up: imports, page cache of the log files
        importer.import_logs(files, os.path.join(tmp, 'warm'), storage='mcap')
        times, reference = {}, None
        for storage in ('sqlite3', 'mcap'):
            for name in ('old', 'rosbags', 'new'):
                out = os.path.join(tmp, f'{name}_{storage}')
                times[name, storage] = run_path(name, files, out, storage)
                gyro = gyro_of(out)
                if reference is None:
                    reference = gyro
                elif not np.array_equal(gyro.view(np.uint64), reference.view(np.uint64)):
                    raise SystemExit(f'{name} {storage}: messages differ from the first path')
                shutil.rmtree(out)
        base = times['old', 'sqlite3']
        print(f'{"path":<10s} {"storage":<8s} {"samples/s":>12s} {"vs old sqlite3":>15s} '
              f'{"vs same storage old":>20s} {"vs rosbags Writer":>18s}')
        for storage in ('sqlite3', 'mcap'):
            for name in ('old', 'rosbags', 'new'):
                t = times[name, storage]
                print(f'{name:<10s} {storage:<8s} {args.samples / t:>12,.0f} {base / t:>14.1f}x '
                      f'{times["old", storage] / t:>19.1f}x '
                      f'{times["rosbags", storage] / t:>17.1f}x')
        print('\npeak RSS of one import process (MB) against log size')
        print(f'{"samples":>10s} {"log MB":>8s} {"old sqlite3":>12s} {"new sqlite3":>12s} '
              f'{"new mcap":>10s}')
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
