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
Fit every thermal baseline on a simulated train run, apply it to the test run, print a table.

Usage: ``python docs/scripts/thermal_baselines_check.py [--seed S] [--hours H] [--rate-hz R]
[--skip emd_wtd_sabp]``. Residual drift is the standard deviation of the 60-s means of the
processed test run (deg/s, per axis); "left vs truth" removes the simulated noise first, so it
is the drift the method left (or added). Times are wall-clock on whatever machine runs it.
"""

import argparse
import time

from gyro_noise_ros.thermal.baselines import BASELINES
from gyro_noise_ros.thermal.simulate import simulate_run
import numpy as np


def _minute_means_std_dps(y, rate_hz):
    n = int(round(60 * rate_hz))
    blocks = y.shape[0] // n
    return np.degrees(np.std(y[:blocks * n].reshape(blocks, n, 3).mean(1), 0))


def main():
    """Run the comparison and print one line per method."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--hours', type=float, default=4.0)
    p.add_argument('--rate-hz', type=float, default=100.0)
    p.add_argument('--skip', nargs='*', default=[])
    args = p.parse_args()
    seeds = np.random.SeedSequence(args.seed).spawn(2)
    train, _ = simulate_run(rng=np.random.default_rng(seeds[0]), hours=args.hours,
                            rate_hz=args.rate_hz)
    test, truth = simulate_run(rng=np.random.default_rng(seeds[1]), hours=args.hours,
                               rate_hz=args.rate_hz)
    print(f'seed {args.seed}, {args.hours} h at {args.rate_hz} Hz, {test.t_s.size} samples, '
          f'compress {truth.compress:.3f}')
    print('method         fit_s   apply_s  residual drift x,y,z (deg/s)     left vs truth x,y,z')
    for name, cls in BASELINES.items():
        if name in args.skip:
            continue
        method = cls()
        t0 = time.perf_counter()
        method.fit(train, rng=np.random.default_rng(0))
        t1 = time.perf_counter()
        out = method.apply(test)
        t2 = time.perf_counter()
        resid = _minute_means_std_dps(out, args.rate_hz)
        left = _minute_means_std_dps(out - truth.noise_rad_s, args.rate_hz)
        print(f'{name:13s} {t1 - t0:6.1f} {t2 - t1:8.1f}   '
              + ' '.join(f'{v:.5f}' for v in resid) + '   '
              + ' '.join(f'{v:.5f}' for v in left), flush=True)


if __name__ == '__main__':
    main()
