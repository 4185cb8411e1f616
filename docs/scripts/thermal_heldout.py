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
The held-out tables of docs/thermal.md: methods trained on one shape, tested on others.

Usage: ``python docs/scripts/thermal_heldout.py [--seeds 1,2,3,4,5] [--slow-seeds 3]
[--rate-hz 20] [--hours 1] [--fast] [--json out.json] [--reuse out.json]
[--write docs/thermal.md]``. Pairs: ``thermal.heldout.HELDOUT_PAIRS`` (trained on heating,
tested on the replicate, cooling, cycle, staircase, sine and cool_reheat),
``BOTH_SIGNS_PAIRS`` (trained on a heat-and-cool cycle) and ``T_ONLY_PAIRS`` on a device whose
drift is a cubic in T alone (the cost of each firmware's rule). For every pair and seed it
simulates the pair, fits each method on the training run, applies it to the test run and divides
each axis's residual drift (std of 60-s means) by the noise floor (the same for the test run's
own noise) and by poly3's; the slow methods (emd_wtd_sabp, parallel) run on the first
``--slow-seeds`` seeds, ``--fast`` leaves them out. With ``--write`` the tables replace the block
between ``<!-- heldout:begin -->`` and ``<!-- heldout:end -->`` of that file; ``--reuse``
formats the scores of an earlier ``--json`` instead of simulating.
"""

import argparse
import json
import os
from pathlib import Path
import sys
import time

from gyro_noise_ros.thermal.heldout import (BOTH_SIGNS_PAIRS, HELDOUT_METHODS, HELDOUT_PAIRS,
                                            HeldoutMethod, run_table, summarise, T_ONLY_DEVICE,
                                            T_ONLY_PAIRS)

BEGIN, END = '<!-- heldout:begin -->', '<!-- heldout:end -->'
T_ONLY_METHODS = (HeldoutMethod('lsq_cv (default)', 'lsq_cv'), HeldoutMethod('poly3', 'poly3'))
HEADER = ('| train -> test | method | x noise floor (x, y, z) | worst seed-axis | x poly3 '
          '(x, y, z) | residual drift (deg/s) | seeds |')


def _three(values, spec='.2f'):
    return ', '.join('n/a' if v is None else f'{v:{spec}}' for v in values)


def _table(rows, pairs):
    lines = [HEADER, '|---|---|---|---|---|---|---|']
    for train, test in pairs:
        first = True
        for r in (r for r in rows if (r['train'], r['test']) == (train, test)):
            label = f'{train} -> {test}' if first else ''
            first = False
            p3 = '' if r['over_poly3'] is None else _three(r['over_poly3'])
            mean = sum(r['residual_deg_s']) / 3.0
            lines.append(f'| {label} | {r["method"]} | {_three(r["over_floor"])} | '
                         f'{r["worst_over_floor"]:.2f} | {p3} | {mean:.4f} | {r["seeds"]} |')
    return '\n'.join(lines)


def _notes(rows, scores, pairs):
    out = []
    for train, test in pairs:
        floor = [s['floor_deg_s'] for s in scores if (s['train'], s['test']) == (train, test)]
        mean = [sum(f[a] for f in floor) / len(floor) for a in range(3)]
        outside = [s['rate_outside'] for s in scores if (s['train'], s['test']) == (train, test)
                   and s['rate_outside'] is not None]
        share = f'{100 * sum(outside) / len(outside):.0f} %' if outside else 'n/a'
        terms = next((r['terms'] for r in rows if (r['train'], r['test']) == (train, test)
                      and r['terms']), [])
        picks = sorted({' '.join(t) for t in terms})
        out.append(f'- {train} -> {test}: noise floor {_three(mean, ".5f")} deg/s; test dT '
                   f'outside the trained range {share}; lsq_cv chose '
                   f'{"; ".join(f"`{p}`" for p in picks)}.')
    return '\n'.join(out)


def _block(scores, args, took):
    rows = summarise(scores)
    when = '' if took is None else (f' ({took / 60:.0f} min, load average {args.load:.1f} at '
                                    'the start)')
    parts = [BEGIN, '']
    for title, pairs, device in (('Trained on heating', HELDOUT_PAIRS, {}),
                                 ('Trained on a heat-and-cool cycle', BOTH_SIGNS_PAIRS, {}),
                                 ('A device whose drift is a cubic in T alone (what poly3 can '
                                  "represent): the cost of each firmware's rule",
                                  T_ONLY_PAIRS, T_ONLY_DEVICE)):
        mine = [r for r in rows if r['device'] == device]
        theirs = [s for s in scores if (s.get('device') or {}) == device]
        parts += [f'**{title}** (mean over seeds; x noise floor per axis, its worst seed and '
                  'axis, x poly3 per axis):', '', _table(mine, pairs), '',
                  _notes(mine, theirs, pairs), '']
    parts += [f'(`python docs/scripts/thermal_heldout.py --seeds {args.seeds} --slow-seeds '
              f'{args.slow_seeds} --rate-hz {args.rate_hz:g} --hours {args.hours:g}'
              f'{" --fast" if args.fast else ""}`{when}.)', END]
    return '\n'.join(parts)


def main():
    """Score the pairs and print (or write) the tables."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--seeds', default='1,2,3,4,5')
    p.add_argument('--slow-seeds', type=int, default=3)
    p.add_argument('--rate-hz', type=float, default=20.0)
    p.add_argument('--hours', type=float, default=1.0)
    p.add_argument('--fast', action='store_true', help='leave out emd_wtd_sabp and parallel')
    p.add_argument('--json', help='also write the per-seed scores here')
    p.add_argument('--reuse', help='format the scores of an earlier --json')
    p.add_argument('--write', help='Markdown file to update in place')
    args = p.parse_args()
    args.load = os.getloadavg()[0]
    took = None
    if args.reuse:
        saved = json.loads(Path(args.reuse).read_text())
        scores = saved['scores'] if isinstance(saved, dict) else saved
        if isinstance(saved, dict):
            took, args.load = saved['took_s'], saved['load_average']
    else:
        methods = [m for m in HELDOUT_METHODS if not (args.fast and m.slow)]
        start = time.perf_counter()
        seeds = [int(s) for s in args.seeds.split(',')]
        say = (lambda text: print(text, file=sys.stderr, flush=True))
        scores = run_table(HELDOUT_PAIRS + BOTH_SIGNS_PAIRS, seeds, methods=methods,
                           slow_seeds=args.slow_seeds, rate_hz=args.rate_hz, hours=args.hours,
                           progress=say)
        scores += run_table(T_ONLY_PAIRS, seeds, methods=T_ONLY_METHODS, rate_hz=args.rate_hz,
                            hours=args.hours, device=T_ONLY_DEVICE, progress=say)
        took = time.perf_counter() - start
    if args.json:
        Path(args.json).write_text(json.dumps({'scores': scores, 'took_s': took,
                                               'load_average': args.load}, indent=1))
    block = _block(scores, args, took)
    print(block)
    if args.write:
        sys.path.insert(0, str(Path(__file__).parent))
        from doc_block import write_block

        return write_block(args.write, BEGIN, END, block, 'thermal_heldout')
    return 0


if __name__ == '__main__':
    sys.exit(main())
