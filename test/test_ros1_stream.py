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
ROS 1 bags stream in constant memory: the chunk list is read, not rosbags' per-message index.

The oracle is rosbags' own indexing reader (``BagSource(fast=False)``): the same messages in the
same order. Overlapping chunks need that index; when it would not fit the reader refuses with one
line.
"""

import tracemalloc

from gyro_noise_ros.bag import ImuBagReader, storage
from gyro_noise_ros.errors import BagError
from gyro_noise_ros.msgs import IMU_MSGTYPE
import numpy as np
import pytest
from rosbags.rosbag1 import Writer
from rosbags.typesys import get_typestore, Stores

ROS1 = get_typestore(Stores.ROS1_NOETIC)


def imu_raw(i, stamp_ns):
    t = ROS1.types
    header = t['std_msgs/msg/Header'](seq=i, stamp=t['builtin_interfaces/msg/Time'](
        sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id='imu_link')
    vec = t['geometry_msgs/msg/Vector3']
    quat = t['geometry_msgs/msg/Quaternion'](0, 0, 0, 1)
    msg = t[IMU_MSGTYPE](header=header, orientation=quat, orientation_covariance=np.zeros(9),
                         angular_velocity=vec(i * 1e-3, -i, 0.5),
                         angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(0, 0, i),
                         linear_acceleration_covariance=np.zeros(9))
    return bytes(ROS1.serialize_ros1(msg, IMU_MSGTYPE))


def write_bag(path, stamps, *, chunk_bytes=1 << 14):
    """One Imu topic; messages written in the given order (out of order: overlapping chunks)."""
    raw0 = imu_raw(0, 0)
    with Writer(path) as writer:
        writer.chunk_threshold = chunk_bytes
        conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=ROS1)
        for i, t in enumerate(stamps.tolist()):
            # same layout for every message: patch seq and stamp into the first one's bytes
            raw = bytearray(raw0)
            raw[0:4] = int(i).to_bytes(4, 'little')
            raw[4:8] = (t // 10**9).to_bytes(4, 'little')
            raw[8:12] = (t % 10**9).to_bytes(4, 'little')
            writer.write(conn, t, bytes(raw))


def read_all(path, *, fast):
    source = storage.BagSource(path, fast=fast)
    try:
        blocks = list(source.blocks('/imu/data_raw'))
        lean = not getattr(source.reader, 'indexes', {1: 1}) if fast else None
    finally:
        source.close()
    raws = [bytes(buf[s:s + n]) for buf, st, ln, _ in blocks for s, n in zip(st, ln)]
    log = np.concatenate([b[3] for b in blocks])
    return raws, log, lean


def test_ros1_blocks_equal_rosbags_reader_without_its_index(tmp_path):
    path = tmp_path / 'ordered.bag'
    stamps = 1_700_000_000 * 10**9 + np.arange(3000, dtype=np.int64) * 150_000
    write_bag(path, stamps)
    raws, log, lean = read_all(path, fast=True)
    ref_raws, ref_log, _ = read_all(path, fast=False)
    assert lean  # the streaming reader holds no per-message index
    assert raws == ref_raws and np.array_equal(log, ref_log) and len(raws) == 3000
    with ImuBagReader(path) as reader:
        assert reader.message_count == 3000
        assert sum(len(b) for b in reader.iter_batches(1000)) == 3000


def test_overlapping_chunks_use_the_index_or_refuse(tmp_path, monkeypatch):
    path = tmp_path / 'overlap.bag'
    base = 1_700_000_000 * 10**9
    t = base + np.arange(2000, dtype=np.int64) * 150_000
    stamps = np.concatenate([t[::2], t[1::2]])  # second half of the chunks interleaves the first
    write_bag(path, stamps)
    raws, log, _ = read_all(path, fast=True)
    ref_raws, ref_log, _ = read_all(path, fast=False)
    assert raws == ref_raws and np.array_equal(log, ref_log)
    assert np.array_equal(log, np.sort(stamps))
    # 2000 messages * 180 B = 360 kB of index against 100 kB available: refused, one line
    monkeypatch.setattr(storage, 'available_memory_bytes', lambda: 100_000)
    with ImuBagReader(path) as reader:
        with pytest.raises(BagError, match='overlap in time.*2000 messages') as err:
            list(reader.iter_batches())
    assert '\n' not in str(err.value)


def test_check_ros1_index_fits_rule():
    per = storage.ROS1_INDEX_BYTES_PER_MESSAGE
    storage.check_ros1_index_fits('x.bag', 1000, available=2 * 1000 * per)  # exactly half: fits
    with pytest.raises(BagError, match='x.bag'):
        storage.check_ros1_index_fits('x.bag', 1001, available=2 * 1000 * per)


@pytest.mark.slow
def test_ros1_read_memory_does_not_grow_with_bag_size(tmp_path):
    peaks = {}
    for n in (20_000, 80_000):
        path = tmp_path / f'b{n}.bag'
        write_bag(path, 1_700_000_000 * 10**9 + np.arange(n, dtype=np.int64) * 150_000,
                  chunk_bytes=1 << 18)
        tracemalloc.start()
        with ImuBagReader(path) as reader:
            total = sum(len(b) for b in reader.iter_batches(8192))
        peaks[n] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert total == n
    # rosbags' index alone would add 60000 messages * ~150 B = 9 MB; a block's decoded data is
    # ~0.5 MB at 8192 messages: allow 2 MB of growth for 4x the bag
    assert peaks[80_000] < peaks[20_000] + 2_000_000, peaks
