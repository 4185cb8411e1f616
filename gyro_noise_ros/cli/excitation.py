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
gyro_noise_excitation: sine-dwell and sine-sweep signal checks (paper 001 section 5.3).

Usage::

    gyro_noise_excitation BAG [BAG_AFTER] --sensor accel|gyro --axis x|y|z
        (--dwell FREQ_HZ | --sweep F0_HZ F1_HZ RATE_HZ_S) [--reference-topic T] [--topic T]
        [--harmonics H] --out DIR

Sine dwell: estimated frequency and amplitude, per-cycle amplitude statistics (the paper's
"amplitude stability") and THD. Sine sweep: amplitude against instantaneous frequency, rising and
falling, and its deviation from the reference channel (``--reference-topic``: a second
``sensor_msgs/Imu`` topic in the same bag, e.g. the shaker's feedback accelerometer, same axis)
when one is recorded. With BAG_AFTER, before and after side by side. Writes ``excitation.json``,
``excitation.md`` and ``excitation_before.png`` (``excitation_after.png``): the whole acquisition
and the waveform detail (paper Figures 7-12). Methods: :mod:`gyro_noise_ros.calibration.
excitation`.

Exit codes: 0 ok, 2 bad option (frequency at or above Nyquist), 3 unreadable recording,
4 data cannot be analysed (NaN/Inf samples, fewer than 3 cycles, no sine above the noise).
"""

import argparse
import json
import math
import os
import sys

import numpy as np

from ._common import run_cli
from .. import __version__
from ..calibration import records
from ..calibration.excitation import DEFAULT_HARMONICS, sine_dwell, sine_sweep
from ..calibration.sixpos import STANDARD_GRAVITY
from ..errors import ParameterError

PROG = 'gyro_noise_excitation'


def build_parser():
    """
    Return the argument parser of gyro_noise_excitation.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        description='Sine dwell / sine sweep signal checks (paper 001 section 5.3).')
    p.add_argument('bags', nargs='+', metavar='BAG', help='recording, and optionally the one '
                   'taken after the stress')
    p.add_argument('--sensor', required=True, choices=('accel', 'gyro'))
    p.add_argument('--axis', required=True, choices=('x', 'y', 'z'))
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument('--dwell', type=float, metavar='FREQ_HZ', help='sine dwell frequency (Hz)')
    mode.add_argument('--sweep', type=float, nargs=3, metavar=('F0_HZ', 'F1_HZ', 'RATE_HZ_S'),
                      help='sine sweep band (Hz) and rate (Hz/s)')
    p.add_argument('--reference-topic', metavar='T',
                   help='sensor_msgs/Imu topic of the reference sensor (same axis)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic of the sensor under test')
    p.add_argument('--harmonics', type=int, default=DEFAULT_HARMONICS,
                   help='harmonics in the THD (those below Nyquist)')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (default: from the stamps)')
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    p.add_argument('--no-figures', action='store_true', help='skip the PNG figures')
    return p


def _channel(args, accel, gyro):
    i = 'xyz'.index(args.axis)
    return (accel if args.sensor == 'accel' else gyro)[:, i]


def _lst(a):
    return [None if not math.isfinite(float(v)) else float(v) for v in np.ravel(a)]


