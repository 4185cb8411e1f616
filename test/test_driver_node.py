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
In-process tests of ``lsm6dso32_driver``: parameters, messages, publish-once, link lifecycle.

The node runs for real (rclpy, Fast DDS) in its own rclpy context. Known samples reach it either
through ``publish_samples`` (what the reader thread calls for each decoded batch) or from a fake
board: a TCP server thread in this process speaking the link protocol through ``socket://`` URLs.
Expected SI values are computed here from the datasheet sensitivities, not with ``link.lsm6dso32``.
"""

import math
import os
import socket
import subprocess
import sys
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from gyro_noise_ros.bag import decode_imu, decode_temperature
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.link import clock as clock_module, protocol as P
from gyro_noise_ros.msgs import imu_rows
from gyro_noise_ros.nodes._ros_common import sensor_data_qos
from gyro_noise_ros.nodes.driver import LinkConfig, Lsm6dso32Driver
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from sensor_msgs.msg import Imu, Temperature

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

# Datasheet sensitivities (LSM6DSO32 DS13146, table 3): mdps/LSB and mg/LSB.
GYRO_MDPS = {125: 4.375, 250: 8.75, 500: 17.5, 1000: 35.0, 2000: 70.0}
ACCEL_MG = {4: 0.122, 8: 0.244, 16: 0.488, 32: 0.976}
G0 = 9.80665


def gyro_lsb(fs_dps):
    return GYRO_MDPS[fs_dps] * 1e-3 * math.pi / 180.0


def accel_lsb(fs_g):
    return ACCEL_MG[fs_g] * 1e-3 * G0


def closed_port_url():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        port = s.getsockname()[1]
    return f'socket://127.0.0.1:{port}'


class Harness:
    """A driver and a subscriber node on one context, spun by one executor in this thread."""

    def __init__(self, context, listen=True, listeners=(), **overrides):
        overrides.setdefault('port', closed_port_url())
        overrides.setdefault('reconnect_period_s', 60.0)
        # Published at once: the tests feed a few frames; the settling has its own test.
        overrides.setdefault('clock_settle_s', 0.0)
        self.driver = Lsm6dso32Driver(context=context, listeners=listeners, parameter_overrides=[
            Parameter(name, value=value) for name, value in overrides.items()])
        self.sub_node = rclpy.create_node('test_listener', context=context)
        self.imu, self.temps, self.diags = [], [], []
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.driver)
        self.executor.add_node(self.sub_node)
        if listen:
            qos = sensor_data_qos(10000)
            self.sub_node.create_subscription(Imu, 'imu/data_raw', self.imu.append, qos)
            self.sub_node.create_subscription(
                Temperature, 'imu/temperature', self.temps.append, qos)
            self.sub_node.create_subscription(
                DiagnosticArray, '/diagnostics', self.diags.append, 10)
            self.spin_until(lambda: self.driver._imu_pub.get_subscription_count() >= 1
                            and self.driver._temp_pub.get_subscription_count() >= 1, 10.0)

    def spin_until(self, condition, timeout_s):
        deadline = time.monotonic() + timeout_s
        while not condition():
            assert time.monotonic() < deadline, 'timed out'
            self.executor.spin_once(timeout_sec=0.02)

    def close(self):
        self.executor.shutdown()
        self.driver.destroy_node()
        self.sub_node.destroy_node()


@pytest.fixture
def harness(context):
    made = []

    def make(**overrides):
        made.append(Harness(context, **overrides))
        return made[-1]

    try:
        yield make
    finally:
        for h in made:
            h.close()


def make_samples(seq, *, gyro=None, accel=None, temp=None, period_us=150):
    seq = np.asarray(seq, np.int64)
    s = np.zeros(seq.size, P.SAMPLE_DTYPE)
    s['seq'] = (seq % 2**32).astype(np.uint32)
    s['t_us'] = ((seq * period_us) % 2**32).astype(np.uint32)
    # Default payload: gyro x carries the sequence number so a subscriber can tell which sample it
    # got.
    s['gyro'] = np.stack([seq % 30000, -(seq % 1000), np.full(seq.size, 7)],
                         axis=1) if gyro is None else gyro
    s['accel'] = np.array([0, 0, 1024]) if accel is None else accel
    s['temp'] = 512 if temp is None else temp
    return s


def stamp_ns(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


# --------------------------------------------------------------------------- parameters


@pytest.mark.parametrize('name, value, fragment', [
    ('odr_hz', 1000.0, "'odr_hz'"),                     # not a datasheet rate
    ('gyro_full_scale_dps', 300, "'gyro_full_scale_dps'"),
    ('accel_full_scale_g', 2, "'accel_full_scale_g'"),
    ('reconnect_period_s', -1.0, "'reconnect_period_s'"),  # below the range
    ('reconnect_period_s', 1, 'floating-point'),          # integer given for a double
    ('temperature_decimation', 0, "'temperature_decimation'"),
    ('frame_id', 'imu link', "'frame_id'"),           # no spaces in a TF frame id
    ('port', '', "'port'"),
    ('port', 'nosuchscheme://x', "'port'"),
    ('loss_warn_ratio', 0.5, "'loss_warn_ratio'"),      # above loss_error_ratio (0.01)
])
def test_bad_parameters_are_refused(context, name, value, fragment):
    with pytest.raises(ParameterError) as info:
        Lsm6dso32Driver(context=context, parameter_overrides=[Parameter(name, value=value)])
    assert fragment in str(info.value)
    assert '\n' not in str(info.value)


def test_main_with_bad_parameter_prints_one_line_and_exits_2():
    proc = subprocess.run(
        [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args', '-p',
         'odr_hz:=1000.0'],
        capture_output=True, text=True, timeout=60, env=dict(os.environ))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('lsm6dso32_driver: error:'), proc.stderr
    assert 'odr_hz' in lines[0] and 'Traceback' not in proc.stderr


def test_runtime_parameter_changes(harness):
    h = harness()
    node = h.driver
    ok = node.set_parameters([Parameter('frame_id', value='gyro_frame')])[0]
    assert ok.successful
    assert node._message_fields['frame_id'] == 'gyro_frame'
    assert not node.set_parameters([Parameter('odr_hz', value=833.0)])[0].successful  # read_only
    assert not node.set_parameters([Parameter('temperature_decimation', value=0)])[0].successful
    assert not node.set_parameters([Parameter('frame_id', value='')])[0].successful
    assert node.get_parameter('temperature_decimation').value == 128


# --------------------------------------------------------------------------- sequence tracker


@pytest.mark.parametrize('gyro_fs, accel_fs', [(2000, 32), (125, 4)])
def test_messages_for_known_samples(harness, gyro_fs, accel_fs):
    h = harness(temperature_decimation=4, frame_id='my_imu',
                angular_velocity_variance_rad2_s2=2.5e-6, linear_acceleration_variance_m2_s4=4e-4,
                temperature_variance_c2=0.01)
    n = 40
    seq = np.arange(1000, 1000 + n)
    rng = np.random.default_rng(3)
    gyro = rng.integers(-32768, 32768, (n, 3)).astype(np.int16)
    gyro[0] = (-32768, 32767, 0)  # the extremes
    accel = rng.integers(-32768, 32768, (n, 3)).astype(np.int16)
    temp = rng.integers(-32768, 32768, n).astype(np.int16)
    samples = make_samples(seq, gyro=gyro, accel=accel, temp=temp)
    host_ns = h.driver.get_clock().now().nanoseconds
    # The scaling comes from the acknowledged configuration, not from the parameters.
    count = h.driver.publish_samples(samples, host_ns, LinkConfig(6667.0, gyro_fs, accel_fs))
    assert count == n
    h.spin_until(lambda: len(h.imu) == n and len(h.temps) == n // 4, 10.0)

    stamps = np.array([stamp_ns(m) for m in h.imu])
    assert np.all(np.diff(stamps) > 0)
    # Stamps are device time mapped onto the node clock; they never lie after the receive time.
    assert stamps[-1] <= host_ns
    # 150 us device spacing is kept (slope 1 until the estimator has fitted a drift).
    np.testing.assert_array_equal(np.diff(stamps), 150_000)
    cov_g = [2.5e-6, 0, 0, 0, 2.5e-6, 0, 0, 0, 2.5e-6]
    cov_a = [4e-4, 0, 0, 0, 4e-4, 0, 0, 0, 4e-4]
    for i, m in enumerate(h.imu):
        assert m.header.frame_id == 'my_imu'
        av = [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
        la = [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
        # One float64 multiplication each side: equal to the last bit or so.
        np.testing.assert_allclose(av, gyro[i] * gyro_lsb(gyro_fs), rtol=1e-15, atol=0)
        np.testing.assert_allclose(la, accel[i] * accel_lsb(accel_fs), rtol=1e-15, atol=0)
        assert m.orientation_covariance[0] == -1.0
        assert list(m.angular_velocity_covariance) == cov_g
        assert list(m.linear_acceleration_covariance) == cov_a
        assert (m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w) == (0, 0, 0, 1)
    # Temperature for seq % 4 == 0 only, with the same stamp as the sample's Imu message.
    picked = np.flatnonzero(seq % 4 == 0)
    assert [stamp_ns(t) for t in h.temps] == stamps[picked].tolist()
    np.testing.assert_allclose([t.temperature for t in h.temps],
                               25.0 + temp[picked] / 256.0, rtol=1e-15)
    assert all(t.variance == 0.01 and t.header.frame_id == 'my_imu' for t in h.temps)


def test_publish_once_and_loss_count(harness):
    h = harness()
    cfg = LinkConfig(6667.0, 2000, 32)
    now = h.driver.get_clock().now().nanoseconds
    assert h.driver.publish_samples(make_samples(np.arange(0, 10)), now, cfg) == 10
    assert h.driver.publish_samples(make_samples(np.arange(5, 15)),
                                    now + 10**6, cfg) == 5  # 5..9 again
    assert h.driver.publish_samples(make_samples(np.arange(20, 25)),
                                    now + 2 * 10**6, cfg) == 5  # 15..19 lost
    h.spin_until(lambda: len(h.imu) == 20, 10.0)
    got = [round(m.angular_velocity.x / gyro_lsb(2000)) for m in h.imu]
    assert got == list(range(15)) + list(range(20, 25))
    snap = h.driver.link_snapshot()
    assert (snap['published'], snap['duplicates'], snap['lost']) == (20, 5, 5)


def test_the_per_frame_kernels_are_ready_before_the_first_frame(harness):
    """The driver compiles (or loads) them when it starts: frames then compile nothing."""
    h = harness()
    kernels = (clock_module._steady_stamps, imu_rows._fill_scaled)
    before = [list(k.signatures) for k in kernels]
    assert all(before)
    cfg = LinkConfig(6667.0, 2000, 32)
    now = h.driver.get_clock().now().nanoseconds
    for b in range(6):  # 16-sample frames 2.4 ms apart: after the first, the clock's steady path
        assert h.driver.publish_samples(make_samples(np.arange(16 * b, 16 * b + 16)),
                                        now + b * 2_400_000 + 10**6, cfg) == 16
    assert [list(k.signatures) for k in kernels] == before


def test_listeners_get_the_bytes_published_while_active_and_a_failing_one_is_counted(harness):
    """In-process listeners (imu_chain): each read's serialised messages, temperatures first."""
    got = []

    def failing(temperatures, imu):
        raise ValueError('a broken listener')

    h = harness(listeners=[lambda t, i: got.append((list(t), list(i))), failing],
                temperature_decimation=4)
    cfg = LinkConfig(6667.0, 2000, 32)
    now = h.driver.get_clock().now().nanoseconds
    for b in range(3):
        assert h.driver.publish_samples(make_samples(np.arange(16 * b, 16 * b + 16)),
                                        now + b * 2_400_000, cfg) == 16
    h.spin_until(lambda: len(h.imu) == 48 and len(h.temps) == 12, 10.0)
    assert [len(i) for _, i in got] == [16, 16, 16] and [len(t) for t, _ in got] == [4, 4, 4]
    listened = [decode for _, imu in got for decode in decode_imu(imu).stamp_ns]
    assert listened == [stamp_ns(m) for m in h.imu]  # what the subscribers received, in order
    temps = decode_temperature([raw for t, _ in got for raw in t])
    assert temps[0].tolist() == [stamp_ns(m) for m in h.temps]
    # the broken listener neither stopped the driver nor the other listener: counted, logged
    assert h.driver.link_snapshot()['listener_errors'] == 3
    h.driver.trigger_deactivate()
    h.driver._handle(make_samples(np.arange(48, 64)), now + 10**8, cfg)  # the reader's call
    assert len(got) == 3  # inactive: nothing published, nothing handed over
    assert h.driver.link_snapshot()['discarded'] == 16


