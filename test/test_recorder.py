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
``gyro_noise_record`` as a real process: loss-free at 6.66 kHz, clean close on SIGINT and SIGTERM.

The replayer of ``test/test_analyzer_e2e.py`` publishes seeded samples in real time; the recorder
writes them; after the signal the bag is read back with :class:`gyro_noise_ros.bag.ImuBagReader`
and compared with what was published: the same count (nothing lost, nothing twice), the same stamps
and values.
"""

import signal
import subprocess
import sys

from gyro_noise_ros.bag import ImuBagReader, list_topics
from gyro_noise_ros.nodes.recorder import default_bag_name
import numpy as np
import pytest
from test_analyzer_e2e import RATE_HZ, ros_env, start_replayer

pytestmark = pytest.mark.ros


def _expected(samples, seed, sigma=0.004):
    # Mirrors the replayer's generator (test_analyzer_e2e._publish_main) for the default options.
    rng = np.random.default_rng(seed)
    index = np.arange(samples, dtype=np.int64)
    stamps = 1_700_000_000_000_000_000 + np.rint(index * (1e9 / RATE_HZ)).astype(np.int64)
    return stamps, rng.standard_normal((samples, 3)) * sigma


def _record(tmp_path, samples, seed, sig, storage):
    out = tmp_path / f'bag_{storage}'
    rec = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                            '-p', f'output:={out}', '-p', f'storage:={storage}',
                            # The replayer publishes reliable, as the driver does: a reliable
                            # subscription keeps a loaded host from dropping messages in transport.
                            '-p', 'reliable:=true'],
                           env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    # The replayer waits for the recorder's Imu subscription, publishes in real time at 6.66 kHz
    # and lingers 1 s, so the recorder has taken everything before the signal.
    rep = start_replayer('--samples', samples, '--seed', seed, '--subscribers', 1)
    try:
        rep_out, rep_err = rep.communicate(timeout=120)
        assert rep.returncode == 0, rep_err
        rec.send_signal(sig)
        rec_out, rec_err = rec.communicate(timeout=30)
    finally:
        for p in (rep, rec):
            if p.poll() is None:
                p.kill()
                p.communicate()
    return out, rec.returncode, rec_err


@pytest.mark.timeout(180)
@pytest.mark.parametrize('sig, storage', [(signal.SIGINT, 'sqlite3'), (signal.SIGTERM, 'mcap')],
                         ids=['sigint-sqlite3', 'sigterm-mcap'])
def test_records_every_message_at_6660_hz(tmp_path, sig, storage):
    samples = 20000  # 3 s at 6.66 kHz
    out, rc, err = _record(tmp_path, samples, seed=7, sig=sig, storage=storage)
    assert rc == 0, err
    summary = [line for line in err.splitlines() if line.startswith('gyro_noise_record: received')]
    assert summary, err
    assert f'received {samples} Imu' in summary[0], summary[0]
    assert f'wrote {samples} and' in summary[0], summary[0]
    assert '0 dropped' in summary[0]

    topics = {t.name: t for t in list_topics(out)}
    assert topics['/imu/data_raw'].count == samples
    # One temperature message per 128 samples (replayer default), recorded too.
    assert topics['/imu/temperature'].count == len(range(0, samples, 128))
    stamps, gyro = _expected(samples, seed=7)
    with ImuBagReader(out) as reader:
        batches = list(reader.iter_batches(100000))
        temps = reader.read_temperature()
    got_stamps = np.concatenate([b.stamp_ns for b in batches])
    got_gyro = np.concatenate([b.gyro for b in batches])
    np.testing.assert_array_equal(got_stamps, stamps)
    np.testing.assert_array_equal(got_gyro, gyro)
    assert batches[0].frame_id == 'imu_link'
    np.testing.assert_array_equal(temps[1], 25.0 + 0.001 * np.arange(0, samples, 128))


@pytest.mark.timeout(120)
def test_killed_recorder_leaves_a_readable_db3(tmp_path):
    out = tmp_path / 'killed'
    rec = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                            '-p', f'output:={out}', '-p', 'flush_period_s:=0.2'],
                           env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    rep = start_replayer('--samples', 10000, '--seed', 3, '--linger-s', 1.5)
    try:
        rep.communicate(timeout=120)
        rec.kill()  # SIGKILL: no drain, no close, no metadata.yaml
        rec.communicate(timeout=30)
    finally:
        for p in (rep, rec):
            if p.poll() is None:
                p.kill()
                p.communicate()
    assert not (out / 'metadata.yaml').exists()
    with ImuBagReader(out / 'killed.db3') as reader:
        n = sum(len(b) for b in reader.iter_batches(100000))
    # The replayer lingers 1.5 s after the last message, several flush periods of 0.2 s: all
    # committed.
    assert n == 10000


@pytest.mark.timeout(180)
def test_two_publishers_are_counted_apart_and_named(tmp_path):
    # Two replayers (two writers of imu/data_raw, as a second driver or another robot's graph
    # would be): the recorder counts each one's messages and sequence gaps apart (one counter for
    # both read millions of drops in interleaved numbers) and warns, naming both.
    samples = 20000  # 3 s each: they overlap even when one starts seconds after the other
    out = tmp_path / 'two'
    rec = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                            '-p', f'output:={out}', '-p', 'reliable:=true'],
                           env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    # Each lingers 5 s after its last message: the recorder takes 13,320 messages a second here
    # and may be seconds behind on a loaded host; a reliable writer resends only while it lives.
    reps = [start_replayer('--samples', samples, '--seed', seed, '--linger-s', 5, node_name=name)
            for seed, name in ((1, 'replayer_a'), (2, 'replayer_b'))]
    try:
        for rep in reps:
            assert rep.communicate(timeout=120)[0].startswith(f'published {samples}')
        rec.send_signal(signal.SIGINT)
        _, err = rec.communicate(timeout=30)
    finally:
        for p in (*reps, rec):
            if p.poll() is None:
                p.kill()
                p.communicate()
    assert rec.returncode == 0, err
    summary = next(ln for ln in err.splitlines() if ln.startswith('gyro_noise_record: received'))
    assert f'received {2 * samples} Imu' in summary and '; 0 dropped in transport' in summary
    imu_part = summary.split('publishers of /imu/data_raw: ', 1)[1].split('; publishers of')[0]
    assert sorted(imu_part.split('; ')) == [f'/replayer_a {samples} (0 dropped)',
                                            f'/replayer_b {samples} (0 dropped)'], summary
    warnings = [ln for ln in err.splitlines() if 'another publisher on /imu/data_raw' in ln]
    assert len(warnings) == 1, err[-3000:]
    assert ('/replayer_b (besides /replayer_a)' in warnings[0]
            or '/replayer_a (besides /replayer_b)' in warnings[0]), warnings[0]
    assert {t.name: t.count for t in list_topics(out)}['/imu/data_raw'] == 2 * samples


def test_refuses_an_existing_output(tmp_path):
    env = ros_env()
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                           '-p', f'output:={tmp_path}'], env=env, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 3
    lines = done.stderr.strip().splitlines()
    assert lines[-1].startswith('gyro_noise_record: error:') and 'exists' in lines[-1], done.stderr
    assert 'Traceback' not in done.stderr


def test_refuses_an_unknown_storage(tmp_path):
    env = ros_env()
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                           '-p', f'output:={tmp_path / "b"}', '-p', 'storage:=zip'],
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert "parameter 'storage'" in done.stderr and 'Traceback' not in done.stderr


def test_default_bag_name():
    from datetime import datetime, timezone

    assert default_bag_name(datetime(2026, 1, 2, 3, 4, 5, tzinfo=timezone.utc)
                            ) == 'gyro_noise_20260102_030405'


if __name__ == '__main__':
    sys.exit(pytest.main([__file__, *sys.argv[1:]]))
