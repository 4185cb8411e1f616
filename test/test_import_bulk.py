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
The bulk bag writer (gyro_noise_ros.bag.bulk) against the per-message ImuBagWriter it replaces.

The oracle is the old path itself, still callable (``import_logs(..., bulk=False)``,
``ImuBagWriter``): the new path must write the same messages byte for byte, with the same bag
times, in the same order, and the importer's report must not change, on logs with injected
corruption.
"""

import dataclasses
import os
import sqlite3

from gyro_noise_ros.app import importer as import_app
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.bag.bulk import BulkImuBagWriter, MCAP_CHUNK_BYTES
from gyro_noise_ros.cli import emulator as emu_cli
from gyro_noise_ros.errors import OutputError, ParameterError
import numpy as np
import pytest
from rosbags.rosbag2 import Reader


def bag_messages(path):
    """(topic, bag time, raw bytes) of every message, in storage order."""
    with Reader(path) as reader:
        return [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]


def storage_file(bag):
    names = sorted(os.listdir(bag))
    return next(os.path.join(bag, f) for f in names if f.endswith(('.db3', '.mcap')))


@pytest.fixture(scope='module')
def corrupt_logs(tmp_path_factory):
    out = tmp_path_factory.mktemp('sd')
    assert emu_cli.main(['--write-sd', str(out), '--samples', '30000', '--sd-file-bytes', '150000',
                         '--seed', '11', '--drop-flagged-rate', '0.002',
                         '--drop-unflagged-rate', '0.002', '--rtc-unix-s', '1700000000',
                         '--gyro-fs-dps', '500', '--accel-fs-g', '8']) == 0
    files = sorted(str(out / f) for f in os.listdir(out))
    rng = np.random.default_rng(3)
    for i, path in enumerate(files):
        data = bytearray(open(path, 'rb').read())
        for pos in rng.integers(200, len(data), 6):  # bit flips: CRC failures and resyncs
            data[pos] ^= 1 << int(rng.integers(8))
        if i == 1:
            data[5000:5000] = bytes(range(77))  # junk between frames
        if i == len(files) - 1:
            del data[-37:]  # power loss in the middle of the last frame
        with open(path, 'wb') as fh:
            fh.write(bytes(data))
    return files


@pytest.mark.parametrize('threads', [1, 2])
@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_bulk_import_writes_the_old_paths_bytes(corrupt_logs, tmp_path, storage, threads):
    reports, bags = {}, {}
    for bulk in (False, True):
        # same bag name in two folders: the name is inside the MCAP file and metadata.yaml
        bag = tmp_path / str(bulk) / 'bag'
        bag.parent.mkdir()
        reports[bulk] = import_app.import_logs(corrupt_logs, bag, storage=storage, bulk=bulk,
                                               angular_velocity_variance=1e-6,
                                               chunk_bytes=1 << 14,
                                               threads=threads if bulk else 1)
        bags[bulk] = bag
    old, new = reports[False], reports[True]
    assert old.crc_errors > 0 and old.corrupt_region_count > 0 and old.temperature_written > 0
    assert dataclasses.replace(new, bag=old.bag) == old
    assert bag_messages(bags[True]) == bag_messages(bags[False])
    assert open(bags[True] / 'metadata.yaml').read() == open(bags[False] / 'metadata.yaml').read()
    if storage == 'mcap':  # the whole file, chunking and indexes included
        with open(storage_file(bags[True]), 'rb') as a, open(storage_file(bags[False]), 'rb') as b:
            assert a.read() == b.read()
    else:  # the rows, primary keys included
        rows = []
        for bulk in (False, True):
            with sqlite3.connect(storage_file(bags[bulk])) as db:
                sql = 'SELECT id, topic_id, timestamp, data FROM messages ORDER BY id'
                rows.append(db.execute(sql).fetchall())
        assert rows[0] == rows[1]


@pytest.mark.parametrize(('storage', 'compression'),
                         [('sqlite3', 'none'), ('mcap', 'none'), ('mcap', 'zstd')])
def test_bulk_writer_api_matches_imu_bag_writer(tmp_path, storage, compression):
    rng = np.random.default_rng(8)
    calls = []
    t = 1_700_000_000 * 10 ** 9
    # sizes cross the MCAP chunk limit mid-call and land exactly on message boundaries
    for n in (1, 2, 3000, MCAP_CHUNK_BYTES // 350, 7, 5000):
        stamps = t + np.cumsum(rng.integers(1, 300_000, n))
        t = int(stamps[-1])
        gyro = rng.normal(size=(n, 3))
        gyro[0, 1] = np.nan
        gyro[-1, 2] = -0.0
        per_row = rng.random() < 0.5
        cov = rng.random((n, 9)) if per_row else rng.random(9)
        calls.append((stamps, gyro, rng.normal(size=(n, 3)), cov, stamps - 1000))
    bags = {}
    for cls in (ImuBagWriter, BulkImuBagWriter):
        bag = tmp_path / cls.__name__ / 'bag'
        bag.parent.mkdir()
        with cls(bag, storage=storage, frame_id='gyro_frame', compression=compression) as writer:
            for i, (stamps, gyro, accel, cov, log) in enumerate(calls):
                writer.write_imu(stamps, gyro, accel, angular_velocity_covariance=cov, log_ns=log)
                writer.write_temperature(stamps[::5], 25.0 + gyro[::5, 0], variance=0.01)
                if i == 2:
                    writer.write_imu(stamps[:10], accel[:10], gyro[:10], topic='/ref/imu')
            if cls is BulkImuBagWriter:  # the block paths were taken, not the per-message fallback
                fast = writer._mcap_storage if storage == 'mcap' else writer._bulk_cursor
                assert fast(writer._imu_conn) is not None
        assert writer.imu_count == sum(c[0].shape[0] for c in calls)
        bags[cls] = bag
    assert bag_messages(bags[BulkImuBagWriter]) == bag_messages(bags[ImuBagWriter])
    if compression != 'none':  # the chunks really are compressed, and read back
        assert b'zstd' in open(storage_file(bags[ImuBagWriter]), 'rb').read()
    if storage == 'mcap':
        assert (open(storage_file(bags[BulkImuBagWriter]), 'rb').read()
                == open(storage_file(bags[ImuBagWriter]), 'rb').read())


def test_a_failed_write_in_the_writer_thread_is_raised_once_and_stops_the_import(
        corrupt_logs, tmp_path, monkeypatch):
    calls = []

    def failing(self, *args, **kwargs):
        calls.append(len(calls))
        if len(calls) == 3:
            raise OutputError('bag: writing failed: No space left on device')

    monkeypatch.setattr(BulkImuBagWriter, 'write_imu', failing)
    with pytest.raises(OutputError, match='No space left'):
        import_app.import_logs(corrupt_logs, tmp_path / 'bag', threads=2, chunk_bytes=1 << 12)
    # the writes queued behind the failed one were dropped, not run
    assert len(calls) == 3
    # and no bag, finished-looking or hidden, is left
    assert list(tmp_path.iterdir()) == []


def test_threads_must_be_one_or_two(corrupt_logs, tmp_path):
    with pytest.raises(import_app.ParameterError, match='threads'):
        import_app.import_logs(corrupt_logs, tmp_path / 'bag', threads=3)


@pytest.mark.parametrize('threads', [1, 2])
def test_a_bag_that_cannot_be_created_is_one_error(corrupt_logs, tmp_path, threads):
    blocker = tmp_path / 'file'
    blocker.write_text('x')
    with pytest.raises(OutputError, match='cannot be created'):
        import_app.import_logs(corrupt_logs, blocker / 'bag', threads=threads)


@pytest.mark.parametrize(('storage', 'compression'), [('mcap', 'lz4'), ('sqlite3', 'zstd')])
def test_writer_refuses_a_compression_it_does_not_write(tmp_path, storage, compression):
    with pytest.raises(ParameterError, match='compression'):
        ImuBagWriter(tmp_path / 'bag', storage=storage, compression=compression)
    assert not (tmp_path / 'bag').exists()
