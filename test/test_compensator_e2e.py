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
End to end: emulator -> driver -> imu_compensator (causal thermal model) -> noise_analyzer.

The emulator ramps the die temperature and leaks it into the gyro bias with a known linear
sensitivity; the driver publishes what the device reports (REP-145); the compensator subtracts
the offset of a causal model with the emulator's sensitivity, evaluated per imu/temperature
message and interpolated onto the gyro stamps. Two analyzers run side by side, one on
``imu/data_raw`` and one remapped onto ``imu/data_compensated``: the first sees the offset drift
the ramp causes, the second sees it gone.
"""

import json
import math
import os
from pathlib import Path
import random
import select
import socket
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.ros

HERE = Path(__file__).resolve().parent
DEG = math.pi / 180.0

# 2 degC/s (7200 degC/h) and 0.02 (deg/s)/degC per axis: the bias ramps 0.04 (deg/s)/s = 144
# (deg/s)/h, far above the analyzer's slope noise (emulator's default noise, chunks of 2000
# samples, ~20 chunks: a few (deg/s)/h), within the chosen WARN limit's sight (50 (deg/s)/h).
RAMP_C_PER_H = 7200.0
SENSITIVITY_DPS_PER_C = (0.02, -0.02, 0.01)
EXPECTED_DRIFT = [s * RAMP_C_PER_H for s in SENSITIVITY_DPS_PER_C]  # (deg/s)/h
ANALYZER_PARAMS = ['chunk_size:=2000', 'memory:=200', 'order_grid_step:=0.05',
                   'diagnostics_period_s:=0.5', 'allan:=false',
                   'drift_abs_warn_deg_s_per_h:=50.0', 'drift_abs_error_deg_s_per_h:=100000.0']

# The compensator with the test's causal model (a model.json loader is the thermal registry's job):
# the model is LinearThermal of test/_thermal_linear.py, built from the JSON on the command line.
_COMPENSATOR = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
from _thermal_linear import LinearThermal
from gyro_noise_ros.nodes import compensator
from gyro_noise_ros.nodes._ros_common import run_node
model = LinearThermal(**json.loads(sys.argv[2]))
sys.exit(run_node(lambda: compensator.ImuCompensatorNode(thermal_model=model), sys.argv[3:],
                  prog='imu_compensator'))
"""


def _free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def _readline(proc, timeout_s):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 0.2)
        if ready:
            line = proc.stdout.readline()
            if line:
                return line.strip()
        if proc.poll() is not None:
            break
    raise AssertionError(f'emulator printed no port (exit {proc.poll()})')


def _collect(names, until, timeout_s):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    context = rclpy.Context()
    rclpy.init(context=context)
    seen = {n: [] for n in names}
    try:
        node = rclpy.create_node('test_e2e_diagnostics', context=context)
        node.create_subscription(DiagnosticArray, '/diagnostics', lambda m: [
            seen[s.name].append(s) for s in m.status if s.name in seen], 100)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not until(seen):
            executor.spin_once(timeout_sec=0.1)
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return seen


def _values(status):
    return {kv.key: kv.value for kv in status.values}


def _chunks(status):
    return int(_values(status).get('Chunks analysed', '0'))


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_compensated_stream_shows_the_thermal_drift_gone(tmp_path, monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', str(random.randint(100, 200)))
    env = dict(os.environ)
    logs = {name: open(tmp_path / f'{name}.log', 'w') for name in
            ('emulator', 'driver', 'compensator', 'analyzer_raw', 'analyzer_comp')}
    procs = []

    def start(name, argv, **kw):
        proc = subprocess.Popen(argv, stderr=logs[name], env=env, **kw)
        procs.append(proc)
        return proc

    model = {'sensitivity': [s * DEG for s in SENSITIVITY_DPS_PER_C], 't_ref': 25.0,
             'temperature_range_c': [20.0, 60.0]}
    chunks_wanted = 16
    try:
        emu = start('emulator', [sys.executable, '-m', 'gyro_noise_ros.cli.emulator', '--tcp',
                                 f'127.0.0.1:{_free_port()}', '--seed', '7', '--accel-fs-g', '32',
                                 '--temp-c', '25.0', '--temp-drift-c-per-h', str(RAMP_C_PER_H),
                                 '--temp-sensitivity-dps-per-c',
                                 ','.join(map(str, SENSITIVITY_DPS_PER_C))],
                    stdout=subprocess.PIPE, text=True)
        url = _readline(emu, 60.0)
        for name, remap in (('analyzer_raw', []),
                            ('analyzer_comp', ['-r', 'imu/data_raw:=imu/data_compensated'])):
            argv = [sys.executable, '-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args',
                    '-r', f'__node:={name}', *remap]
            for p in ANALYZER_PARAMS:
                argv += ['-p', p]
            start(name, argv, stdout=subprocess.DEVNULL)
        start('compensator', [sys.executable, '-c', _COMPENSATOR, str(HERE), json.dumps(model),
                              '--ros-args', '-p', 'drain_period_s:=0.02'],
              stdout=subprocess.DEVNULL)
        start('driver', [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args', '-p',
                         f'port:={url}', '-p', 'reconnect_period_s:=0.2'],
              stdout=subprocess.DEVNULL)
        names = [f'{a}: axis {x}' for a in ('analyzer_raw', 'analyzer_comp') for x in 'xyz']
        names.append('imu_compensator: compensation')

        def done(seen):
            return all(seen[n] and _chunks(seen[n][-1]) >= chunks_wanted for n in names[:-1]) \
                and bool(seen[names[-1]])

        seen = _collect(names, done, timeout_s=150)
    finally:
        for proc in reversed(procs):
            if proc.poll() is None:
                proc.send_signal(2)
        for proc in procs:
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        for fh in logs.values():
            fh.close()
    text = '\n'.join(f'--- {p.name}\n{p.read_text()[-2000:]}' for p in tmp_path.glob('*.log'))
    assert done(seen), ({n: seen[n] and _chunks(seen[n][-1]) for n in names[:-1]}, text)

    comp = _values(seen['imu_compensator: compensation'][-1])
    assert comp['Thermal model'] == 'linear_test'
    assert comp['Temperature range status'] == 'inside', comp
    for axis, expected in zip('xyz', EXPECTED_DRIFT):
        raw = _values(seen[f'analyzer_raw: axis {axis}'][-1])
        fixed = _values(seen[f'analyzer_comp: axis {axis}'][-1])
        raw_drift = float(raw['Offset drift ((deg/s)/h)'])
        fixed_drift = float(fixed['Offset drift ((deg/s)/h)'])
        # The raw stream carries the emulator's ramp x sensitivity; the analyzer's slope over ~16
        # chunks of 0.3 s has a standard error of a few (deg/s)/h on the emulator's default noise,
        # so 15 % of 72-144 (deg/s)/h is several standard errors wide.
        assert raw_drift == pytest.approx(expected, rel=0.15), (axis, raw_drift, expected)
        # Compensated: what is left is the slope noise plus the model's lag (the offset is held
        # between 52-Hz temperature messages: a constant, which does not tilt the slope).
        assert abs(fixed_drift) < 0.1 * abs(expected), (axis, fixed_drift, expected, text)
