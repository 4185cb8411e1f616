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
False-alarm and detection rates of the reference verdict on the six real ADIS16405 runs.

Usage: python docs/scripts/verdict_rates.py [--data DIR] [--jobs N] [--cache FILE]

``--data`` defaults to ``$GYRO_NOISE_REAL_DATA/adis16405_static``, else ``../shared/data/real``
beside the repository.

Every run (1,000,000 samples at 100 Hz, deg/s) is cut into 100 chunks of 10,000 samples per axis;
each chunk gets its bias, variance and fractional orders (default identification: grid 0:2:0.01,
L = 1000, demeaned, all lags). Each ordered pair (checked run, reference run) of the six runs and
each axis (90 comparisons) is judged by ``core.health.evaluate_health`` with the reference built
from the reference run's sequence statistics exactly as ``load_reference`` builds it from a
summary.json, and the default thresholds. The same pairs are judged again with a change injected
into the checked run:

* variance +25 %: the deviations of the run from its mean scaled by sqrt(1.25);
* bias step: a constant added to the whole run (0.2 deg/s; 0.05-0.3 deg/s in the size table,
  which reuses the unchanged run's orders: the identification removes each chunk's mean, so a
  constant cannot change them);
* order shift: the deviations from the run mean filtered by the truncated GL difference
  (``core.fractional.gl_difference``, order +0.1) or sum (order -0.1), L = 1000, mean added back;
  nothing else is adjusted, so what the filter does to the variance is part of the change.

