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
CPU share of ``imu_compensator`` at 6.66 kHz, as a ratio to the driver's own cost in the same run.

Budget: calibration + thermal compensation at the full rate within 20 % of one core (issue 31).
One chain, emulator (real time, TCP loopback) -> ``lsm6dso32_driver`` -> ``imu_compensator``
(its defaults: messages taken as they arrive, ``drain_period_s`` 0; ``--drain-period-s 0.05`` for
the timer drain) -> a raw subscriber in this process draining ``imu/data_compensated`` every 5 ms,
is started for each compensator configuration; the driver's and the compensator's CPU (utime +
stime from ``/proc/<pid>/stat``) are measured over the same window after a warm-up:

1. pass-through: identity calibration, no thermal model (the transport: take, decode, re-encode,
   publish);
2. calibration: a full calibration (bias, scale, misalignment of both sensors);
3. calibration + thermal: as 2 with a causal linear-in-(T, dT) model evaluated per temperature
   message (52 Hz) and interpolated onto every gyro stamp.

Besides the node, the pure arithmetic (calibration + thermal offset on 6,660 samples in
20-ms batches, no ROS) is timed in this process, so the cost of the corrections themselves is
visible apart from the transport. Run: ``.venv/bin/python bench/bench_compensator.py``.
"""

import argparse
import os
import shlex
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_driver import cpu_seconds, free_port, start_emulator, stop  # noqa: E402
import numpy as np  # noqa: E402

ODR = 6667.0

# A compensator process: the node with an injected causal model (the thermal registry's
# model.json loader is another helper's work), spun by the package's Jazzy main() helper.
_COMPENSATOR = r"""
import sys
import numpy as np
from gyro_noise_ros.nodes import compensator
from gyro_noise_ros.nodes._ros_common import run_node


class Linear:
    name = 'bench_linear'
    causal = True
    temperature_range_c = (-40.0, 85.0)

    def drift_rad_s(self, temperature_c, dtemp_c_s):
        t = np.asarray(temperature_c)[:, None]
        r = np.asarray(dtemp_c_s)[:, None]
        return np.array([1e-3, 0.0, -1e-3]) + 2e-4 * (t - 25.0) + 1e-2 * r


model = Linear() if sys.argv[1] == 'thermal' else None
sys.exit(run_node(lambda: compensator.ImuCompensatorNode(thermal_model=model), sys.argv[2:],
                  prog='bench_compensator'))
