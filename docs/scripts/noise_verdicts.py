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
Measure the reliability verdict (the noise at fixed taus): false alarms, detections, real data.

The tables of docs/reliability.md section 2 "What the verdict is worth". Parts::

    emulator  pairs of 4-h static records of ``portenta_emulator --scenario static`` at 104 Hz
              (its board model in-process, quantised as --write-bag writes it, fed to the same
              app.reliability.static_from_batches and noise_verdicts_of as the tool):
              unstressed -> unstressed and unstressed -> --stress (B x1.7, the paper's widening)
    lengths   the same at 1 h and 12 h: detection and false alarms against record length
    real      the six ADIS16405 runs (../shared/data/real/adis16405_static, 100 Hz, 10,000 s):
              all 15 pairs, the largest ratio per tau (the band's argument), and the bias
              stability of each run with its tau (where "x1.7 between runs" came from)
    cli       a pair of emulated 1-h bags and one ADIS pair written as bags and run through
              portenta_emulator and gyro_noise_reliability: the tool's verdicts equal the
              in-process ones

Run (seeded; per-record results cached in --cache; nice it, the emulator part takes ~1 h)::

    nice python docs/scripts/noise_verdicts.py --part all --cache /tmp/noisecache [--write]

``--write`` puts the tables into docs/reliability.md between its markers, with the command.
"""

import argparse
import itertools
import json
import math
import os
import subprocess
import sys
import tempfile
import time

from _doc_tables import print_and_write
from gyro_noise_ros.app.reliability import static_from_batches
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.calibration.noise_change import compare_sensor, FixedTaus, sentence
from gyro_noise_ros.calibration.static_record import CHANNELS
from gyro_noise_ros.cli.emulator import board_from_args
from gyro_noise_ros.core.readout import read_allan
from gyro_noise_ros.units import RAD_TO_DEG, STANDARD_GRAVITY_M_S2
import numpy as np
from reliability_verdicts import _batches, _lower95, _upper95, emulator_argv

SENSORS = ('accel', 'gyro')
HERE = os.path.dirname(os.path.abspath(__file__))
ADIS = os.path.join(os.environ.get('GYRO_NOISE_REAL_DATA', os.path.join(
    HERE, '..', '..', '..', 'shared', 'data', 'real')), 'adis16405_static')


def _summary(st):
    """Per channel the fixed-tau data (or why not), the bias stability and its tau."""
    out = {}
    for ch, r in st.channels.items():
        f = r.fixed
        entry = {'fixed': f if isinstance(f, str) else {
            'tau_s': f.tau_s.tolist(), 'avar': f.avar.tolist(), 'edf': f.edf.tolist(),
            'noise_alpha': f.noise_alpha.tolist(), 'm': f.m.tolist(), 'rate_hz': f.rate_hz,
            'n_samples': f.n_samples}}
        if r.allan is not None:
            ro = read_allan(r.allan)
            entry['floor'] = [ro.bias_stability_rad_s, ro.bias_stability_tau_s,
                              bool(ro.bias_stability_upper_bound)]
            entry['curve'] = [np.asarray(r.allan.tau_s).tolist(),
                              np.asarray(r.allan.adev).tolist()]
        out[ch] = entry
    return {'rate_hz': st.rate_hz, 'duration_s': st.duration_s, 'samples': st.samples,
            'left_out': st.left_out, 'cut': st.cut, 'channels': out}


def _cached(key, cache, make):
    path = os.path.join(cache, key + '.json') if cache else None
    if path and os.path.exists(path):
        with open(path) as fh:
            return json.load(fh)
    t0 = time.time()
    out = make()
    out['cpu_s'] = time.time() - t0
    if path:
        os.makedirs(cache, exist_ok=True)
        with open(path + '.tmp', 'w') as fh:
            json.dump(out, fh)
        os.replace(path + '.tmp', path)
    print(f'  {key}: {out["cpu_s"]:.0f} s', file=sys.stderr, flush=True)
    return out


def emulated(seed, hours, stress, cache, odr=104.0):
    argv = emulator_argv(seed, odr, hours, stress)
    key = 'noise_' + '_'.join(argv).replace('--', '')

    def make():
        # generated once and held (4 h: 72 MB), read twice by the tool's two passes
        held = list(_batches(board_from_args(argv), int(round(hours * 3600 * odr))))
        return _summary(static_from_batches(lambda: iter(held),
                                            source='portenta_emulator ' + ' '.join(argv)))
    return _cached(key, cache, make)


def _adis_batches(run):
    z = np.load(os.path.join(ADIS, f'adis_16405_imu{run}.npz'))
    gyro = np.deg2rad(z['gyro_dps'])
    accel = z['accel_g'] * STANDARD_GRAVITY_M_S2
    t = np.arange(gyro.shape[0]) / float(z['fs_hz'])
    for k in range(0, gyro.shape[0], 65536):
        yield float(z['fs_hz']), t[k:k + 65536], accel[k:k + 65536], gyro[k:k + 65536]


def adis(run, cache):
    return _cached(f'noise_adis_imu{run}', cache, lambda: _summary(
        static_from_batches(lambda: _adis_batches(run), source=f'adis_16405_imu{run}')))


def _fixed(entry):
    f = entry['fixed']
    if isinstance(f, str):
        return f
    return FixedTaus(np.array(f['tau_s']), np.array(f['avar']), np.array(f['edf']),
                     np.array(f['noise_alpha']), np.array(f['m']), f['rate_hz'], f['n_samples'])


def verdict(before, after, sensor, tolerance=0.3):
    chans = [c for c in CHANNELS if c.startswith(sensor)]
    return compare_sensor(sensor, {c: _fixed(before['channels'][c]) for c in chans},
                          {c: _fixed(after['channels'][c]) for c in chans}, tolerance=tolerance)


def _pairs(hours, n_null, n_stress, cache):
    null = [(emulated(1000 + i, hours, False, cache), emulated(2000 + i, hours, False, cache))
            for i in range(n_null)]
    stress = [(emulated(1000 + i, hours, False, cache), emulated(3000 + i, hours, True, cache))
              for i in range(n_stress)]
    return null, stress


def _count(pairs, tolerance=0.3):
    """Channels beyond (a tau beyond), sensors by verdict, tests beyond, median decide (h)."""
    ch_beyond = 0
    sens = {'beyond': 0, 'within': 0, 'undetermined': 0}
    decide = []
    quotes = []
    widest = 1.0
    for b, a in pairs:
        for s in SENSORS:
            v = verdict(b, a, s, tolerance)
            sens[v.verdict] += 1
            ch_beyond += len({t.channel for t in v.tests if t.verdict == 'beyond'})
            widest = max([widest] + [math.exp(abs(math.log(t.ratio))) for t in v.tests])
            if v.decide_record_s:
                decide.append(v.decide_record_s / 3600)
            if v.decisive is not None and v.verdict == 'beyond':
                quotes.append(v.decisive.ratio)
    return ch_beyond, sens, decide, quotes, widest


def part_emulator(cache, pairs, stress_pairs):
    null, stress = _pairs(4.0, pairs, stress_pairs, cache)
    print(f'\n### Emulator, 4-h records at 104 Hz: {pairs} unstressed pairs, {stress_pairs} '
          'unstressed -> --stress pairs\n')
    print('| pairs | channels | channels beyond | sensors beyond / within / undetermined | '
          'records that would decide (median, h) | ratio quoted when beyond (median) | largest '
          'ratio either way |')
    print('|---|---|---|---|---|---|---|')
    rows = {}
    for name, pl in (('unstressed -> unstressed', null), ('unstressed -> --stress', stress)):
        ch, sens, decide, quotes, widest = _count(pl)
        rows[name] = (ch, sens, len(pl))
        med = f'{np.median(decide):.3g}' if decide else '-'
        q = f'x{np.median(quotes):.2f}' if quotes else '-'
        print(f'| {name} | {6 * len(pl)} | {ch} | {sens["beyond"]} / {sens["within"]} / '
              f'{sens["undetermined"]} of {2 * len(pl)} | {med} | {q} | x{widest:.2f} |')
    ch, sens, n = rows['unstressed -> unstressed']
    chs, senss, ns = rows['unstressed -> --stress']
    print(f'\nFalse alarms: {ch} of {6 * n} channels beyond (one-sided 95 % upper bound '
          f'{100 * _upper95(ch, 6 * n):.1f} %), {sens["beyond"]} of {2 * n} sensors. Detection: '
          f'{senss["beyond"]} of {2 * ns} stressed sensors beyond '
          f'({100 * senss["beyond"] / (2 * ns):.0f} %, one-sided 95 % lower bound '
          f'{100 * _lower95(senss["beyond"], 2 * ns):.0f} %), '
          f'{chs} of {6 * ns} channels.')
    b, a = stress[0]
    print(f'\nFor example (seeds 1000 -> 3000 --stress): {sentence(verdict(b, a, "gyro"))}')


def part_lengths(cache, pairs, long_pairs):
    print('\n### Against record length (104 Hz, the same model)\n')
    print('| record (h) | unstressed pairs | sensors beyond (false alarm) | stressed pairs | '
          'stressed sensors beyond | within | undetermined |')
    print('|---|---|---|---|---|---|---|')
    for hours, n in ((1.0, pairs), (4.0, pairs), (12.0, long_pairs)):
        null, stress = _pairs(hours, n, n, cache)
        _, sn, _, _, _ = _count(null)
        _, ss, _, _, _ = _count(stress)
        print(f'| {hours:g} | {n} | {sn["beyond"]} of {2 * n} | {n} | {ss["beyond"]} of '
              f'{2 * n} ({100 * ss["beyond"] / (2 * n):.0f} %) | {ss["within"]} | '
              f'{ss["undetermined"]} |')


def part_real(cache):
    runs = {k: adis(k, cache) for k in range(1, 7)}
    print('\n### The six ADIS16405 runs: all 15 pairs (an unchanged sensor)\n')
    print('| pair | accelerometer | largest ratio (accel) | gyroscope | largest ratio (gyro) |')
    print('|---|---|---|---|---|')
    worst = {(s, tau): 1.0 for s in SENSORS for tau in (1.0, 10.0, 30.0)}
    count = {s: {'beyond': 0, 'within': 0, 'undetermined': 0} for s in SENSORS}
    for i, j in itertools.combinations(range(1, 7), 2):
        cells = []
        for s in SENSORS:
            v = verdict(runs[i], runs[j], s)
            count[s][v.verdict] += 1
            top = max(v.tests, key=lambda t: abs(math.log(t.ratio)))
            for t in v.tests:
                worst[(s, t.tau_s)] = max(worst[(s, t.tau_s)], math.exp(abs(math.log(t.ratio))))
            cells += [v.verdict, f'x{top.ratio:.2f} at {top.tau_s:g} s ({top.channel})']
        print(f'| {i}-{j} | ' + ' | '.join(cells) + ' |')
    for s in SENSORS:
        c = count[s]
        print(f'\n{s}: {c["beyond"]} beyond, {c["within"]} within, {c["undetermined"]} '
              'undetermined of 15 pairs.', end='')
    print('\n\nLargest ratio between two runs (either way) at each fixed tau, all 15 pairs: ' +
          '; '.join(f'{s} ' + ', '.join(f'{worst[(s, tau)]:.2f} at {tau:g} s'
                                        for tau in (1.0, 10.0, 30.0)) for s in SENSORS) + '.')
    print('\n| run | gyro_x bias stability (deg/s) | at tau (s) | ADEV at 44 s (deg/s) | '
          'static-segment rule (core/segments) |')
    print('|---|---|---|---|---|')
    for k, r in runs.items():
        e = r['channels']['gyro_x']
        tau, adev = (np.array(v) for v in e['curve'])
        at = float(np.exp(np.interp(math.log(44.0), np.log(tau), np.log(adev))))
        bound = ' (upper bound)' if e['floor'][2] else ''
        print(f'| imu{k} | {e["floor"][0] * RAD_TO_DEG:.5f}{bound} | {e["floor"][1]:.4g} | '
              f'{at * RAD_TO_DEG:.5f} | {r.get("cut") or "static throughout"} |')


def _write_adis_bag(run, path):
    stamps = None
    with ImuBagWriter(path, temperature_topic=None) as w:
        for rate, t, accel, gyro in _adis_batches(run):
            stamps = 1_700_000_000_000_000_000 + np.round(t * 1e9).astype(np.int64)
            w.write_imu(stamps, gyro, accel)


def _cli(args, out):
    subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.reliability', *args, '--no-figures',
                    '--no-html', '--out', out], check=True, capture_output=True, text=True)
    with open(os.path.join(out, 'reliability.json')) as fh:
        return json.load(fh)['overall']


def part_cli(cache):
    print('\n### Through the tools\n')
    print('| pair | sensor | gyro_noise_reliability | in-process (this script) | same |')
    print('|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as tmp:
        bags = {}
        for name, seed, stress in (('a', 1000, False), ('s', 3000, True)):
            argv = emulator_argv(seed, 104.0, 1.0, stress)
            bags[name] = os.path.join(tmp, name)
            subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.emulator', *argv,
                            '--write-bag', bags[name]], check=True, capture_output=True)
        tool = _cli(['--before-static', bags['a'], '--after-static', bags['s']],
                    os.path.join(tmp, 'out1'))
        here = {s: verdict(emulated(1000, 1.0, False, cache), emulated(3000, 1.0, True, cache),
                           s) for s in SENSORS}
        for s in SENSORS:
            same = tool[s]['sentence'] == sentence(here[s])
            print(f'| emulator 1 h, seed 1000 -> 3000 --stress | {s} | {tool[s]["verdict"]} | '
                  f'{here[s].verdict} | {"yes" if same else "NO"} |')
        for run in (4, 5):
            _write_adis_bag(run, os.path.join(tmp, f'imu{run}'))
        tool = _cli(['--before-static', os.path.join(tmp, 'imu4'), '--after-static',
                     os.path.join(tmp, 'imu5'), '--gravity', '9.80665'],
                    os.path.join(tmp, 'out2'))
        for s in SENSORS:
            v = verdict(adis(4, cache), adis(5, cache), s)
            same = tool[s]['sentence'] == sentence(v)
            print(f'| ADIS16405 imu4 -> imu5 | {s} | {tool[s]["verdict"]} | {v.verdict} | '
                  f'{"yes" if same else "NO"} |')


def _run(args):
    t0 = time.time()
    parts = ('emulator', 'lengths', 'real', 'cli') if args.part == 'all' else (args.part,)
    if 'emulator' in parts:
        part_emulator(args.cache, args.pairs, args.stress_pairs)
    if 'lengths' in parts:
        part_lengths(args.cache, args.pairs, args.long_pairs)
    if 'real' in parts:
        part_real(args.cache)
    if 'cli' in parts:
        part_cli(args.cache)
    print(f'\n({time.time() - t0:.0f} s wall for this run, cached records not recomputed; load '
          f'average {os.getloadavg()[0]:.1f})')


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--part', choices=('emulator', 'lengths', 'real', 'cli', 'all'),
                   default='all')
    p.add_argument('--cache', help='folder for per-record results (resumable)')
    p.add_argument('--pairs', type=int, default=10)
    p.add_argument('--stress-pairs', type=int, default=10)
    p.add_argument('--long-pairs', type=int, default=6, help='pairs of 12-h records')
    p.add_argument('--write', action='store_true', help='update docs/reliability.md (--part all)')
    args = p.parse_args(argv)
    if args.write and args.part != 'all':
        p.error('--write needs --part all')
    if args.write:
        print_and_write(lambda: _run(args), 'noise_verdicts.py', 'reliability.md',
                        argv if argv is not None else sys.argv[1:])
        return 0
    _run(args)
    return 0


if __name__ == '__main__':
    sys.exit(main())
