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
each chunk gets its bias, variance, fractional orders (default identification: grid 0:2:0.01,
L = 1000, demeaned, all lags) and noise colour (``core.chunks.noise_colour``: the log-log slope of
its ADEV over m = 2-64 samples). Each ordered pair (checked run, reference run) of the six runs and
each axis (90 comparisons) is judged by ``core.health.evaluate_health`` with the reference built
from the reference run's sequence statistics exactly as ``load_reference`` builds it from a
summary.json, and the default thresholds. The same pairs are judged again with a change injected
into the checked run:

* variance +25 %: the deviations of the run from its mean scaled by sqrt(1.25);
* bias step: a constant added to the whole run (0.2 deg/s; 0.05-0.3 deg/s in the size table,
  which reuses the unchanged run's orders and colours: both remove each chunk's mean, so a
  constant cannot change them);
* order shift: the deviations from the run mean filtered by the truncated GL difference
  (``core.fractional.gl_difference``, order +0.1) or sum (order -0.1), L = 1000, mean added back;
  nothing else is adjusted, so what the filter does to the variance is part of the change.

Prints Markdown tables: the levels per kind and which items flagged; the largest unchanged
differences in spreads and in standard errors; the candidate noise-colour statistics (chunk
spread, shift, distances); a sweep of the shared multiplier ``reference_warn_sigma``
(``reference_error_sigma`` at twice it) and of the colour multiplier
``reference_colour_warn_sigma`` (``reference_colour_error_sigma`` at twice it); the rule that
chose each default (the smallest multiple of 0.5 without a false alarm, plus 0.5: on the full
records for the shared multiplier, at every record length for the colour multiplier) and its
leave-one-run-out check; the robust locations of the runs; the shift each change
causes per axis; detection against the bias-step size; rates for shorter records (the first 10-50
chunks of each run). ``--cache`` keeps the per-chunk values (9,000 identifications: 33 minutes
here on two shared cores; the colours a few minutes more) for reruns.
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

from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.chunks import noise_colour, robust_location, summarise_sequence
from gyro_noise_ros.core.engine import StreamCounts
from gyro_noise_ros.core.fractional import gl_coefficients, gl_difference, OrderIdentifier
from gyro_noise_ros.core.health import (evaluate_health, HealthThresholds, ReferenceStats,
                                        spread_distance)
from gyro_noise_ros.core.results import AxisSummary
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
COLOUR_MULTIPLIERS = (1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0)
#: Record lengths (chunks per record) of the shorter-records table; the rule wants no false alarm
#: at any of them.
LENGTHS = (10, 25, 50, 100)
#: Added to the smallest multiplier without false alarms (one step of the 0.5 grid): the largest
#: differences between unchanged runs sit just under it, so a seventh run may cross it.
MARGIN = 0.5
#: GL filter orders of the colour's size table.
SIZE_ORDERS = (0.03, 0.05, 0.07, -0.03, -0.05, -0.07)
COLOUR_KEY = 'Noise colour deviation (ADEV slope, m = 2-64 samples)'
#: Pooled-periodogram bins (Fourier frequencies per bin) of the PSD-slope candidates.
PSD_BIN = 10
#: Chunks per run (1,000,000 samples in chunks of 10,000).
CHUNKS_PER_RUN = 100
_IDENT = None


