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
calibration.apply against a slow per-sample twin (np.linalg.solve of the model, sample by sample).

The twin writes the model as the calibration file documents it, measured = (I + diag(S) + M)
@ true + b, and solves it sample by sample; the vectorised path must agree to rounding.
"""

from gyro_noise_ros.calibration.apply import (Calibration, calibration_from_parameters, identity,
                                              KEYS, load_calibration, SensorCalibration)
from gyro_noise_ros.errors import InputError, ParameterError
import numpy as np
import pytest


def _slow_true(measured, bias, scale, mis):
    """Per-sample oracle: solve (I + diag(S) + M) x = measured - b with np.linalg.solve."""
    a = np.eye(3) + np.diag(scale) + np.asarray(mis).reshape(3, 3)
    return np.array([np.linalg.solve(a, row - bias) for row in measured])


def _params(rng):
    mis_a = rng.normal(0, 2e-3, (3, 3))
    np.fill_diagonal(mis_a, 0.0)
    mis_g = rng.normal(0, 2e-3, (3, 3))
    np.fill_diagonal(mis_g, 0.0)
    return {
        'accel_bias_m_s2': rng.normal(0, 0.05, 3).tolist(),
        'accel_scale_factor': rng.normal(0, 1e-3, 3).tolist(),
        'accel_misalignment': mis_a.reshape(-1).tolist(),
        'gyro_bias_rad_s': rng.normal(0, 0.01, 3).tolist(),
        'gyro_scale_factor': rng.normal(0, 1e-3, 3).tolist(),
        'gyro_misalignment': mis_g.reshape(-1).tolist(),
        'calibration_gravity_m_s2': 9.80665,
    }


def _write_yaml(path, params, key='/**'):
    lines = [f'{key}:', '  ros__parameters:']
    for name, value in params.items():
        lines.append(f'    {name}: {value!r}')
    path.write_text('\n'.join(lines) + '\n')


def test_vectorised_matches_per_sample_solve():
    rng = np.random.default_rng(1)
    p = _params(rng)
    cal = calibration_from_parameters(p)
    gyro = rng.normal(0, 1.0, (500, 3))
    accel = rng.normal(0, 9.8, (500, 3))
    g, a = cal.apply(gyro, accel)
    np.testing.assert_allclose(g, _slow_true(gyro, np.array(p['gyro_bias_rad_s']),
                                             np.array(p['gyro_scale_factor']),
                                             p['gyro_misalignment']), rtol=0, atol=1e-12)
    np.testing.assert_allclose(a, _slow_true(accel, np.array(p['accel_bias_m_s2']),
                                             np.array(p['accel_scale_factor']),
                                             p['accel_misalignment']), rtol=0, atol=1e-11)


def test_round_trip_through_the_model():
    # Distort known true values with the forward model, correct them: the truth comes back.
    rng = np.random.default_rng(2)
    cal = calibration_from_parameters(_params(rng)).gyro
    true = rng.normal(0, 2.0, (100, 3))
    measured = true @ cal.matrix.T + cal.bias
    np.testing.assert_allclose(cal.apply(measured), true, rtol=0, atol=1e-12)


def test_identity_changes_nothing_and_is_default():
    x = np.random.default_rng(3).normal(size=(10, 3))
    cal = identity()
    assert cal.gyro.is_identity and cal.accel.is_identity
    np.testing.assert_array_equal(cal.gyro.apply(x), x)
    assert calibration_from_parameters({}).gravity_m_s2 == 9.80665


def test_load_yaml_file_as_written_by_the_calibration_tool(tmp_path):
    rng = np.random.default_rng(4)
    p = _params(rng)
    path = tmp_path / 'calibration.yaml'
    _write_yaml(path, p)
    cal = load_calibration(path)
    assert isinstance(cal, Calibration) and isinstance(cal.accel, SensorCalibration)
    np.testing.assert_array_equal(cal.accel.bias, p['accel_bias_m_s2'])
    np.testing.assert_array_equal(cal.gyro.misalignment.reshape(-1), p['gyro_misalignment'])
    assert set(KEYS) <= set(p)


def test_yaml_is_a_ros_parameter_file(tmp_path):
    # The node can take the same file through --params-file: rclpy must parse it for any node name.
    rclpy_parameter = pytest.importorskip('rclpy.parameter')
    p = _params(np.random.default_rng(5))
    path = tmp_path / 'calibration.yaml'
    _write_yaml(path, p)
    params = rclpy_parameter.parameter_dict_from_yaml_file(str(path), use_wildcard=True)
    values = {k: rclpy_parameter.parameter_value_to_python(v.value) for k, v in params.items()}
    assert list(values['gyro_bias_rad_s']) == p['gyro_bias_rad_s']


@pytest.mark.parametrize('key, value, words', [
    ('accel_bias_m_s2', [0.0, 0.0], 'must have 3 values'),
    ('gyro_bias_rad_s', [0.0, float('nan'), 0.0], 'non-finite'),
    ('accel_scale_factor', [-1.0, 0.0, 0.0], 'singular or ill-conditioned'),
    ('gyro_scale_factor', [0.0, 'x', 0.0], 'must hold numbers'),
    ('gyro_misalignment', [0.1, 0, 0, 0, 0, 0, 0, 0, 0], 'zero diagonal'),
    ('gyro_misalignment', [0, 1.0, 0, 1.0, 0, 0, 0, 0, 0], 'singular or ill-conditioned'),
    ('calibration_gravity_m_s2', -9.8, 'must be > 0'),
])
def test_bad_values_name_the_key(key, value, words):
    with pytest.raises(ParameterError) as err:
        calibration_from_parameters({key: value})
    assert key in str(err.value) and words in str(err.value)


def test_bad_files(tmp_path):
    # an unreadable calibration file is an unreadable input (exit code 3), like a missing model
    missing = tmp_path / 'nope.yaml'
    with pytest.raises(InputError, match='does not exist') as err:
        load_calibration(missing)
    assert err.value.exit_code == 3
    binary = tmp_path / 'binary.yaml'
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(InputError, match='cannot be read as YAML'):
        load_calibration(binary)
    flat = tmp_path / 'flat.yaml'
    flat.write_text('accel_bias_m_s2: [0.0, 0.0, 0.0]\n')
    with pytest.raises(InputError, match='ros__parameters'):
        load_calibration(flat)
    partial = tmp_path / 'partial.yaml'
    partial.write_text('/**:\n  ros__parameters:\n    gyro_bias_rad_s: [0.0, 0.0, 0.0]\n')
    with pytest.raises(InputError, match='missing accel_bias_m_s2'):
        load_calibration(partial)