def test_the_first_samples_wait_for_the_clock_to_settle_then_all_go_in_order(harness):
    # clock_settle_s: the start of a board epoch is held while the clock mapping converges, then
    # published in order with stamps that never step; a restarted board settles again.
    h = harness(clock_settle_s=0.05)
    cfg = LinkConfig(6667.0, 2000, 32)
    now = h.driver.get_clock().now().nanoseconds
    counts = []
    for b in range(40):  # 16-sample frames, 2.4 ms of device time each
        seq = 10_000 + np.arange(16 * b, 16 * (b + 1))
        counts.append(h.driver.publish_samples(make_samples(seq), now + b * 2_400_000, cfg))
    first = next(i for i, c in enumerate(counts) if c)
    assert 0 < first < 39 and counts[first] == 16 * (first + 1)  # 0.05 s = 20.8 frames
    assert sum(counts) == 640
    h.spin_until(lambda: len(h.imu) == 640, 10.0)
    got = [round(m.angular_velocity.x / gyro_lsb(2000)) for m in h.imu]
    assert got == list(range(10_000, 10_640))
    stamps = np.array([stamp_ns(m) for m in h.imu])
    assert np.all(np.abs(np.diff(stamps) - 150_000) < 1500)  # within 1 % of a period
    # The board restarts (its counter falls back): the new epoch is held while it settles.
    assert h.driver.publish_samples(make_samples(np.arange(16)), now + 10**9, cfg) == 0
    assert h.driver.link_snapshot()['restarts'] == 1


