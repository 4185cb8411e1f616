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

"""The nodes give free heap pages back to the system (``_ros_common.heap_trim_timer``)."""

import ctypes
import sys

from gyro_noise_ros.nodes._ros_common import _malloc_trim, HEAP_TRIM_PERIOD_S, heap_trim_timer
import pytest


def _glibc():
    try:
        ctypes.CDLL(None).gnu_get_libc_version
    except (OSError, AttributeError):
        return False
    return sys.platform.startswith('linux')


@pytest.mark.skipif(not _glibc(), reason='malloc_trim is a glibc call')
def test_malloc_trim_is_found_and_runs_on_glibc():
    trim = _malloc_trim()
    assert trim is not None
    blocks = [bytearray(1 << 20) for _ in range(64)]  # 64 MB from the heap, then freed
    del blocks
    assert trim() in (0, 1)  # 1: memory was released, 0: none could be


@pytest.mark.ros
@pytest.mark.skipif(not _glibc(), reason='malloc_trim is a glibc call')
def test_the_heap_trim_timer_is_a_steady_timer_of_the_documented_period(context):
    import rclpy
    from rclpy.clock import ClockType

    node = rclpy.create_node('heap_trim_test', context=context)
    try:
        timer = heap_trim_timer(node)
        assert timer is not None and timer in node.timers
        assert timer.timer_period_ns == int(HEAP_TRIM_PERIOD_S * 1e9)
        assert timer.clock.clock_type == ClockType.STEADY_TIME
    finally:
        node.destroy_node()