def _psd_colour(chunks, fmax):
    """
    Return the ADEV-equivalent slope -(1 + PSD slope) / 2 of each chunk (rows).

    The PSD slope is the least-squares slope of the log of the periodogram, averaged over bins of
    :data:`PSD_BIN` Fourier frequencies, against the log of the bins' mean frequency, over
    frequencies up to ``fmax`` times the sample rate. White noise gives -0.5, as its ADEV slope.
    """
    x = chunks - chunks.mean(axis=1, keepdims=True)
    n = x.shape[1]
    j = np.arange(1, int(fmax * n) + 1)
    j = j[:j.size // PSD_BIN * PSD_BIN]
    power = (np.abs(np.fft.rfft(x, axis=1)) ** 2)[:, j]
    p_bin = power.reshape(x.shape[0], -1, PSD_BIN).mean(axis=2)
    f_bin = (j / n).reshape(-1, PSD_BIN).mean(axis=1)
    lf = np.log(f_bin) - np.log(f_bin).mean()
    slope = (np.log(p_bin) @ lf) / (lf @ lf)
    return -(1.0 + slope) / 2.0


#: Candidate per-chunk noise-colour statistics: (name, function of the (chunks, samples) array).
#: The first is the one the item uses (``core.chunks.noise_colour``).
CANDIDATES = (
    ('ADEV slope, m = 2-64 samples (the item)',
     lambda c: np.array([noise_colour(r) for r in c])),
    ('ADEV slope, m = 2-16 samples',
     lambda c: np.array([noise_colour(r, factors=(2, 4, 8, 16)) for r in c])),
    ('ADEV slope, m = 8-256 samples',
     lambda c: np.array([noise_colour(r, factors=(8, 16, 32, 64, 128, 256)) for r in c])),
    ('PSD slope, f up to 0.15 x rate', lambda c: _psd_colour(c, 0.15)),
    ('PSD slope, f up to 0.25 x rate', lambda c: _psd_colour(c, 0.25)),
    ('PSD slope, f up to 0.5 x rate', lambda c: _psd_colour(c, 0.5)),
)


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


def _runs(data_dir):
    """Yield (run, kind, axis, chunks array (100, 10,000) in rad/s) of every injected run."""
    for run in RUNS:
        gyro = np.deg2rad(np.load(os.path.join(data_dir, f'adis_16405_imu{run}.npz'))
                          ['gyro_dps'])
        for kind in KINDS:
            for i, axis in enumerate(AXES):
                x = _inject(gyro[:, i], kind)
                yield run, kind, axis, x[:x.size // CHUNK * CHUNK].reshape(-1, CHUNK)


def _key(kind, run, axis, prefix=''):
    return f'{prefix}{kind}|{run}|{axis}'


def _unkey(key):
    kind, run, axis = key.split('|')[-3:]
    return kind, int(run), axis


def _extras(gyro, run):
    """
    Return the per-run extras of one run (rad/s, 3 columns) keyed as in the cache.

    ``size|order``: chunk colours of the run filtered by a GL filter of ``order``
    (:data:`SIZE_ORDERS`); ``spectrum``: the chunk-averaged periodogram's power at 40-50 Hz over
    that at 1-10 Hz, and the frequency of its largest 1-Hz-smoothed value between 10 and 30 Hz;
    ``slopes``: local slopes of the whole run's ADEV between m = 1, 2, 4, ..., 64.
    """
    out = {}
    ms = np.array([1, 2, 4, 8, 16, 32, 64])
    f = np.fft.rfftfreq(CHUNK, 1.0 / RATE_HZ)
    smooth = int(round(1.0 / (f[1] - f[0])))
    for i, axis in enumerate(AXES):
        x = gyro[:, i]
        m = float(x.mean())
        for order in SIZE_ORDERS:
            chunks = (m + gl_difference(x - m, order)).reshape(-1, CHUNK)
            out[('size', str(order), run, axis)] = np.array([noise_colour(c) for c in chunks])
        chunks = x.reshape(-1, CHUNK)
        power = np.mean(np.abs(np.fft.rfft(chunks - chunks.mean(axis=1, keepdims=True),
                                           axis=1)) ** 2, axis=0)
        band = (f >= 10.0) & (f <= 30.0)
        smoothed = np.convolve(power, np.ones(smooth) / smooth, mode='same')
        out[('spectrum', 'none', run, axis)] = np.array([
            power[(f >= 40.0) & (f <= 50.0)].mean() / power[(f >= 1.0) & (f <= 10.0)].mean(),
            f[band][np.argmax(smoothed[band])]])
        adev = allan_deviation(x, RATE_HZ, taus=ms).adev
        out[('slopes', 'none', run, axis)] = np.diff(np.log(adev)) / np.diff(np.log(ms))
    return out


def chunk_values(data_dir, jobs, cache):
    """
    Return the per-chunk values of every run, kind and axis.

    Parameters
    ----------
    data_dir : str
        Folder of adis_16405_imuN.npz.
    jobs : int
        Identification processes.
    cache : str or None
        npz file read if present (the colours and extras are added to a cache that lacks them),
        else written.

    Returns
    -------
    values : dict
        ``{(kind, run, axis): array (100, 5)}``: chunk bias (rad/s), variance ((rad/s)^2), both
        orders and the noise colour.
    candidates : dict
        ``{(kind, run, axis): array (100, len(CANDIDATES))}``: the candidate colour statistics.
    extras : dict
        ``{(what, kind, run, axis): array}`` of :func:`_extras`.

    """
    orders, colours, extras = {}, {}, {}
    if cache and os.path.exists(cache):
        stored = np.load(cache)
        for k in stored.files:
            parts = k.split('|')
            if len(parts) == 3:
                orders[_unkey(k)] = stored[k]
            elif parts[0] == 'colour':
                colours[_unkey(k)] = stored[k]
            else:
                extras[(parts[0],) + _unkey(k)] = stored[k]
    if not orders:
        t0 = time.time()
        with ProcessPoolExecutor(jobs) as pool:
            for run, kind, axis, chunks in _runs(data_dir):
                ident = np.array(list(pool.map(_identify, list(chunks), chunksize=4)))
                orders[(kind, run, axis)] = np.column_stack(
                    [chunks.mean(axis=1), chunks.var(axis=1, ddof=1), ident])
                if kind == KINDS[-1] and axis == AXES[-1]:
                    print(f'run {run} identified ({time.time() - t0:.0f} s)', file=sys.stderr)
        colours, extras = {}, {}
    if len(colours) != len(orders) or not extras:
        t0 = time.time()
        for run, kind, axis, chunks in _runs(data_dir):
            colours[(kind, run, axis)] = np.column_stack([f(chunks) for _, f in CANDIDATES])
        for run in RUNS:
            extras.update(_extras(np.deg2rad(np.load(os.path.join(
                data_dir, f'adis_16405_imu{run}.npz'))['gyro_dps']), run))
        print(f'noise colours computed ({time.time() - t0:.0f} s)', file=sys.stderr)
        if cache:
            np.savez(cache, **{_key(*k): v for k, v in orders.items()},
                     **{_key(*k, prefix='colour|'): v for k, v in colours.items()},
                     **{_key(*k[1:], prefix=f'{k[0]}|'): v for k, v in extras.items()})
    values = {k: np.column_stack([v, colours[k][:, 0]]) for k, v in orders.items()}
    return values, colours, extras


def _closed_form_colour(order, memory=1000, factors=(2, 4, 8, 16, 32, 64)):
    """Exact ADEV slope of white noise filtered by the truncated GL difference of ``order``."""
    c = gl_coefficients(order, memory)
    avar = [np.sum(np.convolve(np.r_[np.ones(m), -np.ones(m)], c) ** 2) / (2.0 * m * m)
            for m in factors]
    return float(np.polyfit(np.log(factors), 0.5 * np.log(avar), 1)[0])


_SEQ = {}


def _sequence(values, key=None):
    if key is not None and key in _SEQ:
        return _SEQ[key]
    t = (np.arange(values.shape[0]) * CHUNK + (CHUNK - 1) / 2.0) / RATE_HZ
    seq = summarise_sequence(t, values[:, 0], values[:, 1], values[:, 2], values[:, 3],
                             order_step=ORDER_STEP, noise_colour=values[:, 4])
    if key is not None:
        _SEQ[key] = seq
    return seq


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
    n = chunks or CHUNKS_PER_RUN
    for a, r, axis in pairs:
        if bias_deg_s is not None:
            v = values[('none', a, axis)].copy()
            v[:, 0] += math.radians(bias_deg_s)
            key = ('bias', bias_deg_s, a, axis, n)
        else:
            v = values[(kind, a, axis)]
            key = (kind, a, axis, n)
        ref = values[('none', r, axis)]
        out.append(_judge(_sequence(v[:n], key), _sequence(ref[:n], ('none', r, axis, n)),
                          thresholds))
    return out


def _flagged(verdicts, item=None):
    """Count the verdicts flagged (WARN or ERROR): overall, or by the item ``item`` alone."""
    if item is None:
        return sum(v.level in ('WARN', 'ERROR') for v in verdicts)
    return sum(any(k == item and lv in ('WARN', 'ERROR') for k, _, lv in v.items)
               for v in verdicts)


def _alarmed(verdict, colour):
    """Whether the colour item (``colour``) or any other item flagged ``verdict``."""
    return any((k == COLOUR_KEY) == colour and lv in ('WARN', 'ERROR')
               for k, _, lv in verdict.items)


def _items(verdicts):
    c = Counter()
    for v in verdicts:
        for key, _, level in v.items:
            if level in ('WARN', 'ERROR'):
                c[key] += 1
    return ', '.join(f'{k}: {n}' for k, n in sorted(c.items())) or '-'


def _thresholds(k=None, colour=None):
    th = HealthThresholds()
    if k is not None:
        th = replace(th, reference_warn_sigma=k, reference_error_sigma=2 * k)
    if colour is not None:
        th = replace(th, reference_colour_warn_sigma=colour,
                     reference_colour_error_sigma=2 * colour)
    return th


def fit_multiplier(values, pairs, *, colour=False, lengths=None):
    """
    Return the multiplier rule's choice on ``pairs``, for the shared or the colour multiplier.

    The rule: the smallest multiple of 0.5 up to 8 with no false alarm (no WARN, no ERROR, ERROR
    at twice the multiplier) on the unchanged ``pairs``, plus :data:`MARGIN`; on the full records
    (100 chunks) for the shared multiplier, at every record length of :data:`LENGTHS` for the
    colour multiplier (module doc of ``core/health.py``: at 100 chunks alone it would give 1.5,
    which false-alarms on 10-chunk records). The shared multiplier is judged on every item but the
    noise colour (which keeps its default), the colour multiplier on the noise colour alone.

    Parameters
    ----------
    values : dict
        From :func:`chunk_values`.
    pairs : list
        (checked run, reference run, axis) comparisons to fit on.
    colour : bool, keyword-only
        Fit the colour multiplier instead of the shared one.
    lengths : tuple of int, optional, keyword-only
        Record lengths (chunks) instead of the rule's.

    Returns
    -------
    float or None
        None when no multiplier up to 8 keeps them.

    """
    if lengths is None:
        lengths = LENGTHS if colour else (CHUNKS_PER_RUN,)
    for k in np.arange(0.5, 8.01, 0.5):
        th = _thresholds(colour=k) if colour else _thresholds(k)
        if not any(_alarmed(v, colour) for n in lengths
                   for v in _verdicts(values, 'none', th, pairs, chunks=n)):
            return float(k) + MARGIN
    return None


def _pct(count, total):
    return f'{100.0 * count / total:.0f} %'


def _candidate_table(candidates, pairs):
    """Print the candidate colour statistics, compared in pooled chunk spreads (100 chunks)."""
    print('\nCandidate noise-colour statistics (all in ADEV-slope units: -0.5 for white noise; '
          'the PSD slopes as -(1 + PSD slope) / 2), 100 chunks per record: median chunk spread, '
          'run-to-run standard deviation of the robust location (median over the axes), the '
          'median shift the GL filters cause, the largest distance between unchanged runs and '
          'the smallest between a filtered run and an unchanged reference (in pooled chunk '
          'spreads, over the 90 comparisons), and the share of the 90 filtered comparisons above '
          '5 and above 2.5 spreads (difference / sum).\n')
    print('| statistic | chunk spread | run-to-run SD | shift: difference / sum | largest '
          'unchanged | smallest filtered | above 5 | above 2.5 |')
    print('|---|---:|---:|---:|---:|---:|---:|---:|')
    filters = KINDS[3:]
    for i, (name, _) in enumerate(candidates['names']):
        loc = {k: robust_location(v[:, i]) for k, v in candidates['values'].items()}
        spread = np.median([loc[('none', r, a)].spread for r in RUNS for a in AXES])
        run_sd = np.median([np.std([loc[('none', r, a)].location for r in RUNS], ddof=1)
                            for a in AXES])
        shift = [np.median([loc[(k, r, a)].location - loc[('none', r, a)].location
                            for r in RUNS for a in AXES]) for k in filters]
        unchanged = max(spread_distance(loc[('none', a, ax)], loc[('none', r, ax)])
                        for a, r, ax in pairs)
        dist = {k: [spread_distance(loc[(k, a, ax)], loc[('none', r, ax)]) for a, r, ax in pairs]
                for k in filters}
        smallest = min(min(d) for d in dist.values())
        above = [' / '.join(_pct(sum(x > lim for x in dist[k]), len(pairs)) for k in filters)
                 for lim in (5.0, 2.5)]
        print(f'| {name} | {spread:.4f} | {run_sd:.4f} | {shift[0]:+.3f} / {shift[1]:+.3f} | '
              f'{unchanged:.2f} | {smallest:.2f} | {above[0]} | {above[1]} |')


def main():
    """Print the tables of docs/verdicts.md."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--data', default=DEFAULT_DATA)
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1)
    parser.add_argument('--cache', default=None, help='npz of the per-chunk values')
    args = parser.parse_args()
    values, cand, extras = chunk_values(args.data, args.jobs, args.cache)
    default = HealthThresholds()
    pairs = _pairs()
    k0, c0 = default.reference_warn_sigma, default.reference_colour_warn_sigma
    print(f'Default thresholds: WARN above {k0:g}, ERROR above '
          f'{default.reference_error_sigma:g} sigma (pooled chunk spreads; for the drift pooled '
          f'standard errors); the noise colour WARN above {c0:g}, ERROR above '
          f'{default.reference_colour_error_sigma:g} pooled chunk spreads; {len(pairs)} '
          'comparisons per kind.\n')
    print('| change in the checked run | OK | WARN | ERROR | flagged | items that flagged |')
    print('|---|---:|---:|---:|---:|---|')
    for kind in KINDS:
        verdicts = _verdicts(values, kind, default, pairs)
        levels = Counter(v.level for v in verdicts)
        print(f'| {kind} | {levels["OK"]} | {levels["WARN"]} | {levels["ERROR"]} | '
              f'{_pct(_flagged(verdicts), len(pairs))} | {_items(verdicts)} |')

    blind = _thresholds(colour=1000.0)
    print('\nWithout the noise colour (its multipliers at 1000): '
          + ', '.join(f'{kind} {_pct(_flagged(_verdicts(values, kind, blind, pairs)), len(pairs))}'
                      for kind in KINDS[3:]) + ' flagged.')

    print('\nLargest difference between unchanged runs (90 comparisons), in pooled chunk spreads '
          '(the rule) and in pooled standard errors of the location (spread / sqrt(chunks)); '
          'and in pooled chunk spreads on the first 10 chunks of each run.\n')
    print('| quantity | in spreads | in standard errors | in spreads, 10 chunks |')
    print('|---|---:|---:|---:|')
    for name, field_name in (('bias', 'bias_robust'), ('log variance', 'log_variance_robust'),
                             ('variance-method order', 'alpha_var_robust'),
                             ('correlation-method order', 'alpha_corr_robust'),
                             ('noise colour', 'noise_colour_robust')):
        d_spread = d_se = 0.0
        for a, r, axis in pairs:
            m = getattr(_sequence(values[('none', a, axis)], ('none', a, axis, 100)), field_name)
            q = getattr(_sequence(values[('none', r, axis)], ('none', r, axis, 100)), field_name)
            diff = abs(m.location - q.location)
            d_spread = max(d_spread, diff / math.hypot(m.spread, q.spread))
            se = math.hypot(m.spread / math.sqrt(m.count), q.spread / math.sqrt(q.count))
            d_se = max(d_se, diff / se)
        d_short = max(spread_distance(
            getattr(_sequence(values[('none', a, axis)][:10], ('none', a, axis, 10)), field_name),
            getattr(_sequence(values[('none', r, axis)][:10], ('none', r, axis, 10)), field_name))
            for a, r, axis in pairs)
        print(f'| {name} | {d_spread:.2f} | {d_se:.1f} | {d_short:.2f} |')

    _candidate_table({'names': CANDIDATES, 'values': cand}, pairs)

    print('\nClosed form (white noise filtered by the truncated GL difference, L = 1000): the '
          'ADEV slope over m = 2-64 samples moves by '
          f'{_closed_form_colour(0.1) - _closed_form_colour(0.0):+.3f} (order +0.1) and '
          f'{_closed_form_colour(-0.1) - _closed_form_colour(0.0):+.3f} (order -0.1).')
    print("\nThe runs' spectra and Allan curves: power at 40-50 Hz over power at 1-10 Hz of "
          'the chunk-averaged periodogram per axis, the frequency of the largest 1-Hz-smoothed '
          "power between 10 and 30 Hz on z, and the local slopes of the whole run's ADEV on x "
          'and z between m = 1, 2, 4, 8 samples.\n')
    print('| run | x: 40-50 / 1-10 Hz | y: 40-50 / 1-10 Hz | z: 40-50 / 1-10 Hz | '
          'z: peak 10-30 Hz | x: slopes m = 1-2, 2-4, 4-8 | z: slopes m = 1-2, 2-4, 4-8 |')
    print('|---|---:|---:|---:|---:|---|---|')
    for run in RUNS:
        spec = {a: extras[('spectrum', 'none', run, a)] for a in AXES}
        slopes = {a: extras[('slopes', 'none', run, a)][:3] for a in 'xz'}
        print(f'| imu{run} | ' + ' | '.join(f'{spec[a][0]:.2f}' for a in AXES)
              + f' | {spec["z"][1]:.1f} Hz | '
              + ' | '.join(', '.join(f'{v:+.2f}' for v in slopes[a]) for a in 'xz') + ' |')

    print(f'\nFilter size (the colour item alone, multiplier {c0:g}): a GL filter of order d in '
          'the checked run; median shift of the colour and the share of the 90 comparisons the '
          'colour item flags.\n')
    print('| filter order | colour shift | flagged by the colour |')
    print('|---:|---:|---:|')
    for order in sorted(SIZE_ORDERS + (-0.1, 0.1), key=lambda o: (abs(o), -o)):
        kind = {0.1: KINDS[3], -0.1: KINDS[4]}.get(order)
        col = {(r, a): (cand[(kind, r, a)][:, 0] if kind else
                        extras[('size', str(order), r, a)]) for r in RUNS for a in AXES}
        shift = np.median([np.median(col[(r, a)]) - np.median(cand[('none', r, a)][:, 0])
                           for r in RUNS for a in AXES])
        flagged = 0
        for a, r, axis in pairs:
            d = spread_distance(robust_location(col[(a, axis)]),
                                robust_location(cand[('none', r, axis)][:, 0]))
            flagged += d > c0
        print(f'| {order:+g} | {shift:+.3f} | {_pct(flagged, len(pairs))} |')

    print(f'\nShared multiplier sweep (ERROR at twice the multiplier; noise colour at {c0:g}): '
          'false alarms and detection.\n')
    print('| multiplier | WARN, unchanged | ERROR, unchanged | '
          + ' | '.join(KINDS[1:]) + ' |')
    print('|---:|---:|---:|' + '---:|' * (len(KINDS) - 1))
    for k in MULTIPLIERS:
        th = _thresholds(k)
        base = Counter(v.level for v in _verdicts(values, 'none', th, pairs))
        det = [_pct(_flagged(_verdicts(values, kind, th, pairs)), len(pairs))
               for kind in KINDS[1:]]
        print(f'| {k:g} | {100.0 * base["WARN"] / len(pairs):.1f} % | {base["ERROR"]} | '
              + ' | '.join(det) + ' |')

    print(f'\nColour multiplier sweep (ERROR at twice it; shared multiplier at {k0:g}): the '
          'noise-colour item alone, unchanged comparisons flagged at 100 and at 10 chunks per '
          'record, and the filtered comparisons it flags (100 chunks).\n')
    print('| colour multiplier | flagged unchanged, 100 chunks | ERROR | flagged unchanged, '
          '10 chunks | ERROR | order: GL difference 0.1 | order: GL sum 0.1 |')
    print('|---:|---:|---:|---:|---:|---:|---:|')
    for k in COLOUR_MULTIPLIERS:
        th = _thresholds(colour=k)
        cells = []
        for n in (100, 10):
            vs = _verdicts(values, 'none', th, pairs, chunks=n)
            err = sum(any(key == COLOUR_KEY and lv == 'ERROR' for key, _, lv in v.items)
                      for v in vs)
            cells += [f'{100.0 * _flagged(vs, COLOUR_KEY) / len(pairs):.1f} %', str(err)]
        det = [_pct(_flagged(_verdicts(values, kind, th, pairs), COLOUR_KEY), len(pairs))
               for kind in KINDS[3:]]
        print(f'| {k:g} | ' + ' | '.join(cells + det) + ' |')

    print(f'\nThe rule on all {len(pairs)} comparisons gives {fit_multiplier(values, pairs):g} '
          f'for the shared multiplier (no false alarm on the 100-chunk records; '
          f'{fit_multiplier(values, pairs, lengths=LENGTHS):g} if it had to hold at every '
          f'record length) and {fit_multiplier(values, pairs, colour=True):g} for the colour '
          f'multiplier (at every record length; '
          f'{fit_multiplier(values, pairs, colour=True, lengths=(CHUNKS_PER_RUN,)):g} on the '
          '100-chunk records alone).')
    print('\nLeave one run out: the rule (the smallest of 0.5, 1, ... 8 without a false alarm, '
          f'plus {MARGIN:g}; for the shared multiplier on the 100-chunk records, for the colour '
          f'multiplier at every record length of {", ".join(map(str, LENGTHS))} chunks) on the '
          '60 comparisons among the other five runs, applied to the 30 comparisons that involve '
          'the held-out run (as checked run or as reference; 100 chunks).\n')
    big = max(BIAS_SIZES_DEG_S)
    print('| held-out run | shared: smallest without false alarm | fitted | colour: smallest '
          'without false alarm | fitted | WARN | ERROR | '
          + ' | '.join(KINDS[1:]) + f' | bias step {big:g} deg/s |')
    print('|---|---:|---:|---:|---:|---:|---:|' + '---:|' * len(KINDS))
    for held in RUNS:
        train = _pairs([r for r in RUNS if r != held])
        test = [p for p in pairs if held in p[:2]]
        k = fit_multiplier(values, train)
        c = fit_multiplier(values, train, colour=True)
        if k is None or c is None:
            print(f'| imu{held} | none up to 8 | | | | | | ' + ' | '.join('' for _ in KINDS)
                  + ' |')
            continue
        th = _thresholds(k, colour=c)
        base = Counter(v.level for v in _verdicts(values, 'none', th, test))
        det = [_pct(_flagged(_verdicts(values, kind, th, test)), len(test))
               for kind in KINDS[1:]]
        det.append(_pct(_flagged(_verdicts(values, 'none', th, test, bias_deg_s=big)), len(test)))
        print(f'| imu{held} | {k - MARGIN:g} | {k:g} | {c - MARGIN:g} | {c:g} | '
              f'{base["WARN"]} of {len(test)} | {base["ERROR"]} | ' + ' | '.join(det) + ' |')

    print('\nThe unchanged runs: robust location (spread) of the chunk orders, variance method / '
          'correlation method, and of the chunk bias (deg/s).\n')
    print('| run | ' + ' | '.join(f'{a}: orders | {a}: bias' for a in AXES) + ' |')
    print('|---|' + '---|---|' * len(AXES))
    for run in RUNS:
        cells = []
        for axis in AXES:
            q = _sequence(values[('none', run, axis)], ('none', run, axis, 100))
            v, c, b = q.alpha_var_robust, q.alpha_corr_robust, q.bias_robust
            cells.append(f'{v.location:.3f} ({v.spread:.3f}) / {c.location:.3f} ({c.spread:.3f})')
            cells.append(f'{math.degrees(b.location):+.4f} ({math.degrees(b.spread):.4f})')
        print(f'| imu{run} | ' + ' | '.join(cells) + ' |')

    print('\nThe unchanged runs: robust location (spread) of the chunk noise colour (ADEV slope, '
          'm = 2-64 samples).\n')
    print('| run | ' + ' | '.join(AXES) + ' |')
    print('|---|' + '---:|' * len(AXES))
    for run in RUNS:
        cells = []
        for axis in AXES:
            q = _sequence(values[('none', run, axis)], ('none', run, axis, 100))
            c = q.noise_colour_robust
            cells.append(f'{c.location:+.4f} ({c.spread:.4f})')
        print(f'| imu{run} | ' + ' | '.join(cells) + ' |')

    print('\nPer axis (defaults): the shift that the change causes in the identified orders and '
          'in the noise colour (median over the six runs of the robust location, changed minus '
          'unchanged run), the share of the 30 comparisons flagged by the noise colour alone and '
          'by any item.\n')
    print('| change | axis | variance-method order shift | correlation-method order shift | '
          'noise colour shift | flagged by the colour | flagged |')
    print('|---|---|---:|---:|---:|---:|---:|')
    for kind in KINDS[1:]:
        for axis in AXES:
            shifts = np.array([[getattr(_sequence(values[(kind, run, axis)],
                                                  (kind, run, axis, 100)), f).location
                                - getattr(_sequence(values[('none', run, axis)],
                                                    ('none', run, axis, 100)), f).location
                                for f in ('alpha_var_robust', 'alpha_corr_robust',
                                          'noise_colour_robust')]
                               for run in RUNS])
            sub_pairs = [p for p in pairs if p[2] == axis]
            verdicts = _verdicts(values, kind, default, sub_pairs)
            print(f'| {kind} | {axis} | {np.median(shifts[:, 0]):+.3f} | '
                  f'{np.median(shifts[:, 1]):+.3f} | {np.median(shifts[:, 2]):+.3f} | '
                  f'{_pct(_flagged(verdicts, COLOUR_KEY), len(sub_pairs))} | '
                  f'{_pct(_flagged(verdicts), len(sub_pairs))} |')

    print(f'\nBias step size (defaults); the datasheet in-run bias stability is '
          f'{DATASHEET_BIAS_STABILITY_DEG_S:g} deg/s.\n')
    print('| step (deg/s) | x datasheet bias stability | flagged |')
    print('|---:|---:|---:|')
    for size in BIAS_SIZES_DEG_S:
        verdicts = _verdicts(values, 'none', default, pairs, bias_deg_s=size)
        print(f'| {size:g} | {size / DATASHEET_BIAS_STABILITY_DEG_S:.0f} | '
              f'{_pct(_flagged(verdicts), len(pairs))} |')

    print('\nShorter records (the first N chunks of both runs; defaults).\n')
    print('| chunks per record | WARN, unchanged | ERROR, unchanged | '
          + ' | '.join(KINDS[1:]) + ' |')
    print('|---:|---:|---:|' + '---:|' * (len(KINDS) - 1))
    for n in LENGTHS:
        base = Counter(v.level for v in _verdicts(values, 'none', default, pairs, chunks=n))
        det = [_pct(_flagged(_verdicts(values, kind, default, pairs, chunks=n)), len(pairs))
               for kind in KINDS[1:]]
        print(f'| {n} | {100.0 * base["WARN"] / len(pairs):.1f} % | {base["ERROR"]} | '
              + ' | '.join(det) + ' |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
