"""
STYLE.md section 1: every module outside ``gyro_noise_ros/nodes/`` imports and runs without ROS.

One subprocess (a clean ``sys.modules``) imports every non-node module of the package, discovered
by walking the package, and reports after each import whether ``rclpy`` or any ``*_msgs`` package
got loaded, so a failure names the module that pulled ROS in.
"""

import json
import subprocess
import sys

_PROBE = r'''
import importlib, json, pkgutil, sys
import gyro_noise_ros

def ros_loaded():
    return sorted(m for m in sys.modules
                  if m.split('.')[0] == 'rclpy' or m.split('.')[0].endswith('_msgs'))

names = sorted(info.name for info in pkgutil.walk_packages(gyro_noise_ros.__path__, 'gyro_noise_ros.')
               if not (info.name == 'gyro_noise_ros.nodes' or info.name.startswith('gyro_noise_ros.nodes.')))
names += sys.argv[1:]  # positive control: extra modules to import after the package's own
report = {'modules': names, 'culprits': {}}
for name in names:
    importlib.import_module(name)
    loaded = ros_loaded()
    if loaded:
        report['culprits'][name] = loaded
        break
print(json.dumps(report))
'''


def _probe(*extra):
    proc = subprocess.run([sys.executable, '-c', _PROBE, *extra], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_non_node_modules_do_not_import_ros():
    report = _probe()
    # Guards the discovery: the link layer must be among the modules checked.
    assert 'gyro_noise_ros.link.protocol' in report['modules']
    assert not any(m.startswith('gyro_noise_ros.nodes') for m in report['modules'])
    assert report['culprits'] == {}, f'ROS imported by: {report["culprits"]}'


def test_probe_detects_a_ros_import():
    # Positive control: the same probe must name a module that does import rclpy.
    report = _probe('gyro_noise_ros.nodes.driver')
    assert list(report['culprits']) == ['gyro_noise_ros.nodes.driver']
    assert 'rclpy' in report['culprits']['gyro_noise_ros.nodes.driver']
