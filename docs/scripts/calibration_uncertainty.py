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
Measure what the static calibration's uncertainties, tilt test and gravity check are worth.

The tables of docs/reliability.md section 1 ("What the numbers are worth"). Every record comes
from the emulator's scenario model (``calibration/emulate.py``) with the emulator's defaults at
104 Hz: accelerometer white noise 70 ug/sqrt(Hz) (0.5 mg per sample), gyro 0.058 deg/s per
sample, bias wander (flicker plateau at half the white Allan deviation at 1 s, random walk
white / 11.5) on both, paper Table 6 biases and scale factors, 0.1 % cross-axis terms. The truth
of a bias is the bias *during the calibration*: the constant plus the mean of the wander the
scenario generated over the samples used (regenerated from its seed); the distance to the
constant alone is shown beside it. Run::

    python docs/scripts/calibration_uncertainty.py [--runs 100] [--tilt-runs 20]
        [--multi-runs 40] [--gyro-runs 20] [--few-runs 20]

The gyro and the 9-14 pose rows turn each sequence to a seeded heading (where the horizontal Earth
rate points in the sensor frame is unknown to the calibration, so its coverage is over headings).

(seeded: the same numbers every time).
"""

import argparse
import dataclasses
import os
import time

from gyro_noise_ros.calibration.dwell_noise import fit_dwell_noise
from gyro_noise_ros.calibration.emulate import (BiasVariation, MultiPose, Scenario,
                                                SensorErrors, simulate, SixPosition)
from gyro_noise_ros.calibration.gyro_turns import direction_variances, fit_gyro_turns, Turn
from gyro_noise_ros.calibration.multipose import calibrate_poses, triangular
from gyro_noise_ros.calibration.sixpos import calibrate_six, consistency
from gyro_noise_ros.calibration.static import (DetectorSettings, find_dwells, select_poses,
                                               select_six, WindowAccumulator)
from gyro_noise_ros.errors import InputDataError
import numpy as np

G = 9.80665
MG = G * 1e-3
RATE = 104.0
N_ACC = 70e-6 * G / np.sqrt(2.0)
WHITE = 70e-6 * G * np.sqrt(RATE / 2.0)
GYRO_WHITE = 0.058 * np.pi / 180.0
N_GYR = GYRO_WHITE / np.sqrt(RATE)
ACCEL_WANDER = {'accel_bias_instability_m_s2': N_ACC / 2.0 / 0.664,
                'accel_random_walk_m_s2_sqrt_s': N_ACC / 11.5}
GYRO_WANDER = {'gyro_bias_instability_rad_s': N_GYR / 2.0 / 0.664,
               'gyro_random_walk_rad_s_sqrt_s': N_GYR / 11.5}
MIS = np.array([0.10, -0.05, 0.08, 0.03, -0.10, 0.05]) / 100.0
GYRO = {'gyro_bias_rad_s': (0.0135, -0.006, 0.0044), 'gyro_scale_factor': (0.003, -0.002, 0.001),
        'gyro_misalignment': np.array([0.2, -0.1, 0.15, 0.3, -0.25, 0.1]) / 100.0}
OFF = ~np.eye(3, dtype=bool)


def errors(wander=True):
    return SensorErrors(accel_misalignment=MIS, **GYRO,
                        **(dict(ACCEL_WANDER, **GYRO_WANDER) if wander else {}))


def record(motion, err, seed):
    n = int(round((motion.duration_s + 5.0) * RATE))
    sc = Scenario(motion, err, RATE, np.random.default_rng([seed, 2]))
    t, a, g = simulate(sc, n, RATE, rng=np.random.default_rng(seed), accel_noise_m_s2=WHITE,
                       gyro_noise_rad_s=GYRO_WHITE)
    acc = WindowAccumulator(RATE)
    acc.update(t, a, g)
    return t, a, g, find_dwells(acc.result(), DetectorSettings())


def wander_mean(err, t, seed, dwells):
    acc_rng, _ = np.random.default_rng([seed, 2]).spawn(2)
    u = BiasVariation(err.accel_bias_instability_m_s2, err.accel_random_walk_m_s2_sqrt_s, RATE,
                      acc_rng).generate(t.size)
    used = np.zeros(t.size, bool)
    for d in dwells:
        used |= (t >= d.t_start_s - 1e-9) & (t < d.t_end_s - 1e-9)
    return u[used].mean(axis=0)


def coverage(z):
    z = np.abs(np.concatenate([np.ravel(v) for v in z]))
    return f'{100 * np.mean(z < 1):.1f} %', f'{np.sqrt(np.mean(z ** 2)):.2f}', z.size


def six_position_table(runs):
    print('### Six-position: coverage of the stated 1-sigma uncertainty\n')
    print('| noise | calibrations | values | b: within 1 sigma | rms z | S: within 1 sigma '
          '| rms z | M: within 1 sigma | rms z | mean sigma b (mg) | mean sigma S (%) '
          '| b within 1 sigma of the constant |')
    print('|---|---|---|---|---|---|---|---|---|---|---|---|')
    checks = {}
    for label, wander in (('white + default wander', True), ('white only', False)):
        err = errors(wander)
        motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0)
        zb, zs, zm, zc, sb, ss, fa_pair, fa_loo = [], [], [], [], [], [], 0, 0
        for seed in range(runs):
            t, _, _, det = record(motion, err, 1000 + seed)
            chosen = select_six([det])
            res, _, _ = calibrate_six(chosen, G)
            truth = err.accel_bias_m_s2 + wander_mean(err, t, 1000 + seed, chosen.values())
            zb.append((res.accel_bias_m_s2 - truth) / res.accel_bias_sigma_m_s2)
            zc.append((res.accel_bias_m_s2 - err.accel_bias_m_s2) / res.accel_bias_sigma_m_s2)
            zs.append((res.accel_scale_factor - err.accel_scale_factor)
                      / res.accel_scale_factor_sigma)
            zm.append((res.accel_misalignment - err.accel_misalignment)[OFF]
                      / res.accel_misalignment_sigma[OFF])
            sb.append(res.accel_bias_sigma_m_s2 / MG)
            ss.append(res.accel_scale_factor_sigma * 100)
            pairs, loo = consistency(chosen, G)
            fa_pair += not all(p.consistent for p in pairs)
            fa_loo += not all(c.consistent for c in loo)
        cb, cs, cm, cc = coverage(zb), coverage(zs), coverage(zm), coverage(zc)
        print(f'| {label} | {runs} | {cb[2]} + {cs[2]} + {cm[2]} | {cb[0]} | {cb[1]} | {cs[0]} '
              f'| {cs[1]} | {cm[0]} | {cm[1]} | {np.mean(sb):.4f} | {np.mean(ss):.5f} '
              f'| {cc[0]} |')
        checks[label] = (runs, fa_pair, fa_loo)
    print()
    return checks


def tilt_table(runs, untilted):
    print('### Six-position: the tilt (consistency) test and the leave-one-out gravity check\n')
    print('| dwell tilt | calibrations | refused by the consistency test | the tilted dwell '
          'named | gravity check failed |')
    print('|---|---|---|---|---|')
    for label, (n, fa_pair, fa_loo) in untilted.items():
        print(f'| none ({label}) | {n} | {fa_pair} (false alarms) | - | {fa_loo} of {n} '
              f'(false alarms) |')
    err = errors(True)
    dwells = ('+x', '-x', '+y', '-y', '+z', '-z')
    for deg in (0.1, 0.3, 1.0, 3.0, 5.0):
        refused = named = loo_failed = gated = 0
        for seed in range(runs):
            o = dwells[seed % 6]
            motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0, tilts=((o, deg),))
            _, _, _, det = record(motion, err, 2000 + seed)
            try:
                chosen = select_six([det])
            except InputDataError:
                gated += 1                     # beyond --max-tilt-deg: refused, named too
                refused += 1
                named += 1
                continue
            pairs, loo = consistency(chosen, G)
            bad = [p for p in pairs if not p.consistent]
            refused += bool(bad)
            named += any(p.suspect == o for p in bad)
            loo_failed += not all(c.consistent for c in loo)
        extra = f' ({gated} by --max-tilt-deg)' if gated else ''
        print(f'| {deg:g} deg | {runs} | {refused}{extra} | {named} | {loo_failed} of '
              f'{runs - gated} |')
    print()


def multi_pose_table(runs):
    print('### Multi-pose (18 poses x 30 s, 5 s turns): accuracy and coverage\n')
    print('| noise | calibrations | largest abs(b - truth) (mg) | largest abs(b - constant) (mg) '
          '| largest abs(S - truth) (%) | b within 1 sigma | S within 1 sigma '
          '| gravity check failed |')
    print('|---|---|---|---|---|---|---|---|')
    for label, wander in (('white + default wander', True), ('white only', False)):
        err = errors(wander)
        lower, _ = triangular(err.accel_matrix)
        motion = MultiPose(poses=18, dwell_s=30.0, move_s=5.0, lead_s=5.0)
        eb, ec, es, zb, zs, failed = [], [], [], [], [], 0
        for seed in range(runs):
            t, _, _, det = record(motion, err, 3000 + seed)
            dwells = select_poses([det])
            res, loo, _ = calibrate_poses(dwells, G)
            truth = err.accel_bias_m_s2 + wander_mean(err, t, 3000 + seed, dwells)
            eb.append(np.abs(res.bias_m_s2 - truth) / MG)
            ec.append(np.abs(res.bias_m_s2 - err.accel_bias_m_s2) / MG)
            es.append(np.abs(res.scale_factor - (np.diag(lower) - 1.0)) * 100)
            zb.append((res.bias_m_s2 - truth) / res.bias_sigma_m_s2)
            zs.append((res.scale_factor - (np.diag(lower) - 1.0)) / res.scale_factor_sigma)
            failed += bool(res.left_out) or not all(c.consistent for c in loo)
        print(f'| {label} | {runs} | {np.max(eb):.4f} | {np.max(ec):.4f} | {np.max(es):.5f} '
              f'| {coverage(zb)[0]} | {coverage(zs)[0]} | {failed} |')
    print()


def _turns(t, g, dwells):
    out = []
    for k in range(len(dwells) - 1):
        sel = (t >= dwells[k].t_end_s - 1e-9) & (t <= dwells[k + 1].t_start_s + 1e-9)
        out.append(Turn(k, k + 1, t[sel], g[sel]))
    return out


def heading(seed):
    """Return a heading per calibration (deg): where the horizontal Earth rate points."""
    return float(np.random.default_rng([seed, 9]).uniform(0.0, 360.0))


def gyro_table(runs):
    print('### Gyro scale factor and misalignment from the turns\n')
    print('| sequence | calibrations | terms estimated | S within 1 sigma | rms z '
          '| M within 1 sigma | rms z | mean sigma S (%) | mean sigma M (%) |')
    print('|---|---|---|---|---|---|---|---|---|')
    err = errors(True)
    sequences = (('multi-pose 18 x 30 s', MultiPose(poses=18, dwell_s=30.0, move_s=5.0,
                                                    lead_s=5.0)),
                 ('six-position 6 x 60 s', SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0)))
    for label, motion in sequences:
        zs, zm, ss, sm, est = [], [], [], [], 0
        for seed in range(runs):
            turned = dataclasses.replace(motion, heading_deg=heading(4000 + seed))
            t, _, g, det = record(turned, err, 4000 + seed)
            if isinstance(motion, MultiPose):
                dwells = select_poses([det])
                acc, _, accel_noise = calibrate_poses(dwells, G)
                directions = acc.compensate(np.array([d.accel_mean_m_s2 for d in dwells]))
                _, rot = triangular(err.accel_matrix)
            else:
                chosen = select_six([det])
                acc, _, _ = calibrate_six(chosen, G)
                dwells = sorted(chosen.values(), key=lambda d: d.t_start_s)
                directions = acc.compensate_accel(np.array([d.accel_mean_m_s2 for d in dwells]))
                accel_noise = fit_dwell_noise([d.window_t_s for d in dwells],
                                              [d.window_n for d in dwells],
                                              [d.window_accel_m_s2 for d in dwells])
                rot = np.eye(3)
            noise = fit_dwell_noise([d.window_t_s for d in dwells], [d.window_n for d in dwells],
                                    [d.window_gyro_rad_s for d in dwells])
            turns = _turns(t, g, dwells)
            dvar = direction_variances(turns, accel_noise, list(range(len(dwells))), G)
            res = fit_gyro_turns(turns, directions, dwells, noise, direction_variance=dvar,
                                 latitude_deg=motion.latitude_deg)
            truth = err.gyro_matrix @ rot.T
            d = res.estimated.diagonal()
            o = res.estimated[OFF]
            zs.append((res.scale_factor - (np.diag(truth) - 1.0))[d] / res.scale_factor_sigma[d])
            zm.append((res.misalignment - truth)[OFF][o] / res.misalignment_sigma[OFF][o])
            ss.append(res.scale_factor_sigma[d] * 100)
            sm.append(res.misalignment_sigma[OFF][o] * 100)
            est += int(res.estimated.sum())
        cs, cm = coverage(zs), coverage(zm)
        print(f'| {label} | {runs} | {est / runs:.1f} of 9 | {cs[0]} | {cs[1]} | {cm[0]} '
              f'| {cm[1]} | {np.mean(np.concatenate(ss)):.4f} '
              f'| {np.mean(np.concatenate(sm)):.4f} |')
    print()


def few_poses_table(runs):
    print('### Multi-pose at its minimum: 9 to 14 poses x 30 s\n')
    print('| poses | calibrations | gravity checks run | false alarms (calibrations) '
          '| one pose off by 1 mg: flagged | that pose named | b within 1 sigma '
          '| S within 1 sigma |')
    print('|---|---|---|---|---|---|---|---|')
    err = errors(True)
    lower, _ = triangular(err.accel_matrix)
    for poses in (9, 10, 12, 14):
        checks = false = flagged = named = 0
        zb, zs = [], []
        for seed in range(runs):
            motion = MultiPose(poses=poses, dwell_s=30.0, move_s=5.0, lead_s=5.0,
                               heading_deg=heading(5000 + seed))
            t, _, _, det = record(motion, err, 5000 + seed)
            dwells = select_poses([det])
            res, loo, _ = calibrate_poses(dwells, G)
            checks += len(loo)
            false += bool(res.left_out) or not all(c.consistent for c in loo)
            truth = err.accel_bias_m_s2 + wander_mean(err, t, 5000 + seed, dwells)
            zb.append((res.bias_m_s2 - truth) / res.bias_sigma_m_s2)
            zs.append((res.scale_factor - (np.diag(lower) - 1.0)) / res.scale_factor_sigma)
            # the same poses with one of them 1 mg off along gravity (a knock, a pose that moved)
            k = seed % poses
            up = dwells[k].accel_mean_m_s2 / np.linalg.norm(dwells[k].accel_mean_m_s2)
            dwells[k] = dataclasses.replace(dwells[k],
                                            accel_mean_m_s2=dwells[k].accel_mean_m_s2 + MG * up)
            res, loo, _ = calibrate_poses(dwells, G)
            bad = [j for j, c in enumerate(loo) if not c.consistent]
            flagged += bool(bad) or bool(res.left_out)
            named += bad == [k] or res.left_out == (loo[k].label,) if loo else 0
        print(f'| {poses} | {runs} | {checks} | {false} | {flagged if checks else "-"} '
              f'| {named if checks else "-"} | {coverage(zb)[0]} | {coverage(zs)[0]} |')
    print()


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--runs', type=int, default=100, help='six-position calibrations per row')
    p.add_argument('--tilt-runs', type=int, default=20, help='calibrations per tilt')
    p.add_argument('--multi-runs', type=int, default=40, help='multi-pose calibrations per row')
    p.add_argument('--gyro-runs', type=int, default=20, help='calibrations per gyro row')
    p.add_argument('--few-runs', type=int, default=20,
                   help='calibrations per row of the 9-14 pose table')
    args = p.parse_args()
    t0 = time.time()
    untilted = six_position_table(args.runs)
    tilt_table(args.tilt_runs, untilted)
    multi_pose_table(args.multi_runs)
    gyro_table(args.gyro_runs)
    few_poses_table(args.few_runs)
    print(f'({time.time() - t0:.0f} s wall, load average {os.getloadavg()[0]:.1f})')


if __name__ == '__main__':
    main()
