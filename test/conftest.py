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
Shared fixtures: the private ROS graph every ROS-starting test runs in.

``ros_graph`` leases a ``ROS_DOMAIN_ID`` checked free on this host and held for the test
(:func:`gyro_noise_ros.rosgraph.lease_domain`: port tables plus a file lock, domains 1..101, never
0) and puts the private graph's environment into ``os.environ`` for the test's duration
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, no static peers, no discovery server, no DDS XML
profile): rclpy contexts created in the test and every subprocess started with the default or a
copied environment join that graph and no other.

Every test marked ``ros`` gets the fixture without asking. Outside it, ``ROS_DOMAIN_ID`` holds a
value rcl refuses ("not an integral number"), so a test that starts ROS without the marker or the
fixture fails at ``rclpy.init`` instead of joining domain 0, the one a robot uses.
"""

import os

from gyro_noise_ros import rosgraph
import pytest

#: ``ROS_DOMAIN_ID`` outside the fixture: rcl refuses it, so nothing joins a real graph by mistake.
NO_GRAPH = 'none-use-the-ros_graph-fixture'


class RosGraph:
    """
    The private graph of one test.

    Attributes
    ----------
    domain_id : int
        Its ``ROS_DOMAIN_ID`` (held until the test ends).

    """

    def __init__(self, lease):
        self._lease = lease
        self.domain_id = lease.domain_id

    def env(self, **extra):
        """Return the environment of a subprocess in this graph (``os.environ`` plus ``extra``)."""
        return {**self._lease.env(), **{k: str(v) for k, v in extra.items()}}

    def __repr__(self):
        return f'RosGraph(domain_id={self.domain_id})'


def pytest_collection_modifyitems(config, items):
    # A ``usefixtures`` mark added here would come too late for the fixture closure; the names
    # list is what pytest sets up, first entry first.
    for item in items:
        if item.get_closest_marker('ros') is not None and 'ros_graph' not in item.fixturenames:
            item.fixturenames.insert(0, 'ros_graph')


_saved_domain = []


def pytest_configure(config):
    # Set before any fixture or test module runs: outside ``ros_graph``, ``rclpy.init`` fails
    # rather than join domain 0.
    _saved_domain.append(os.environ.get('ROS_DOMAIN_ID'))
    os.environ['ROS_DOMAIN_ID'] = NO_GRAPH


def pytest_unconfigure(config):
    if _saved_domain:
        saved = _saved_domain.pop()
        if saved is None:
            os.environ.pop('ROS_DOMAIN_ID', None)
        else:
            os.environ['ROS_DOMAIN_ID'] = saved


@pytest.fixture
def ros_graph(monkeypatch):
    """Lease a free domain and put its localhost-only environment into ``os.environ``."""
    with rosgraph.lease_domain() as lease:
        for name in rosgraph.UNSET_VARIABLES:
            monkeypatch.delenv(name, raising=False)
        for name, value in lease.env().items():
            if os.environ.get(name) != value:
                monkeypatch.setenv(name, value)
        yield RosGraph(lease)


@pytest.fixture
def context(ros_graph):
    """Yield an initialised rclpy context in the test's private graph (shut down afterwards)."""
    import rclpy

    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        yield ctx
    finally:
        rclpy.try_shutdown(context=ctx)
