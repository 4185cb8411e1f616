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
STYLE.md section 1: every module outside ``gyro_noise_ros/nodes/`` imports and runs without ROS.

One subprocess (a clean ``sys.modules``) imports every non-node module of the package, discovered
by walking the package, and reports after each import whether ``rclpy`` or any ``*_msgs`` package
got loaded, so a failure names the module that pulled ROS in.
"""

import json
import subprocess
import sys

import pytest

_PROBE = r"""
import importlib, json, pkgutil, sys
import gyro_noise_ros

def ros_loaded():
    return sorted(m for m in sys.modules
                  if m.split('.')[0] == 'rclpy' or m.split('.')[0].endswith('_msgs'))

names = sorted(info.name
               for info in pkgutil.walk_packages(gyro_noise_ros.__path__, 'gyro_noise_ros.')
               if not (info.name == 'gyro_noise_ros.nodes'
                       or info.name.startswith('gyro_noise_ros.nodes.')))
names += sys.argv[1:]  # positive control: extra modules to import after the package's own
report = {'modules': names, 'culprits': {}}
for name in names:
    importlib.import_module(name)
    loaded = ros_loaded()
    if loaded:
        report['culprits'][name] = loaded
        break
print(json.dumps(report))
"""


_CONTROL = 'gyro_noise_ros.nodes.driver'


@pytest.fixture(scope='module')
def report():
    # One subprocess for both tests: the package's modules, then the positive control last.
    proc = subprocess.run([sys.executable, '-c', _PROBE, _CONTROL], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_non_node_modules_do_not_import_ros(report):
    # Guards the discovery: the link layer must be among the modules checked.
    assert 'gyro_noise_ros.link.protocol' in report['modules']
    assert 'gyro_noise_ros.msgs.imu' in report['modules']
    assert not any(m.startswith('gyro_noise_ros.nodes') for m in report['modules'][:-1])
    culprits = {m: v for m, v in report['culprits'].items() if m != _CONTROL}
    assert culprits == {}, f'ROS imported by: {culprits}'


def test_probe_detects_a_ros_import(report):
    # Positive control: the same probe names a module that does import rclpy.
    assert list(report['culprits']) == [_CONTROL]
    assert 'rclpy' in report['culprits'][_CONTROL]
