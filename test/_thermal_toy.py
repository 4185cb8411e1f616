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
Test-only thermal methods: a per-axis linear-in-temperature drift model and first-order filters.

They implement the ThermalMethod protocol in a few obviously-correct lines so the registry, the
CLI and the metrics can be tested before (and independently of) the real methods.
"""

import math

import numpy as np
import scipy.signal


class LinearInT:
    """Per-axis gyro offset b0 + b1 T, least squares; causal."""

    name = 'toy_linear'
    causal = True

    def __init__(self):
        self.coef = None

    def fit(self, run, *, rng):
        design = np.column_stack([np.ones(run.t_s.size), run.temperature_c])
        self.coef = np.linalg.lstsq(design, run.gyro_rad_s, rcond=None)[0]

    def drift_rad_s(self, temperature_c, dtemp_c_s):
        temp = np.asarray(temperature_c, dtype=float)
        return self.coef[0][None, :] + temp[:, None] * self.coef[1][None, :]

    def apply(self, run):
        return run.gyro_rad_s - self.drift_rad_s(run.temperature_c, None)

    def to_dict(self):
        return {'coef_rad_s': np.asarray(self.coef).tolist()}

    @classmethod
    def from_dict(cls, d):
        m = cls()
        m.coef = np.asarray(d['coef_rad_s'], dtype=float).reshape(2, 3)
        return m


class FirstOrderLowPass:
    """y[k] = y[k-1] + a (x[k] - y[k-1]), a = 1 - exp(-2 pi fc / fs); zero-phase if asked."""

    name = 'toy_lowpass'

    def __init__(self, fc_hz=5.0, zero_phase=False):
        self.fc_hz = fc_hz
        self.zero_phase = zero_phase
        self.causal = not zero_phase

    def fit(self, run, *, rng):
        pass

    def coefficients(self, rate_hz):
        a = 1.0 - math.exp(-2.0 * math.pi * self.fc_hz / rate_hz)
        return [a], [1.0, -(1.0 - a)]

    def apply(self, run):
        b, a = self.coefficients(run.rate_hz)
        if self.zero_phase:
            return scipy.signal.filtfilt(b, a, run.gyro_rad_s, axis=0)
        return scipy.signal.lfilter(b, a, run.gyro_rad_s, axis=0)

    def to_dict(self):
        return {'fc_hz': self.fc_hz, 'zero_phase': self.zero_phase}

    @classmethod
    def from_dict(cls, d):
        return cls(d['fc_hz'], d['zero_phase'])


class Identity:
    """Returns the input; causal."""

    name = 'toy_identity'
    causal = True

    def fit(self, run, *, rng):
        pass

    def apply(self, run):
        return np.array(run.gyro_rad_s, dtype=float)

    def to_dict(self):
        return {}

    @classmethod
    def from_dict(cls, d):
        return cls()


T0_NS = 1_700_000_000 * 10**9


def write_thermal_bag(path, t_s, gyro_rad_s, temp_t_s, temperature_c, *, storage='sqlite3',
                      imu_topic='/imu/data_raw', temperature_topic='/imu/temperature',
                      extra_topic=None, t0_ns=T0_NS):
    """Write a rosbag2 with Imu (and Temperature unless temperature_topic is None) messages."""
    from gyro_noise_ros.bag import ImuBagWriter

    stamps = t0_ns + np.round(np.asarray(t_s) * 1e9).astype(np.int64)
    n = stamps.size
    accel = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.001 * np.arange(n)[:, None]
    with ImuBagWriter(path, storage=storage, imu_topic=imu_topic,
                      temperature_topic=temperature_topic) as w:
        w.write_imu(stamps, gyro_rad_s, accel, log_ns=t0_ns + np.arange(n, dtype=np.int64))
        if temperature_topic is not None:
            t_stamps = t0_ns + np.round(np.asarray(temp_t_s) * 1e9).astype(np.int64)
            w.write_temperature(t_stamps, temperature_c, variance=0.01)
        if extra_topic is not None:
            from rosbags.typesys import get_typestore, Stores

            store = get_typestore(Stores.ROS2_JAZZY)
            conn = w._writer.add_connection(extra_topic, 'std_msgs/msg/String', typestore=store)
            for i in range(3):
                raw = store.serialize_cdr(store.types['std_msgs/msg/String'](data=f'note {i}'),
                                          'std_msgs/msg/String')
                w._writer.write(conn, t0_ns + i, raw)
    return path, accel


class HardThreshold:
    """Zero every sample with |x| <= k sigma (sigma fixed at fit); non-linear, causal."""

    name = 'toy_threshold'
    causal = True

    def __init__(self, threshold_rad_s=3e-3):
        self.threshold_rad_s = threshold_rad_s

    def fit(self, run, *, rng):
        pass

    def apply(self, run):
        g = np.asarray(run.gyro_rad_s, dtype=float)
        return np.where(np.abs(g) > self.threshold_rad_s, g, 0.0)

    def to_dict(self):
        return {'threshold_rad_s': self.threshold_rad_s}

    @classmethod
    def from_dict(cls, d):
        return cls(d['threshold_rad_s'])
