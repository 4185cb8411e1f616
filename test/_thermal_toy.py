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