def analyze(path, args):
    """
    Analyse one recording; return (JSON entry, result, t, x).

    Parameters
    ----------
    path : path
        Recording.
    args : argparse.Namespace
        Parsed options.

    Returns
    -------
    tuple

    """
    rate, t, accel, gyro = records.read_imu(path, topic=args.topic, rate_hz=args.rate_hz)
    x = _channel(args, accel, gyro)
    u = 'm_s2' if args.sensor == 'accel' else 'rad_s'
    entry = {'source': str(path), 'rate_hz': rate, 'samples': int(x.size)}
    if args.dwell is not None:
        r = sine_dwell(x, rate, args.dwell, harmonics=args.harmonics)
        entry.update({
            'frequency_hz': r.frequency_hz, f'amplitude_{u}': r.amplitude,
            f'offset_{u}': r.offset, f'cycle_amplitude_mean_{u}': r.cycle_amplitude_mean,
            f'cycle_amplitude_std_{u}': r.cycle_amplitude_std,
            f'cycle_amplitude_min_{u}': r.cycle_amplitude_min,
            f'cycle_amplitude_max_{u}': r.cycle_amplitude_max,
            'amplitude_stability': r.amplitude_stability, 'thd': r.thd,
            f'harmonics_{u}': _lst(r.harmonics), f'residual_rms_{u}': r.residual_rms,
            'start_s': r.start_s, 'duration_s': r.duration_s, 'cycles': r.cycles})
        if args.sensor == 'accel':
            entry['amplitude_g'] = r.amplitude / STANDARD_GRAVITY
        return entry, r, t, x
    ref = None
    if args.reference_topic:
        # both topics share the bag's clock: absolute stamps, reference put on the sensor's
        _, ta, _, _ = records.read_imu(path, topic=args.topic, rate_hz=args.rate_hz, t0_ns=0)
        _, rt, racc, rgyr = records.read_imu(path, topic=args.reference_topic, t0_ns=0)
        ref = np.interp(ta, rt, _channel(args, racc, rgyr))
    f0, f1, rate_hz_s = args.sweep
    r = sine_sweep(x, rate, f0, f1, rate_hz_s, reference=ref)
    entry.update({'bin_hz': _lst(r.bin_hz), f'amplitude_up_{u}': _lst(r.amplitude_up),
                  f'amplitude_down_{u}': _lst(r.amplitude_down)})
    if ref is not None:
        entry.update({f'reference_up_{u}': _lst(r.reference_up),
                      f'reference_down_{u}': _lst(r.reference_down),
                      'deviation_up': _lst(r.deviation_up),
                      'deviation_down': _lst(r.deviation_down)})
        dev = np.concatenate([r.deviation_up, r.deviation_down])
        dev = dev[np.isfinite(dev)]
        entry['max_abs_deviation'] = float(np.max(np.abs(dev))) if dev.size else None
    return entry, r, t, x