# --------------------------------------------------------------------------- link lifecycle


class FakeBoard:
    """TCP server thread; ``script(conn, decoder)`` runs once per accepted connection."""

    def __init__(self, scripts):
        self.server = socket.socket()
        self.server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.server.bind(('127.0.0.1', 0))
        self.server.listen(4)
        self.server.settimeout(30.0)
        self.url = f'socket://127.0.0.1:{self.server.getsockname()[1]}'
        self.scripts = list(scripts)
        self.commands = []
        self.errors = []
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        try:
            for script in self.scripts:
                conn, _ = self.server.accept()
                with conn:
                    conn.settimeout(10.0)
                    script(self, conn)
        except Exception as err:  # noqa: BLE001 - reported by the test through self.errors
            self.errors.append(repr(err))
        finally:
            self.done.set()

    def read_command(self, conn):
        decoder = P.Decoder()
        while True:
            data = conn.recv(4096)
            assert data, 'driver closed the connection before configuring'
            result = decoder.feed(data)
            if result.commands:
                self.commands.append(result.commands[0])
                return result.commands[0]

    @staticmethod
    def ack(cmd, ok=True, message=''):
        return P.encode_ack(P.Ack(cmd.command_id, ok, cmd.odr_hz, cmd.gyro_fs_dps, cmd.accel_fs_g,
                                  message, 0 if ok else P.NAK_BAD_ODR))

    def close(self):
        self.server.close()


