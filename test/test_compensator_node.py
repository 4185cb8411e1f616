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
``imu_compensator`` in-process: published messages equal the pure computation; refusals.

The node runs in this process with ``parameter_overrides`` (or an injected causal model) in the
test's private graph (``ros_graph`` in ``conftest.py``) and its own rclpy context; a player node
publishes serialised Imu and Temperature messages, a listener takes ``imu/data_compensated`` raw
and decodes it.
"""

import importlib
import subprocess
import sys
import time

from _thermal_linear import LinearThermal
from gyro_noise_ros.bag import decode_imu, decode_temperature
from gyro_noise_ros.calibration.apply import calibration_from_parameters
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.msgs import encode_imu_cdr, encode_temperature_cdr
from gyro_noise_ros.msgs import typestore
from gyro_noise_ros.nodes import compensator
from gyro_noise_ros.nodes._ros_common import ERROR, OK, PolledGroup
from gyro_noise_ros.nodes._ros_common import sensor_data_qos, take_all
from gyro_noise_ros.nodes._ros_common import unused_callback, WARN
from gyro_noise_ros.thermal.live import LiveDriftEvaluator
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu, Temperature

pytestmark = pytest.mark.ros

RATE_HZ = 6660.0
NS = 1_000_000_000
T0_NS = 1_700_000_000 * NS


def _calibration_params(seed):
    rng = np.random.default_rng(seed)
    mis = [rng.normal(0, 2e-3, (3, 3)) for _ in range(2)]
    for m in mis:
        np.fill_diagonal(m, 0.0)
    return {'accel_bias_m_s2': rng.normal(0, 0.05, 3).tolist(),
            'accel_scale_factor': rng.normal(0, 1e-3, 3).tolist(),
            'accel_misalignment': mis[0].reshape(-1).tolist(),
            'gyro_bias_rad_s': rng.normal(0, 0.01, 3).tolist(),
            'gyro_scale_factor': rng.normal(0, 1e-3, 3).tolist(),
            'gyro_misalignment': mis[1].reshape(-1).tolist()}


def _imu_stream(n, seed):
    rng = np.random.default_rng(seed)
    stamps = T0_NS + np.rint(np.arange(n) * NS / RATE_HZ).astype(np.int64)
    gyro = rng.normal(0, 0.5, (n, 3))
    accel = rng.normal(0, 1.0, (n, 3)) + [0.0, 0.0, 9.81]
    raws = encode_imu_cdr(stamps, gyro, accel, frame_id='imu_test',
                          angular_velocity_covariance=np.diag([1e-6, 2e-6, 3e-6]),
                          linear_acceleration_covariance=np.diag([4e-4, 5e-4, 6e-4]))
    return stamps, gyro, accel, raws


def _spin_until(executor, predicate, timeout_s):
    deadline = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    return predicate()


class _Harness:
    """Player of raw messages and listener of imu/data_compensated around one node."""

    def __init__(self, context, node):
        self.node = node
        self.other = rclpy.create_node('test_compensator_io', context=context)
        self.imu_pub = self.other.create_publisher(Imu, 'imu/data_raw', sensor_data_qos(5000))
        self.temp_pub = self.other.create_publisher(Temperature, 'imu/temperature',
                                                    sensor_data_qos(5000))
        self._out = []
        qos = QoSProfile(depth=50000, reliability=ReliabilityPolicy.RELIABLE)
        # Taken in bulk like the node does (one spin per message would be far too slow).
        self.sub = self.other.create_subscription(Imu, 'imu/data_compensated', unused_callback,
                                                  qos, raw=True, callback_group=PolledGroup())
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(node)
        self.executor.add_node(self.other)
        assert _spin_until(self.executor, lambda: self.imu_pub.get_subscription_count() > 0
                           and self.temp_pub.get_subscription_count() > 0, 20)
        assert _spin_until(self.executor,
                           lambda: node._pub.get_subscription_count() > 0, 20)
        _spin_until(self.executor, lambda: False, 0.3)  # let the readers finish matching

    def play(self, raws, *, temperatures=(), block=400):
        """Publish temperatures then Imu blocks, each after the node took the previous one."""
        for raw in temperatures:
            self.temp_pub.publish(raw)
        sent = self.node.counts['received']
        for start in range(0, len(raws), block):
            for raw in raws[start:start + block]:
                self.imu_pub.publish(raw)
            sent += len(raws[start:start + block])
            got = _spin_until(self.executor, lambda: len(self.out) >= sent, 20)
            assert got, (len(self.out), sent)

    @property
    def out(self):
        """Every imu/data_compensated message received so far (serialised)."""
        if self.executor is not None:
            self._out += take_all(self.sub, Imu)[0]
        return self._out

    def close(self):
        self.out
        self.executor.shutdown()
        self.executor = None
        self.other.destroy_node()
        self.node.destroy_node()


def _overrides(**values):
    return [Parameter(k, value=v) for k, v in values.items()]


@pytest.mark.timeout(120)
def test_published_messages_equal_the_pure_calibration(context):
    params = _calibration_params(3)
    node = compensator.ImuCompensatorNode(context=context,
                                          parameter_overrides=_overrides(**params))
    stamps, gyro, accel, raws = _imu_stream(3000, seed=4)
    io = _Harness(context, node)
    try:
        io.play(raws)
    finally:
        io.close()
    out = decode_imu(io.out)
    assert out.frame_id == 'imu_test'
    np.testing.assert_array_equal(out.stamp_ns, stamps)
    exp_gyro, exp_accel = calibration_from_parameters(params).apply(gyro, accel)
    # Same arithmetic on the same float64 values: bit-identical.
    np.testing.assert_array_equal(out.gyro, exp_gyro)
    np.testing.assert_array_equal(out.accel, exp_accel)
    assert np.abs(out.gyro - gyro).max() > 1e-3  # the calibration did change the values
    # Everything but the two vectors is copied: orientation, covariances, header.
    msg = typestore().deserialize_cdr(io.out[17], 'sensor_msgs/msg/Imu')
    assert msg.orientation_covariance[0] == -1.0 and msg.orientation.w == 1.0
    np.testing.assert_array_equal(msg.angular_velocity_covariance,
                                  np.diag([1e-6, 2e-6, 3e-6]).ravel())
    np.testing.assert_array_equal(msg.linear_acceleration_covariance,
                                  np.diag([4e-4, 5e-4, 6e-4]).ravel())
    status = node.diagnostics().status[0]
    values = {kv.key: kv.value for kv in status.values}
    assert status.name == 'imu_compensator: compensation' and status.level == OK
    assert values['Messages published'] == '3000' and values['Calibration source'] == 'parameters'
    assert status.hardware_id == 'imu_test'


@pytest.mark.timeout(120)
def test_thermal_offset_is_subtracted_and_range_drives_the_level(context):
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), offset=(1e-3, 0.0, 0.0),
                          temperature_range_c=(20.0, 30.0), range_margin_c=2.0)
    node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                          parameter_overrides=_overrides(
                                              temperature_rate_window_s=1.0))
    stamps, gyro, accel, raws = _imu_stream(2 * int(RATE_HZ), seed=5)
    t_stamps = T0_NS + np.arange(0, 2 * NS + 1, NS // 50)  # 50 Hz over the whole stream
    temps = 25.0 + 2.0 * (t_stamps - T0_NS) / NS
    io = _Harness(context, node)
    try:
        status = node.diagnostics().status[0]
        assert status.level == ERROR  # no data yet
        io.play(raws, temperatures=encode_temperature_cdr(t_stamps, temps, frame_id='imu_test'))
        status = node.diagnostics().status[0]
        assert status.level == OK, status.message
        values = {kv.key: kv.value for kv in status.values}
        assert values['Temperature range status'] == 'inside'
        assert values['Thermal model'] == 'linear_test'
        # Within the margin (31 degC): WARN; beyond it (40 degC): ERROR, offset not extrapolated.
        # Three seconds apart: a die cannot move 9 degC in 20 ms (core.plausible rejects that).
        late = t_stamps[-1] + NS // 50
        for temp, level, range_name in ((31.0, WARN, 'within margin'), (40.0, ERROR, 'outside')):
            late += 3 * NS
            io.temp_pub.publish(encode_temperature_cdr([late], [temp], frame_id='imu_test')[0])
            assert _spin_until(io.executor, lambda: node.thermal.stamp_ns == late, 10)
            status = node.diagnostics().status[0]
            values = {kv.key: kv.value for kv in status.values}
            assert status.level == level and values['Temperature range status'] == range_name
        assert 'beyond the model range' in status.message
    finally:
        io.close()
    out = decode_imu(io.out[:len(raws)])
    ev = LiveDriftEvaluator(model, rate_window_s=1.0)
    ev.add_temperature(t_stamps, temps)
    expected = gyro - ev.drift_at(stamps)
    # The node evaluated the same knots from batches of messages: the trailing-window rate's
    # running sums start at another sample, so agreement is to rounding, not bit for bit.
    np.testing.assert_allclose(out.gyro, expected, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(out.accel, accel)  # identity calibration: untouched


@pytest.mark.timeout(120)
def test_by_default_samples_newer_than_the_latest_temperature_get_its_offset_at_once(context):
    # temperature_sync latest (the default, drained as messages arrive): nothing waits for a
    # newer temperature; a sample past the newest one gets its offset, held, and is not counted.
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), temperature_range_c=(20.0, 30.0))
    node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                          parameter_overrides=_overrides(
                                              temperature_rate_window_s=1.0))
    n = int(RATE_HZ)  # 1 s of samples, all after the two temperatures but the first
    stamps, gyro, _, raws = _imu_stream(n, seed=9)
    t_stamps = T0_NS + np.array([-NS // 2, 0])
    temps = np.array([25.0, 26.0])
    io = _Harness(context, node)
    try:
        io.play(raws, temperatures=encode_temperature_cdr(t_stamps, temps, frame_id='imu_test'))
        status = node.diagnostics().status[0]
        values = {kv.key: kv.value for kv in status.values}
    finally:
        io.close()
    assert values['Temperature sync'] == 'latest'
    assert values['Messages compensated with a held offset'] == '0'
    assert values['Messages waiting for a temperature'] == '0'
    assert status.level == OK, status.message
    # The last sample is (n - 1) periods past the newest temperature.
    assert float(values['Newest sample past its offset (ms)']) == pytest.approx(
        (stamps[-1] - t_stamps[-1]) / 1e6, abs=0.05)
    twin = LiveDriftEvaluator(model, rate_window_s=1.0)
    twin.add_temperature(t_stamps, temps)
    newest = twin.drift_at(t_stamps[-1:])[0]
    np.testing.assert_allclose(decode_imu(io.out).gyro, gyro - newest, rtol=0, atol=1e-13)


@pytest.mark.timeout(120)
def test_samples_newer_than_the_latest_temperature_wait_for_the_next_one(context):
    # temperature_sync interpolate: a reliable imu/temperature stalled behind a resent message;
    # the gyro samples after the newest temperature do not get its offset, held; they wait
    # (max_temperature_wait_s) and get the interpolated one when the next temperature comes, or,
    # past the bound, the newest one and a count. Drained on a timer, the other drain.
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), temperature_range_c=(20.0, 30.0))
    node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                          parameter_overrides=_overrides(
                                              temperature_rate_window_s=1.0,
                                              temperature_sync='interpolate',
                                              max_temperature_wait_s=0.5,
                                              drain_period_s=0.01))
    n = int(RATE_HZ)  # 1 s of samples
    stamps, gyro, accel, raws = _imu_stream(n + 400, seed=8)
    t_stamps = T0_NS + np.array([0, NS // 2, NS])
    temps = np.array([25.0, 26.0, 28.0])  # a ramp that speeds up: a held offset would show
    t_raws = encode_temperature_cdr(t_stamps, temps, frame_id='imu_test')
    io = _Harness(context, node)
    half = int(np.searchsorted(stamps, t_stamps[1], side='right'))
    try:
        for raw in t_raws[:2]:
            io.temp_pub.publish(raw)
        assert _spin_until(io.executor, lambda: node.thermal.stamp_ns == t_stamps[1], 10)
        for start in range(0, n, 400):  # in blocks, as play() does (best-effort player)
            for raw in raws[start:min(n, start + 400)]:
                io.imu_pub.publish(raw)
            assert _spin_until(io.executor, lambda: node.counts['received'] == min(
                n, start + 400), 20)
        # Up to the 0.5 s temperature: published; the rest waits.
        assert _spin_until(io.executor, lambda: len(io.out) == half, 5), (len(io.out), half)
        waiting = node._gate.waiting
        io.temp_pub.publish(t_raws[2])  # the stalled temperature arrives (0.5 s bound not hit)
        assert _spin_until(io.executor, lambda: len(io.out) == n, 10)
        # Beyond the last temperature, with no newer one: published after 0.5 s, counted.
        for raw in raws[n:]:
            io.imu_pub.publish(raw)
        assert _spin_until(io.executor, lambda: len(io.out) == n + 400, 10)
        status = node.diagnostics().status[0]
        values = {kv.key: kv.value for kv in status.values}
    finally:
        io.close()
    assert waiting == n - half
    # Sample n is stamped at the 1 s temperature exactly (covered); the 399 after it went late.
    assert values['Messages compensated with a held offset'] == '399'
    assert status.level == WARN and 'held offset' in status.message
    assert 0.0 < float(values['Longest wait for a temperature (s)']) < 0.5
    out = decode_imu(io.out)
    twin = LiveDriftEvaluator(model, rate_window_s=1.0)
    twin.add_temperature(t_stamps, temps)
    expected = gyro[:n] - twin.drift_at(stamps[:n])
    # Every sample of the first second interpolated between the knots around it, as if no
    # temperature had been late (to rounding: the rate's running sums start elsewhere).
    np.testing.assert_allclose(out.gyro[:n], expected, rtol=0, atol=1e-13)
    # The late ones: the newest offset (the 1 s knot's), held.
    np.testing.assert_allclose(out.gyro[n + 1:], gyro[n + 1:] - twin.drift_at(t_stamps[2:])[0],
                               rtol=0, atol=1e-13)


def test_non_causal_model_is_refused(context):
    with pytest.raises(ParameterError, match='VMD'):
        compensator.ImuCompensatorNode(context=context,
                                       thermal_model=LinearThermal(name='parallel'))


def test_reliable_applies_to_the_imu_stream_temperatures_stay_best_effort(context):
    # A reliable temperature stream delivered in order would hold every newer temperature back
    # behind a lost one until it is resent (Fast DDS: a heartbeat, 3 s): a 3-s-old offset in the
    # 6.66 kHz soak. Only the newest temperature matters, so it is always best effort.
    node = compensator.ImuCompensatorNode(context=context,
                                          parameter_overrides=_overrides(reliable=True))
    try:
        assert node._imu_sub.qos_profile.reliability == ReliabilityPolicy.RELIABLE
        assert node._temp_sub.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
    finally:
        node.destroy_node()


def test_file_and_parameters_are_not_both_accepted(context, tmp_path):
    path = tmp_path / 'calibration.yaml'
    path.write_text('/**:\n  ros__parameters:\n' + ''.join(
        f'    {k}: {v!r}\n' for k, v in _calibration_params(1).items()))
    node = compensator.ImuCompensatorNode(context=context, parameter_overrides=_overrides(
        calibration_file=str(path)))
    assert node._cal_source == f'file {path}'
    node.destroy_node()
    with pytest.raises(ParameterError, match='not both'):
        compensator.ImuCompensatorNode(context=context, parameter_overrides=_overrides(
            calibration_file=str(path), gyro_bias_rad_s=[0.1, 0.0, 0.0]))


@pytest.mark.timeout(60)
@pytest.mark.parametrize('args, words', [
    (['-p', 'gyro_scale_factor:=[-1.0, 0.0, 0.0]'], "'gyro_scale_factor'"),
    (['-p', 'accel_bias_m_s2:=[0.0, 0.0]'], "'accel_bias_m_s2'"),
    (['-p', 'realtime_priority:=100'], "'realtime_priority'"),
])
def test_bad_parameters_give_one_line_and_exit_2(args, words):
    proc = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.compensator',
                           '--ros-args', *args], capture_output=True, text=True, timeout=50)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and words in lines[0], proc.stderr
    assert lines[0].startswith('imu_compensator: error:')


def test_params_file_is_the_calibration_file(context, tmp_path):
    # calibration.yaml works as a --params-file: the node's own parameter names are its keys.
    params = _calibration_params(2)
    path = tmp_path / 'calibration.yaml'
    path.write_text('/**:\n  ros__parameters:\n' + ''.join(
        f'    {k}: {v!r}\n' for k, v in params.items()) + '    calibration_gravity_m_s2: 9.81\n')
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=['--ros-args', '--params-file', str(path)])
    try:
        node = compensator.ImuCompensatorNode(context=ctx)
        expected = calibration_from_parameters({**params, 'calibration_gravity_m_s2': 9.81})
        for sensor in ('accel', 'gyro'):
            got, want = getattr(node.calibration, sensor), getattr(expected, sensor)
            for field in ('bias', 'scale_factor', 'misalignment'):
                np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
        assert node.calibration.gravity_m_s2 == 9.81
        assert node._cal_source == 'parameters'
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


def test_model_file_through_the_registry(context, monkeypatch):
    # The thermal registry (gyro_noise_ros.thermal.methods.load_model) returns the fitted method
    # with its training record; a stand-in of that shape is enough to test the node's side.
    import types

    loaded = types.SimpleNamespace(
        method=LinearThermal(temperature_range_c=None),
        training=types.SimpleNamespace(temperature_min_c=15.0, temperature_max_c=35.0))
    module = types.ModuleType('gyro_noise_ros.thermal.methods')
    module.DEFAULT_RANGE_MARGIN_C = 5.0
    module.load_model = lambda path: loaded
    monkeypatch.setitem(sys.modules, 'gyro_noise_ros.thermal.methods', module)
    # `from . import methods` reads the package attribute once the real module was imported
    monkeypatch.setattr(importlib.import_module('gyro_noise_ros.thermal'), 'methods', module,
                        raising=False)
    node = compensator.ImuCompensatorNode(context=context, parameter_overrides=_overrides(
        thermal_model_file='model.json'))
    values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    assert values['Thermal model range (degC)'] == '15 to 35, margin 5'
    node.destroy_node()
    loaded.method = LinearThermal(name='parallel')
    with pytest.raises(ParameterError, match='offline only'):
        compensator.ImuCompensatorNode(context=context, parameter_overrides=_overrides(
            thermal_model_file='model.json'))


@pytest.mark.timeout(60)
def test_corrupt_temperature_is_counted_not_fatal(context):
    node = compensator.ImuCompensatorNode(context=context, thermal_model=LinearThermal(
        temperature_range_c=(0.0, 50.0)))
    _, _, _, raws = _imu_stream(400, seed=6)
    io = _Harness(context, node)
    try:
        good = encode_temperature_cdr([T0_NS], [25.0], frame_id='imu_test')[0]
        io.play([], temperatures=[b'\x00\x01\x00\x00' + b'\xff' * 8])
        assert _spin_until(io.executor, lambda: node.thermal.rejected >= 1, 10)
        io.play(raws, temperatures=[good])
        assert _spin_until(io.executor, lambda: node.counts['temperatures'] >= 2, 10)
        values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    finally:
        io.close()
    assert len(io.out) == 400
    assert values['Temperature messages'] == '2'
    assert int(values['Temperature messages rejected']) >= 1


def test_imu_before_the_first_temperature_waits_then_is_dropped_never_published_raw(context):
    node = compensator.ImuCompensatorNode(
        context=context, thermal_model=LinearThermal(temperature_range_c=(0.0, 50.0)),
        parameter_overrides=[Parameter('temperature_wait_s', value=0.3),
                             Parameter('max_temperature_wait_s', value=1.0)])
    _, _, _, raws = _imu_stream(400, seed=7)
    io = _Harness(context, node)
    try:
        for raw in raws:
            io.imu_pub.publish(raw)
        assert _spin_until(io.executor, lambda: node._gate.dropped == 400, 10)
        values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
        level = node.diagnostics().status[0].level
        # A temperature now lets later messages through; the dropped ones stay dropped.
        good = encode_temperature_cdr([T0_NS], [25.0], frame_id='imu_test')[0]
        io.temp_pub.publish(good)
        assert _spin_until(io.executor, lambda: node.counts['temperatures'] >= 1, 10)
        for raw in raws[:100]:
            io.imu_pub.publish(raw)
        assert _spin_until(io.executor, lambda: len(io.out) >= 100, 10)
    finally:
        io.close()
    assert values['Messages dropped waiting for the first temperature'] == '400'
    assert level == WARN
    assert len(io.out) == 100 and node.counts['published'] == 100


@pytest.mark.timeout(60)
def test_temperatures_published_before_the_samples_taken_are_applied_to_them(context, monkeypatch):
    # The driver publishes a read's temperature before its Imu messages. A temperature that
    # reaches the node between the start of a drain and its Imu take must still be applied to
    # those samples: the node takes temperatures after the Imu messages, not before.
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), temperature_range_c=(20.0, 30.0))
    node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                          parameter_overrides=_overrides(
                                              drain_period_s=0.5, temperature_rate_window_s=1.0))
    t_stamps = T0_NS + np.array([-NS // 2, 0])
    temps = np.array([25.0, 26.0])
    queue = [encode_temperature_cdr(t_stamps[:1], temps[:1], frame_id='imu_test')]
    samples = []

    def take(sub, msg_type, limit=None):
        """Stands for the node's takes: Imu messages once, the temperatures queued so far."""
        if msg_type is Imu:
            if samples:  # the second temperature was published just before these samples
                queue.append(encode_temperature_cdr(t_stamps[1:], temps[1:], frame_id='imu_test'))
            raws = samples[:]
            samples.clear()
        else:
            raws = [raw for batch in queue for raw in batch]
            queue.clear()
        return raws, [0] * len(raws), [0] * len(raws)

    monkeypatch.setattr(compensator, 'take_all', take)
    node.drain()  # the first temperature: an offset exists
    samples += _imu_stream(16, seed=3)[3]  # stamps from T0_NS: at and after the second temperature
    sent = []
    monkeypatch.setattr(node, '_emit', lambda *batch: sent.append(batch))
    try:
        node.drain()
    finally:
        node.destroy_node()
    assert node.thermal.stamp_ns == t_stamps[1]
    _, _, stamp_ns, _, _ = sent[0]
    twin = LiveDriftEvaluator(model, rate_window_s=1.0)
    twin.add_temperature(t_stamps, temps)
    np.testing.assert_array_equal(node.thermal.drift_at(stamp_ns), twin.drift_at(stamp_ns))