Prints Markdown tables: the levels per kind and which items flagged; a sweep of the multiplier
``reference_warn_sigma`` (``reference_error_sigma`` at twice it); the rule that chose the default
(the smallest multiplier without a false alarm, plus 0.5) and its leave-one-run-out check; the
largest unchanged differences in spreads and in standard errors; the robust locations of the
runs; the order shift each change causes per axis; detection against the bias-step size; rates
for shorter records (the first 10-50 chunks of each run). ``--cache`` keeps the per-chunk values
(9,000 identifications: 33 minutes here on two shared cores) for reruns.
"""

import argparse
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
import itertools
import math
import os
import sys
import time

from gyro_noise_ros.core.chunks import summarise_sequence
from gyro_noise_ros.core.engine import AxisSummary, StreamCounts
from gyro_noise_ros.core.fractional import gl_difference, OrderIdentifier
from gyro_noise_ros.core.health import evaluate_health, HealthThresholds, ReferenceStats
import numpy as np

# $GYRO_NOISE_REAL_DATA (as for the tests), else ../shared/data/real beside the repository
DEFAULT_DATA = os.path.join(
    os.environ.get('GYRO_NOISE_REAL_DATA') or os.path.join(
        os.path.dirname(__file__), '..', '..', '..', 'shared', 'data', 'real'), 'adis16405_static')
RUNS = range(1, 7)
AXES = 'xyz'
CHUNK = 10_000
RATE_HZ = 100.0
ORDER_STEP = 0.01
#: The bias step of the headline table (deg/s) and the sizes of the size table.
BIAS_STEP_DEG_S = 0.2
BIAS_SIZES_DEG_S = (0.05, 0.1, 0.15, 0.2, 0.3)
#: Datasheet in-run bias stability of the ADIS16405 (deg/s, 1 sigma).
DATASHEET_BIAS_STABILITY_DEG_S = 0.007
KINDS = ('none', 'variance +25 %', f'bias step {BIAS_STEP_DEG_S:g} deg/s',
         'order: GL difference 0.1', 'order: GL sum 0.1')
MULTIPLIERS = (3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0)
#: Added to the smallest multiplier without false alarms (one step of the 0.5 grid): the largest
#: differences between unchanged runs sit just under it, so a seventh run may cross it.
MARGIN = 0.5
_IDENT = None


def _identify(chunk):
    global _IDENT
    if _IDENT is None:
        _IDENT = OrderIdentifier(CHUNK)
    res = _IDENT(chunk)
    return res.alpha_var, res.alpha_corr


def _inject(x, kind):
    """Return the run x (rad/s) with the change of ``kind`` (module doc)."""
    m = float(x.mean())
    if kind == 'none':
        return x
    if kind.startswith('variance'):
        return m + math.sqrt(1.25) * (x - m)
    if kind.startswith('bias'):
        return x + math.radians(BIAS_STEP_DEG_S)
    order = 0.1 if 'difference' in kind else -0.1
    return m + gl_difference(x - m, order)


def chunk_values(data_dir, jobs, cache):
    """
    Return ``{(kind, run, axis): array (100, 4)}`` of chunk bias, variance, both orders (rad/s).

    Parameters
    ----------
    data_dir : str
        Folder of adis_16405_imuN.npz.
    jobs : int
        Identification processes.
    cache : str or None
        npz file read if present, else written.

    Returns
    -------
    dict

    """
    if cache and os.path.exists(cache):
        stored = np.load(cache)
        return {tuple(k.split('|')[:1]) + (int(k.split('|')[1]), k.split('|')[2]): stored[k]
                for k in stored.files}
    out = {}
    t0 = time.time()
    with ProcessPoolExecutor(jobs) as pool:
        for run in RUNS:
            gyro = np.deg2rad(np.load(os.path.join(data_dir, f'adis_16405_imu{run}.npz'))
                              ['gyro_dps'])
            for kind in KINDS:
                for i, axis in enumerate(AXES):
                    x = _inject(gyro[:, i], kind)
                    chunks = x[:x.size // CHUNK * CHUNK].reshape(-1, CHUNK)
                    orders = np.array(list(pool.map(_identify, list(chunks), chunksize=4)))
                    out[(kind, run, axis)] = np.column_stack(
                        [chunks.mean(axis=1), chunks.var(axis=1, ddof=1), orders])
            print(f'run {run} identified ({time.time() - t0:.0f} s)', file=sys.stderr)
    if cache:
        np.savez(cache, **{f'{k}|{r}|{a}': v for (k, r, a), v in out.items()})
    return out


def _sequence(values):
    t = (np.arange(values.shape[0]) * CHUNK + (CHUNK - 1) / 2.0) / RATE_HZ
    return summarise_sequence(t, values[:, 0], values[:, 1], values[:, 2], values[:, 3],
                              order_step=ORDER_STEP)


def _judge(checked, reference, thresholds):
    """Return the verdict of one checked sequence against one reference sequence."""
    n = checked.chunks * CHUNK
    stream = StreamCounts(samples=n, samples_lost=0, gaps=0, out_of_order=0,
                          chunks=checked.chunks, tail_samples=0, discarded_samples=0,
                          discarded_partials=0, rate_hz=RATE_HZ, duration_s=n / RATE_HZ)
    summary = AxisSummary('x', checked, stream, 0, checked.chunks, 0, 0, 0, 0, float('nan'))
    return evaluate_health(summary, reference=ReferenceStats.from_sequence(reference),
                           thresholds=thresholds)


def _pairs(runs=RUNS):
    return [(a, r, axis) for a, r in itertools.permutations(runs, 2) for axis in AXES]


def _verdicts(values, kind, thresholds, pairs, *, chunks=None, bias_deg_s=None):
    """Verdicts of ``pairs`` with the change ``kind`` in the checked run."""
    out = []
    for a, r, axis in pairs:
        if bias_deg_s is not None:
            v = values[('none', a, axis)].copy()
            v[:, 0] += math.radians(bias_deg_s)
        else:
            v = values[(kind, a, axis)]
        ref = values[('none', r, axis)]
        if chunks is not None:
            v, ref = v[:chunks], ref[:chunks]
        out.append(_judge(_sequence(v), _sequence(ref), thresholds))
    return out


def _flagged(verdicts):
    return sum(v.level in ('WARN', 'ERROR') for v in verdicts)


def _items(verdicts):
    c = Counter()
    for v in verdicts:
        for key, _, level in v.items:
            if level in ('WARN', 'ERROR'):
                c[key] += 1
    return ', '.join(f'{k}: {n}' for k, n in sorted(c.items())) or '-'


def _thresholds(k):
    return replace(HealthThresholds(), reference_warn_sigma=k, reference_error_sigma=2 * k)


def fit_multiplier(values, pairs):
    """
    Return the multiplier rule's choice on ``pairs``.

    The rule: the smallest multiple of 0.5 from 3 to 8 with no false alarm (no WARN, no ERROR,
    ERROR at twice the multiplier) on the unchanged ``pairs``, plus :data:`MARGIN`.

    Parameters
    ----------
    values : dict
        From :func:`chunk_values`.
    pairs : list
        (checked run, reference run, axis) comparisons to fit on.

    Returns
    -------
    float or None
        None when no multiplier up to 8 keeps them.

    """
    for k in np.arange(3.0, 8.01, 0.5):
        levels = Counter(v.level for v in _verdicts(values, 'none', _thresholds(k), pairs))
        if levels['ERROR'] == 0 and levels['WARN'] == 0:
            return float(k) + MARGIN
    return None


def main():
    """Print the tables of docs/verdicts.md."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--data', default=DEFAULT_DATA)
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1)
    parser.add_argument('--cache', default=None, help='npz of the per-chunk values')
    args = parser.parse_args()
    values = chunk_values(args.data, args.jobs, args.cache)
    default = HealthThresholds()
    pairs = _pairs()
    k0 = default.reference_warn_sigma
    print(f'Default thresholds: WARN above {k0:g}, ERROR above '
          f'{default.reference_error_sigma:g} sigma (pooled chunk spreads; for the drift pooled '
          f'standard errors); {len(pairs)} comparisons per kind.\n')
    print('| change in the checked run | OK | WARN | ERROR | flagged | items that flagged |')
    print('|---|---:|---:|---:|---:|---|')
    for kind in KINDS:
        verdicts = _verdicts(values, kind, default, pairs)
        levels = Counter(v.level for v in verdicts)
        print(f'| {kind} | {levels["OK"]} | {levels["WARN"]} | {levels["ERROR"]} | '
              f'{100.0 * _flagged(verdicts) / len(pairs):.0f} % | {_items(verdicts)} |')

    print('\nLargest difference between unchanged runs (90 comparisons), in pooled chunk spreads '
          '(the rule) and in pooled standard errors of the location (spread / sqrt(chunks)).\n')
    print('| quantity | in spreads | in standard errors |')
    print('|---|---:|---:|')
    for name, field_name in (('bias', 'bias_robust'), ('log variance', 'log_variance_robust'),
                             ('variance-method order', 'alpha_var_robust'),
                             ('correlation-method order', 'alpha_corr_robust')):
        d_spread = d_se = 0.0
        for a, r, axis in pairs:
            m = getattr(_sequence(values[('none', a, axis)]), field_name)
            q = getattr(_sequence(values[('none', r, axis)]), field_name)
            diff = abs(m.location - q.location)
            d_spread = max(d_spread, diff / math.hypot(m.spread, q.spread))
            se = math.hypot(m.spread / math.sqrt(m.count), q.spread / math.sqrt(q.count))
            d_se = max(d_se, diff / se)
        print(f'| {name} | {d_spread:.2f} | {d_se:.1f} |')

    print('\nMultiplier sweep (ERROR at twice the multiplier): false alarms and detection.\n')
    print('| multiplier | WARN, unchanged | ERROR, unchanged | '
          + ' | '.join(KINDS[1:]) + ' |')
    print('|---:|---:|---:|' + '---:|' * (len(KINDS) - 1))
    for k in MULTIPLIERS:
        th = _thresholds(k)
        base = Counter(v.level for v in _verdicts(values, 'none', th, pairs))
        det = [100.0 * _flagged(_verdicts(values, kind, th, pairs)) / len(pairs)
               for kind in KINDS[1:]]
        print(f'| {k:g} | {100.0 * base["WARN"] / len(pairs):.1f} % | {base["ERROR"]} | '
              + ' | '.join(f'{d:.0f} %' for d in det) + ' |')

    print(f'\nThe rule on all {len(pairs)} comparisons gives {fit_multiplier(values, pairs):g}.')
    print('\nLeave one run out: the rule (the smallest of 3, 3.5, ... 8 without a false alarm, '
          f'plus {MARGIN:g}) on the 60 comparisons among the other five runs, applied to the 30 '
          'comparisons that involve the held-out run (as checked run or as reference).\n')
    big = max(BIAS_SIZES_DEG_S)
    print('| held-out run | smallest without false alarm | fitted multiplier | WARN | ERROR | '
          + ' | '.join(KINDS[1:]) + f' | bias step {big:g} deg/s |')
    print('|---|---:|---:|---:|---:|' + '---:|' * len(KINDS))
    for held in RUNS:
        train = _pairs([r for r in RUNS if r != held])
        test = [p for p in pairs if held in p[:2]]
        k = fit_multiplier(values, train)
        if k is None:
            print(f'| imu{held} | none up to 8 | | | | ' + ' | '.join('' for _ in KINDS) + ' |')
            continue
        th = _thresholds(k)
        base = Counter(v.level for v in _verdicts(values, 'none', th, test))
        det = [100.0 * _flagged(_verdicts(values, kind, th, test)) / len(test)
               for kind in KINDS[1:]]
        det.append(100.0 * _flagged(_verdicts(values, 'none', th, test, bias_deg_s=big))
                   / len(test))
        print(f'| imu{held} | {k - MARGIN:g} | {k:g} | {base["WARN"]} of {len(test)} | '
              f'{base["ERROR"]} | ' + ' | '.join(f'{d:.0f} %' for d in det) + ' |')

    print('\nThe unchanged runs: robust location (spread) of the chunk orders, variance method / '
          'correlation method, and of the chunk bias (deg/s).\n')
    print('| run | ' + ' | '.join(f'{a}: orders | {a}: bias' for a in AXES) + ' |')
    print('|---|' + '---|---|' * len(AXES))
    for run in RUNS:
        cells = []
        for axis in AXES:
            q = _sequence(values[('none', run, axis)])
            v, c, b = q.alpha_var_robust, q.alpha_corr_robust, q.bias_robust
            cells.append(f'{v.location:.3f} ({v.spread:.3f}) / {c.location:.3f} ({c.spread:.3f})')
            cells.append(f'{math.degrees(b.location):+.4f} ({math.degrees(b.spread):.4f})')
        print(f'| imu{run} | ' + ' | '.join(cells) + ' |')

    print(f'\nPer axis (multiplier {k0:g}): the shift of the identified order that the change '
          'causes (median over the six runs of the robust location, changed minus unchanged run), '
          'and the share of the 30 comparisons flagged.\n')
    print('| change | axis | variance-method order shift | correlation-method order shift | '
          'flagged |')
    print('|---|---|---:|---:|---:|')
    for kind in KINDS[1:]:
        for axis in AXES:
            shifts = np.array([[getattr(_sequence(values[(kind, run, axis)]), f).location
                                - getattr(_sequence(values[('none', run, axis)]), f).location
                                for f in ('alpha_var_robust', 'alpha_corr_robust')]
                               for run in RUNS])
            sub_pairs = [p for p in pairs if p[2] == axis]
            flagged = _flagged(_verdicts(values, kind, default, sub_pairs))
            print(f'| {kind} | {axis} | {np.median(shifts[:, 0]):+.3f} | '
                  f'{np.median(shifts[:, 1]):+.3f} | {100.0 * flagged / len(sub_pairs):.0f} % |')

    print(f'\nBias step size (multiplier {k0:g}); the datasheet in-run bias stability is '
          f'{DATASHEET_BIAS_STABILITY_DEG_S:g} deg/s.\n')
    print('| step (deg/s) | x datasheet bias stability | flagged |')
    print('|---:|---:|---:|')
    for size in BIAS_SIZES_DEG_S:
        verdicts = _verdicts(values, 'none', default, pairs, bias_deg_s=size)
        print(f'| {size:g} | {size / DATASHEET_BIAS_STABILITY_DEG_S:.0f} | '
              f'{100.0 * _flagged(verdicts) / len(pairs):.0f} % |')

    print(f'\nShorter records (the first N chunks of both runs; multiplier {k0:g}).\n')
    print('| chunks per record | WARN, unchanged | ERROR, unchanged | '
          + ' | '.join(KINDS[1:]) + ' |')
    print('|---:|---:|---:|' + '---:|' * (len(KINDS) - 1))
    for n in (10, 25, 50, 100):
        base = Counter(v.level for v in _verdicts(values, 'none', default, pairs, chunks=n))
        det = [100.0 * _flagged(_verdicts(values, kind, default, pairs, chunks=n)) / len(pairs)
               for kind in KINDS[1:]]
        print(f'| {n} | {100.0 * base["WARN"] / len(pairs):.1f} % | {base["ERROR"]} | '
              + ' | '.join(f'{d:.0f} %' for d in det) + ' |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
