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
The parallel model's drift stage in-sample, and where the simulated drift sits among the modes.

Usage::

    python docs/scripts/thermal_drift_model_check.py [--seed 7] [--hours 0.5] [--rate-hz 20]
        [--k 4] [--alpha 10000]

On one simulated oven run (the replicate example of docs/thermal.md: ``simulate --seed 7
--hours 0.5 --rate-hz 20``, its training run) and a VMD with the (K, alpha) the default MOPSO
picked there (4 or 5 modes, alpha 10000):

1. **In-sample drift error** (std of the 60-s means of drift part minus prediction, deg/s, the
   training run's own residual drift) of BAS alone (the paper's search, ``refine_iterations=0``),
   BAS plus the L-BFGS refinement (network alone on [T, dT]), and the package's drift model
   (stated basis + network), beside ``poly3`` fitted on the same run (its in-sample residual
   drift).
2. **Drift share of each mode**: with its centre frequencies fixed, one exact VMD sweep is a
   linear filter bank, so the simulated drift and the simulated noise can be passed through the
   same filters separately; the share is var(drift part) / (var(drift part) + var(noise part))
   per mode. A mode above the lowest with a share well away from 0 and 1 is a mixed band.
"""

import argparse

from gyro_noise_ros.thermal.baselines import TemperaturePolynomial
from gyro_noise_ros.thermal.elman import fit_drift, fit_elman
from gyro_noise_ros.thermal.metrics import noise_metrics
from gyro_noise_ros.thermal.parallel import block_means
from gyro_noise_ros.thermal.run import temperature_rate_c_s
from gyro_noise_ros.thermal.simulate import simulate_pair
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np


def main():
    """Fit the drift stages on one run and print both tables."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--hours', type=float, default=0.5)
    parser.add_argument('--rate-hz', type=float, default=20.0)
    parser.add_argument('--k', type=int, default=4)
    parser.add_argument('--alpha', type=float, default=10000.0)
    args = parser.parse_args()
    (_, run, truth), _ = simulate_pair(seed=args.seed, rate_hz=args.rate_hz, hours=args.hours)
    rate = run.rate_hz
    temp = run.temperature_c
    dtemp = temperature_rate_c_s(run.t_s, temp)
    q = -(-temp.size // 2000)
    grid = block_means(np.c_[temp, dtemp], q)
    centres = np.arange(grid.shape[0]) * q + 0.5 * (q - 1)

    def left(drift, pred):
        full = np.interp(np.arange(temp.size), centres, pred)
        return noise_metrics(drift - full, rate).residual_drift_deg_s

    poly = TemperaturePolynomial()
    poly.fit(run, rng=np.random.default_rng(0))
    out_poly = poly.apply(run)
    print(f'Training run of `simulate --seed {args.seed} --hours {args.hours:g} --rate-hz '
          f'{args.rate_hz:g}`, VMD K = {args.k}, alpha = {args.alpha:g}; grid of {q} samples\n')
    print('| axis | BAS alone | BAS + refinement (network alone) | basis + network (default) '
          '| poly3 | raw |')
    print('|---|---|---|---|---|---|')
    shares = []
    for a, axis in enumerate('xyz'):
        dec = vmd(run.gyro_rad_s[:, a], k=args.k, alpha=args.alpha, solver='exact',
                  max_iter=30)
        drift = dec.modes[0]
        target = block_means(drift, q)
        cells = []
        for kw in ({'refine_iterations': 0}, {}):
            net = fit_elman(grid, target, dt_s=q / rate, rng=np.random.default_rng(a),
                            symmetric=(1,), **kw)
            cells.append(left(drift, net.predict(grid)))
        model = fit_drift(grid, target, dt_s=q / rate, rng=np.random.default_rng(a),
                          weight_decay=1e-3)
        cells.append(left(drift, model.predict(grid)))
        cells.append(noise_metrics(out_poly[:, a], rate).residual_drift_deg_s)
        cells.append(noise_metrics(run.gyro_rad_s[:, a], rate).residual_drift_deg_s)
        print(f'| {axis} | ' + ' | '.join(f'{c:.4f}' for c in cells) + ' |')
        fixed = dec.center_freqs
        d_modes = vmd(truth.drift_rad_s[:, a], k=args.k, alpha=args.alpha, solver='exact',
                      max_iter=1, center_freqs=fixed).modes
        n_modes = vmd(truth.noise_rad_s[:, a], k=args.k, alpha=args.alpha, solver='exact',
                      max_iter=1, center_freqs=fixed).modes
        vd, vn = d_modes.var(axis=1), n_modes.var(axis=1)
        shares.append((fixed * rate, vd / (vd + vn)))
    print('\nResidual drift (deg/s, std of 60-s means) of the drift part minus the prediction '
          '(in-sample), and of the output of poly3 and the raw output.\n')
    print('| axis | mode centre (Hz): drift share |')
    print('|---|---|')
    for axis, (freqs, share) in zip('xyz', shares):
        print(f'| {axis} | ' + ', '.join(f'{f:.3g}: {s:.3g}' for f, s in zip(freqs, share))
              + ' |')


if __name__ == '__main__':
    main()
