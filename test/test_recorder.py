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

import os
import signal
import subprocess
import sys
import time
import warnings

from _e2e import free_port, readline
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


#: Give up when nothing moved for this long (s): no progress line of the recorder, no new count.
#: The waits below end on completion, not at a fixed time: on a host at load ~25 the replayer
#: alone took 98 s from its start to its first message (bytes encoded, rclpy imported, matched).
STALL_S = 240.0


def _wait_progress(log, want, rec, rep=None):
    """
    Wait until the recorder reports ``want`` written (None: until it has subscribed).

    Fail after STALL_S without a change, or when the recorder or the replayer ``rep`` ended.
    """
    seen, moved = None, time.monotonic()
    while True:
        text = log.read_text()
        got = _progress(log) if want is not None else ('] [gyro_noise_record]: recording' in text,)
        if all(g >= w for g, w in zip(got, want or (True,))):
            return
        if got != seen:
            seen, moved = got, time.monotonic()
        assert time.monotonic() - moved < STALL_S, (got, want, text[-2000:])
        assert rep is None or rep.poll() is None, rep.communicate()
        assert rec.poll() is None, text[-2000:]
        time.sleep(0.1)


def _record(tmp_path, samples, seed, sig, storage):
    out = tmp_path / f'bag_{storage}'
    log = tmp_path / f'recorder_{storage}.log'
    rec = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
                            '-p', f'output:={out}', '-p', f'storage:={storage}',
                            # The replayer publishes reliable, as the driver does: a reliable
                            # subscription keeps a loaded host from dropping messages in transport.
                            '-p', 'reliable:=true', '-p', 'report_period_s:=0.25'],
                           env=ros_env(), stdout=subprocess.DEVNULL, stderr=open(log, 'w'))
    rep = None
    try:
        # The replayer starts once the recorder has subscribed (its first progress line), waits
        # for the match and publishes in real time at 6.66 kHz; it then lingers (its reliable
        # writer resends what a starved recorder has not taken yet) until the recorder reports
        # every message written, and only then the signal comes.
        _wait_progress(log, None, rec)
        rep = start_replayer('--samples', samples, '--seed', seed, '--subscribers', 1,
                             '--match-timeout-s', STALL_S, '--linger-s', 10 * STALL_S)
        _wait_progress(log, (samples, len(range(0, samples, 128))), rec, rep)
        rec.send_signal(sig)
        rec.wait(timeout=STALL_S)  # the last drain and the bag's close
    finally:
        for p in (rep, rec):
            if p is not None and p.poll() is None:
                p.kill()
                p.communicate()
    return out, rec.returncode, log.read_text()


def _progress(log):
    """(Imu, Temperature) messages the recorder last reported written ((0, 0) before any)."""
    import re

    counts = re.findall(r'\[gyro_noise_record\]: (\d+) Imu, (\d+) Temperature',
                        log.read_text())
    return tuple(map(int, counts[-1])) if counts else (0, 0)


@pytest.mark.timeout(900)  # an upper bound only: the waits end on completion or a stall
@pytest.mark.parametrize('sig, storage', [(signal.SIGINT, 'sqlite3'), (signal.SIGTERM, 'mcap')],
                         ids=['sigint-sqlite3', 'sigterm-mcap'])
def test_records_every_message_at_6660_hz(tmp_path, sig, storage):
    samples = 20000  # 3 s at 6.66 kHz
    out, rc, err = _record(tmp_path, samples, seed=7, sig=sig, storage=storage)
    assert rc == 128 + sig, err  # interrupted (130, 143): the bag is closed all the same
    assert err.strip().splitlines()[-1].startswith('gyro_noise_record: interrupted'), err
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


#: Run time before the kill (the issue's scenario: 20 s at 6.66 kHz).
KILL_AFTER_S = 20.0
#: What the recorder may lose: everything younger than this at the kill (the flush period is
#: 0.5 s; the rest is slack for a loaded host's late timers) ...
AT_RISK_S = 1.0
#: ... and of the older messages, this fraction at most (the issue's criterion, 99 % recovered).
MAX_OLD_LOSS = 0.01
#: The end-to-end criterion is judged on a host that streamed at least this mean rate (Hz) ...
MIN_RATE_HZ = 6000.0
#: ... and whose 1-minute load average per CPU at the kill was at most this (a host shared with
#: other jobs starves the recorder, which then lags the stream by seconds: lag, not a kill loss).
MAX_LOAD_PER_CPU = 1.5


