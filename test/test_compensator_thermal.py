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


"""imu_compensator with a model.json: accelerometer compensation and the trained dT range."""

from gyro_noise_ros.bag import decode_imu
from gyro_noise_ros.msgs import encode_temperature_cdr
from gyro_noise_ros.nodes import compensator
from gyro_noise_ros.thermal import methods
from gyro_noise_ros.thermal.run import ThermalRun
import numpy as np
import pytest
from rclpy.parameter import Parameter
from test_compensator_node import _Harness, _imu_stream, NS, RATE_HZ
from test_compensator_node import _spin_until, T0_NS

pytestmark = pytest.mark.ros


def _model_file(tmp_path, method):
    """Fit ``method`` and the accelerometer polynomial on a 20-min warm-up, save it."""
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 1200.0, 0.2)
    # holds around the ramp: a constant rate alone cannot support a dT term
    temp = np.interp(t, [0.0, 200.0, 1000.0, t[-1]], [15.0, 15.0, 35.0, 35.0])
    d = temp - 25.0
    gyro = np.column_stack([1e-3 * d, -5e-4 * d, 2e-4 * d]) + rng.normal(0, 1e-4, (t.size, 3))
    accel = (np.column_stack([2e-3 * d, -1e-3 * d + 2e-5 * d ** 2, 9.81 + 3e-3 * d])
             + rng.normal(0, 1e-4, (t.size, 3)))
    run = ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=5.0, name='ramp',
                     accel_m_s2=accel)
    model = methods.fit_method(method, run, rng=np.random.default_rng(0))
    path = tmp_path / 'model.json'
    methods.save_model(model.method, path, training=model.training, accel=model.accel)
    return path, model


@pytest.mark.timeout(120)
def test_accelerometer_offset_change_is_subtracted(context, tmp_path):
    path, model = _model_file(tmp_path, 'poly3')
    node = compensator.ImuCompensatorNode(context=context, parameter_overrides=[
        Parameter('thermal_model_file', value=str(path))])
    stamps, gyro, accel, raws = _imu_stream(int(RATE_HZ), seed=6)
    t_stamps = T0_NS + np.arange(0, NS + 1, NS // 50)
    temps = np.full(t_stamps.size, 30.0)
    io = _Harness(context, node)
    try:
        io.play(raws, temperatures=encode_temperature_cdr(t_stamps, temps, frame_id='imu_test'))
        values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    finally:
        io.close()
    out = decode_imu(io.out)
    # poly3 does not use dT: no start-up wait, every message published
    assert out.stamp_ns.size == stamps.size
    expected_gyro = gyro - model.method.drift_rad_s([30.0], [0.0])
    expected_accel = accel - model.accel.drift_rad_s([30.0], [0.0])
    np.testing.assert_allclose(out.gyro, expected_gyro, rtol=0, atol=1e-15)
    np.testing.assert_allclose(out.accel, expected_accel, rtol=0, atol=1e-14)
    # the change from T_ref (25 degC) at 30 degC: about 10 mg on x
    assert abs(model.accel.drift_rad_s([30.0], [0.0])[0, 0] - 0.01) < 1e-3
    assert values['Accelerometer thermal offset (mg)'] != 'none'


@pytest.mark.timeout(120)
def test_rate_model_waits_for_its_window_and_counts_rates_outside_training(context, tmp_path):
    path, model = _model_file(tmp_path, 'linear_tdt')
    node = compensator.ImuCompensatorNode(context=context, parameter_overrides=[
        Parameter('thermal_model_file', value=str(path)),
        Parameter('temperature_rate_window_s', value=1.0)])
    assert node.thermal.start_up_s == 1.0
    lo, hi = node.thermal.rate_range_c_s
    assert lo == pytest.approx(model.training.temperature_rate_min_c_s)
    stamps, gyro, accel, raws = _imu_stream(2 * int(RATE_HZ), seed=7)
    t_stamps = T0_NS + np.arange(0, 2 * NS + 1, NS // 50)
    # cooling at 0.5 degC/s: far below the heating-only training range
    temps = 30.0 - 0.5 * (t_stamps - T0_NS) / NS
    io = _Harness(context, node)
    try:
        io.play(raws, temperatures=encode_temperature_cdr(t_stamps, temps, frame_id='imu_test'))
        assert _spin_until(io.executor, lambda: len(io.out) >= len(raws), 10)
        values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    finally:
        io.close()
    # nothing dropped: the samples of the first second waited for the filled window
    assert decode_imu(io.out).stamp_ns.size == stamps.size
    assert int(values['Temperature messages outside the trained rate range']) > 0.9 * 50
    assert float(values['Share outside the trained range of T or dT (%)']) > 90.0
    assert values['Temperature messages waiting for the rate window'] == '0'
