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
What reading and repairing a killed recording costs, as ratios against the finished recording.

Builds, in a temporary folder, one recording per storage of N Imu messages (and one Temperature
per 128) as :class:`gyro_noise_ros.bag.ImuBagWriter` writes them, then a killed copy of each:

* MCAP: the file cut at 90 % of its size (no summary, no footer, the last chunk cut);
* sqlite3: the file plus an unfinished transaction of 5 % more rows left in a hot journal by a
  child process that dies without committing.

Times, side by side in this process: opening and reading every Imu message with
:class:`ImuBagReader` from the killed copy (index walk / rolled-back copy included) against the
finished bag, per message read; and ``repair_bag`` of the killed copy against rosbags' own
per-message copy (``Reader.messages`` + ``Writer.write``) of the finished bag, per message
written.

Run: ``.venv/bin/python bench/bench_recover.py [--messages 1000000]``
"""

import argparse
from pathlib import Path
import shlex
import subprocess
import sys
import tempfile
import time

from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.bag.repair import repair_bag
import numpy as np
from rosbags.rosbag2 import Reader, StoragePlugin, Writer


def _write(path, storage, n):
    rng = np.random.default_rng(1)
    stamps = 1_700_000_000_000_000_000 + np.rint(np.arange(n) * (1e9 / 6660)).astype(np.int64)
    with ImuBagWriter(path, storage=storage) as writer:
        for i in range(0, n, 65536):
            part = stamps[i:i + 65536]
            writer.write_imu(part, rng.standard_normal((part.size, 3)) * 0.004,
                             rng.standard_normal((part.size, 3)))
            writer.write_temperature(part[::128], np.full(part[::128].size, 25.0))


def _kill(full, killed, storage, n):
    killed.mkdir()
    (src,) = [p for p in full.iterdir() if p.suffix in ('.db3', '.mcap')]
    target = killed / f'{killed.name}{src.suffix}'
    if storage == 'mcap':
        data = src.read_bytes()
        target.write_bytes(data[:int(len(data) * 0.9)])
        return
    target.write_bytes(src.read_bytes())
    code = ('import os, sqlite3; c = sqlite3.connect(%r); c.execute("PRAGMA cache_size=1");'
            'c.execute("BEGIN"); c.executemany("INSERT INTO messages (topic_id, timestamp, data) '
            'VALUES (1, ?, ?)", ((i, bytes(324)) for i in range(%d))); os._exit(0)')
    subprocess.run([sys.executable, '-c', code % (str(target), n // 20)], check=True)


def _read(path):
    start = time.perf_counter()
    with ImuBagReader(path) as reader:
        n = sum(len(b) for b in reader.iter_batches(65536))
    return n, time.perf_counter() - start


def _rosbags_copy(src, out, storage):
    start = time.perf_counter()
    plugin = StoragePlugin.SQLITE3 if storage == 'sqlite3' else StoragePlugin.MCAP
    n = 0
    with Reader(src) as reader, Writer(out, version=9, storage_plugin=plugin) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data,
                                             rihs01=c.digest) for c in reader.connections}
        for conn, t, raw in reader.messages():
            writer.write(conns[conn.id], t, raw)
            n += 1
    return n, time.perf_counter() - start


def main(argv=None):
    """Run the benchmark and print one table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--messages', type=int, default=1_000_000)
    args = p.parse_args(argv)
    print('command: python bench/bench_recover.py ' + shlex.join(argv or sys.argv[1:]))
    print(f'{args.messages:,} Imu messages per recording; rates in messages/s')
    print(f'{"":34s}{"finished":>12s}{"killed":>12s}{"ratio":>8s}')
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for storage in ('mcap', 'sqlite3'):
            full, killed = tmp / f'full_{storage}', tmp / f'killed_{storage}'
            _write(full, storage, args.messages)
            _kill(full, killed, storage, args.messages)
            n_full, t_full = _read(full)
            n_killed, t_killed = _read(killed)
            r_full, r_killed = n_full / t_full, n_killed / t_killed
            print(f'{"read Imu, " + storage:34s}{r_full:12,.0f}{r_killed:12,.0f}'
                  f'{r_killed / r_full:7.2f}x   ({n_killed:,} of {n_full:,} readable)')
            n_base, t_base = _rosbags_copy(full, tmp / f'copy_{storage}', storage)
            start = time.perf_counter()
            res = repair_bag(killed, tmp / f'repaired_{storage}')
            t_rep = time.perf_counter() - start
            base, rep = n_base / t_base, res.messages / t_rep
            print(f'{"rosbags copy vs repair, " + storage:34s}{base:12,.0f}{rep:12,.0f}'
                  f'{rep / base:7.2f}x')
    return 0


if __name__ == '__main__':
    sys.exit(main())
