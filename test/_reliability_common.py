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

"""Shared helpers of the reliability-procedure tests: synthetic six-position records and bags."""

from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.calibration.emulate import Scenario, SensorErrors, simulate, SixPosition
import numpy as np

T0_NS = 1_700_000_000 * 10**9


def six_position_record(*, errors=None, rate_hz=100.0, dwell_s=30.0, move_s=4.0, seed=0,
                        accel_noise=0.04, gyro_noise=1e-3, order=None, extra_s=0.0):
    """Return (t, accel, gyro) of a six-position sequence through the scenario model."""
    rng = np.random.default_rng(seed)
    kw = {} if order is None else {'order': tuple(order)}
    motion = SixPosition(dwell_s=dwell_s, move_s=move_s, **kw)
    sc = Scenario(motion, errors or SensorErrors(), rate_hz, rng)
    n = int(round((motion.duration_s + extra_s) * rate_hz))
    return simulate(sc, n, rate_hz, rng=rng, accel_noise_m_s2=accel_noise,
                    gyro_noise_rad_s=gyro_noise)


def write_bag(path, t, accel, gyro, *, topic='/imu/data_raw', temperature_degc=None,
              frame_id='imu_link'):
    """Write an Imu bag (stamps T0 + t), with sensor_msgs/Temperature at 1 Hz when given."""
    stamps = T0_NS + np.round(np.asarray(t) * 1e9).astype(np.int64)
    temp_topic = None if temperature_degc is None else '/imu/temperature'
    with ImuBagWriter(path, imu_topic=topic, temperature_topic=temp_topic,
                      frame_id=frame_id) as w:
        w.write_imu(stamps, gyro, accel)
        if temperature_degc is not None:
            # temperature_degc: a constant or a function of t (s)
            ts = np.arange(float(t[0]), float(t[-1]), 1.0)
            temp = (temperature_degc(ts) if callable(temperature_degc)
                    else np.full(ts.size, float(temperature_degc)))
            w.write_temperature(T0_NS + np.round(ts * 1e9).astype(np.int64), temp)
    return path


def static_record(*, errors, rate_hz=10.0, duration_s=20000.0, seed=0, accel_noise=0.02,
                  gyro_noise=2e-3):
    """Return (t, accel, gyro) of a static record (+z up) through the scenario model."""
    from gyro_noise_ros.calibration.emulate import Static
    rng = np.random.default_rng(seed)
    sc = Scenario(Static(), errors, rate_hz, rng)
    return simulate(sc, int(duration_s * rate_hz), rate_hz, rng=rng,
                    accel_noise_m_s2=accel_noise, gyro_noise_rad_s=gyro_noise)