"""

CALIBRATION = {
    'accel_bias_m_s2': [0.05, -0.04, 0.03], 'accel_scale_factor': [-2e-4, 7e-4, 5e-4],
    'accel_misalignment': [0.0, 1e-3, -2e-3, 5e-4, 0.0, 1e-3, -1e-3, 2e-3, 0.0],
    'gyro_bias_rad_s': [0.01, -0.02, 0.005], 'gyro_scale_factor': [1e-3, -1e-3, 2e-3],
    'gyro_misalignment': [0.0, -1e-3, 2e-3, 1e-3, 0.0, -5e-4, 2e-3, 1e-3, 0.0],
}


def _param_args(calibrated):
    args = []
    if calibrated:
        for key, value in CALIBRATION.items():
            args += ['-p', f'{key}:=[{", ".join(repr(v) for v in value)}]']
    return args


class Listener:
    """Raw reliable subscription on imu/data_compensated drained every 5 ms."""

    def __init__(self):
        import rclpy
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Imu

        from gyro_noise_ros.nodes._ros_common import PolledGroup, take_all, unused_callback
        self.rclpy, self.take_all, self.imu = rclpy, take_all, Imu
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('bench_compensated_listener', context=self.context)
        qos = QoSProfile(depth=20000, reliability=ReliabilityPolicy.RELIABLE)
        self.sub = self.node.create_subscription(Imu, 'imu/data_compensated', unused_callback,
                                                 qos, raw=True, callback_group=PolledGroup())
        self.count = 0

    def drain(self):
        self.count += len(self.take_all(self.sub, self.imu)[0])

    def close(self):
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def measure(kind, args, listener):
    """Run emulator -> driver -> compensator; return CPU % of one core of driver and node."""
    port = free_port()
    emu = start_emulator(port)
    driver = subprocess.Popen(
        [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args', '-p',
         f'port:=socket://127.0.0.1:{port}', '-p', 'reconnect_period_s:=0.2'],
        stderr=subprocess.DEVNULL)
    comp = subprocess.Popen(
        [sys.executable, '-c', _COMPENSATOR, 'thermal' if kind == 'thermal' else 'none',
         '--ros-args', '-p', f'drain_period_s:={args.drain_period_s}',
         *_param_args(kind != 'pass-through')],
        stderr=subprocess.DEVNULL)
    try:
        def wait(seconds):
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                listener.drain()
                time.sleep(0.005)

        wait(args.warmup)
        d0, c0, n0, t0 = cpu_seconds(driver.pid), cpu_seconds(comp.pid), listener.count, \
            time.monotonic()
        wait(args.seconds)
        d1, c1, n1, t1 = cpu_seconds(driver.pid), cpu_seconds(comp.pid), listener.count, \
            time.monotonic()
        assert driver.poll() is None and comp.poll() is None, f'{kind}: a process exited early'
    finally:
        stop(comp)
        stop(driver)
        stop(emu)
    wall = t1 - t0
    return {'driver': 100 * (d1 - d0) / wall, 'node': 100 * (c1 - c0) / wall,
            'rate': (n1 - n0) / wall}


def pure_cost(seconds=2.0):
    """CPU % of one core of calibration + thermal arithmetic alone at 6.66 kHz in 20-ms batches."""
    from gyro_noise_ros.calibration.apply import calibration_from_parameters
    from gyro_noise_ros.thermal.live import LiveDriftEvaluator

    class Linear:

        name, causal, temperature_range_c = 'bench_linear', True, (-40.0, 85.0)

        def drift_rad_s(self, temperature_c, dtemp_c_s):
            return np.array([1e-3, 0.0, -1e-3]) + 2e-4 * (np.asarray(temperature_c)[:, None]
                                                          - 25.0) \
                + 1e-2 * np.asarray(dtemp_c_s)[:, None]

    cal = calibration_from_parameters(CALIBRATION)
    ev = LiveDriftEvaluator(Linear())
    # a model using dT gives offsets once its 10-s rate window has filled: fill it first
    ev.add_temperature(np.arange(-11, 0, dtype=np.int64) * 1_000_000_000, np.full(11, 25.0))
    rng = np.random.default_rng(0)
    batch = int(ODR * 0.02)
    n_batches = int(seconds / 0.02)
    gyro = rng.normal(size=(batch, 3))
    accel = rng.normal(size=(batch, 3))
    step = int(1e9 / ODR)
    t_start = time.process_time()
    for i in range(n_batches):
        stamps = np.arange(i * batch, (i + 1) * batch, dtype=np.int64) * step
        # 52 Hz temperature: about one message per 20-ms batch.
        ev.add_temperature(stamps[-1:], [25.0 + 1e-3 * i])
        g, a = cal.apply(gyro, accel)
        g -= ev.drift_at(stamps)
    return 100 * (time.process_time() - t_start) / (n_batches * 0.02)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seconds', type=float, default=10.0, help='measurement window (s)')
    parser.add_argument('--warmup', type=float, default=5.0, help='wait after start (s)')
    parser.add_argument('--drain-period-s', type=float, default=0.0,
                        help="the compensator's drain_period_s (s; 0: as messages arrive)")
    parser.add_argument('--only', choices=('pass-through', 'calibration', 'thermal'),
                        help='measure one configuration only')
    args = parser.parse_args(argv)
    from gyro_noise_ros.rosgraph import lease_domain

    lease = lease_domain()  # a private graph, held until this process exits
    lease.export()
    listener = Listener()
    rows = []
    try:
        for kind in [args.only] if args.only else ('pass-through', 'calibration', 'thermal'):
            rows.append((kind, measure(kind, args, listener)))
    finally:
        listener.close()
    pure = pure_cost()
    print(f'command: {shlex.join([sys.executable] + sys.argv)}')
    print(f'emulator: real time, {ODR:g} Hz, TCP loopback; window {args.seconds:g} s after '
          f'{args.warmup:g} s; compensator drain_period_s {args.drain_period_s:g}; '
          f'{os.cpu_count()} cores, shared with other work (expect noise)')
    print(f'{"compensator configuration":28s} {"node CPU %":>10s} {"driver CPU %":>12s} '
          f'{"node / driver":>13s} {"compensated msg/s":>18s}')
    for kind, r in rows:
        print(f'{kind:28s} {r["node"]:10.1f} {r["driver"]:12.1f} {r["node"] / r["driver"]:13.2f} '
              f'{r["rate"]:18.0f}')
    print(f'pure calibration + thermal arithmetic at {ODR:g} Hz (20-ms batches, this process): '
          f'{pure:.2f} % of one core')
    worst = max(r['node'] for _, r in rows)
    print(f'compensator CPU share at {ODR:g} Hz: {worst:.1f} % of one core (budget <= 20 %)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
