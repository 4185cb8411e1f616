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
A minimal causal thermal model for tests: gyro offset linear in temperature (and its rate).

``drift_rad_s(T, dT) = offset + sensitivity * (T - t_ref) + rate_gain * dT`` per axis. It follows
the ThermalMethod protocol (fit by least squares on a ThermalRun) so the live evaluator and the
node treat it like any causal method of ``gyro_noise_ros.thermal``.
"""

from gyro_noise_ros.thermal.run import temperature_rate_c_s
import numpy as np


class LinearThermal:
    """Per-axis offset + sensitivity * (T - t_ref) + rate_gain * dT (rad/s)."""

    causal = True

    def __init__(self, sensitivity=(0.0, 0.0, 0.0), *, t_ref=25.0, offset=(0.0, 0.0, 0.0),
                 rate_gain=(0.0, 0.0, 0.0), temperature_range_c=(20.0, 30.0), name='linear_test',
                 range_margin_c=None):
        self.name = name
        self.sensitivity = np.asarray(sensitivity, dtype=float)
        self.t_ref = float(t_ref)
        self.offset = np.asarray(offset, dtype=float)
        self.rate_gain = np.asarray(rate_gain, dtype=float)
        # a model without a rate term does not wait for the rate window live (as poly3)
        self.uses_rate = bool(np.any(self.rate_gain != 0))
        self.temperature_range_c = (None if temperature_range_c is None
                                    else tuple(temperature_range_c))
        if range_margin_c is not None:
            self.range_margin_c = range_margin_c

    def drift_rad_s(self, temperature_c, dtemp_c_s):
        temp = np.asarray(temperature_c, dtype=float)[:, None]
        rate = np.asarray(dtemp_c_s, dtype=float)[:, None]
        return self.offset + self.sensitivity * (temp - self.t_ref) + self.rate_gain * rate

    def fit(self, run, *, rng=None):
        # Least squares of each gyro axis on [1, T - t_ref] over the run (rate term left at 0).
        self.t_ref = float(np.mean(run.temperature_c))
        design = np.column_stack([np.ones(run.t_s.size), run.temperature_c - self.t_ref])
        coef, *_ = np.linalg.lstsq(design, run.gyro_rad_s, rcond=None)
        self.offset, self.sensitivity = coef[0], coef[1]
        self.temperature_range_c = (float(run.temperature_c.min()), float(run.temperature_c.max()))

    def apply(self, run):
        rate = temperature_rate_c_s(run.t_s, run.temperature_c)
        return run.gyro_rad_s - self.drift_rad_s(run.temperature_c, rate)

    def to_dict(self):
        return {'method': self.name, 'sensitivity': self.sensitivity.tolist(), 't_ref': self.t_ref,
                'offset': self.offset.tolist(), 'rate_gain': self.rate_gain.tolist(),
                'temperature_range_c': list(self.temperature_range_c)}
