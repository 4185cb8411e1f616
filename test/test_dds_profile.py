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

"""The nodes' participant profile: a subscriber killed -9 no longer stalls a reliable stream."""

import os
from pathlib import Path
import signal
import subprocess
import sys
import textwrap
import time

from gyro_noise_ros.nodes import _dds_profile
import pytest

_SCRIPT = textwrap.dedent("""
    import sys, time
    role, depth, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    if role == 'victim' and sys.argv[4] == 'profile':
        from gyro_noise_ros.nodes._dds_profile import use_package_profile
        assert use_package_profile()
    import rclpy
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Imu
    rclpy.init()
    node = rclpy.create_node('dds_profile_' + role)
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                     reliability=ReliabilityPolicy.RELIABLE)
    t0 = time.monotonic()
    if role == 'pub':  # 6.66 kHz in 16-message batches, as the driver publishes a board frame
        pub = node.create_publisher(Imu, 'dds_profile_imu', qos)
        raw, n = serialize_message(Imu()), 0
        while time.monotonic() - t0 < seconds:
            with pub.handle:
                while n < int((time.monotonic() - t0) * 6660):
                    pub.handle.publish_raw(raw)
                    n += 1
            print(time.monotonic(), n, flush=True)
            time.sleep(0.0024)
    else:  # a reliable reader; 'live' prints its running count
        sub = node.create_subscription(Imu, 'dds_profile_imu', lambda m: None, qos, raw=True)
        n = 0
        while time.monotonic() - t0 < seconds:
            with sub.handle:
                while sub.handle.take_message(Imu, True) is not None:
                    n += 1
            if role == 'live':
                print(time.monotonic(), n, flush=True)
            time.sleep(0.002)
""")


def _series(text):
    return [tuple(map(float, line.split())) for line in text.splitlines()
            if line and line[0].isdigit()]


def _count_at(series, t):
    return max((n for s, n in series if s <= t), default=0.0)


def test_the_profile_is_used_unless_the_user_chose(monkeypatch):
    for name in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                 'RMW_IMPLEMENTATION'):
        # set, then removed: monkeypatch restores what was there before (nothing) afterwards,
        # also for the variable use_package_profile() sets
        monkeypatch.setenv(name, 'placeholder')
        monkeypatch.delenv(name)
    assert _dds_profile.use_package_profile()
    assert os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] == str(_dds_profile.PROFILE)
    text = Path(_dds_profile.PROFILE).read_text()
    assert f'<leaseDuration><sec>{_dds_profile.LEASE_S:g}</sec>' in text
    # the constants the docs and bench_soak read are the file's values (the file is the owner)
    announce_ns = round(_dds_profile.ANNOUNCE_S * 1e9)
    assert (f'<leaseAnnouncement><sec>{int(_dds_profile.ANNOUNCE_S)}</sec><nanosec>'
            f'{announce_ns % 10 ** 9}</nanosec>') in text
    # the user's own profile file, or another middleware: left as it is
    for name, value in (('FASTRTPS_DEFAULT_PROFILES_FILE', '/theirs.xml'),
                        ('FASTDDS_DEFAULT_PROFILES_FILE', '/theirs.xml'),
                        ('RMW_IMPLEMENTATION', 'rmw_cyclonedds_cpp')):
        monkeypatch.delenv('FASTRTPS_DEFAULT_PROFILES_FILE', raising=False)
        monkeypatch.setenv(name, value)
        assert not _dds_profile.use_package_profile()
        assert os.environ.get('FASTRTPS_DEFAULT_PROFILES_FILE') in (None, '/theirs.xml')
        monkeypatch.delenv(name)
    monkeypatch.setenv('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    assert _dds_profile.use_package_profile()


# slow: a 6.66 kHz reliable stream for 14 s with a reader killed -9 beside a live one
@pytest.mark.slow
@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_reader_killed_9_does_not_stall_the_stream_for_the_others(ros_graph, tmp_path):
    # At the lab depth (60,000) a dead reliable reader with Fast DDS's 20-s lease slowed the
    # writer to 1,000-2,000 messages/s for ~25 s (docs/scale.md); announcing the package's 3-s
    # lease, the live reader must have nearly everything 6 s after the kill.
    script = tmp_path / 'dds_profile_roles.py'
    script.write_text(_SCRIPT)
    env = ros_graph.env(PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    for name in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE'):
        env.pop(name, None)

    def start(role, *args):
        # into files: a pipe nobody reads would stop a printing reader, and the writer with it
        with open(tmp_path / f'{role}.out', 'w') as out, \
                open(tmp_path / f'{role}.err', 'w') as err:
            return subprocess.Popen([sys.executable, str(script), role, *map(str, args)],
                                    env=env, stdout=out, stderr=err)

    def output(role):
        return (tmp_path / f'{role}.out').read_text(), (tmp_path / f'{role}.err').read_text()

    live = start('live', 60000, 18)
    victim = start('victim', 60000, 30, 'profile')
    time.sleep(2.0)
    pub = start('pub', 60000, 14)
    try:
        time.sleep(5.0)
        assert victim.poll() is None, output('victim')[1][-2000:]
        killed = time.monotonic()
        victim.send_signal(signal.SIGKILL)
        pub.wait(timeout=60)
        live.wait(timeout=60)
    finally:
        for proc in (live, victim, pub):
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    (pub_out, pub_err), (live_out, live_err) = output('pub'), output('live')
    assert pub.returncode == 0 and live.returncode == 0, (pub_err[-2000:], live_err[-2000:])
    sent, got = _series(pub_out), _series(live_out)

    def window(start, end):
        return (_count_at(sent, end) - _count_at(sent, start),
                _count_at(got, end) - _count_at(got, start))

    published, received = window(killed - 2.0, killed)
    assert received > 0.9 * published > 0.9 * 0.8 * 2.0 * 6660  # keeping up before the kill
    published, received = window(killed, killed + 6.0)
    assert published > 0.8 * 6.0 * 6660  # the writer itself kept its rate
    assert received > 0.9 * published, (received, published)