def _corrupt(frame):
    bad = bytearray(frame)
    bad[P.HEADER_SIZE + 3] ^= 0x10  # a payload byte: the CRC no longer matches
    return bytes(bad)


def test_session_with_faults_and_reconnection(harness):
    def first(board, conn):
        cmd = board.read_command(conn)
        # Samples sent before the acknowledgement may have the old scaling: never published.
        early = make_samples(np.arange(5, 105))
        early['flags'][45] = P.FLAG_FIFO_OVERRUN  # the sensor lost samples the board never saw
        conn.sendall(P.encode_samples(make_samples(np.arange(0, 5))) + board.ack(cmd)
                     + P.encode_samples(early))
        conn.sendall(_corrupt(P.encode_samples(make_samples(np.arange(105, 115)))))
        conn.sendall(P.encode_samples(make_samples(np.arange(115, 205))))
        time.sleep(0.3)  # then the cable is pulled

    def second(board, conn):
        cmd = board.read_command(conn)
        # After the replug the board re-sends its last 10 samples, then continues after a gap.
        conn.sendall(board.ack(cmd) + P.encode_samples(make_samples(np.arange(195, 205)))
                     + P.encode_samples(make_samples(np.arange(210, 300))))
        time.sleep(3.0)

    board = FakeBoard([first, second])
    try:
        # No diagnostics timer during the test: link_status() below must see the whole session.
        h = harness(port=board.url, reconnect_period_s=0.1, diagnostics_period_s=3600.0)
        h.spin_until(lambda: len(h.imu) >= 280, 20.0)
        h.spin_until(lambda: h.driver.link_snapshot()['connections'] == 2, 5.0)
        got = [round(m.angular_velocity.x / gyro_lsb(2000)) for m in h.imu]
        assert got == list(range(5, 105)) + list(range(115, 205)) + list(range(210, 300))
        assert np.all(np.diff([stamp_ns(m) for m in h.imu]) > 0)
        snap = h.driver.link_snapshot()
        assert snap['published'] == 280
        assert snap['lost'] == 10 + 5  # the corrupt frame's samples and the gap after the replug
        assert snap['duplicates'] == 10
        assert snap['link']['crc_errors'] >= 1
        assert 'disconnected' in snap['last_error']
        assert [c.command_id for c in board.commands] == [1, 2]
        assert board.commands[0].odr_hz == 6667.0 and board.commands[0].gyro_fs_dps == 2000
        assert board.commands[0].accel_fs_g == 32

        status = h.driver.link_status()
        values = {kv.key: kv.value for kv in status.values}
        assert status.name == 'lsm6dso32_driver: link'
        # Sensor and board identity, never the port path (a socket URL has no USB serial number).
        assert status.hardware_id == 'lsm6dso32/portenta_h7/imu_link'
        assert values['Connection'] == 'streaming'
        assert values['Samples lost'] == '15' and values['Samples published'] == '280'
        assert values['Duplicates dropped'] == '10' and int(values['CRC errors']) >= 1
        assert values['Connections'] == '2'
        assert values['Sensor FIFO overruns'] == '1'
        assert status.level in (DiagnosticStatus.WARN, DiagnosticStatus.ERROR)
        assert board.errors == []
    finally:
        board.close()


