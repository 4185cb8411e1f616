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
Measure the reliability verdicts: stated sigma against the spread, false alarms and detections.

The tables of docs/reliability.md section 2. Every record is ``portenta_emulator --scenario
static`` (the emulator's own board model, :func:`gyro_noise_ros.cli.emulator.board_from_args`,
quantised at the full scales as ``--write-bag`` writes it, fed to the same
:func:`gyro_noise_ros.app.reliability.static_from_batches` and
:func:`~gyro_noise_ros.app.reliability.verdicts_of` as ``gyro_noise_reliability``; no bag is
written, only the disk I/O is skipped). Parts::

    truth     the emulator's closed-form Allan variance (white + its Gauss-Markov flicker sum +
              random walk) before and after --stress: which channels the stress changes, by how
              much
    sigma     N records of 4 h at 12.5 Hz: spread of log(width) and of the log noise terms
              against the stated standard deviations
    default   10 pairs of unstressed 4 h records at 104 Hz (the walk-through's length) and 10
              pairs unstressed -> --stress: verdict counts
    long      4 + 4 pairs of 48 h records at 12.5 Hz (same model, a rate the machine can afford
              at that length): where the verdicts get their power

With the sigma part, a table of what record length the verdict needs (a normal model of the
verdict fed with the measured 4-h spread; the default and long parts check it).

Run (seeded: the same numbers every time; per-record results are cached in --cache)::

    nice python docs/scripts/reliability_verdicts.py --part all --cache /tmp/relcache

``--write`` puts the tables into docs/reliability.md between its markers, with the command.
"""

import argparse
import dataclasses
import json
import math
import os
import sys
import time

from _doc_tables import print_and_write
from gyro_noise_ros.app.reliability import static_from_batches, verdicts_of
from gyro_noise_ros.calibration.emulate import FLICKER_PER_DECADE, FLICKER_TAU_S
from gyro_noise_ros.calibration.interval import bias_instability_interval, Interval
from gyro_noise_ros.calibration.static_record import CHANNELS, TERMS
from gyro_noise_ros.cli._scenario import scenario_from_args
from gyro_noise_ros.cli.emulator import board_from_args, build_parser
from gyro_noise_ros.core.simulate import gauss_markov_avar
from gyro_noise_ros.link import lsm6dso32 as lsm
from gyro_noise_ros.link.emulator import ACCEL_NOISE_DENSITY_UG_RTHZ
from gyro_noise_ros.units import DEG_TO_RAD, STANDARD_GRAVITY_M_S2
import numpy as np
import scipy.stats


def emulator_argv(seed, odr_hz, hours, stress):
    return (['--odr-hz', f'{odr_hz:g}', '--scenario', 'static', '--seed', str(seed),
             '--duration-s', f'{hours * 3600:g}'] + (['--stress'] if stress else []))


def _batches(board, n):
    gl = lsm.gyro_sensitivity_rad_s_per_lsb(board.gyro_fs_dps)
    al = lsm.accel_sensitivity_m_s2_per_lsb(board.accel_fs_g)
    done = 0
    while done < n:
        m = min(65536, n - done)
        s = board.next_samples(m)
        yield board.odr_hz, board.last_truth.time_s, s['accel'] * al, s['gyro'] * gl
        done += m


def record(seed, odr_hz, hours, stress, cache):
    """Return the cached per-channel summary of one emulated static record."""
    argv = emulator_argv(seed, odr_hz, hours, stress)
    key = '_'.join(argv).replace('--', '').replace('/', '')
    path = os.path.join(cache, key + '.json') if cache else None
    if path and os.path.exists(path):
        with open(path) as fh:
            return json.load(fh)
    t0 = time.time()
    held = list(_batches(board_from_args(argv), int(round(hours * 3600 * odr_hz))))
    st = static_from_batches(lambda: iter(held), source='portenta_emulator ' + ' '.join(argv))
    out = {'argv': argv, 'record_s': st.duration_s, 'cpu_s': time.time() - t0, 'channels': {}}
    for ch, r in st.channels.items():
        iv = dataclasses.asdict(r.interval)
        terms = ({t: [r.terms[t].value, r.terms[t].sd_log] for t in TERMS}
                 if r.terms else None)
        out['channels'][ch] = {'interval': iv, 'terms': terms}
    if path:
        os.makedirs(cache, exist_ok=True)
        with open(path + '.tmp', 'w') as fh:
            json.dump(out, fh, allow_nan=True)
        os.replace(path + '.tmp', path)
    print(f'  {" ".join(argv)}: {time.time() - t0:.0f} s', file=sys.stderr, flush=True)
    return out


class _Static:
    """The part of a StaticAnalysis that verdicts_of reads, rebuilt from the cache."""

    def __init__(self, rec):
        self.channels = {}
        for ch, d in rec['channels'].items():
            iv = dict(d['interval'])
            if iv['fallback_s'] is not None:
                iv['fallback_s'] = tuple(iv['fallback_s'])
            self.channels[ch] = type('R', (), {'interval': Interval(**iv)})


def truth():
    """Return the emulator's closed-form widths before/after --stress per sensor."""
    out = {}
    tau = np.logspace(-2, 5, 7001)
    for stress in (False, True):
        args = build_parser().parse_args(emulator_argv(0, 104.0, 4, stress))
        e = scenario_from_args(args).errors
        n_acc = ACCEL_NOISE_DENSITY_UG_RTHZ * 1e-6 * STANDARD_GRAVITY_M_S2 / math.sqrt(2.0)
        n_gyr = args.noise_std_dps * DEG_TO_RAD / math.sqrt(args.odr_hz)
        for sensor, n, b, k in (
                ('accel', n_acc, e.accel_bias_instability_m_s2, e.accel_random_walk_m_s2_sqrt_s),
                ('gyro', n_gyr, e.gyro_bias_instability_rad_s, e.gyro_random_walk_rad_s_sqrt_s)):
            # the emulator's flicker: Gauss-Markov components 3 per decade (emulate.py)
            lo = max(FLICKER_TAU_S[0], 2.0 / args.odr_hz)
            m = max(1, int(np.ceil(np.log10(FLICKER_TAU_S[1] / lo) * FLICKER_PER_DECADE)) + 1)
            taus = lo * 10.0 ** (np.arange(m) / FLICKER_PER_DECADE)
            s = b * math.sqrt(math.log(10.0) / FLICKER_PER_DECADE / math.pi)
            flicker = sum(gauss_markov_avar(tau, s, t) for t in taus)
            avar = n * n / tau + k * k * tau / 3.0 + flicker
            iv = bias_instability_interval(tau, np.sqrt(avar))
            out[(sensor, stress)] = iv
    return {s: (out[(s, False)], out[(s, True)]) for s in ('accel', 'gyro')}


_TRUTH = {}


def _truth_ratio(ch):
    """Return the emulator's true width ratio after/before --stress of one channel."""
    if not _TRUTH:
        _TRUTH.update({s: a.width_s / b.width_s for s, (b, a) in truth().items()})
    return _TRUTH[ch.split('_')[0]]


def _upper95(k, n):
    """Return the one-sided 95 % Clopper-Pearson upper bound of a rate k / n."""
    return 1.0 if k >= n else float(scipy.stats.beta.ppf(0.95, k + 1, n - k))


def _lower95(k, n):
    """Return the one-sided 95 % Clopper-Pearson lower bound of a rate k / n."""
    return 0.0 if k <= 0 else float(scipy.stats.beta.ppf(0.05, k, n - k + 1))


def part_truth():
    print('\n### Truth: the emulator model, closed form\n')
    print('| sensor | interval before (s) | interval after --stress (s) | width ratio |')
    print('|---|---|---|---|')
    for sensor, (b, a) in truth().items():
        print(f'| {sensor} (x, y, z alike) | {b.lo_s:.3g} - {b.hi_s:.4g} | {a.lo_s:.3g} - '
              f'{a.hi_s:.4g} | {a.width_s / b.width_s:.3f} |')
    big = [ch for ch in CHANNELS if _truth_ratio(ch) >= 2.0]
    print('\nChannels --stress changes by 2x or more (emulator truth): '
          f'{", ".join(big) or "none"}.')


def part_sigma(n, cache):
    recs = [record(7000 + i, 12.5, 4, False, cache) for i in range(n)]
    print(f'\n### Stated standard deviation against the spread: {n} records of 4 h at 12.5 Hz\n')
    print('| quantity | sensor | values | sd of log (spread) | rms of stated sd | ratio | '
          'within +/-1 stated sd | within +/-1.645 stated sd |')
    print('|---|---|---|---|---|---|---|---|')
    rows = [('interval width', None)] + [(t.replace('_', ' '), t) for t in TERMS]
    spreads = {}
    for label, term in rows:
        for sensor in ('accel', 'gyro'):
            z, v, sds = [], [], []
            for ch in CHANNELS:
                if not ch.startswith(sensor):
                    continue
                vals, sd = [], []
                for r in recs:
                    c = r['channels'][ch]
                    if term is None:
                        iv = c['interval']
                        if iv['lo_s'] is None or iv['hi_s'] is None or iv['fallback_significant']:
                            continue
                        vals.append(math.log(iv['hi_s'] - iv['lo_s']))
                        sd.append(iv['width_sd_log'])
                    elif c['terms'] and c['terms'][term][0] > 0:
                        vals.append(math.log(c['terms'][term][0]))
                        sd.append(c['terms'][term][1])
                vals, sd = np.array(vals), np.array(sd)
                ok = np.isfinite(sd)
                vals, sd = vals[ok], sd[ok]
                # each axis about its own mean (the axes share a model, not a value)
                z += list((vals - vals.mean()) / sd)
                v += list(vals - vals.mean())
                sds += list(sd)
            v, sds, z = np.array(v), np.array(sds), np.abs(np.array(z))
            spread = float(np.sqrt(np.sum(v ** 2) / (v.size - 3)))
            stated = float(np.sqrt(np.mean(sds ** 2)))
            spreads[(label, sensor)] = spread
            print(f'| {label} | {sensor} | {v.size} | {spread:.4f} | {stated:.4f} | '
                  f'{spread / stated:.2f} | {np.mean(z <= 1):.0%} | {np.mean(z <= 1.645):.0%} |')
    return spreads


def part_power(spreads, alpha=0.05, tolerance=0.5, hours=(4, 12, 24, 48, 96, 168)):
    """
    Print what record length the interval verdict needs, from the measured 4-h spread.

    The verdict tests log(W_after / W_before) against log(1 + tolerance) one-sided at ``alpha``.
    With the spread s4 of log(width) of one 4-h record (part sigma) and sd falling as
    1/sqrt(length) (EDF at a fixed tau grows with the record), a pair of L-hour records has
    ``s = sqrt(2) s4 sqrt(4 / L)`` and a channel whose true ratio is r is called beyond with
    probability ``Phi((log r - log(1 + tol)) / s - z)``; the sensor's three-axis mean has s /
    sqrt(3). A normal approximation of the verdict (it ignores open ends and ambiguous crossings,
    which make short records undetermined more often): the measured tables are the check.
    """
    z = float(scipy.stats.norm.ppf(1 - alpha))
    band = math.log(1.0 + tolerance)
    print('\n### Record length against power (normal model from the measured 4-h spread)\n')
    ratio = _truth_ratio('gyro_x')
    print('| record (h) | sensor | sd of log ratio, pair | channel false alarm (unchanged) | '
          f'channel detection (x{ratio:.2f}) | all 30 channels of 10 stressed sensors beyond | '
          'sensor (3-axis mean) detection |')
    print('|---|---|---|---|---|---|---|')
    for h in hours:
        for sensor in ('accel', 'gyro'):
            s = math.sqrt(2.0) * spreads[('interval width', sensor)] * math.sqrt(4.0 / h)
            mu = math.log(_truth_ratio(sensor + '_x'))
            fa = scipy.stats.norm.cdf(-band / s - z)
            det = scipy.stats.norm.cdf((mu - band) / s - z)
            sen = scipy.stats.norm.cdf((mu - band) / (s / math.sqrt(3.0)) - z)
            print(f'| {h:g} | {sensor} | {s:.3f} | {fa:.1e} | {det:.1%} | {det ** 30:.1%} | '
                  f'{sen:.1%} |')


def _pairs(pairs, cache, odr, hours, seeds, stress_pairs=None):
    a0, b0, s0 = seeds
    null = [(record(a0 + i, odr, hours, False, cache), record(b0 + i, odr, hours, False, cache))
            for i in range(pairs)]
    stress = [(record(a0 + i, odr, hours, False, cache), record(s0 + i, odr, hours, True, cache))
              for i in range(pairs if stress_pairs is None else stress_pairs)]
    return null, stress


def _count(pairs_list, tolerance=0.5):
    ch = {'beyond': 0, 'physiological': 0, 'undetermined': 0}
    sen = dict(ch)
    old = 0
    decide, changes = [], []
    for b, a in pairs_list:
        verdicts, sensors = verdicts_of(_Static(b), _Static(a))
        for name, v in verdicts.items():
            ch[v.verdict] += 1
            if v.change is not None:
                changes.append(v.change)
                old += abs(v.change) > tolerance
            if v.decide_record_s:
                decide.append(max(v.decide_record_s))
        for s in sensors.values():
            sen[s.verdict] += 1
    return ch, sen, old, decide, changes


def part_pairs(label, pairs, cache, odr, hours, seeds, stress_pairs=None):
    null, stress = _pairs(pairs, cache, odr, hours, seeds, stress_pairs)
    print(f'\n### {label}: {pairs} unstressed pairs and {len(stress)} stressed pairs of '
          f'{hours:g} h records at {odr:g} Hz\n')
    print('| pairs | channels | beyond | physiological | undetermined | old rule (abs(change) '
          '> 50 %) | sensors beyond / physiological / undetermined | median record that '
          'would decide (h) | median change |')
    print('|---|---|---|---|---|---|---|---|---|')
    for name, pl in (('unstressed -> unstressed', null), ('unstressed -> --stress', stress)):
        ch, sen, old, decide, changes = _count(pl)
        n = 6 * len(pl)
        med = f'{np.median(decide) / 3600:.0f}' if decide else 'n/a'
        print(f'| {name} | {n} | {ch["beyond"]} | {ch["physiological"]} | '
              f'{ch["undetermined"]} | {old} | {sen["beyond"]} / {sen["physiological"]} / '
              f'{sen["undetermined"]} of {2 * len(pl)} | {med} | '
              f'{100 * np.median(changes):+.0f} % |')
    fa, n_null = _count(null)[0]['beyond'], 6 * len(null)
    det = n_det = 0
    for b, a in stress:
        verdicts, _ = verdicts_of(_Static(b), _Static(a))
        for name, v in verdicts.items():
            if _truth_ratio(name) >= 2.0:
                n_det += 1
                det += v.verdict == 'beyond'
    sen_fa = _count(null)[1]['beyond']
    sen_det = _count(stress)[1]['beyond']
    print(f'\nFalse-alarm rate (unstressed pairs, channel called beyond): {fa} of {n_null} '
          f'({100 * fa / n_null:.1f} %, one-sided 95 % upper bound '
          f'{100 * _upper95(fa, n_null):.1f} %); sensors: {sen_fa} of {2 * len(null)}. '
          'Detection rate (channels --stress changes '
          f'by 2x or more, called beyond): {det} of {n_det} ({100 * det / max(n_det, 1):.0f} %, '
          f'one-sided 95 % lower bound {100 * _lower95(det, n_det):.0f} %); sensors: {sen_det} of '
          f'{2 * len(stress)}.')
    amb = sum(1 for pl in (null, stress) for pair in pl for rec in pair
              for c in rec['channels'].values() if c['interval']['fallback_s'] is not None)
    sig = sum(1 for pl in (null, stress) for pair in pl for rec in pair
              for c in rec['channels'].values() if c['interval']['fallback_significant'])
    cpu = sum(rec['cpu_s'] for pl in (null, stress) for pair in pl for rec in pair)
    print(f'\nAmbiguous upper crossings among these channel-records: {amb} (significant: '
          f'{sig}); generation and analysis {cpu / 60:.0f} min.')


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--part', choices=('truth', 'sigma', 'default', 'long', 'all'),
                   default='all')
    p.add_argument('--cache', help='folder for per-record results (resumable)')
    p.add_argument('--sigma-records', type=int, default=100)
    p.add_argument('--pairs', type=int, default=10)
    p.add_argument('--stress-pairs', type=int, default=None,
                   help='unstressed -> --stress pairs at the default length (default: --pairs)')
    p.add_argument('--long-pairs', type=int, default=4)
    p.add_argument('--long-stress-pairs', type=int, default=None)
    p.add_argument('--long-hours', type=float, default=48.0)
    p.add_argument('--write', action='store_true',
                   help='write the tables into docs/reliability.md between its markers '
                        '(with --part all)')
    args = p.parse_args(argv)
    if args.write and args.part != 'all':
        p.error('--write needs --part all')
    parts = ('truth', 'sigma', 'default', 'long') if args.part == 'all' else (args.part,)
    if args.write:
        print_and_write(lambda: _run(parts, args), 'reliability_verdicts.py', 'reliability.md',
                        argv if argv is not None else sys.argv[1:])
        return 0
    _run(parts, args)
    return 0


def _run(parts, args):
    if 'truth' in parts:
        part_truth()
    if 'sigma' in parts:
        spreads = part_sigma(args.sigma_records, args.cache)
        part_power(spreads)
    if 'default' in parts:
        part_pairs('Default length', args.pairs, args.cache, 104.0, 4, (1000, 2000, 3000),
                   args.stress_pairs)
    if 'long' in parts:
        part_pairs('Long records', args.long_pairs, args.cache, 12.5, args.long_hours,
                   (4000, 5000, 6000), args.long_stress_pairs)


if __name__ == '__main__':
    sys.exit(main())
