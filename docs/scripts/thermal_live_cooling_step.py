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
Live compensation through a cooling step: what each causal model leaves, in 1-s means.

Usage::

    python docs/scripts/thermal_live_cooling_step.py [--seed 3] [--rate-hz 20]
        [--figure docs/figures/thermal/live_cooling_step.png]

The board is calibrated on a warm-up (``heating``: 10 -> 50 degC at 1 degC/min, the usual
calibration run) and then, held out, left at 50 degC and cooled quickly to 10 degC (``cooling``
with a 0.5 degC/s set-point ramp: a chamber door opened, a fan switched on; the die follows
with its 600-s lag). Each causal model (``poly3``, ``linear_tdt``, ``bp``) is fitted on the
warm-up and run exactly as the ``imu_compensator`` node runs it:
:class:`gyro_noise_ros.thermal.live.LiveDriftEvaluator`, fed the temperature messages (52 Hz,
as the driver publishes them) in batches of one second, its offsets interpolated onto the gyro
stamps. The output is the compensated rate; the script prints, per model and axis, the standard
deviation of the 1-s means (the raw run's, and the ratio), the step the model leaves (mean of the
last 20 minutes minus the mean of the first 20, deg/s) and the largest excursion of the 60-s
means (all from the end of the first 10-s rate window, which the node holds back), and draws
the 1-s means of the raw and compensated x axis against time with the die
temperature.
"""

import argparse
from pathlib import Path

from gyro_noise_ros.plotting import pyplot, save_figure
from gyro_noise_ros.thermal.baselines import BPNetwork, LinearTdT, TemperaturePolynomial
from gyro_noise_ros.thermal.live import LiveDriftEvaluator
from gyro_noise_ros.thermal.simulate import make_profile, simulate_pair
from gyro_noise_ros.units import RAD_TO_DEG
import numpy as np


def live_compensate(method, run, truth):
    """Return the run compensated the way the live node does it (rad/s, (n, 3))."""
    ev = LiveDriftEvaluator(method, margin_c=50.0)
    stamps = np.round(run.t_s * 1e9).astype(np.int64)
    t_stamps = stamps[truth.temperature_index]
    out = np.array(run.gyro_rad_s, dtype=float)
    second = int(round(run.rate_hz))
    for lo in range(0, stamps.size, second):
        hi = min(lo + second, stamps.size)
        # the temperature messages stamped up to the end of this second arrive with it
        sel = (t_stamps >= stamps[lo]) & (t_stamps <= stamps[hi - 1])
        ev.add_temperature(t_stamps[sel], truth.temperature_reading_c[sel])
        drift = ev.drift_at(stamps[lo:hi])
        if drift is not None:
            out[lo:hi] -= drift
    return out


def means(x, n):
    """Return the means of consecutive blocks of n samples (whole blocks only)."""
    k = x.shape[0] // n
    return x[:k * n].reshape(k, n, *x.shape[1:]).mean(axis=1)


def main():
    """Fit, compensate live, print and draw."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--seed', type=int, default=3)
    parser.add_argument('--rate-hz', type=float, default=20.0)
    parser.add_argument('--figure', default='docs/figures/thermal/live_cooling_step.png')
    args = parser.parse_args()
    (_, train, _), (_, test, truth) = simulate_pair(
        seed=args.seed, rate_hz=args.rate_hz, compress=1.0, profile=make_profile('heating'),
        test_profile=make_profile('cooling', rate_c_s=0.5))
    rate = test.rate_hz
    outputs = {'raw': np.asarray(test.gyro_rad_s, dtype=float)}
    for method in (TemperaturePolynomial(), LinearTdT(), BPNetwork()):
        method.fit(train, rng=np.random.default_rng(args.seed))
        outputs[method.name] = live_compensate(method, test, truth)
    second, minute = int(round(rate)), int(round(60 * rate))
    span = int(round(1200 * rate))
    # the node holds the first rate window of data until the temperature rate exists
    start = int(round(10.0 * rate))
    outputs = {k: v[start:] for k, v in outputs.items()}
    print(f'heating -> cooling step, seed {args.seed}, {rate:g} Hz, natural time '
          f'({test.t_s[-1] / 3600:.2f} h); die {truth.die_c.max():.1f} -> '
          f'{truth.die_c.min():.1f} degC\n')
    print('| output | axis | std of 1-s means (deg/s) | raw / this | step left: last 20 min - '
          'first 20 min (deg/s) | largest 60-s mean excursion (deg/s) |')
    print('|---|---|---|---|---|---|')
    raw_std = np.std(means(outputs['raw'], second), axis=0, ddof=1)
    for name, out in outputs.items():
        s1 = np.std(means(out, second), axis=0, ddof=1)
        step = out[-span:].mean(axis=0) - out[:span].mean(axis=0)
        m60 = means(out, minute)
        excursion = np.max(np.abs(m60 - m60.mean(axis=0)), axis=0)
        for a, axis in enumerate('xyz'):
            print(f'| {name} | {axis} | {s1[a] * RAD_TO_DEG:.4f} | {raw_std[a] / s1[a]:.1f} | '
                  f'{step[a] * RAD_TO_DEG:+.4f} | {excursion[a] * RAD_TO_DEG:.4f} |')
    if args.figure:
        plt = pyplot()
        fig, panels = plt.subplots(2, 1, figsize=(10, 7), sharex=True,
                                   gridspec_kw={'height_ratios': [1, 3]})
        t_min = means(test.t_s[start:], second) / 60.0
        panels[0].plot(test.t_s / 60.0, truth.die_c, color='tab:red', lw=1.0)
        panels[0].set_ylabel('die temperature (degC)')
        for name, out in outputs.items():
            panels[1].plot(t_min, means(out[:, 0], second) * RAD_TO_DEG, lw=0.6,
                           label=name, alpha=0.5 if name == 'raw' else 0.9)
        panels[1].set_ylabel('x, 1-s means (deg/s)')
        panels[1].set_xlabel('time (min)')
        panels[1].legend(fontsize=8)
        for p in panels:
            p.grid(True, alpha=0.3)
        fig.suptitle('Live compensation (LiveDriftEvaluator, 52-Hz temperature) of a cooling step '
                     'after a warm-up calibration', fontsize=10)
        Path(args.figure).parent.mkdir(parents=True, exist_ok=True)
        save_figure(fig, args.figure, dpi=100, tight=True)
        print(f'\nwrote {args.figure}')


if __name__ == '__main__':
    main()
