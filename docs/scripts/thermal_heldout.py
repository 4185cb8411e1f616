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
The held-out comparison of docs/thermal.md: methods trained on one shape, tested on another.

Usage: ``python docs/scripts/thermal_heldout.py [--seeds 1,2,3,4,5] [--rate-hz 20]
[--hours 1] [--methods poly3,linear_tdt,...] [--json out.json]``. For each train -> test pair
(``app.thermal.HELDOUT_PAIRS``: a heating replicate, heating -> cooling, heating -> cycle,
staircase -> cool_reheat, cycle -> sine) and seed it simulates the pair, fits every method on
the training run, applies it to the test run and prints the mean residual drift (std of 60-s
means, deg/s, mean over axes and seeds) beside the least-squares oracle on the true drift terms
(and on the measured T and dT): the ratio column is what a method leaves per unit of what the
data allow. Rows: ``gyro_noise_ros.app.thermal.heldout_scores``.
"""

import argparse
import json
import sys

from gyro_noise_ros.app.thermal import HELDOUT_METHODS, HELDOUT_PAIRS, heldout_scores


def _table(rows):
    lines = ['| train -> test | method | residual drift (deg/s) | x oracle | x oracle per seed '
             '| test dT outside training |', '|---|---|---|---|---|---|']
    for r in rows:
        seeds = ', '.join(f'{v:.2f}' for v in r['seed_ratios'])
        frac = r['rate_outside_fraction']
        out = '' if frac is None else f'{100 * frac:.0f} %'
        lines.append(f'| {r["train"]} -> {r["test"]} | {r["method"]} | {r["mean_deg_s"]:.4f} | '
                     f'{r["ratio_to_oracle"]:.2f} | {seeds} | {out} |')
    return '\n'.join(lines)


def main():
    """Run the comparison and print the table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--seeds', default='1,2,3,4,5')
    p.add_argument('--rate-hz', type=float, default=20.0)
    p.add_argument('--hours', type=float, default=1.0)
    p.add_argument('--methods', help='labels of HELDOUT_METHODS to run (default: all)')
    p.add_argument('--pairs', help='train>test,... (default: HELDOUT_PAIRS)')
    p.add_argument('--json', help='also write the rows here')
    args = p.parse_args()
    methods = HELDOUT_METHODS
    if args.methods:
        wanted = args.methods.split(',')
        methods = [m for m in HELDOUT_METHODS if m[0] in wanted]
        methods += [(w, w, {}) for w in wanted if w not in {m[0] for m in methods}]
    pairs = HELDOUT_PAIRS if not args.pairs else [tuple(x.split('>'))
                                                  for x in args.pairs.split(',')]
    rows = heldout_scores(pairs=pairs, methods=methods,
                          seeds=[int(s) for s in args.seeds.split(',')], rate_hz=args.rate_hz,
                          hours=args.hours,
                          progress=lambda text: print(text, file=sys.stderr, flush=True))
    print(_table(rows))
    if args.json:
        with open(args.json, 'w') as fh:
            json.dump(rows, fh, indent=1)


if __name__ == '__main__':
    main()
