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
Killed recordings: a cut MCAP read by its chunks, a hot sqlite3 journal through a copy, repair.

What a killed writer leaves on disk is reproduced without killing anything: a bag is written with
:class:`ImuBagWriter` (flushing as the recorder does) and its storage file is copied, or cut, at a
known point. The oracle for an MCAP cut at any byte is rosbags' own chunk index of the complete
file: the messages readable after the cut are exactly those of the chunks that end before it.
``test_recorder.py`` kills a real recorder.
"""

import collections
import hashlib
import logging
import shutil
import sqlite3
import subprocess
import sys

from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter, list_topics
from gyro_noise_ros.bag.mcap_records import mcap_has_footer
from gyro_noise_ros.bag.repair import default_repaired_path, repair_bag
from gyro_noise_ros.cli import record
from gyro_noise_ros.errors import BagError, OutputError
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2.storage_mcap import McapReader

RATE_HZ = 6660.0


def _data(n, seed):
    rng = np.random.default_rng(seed)
    stamps = 1_700_000_000_000_000_000 + np.rint(np.arange(n) * (1e9 / RATE_HZ)).astype(np.int64)
    return stamps, rng.standard_normal((n, 3)) * 0.01, rng.standard_normal((n, 3))


def _write(path, storage, n, seed, *, flush_every=0, block=500):
    """Write n Imu messages (and one Temperature per 128) in blocks, flushing every few blocks."""
    stamps, gyro, accel = _data(n, seed)
    temps = []
    with ImuBagWriter(path, storage=storage) as writer:
        for k, i in enumerate(range(0, n, block)):
            writer.write_imu(stamps[i:i + block], gyro[i:i + block], accel[i:i + block])
            t_stamps = stamps[i:i + block:128]
            writer.write_temperature(t_stamps, np.full(t_stamps.size, 25.0 + 0.001 * i))
            temps.append(t_stamps)
            if flush_every and (k + 1) % flush_every == 0:
                writer.flush()
    return stamps, gyro, np.concatenate(temps)


def _read(path):
    with ImuBagReader(path) as reader:
        batches = list(reader.iter_batches(100000))
        temps = reader.read_temperature()
        note = reader.recovery
    if not batches:
        return np.zeros(0, np.int64), np.zeros((0, 3)), temps, note
    return (np.concatenate([b.stamp_ns for b in batches]),
            np.concatenate([b.gyro for b in batches]), temps, note)


def _sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _chunk_index(mcap):
    """(end offset, Imu messages, Temperature messages) of every chunk, from rosbags' index."""
    reader = McapReader(mcap)
    reader.open()
    try:
        ids = {c.topic: c.id for c in reader.connections}
        return [(c.chunk_start_offset + c.chunk_length,
                 c.channel_count.get(ids['/imu/data_raw'], 0),
                 c.channel_count.get(ids['/imu/temperature'], 0)) for c in reader.chunks]
    finally:
        reader.close()


@pytest.mark.parametrize('cut_fraction', [0.05, 0.2, 0.37, 0.5, 0.83, 0.97])
def test_cut_mcap_reads_exactly_the_chunks_before_the_cut(tmp_path, cut_fraction, caplog):
    stamps, gyro, temp_stamps = _write(tmp_path / 'full', 'mcap', 30_000, seed=1)
    (full,) = (tmp_path / 'full').glob('*.mcap')
    data = full.read_bytes()
    cut = int(len(data) * cut_fraction)
    killed = tmp_path / 'killed'
    killed.mkdir()
    (killed / 'killed.mcap').write_bytes(data[:cut])
    complete = [(imu, temp) for end, imu, temp in _chunk_index(full) if end <= cut]
    expected = sum(imu for imu, _ in complete)
    expected_temps = sum(temp for _, temp in complete)
    assert not mcap_has_footer(killed / 'killed.mcap')
    if expected == 0:
        # nothing complete yet: the topic is known (its channel is in the first chunk) or not
        with pytest.raises(BagError):
            _read(killed)
        return
    got_stamps, got_gyro, temps, note = _read(killed)
    np.testing.assert_array_equal(got_stamps, stamps[:expected])
    np.testing.assert_array_equal(got_gyro, gyro[:expected])
    np.testing.assert_array_equal(temps[0], temp_stamps[:expected_temps])
    assert note.startswith('truncated MCAP')
    assert f'read {expected + expected_temps} messages' in note
    assert 'gyro_noise_record repair' in note
    # said once, as one warning of the package's logger (a tool prints it: test_repair_...)
    assert [r.getMessage() for r in caplog.records] == [note]
    assert caplog.records[0].levelno == logging.WARNING
    assert {t.name: t.count for t in list_topics(killed)}['/imu/data_raw'] == expected


