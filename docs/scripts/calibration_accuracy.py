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
Accuracy of the six-position calibration against noise level and dwell length.

See docs/reliability.md. For each white-noise level and dwell length, simulate seeded
six-position records carrying the paper 001 Table 6 "before" values (100 Hz, 5 s rotations), run
the static-dwell detector and the estimator, and print the RMS error of the biases (mg) and scale
factors (%) beside the mean reported standard uncertainty. A last block adds the emulator's
default bias variation (flicker + random walk) to show what wander does. Run:
``python docs/scripts/calibration_accuracy.py [SEEDS]``.
"""

import sys

from gyro_noise_ros.calibration.emulate import (MG, PAPER_BEFORE_BIAS_MG, PAPER_BEFORE_SCALE_PCT,
                                                Scenario, SensorErrors, simulate, SixPosition)
from gyro_noise_ros.calibration.sixpos import six_position
from gyro_noise_ros.calibration.static import (DetectorSettings, find_dwells, ORIENTATIONS,
                                               select_six, WindowAccumulator)
import numpy as np

RATE = 100.0
#: 10 s dwells keep 8 s after trimming one 1 s window at each end
SETTINGS = DetectorSettings(min_static_s=5.0)


def run(noise_mg, dwell_s, seeds, errors):
    db, ds, sb, ss = [], [], [], []
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        motion = SixPosition(dwell_s=dwell_s, move_s=5.0, lead_s=2.0)
        sc = Scenario(motion, errors, RATE, rng)
        n = int((motion.duration_s + 2.0) * RATE)
        t, a, g = simulate(sc, n, RATE, rng=rng, accel_noise_m_s2=noise_mg * MG,
                           gyro_noise_rad_s=1e-3)
        acc = WindowAccumulator(RATE)
        acc.update(t, a, g)
        ch = select_six([find_dwells(acc.result(), SETTINGS)], SETTINGS)
        dw = [ch[o] for o in ORIENTATIONS]
        r = six_position([d.accel_mean_m_s2 for d in dw], 9.80665,
                         accel_sems_m_s2=[d.accel_sem_m_s2 for d in dw])
        db.append(r.accel_bias_m_s2 / MG - PAPER_BEFORE_BIAS_MG)
        ds.append(r.accel_scale_factor * 100 - PAPER_BEFORE_SCALE_PCT)
        sb.append(r.accel_bias_sigma_m_s2 / MG)
        ss.append(r.accel_scale_factor_sigma * 100)
    return (np.sqrt(np.mean(np.square(db))), np.mean(sb), np.sqrt(np.mean(np.square(ds))),
            np.mean(ss))


def main(seeds=30):
    print('| noise (mg/sample) | dwell (s) | RMS error b (mg) | reported sigma b (mg) | '
          'RMS error S (%) | reported sigma S (%) |')
    print('|---|---|---|---|---|---|')
    white = SensorErrors()
    for noise in (0.5, 2.0, 5.0):
        for dwell in (10.0, 30.0, 60.0, 300.0):
            eb, sb, es, ss = run(noise, dwell, seeds, white)
            print(f'| {noise:g} | {dwell:g} | {eb:.4f} | {sb:.4f} | {es:.5f} | {ss:.5f} |')
    n_white = 0.5 * MG / np.sqrt(RATE)      # white density of 0.5 mg per sample at 100 Hz
    wander = SensorErrors(accel_bias_instability_m_s2=n_white / 2 / 0.664,
                          accel_random_walk_m_s2_sqrt_s=n_white / 11.5)
    for dwell in (10.0, 60.0, 300.0):
        eb, sb, es, ss = run(0.5, dwell, seeds, wander)
        print(f'| 0.5 + flicker/random walk | {dwell:g} | {eb:.4f} | {sb:.4f} | {es:.5f} | '
              f'{ss:.5f} |')


if __name__ == '__main__':
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 30)