@pytest.mark.timeout(120)
def test_the_usual_batch_pass_publishes_the_general_paths_bytes(context):
    """Rows corrected in one compiled pass against the span decoder, numpy calibration, patch."""
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), temperature_range_c=(20.0, 30.0))
    params = _calibration_params(11)
    stamps, _, _, raws = _imu_stream(2000, seed=12)
    t_stamps = T0_NS + np.arange(-NS, NS // 3, NS // 50)  # 50 Hz, the window filled
    temps = encode_temperature_cdr(t_stamps, 25.0 + 0.5 * (t_stamps - T0_NS) / NS,
                                   frame_id='imu_test')
    outs, fast = [], []
    for general in (False, True):
        node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                              parameter_overrides=_overrides(
                                                  temperature_rate_window_s=1.0, **params))
        if general:  # every batch through the span decoder (the path of a mixed layout)
            node._layout.rows = lambda raws: None
        calls = []
        node_emit = node._emit

        def emit(spans, rows, stamp_ns, gyro, accel, calls=calls, node_emit=node_emit):
            calls.append(gyro is None)
            node_emit(spans, rows, stamp_ns, gyro, accel)
        node._emit = emit
        io = _Harness(context, node)
        try:
            io.play(raws, temperatures=temps, block=100)
        finally:
            io.close()
        outs.append(io.out)
        fast.append(sum(calls) / len(calls))
    # the first run took the compiled pass (all of it, unless a batch beat the first
    # temperature and waited at the gate), the second never
    assert fast[0] > 0.5 and fast[1] == 0.0
    assert len(outs[0]) == len(raws) and outs[0] == outs[1]
    np.testing.assert_array_equal(decode_imu(outs[0]).stamp_ns, stamps)