def test_zero_filled_mcap_tail_is_a_cut(tmp_path):
    # A power loss can leave the file's last blocks allocated but zero-filled.
    stamps = _write(tmp_path / 'full', 'mcap', 20_000, seed=2)[0]
    (full,) = (tmp_path / 'full').glob('*.mcap')
    data = bytearray(full.read_bytes())
    cut = len(data) * 2 // 3
    data[cut:] = bytes(len(data) - cut)
    (tmp_path / 'z.mcap').write_bytes(bytes(data))
    expected = sum(imu for end, imu, _ in _chunk_index(full) if end <= cut)
    got, _, _, note = _read(tmp_path / 'z.mcap')
    np.testing.assert_array_equal(got, stamps[:expected])
    # the zeros start inside a chunk: its header is intact, its records are not
    assert 'does not decompress or parse' in note


def test_flush_bounds_what_a_killed_mcap_writer_loses(tmp_path):
    # What is on disk right after ImuBagWriter.flush() (the recorder's flush timer) is read back
    # completely: the file as a killed process leaves it (the OS has every byte written).
    stamps, gyro, accel = _data(5000, 3)
    snapshots = []
    writer = ImuBagWriter(tmp_path / 'live', storage='mcap')
    try:
        (live,) = (tmp_path / 'live').glob('*.mcap')

        def snapshot():
            snapshots.append(tmp_path / f'snap{len(snapshots)}.mcap')
            shutil.copy(live, snapshots[-1])

        writer.write_imu(stamps[:1200], gyro[:1200], accel[:1200])
        writer.write_temperature(stamps[0], 25.0)
        writer.flush()  # far below rosbags' 1 MiB chunk: only the flush closes this chunk
        snapshot()
        writer.write_imu(stamps[1200:2200], gyro[1200:2200], accel[1200:2200])
        snapshot()  # 1000 messages in the pending chunk, in memory: lost in a crash
        writer.write_imu(stamps[2200:], gyro[2200:], accel[2200:])
        snapshot()  # past 1 MiB: rosbags closed a chunk by size (it may sit in the file buffer)
        writer.flush()
        snapshot()
    finally:
        writer.close()
    counts = []
    for path in snapshots:
        got, got_gyro, temps, _ = _read(path)
        np.testing.assert_array_equal(got, stamps[:got.size])
        np.testing.assert_array_equal(got_gyro, gyro[:got.size])
        np.testing.assert_array_equal(temps[0], stamps[:1])
        counts.append(got.size)
    assert counts[0] == counts[1] == 1200
    assert 1200 <= counts[2] < 5000 and counts[3] == 5000


def _kill_mid_transaction(db3, rows=2000):
    """Insert rows in a child process that dies without committing (a hot rollback journal)."""
    code = ('import os, sqlite3; c = sqlite3.connect(%r); c.execute("PRAGMA cache_size=1");'
            'c.execute("BEGIN"); c.executemany("INSERT INTO messages (topic_id, timestamp, data) '
            'VALUES (1, ?, ?)", ((i, bytes(4000)) for i in range(%d))); os._exit(0)')
    subprocess.run([sys.executable, '-c', code % (str(db3), rows)], check=True, timeout=60)
    journal = db3.with_name(db3.name + '-journal')
    assert journal.stat().st_size > 0
    return journal


def test_hot_journal_is_rolled_back_in_a_copy_never_in_place(tmp_path, caplog):
    stamps, gyro, temp_stamps = _write(tmp_path / 'rec', 'sqlite3', 3000, seed=4)
    (db3,) = (tmp_path / 'rec').glob('*.db3')
    (tmp_path / 'rec' / 'metadata.yaml').unlink()  # killed: no metadata.yaml either
    journal = _kill_mid_transaction(db3)
    before = (_sha(db3), _sha(journal))
    for path in (tmp_path / 'rec', db3):  # the folder or its file
        got, got_gyro, temps, note = _read(path)
        np.testing.assert_array_equal(got, stamps)
        np.testing.assert_array_equal(got_gyro, gyro)
        np.testing.assert_array_equal(temps[0], temp_stamps)
        assert 'unfinished transaction' in note and 'rolled-back copy' in note
    assert (_sha(db3), _sha(journal)) == before  # the user's files untouched
    # said at each opening (the folder, its file), a warning of the package's logger
    notes = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(notes) == 2 and all(n.startswith('sqlite3 bag') for n in notes)
    # read immutable, as rosbags does, the file is not what was committed (half-written pages)
    assert sqlite3.connect(f'file:{db3}?immutable=1', uri=True).execute(
        'SELECT count(*) FROM messages').fetchone() != (3000 + temp_stamps.size,)


