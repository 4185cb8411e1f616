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
Bulk sensor_msgs/Imu decoding of gyro_noise_ros.bag against rosbags' per-message deserialiser.

Builds one bag per storage (sqlite3, mcap) of N Imu messages in a temporary directory, then times,
side by side in this process on the same bytes:

1. decode only: a list of raw CDR messages in memory -> stamp/gyro/accel arrays, by
   ``typestore.deserialize_cdr`` per message vs :func:`gyro_noise_ros.bag.decode_imu` in batches;
2. end to end: open the bag and produce the arrays, by rosbags ``Reader.messages`` +
   ``deserialize_cdr`` per message vs :class:`gyro_noise_ros.bag.ImuBagReader.iter_batches`;
3. the same for a ROS 1 ``.bag`` (rosbags' ROS 1 iterator in both; ``deserialize_ros1`` vs bulk);
4. writing: :class:`ImuBagWriter` (bulk encoding) vs rosbags ``serialize_cdr`` + ``Writer.write``.

Run: ``.venv/bin/python bench/bench_bag_decode.py [--messages 1000000]``
"""

import argparse
from pathlib import Path
import shlex
import sys
import tempfile
import time

from gyro_noise_ros.bag import decode_imu, ImuBagReader, ImuBagWriter
from gyro_noise_ros.msgs import IMU_MSGTYPE
import numpy as np
from rosbags.rosbag1 import Reader as Ros1Reader
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

TS = get_typestore(Stores.ROS2_JAZZY)
TS1 = get_typestore(Stores.ROS1_NOETIC)


def slow_arrays(pairs):
    """Decode with rosbags per message: the baseline every user of rosbags writes."""
    n = len(pairs)
    stamp = np.empty(n, np.int64)
    log = np.empty(n, np.int64)
    gyro = np.empty((n, 3))
    accel = np.empty((n, 3))
    for i, (t, raw) in enumerate(pairs):
        msg = TS.deserialize_cdr(raw, IMU_MSGTYPE)
        stamp[i] = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        log[i] = t
        av, la = msg.angular_velocity, msg.linear_acceleration
        gyro[i] = (av.x, av.y, av.z)
        accel[i] = (la.x, la.y, la.z)
    return stamp, log, gyro, accel


def ros1_raws(stamps, gyro, accel):
    """ROS 1 sensor_msgs/Imu bytes (seq, stamp, 'imu_link', 37 float64), built with numpy."""
    n = stamps.shape[0]
    head = 16 + 8
    rows = np.zeros((n, head + 296), np.uint8)
    rows[:, 0:4] = np.arange(n, dtype='<u4').view(np.uint8).reshape(n, 4)
    rows[:, 4:8] = (stamps // 1_000_000_000).astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 8:12] = (stamps % 1_000_000_000).astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 12:16] = np.frombuffer(np.array(8, '<u4').tobytes(), np.uint8)
    rows[:, 16:24] = np.frombuffer(b'imu_link', np.uint8)
    tail = np.zeros((n, 37))
    tail[:, 3] = 1.0
    tail[:, 4] = -1.0
    tail[:, 13:16] = gyro
    tail[:, 25:28] = accel
    rows[:, head:] = tail.astype('<f8').view(np.uint8)
    blob = rows.tobytes()
    size = rows.shape[1]
    return [blob[i:i + size] for i in range(0, n * size, size)]


def slow_read_ros1(path):
    gyros = []
    with Ros1Reader(path) as reader:
        for _, _, raw in reader.messages():
            msg = TS1.deserialize_ros1(raw, IMU_MSGTYPE)
            av = msg.angular_velocity
            gyros.append((av.x, av.y, av.z))
    return np.array(gyros)


def slow_read(path):
    out = []
    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.msgtype == IMU_MSGTYPE]
        batch = []
        for _, t, raw in reader.messages(connections=conns):
            batch.append((t, raw))
            if len(batch) == 65536:
                out.append(slow_arrays(batch)[2])
                batch = []
        if batch:
            out.append(slow_arrays(batch)[2])
    return np.concatenate(out)


def fast_read(path):
    with ImuBagReader(path) as reader:
        return np.concatenate([b.gyro for b in reader.iter_batches()])


def slow_write(path, storage, stamps, gyro, accel):
    t = TS.types
    vec, quat = t['geometry_msgs/msg/Vector3'], t['geometry_msgs/msg/Quaternion']
    ocov = np.zeros(9)
    ocov[0] = -1.0
    with Writer(path, version=9, storage_plugin=storage) as writer:
        conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=TS)
        for s, g, a in zip(stamps.tolist(), gyro.tolist(), accel.tolist()):
            header = t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
                sec=s // 1_000_000_000, nanosec=s % 1_000_000_000), frame_id='imu_link')
            msg = t[IMU_MSGTYPE](header=header, orientation=quat(0.0, 0.0, 0.0, 1.0),
                                 orientation_covariance=ocov, angular_velocity=vec(*g),
                                 angular_velocity_covariance=np.zeros(9),
                                 linear_acceleration=vec(*a),
                                 linear_acceleration_covariance=np.zeros(9))
            writer.write(conn, s, TS.serialize_cdr(msg, IMU_MSGTYPE))


def timed(fn, *args):
    start = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - start, out


def row(label, n, t_slow, t_fast):
    print(f'{label:<34s} {n / t_slow:>14,.0f} {n / t_fast:>14,.0f} {t_slow / t_fast:>8.1f}x')


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--messages', type=int, default=1_000_000, help='Imu messages per bag')
    parser.add_argument('--write-messages', type=int, default=200_000,
                        help='messages for the (slow) writing comparison')
    parser.add_argument(
        '--ros1-messages', type=int, default=200_000,
        help='messages for the ROS 1 comparison (rosbags keeps its index in memory)')
    args = parser.parse_args(argv)
    n = args.messages
    rng = np.random.default_rng(0)
    stamps = 1_700_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 150_150
    gyro = rng.normal(0.0, 0.01, (n, 3))
    accel = rng.normal(0.0, 0.1, (n, 3)) + (0.0, 0.0, 9.81)

    print(f'command: {shlex.join([Path(sys.executable).name, *sys.argv])}')
    print(f'{n:,} sensor_msgs/Imu messages per bag, rates in messages/s, ratio = bulk / rosbags')
    print(f'{"":<34s} {"rosbags":>14s} {"gyro_noise_ros":>14s} {"ratio":>9s}')
    with tempfile.TemporaryDirectory() as tmp:
        paths = {}
        for storage in ('sqlite3', 'mcap'):
            paths[storage] = Path(tmp, storage)
            with ImuBagWriter(paths[storage], storage=storage) as writer:
                for i in range(0, n, 100_000):
                    writer.write_imu(stamps[i:i + 100_000], gyro[i:i + 100_000],
                                     accel[i:i + 100_000])

        with Reader(paths['sqlite3']) as reader:
            pairs = [(t, raw) for _, t, raw in reader.messages()]
        t_slow, slow = timed(slow_arrays, pairs)
        raws = [raw for _, raw in pairs]
        logs = np.array([t for t, _ in pairs], np.int64)

        def fast_decode(raws, logs):
            return np.concatenate([decode_imu(raws[i:i + 65536], log_ns=logs[i:i + 65536]).gyro
                                   for i in range(0, n, 65536)])

        t_fast, fast = timed(fast_decode, raws, logs)
        assert np.array_equal(slow[2], fast), 'bulk and rosbags disagree'
        row('decode only (raw CDR in memory)', n, t_slow, t_fast)
        del pairs, raws, slow

        for storage, path in paths.items():
            t_slow, slow = timed(slow_read, path)
            t_fast, fast = timed(fast_read, path)
            assert np.array_equal(slow, fast), f'{storage}: bulk and rosbags disagree'
            row(f'read + decode, {storage}', n, t_slow, t_fast)

        m = min(args.ros1_messages, n)
        ros1_path = Path(tmp, 'rec.bag')
        with Ros1Writer(ros1_path) as writer:
            conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=TS1)
            for t, raw in zip(stamps[:m].tolist(), ros1_raws(stamps[:m], gyro[:m], accel[:m])):
                writer.write(conn, t, raw)
        t_slow, slow = timed(slow_read_ros1, ros1_path)
        t_fast, fast = timed(fast_read, ros1_path)
        assert np.array_equal(
            slow, fast) and np.array_equal(fast, gyro[:m]), 'ros1: decoders disagree'
        row(f'read + decode, ros1 ({m:,})', m, t_slow, t_fast)

        m = min(args.write_messages, n)
        for storage, plugin in (('sqlite3', StoragePlugin.SQLITE3), ('mcap', StoragePlugin.MCAP)):
            t_slow, _ = timed(slow_write, Path(tmp, f'ws_{storage}'), plugin, stamps[:m], gyro[:m],
                              accel[:m])

            def fast_write(storage=storage):
                with ImuBagWriter(Path(tmp, f'wf_{storage}'), storage=storage) as writer:
                    writer.write_imu(stamps[:m], gyro[:m], accel[:m])

            t_fast, _ = timed(fast_write)
            row(f'encode + write, {storage} ({m:,})', m, t_slow, t_fast)
    return 0


if __name__ == '__main__':
    sys.exit(main())