def plot(path, args, label, result, t, x):
    """
    Draw the whole acquisition and the waveform detail (paper 001 Figures 7-12).

    Parameters
    ----------
    path : path
        PNG file.
    args : argparse.Namespace
        Parsed options.
    label : str
        'before' or 'after'.
    result : DwellResult or SweepResult
        Analysis.
    t, x : numpy.ndarray
        Time (s) and samples.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    scale, unit = ((1.0 / STANDARD_GRAVITY, 'g') if args.sensor == 'accel' else
                   (180.0 / math.pi, 'deg/s'))
    fig, (pa, pb) = plt.subplots(1, 2, figsize=(11, 4.2))
    pa.plot(t, x * scale, lw=0.5)
    pa.set_xlabel('time (s)')
    pa.set_ylabel(f'{args.sensor} {args.axis} ({unit})')
    pa.set_title(f'(a) whole acquisition, {label}')
    if args.dwell is not None:
        lo = int(result.start_s * len(t) / max(t[-1], 1e-9))
        n = int(4 * len(t) / max(t[-1], 1e-9) / result.frequency_hz)
        pb.plot(t[lo:lo + n], x[lo:lo + n] * scale, '.-', lw=0.8, ms=3)
        pb.set_xlabel('time (s)')
        pb.set_title(f'(b) wave form: {result.frequency_hz:.3f} Hz, amplitude '
                     f'{result.amplitude * scale:.4g} {unit}, THD {100 * result.thd:.2f} %',
                     fontsize=9)
    else:
        pb.plot(result.bin_hz, result.amplitude_up * scale, 'o-', label='rising frequency')
        pb.plot(result.bin_hz, result.amplitude_down * scale, 's-', label='falling frequency')
        if result.reference_up is not None:
            pb.plot(result.bin_hz, result.reference_up * scale, 'k--', lw=1, label='reference')
        pb.set_xlabel('instantaneous frequency (Hz)')
        pb.set_ylabel(f'amplitude ({unit})')
        pb.set_title('(b) amplitude against frequency', fontsize=9)
        pb.legend(fontsize=8)
    for panel in (pa, pb):
        panel.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(doc):
    """
    Return ``excitation.md``.

    Parameters
    ----------
    doc : dict
        The ``excitation.json`` document.

    Returns
    -------
    str

    """
    sides = [s for s in ('before', 'after') if doc.get(s)]
    out = [f'# Excitation check ({doc["mode"]}, {doc["sensor"]} {doc["axis"]})', '',
           '| quantity | ' + ' | '.join(sides) + ' |', '|---|' + '---|' * len(sides)]
    keys = [k for k in doc[sides[0]] if not isinstance(doc[sides[0]][k], list)
            and k not in ('source',)]
    for k in keys:
        vals = []
        for s in sides:
            v = doc[s].get(k)
            vals.append(f'{v:.6g}' if isinstance(v, float) else str(v))
        out.append(f'| {k} | ' + ' | '.join(vals) + ' |')
    if doc['mode'] == 'sweep':
        u = doc['unit']
        for s in sides:
            e = doc[s]
            out += ['', f'## {s}: amplitude per frequency bin ({u})', '',
                    '| f (Hz) | rising | falling | deviation rising | deviation falling |',
                    '|---|---|---|---|---|']
            for k, f in enumerate(e['bin_hz']):
                def g(name):
                    v = e.get(name)
                    return 'n/a' if v is None or v[k] is None else f'{v[k]:.4g}'
                out.append(f'| {f:.3f} | {g(f"amplitude_up_{u}")} | {g(f"amplitude_down_{u}")} '
                           f'| {g("deviation_up")} | {g("deviation_down")} |')
    if doc.get('change'):
        out += ['', 'Change after/before: ' + ', '.join(
            f'{k} {v:+.4g}' for k, v in doc['change'].items() if v is not None)]
    return '\n'.join(out) + '\n'


def _body(argv):
    args = build_parser().parse_args(argv)
    if len(args.bags) > 2:
        raise ParameterError(f'give one recording, or two (before and after); got '
                             f'{len(args.bags)}')
    if args.harmonics < 1:
        raise ParameterError(f'--harmonics must be >= 1, got {args.harmonics}')
    if args.reference_topic and args.dwell is not None:
        raise ParameterError('--reference-topic applies to --sweep')
    u = 'm_s2' if args.sensor == 'accel' else 'rad_s'
    doc = {'sensor': args.sensor, 'axis': args.axis,
           'mode': 'dwell' if args.dwell is not None else 'sweep', 'unit': u,
           'nominal': ({'frequency_hz': args.dwell} if args.dwell is not None else
                       dict(zip(('f0_hz', 'f1_hz', 'rate_hz_s'), args.sweep))),
           'version': __version__}
    plots = []
    for side, path in zip(('before', 'after'), args.bags):
        entry, res, t, x = analyze(path, args)
        doc[side] = entry
        plots.append((side, res, t, x))
    if 'after' in doc and args.dwell is not None:
        b, a = doc['before'], doc['after']
        doc['change'] = {
            'amplitude_relative': a[f'amplitude_{u}'] / b[f'amplitude_{u}'] - 1.0,
            'frequency_hz': a['frequency_hz'] - b['frequency_hz'],
            'amplitude_stability': a['amplitude_stability'] - b['amplitude_stability'],
            'thd': a['thd'] - b['thd']}
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'excitation.json'), 'w') as fh:
        json.dump(doc, fh, indent=2)
    with open(os.path.join(args.out, 'excitation.md'), 'w') as fh:
        fh.write(markdown(doc))
    if not args.no_figures:
        for side, res, t, x in plots:
            plot(os.path.join(args.out, f'excitation_{side}.png'), args, side, res, t, x)
    for side, _, _, _ in plots:
        e = doc[side]
        if args.dwell is not None:
            print(f'{side}: {e["frequency_hz"]:.4f} Hz, amplitude {e[f"amplitude_{u}"]:.5g} '
                  f'{u}, amplitude stability {100 * e["amplitude_stability"]:.2f} %, '
                  f'THD {100 * e["thd"]:.2f} %')
        else:
            dev = e.get('max_abs_deviation')
            print(f'{side}: sweep analysed in {len(e["bin_hz"])} bins' + (
                '' if dev is None else f', largest deviation from the reference '
                f'{100 * dev:.2f} %'))
    print(f'wrote {os.path.join(args.out, "excitation.json")}, excitation.md')
    return 0


def main(argv=None):
    """
    Run gyro_noise_excitation.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