def test_bag_without_metadata_says_so(tmp_path):
    stamps = _write(tmp_path / 'rec', 'sqlite3', 600, seed=5)[0]
    (tmp_path / 'rec' / 'metadata.yaml').unlink()
    got, _, _, note = _read(tmp_path / 'rec')
    np.testing.assert_array_equal(got, stamps)
    assert 'no metadata.yaml' in note
    _write(tmp_path / 'done', 'sqlite3', 10, seed=5)
    assert _read(tmp_path / 'done')[3] is None


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_repair_writes_a_complete_bag_and_leaves_the_input(tmp_path, storage, capsys):
    _write(tmp_path / 'full', storage, 12_000, seed=6, flush_every=4)
    killed = tmp_path / 'killed'
    killed.mkdir()
    (src,) = [p for p in (tmp_path / 'full').iterdir() if p.suffix in ('.db3', '.mcap')]
    if storage == 'mcap':
        data = src.read_bytes()
        end = _chunk_index(src)[2][0]
        (killed / f'killed{src.suffix}').write_bytes(data[:end + 1000])
    else:
        shutil.copy(src, killed / 'killed.db3')
        _kill_mid_transaction(killed / 'killed.db3')
    expected, exp_gyro, exp_temps, _ = _read(killed)
    hashes = {p.name: _sha(p) for p in killed.iterdir()}
    assert record.main(['repair', str(killed)]) == 0
    out = default_repaired_path(killed)
    assert out == tmp_path / 'killed_repaired'
    said = capsys.readouterr()
    assert f'wrote {expected.size + exp_temps[0].size} messages' in said.out
    # the tool says the recovery once, as one line with its name
    kind = 'truncated MCAP' if storage == 'mcap' else 'sqlite3 bag'
    assert said.err.startswith(f'gyro_noise_record repair: warning: {kind} ')
    assert len(said.err.strip().splitlines()) == 1
    assert {p.name: _sha(p) for p in killed.iterdir()} == hashes
    names = sorted(p.name for p in out.iterdir())
    assert names == ['killed_repaired' + src.suffix, 'metadata.yaml']
    assert sorted(p.name for p in tmp_path.iterdir()) == ['full', 'killed', 'killed_repaired']
    # rosbags opens it through metadata.yaml, counts consistent with the messages
    with AnyReader([out]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert counts == {'/imu/data_raw': expected.size, '/imu/temperature': exp_temps[0].size}
        assert sum(1 for _ in reader.messages()) == reader.message_count == sum(counts.values())
    got, got_gyro, temps, note = _read(out)
    assert note is None
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(got_gyro, exp_gyro)
    np.testing.assert_array_equal(temps[0], exp_temps[0])
    # the other storage on request, same messages
    other = 'mcap' if storage == 'sqlite3' else 'sqlite3'
    res = repair_bag(killed, tmp_path / 'other', storage=other)
    assert res.storage == other and res.messages == expected.size + exp_temps[0].size
    np.testing.assert_array_equal(_read(tmp_path / 'other')[0], expected)
    assert res.as_dict()['topics'][0] == {'topic': '/imu/data_raw',
                                          'msgtype': 'sensor_msgs/msg/Imu',
                                          'messages': int(expected.size)}


def test_repair_errors_and_interruption_leave_nothing(tmp_path, capsys, monkeypatch):
    _write(tmp_path / 'bag', 'mcap', 3000, seed=7)
    assert record.main(['repair', str(tmp_path / 'nope')]) == 3
    assert record.main(['repair', str(tmp_path / 'bag'), '--out', str(tmp_path / 'bag')]) == 6
    # argparse, as in every tool: exit 2
    assert record.main(['repair', str(tmp_path / 'bag'), '--storage', 'zip']) == 2
    err = capsys.readouterr().err
    assert 'Traceback' not in err
    assert 'does not exist' in err and 'is the input' in err

    import gyro_noise_ros.bag.repair as repair_mod

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(repair_mod, 'write_raw', interrupted)
    assert record.main(['repair', str(tmp_path / 'bag'), '--out', str(tmp_path / 'r')]) == 130
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag']  # no bag, no hidden stage
    monkeypatch.undo()
    assert record.main(['repair', str(tmp_path / 'bag'), '--out', str(tmp_path / 'r')]) == 0


def test_rolled_back_copy_needs_room(tmp_path, monkeypatch):
    from gyro_noise_ros.bag import recover

    _write(tmp_path / 'rec', 'sqlite3', 100, seed=8)
    (db3,) = (tmp_path / 'rec').glob('*.db3')
    _kill_mid_transaction(db3, rows=50)
    usage = collections.namedtuple('usage', 'total used free')
    monkeypatch.setattr(recover.shutil, 'disk_usage', lambda path: usage(10**9, 10**9, 1000))
    with pytest.raises(BagError, match='set TMPDIR'):
        _read(db3)
    with pytest.raises(OutputError):
        repair_bag(tmp_path / 'rec', tmp_path / 'rec')
