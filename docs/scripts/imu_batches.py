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
Consume ``imu/data_raw`` at 6.66 kHz from Python in batches (the recipe of docs/batches.md).

Usage::

    python docs/scripts/imu_batches.py [--ros-args -r imu/data_raw:=/seeker/imu/data_raw]

Prints one line per second: messages, the batch sizes, the mean rate of each axis and the samples
missing from the stamps. The three steps, each a few lines you can copy:

1. a raw subscription (``raw=True``: serialised bytes, no Python message per sample) in a
   callback group the executor never runs, with a deep sensor-data history;
2. a timer (every ``PERIOD_S``) that takes every queued message with ``take_message``;
3. one bulk decode of the batch with ``gyro_noise_ros.msgs`` into numpy arrays.
"""

import sys

from gyro_noise_ros.msgs import decode_imu_spans, join_raws
import numpy as np
import rclpy
from rclpy.callback_groups import CallbackGroup
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu

#: Batch period (s): 133 messages at 6.66 kHz; the history below holds 3 s of them.
PERIOD_S = 0.02
DEPTH = 20000


class Never(CallbackGroup):
    """A callback group the executor never runs: the node takes the messages itself."""

    def can_execute(self, entity):
        return False

    def beginning_execution(self, entity):
        return False

    def ending_execution(self, entity):
        pass


class ImuBatches(Node):
    """Take ``imu/data_raw`` every ``PERIOD_S``; call :meth:`on_batch` with numpy arrays."""

    def __init__(self, **kwargs):
        super().__init__('imu_batches', **kwargs)
        # Best effort (sensor data, REP-2003) with a deep history: a reader that lags keeps up to
        # DEPTH messages and never makes the driver resend; a reliable one would.
        qos = QoSProfile(depth=DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.sub = self.create_subscription(Imu, 'imu/data_raw', lambda msg: None, qos,
                                            raw=True, callback_group=Never())
        self.create_timer(PERIOD_S, self.drain)
        self.stats = {'messages': 0, 'batches': 0, 'missing': 0, 'sum': np.zeros(3)}
        self._last_ns = None

    def drain(self):
        """Take every queued message, decode them in one go."""
        raws = []
        with self.sub.handle:
            take = self.sub.handle.take_message
            while (item := take(Imu, True)) is not None:
                raws.append(item[0])
        if raws:
            # keep: the indices decoded (None: all), e.g. when a corrupt message was skipped
            keep, stamp_ns, gyro_rad_s, accel_m_s2 = decode_imu_spans(*join_raws(raws), False,
                                                                      True)
            self.on_batch(stamp_ns, gyro_rad_s, accel_m_s2)

    def on_batch(self, stamp_ns, gyro_rad_s, accel_m_s2):
        """Use a batch: stamps (int64 ns), angular velocity (n, 3) rad/s, acceleration m/s^2."""
        s = self.stats
        s['messages'] += stamp_ns.size
        s['batches'] += 1
        s['sum'] += gyro_rad_s.sum(axis=0)
        steps = np.diff(stamp_ns if self._last_ns is None else np.r_[self._last_ns, stamp_ns])
        period = np.median(steps) if steps.size else 0
        if period > 0:  # whole periods beyond the first: samples missing before the batch's
            s['missing'] += int(np.sum(np.maximum(np.rint(steps / period) - 1, 0)))
        self._last_ns = int(stamp_ns[-1])


def main(args=None):
    """Run until Ctrl-C, printing once per second."""
    rclpy.init(args=args)
    node = ImuBatches()

    def report():
        s = node.stats
        if s['messages']:
            x, y, z = s['sum'] / s['messages']
            print(f'{s["messages"]} messages in {s["batches"]} batches, mean rate '
                  f'{x:+.2e} {y:+.2e} {z:+.2e} rad/s, {s["missing"]} missing', flush=True)

    node.create_timer(1.0, report)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