def _cpu_s(pid):
    """CPU time (user + system) a process has used so far, in s (Linux /proc)."""
    with open(f'/proc/{pid}/stat') as fh:
        fields = fh.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _written_by(log, t_ns):
    """Imu messages the recorder reported written at its last progress line before t_ns."""
    import re

    lines = re.findall(r'\[(\d+)\.(\d+)\] \[gyro_noise_record\]: (\d+) Imu',
                       log.read_text())
    counts = [int(n) for sec, frac, n in lines
              if int(sec) * 1_000_000_000 + int(frac.ljust(9, '0')[:9]) <= t_ns]
    assert counts, f'no progress line of the recorder before the cut-off in {log}'
    return counts[-1]


def _driver_published(stamps_counts, t_ns):
    """Upper bound of the driver's published count at t_ns: its first status at or after t_ns."""
    later = [(stamp, count) for stamp, count in stamps_counts if stamp >= t_ns]
    assert later, 'no driver status after the cut-off time'
    return min(later)[1]


@pytest.mark.slow
@pytest.mark.timeout(240)
@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_killed_recorder_keeps_all_but_the_last_second(tmp_path, storage, ros_graph):
    """
    Emulator -> driver -> gyro_noise_record, kill -9 after 20 s.

    One recorder per run: two at once on a 2-core host slowed the whole chain below 6.66 kHz.

    The published count comes from the driver's own counter ('Samples published' of its link
    status, every 0.25 s); messages published more than 1 s before the kill are bounded from
    above by its first status after that time, so the criterion is checked conservatively. The
    killed recording is read as it is (one warning line) and repaired into a complete bag that
    rosbags opens, with the same messages.
    """
    from diagnostic_msgs.msg import DiagnosticArray
    from gyro_noise_ros.bag.repair import repair_bag
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosbags.highlevel import AnyReader

    env = ros_env()
    bag, log = tmp_path / storage, tmp_path / 'recorder.log'
    procs = []
    try:
        rec = subprocess.Popen(
            [sys.executable, '-m', 'gyro_noise_ros.nodes.recorder', '--ros-args',
             '-p', f'output:={bag}', '-p', f'storage:={storage}',
             '-p', 'reliable:=true', '-p', 'report_period_s:=0.25'],
            env=env, stdout=subprocess.DEVNULL, stderr=open(log, 'w'))
        procs.append(rec)
        port = free_port()
        driver = subprocess.Popen(
            [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args',
             '-p', f'port:=socket://127.0.0.1:{port}', '-p', 'reconnect_period_s:=0.2',
             '-p', 'diagnostics_period_s:=0.25', '-p', 'qos_depth:=60000'],
            env=env, stdout=subprocess.DEVNULL, stderr=open(tmp_path / 'driver.log', 'w'))
        procs.append(driver)
        context = rclpy.Context()
        rclpy.init(context=context, domain_id=ros_graph.domain_id)
        statuses = []
        try:
            node = rclpy.create_node('test_kill_listener', context=context)

            def on_diagnostics(msg):
                for status in msg.status:
                    if status.name == 'lsm6dso32_driver: link':
                        values = {kv.key: kv.value for kv in status.values}
                        statuses.append((msg.header.stamp.sec * 1_000_000_000
                                         + msg.header.stamp.nanosec,
                                         int(values['Samples published'])))

            node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics,
                                     QoSProfile(depth=100,
                                                reliability=ReliabilityPolicy.RELIABLE))
            executor = rclpy.executors.SingleThreadedExecutor(context=context)
            executor.add_node(node)

            def spin_until(done, timeout_s):
                deadline = time.monotonic() + timeout_s
                while not done():
                    assert time.monotonic() < deadline, 'timed out'
                    executor.spin_once(timeout_sec=0.05)

            # The recorder subscribes before anything is published (the driver has no board yet).
            spin_until(lambda: statuses, 60.0)
            emu = subprocess.Popen(
                [sys.executable, '-m', 'gyro_noise_ros.cli.emulator', '--tcp',
                 f'127.0.0.1:{port}', '--seed', '3', '--accel-fs-g', '32'],
                stdout=subprocess.PIPE, stderr=open(tmp_path / 'emu.log', 'w'), text=True)
            procs.append(emu)
            readline(emu, 120.0)  # a loaded host starts the emulator slowly
            spin_until(lambda: statuses[-1][1] > 0, 60.0)
            started = time.monotonic()
            spin_until(lambda: time.monotonic() - started > KILL_AFTER_S, KILL_AFTER_S + 30.0)
            cpu_s = _cpu_s(rec.pid)
            load = os.getloadavg()[0] / os.cpu_count()
            kill_ns = time.time_ns()
            rec.kill()  # SIGKILL: no drain, no flush, no close
            # a status stamped after the kill, so the counts at the kill are bounded
            spin_until(lambda: statuses[-1][0] >= kill_ns, 20.0)
            node.destroy_node()
        finally:
            rclpy.try_shutdown(context=context)
        rec.wait(timeout=30)
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    old = _driver_published(statuses, kill_ns - int(AT_RISK_S * 1e9))
    at_kill = _driver_published(statuses, kill_ns)
    # The chain itself must have streamed (a loaded host paces the emulator below 6.66 kHz; the
    # criterion holds at any rate, 1 % of the older messages is then still > 100 messages).
    assert old > 10_000, (old, statuses[-3:])
    t_first, n_first = next((t, n) for t, n in statuses if n > 0)
    rate_hz = (at_kill - n_first) / ((kill_ns - t_first) / 1e9)
    written = _written_by(log, kill_ns - int(AT_RISK_S * 1e9))
    assert not (bag / 'metadata.yaml').exists()
    with ImuBagReader(bag) as reader:
        stamps = np.concatenate([b.stamp_ns for b in reader.iter_batches(100000)])
        note = reader.recovery
    assert note is not None and 'gyro_noise_record repair' in note, note
    print(note)
    kept = stamps.size
    print(f'{storage}: {kept} Imu recovered; published {old} up to 1 s before the kill, '
          f'{at_kill} at the kill ({100.0 * kept / old:.2f} % of the older ones; '
          f'{rate_hz:.0f} Hz published on average); the recorder had written {written} '
          f'up to 1 s before the kill, using {1e6 * cpu_s / max(kept, 1):.0f} us '
          f'of CPU per Imu message; load {load:.2f} per CPU')
    # The documented bound, whatever the load: everything the recorder had written 1 s before
    # the kill (its own progress line) is kept.
    assert kept >= written, (storage, kept, written)
    if rate_hz < MIN_RATE_HZ or load > MAX_LOAD_PER_CPU:
        # A host too loaded to stream 6.66 kHz, or shared with other jobs, starves the
        # recorder, which then lags the stream by seconds: that is lag, not what a kill loses.
        # Said with the numbers, not hidden; the bound above was asserted.
        warnings.warn(f'{storage}: host at {rate_hz:.0f} Hz and load {load:.2f} per CPU: the '
                      f'99 % criterion is not judged ({100.0 * kept / old:.1f} % of the '
                      f'published kept; the recorder lagged {old - written} messages 1 s '
                      f'before the kill; all {written} it had written then were kept)')
    else:
        # The criterion at 6.66 kHz: 99 % of what was published 1 s before the kill.
        assert kept >= (1 - MAX_OLD_LOSS) * old, (storage, kept, old, at_kill, written)
    assert kept <= at_kill and np.all(np.diff(stamps) > 0)
    fixed = repair_bag(bag, tmp_path / f'{storage}_fixed')
    with AnyReader([tmp_path / f'{storage}_fixed']) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert sum(1 for _ in reader.messages()) == reader.message_count
    assert counts['/imu/data_raw'] == kept and fixed.messages == sum(counts.values())


# slow: two publisher processes and the recorder in real time (10 s)
@pytest.mark.slow
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
    assert rec.returncode == 130, err  # interrupted by SIGINT, the bag closed
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
    assert done.returncode == 6  # an output in the way, as in every tool
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
