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
``docs/diagnostics.md`` lists every ``/diagnostics`` key the nodes publish, and no other.

The nodes run in-process: the driver unconfigured and streaming-less (its key set is fixed), the
analyzer before any data and after a few chunks of a bag (its key set grows with the data).
"""

from pathlib import Path
import re

from gyro_noise_ros.nodes.analyzer import NoiseAnalyzerNode
from gyro_noise_ros.nodes.driver import Lsm6dso32Driver
import pytest
from rclpy.parameter import Parameter
from test_analyzer_node import _make_bag, _raw_messages, _replay, _spin_until
from test_driver_node import closed_port_url

pytestmark = [pytest.mark.ros, pytest.mark.timeout(180)]

DOC = Path(__file__).resolve().parents[1] / 'docs' / 'diagnostics.md'


def _documented(heading_start):
    text = DOC.read_text()
    section = text.split('\n## ' + heading_start, 1)[1].split('\n## ', 1)[0]
    return set(re.findall(r'^\| `([^`]+)` \|', section, flags=re.MULTILINE)) - {'key'}


def _keys(status):
    return {kv.key for kv in status.values}


def test_driver_keys_are_documented(context):
    driver = Lsm6dso32Driver(context=context, parameter_overrides=[
        Parameter('port', value=closed_port_url()), Parameter('autostart', value=False)])
    try:
        published = _keys(driver.link_status())
    finally:
        driver.destroy_node()
    assert published == _documented('`lsm6dso32_driver`')


def test_analyzer_keys_are_documented(context, tmp_path):
    documented = _documented('`noise_analyzer`')
    node = NoiseAnalyzerNode(context=context, parameter_overrides=[
        Parameter('chunk_size', value=1000), Parameter('memory', value=100),
        Parameter('order_grid_step', value=0.1), Parameter('allan_period_s', value=0.1)])
    executor = pub_node = None
    try:
        seen = set()
        for status in node.diagnostics().status:
            seen |= _keys(status)
        _make_bag(tmp_path / 'bag', 5000, seed=3)
        executor, pub_node = _replay(context, node, _raw_messages(tmp_path / 'bag'))
        assert _spin_until(executor, lambda: len(node.results) >= 12, 60)
        for status in node.diagnostics().status:
            seen |= _keys(status)
        assert {'Last chunk', 'Bias stability (deg/s)', 'Offset drift ((deg/s)/h)'} <= seen
        assert seen <= documented, f'undocumented keys: {sorted(seen - documented)}'
    finally:
        if executor is not None:
            executor.shutdown()
        if pub_node is not None:
            pub_node.destroy_node()
        node.destroy_node()
