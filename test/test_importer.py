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
gyro_noise_import on emulator-written SD logs split across files, with injected corruption.

The report's counts are exact and the bag (read back with rosbags) holds the right messages.

The reference is an independent walk over the *clean* files (frame by frame with struct, possible
only because they are clean) and a plain-Python twin of the counter rules.
"""

import os
import struct

from gyro_noise_ros.app import importer as import_app
from gyro_noise_ros.cli import emulator as emu_cli
from gyro_noise_ros.cli import importer
from gyro_noise_ros.link import lsm6dso32 as lsm
from gyro_noise_ros.link import protocol as p
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import get_typestore, Stores

RTC = 1_700_000_000
N_SAMPLES = 24_000


def walk_frames(data):
    """(offset, type, payload) of every frame of a clean file."""
    frames, pos = [], 0
    while pos < len(data):
        assert data[pos:pos + 2] == b'\xa5\x5a'
        ftype, length = data[pos + 3], struct.unpack_from('<H', data, pos + 4)[0]
        frames.append((pos, ftype, data[pos + 6:pos + 6 + length]))
        pos += 10 + length
    return frames


def twin_counts(seqs, flags):
    lost = flagged = 0
    for prev, seq, flag in zip(seqs[:-1], seqs[1:], flags[1:]):
        gap = (seq - prev) % 2 ** 32
        if 0 < gap < 2 ** 31:
            lost += gap - 1
            flagged += (gap - 1) if flag & p.FLAG_SAMPLE_LOST else 0
    return lost, flagged


@pytest.fixture(scope='module')
def sd_logs(tmp_path_factory):
    out = tmp_path_factory.mktemp('sd')
    code = emu_cli.main(['--write-sd', str(out), '--samples', str(N_SAMPLES), '--sd-file-bytes',
                         '120000', '--seed', '5', '--drop-flagged-rate', '0.002',
                         '--drop-unflagged-rate', '0.002', '--rtc-unix-s', str(RTC), '--seq0',
                         str(2 ** 32 - 5000), '--t0-us', str(2 ** 32 - 1_000_000), '--gyro-fs-dps',
                         '500', '--accel-fs-g', '8'])
    assert code == 0
    files = sorted(str(out / f) for f in os.listdir(out))
    assert len(files) >= 4
    clean = {}
    for path in files:
        with open(path, 'rb') as fh:
            clean[path] = fh.read()
    return files, clean


def samples_of(frames):
    payloads = [pl for _, ftype, pl in frames if ftype == p.FRAME_SAMPLES]
    return np.frombuffer(b''.join(payloads), dtype=p.SAMPLE_DTYPE)


def corrupt_copy(files, clean, dest):
    """
    Copy the logs with three injected faults.

    Return (paths, kept samples, discarded bytes, regions).
    """
    os.makedirs(dest, exist_ok=True)
    paths, kept, discarded, regions = [], [], 0, []
    for i, path in enumerate(files):
        data = bytearray(clean[path])
        frames = walk_frames(bytes(data))
        drop = set()
        if i == 1:   # zero the payload of the 10th frame: header valid, CRC fails
            off, _, payload = frames[10]
            data[off + 6:off + 6 + len(payload)] = bytes(len(payload))
            drop.add(10)
            discarded += 10 + len(payload)
            regions.append((os.path.basename(path), off, 10 + len(payload)))
        if i == 2:   # 100 junk bytes (no sync byte) between frames 4 and 5
            off = frames[5][0]
            data[off:off] = bytes(range(100))
            discarded += 100
            regions.append((os.path.basename(path), off, 100))
        if i == 3:   # the file ends in the middle of its last frame (power loss while writing)
            off, _, payload = frames[-1]
            cut = off + 6 + len(payload) // 2
            discarded += cut - off
            regions.append((os.path.basename(path), off, cut - off))
            del data[cut:]
            drop.add(len(frames) - 1)
        kept.append(samples_of([f for j, f in enumerate(frames) if j not in drop]))
        out = os.path.join(dest, os.path.basename(path))
        with open(out, 'wb') as fh:
            fh.write(bytes(data))
        paths.append(out)
    return paths, np.concatenate(kept), discarded, regions


def read_bag(path):
    store = get_typestore(Stores.ROS2_JAZZY)
    imu, temp, frame_ids, imu_ns, temp_ns = [], [], set(), [], []
    with AnyReader([path], default_typestore=store) as reader:
        for conn, t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            frame_ids.add(msg.header.frame_id)
            if conn.topic == '/imu/data_raw':
                assert t == stamp
                v, a = msg.angular_velocity, msg.linear_acceleration
                imu.append((0.0, v.x, v.y, v.z, a.x, a.y, a.z, msg.angular_velocity_covariance[0],
                            msg.orientation_covariance[0]))
                imu_ns.append(stamp)
            elif conn.topic == '/imu/temperature':
                temp.append((0.0, msg.temperature))
                temp_ns.append(stamp)
    # column 0 is a placeholder: stamps are returned as exact int64 (float64 cannot hold ns since
    # 1970)
    return np.array(imu), np.array(temp), frame_ids, np.array(imu_ns), np.array(temp_ns)


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_import_with_corruption_counts_exact_and_bag_right(sd_logs, tmp_path, storage):
    files, clean = sd_logs
    paths, kept, discarded, regions = corrupt_copy(files, clean, tmp_path / 'logs')
    bag = tmp_path / 'bag'
    # files given out of order: the importer orders them by their headers
    rep = import_app.import_logs(paths[::-1], bag, storage=storage, angular_velocity_variance=1e-6)
    assert rep.samples_written == kept.size
    assert rep.bytes_discarded == discarded
    assert rep.resyncs == 3 and rep.corrupt_region_count == 3
    assert [(os.path.basename(r.path), r.offset, r.length) for r in rep.corrupt_regions] == regions
    assert rep.crc_errors >= 1 and rep.frames_truncated >= 1
    lost, flagged = twin_counts(kept['seq'].astype(np.int64).tolist(), kept['flags'].tolist())
    assert (rep.samples_lost, rep.samples_flagged_lost) == (lost, flagged)
    assert rep.missing_file_indices == () and rep.time_jumps == 0
    assert rep.configurations == ((500, 8, 6667.0),)

    imu, temp, frame_ids, imu_ns, temp_ns = read_bag(bag)
    assert frame_ids == {'imu_link'}
    assert imu.shape[0] == kept.size
    si = lsm.to_si(kept, gyro_fs_dps=500, accel_fs_g=8)
    assert np.array_equal(imu[:, 1:4], si.gyro_rad_s)
    assert np.array_equal(imu[:, 4:7], si.accel_m_s2)
    assert np.all(imu[:, 7] == 1e-6) and np.all(imu[:, 8] == -1)  # REP-145: no orientation
    # stamps: device time unwrapped across the wrap at 2**32 us, anchored at the header's RTC time
    t = kept['t_us'].astype(np.int64)
    t = t + 2 ** 32 * (t < t[0])
    first_head = p.Decoder().feed(clean[files[0]][:200]).headers[0]
    expected = RTC * 1_000_000_000 + (t - first_head.t_us) * 1000
    assert np.array_equal(imu_ns, expected)
    # temperature: 52 Hz of data time -> floor(n * 52 / 6667) messages, each an Imu sample's stamp
    assert abs(temp.shape[0] - kept.size * 52 / 6667) <= 1
    assert np.isin(temp_ns, expected).all()
    assert np.allclose(temp[:, 1], 25.0, atol=0.01)


def test_missing_middle_file_is_reported_and_counted(sd_logs, tmp_path):
    files, clean = sd_logs
    use = [f for i, f in enumerate(files) if i != 2]
    all_kept = np.concatenate([samples_of(walk_frames(clean[f])) for f in use])
    rep = import_app.import_logs(use, tmp_path / 'bag', start_time='zero', temperature_rate_hz=0)
    assert rep.missing_file_indices == (2,)
    assert rep.samples_written == all_kept.size
    lost, flagged = twin_counts(all_kept['seq'].astype(np.int64).tolist(),
                                all_kept['flags'].tolist())
    assert (rep.samples_lost, rep.samples_flagged_lost) == (lost, flagged)
    assert rep.first_stamp_ns == 0 and rep.temperature_written == 0


def test_cli_prints_report_and_refuses_bad_input(sd_logs, tmp_path, capsys):
    files, _ = sd_logs
    bag = tmp_path / 'bag'
    assert importer.main([*files, '--out', str(bag), '--start-time', '1000.5', '--topic',
                          'gyro/raw']) == 0
    out = capsys.readouterr().out
    assert (
        'samples written' in out
        and 'corrupt regions        0' in out
        and 'epoch unix:1000.5' in out
    )
    assert importer.main([*files, '--out', str(bag)]) == 6  # exists: an output in the way
    assert 'exists' in capsys.readouterr().err
    junk = tmp_path / 'junk.GNL'
    junk.write_bytes(bytes(range(256)) * 40)
    # no header: scaling unknown
    assert importer.main([str(junk), '--out', str(tmp_path / 'b2')]) == 4
    assert importer.main([str(junk), '--out', str(tmp_path / 'b3'), '--gyro-fs-dps', '2000',
                          '--accel-fs-g', '4']) == 4  # no samples at all
    assert not (tmp_path / 'b3').exists()
    assert importer.main([*files, '--out', str(tmp_path / 'b4'), '--gyro-fs-dps', '300']) == 2
    # the writer thread changes nothing the user sees: same report, same messages
    capsys.readouterr()
    reports = []
    for threads in ('1', '2'):
        out_bag = tmp_path / threads / 'bag'
        assert importer.main([*files, '--out', str(out_bag), '--threads', threads]) == 0
        reports.append(capsys.readouterr().out.replace(str(out_bag), 'BAG'))
    assert reports[0] == reports[1] and 'samples written' in reports[0]
    for one, two in zip(read_bag(tmp_path / '1' / 'bag'), read_bag(tmp_path / '2' / 'bag')):
        if isinstance(one, set):
            assert one == two
        else:
            np.testing.assert_array_equal(one, two)


@pytest.mark.slow
def test_import_memory_does_not_grow_with_log_size(tmp_path):
    import tracemalloc

    peaks = {}
    for n in (5_000, 10_000, 80_000):
        logs = tmp_path / f'logs{n}'
        assert emu_cli.main(['--write-sd', str(logs), '--samples', str(n), '--sd-file-bytes',
                             '300000']) == 0
        files = sorted(str(logs / f) for f in os.listdir(logs))
        tracemalloc.start()
        import_app.import_logs(files, tmp_path / f'bag{n}', chunk_bytes=1 << 16)
        peaks[n] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    # 8x the data (0.5 MB more of samples as numpy arrays alone) must not raise the Python-heap
    # peak by more than a chunk's worth of decoded data and bookkeeping: allow 25 % (the first,
    # smaller run only warms caches and imports up)
    assert peaks[80_000] < 1.25 * peaks[10_000], peaks


def test_same_log_twice_or_overlapping_logs_are_refused(sd_logs, tmp_path, capsys):
    files, clean = sd_logs
    # the same file twice (as given, or through another path): a command-line mistake, exit 2
    other_path = os.path.join(os.path.dirname(files[0]), '.', os.path.basename(files[0]))
    for twice in ([files[0], files[0]], [*files, other_path]):
        assert importer.main([*twice, '--out', str(tmp_path / 'b')]) == 2
        err = capsys.readouterr().err
        assert 'given twice' in err and os.path.basename(files[0]) in err
    # a copy under another name: the same data twice, exit 4, both files named
    copy = tmp_path / 'S001F009.GNL'
    copy.write_bytes(clean[files[1]])
    assert importer.main([*files, str(copy), '--out', str(tmp_path / 'b')]) == 4
    err = capsys.readouterr().err
    assert 'S001F001.GNL' in err and 'S001F009.GNL' in err and 'same log twice' in err
    # overlapping sequences: file 2 with the first half of file 3's frames appended
    frames = walk_frames(clean[files[3]])
    mid = frames[len(frames) // 2][0]
    overlap = tmp_path / 'overlap'
    overlap.mkdir()
    for path in files:
        (overlap / os.path.basename(path)).write_bytes(clean[path])
    (overlap / os.path.basename(files[2])).write_bytes(clean[files[2]] + clean[files[3]][
        frames[1][0]:mid])
    logs = sorted(str(p) for p in overlap.iterdir())
    assert importer.main([*logs, '--out', str(tmp_path / 'b')]) == 4
    err = capsys.readouterr().err
    assert 'overlap' in err and 'S001F002.GNL' in err and 'S001F003.GNL' in err
    assert err.count('\n') == 1 and 'Traceback' not in err
    assert not (tmp_path / 'b').exists()


def test_interrupted_or_failed_import_leaves_no_bag_and_a_retry_works(sd_logs, tmp_path,
                                                                      monkeypatch, capsys):
    files, clean = sd_logs
    bag = tmp_path / 'bag'
    # a read size whose buffers cannot be had: refused before anything is written
    assert importer.main([*files, '--out', str(bag), '--chunk-bytes', '100000000000000']) == 2
    assert 'chunk_bytes must be in 1..' in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
    from gyro_noise_ros.link import sdlog

    real_split = sdlog.SdLogReader._split
    calls = []

    def interrupt_midway(path, res, config):
        calls.append(path)
        if len(calls) == 20:
            raise KeyboardInterrupt
        return real_split(path, res, config)

    for threads in ('1', '2'):
        calls.clear()
        monkeypatch.setattr(sdlog.SdLogReader, '_split', staticmethod(interrupt_midway))
        code = importer.main([*files, '--out', str(bag), '--threads', threads,
                              '--chunk-bytes', '4096'])
        assert code == 130 and len(calls) == 20
        assert list(tmp_path.iterdir()) == []  # nothing that looks finished, nothing hidden
        monkeypatch.setattr(sdlog.SdLogReader, '_split', staticmethod(real_split))
    assert importer.main([*files, '--out', str(bag)]) == 0
    assert sorted(p.name for p in bag.iterdir()) == ['bag.mcap', 'metadata.yaml']
    expected = sum(samples_of(walk_frames(clean[f])).size for f in files)
    assert read_bag(bag)[0].shape[0] == expected
