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
``imu_chain`` (driver and compensator in one process) as a user runs it: real processes.

``portenta_emulator`` -> ``imu_chain`` (a calibration given with ``-p``) -> this test, which takes
``imu/data_raw`` and ``imu/data_compensated`` reliably and checks that every raw sample comes out
compensated, once, with the calibration applied to its values (the node's bytes against the
driver's path are checked in ``test_compensator_node.py``). The parameters of both nodes on one
command line: each node takes its own, a name neither has is refused, a name in the wrong node's
section is refused; ``--help`` lists both tables.
"""

import signal
import subprocess
import sys
import time

from _e2e import free_port
from gyro_noise_ros.bag import decode_imu
from gyro_noise_ros.calibration.apply import calibration_from_parameters
from gyro_noise_ros.nodes._ros_common import PolledGroup, take_all, unused_callback
import numpy as np
import pytest
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu

pytestmark = pytest.mark.ros

CHAIN = [sys.executable, '-m', 'gyro_noise_ros.nodes.chain']
CALIBRATION = {
    'gyro_bias_rad_s': [0.01, -0.02, 0.005], 'gyro_scale_factor': [1e-3, -1e-3, 2e-3],
    'gyro_misalignment': [0.0, -1e-3, 2e-3, 1e-3, 0.0, -5e-4, 2e-3, 1e-3, 0.0],
    'accel_bias_m_s2': [0.05, -0.04, 0.03], 'accel_scale_factor': [-2e-4, 7e-4, 5e-4],
    'accel_misalignment': [0.0, 1e-3, -2e-3, 5e-4, 0.0, 1e-3, -1e-3, 2e-3, 0.0],
}


def _params(values):
    return [word for key, value in values.items()
            for word in ('-p', f'{key}:=[{", ".join(repr(v) for v in value)}]')]


def _run(*args, timeout=60):
    return subprocess.run([*CHAIN, *args], capture_output=True, text=True, timeout=timeout)


def test_help_lists_both_nodes_parameters():
    result = _run('--help')
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert out.startswith('usage: imu_chain ')
    driver_part, compensator_part = out.split('== lsm6dso32_driver ==')[1].split(
        '== imu_compensator ==')
    assert '  port = ' in driver_part and '  calibration_file = ' not in driver_part
    assert '  calibration_file = ' in compensator_part and '  port = ' not in compensator_part


@pytest.mark.parametrize('section, name', [(None, 'bogus_name'), ('imu_compensator', 'port'),
                                           ('lsm6dso32_driver', 'gyro_bias_rad_s')])
def test_a_name_neither_node_has_or_one_given_to_the_wrong_node_is_refused(tmp_path, section,
                                                                           name):
    if section is None:
        args = ['--ros-args', '-p', 'port:=socket://127.0.0.1:9', '-p', f'{name}:=1.0']
    else:
        value = '[0.0, 0.0, 0.0]' if name.endswith('rad_s') else "'socket://127.0.0.1:9'"
        path = tmp_path / 'params.yaml'
        path.write_text(f'{section}:\n  ros__parameters:\n    {name}: {value}\n')
        args = ['--ros-args', '-p', 'port:=socket://127.0.0.1:9', '--params-file', str(path)]
    result = _run(*args)
    assert result.returncode == 2, result.stderr
    errors = [line for line in result.stderr.splitlines() if 'error' in line.lower()]
    assert len(errors) == 1 and name in errors[0] and 'Traceback' not in result.stderr
    assert ('nor does any other node of this process' in errors[0]) == (section is None)


@pytest.mark.timeout(120)
def test_every_raw_sample_comes_out_compensated_once_with_the_calibration(tmp_path, context):
    port = free_port()
    log = open(tmp_path / 'chain.log', 'w')
    chain = subprocess.Popen([*CHAIN, '--ros-args', '-p', f'port:=socket://127.0.0.1:{port}',
                              '-p', 'reconnect_period_s:=0.2', '-p', 'hardware_id:=bench_imu',
                              *_params(CALIBRATION)], stderr=log, stdout=subprocess.DEVNULL)
    node = rclpy.create_node('test_chain_probe', context=context)
    qos = QoSProfile(depth=60000, reliability=ReliabilityPolicy.RELIABLE)
    subs = {topic: node.create_subscription(Imu, topic, unused_callback, qos, raw=True,
                                            callback_group=PolledGroup())
            for topic in ('imu/data_raw', 'imu/data_compensated')}
    got = {topic: [] for topic in subs}
    emulator = None
    try:
        deadline = time.monotonic() + 30
        while not all(node.count_publishers(t) for t in subs):
            assert time.monotonic() < deadline and chain.poll() is None, (
                (tmp_path / 'chain.log').read_text())
            time.sleep(0.1)
        time.sleep(0.5)  # the readers matched: the chain's first message reaches them
        emulator = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.cli.emulator',
                                     '--tcp', f'127.0.0.1:{port}', '--seed', '3'],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while len(got['imu/data_raw']) < 10000:
            assert time.monotonic() < deadline, {t: len(v) for t, v in got.items()}
            for topic, sub in subs.items():
                got[topic] += take_all(sub, Imu)[0]
            time.sleep(0.01)
        emulator.send_signal(signal.SIGINT)
        emulator.wait(10)
        quiet_since = time.monotonic()
        while time.monotonic() - quiet_since < 1.0:  # until nothing more comes
            for topic, sub in subs.items():
                more = take_all(sub, Imu)[0]
                got[topic] += more
                if more:
                    quiet_since = time.monotonic()
            time.sleep(0.01)
        chain.send_signal(signal.SIGINT)
        code = chain.wait(20)
    finally:
        for proc in (emulator, chain):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait()
        log.close()
        node.destroy_node()
    text = (tmp_path / 'chain.log').read_text()
    assert code == 130 and 'imu_chain: interrupted' in text and 'Traceback' not in text
    assert "compensating the driver's reads in this process -> /imu/data_compensated" in text
    raw, out = (decode_imu(got[t]) for t in ('imu/data_raw', 'imu/data_compensated'))
    # every sample, once, in order, the stamps and frame kept
    np.testing.assert_array_equal(out.stamp_ns, raw.stamp_ns)
    assert np.all(np.diff(raw.stamp_ns) > 0) and out.frame_id == raw.frame_id
    gyro, accel = calibration_from_parameters(CALIBRATION).apply(raw.gyro, raw.accel)
    np.testing.assert_array_equal(out.gyro, gyro)
    np.testing.assert_array_equal(out.accel, accel)