def test_no_ack_then_nak_are_reported(harness):
    def silent(board, conn):
        board.read_command(conn)
        time.sleep(1.0)

    def refuse(board, conn):
        cmd = board.read_command(conn)
        conn.sendall(board.ack(cmd, ok=False, message='odr not supported'))
        time.sleep(1.0)

    board = FakeBoard([silent, refuse])
    try:
        # 1 s between attempts keeps each error visible long enough to be seen.
        h = harness(port=board.url, ack_timeout_s=0.3, reconnect_period_s=1.0)
        h.spin_until(lambda: 'no acknowledgement' in h.driver.link_snapshot()['last_error'], 10.0)
        h.spin_until(lambda: 'odr not supported' in h.driver.link_snapshot()['last_error'], 10.0)
        assert 'refused' in h.driver.link_snapshot()['last_error']
        status = h.driver.link_status()
        assert status.level == DiagnosticStatus.ERROR
        assert h.driver.link_snapshot()['published'] == 0
    finally:
        board.close()


def test_diagnostics_topic_when_port_absent(harness):
    h = harness(diagnostics_period_s=0.2, reconnect_period_s=0.2)
    h.spin_until(lambda: any(
        a.status and 'cannot open' in a.status[0].message for a in h.diags), 10.0)
    status = [a for a in h.diags if 'cannot open' in a.status[0].message][-1].status[0]
    assert status.name == 'lsm6dso32_driver: link'
    assert status.level == DiagnosticStatus.ERROR
    assert status.message.startswith('Link down: cannot open socket://127.0.0.1:')
    values = {kv.key: kv.value for kv in status.values}
    for key in ('Sample rate (Hz)', 'Samples lost', 'CRC errors', 'Resyncs', 'Bytes discarded',
                'Connection', 'Last error'):
        assert isinstance(values[key], str) and values[key], key
    assert values['Connection'] == 'disconnected'


@pytest.mark.parametrize('speed, level',
                         [(1.0, DiagnosticStatus.OK), (0.5, DiagnosticStatus.WARN)],
                         ids=['on_rate', 'half_rate'])
def test_rate_check_against_the_acknowledged_odr(harness, speed, level):
    # The board acknowledges 6667 Hz and streams at speed x 6667 Hz (paced on absolute time, so
    # the count in a window is exact to a frame): on rate -> OK, half rate -> WARN naming the rate.
    def stream(board, conn):
        cmd = board.read_command(conn)
        conn.sendall(board.ack(cmd))
        t0, sent = time.monotonic(), 0
        while time.monotonic() - t0 < 4.0:
            due = int((time.monotonic() - t0) * 6667.0 * speed) // 16 * 16
            if due > sent:
                conn.sendall(P.encode_samples(make_samples(np.arange(sent, due))))
                sent = due
            time.sleep(0.002)

    board = FakeBoard([stream])
    try:
        # No subscriber: this process also runs the board, and deserialising 6667 messages/s in
        # Python would starve the driver's thread of the GIL.
        h = harness(port=board.url, diagnostics_period_s=3600.0, listen=False)
        h.spin_until(lambda: h.driver.link_snapshot()['published'] > 1000, 10.0)
        h.driver.link_status()  # starts a full window
        t = time.monotonic()
        h.spin_until(lambda: time.monotonic() - t > 1.5, 5.0)
        status = h.driver.link_status()
        assert status.level == level, status.message
        rate = float({kv.key: kv.value for kv in status.values}['Sample rate (Hz)'])
        # Window edges cut frames of 16 samples: 2 frames in 1.5 s is 21 Hz.
        assert abs(rate - 6667.0 * speed) < 0.02 * 6667.0 * speed + 25.0
        if level == DiagnosticStatus.WARN:
            assert status.message.startswith('Sample rate')
    finally:
        board.close()
