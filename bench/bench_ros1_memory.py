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
Peak memory reading ROS 1 bags: rosbags' indexing reader against the chunk-streaming reader.

rosbags' ``rosbag1.Reader.open`` keeps one index entry per message; :class:`ImuBagReader` on a
ROS 1 bag (chunks in time order, as ``rosbag record`` writes them) reads only the chunk list and
streams each chunk's records. Each measurement runs in a fresh process (its ``VmHWM``):

* ``baseline``: the same imports, no bag opened;
* ``rosbags``: ``rosbags.rosbag1.Reader`` opened on the bag (messages not even read);
* ``streamed``: every Imu message of the bag decoded by ``ImuBagReader.iter_batches``.

The slope of ``rosbags`` over the message count is the per-message index cost used by
``gyro_noise_ros.bag.storage.ROS1_INDEX_BYTES_PER_MESSAGE``.

Run: ``.venv/bin/python bench/bench_ros1_memory.py [--messages 200000,800000,3200000]``
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile

from gyro_noise_ros.msgs import IMU_MSGTYPE
import numpy as np
from rosbags.rosbag1 import Writer
from rosbags.typesys import get_typestore, Stores

HWM = ("\nprint(next(int(line.split()[1]) for line in open('/proc/self/status') "
       "if line.startswith('VmHWM:')))")
CHILD = {
    'baseline': ('import sys, numpy, rosbags.rosbag1, gyro_noise_ros.bag'),
    'rosbags': ('import sys, numpy, gyro_noise_ros.bag\n'
                'from rosbags.rosbag1 import Reader\n'
                'r = Reader(sys.argv[1]); r.open(); n = sum(len(v) for v in r.indexes.values())\n'
                'assert n > 0'),
    'streamed': ('import sys, numpy, rosbags.rosbag1\n'
                 'from gyro_noise_ros.bag import ImuBagReader\n'
                 'with ImuBagReader(sys.argv[1]) as r:\n'
                 '    n = sum(len(b) for b in r.iter_batches())\n'
                 'assert n == r.message_count, (n, r.message_count)'),
}


def ros1_raws(n, start):
    """ROS 1 sensor_msgs/Imu bytes (seq, stamp, 'imu_link', 37 float64) built with numpy."""
    stamps = 1_700_000_000 * 10 ** 9 + (start + np.arange(n, dtype=np.int64)) * 150_000
    head = 24
    rows = np.zeros((n, head + 296), np.uint8)
    rows[:, 0:4] = (start + np.arange(n, dtype='<u4')).view(np.uint8).reshape(n, 4)
    rows[:, 4:8] = (stamps // 10 ** 9).astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 8:12] = (stamps % 10 ** 9).astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 12:16] = np.frombuffer(np.array(8, '<u4').tobytes(), np.uint8)
    rows[:, 16:24] = np.frombuffer(b'imu_link', np.uint8)
    tail = np.zeros((n, 37))
    tail[:, 3] = 1.0
    tail[:, 4] = -1.0
    tail[:, 13:16] = np.random.default_rng(start).normal(size=(n, 3))
    rows[:, head:] = tail.astype('<f8').view(np.uint8)
    blob = rows.tobytes()
    size = rows.shape[1]
    return stamps.tolist(), [blob[i:i + size] for i in range(0, n * size, size)]


def write_bag(path, n):
    store = get_typestore(Stores.ROS1_NOETIC)
    with Writer(path) as writer:
        conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=store)
        for start in range(0, n, 1 << 16):
            stamps, raws = ros1_raws(min(1 << 16, n - start), start)
            for t, raw in zip(stamps, raws):
                writer.write(conn, t, raw)


def peak_mb(kind, path):
    """Peak RSS (VmHWM: of the new process image only, not the forking parent's) in MB."""
    out = subprocess.run([sys.executable, '-c', CHILD[kind] + HWM, path], check=True,
                         capture_output=True, text=True).stdout
    return int(out.split()[-1]) / 1024.0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--messages', default='200000,800000,3200000',
                        help='comma-separated bag sizes (Imu messages)')
    args = parser.parse_args(argv)
    sizes = [int(v) for v in args.messages.split(',')]
    print(f'bench_ros1_memory: 1 process at a time on {len(os.sched_getaffinity(0))} visible '
          f'core(s); load average {os.getloadavg()[0]:.1f} (memory is not affected by the load)')
    print(f'{"messages":>10s} {"bag MB":>8s} {"baseline MB":>12s} {"rosbags MB":>11s} '
          f'{"streamed MB":>12s}')
    tmp = tempfile.mkdtemp(prefix='bench_ros1_')
    rows = []
    try:
        for n in sizes:
            path = os.path.join(tmp, f'imu{n}.bag')
            write_bag(path, n)
            mb = os.path.getsize(path) / 1e6
            cells = [peak_mb(kind, path) for kind in ('baseline', 'rosbags', 'streamed')]
            rows.append((n, cells))
            os.remove(path)
            print(f'{n:>10d} {mb:>8.1f} {cells[0]:>12.0f} {cells[1]:>11.0f} {cells[2]:>12.0f}')
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if len(rows) > 1:
        (n0, c0), (n1, c1) = rows[0], rows[-1]
        for i, kind in ((1, 'rosbags'), (2, 'streamed')):
            slope = (c1[i] - c0[i]) * 2 ** 20 / (n1 - n0)
            print(f'{kind}: {slope:.0f} B more peak memory per message '
                  f'({n0} -> {n1} messages)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
