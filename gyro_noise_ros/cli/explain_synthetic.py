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
The hidden-effect sweep of the discrepancy workflow, from the command line (a measurement tool).

Usage::

    python -m gyro_noise_ros.cli.explain_synthetic [--effects LIST] [--seeds N] [--first-seed S]
        [--samples N] [--ensemble M] [--verbose] [--coverage [--bootstrap B]]

Prints, per case, how often :func:`gyro_noise_ros.explain.synthetic.sweep` names the hidden
effect first, finds all of it, ends inside the band, explains the record, or adds an extra
effect; with ``--coverage``, how often the 95 % intervals of the effect parameters hold the hidden
value (:func:`gyro_noise_ros.explain.synthetic.coverage`). The tables of docs/discrepancy.md are
made with it. Exit codes: see :mod:`gyro_noise_ros.cli._common`.
"""

import argparse
from collections.abc import Sequence
import sys

from ._common import run_cli
from ..explain.synthetic import coverage, EFFECTS, sweep

PROG = 'python -m gyro_noise_ros.cli.explain_synthetic'


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser."""
    p = argparse.ArgumentParser(prog=PROG,
                                description='hidden-effect sweep of the discrepancy workflow')
    p.add_argument('--effects', default='all',
                   help="comma list of cases, '+' joins effects of one case, "
                   "'none' is effect-free; 'all' = every catalogue effect alone")
    p.add_argument('--seeds', type=int, default=20)
    p.add_argument('--first-seed', type=int, default=100)
    p.add_argument('--samples', type=int, default=60000)
    p.add_argument('--ensemble', type=int, default=16)
    p.add_argument('--verbose', action='store_true')
    p.add_argument('--coverage', action='store_true',
                   help='coverage of the 95 %% intervals of the effect parameters instead '
                   '(effects: sinusoid, bias_drift, bias_transient, temperature_sensitivity, '
                   'rate_random_walk, bias_instability, gauss_markov)')
    p.add_argument('--bootstrap', type=int, default=20, help='bootstrap records (--coverage)')
    return p


def _coverage_table(cases: list[tuple[str, ...]], seeds: range, args: argparse.Namespace) -> None:
    """Print the coverage of each case's parameter intervals."""
    print(f'{"parameter":<58} {"runs":>5} {"inside 95 %":>11} {"sd of z":>8}')
    for case in cases:
        table = coverage(case, seeds, n=args.samples, replicates=args.bootstrap)
        for key, row in table.items():
            if key != '_not_fitted':
                print(f'{"+".join(case) + ": " + key:<58} {row["runs"]:>5} '
                      f'{row["inside"]:>11} {row["z_sd"]:>8.2f}')
        if table['_not_fitted']:
            print(f'{"+".join(case)}: not detected on {table["_not_fitted"]} records')


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    cases: list[tuple[str, ...]] = [(e,) for e in EFFECTS] if args.effects == 'all' else \
        [tuple(c.split('+')) if c != 'none' else () for c in args.effects.split(',')]
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    if args.coverage:
        _coverage_table(cases, seeds, args)
        return 0
    say = (lambda text: print(text, file=sys.stderr, flush=True)) if args.verbose else None
    table = sweep(cases, seeds, n=args.samples, ensemble=args.ensemble, progress=say)
    print(f'{"case":<40} {"runs":>5} {"first ok":>9} {"all found":>9} {"inside":>7} '
          f'{"explained":>9} {"extra":>6}')
    for key, row in table.items():
        print(f'{key:<40} {row["runs"]:>5} {row["first_correct"]:>9} {row["all_found"]:>9} '
              f'{row["inside"]:>7} {row["explained"]:>9} {row["extra"]:>6}')
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the sweep on ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
