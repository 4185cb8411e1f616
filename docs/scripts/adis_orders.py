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
Fractional-order identification of the six ADIS16405 static runs (paper 000 Tables 5-6 analogue).

Usage: python docs/scripts/adis_orders.py [--data DIR] [--jobs N] [--out FILE]
Reads ../shared/data/real/adis16405_static/adis_16405_imuN.npz (100 Hz, deg/s, 1e6 samples per
run), cuts every axis into 10,000-sample chunks (100 chunks per run and axis), identifies each
chunk with the default options (grid 0:2:0.01, L = 1000, demeaned, all lags) and prints a Markdown
table of the per-run, per-axis mean and variance (ddof = 1) of the order for both methods.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
import os
import sys
import time

from gyro_noise_ros.core.chunks import Chunker, summarise_sequence
from gyro_noise_ros.core.fractional import OrderIdentifier
import numpy as np

DEFAULT_DATA = os.path.join(os.path.dirname(__file__), '..', '..', '..', 'shared', 'data', 'real',
                            'adis16405_static')
_IDENT = None


def _work(chunk):
    global _IDENT
    if _IDENT is None:
        _IDENT = OrderIdentifier(10000)
    # deg/s -> rad/s: the order and f are unit-free, the variance is reported in (deg/s)^2 below
    res = _IDENT(np.deg2rad(chunk))
    return res.alpha_var, res.alpha_corr, len(
        res.tied_alphas_var) > 1, len(res.tied_alphas_corr) > 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--data', default=DEFAULT_DATA)
    parser.add_argument('--jobs', type=int, default=os.cpu_count())
    parser.add_argument('--runs', default='1,2,3,4,5,6')
    args = parser.parse_args()
    t0 = time.time()
    rows = []
    per_axis = {a: ([], []) for a in 'XYZ'}
    with ProcessPoolExecutor(args.jobs) as pool:
        for run in [int(r) for r in args.runs.split(',')]:
            data = np.load(os.path.join(args.data, f'adis_16405_imu{run}.npz'))['gyro_dps']
            for i, axis in enumerate('XYZ'):
                chunks = Chunker(10000).push(data[:, i])
                out = list(pool.map(_work, chunks, chunksize=4))
                av = np.array([o[0] for o in out])
                ac = np.array([o[1] for o in out])
                var = [np.var(c, ddof=1) for c in chunks]
                s = summarise_sequence(np.arange(len(chunks)) * 100.0 + 50.0,
                                       [c.mean() for c in chunks], var, av, ac,
                                       ties_var=sum(o[2] for o in out),
                                       ties_corr=sum(o[3] for o in out))
                per_axis[axis][0].extend(av)
                per_axis[axis][1].extend(ac)
                rows.append((run, axis, s))
    print('| run | axis | chunks | mean variance ((deg/s)^2) | alpha, variance method: mean | '
          'variance | ' 'alpha, correlation method: mean | variance | exact ties (var/corr) |')
    print('|---|---|---|---|---|---|---|---|---|')
    for run, axis, s in rows:
        print(f'| imu{run} | {axis} | {s.chunks} | {s.mean_variance:.5f} | '
              f'{s.alpha_var_mean:.4f} | '
              f'{s.alpha_var_variance:.6f} | {s.alpha_corr_mean:.4f} | '
              f'{s.alpha_corr_variance:.6f} | ' f'{s.ties_var}/{s.ties_corr} |')
    print()
    print('| axis, all runs | chunks | alpha var. method mean | variance | alpha corr. method '
          'mean | variance |')
    print('|---|---|---|---|---|---|')
    for axis, (av, ac) in per_axis.items():
        print(f'| {axis} | {len(av)} | {np.mean(av):.4f} | {np.var(av, ddof=1):.6f} | '
              f'{np.mean(ac):.4f} | ' f'{np.var(ac, ddof=1):.6f} |')
    print(f'\n({time.time() - t0:.0f} s with {args.jobs} processes)', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
