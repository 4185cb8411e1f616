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
Coverage of the Allan deviation's confidence intervals on seeded power-law rate noise.

For white, flicker and random-walk rate noise (``core.simulate.power_law_rate``, whose expected
Allan variance ``power_law_rate_avar`` is exact) the script draws ``--records`` records of
``--samples`` samples at ``--rate-hz`` and counts, at every tau, how often the interval of
``core.allan.allan_deviation`` (default 68.3 %) holds the true deviation: on the octave taus
(the table), on the dense taus (smallest and largest coverage over them), the largest EDF at the
three longest octave taus against the number of non-overlapping averages there, and how often the
random-walk bound of the readout (``core.readout.random_walk_bound``, the K bound of imu.yaml)
holds the true K.

Usage (seeded: the same numbers every time)::

    nice python docs/scripts/allan_coverage.py [--records 1000] [--samples 33620] [--rate-hz 43]
        [--seed 1] [--write]

``--write`` puts the tables into docs/allan.md between its markers, with the command.
"""

import argparse
import math
import os
import sys
import time

from _doc_tables import print_and_write
from gyro_noise_ros.core.allan import allan_deviation, DEFAULT_CONFIDENCE, edf_greenhall
from gyro_noise_ros.core.readout import random_walk_bound
from gyro_noise_ros.core.simulate import power_law_rate, power_law_rate_avar
import numpy as np

KINDS = ((0, 'white (angle random walk)'), (-1, 'flicker (bias instability)'),
         (-2, 'random walk (rate random walk)'))


def measure(alpha, records, n, rate_hz, seed):
    """Return coverage per octave tau, (min, max) over dense taus, EDFs, K-bound hits."""
    rng = np.random.default_rng([seed, -alpha])
    hits = dense_hits = 0
    edf_max = None
    k_hits = 0
    truth = dense_truth = None
    for _ in range(records):
        y = power_law_rate(n, alpha, rng=rng)
        res = allan_deviation(y, rate_hz)
        dense = allan_deviation(y, rate_hz, taus='dense')
        if truth is None:
            truth = np.sqrt(power_law_rate_avar(res.m, alpha, n))
            dense_truth = np.sqrt(power_law_rate_avar(dense.m, alpha, n))
        hits = hits + ((res.ci_low <= truth) & (truth <= res.ci_high))
        dense_hits = dense_hits + ((dense.ci_low <= dense_truth) & (dense_truth <= dense.ci_high))
        edf_max = res.edf if edf_max is None else np.maximum(edf_max, res.edf)
        # the unit-rate records have K^2 = rate_hz (AVAR = m / 3 = K^2 tau / 3), else K = 0
        k_true = math.sqrt(rate_hz) if alpha == -2 else 0.0
        k_hits += int(random_walk_bound(dense) >= k_true)
    return res, hits / records, dense_hits / records, edf_max, k_hits / records


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    p.add_argument('--records', type=int, default=1000)
    p.add_argument('--samples', type=int, default=33620)
    p.add_argument('--rate-hz', type=float, default=43.0)
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--write', action='store_true', help='update docs/allan.md')
    args = p.parse_args(argv)
    if args.write:
        print_and_write(lambda: _run(args), 'allan_coverage.py', 'allan.md',
                        argv if argv is not None else sys.argv[1:])
        return 0
    _run(args)
    return 0


def _run(args):
    t0 = time.time()
    rows = []
    for alpha, name in KINDS:
        rows.append((name,) + measure(alpha, args.records, args.samples, args.rate_hz,
                                      args.seed))
    res = rows[0][1]
    sd = math.sqrt(DEFAULT_CONFIDENCE * (1 - DEFAULT_CONFIDENCE) / args.records)
    print(f'\n{args.records} records of {args.samples} samples at {args.rate_hz:g} Hz per noise, '
          f'seed {args.seed}; nominal {100 * DEFAULT_CONFIDENCE:.1f} %, binomial sd of a '
          f'coverage {100 * sd:.1f} %.\n')
    print('| noise | ' + ' | '.join(f'{t:.3g} s' for t in res.tau_s) + ' |')
    print('|---|' + '---|' * res.tau_s.size)
    print('| averages | ' + ' | '.join(str(args.samples // int(m)) for m in res.m) + ' |')
    for name, _, cov, dense, _, _ in rows:
        print(f'| {name} | ' + ' | '.join(f'{100 * c:.1f}' for c in cov) + ' |')
    print('\n| noise | octave taus: lowest - highest coverage | dense taus (~10 per decade) | '
          'largest EDF at the three longest octave taus | white-FM EDF there | K bound '
          '>= true K |')
    print('|---|---|---|---|---|---|')
    for name, r, cov, dense, edf_max, k_hits in rows:
        print(f'| {name} | {100 * cov.min():.1f} - {100 * cov.max():.1f} % | '
              f'{100 * dense.min():.1f} - {100 * dense.max():.1f} % | '
              + ', '.join(f'{e:.1f}' for e in edf_max[-3:]) + ' | '
              + ', '.join(f'{e:.1f}' for e in _white_edf(r)) + f' | {100 * k_hits:.1f} % |')
    load = ', '.join(f'{v:.2f}' for v in os.getloadavg())
    print(f'\n{time.time() - t0:.0f} s wall, load average {load}.')


def _white_edf(res):
    return [edf_greenhall(0, int(m), res.n_samples + 1) for m in res.m[-3:]]


if __name__ == '__main__':
    sys.exit(main())
