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
CPU share of one core used by ``lsm6dso32_driver`` at the real link rate (6667 Hz, target <= 20 %).

Three runs against ``portenta_emulator`` streaming in real time on TCP loopback, each measured from
``/proc/<pid>/stat`` (utime + stime) over the same window after a warm-up:

1. baseline: a decode-only reader (pyserial + ``link.protocol.Decoder``, reading as the driver
   does, each frame as it arrives: ``link.reader.read_available``; no ROS): the cost of the link
   itself in Python;
2. the driver with no subscriber;
3. the driver with one subscriber (this process, draining a raw subscription every 5 ms).

Printed side by side with the emulator's own CPU in each run, the messages/s the subscriber
received, and the command line that produced the numbers. Run: ``.venv/bin/python
bench/bench_driver.py``.
"""

import argparse
import os
import shlex
import signal
import socket
import subprocess
import sys
import time

TICK = os.sysconf('SC_CLK_TCK')
ODR = 6667.0

_READER = r"""
import sys, time, serial
from gyro_noise_ros.link.protocol import Decoder
from gyro_noise_ros.link.reader import read_available
ser = serial.serial_for_url(sys.argv[1], timeout=0)
fd = ser.fileno()
dec = Decoder()
n = 0
try:
    while True:
        data = read_available(ser, fd, 0.01)
        if data:
            n += len(dec.feed(data).samples)
except KeyboardInterrupt:
    pass
"""


def cpu_seconds(pid):
    """Return utime + stime of a process, in seconds (fields 14 and 15 of /proc/<pid>/stat)."""
    with open(f'/proc/{pid}/stat') as fh:
        fields = fh.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def start_emulator(port):
    proc = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.cli.emulator', '--tcp',
                             f'127.0.0.1:{port}', '--seed', '1', '--accel-fs-g', '32'],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    proc.stdout.readline()  # the URL: listening from now on
    return proc


def stop(proc):
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


class Subscriber:
    """Raw subscription drained with take_message: the cheapest Python consumer (ROS_ON_PIP.md)."""

    def __init__(self):
        import rclpy
        from sensor_msgs.msg import Imu

        from gyro_noise_ros.nodes._ros_common import sensor_data_qos
        self.rclpy, self.imu_type = rclpy, Imu
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('bench_listener', context=self.context)
        self.sub = self.node.create_subscription(Imu, 'imu/data_raw', lambda m: None,
                                                 sensor_data_qos(20000), raw=True)
        self.count = 0
        self.dds_missing = 0  # gaps in the DDS publication sequence numbers: lost by the transport
        self._last_dds = None

    def drain(self):
        with self.sub.handle:
            while True:
                item = self.sub.handle.take_message(self.imu_type, True)
                if item is None:
                    break
                self.count += 1
                dds = item[1].get('publication_sequence_number') or 0
                if self._last_dds is not None and dds > self._last_dds + 1:
                    self.dds_missing += dds - self._last_dds - 1
                self._last_dds = dds

    def close(self):
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def measure(kind, args, subscriber=None):
    """Start emulator + consumer, warm up, measure CPU over the window; return a result row."""
    port = free_port()
    url = f'socket://127.0.0.1:{port}'
    emu = start_emulator(port)
    if kind == 'reader':
        consumer = subprocess.Popen([sys.executable, '-c', _READER, url])
    else:
        consumer = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.nodes.driver',
                                     '--ros-args', '-p', f'port:={url}', '-p',
                                     'reconnect_period_s:=0.2'], stderr=subprocess.DEVNULL,
                                    env=dict(os.environ))
    try:
        def wait(seconds):
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                if subscriber is not None:
                    subscriber.drain()
                time.sleep(0.005)

        wait(args.warmup)
        c0, e0, t0 = cpu_seconds(consumer.pid), cpu_seconds(emu.pid), time.monotonic()
        n0 = subscriber.count + subscriber.dds_missing if subscriber else 0
        wait(args.seconds)
        c1, e1, t1 = cpu_seconds(consumer.pid), cpu_seconds(emu.pid), time.monotonic()
        n1 = subscriber.count + subscriber.dds_missing if subscriber else 0
        assert consumer.poll() is None, f'{kind} exited early'
    finally:
        stop(consumer)
        stop(emu)
    wall = t1 - t0
    return {'consumer': 100 * (c1 - c0) / wall, 'emulator': 100 * (e1 - e0) / wall,
            'rate': (n1 - n0) / wall if subscriber else None}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seconds', type=float, default=10.0, help='measurement window (s)')
    parser.add_argument('--warmup', type=float, default=4.0,
                        help='wait after start before measuring (s)')
    args = parser.parse_args(argv)
    from gyro_noise_ros.rosgraph import lease_domain

    lease = lease_domain()  # a private graph, held until this process exits
    lease.export()

    rows = [('decode-only reader (baseline, no ROS)', measure('reader', args)),
            ('lsm6dso32_driver, no subscriber', measure('driver', args))]
    sub = Subscriber()
    try:
        rows.append(('lsm6dso32_driver, 1 raw subscriber', measure('driver', args, sub)))
    finally:
        sub.close()

    base = rows[0][1]['consumer']
    print(f'command: {shlex.join([sys.executable] + sys.argv)}')
    print(f'emulator: real time, {ODR:g} Hz, TCP loopback; window {args.seconds:g} s after '
          f'{args.warmup:g} s; ' f'{os.cpu_count()} cores (shared machine: expect noise)')
    print(f'{"consumer":40s} {"CPU % of a core":>16s} {"x baseline":>11s} {"emulator CPU %":>15s} '
          f'{"published msg/s":>16s}')
    for name, r in rows:
        rate = '-' if r['rate'] is None else f'{r["rate"]:.0f}'
        print(f'{name:40s} {r["consumer"]:16.1f} {r["consumer"] / base:11.2f} '
              f'{r["emulator"]:15.1f} {rate:>16s}')
    print(f'published msg/s: counted by the subscriber from DDS publication numbers (received '
          f'{sub.count}, lost by the best-effort transport {sub.dds_missing}, over warm-up and '
          'window)')
    worst = max(r['consumer'] for name, r in rows[1:])
    print(f'driver CPU share at {ODR:g} Hz: {worst:.1f} % of one core (target <= 20 %)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
