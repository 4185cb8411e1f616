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
The analyzer under ``use_sim_time`` with a late, paused or absent ``/clock``.

What ``ros2 bag play --clock`` does, written as a test publisher (``ros2 bag`` is not on PyPI):
``/clock`` once at the first stamp, then paused, while Imu messages stamped on the recording's
time base keep coming. Draining on the ROS clock stalls there: the subscription queue overflows
and the analyzer reported samples lost that were never lost. It must receive every message and
judge losses from the stamps only.
"""

import time

from builtin_interfaces.msg import Time
from gyro_noise_ros.msgs import encode_imu_cdr
from gyro_noise_ros.nodes.analyzer import NoiseAnalyzerNode
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

RATE_HZ = 1000.0
T0_NS = 1_700_000_000_000_000_000


@pytest.mark.parametrize('clock_messages', [0, 1], ids=['no_clock', 'paused_clock'])
def test_paused_clock_gives_no_false_loss(clock_messages):
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    executor = SingleThreadedExecutor(context=ctx)
    node = NoiseAnalyzerNode(context=ctx, parameter_overrides=[
        Parameter('use_sim_time', value=True), Parameter('chunk_size', value=1000),
        Parameter('memory', value=100), Parameter('order_grid_step', value=0.1),
        Parameter('rate_hz', value=RATE_HZ), Parameter('allan', value=False),
        Parameter('use_temperature', value=False), Parameter('queue_depth', value=2000)])
    player = rclpy.create_node('bag_player', context=ctx)
    try:
        executor.add_node(node)
        executor.add_node(player)
        clock_pub = player.create_publisher(Clock, '/clock', QoSProfile(depth=10))
        imu_pub = player.create_publisher(Imu, 'imu/data_raw', QoSProfile(depth=5000))
        end = time.monotonic() + 10.0
        while imu_pub.get_subscription_count() < 1 or (clock_messages and
                                                       clock_pub.get_subscription_count() < 1):
            assert time.monotonic() < end, 'discovery timed out'
            executor.spin_once(timeout_sec=0.02)
        for _ in range(clock_messages):
            clock_pub.publish(Clock(clock=Time(sec=T0_NS // 10**9, nanosec=T0_NS % 10**9)))
        n = 5000  # 5 chunks; 2.5 queue depths, so a stalled drain must overflow
        rng = np.random.default_rng(0)
        stamps = T0_NS + np.rint(np.arange(n) * 1e9 / RATE_HZ).astype(np.int64)
        blobs = encode_imu_cdr(stamps, rng.standard_normal((n, 3)) * 1e-3, np.zeros((n, 3)))
        sent = 0
        while sent < n or node.messages_received < n:
            assert time.monotonic() < end + 30.0, (node.messages_received, sent)
            for blob in blobs[sent:sent + 100]:  # 100 ms of recording per burst
                imu_pub.publish(blob)
            sent = min(n, sent + 100)
            executor.spin_once(timeout_sec=0.01)
        assert node.messages_received == n
        # The worker analyses the 5 chunks and the drain timer collects them; until then the
        # status is STALE ('no complete chunk yet'), whatever the clock.
        while len(node.results) < 3 * (n // 1000):
            assert time.monotonic() < end + 60.0, len(node.results)
            executor.spin_once(timeout_sec=0.02)
        counts = next(iter(node.engine.summary(allan=False).values())).stream
        assert counts.samples == n and counts.samples_lost == 0
        for status in node.diagnostics().status:
            values = {kv.key: kv.value for kv in status.values}
            assert values['Samples lost'].startswith('0 '), values['Samples lost']
            assert status.level[0] < 2, status.message
    finally:
        executor.shutdown()
        node.destroy_node()
        player.destroy_node()
        rclpy.try_shutdown(context=ctx)
