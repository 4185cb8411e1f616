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

"""Helpers the end-to-end tests share: a free port, the emulator's port line, /diagnostics."""

import select
import socket
import time


def free_port():
    """Return a loopback TCP port that was free a moment ago."""
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def readline(proc, timeout_s):
    """Return the first line proc prints on stdout (the emulator's port); fail on silence."""
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


def collect_diagnostics(names, until, timeout_s):
    """Spin a subscriber on /diagnostics; return {status name: [DiagnosticStatus, ...]}."""
    from diagnostic_msgs.msg import DiagnosticArray
    import rclpy

    context = rclpy.Context()
    rclpy.init(context=context)
    seen = {n: [] for n in names}
    try:
        node = rclpy.create_node('test_diagnostics_listener', context=context)
        node.create_subscription(DiagnosticArray, '/diagnostics',
                                 lambda m: [seen[s.name].append(s) for s in m.status
                                            if s.name in seen], 100)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not until(seen):
            executor.spin_once(timeout_sec=0.1)
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return seen


def values(status):
    """Return the key/value pairs of a DiagnosticStatus as a dict."""
    return {kv.key: kv.value for kv in status.values}


def chunks(status):
    """Return the analyzer's 'Chunks analysed' count of a status (0 when absent)."""
    return int(values(status).get('Chunks analysed', '0'))