@pytest.mark.timeout(60)
def test_the_usual_batch_pass_is_ready_before_the_first_batch(context):
    """The node compiles (or loads) its kernel when it starts: batches then compile nothing."""
    from gyro_noise_ros.msgs import imu_rows
    for identity in (True, False):
        overrides = _overrides() if identity else _overrides(**_calibration_params(2))
        node = compensator.ImuCompensatorNode(context=context, parameter_overrides=overrides)
        before = list(imu_rows._correct_rows.signatures)  # compiled by the constructor
        try:
            assert before
            node.compensate(_imu_stream(16, seed=1)[3])
            node.compensate(_imu_stream(3, seed=2)[3])
        finally:
            node.destroy_node()
        assert list(imu_rows._correct_rows.signatures) == before
        assert node.counts['published'] == 19


def _driver_reads(seed, n_reads=60, per_read=16, temperature_every=128):
    """Return a driver's reads: (temperatures, imu) serialised, a temperature every 128th."""
    stamps, _, _, raws = _imu_stream(n_reads * per_read, seed=seed)
    rng = np.random.default_rng(seed)
    reads = []
    for r in range(n_reads):
        i = np.arange(r * per_read, (r + 1) * per_read)
        pick = i[i % temperature_every == 0]
        temps = encode_temperature_cdr(stamps[pick], 25.0 + 0.01 * pick / 128.0
                                       + rng.normal(0, 1e-3, pick.size), frame_id='imu_test')
        reads.append((temps, [raws[k] for k in i]))
    return reads


