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
Two effects hidden at once: the table of docs/discrepancy.md section 6 ("Two effects at once").

Usage: python docs/scripts/discrepancy_pairs.py [--seeds 5] [--first-seed 300] [--jobs 1]
       [--write] [--pairs a+b,c+d]

Every unordered pair of the catalogue of ``explain.synthetic`` (36 pairs) on ``--seeds`` records
each (``synthetic.outcome``: 20,000 samples at 100 Hz, 150,000 when the pair holds
bias_instability, as the single-effect table; 8 members, no bootstrap). Per record: both hidden
effects named, a false effect named (one not hidden), and whether each hidden effect is
*needed*: the workflow restricted to the other one leaves the record unexplained. A pair record
is "at detectable sizes" when both are needed (neither explains it alone). With ``--write`` the
table replaces the block between the markers ``<!-- pairs-table -->`` and
``<!-- /pairs-table -->`` of docs/discrepancy.md.
"""

import argparse
import itertools
import multiprocessing
import os
import sys
import time

from gyro_noise_ros.explain.synthetic import EFFECTS, outcome

DOC = os.path.join(os.path.dirname(__file__), '..', 'discrepancy.md')
MARK = ('<!-- pairs-table -->', '<!-- /pairs-table -->')


def run(job):
    """Return the outcome of one (pair, seed)."""
    pair, seed = job
    n = 150_000 if 'bias_instability' in pair else 20_000
    t0 = time.time()
    got = outcome(pair, seed, n=n, ensemble=8, needed=True)
    got['seconds'] = time.time() - t0
    return got


def table(results, command):
    """Return the Markdown lines of the pair table and its totals."""
    rows = {}
    for got in results:
        rows.setdefault('+'.join(got['hidden']), []).append(got)
    lines = [f'Command: `{command}`', '',
             '| pair | records | at detectable sizes | both named (all) | both named (detectable)'
             ' | false effect named | named (per seed) |', '|---|---:|---:|---:|---:|---:|---|']
    total = {'n': 0, 'det': 0, 'both': 0, 'both_det': 0, 'extra': 0}
    for key, got in rows.items():
        det = [g for g in got if g['detectable']]
        count = {'n': len(got), 'det': len(det), 'both': sum(g['all_found'] for g in got),
                 'both_det': sum(g['all_found'] for g in det),
                 'extra': sum(g['extra'] for g in got)}
        for k in total:
            total[k] += count[k]
        named = '; '.join(','.join(g['named']) or '-' for g in got)
        lines.append(f"| {key} | {count['n']} | {count['det']} | {count['both']} | "
                     f"{count['both_det']} | {count['extra']} | {named} |")

    def pct(a, b):
        return f'{a} of {b} ({100.0 * a / b:.0f} %)' if b else '-'

    lines += ['', f"All records: both named in {pct(total['both'], total['n'])}, no false effect "
              f"in {pct(total['n'] - total['extra'], total['n'])}. At detectable sizes (each "
              f"effect needed): {pct(total['det'], total['n'])} of the records; both named in "
              f"{pct(total['both_det'], total['det'])}."]
    return lines


def write(lines):
    """Replace the marked block of docs/discrepancy.md with ``lines``."""
    with open(DOC) as fh:
        text = fh.read()
    start, end = text.index(MARK[0]) + len(MARK[0]), text.index(MARK[1])
    with open(DOC, 'w') as fh:
        fh.write(text[:start] + '\n' + '\n'.join(lines) + '\n' + text[end:])


def main(argv=None):
    """Run the pairs and print (or write) the table."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    p.add_argument('--seeds', type=int, default=5)
    p.add_argument('--first-seed', type=int, default=300)
    p.add_argument('--jobs', type=int, default=1)
    p.add_argument('--pairs', help="comma list of 'a+b' (default: every pair)")
    p.add_argument('--write', action='store_true', help='replace the table in the doc')
    args = p.parse_args(argv)
    pairs = ([tuple(c.split('+')) for c in args.pairs.split(',')] if args.pairs
             else list(itertools.combinations(EFFECTS, 2)))
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    jobs = [(pair, seed) for pair in pairs for seed in seeds]
    t0 = time.time()
    with multiprocessing.Pool(args.jobs) as pool:
        results = []
        for got in pool.imap(run, jobs):
            results.append(got)
            print(f"{'+'.join(got['hidden'])} {got['seed']}: named {got['named']}, needed "
                  f"{got['needed']} ({got['seconds']:.0f} s)", file=sys.stderr, flush=True)
    command = ('python docs/scripts/discrepancy_pairs.py --seeds '
               f'{args.seeds} --first-seed {args.first_seed}'
               + (f' --pairs {args.pairs}' if args.pairs else ''))
    lines = table(results, command) + [
        '', f'({len(jobs)} records, {time.time() - t0:.0f} s with {args.jobs} process(es).)']
    print('\n'.join(lines))
    if args.write:
        write(lines)
    return 0


if __name__ == '__main__':
    sys.exit(main())
