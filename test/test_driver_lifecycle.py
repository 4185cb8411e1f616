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
``lsm6dso32_driver`` as a ROS user meets it: QoS, lifecycle services, start-up errors, duplicates.

The driver runs in-process on a private context and domain (see test_driver_node, whose harness
and fake board are reused).
"""

import os
import subprocess
import sys
import threading
import time

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.link import protocol as P
from gyro_noise_ros.nodes._ros_common import sensor_data_qos
from gyro_noise_ros.nodes.driver import LinkConfig, Lsm6dso32Driver
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Imu
from test_driver_node import FakeBoard, Harness, harness, make_samples  # noqa: F401

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]


def test_default_qos_and_sensor_data_subscribers_both_receive(context):  # noqa: F811
    # REP-2003: a reliable publisher serves a default-QoS (reliable) subscriber such as RViz set
    # to Reliable, and a best-effort sensor-data one; a best-effort publisher starves the first.
    h = Harness(context, listen=False)
    try:
        reliable, best_effort = [], []
        h.sub_node.create_subscription(Imu, 'imu/data_raw', reliable.append,
                                       QoSProfile(depth=1000))
        h.sub_node.create_subscription(Imu, 'imu/data_raw', best_effort.append,
                                       sensor_data_qos(1000))
        h.spin_until(lambda: h.driver._imu_pub.get_subscription_count() >= 2, 10.0)
        n = 200
        h.driver.publish_samples(make_samples(np.arange(n)), time.time_ns(),
                                 LinkConfig(6667.0, 2000, 32))
        h.spin_until(lambda: len(reliable) >= n and len(best_effort) >= n, 10.0)
        assert len(reliable) == len(best_effort) == n
    finally:
        h.close()


def test_unknown_ros_argument_is_one_line_and_exit_2():
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args',
                           '--bogus'], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ))
    assert done.returncode == 2
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert lines == ["lsm6dso32_driver: error: unknown ROS arguments: ['--bogus']"], done.stderr


@pytest.mark.parametrize('url', ['socket://127.0.0.1', 'socket://:5760', 'socket://h:port'])
def test_network_url_without_port_is_refused_at_start(context, url):  # noqa: F811
    with pytest.raises(ParameterError, match="'port'"):
        Lsm6dso32Driver(context=context, parameter_overrides=[Parameter('port', value=url)])


def test_url_without_port_exits_2_from_the_command_line():
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args',
                           '-p', 'port:=socket://127.0.0.1'], capture_output=True, text=True,
                          timeout=60, env=dict(os.environ))
    assert done.returncode == 2
    assert done.stderr.strip().startswith("lsm6dso32_driver: error: parameter 'port'")
    assert 'Traceback' not in done.stderr


def test_one_sample_frame_sent_twice_counts_as_a_duplicate(harness):  # noqa: F811
    def script(board, conn):
        cmd = board.read_command(conn)
        frames = [P.encode_samples(make_samples([s])) for s in range(10)]
        # Sample 5 arrives twice, as a board re-sending its last frame would send it.
        conn.sendall(board.ack(cmd) + b''.join(frames[:6]) + frames[5] + b''.join(frames[6:]))
        board.sent.set()
        board.release.wait(20.0)

    board = FakeBoard([script])
    board.sent, board.release = threading.Event(), threading.Event()
    try:
        h = harness(port=board.url)
        h.spin_until(lambda: h.driver.link_snapshot()['link'].get('frames_ok', 0) >= 11, 10.0)
        values = {kv.key: kv.value for kv in h.driver.link_status().values}
        assert values['Samples published'] == '10'
        assert values['Duplicates dropped'] == '1'
        assert values['Samples lost'] == '0'
    finally:
        board.release.set()
        board.close()


def _call(h, client, request, timeout_s=10.0):
    future = client.call_async(request)
    h.spin_until(future.done, timeout_s)
    return future.result()


def _transition(h, client, transition_id):
    request = ChangeState.Request()
    request.transition = Transition(id=transition_id)
    return _call(h, client, request).success


def test_lifecycle_through_the_services(context):  # noqa: F811
    connected, released, stop = threading.Event(), threading.Event(), threading.Event()

    def script(board, conn):
        cmd = board.read_command(conn)
        connected.set()
        conn.sendall(board.ack(cmd))
        seq = 0
        conn.settimeout(0.005)
        while not stop.is_set():
            conn.sendall(P.encode_samples(make_samples(np.arange(seq, seq + 16))))
            seq += 16
            try:
                if conn.recv(64) == b'':
                    break  # the driver closed the port
            except (TimeoutError, OSError):
                pass
        released.set()

    board = FakeBoard([script])
    h = Harness(context, listen=False, port=board.url, autostart=False)
    try:
        got = []
        h.sub_node.create_subscription(Imu, 'imu/data_raw', got.append, sensor_data_qos(10000))
        get_state = h.sub_node.create_client(GetState, '/lsm6dso32_driver/get_state')
        change = h.sub_node.create_client(ChangeState, '/lsm6dso32_driver/change_state')
        h.spin_until(lambda: get_state.service_is_ready() and change.service_is_ready(), 10.0)

        def state():
            return _call(h, get_state, GetState.Request()).current_state.label

        assert state() == 'unconfigured'
        time.sleep(0.3)
        assert not connected.is_set(), 'the port must stay closed until configure'

        assert _transition(h, change, Transition.TRANSITION_CONFIGURE)
        assert state() == 'inactive'
        h.spin_until(lambda: connected.is_set()
                     and h.driver.link_snapshot()['discarded'] > 100, 10.0)
        assert got == [] and h.driver.link_snapshot()['published'] == 0

        assert _transition(h, change, Transition.TRANSITION_ACTIVATE)
        assert state() == 'active'
        h.spin_until(lambda: len(got) >= 200, 10.0)

        assert _transition(h, change, Transition.TRANSITION_DEACTIVATE)
        assert state() == 'inactive'
        published = h.driver.link_snapshot()['published']
        time.sleep(0.2)
        assert h.driver.link_snapshot()['published'] == published
        # Samples dropped while inactive are not losses.
        assert h.driver.link_snapshot()['lost'] == 0

        assert _transition(h, change, Transition.TRANSITION_CLEANUP)
        assert state() == 'unconfigured'
        assert released.wait(10.0), 'cleanup must release the port'
    finally:
        stop.set()
        h.close()
        board.close()
