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
reference. Each row: how often the test alone is significant and how often the verdict flags
(significant and beyond the practical tolerance, 1 %), on records without the defect (false
alarms), with one significant but within the tolerance (no flag by design) and with one beyond
it (detections), at the default false-alarm probability 1e-3. Run::

    python docs/scripts/excitation_verdicts.py [RECORDS_PER_ROW]

(seeded: the same numbers every time).
"""

import sys
import time

from gyro_noise_ros.calibration.emulate import Excitation
from gyro_noise_ros.calibration.excitation import DEFAULT_TOLERANCE, sine_dwell, sine_sweep
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


def rate(fn, flag, p_key, n, **kw):
    results = [fn(seed, **kw) for seed in range(n)]
    return (sum(getattr(r, p_key) < r.alpha for r in results), sum(flag(r) for r in results))


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    t0 = time.time()
    print(f'practical tolerance {100 * DEFAULT_TOLERANCE:g} %\n')
    print('| verdict | record | significant | flagged | of |')
    print('|---|---|---|---|---|')
    steady = lambda r: not r.steady                                           # noqa: E731
    clean = lambda r: not r.clean                                             # noqa: E731
    gain = lambda r: not r.matches_reference                                  # noqa: E731
    flat = lambda r: not r.flat                                               # noqa: E731
    rows = [
        ('unsteady (dwell)', 'clean sine + noise', dwell, steady, 'stability_p', {}),
        ('unsteady (dwell)', '1 % amplitude modulation at 0.1 Hz (stability 0.7 %)', dwell,
         steady, 'stability_p', {'am': 0.01}),
        ('unsteady (dwell)', '3 % amplitude modulation at 0.1 Hz (stability 2.1 %)', dwell,
         steady, 'stability_p', {'am': 0.03}),
        ('distorted (dwell)', 'clean sine + noise', dwell, clean, 'distortion_p', {}),
        ('distorted (dwell)', '0.5 % second harmonic', dwell, clean, 'distortion_p',
         {'h2': 5e-3}),
        ('distorted (dwell)', '2 % second harmonic', dwell, clean, 'distortion_p', {'h2': 2e-2}),
        ('gain differs (sweep)', 'sensor = reference + noise', sweep, gain, 'gain_p', {}),
        ('gain differs (sweep)', '0.1 % gain error', sweep, gain, 'gain_p', {'gain': 1e-3}),
        ('gain differs (sweep)', '2 % gain error', sweep, gain, 'gain_p', {'gain': 2e-2}),
        ('frequency-dependent (sweep)', 'sensor = reference + noise', sweep, flat, 'flatness_p',
         {}),
        ('frequency-dependent (sweep)', 'gain changing 2 % over 5-10 Hz (rms 0.6 %)', sweep,
         flat, 'flatness_p', {'slope': 2e-2}),
        ('frequency-dependent (sweep)', 'gain changing 6 % over 5-10 Hz (rms 1.7 %)', sweep,
         flat, 'flatness_p', {'slope': 6e-2}),
    ]
    for verdict, what, fn, flag, p_key, kw in rows:
        significant, flagged = rate(fn, flag, p_key, n, **kw)
        print(f'| {verdict} | {what} | {significant} | {flagged} | {n} |')
    print(f'\n({time.time() - t0:.0f} s wall)')


if __name__ == '__main__':
    main()
