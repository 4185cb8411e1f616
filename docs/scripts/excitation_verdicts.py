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
Measure the false-alarm and detection rates of the excitation verdicts.

The table of docs/reliability.md section 3. Records as paper 001 section 5.3 takes them, seen by
the emulator's accelerometer: 0.3 g on one axis at 104 Hz with 0.5 mg of white noise per sample;
sine dwell at 8 Hz for 30 s, sine sweep 5 -> 10 -> 5 Hz at 0.5 Hz/s for 40 s against an ideal
reference. Each row: how often the verdict flags, on records without the defect (false alarms)
and with a known one (detections), at the default false-alarm probability 1e-3. Run::

    python docs/scripts/excitation_verdicts.py [RECORDS_PER_ROW]

(seeded: the same numbers every time).
"""

import sys
import time

from gyro_noise_ros.calibration.emulate import Excitation
from gyro_noise_ros.calibration.excitation import sine_dwell, sine_sweep
import numpy as np

G = 9.80665
RATE = 104.0
NOISE = 70e-6 * G * np.sqrt(RATE / 2.0)
AMP = 0.3 * G


def dwell(seed, *, am=0.0, h2=0.0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(30 * RATE)) / RATE
    env = AMP * (1.0 + am * np.sin(2 * np.pi * 0.1 * t + rng.uniform(0, 6.3)))
    x = (G + env * np.sin(2 * np.pi * 8.0 * t + rng.uniform(0, 6.3))
         + h2 * AMP * np.sin(4 * np.pi * 8.0 * t + rng.uniform(0, 6.3))
         + rng.normal(0, NOISE, t.size))
    return sine_dwell(x, RATE, 8.0)


def sweep(seed, *, gain=0.0, slope=0.0):
    rng = np.random.default_rng(seed)
    ex = Excitation(sensor='accel', axis='y', amplitude=AMP, frequency_hz=5.0, sweep_to_hz=10.0,
                    sweep_rate_hz_s=0.5)
    t = np.arange(int(40 * RATE)) / RATE
    ref = ex.reference(t)[:, 1]
    _, freq = ex.phase_and_frequency(t)
    # a gain error, and one changing linearly across the band (slope: change over 5 Hz)
    meas = ref * (1.0 + gain + slope * (freq - 7.5) / 5.0) + rng.normal(0, NOISE, t.size)
    return sine_sweep(meas, RATE, 5.0, 10.0, 0.5, reference=ref)


def rate(fn, flag, n, **kw):
    return sum(flag(fn(seed, **kw)) for seed in range(n))


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    t0 = time.time()
    print('| verdict | record | flagged | of |')
    print('|---|---|---|---|')
    steady = lambda r: not r.steady                                           # noqa: E731
    clean = lambda r: not r.clean                                             # noqa: E731
    gain = lambda r: not r.matches_reference                                  # noqa: E731
    flat = lambda r: not r.flat                                               # noqa: E731
    rows = [
        ('unsteady (dwell)', 'clean sine + noise', dwell, steady, {}),
        ('unsteady (dwell)', '0.1 % amplitude modulation at 0.1 Hz', dwell, steady,
         {'am': 0.001}),
        ('unsteady (dwell)', '0.3 % amplitude modulation at 0.1 Hz', dwell, steady,
         {'am': 0.003}),
        ('distorted (dwell)', 'clean sine + noise', dwell, clean, {}),
        ('distorted (dwell)', '0.01 % second harmonic', dwell, clean, {'h2': 1e-4}),
        ('distorted (dwell)', '0.02 % second harmonic', dwell, clean, {'h2': 2e-4}),
        ('distorted (dwell)', '0.03 % second harmonic', dwell, clean, {'h2': 3e-4}),
        ('gain differs (sweep)', 'sensor = reference + noise', sweep, gain, {}),
        ('gain differs (sweep)', '0.01 % gain error', sweep, gain, {'gain': 1e-4}),
        ('gain differs (sweep)', '0.03 % gain error', sweep, gain, {'gain': 3e-4}),
        ('frequency-dependent (sweep)', 'sensor = reference + noise', sweep, flat, {}),
        ('frequency-dependent (sweep)', 'gain changing 0.1 % over 5-10 Hz', sweep, flat,
         {'slope': 1e-3}),
        ('frequency-dependent (sweep)', 'gain changing 0.3 % over 5-10 Hz', sweep, flat,
         {'slope': 3e-3}),
    ]
    for verdict, what, fn, flag, kw in rows:
        print(f'| {verdict} | {what} | {rate(fn, flag, n, **kw)} | {n} |')
    print(f'\n({time.time() - t0:.0f} s wall)')


if __name__ == '__main__':
    main()