@pytest.mark.timeout(180)
@pytest.mark.parametrize('sync', ['latest', 'interpolate'])
def test_in_process_reads_publish_the_bytes_of_the_dds_path(context, sync):
    """imu_chain's compensator (accept, no subscriptions) against the node fed through DDS."""
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), temperature_range_c=(20.0, 30.0))
    params = dict(_calibration_params(21), temperature_rate_window_s=0.05,
                  temperature_sync=sync, max_temperature_wait_s=5.0)
    reads = _driver_reads(22)
    # Through DDS, read by read as the driver publishes them: temperatures, then the samples.
    node = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                          parameter_overrides=_overrides(**params))
    io = _Harness(context, node)
    try:
        for temps, imu in reads:
            for raw in temps:
                io.temp_pub.publish(raw)
            for raw in imu:
                io.imu_pub.publish(raw)
            sent = node.counts['received'] + len(imu)
            assert _spin_until(io.executor, lambda: node.counts['received'] == sent, 20)
        assert _spin_until(io.executor, lambda: len(io.out) == node.counts['published'], 10)
        dds, dds_counts = io.out, dict(node.counts)
    finally:
        io.close()
    # In process: the same reads handed over by accept(), as the driver's thread does.
    chained = compensator.ImuCompensatorNode(context=context, thermal_model=model,
                                             in_process=True,
                                             parameter_overrides=_overrides(**params))
    listener = rclpy.create_node('test_chain_listener', context=context)
    sub = listener.create_subscription(Imu, 'imu/data_compensated', unused_callback,
                                       QoSProfile(depth=50000,
                                                  reliability=ReliabilityPolicy.RELIABLE),
                                       raw=True, callback_group=PolledGroup())
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    executor.add_node(chained)
    out = []
    try:
        assert not chained.get_subscriptions_info_by_topic('imu/data_raw')
        assert _spin_until(executor, lambda: chained._pub.get_subscription_count() > 0, 20)
        _spin_until(executor, lambda: False, 0.3)
        for temps, imu in reads:
            chained.accept(temps, imu)
        assert _spin_until(executor, lambda: len(out) == chained.counts['published']
                           or out.extend(take_all(sub, Imu)[0]), 20)
        counts = dict(chained.counts)
    finally:
        executor.shutdown()
        listener.destroy_node()
        chained.destroy_node()
    assert counts == dds_counts and counts['received'] == sum(len(i) for _, i in reads)
    # latest publishes every sample at once; interpolate holds those after the last temperature
    newest = decode_temperature([raw for temps, _ in reads for raw in temps])[0].max()
    stamps = decode_imu([raw for _, imu in reads for raw in imu]).stamp_ns
    assert counts['published'] == (counts['received'] if sync == 'latest'
                                   else np.count_nonzero(stamps <= newest))
    assert out == dds  # the same bytes
