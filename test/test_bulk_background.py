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
The background MCAP file writer of the bulk bag writer (gyro_noise_ros.bag.bulk.BackgroundFile).

Oracles: the bytes written in the calling thread (``background_io = False``) and rosbags' own
per-message ImuBagWriter path; a failing file must surface its error, never lose it.
"""

import io
import os

from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.bag.bulk import BackgroundFile, BulkImuBagWriter, MCAP_CHUNK_BYTES
from gyro_noise_ros.errors import BagError
import numpy as np
import pytest


class FailingFile(io.BytesIO):
    """A file whose writes fail after ``ok`` of them (a full disk)."""

    def __init__(self, ok):
        super().__init__()
        self.ok = ok

    def write(self, data):
        if self.ok <= 0:
            raise OSError(28, 'No space left on device')
        self.ok -= 1
        return super().write(data)


def test_background_file_keeps_order_and_position():
    raw = io.BytesIO(b'')
    raw.write(b'head')
    sink = BackgroundFile(raw, depth=2)
    expected = b'head'
    rng = np.random.default_rng(1)
    for i in range(200):
        parts = [rng.integers(0, 256, int(rng.integers(0, 3000)), np.uint8).tobytes()
                 for _ in range(int(rng.integers(1, 4)))]
        if i % 2:
            sink.write_all([memoryview(p) for p in parts])
        else:
            for p in parts:
                assert sink.write(p) == len(p)
        expected += b''.join(parts)
        assert sink.tell() == len(expected)
    sink.flush()
    assert raw.getvalue() == expected
    value = []
    raw.close = lambda: value.append(raw.getvalue())
    sink.close()
    assert value == [expected]


def test_background_file_raises_a_failed_write():
    sink = BackgroundFile(FailingFile(ok=3), depth=1)
    with pytest.raises(OSError, match='No space left'):
        for _ in range(100):
            sink.write(b'x' * 100)
        sink.close()


def test_bag_write_failure_in_the_background_is_a_bag_error(tmp_path, monkeypatch):
    writer = BulkImuBagWriter(tmp_path / 'bag', storage='mcap')
    n = 3 * MCAP_CHUNK_BYTES // 300
    stamps = 1_700_000_000 * 10 ** 9 + np.arange(n) * 150_000
    writer.write_imu(stamps[:10], np.zeros((10, 3)), np.zeros((10, 3)))
    sink = writer._writer.storage.bio
    assert isinstance(sink, BackgroundFile)

    def fail(data):
        raise OSError(28, 'No space left on device')

    monkeypatch.setattr(sink.raw, 'write', fail)
    with pytest.raises(BagError, match='No space left'):
        for _ in range(20):
            writer.write_imu(stamps, np.zeros((n, 3)), np.zeros((n, 3)))
    with pytest.raises(BagError):
        writer.close()


@pytest.mark.parametrize('background', [True, False])
def test_mcap_bytes_with_and_without_background_thread(tmp_path, monkeypatch, background):
    monkeypatch.setattr(BulkImuBagWriter, 'background_io', background)
    rng = np.random.default_rng(5)
    t = 1_700_000_000 * 10 ** 9
    calls = []
    for n in (5, 9000, 1, 3 * MCAP_CHUNK_BYTES // 355 + 17, 40):
        stamps = t + np.cumsum(rng.integers(1, 300_000, n))
        t = int(stamps[-1])
        calls.append((stamps, rng.normal(size=(n, 3)), rng.normal(size=(n, 3))))
    files = []
    for cls in (ImuBagWriter, BulkImuBagWriter):
        bag = tmp_path / cls.__name__ / 'bag'
        bag.parent.mkdir()
        with cls(bag, storage='mcap') as writer:
            for stamps, gyro, accel in calls:
                writer.write_imu(stamps, gyro, accel, angular_velocity_covariance=np.eye(3))
                writer.write_temperature(stamps[::7], 20 + gyro[::7, 0])
            if cls is BulkImuBagWriter:
                assert isinstance(writer._writer.storage.bio, BackgroundFile) == background
        name = next(f for f in os.listdir(bag) if f.endswith('.mcap'))
        files.append(open(bag / name, 'rb').read())
    assert files[0] == files[1]
