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

"""The batch-consumption recipe (docs/batches.md, docs/scripts/imu_batches.py)."""

import importlib.util
from pathlib import Path
import time

from gyro_noise_ros.msgs import encode_imu_cdr
from gyro_noise_ros.nodes._ros_common import driver_qos
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import Imu

pytestmark = pytest.mark.ros

_SCRIPT = Path(__file__).resolve().parents[1] / 'docs' / 'scripts' / 'imu_batches.py'


def _recipe():
    spec = importlib.util.spec_from_file_location('imu_batches', _SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.timeout(60)
def test_the_recipe_gets_every_message_in_batches_with_its_values(context):
    recipe = _recipe()
    node = recipe.ImuBatches(context=context)
    got = []
    plain_on_batch = node.on_batch

    def keep(stamp_ns, gyro, accel):
        got.append((stamp_ns, gyro, accel))
        plain_on_batch(stamp_ns, gyro, accel)

    node.on_batch = keep
    source = rclpy.create_node('recipe_source', context=context)
    pub = source.create_publisher(Imu, 'imu/data_raw', driver_qos(5000))  # as the driver does
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(source)
    try:
        deadline = time.monotonic() + 20
        while pub.get_subscription_count() < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        rng = np.random.default_rng(4)
        n, rate = 4000, 6667.0
        stamps = 10**18 + np.rint(np.arange(n) * 1e9 / rate).astype(np.int64)
        gyro, accel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
        sent = np.ones(n, bool)
        sent[[1000, 2500, 2501]] = False  # three samples the board lost: the stamps show them
        blobs = encode_imu_cdr(stamps[sent], gyro[sent], accel[sent])
        for start in range(0, len(blobs), 64):  # a frame at a time, as the driver publishes
            for blob in blobs[start:start + 64]:
                pub.publish(blob)
            executor.spin_once(timeout_sec=0.001)
        while node.stats['messages'] < sent.sum() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()
    assert node.stats['messages'] == sent.sum()
    assert 1 < node.stats['batches'] < len(blobs)  # taken in batches, not one by one
    stamp_ns, g, a = (np.concatenate(x) for x in zip(*got))
    np.testing.assert_array_equal(stamp_ns, stamps[sent])
    np.testing.assert_array_equal(g, gyro[sent])
    np.testing.assert_array_equal(a, accel[sent])
    assert node.stats['missing'] == 3
