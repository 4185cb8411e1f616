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
gyro_noise_reliability: the before/after verdict of paper 001 (calibration, Allan, uniformity).

Usage::

    gyro_noise_reliability [--before-calibration BAG [BAG ...]] [--before-static BAG]
        [--after-calibration BAG [BAG ...]] [--after-static BAG] [--c 2] [--tolerance 0.5]
        [--topic T] [--gravity M_S2 | --latitude DEG [--height M]] [--min-static-s S] --out DIR

Any part may be absent; the report covers what was given. From the static records: the dense
overlapping Allan deviation of every accelerometer and gyro axis, the bias-instability interval
(paper 001 section 6) before and after, its relative change and a verdict per axis
(``physiological`` within +/- tolerance, ``beyond``, or ``undetermined`` with the reason), and the
change of the fitted noise terms. From the calibrations: Table 6 before/after, the uniformity
indicators and the gravity check. Writes ``reliability.json``, ``reliability.md``,
``fig6_accel.png``, ``fig6_gyro.png`` and ``before/`` ``after/`` calibration files into DIR.

Exit codes: 0 ok (some parts may be undetermined, see the report), 2 bad option or nothing
given, 3 unreadable recording, 4 a static record that cannot be analysed at all (too short for
the Allan analysis, constant, not static: one line naming it), or every given part failed, 6
``--out`` cannot be written (checked before reading anything).
"""

import argparse
import json
import math
import os
import sys

import numpy as np

from ._common import run_cli
from .. import __version__
from ..app.calibrate import (CalibrateParams, calibration_files, MG, resolve_gravity,
                             run_calibration, table6_rows)
from ..calibration import records
from ..calibration.interval import compare, DEFAULT_C, DEFAULT_MIN_EDF, DEFAULT_TOLERANCE
from ..calibration.static import DetectorSettings
from ..calibration.static_record import CHANNELS, StaticRecord, unit_of
from ..errors import InputDataError, ParameterError
from ..htmlreport.reliability import write_reliability_html
from ..outputs import atomic_write_text, make_out_dir, staged_output

PROG = 'gyro_noise_reliability'
PARTS = ('before_calibration', 'before_static', 'after_calibration', 'after_static')


def build_parser():
    """
    Return the argument parser of gyro_noise_reliability.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        description='Before/after reliability verdict (paper 001): six-position calibrations, '
        'Allan deviation and bias-instability interval of static records.')
    for part in PARTS:
        flag = '--' + part.replace('_', '-')
        if part.endswith('calibration'):
            p.add_argument(flag, nargs='+', metavar='BAG',
                           help='six-position recording(s) (one with six dwells, or six)')
        else:
            p.add_argument(flag, metavar='BAG', help='long static recording')
    p.add_argument('--c', type=float, default=DEFAULT_C,
                   help='level factor: interval where ADEV < c * sigma_min (paper: 2)')
    p.add_argument('--tolerance', type=float, default=DEFAULT_TOLERANCE,
                   help='largest relative change of the interval width still physiological')
    p.add_argument('--min-edf', type=float, default=DEFAULT_MIN_EDF,
                   help='sigma_min only among taus with at least this many degrees of freedom '
                        '(0: all taus, the plain reading of the paper)')
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the single Imu topic)')
    g = p.add_mutually_exclusive_group()
    g.add_argument('--gravity', type=float, metavar='M_S2', help='local gravity (m/s^2)')
    g.add_argument('--latitude', type=float, metavar='DEG', help='latitude (deg), WGS-84 gravity')
    p.add_argument('--height', type=float, default=0.0, metavar='M', help='height (m)')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (default: from the stamps)')
    p.add_argument('--min-static-s', type=float, default=10.0,
                   help='shortest usable calibration dwell (s)')
    p.add_argument('--no-figures', action='store_true', help='skip the PNG figures')
    p.add_argument('--no-html', action='store_true', help='write no report.html')
    return p


def analyze_static(path, *, topic=None, rate_hz=None, c=DEFAULT_C, settings=None,
                   min_edf=DEFAULT_MIN_EDF):
    """
    Stream a static record through :class:`StaticRecord`.

    Parameters
    ----------
    path : path
        Recording.
    topic : str, optional, keyword-only
        Imu topic.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz).
    c : float, keyword-only
        Level factor.
    settings : DetectorSettings, optional, keyword-only
        Static-window thresholds.
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min.

    Returns
    -------
    (dict, dict)
        Per-channel results and the record document (rate, samples, duration, static check).

    """
    rec = None
    for rate, t, accel, gyro in records.iter_imu(path, topic=topic, rate_hz=rate_hz):
        if rec is None:
            kw = {} if settings is None else {'settings': settings}
            rec = StaticRecord(rate, c=c, source=str(path), min_edf=min_edf, **kw)
        rec.update(t, accel, gyro)
    if rec is None:
        raise InputDataError(f'static record {str(path)!r} holds no Imu samples')
    results, check = rec.finish()
    if not any(r.interval.closed for r in results.values()):
        # not one channel can give its bias-instability interval: a 20 s record, a constant
        # one, a six-position record given as static... six "undetermined" and exit 0 would
        # hide that the record is not what the procedure needs
        reasons = [r.interval.reason for r in results.values()
                   if not math.isfinite(r.interval.sigma_min) and r.interval.reason]
        if reasons:
            why = reasons[0]
        else:
            longest = max(float(np.asarray(r.allan.tau_s)[-1]) for r in results.values()
                          if r.allan is not None)
            why = ('record too short: no channel has a bias-instability interval that closes '
                   f'inside it '
                   f'(longest tau {longest:.3g} s); a static record must be several times longer '
                   f'than the interval (hours for a MEMS sensor)')
        raise InputDataError(f'static record {str(path)!r} ({rec.duration_s:.1f} s, '
                             f'{rec.samples} samples) cannot be analysed: {why}')
    doc = {'source': str(path), 'rate_hz': rec.rate_hz, 'samples': rec.samples,
           'duration_s': rec.duration_s, **check}
    return results, doc


def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def _interval_entry(ch, before, after, tolerance):
    u = unit_of(ch)
    ib = before.interval if before else None
    ia = after.interval if after else None
    v = compare(ib, ia, tolerance=tolerance)
    entry = {
        'before_s': [ib.lo_s, ib.hi_s] if ib else None,
        'after_s': [ia.lo_s, ia.hi_s] if ia else None,
        'width_before_s': ib.width_s if ib else None,
        'width_after_s': ia.width_s if ia else None,
        'change': v.change, 'verdict': v.verdict, 'reason': v.reason,
        'tau_min_before_s': _num(ib.tau_min_s) if ib else None,
        'tau_min_after_s': _num(ia.tau_min_s) if ia else None,
        f'sigma_min_before_{u}': _num(ib.sigma_min) if ib else None,
        f'sigma_min_after_{u}': _num(ia.sigma_min) if ia else None,
        'reason_before': ib.reason if ib else 'not given',
        'reason_after': ia.reason if ia else 'not given',
    }
    return entry


def _terms_entry(ch, before, after):
    u = unit_of(ch)
    keys = {'noise_density': f'noise_density_{u}_per_sqrt_hz',
            'bias_instability': f'bias_instability_{u}',
            'random_walk': f'random_walk_{u}_per_sqrt_s'}
    out = {}
    for side, res in (('before', before), ('after', after)):
        if res is None or res.terms is None:
            out[side] = None
            continue
        out[side] = {}
        for k, name in keys.items():
            value, lo, hi = res.terms[k]
            out[side][name] = value
            out[side][name + '_ci'] = [lo, hi]
    if out['before'] and out['after']:
        out['ratio_after_before'] = {
            name: (out['after'][name] / out['before'][name] if out['before'][name] > 0 else None)
            for name in keys.values()}
    return out


def _calibration_entry(doc):
    if doc is None:
        return None
    keep = ('gravity_m_s2', 'accel', 'gyro', 'uniformity', 'gravity_check', 'dwells', 'sources')
    return {k: doc[k] for k in keep}


def _uniformity(cb, ca):
    out = {'before': cb['uniformity'] if cb else None, 'after': ca['uniformity'] if ca else None}
    if cb and ca:
        out['ratio_after_before'] = {
            k: (ca['uniformity'][k] / cb['uniformity'][k] if cb['uniformity'][k] > 0 else None)
            for k in cb['uniformity']}
    return out


def _summary(intervals):
    out = {}
    for sensor in ('accel', 'gyro'):
        rows = [intervals[f'{sensor}_{a}'] for a in 'xyz']
        wb = [r['width_before_s'] for r in rows if r['width_before_s'] is not None]
        wa = [r['width_after_s'] for r in rows if r['width_after_s'] is not None]
        mb = float(np.mean(wb)) if len(wb) == 3 else None
        ma = float(np.mean(wa)) if len(wa) == 3 else None
        out[sensor] = {
            'mean_width_before_s': mb, 'mean_width_after_s': ma,
            'mean_change': (ma / mb - 1.0) if (mb and ma) else None,
            'verdicts': [r['verdict'] for r in rows]}
    return out


def markdown(doc):
    """
    Return ``reliability.md`` of a reliability document.

    Parameters
    ----------
    doc : dict
        The ``reliability.json`` document.

    Returns
    -------
    str

    """
    mg = MG
    out = ['# Reliability test (paper 001): before / after', '',
           f'Bias-instability interval: tau range where ADEV < {doc["c"]:g} sigma_min; '
           f'physiological within +/-{100 * doc["tolerance"]:.0f} % of the before width.', '',
           '| channel | before (s) | after (s) | width before (s) | width after (s) | change | '
           'verdict |', '|---|---|---|---|---|---|---|']

    def rng(pair):
        if pair is None:
            return 'not given'
        return ' - '.join('open' if v is None else f'{v:.3g}' for v in pair)

    def num(v, spec):
        return 'n/a' if v is None else format(v, spec)

    for ch, e in doc['bias_instability_interval'].items():
        out.append(f'| {ch} | {rng(e["before_s"])} | {rng(e["after_s"])} | '
                   f'{num(e["width_before_s"], ".4g")} | {num(e["width_after_s"], ".4g")} | '
                   f'{num(None if e["change"] is None else 100 * e["change"], "+.0f")} % | '
                   f'{e["verdict"]} |')
    reasons = [(ch, e['reason']) for ch, e in doc['bias_instability_interval'].items()
               if e['reason']]
    if reasons:
        out += ['', 'Undetermined because:', '']
        out += [f'- {ch}: {r}' for ch, r in reasons]
    s = doc['summary']
    out += ['', 'Mean width over the three axes (paper: 420 s -> 945 s, +125 %):', '']
    for sensor, e in s.items():
        pct = None if e['mean_change'] is None else 100 * e['mean_change']
        out.append(f'- {sensor}: {num(e["mean_width_before_s"], ".4g")} s -> '
                   f'{num(e["mean_width_after_s"], ".4g")} s, change {num(pct, "+.0f")} %')
    cb, ca = doc['calibration']['before'], doc['calibration']['after']
    if cb or ca:
        out += ['', '## Six-position calibration (paper 001 Table 6)', '',
                '| | before | after |', '|---|---|---|']
        rows_b = table6_rows(cb) if cb else None
        rows_a = table6_rows(ca) if ca else None
        for k in range(6):
            name = (rows_b or rows_a)[k][0]
            unit = 'mg' if name.startswith('b') else '%'
            vb = f'{rows_b[k][1]:.3f} {unit}' if rows_b else 'not given'
            va = f'{rows_a[k][1]:.3f} {unit}' if rows_a else 'not given'
            out.append(f'| {name} | {vb} | {va} |')
        ub = doc['uniformity']['before']
        ua = doc['uniformity']['after']

        def u(d, key, scale, spec):
            return 'not given' if d is None else format(d[key] * scale, spec)

        out += [f'| std of biases (uniformity) | '
                f'{u(ub, "accel_bias_std_m_s2", 1 / mg, ".3f")} mg | '
                f'{u(ua, "accel_bias_std_m_s2", 1 / mg, ".3f")} mg |',
                f'| std of scale factors | {u(ub, "accel_scale_factor_std", 100, ".3f")} % | '
                f'{u(ua, "accel_scale_factor_std", 100, ".3f")} % |',
                f'| gravity check, mean abs(a) raw (m/s^2) | '
                f'{u(cb and cb["gravity_check"], "mean_norm_raw_m_s2", 1, ".4f")} | '
                f'{u(ca and ca["gravity_check"], "mean_norm_raw_m_s2", 1, ".4f")} |',
                f'| gravity check, leave-one-out calibrated (m/s^2) | '
                f'{u(cb and cb["gravity_check"], "loo_mean_norm_m_s2", 1, ".5f")} | '
                f'{u(ca and ca["gravity_check"], "loo_mean_norm_m_s2", 1, ".5f")} |',
                f'| gravity check verdict | '
                f'{_verdict(cb)} | {_verdict(ca)} |']
    if doc['errors']:
        out += ['', '## Parts that could not be analysed', '']
        out += [f'- {k}: {v}' for k, v in doc['errors'].items()]
    return '\n'.join(out) + '\n'


def _verdict(doc):
    if doc is None:
        return 'not given'
    return 'consistent' if doc['gravity_check']['consistent'] else 'inconsistent'


def plot_fig6(path, sensor, before, after, intervals, c):
    """
    Draw paper 001 Figure 6 for one sensor: ADEV per axis before and after, level and interval.

    Parameters
    ----------
    path : path
        PNG file.
    sensor : {'accel', 'gyro'}
        Which sensor.
    before, after : dict or None
        ``{channel: ChannelResult}`` of each static record.
    intervals : dict
        The ``bias_instability_interval`` entries.
    c : float
        Level factor.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    unit = '(m/s^2)' if sensor == 'accel' else '(rad/s)'
    fig, panels = plt.subplots(1, 2, figsize=(11, 4.6), sharey=True)
    colors = {'x': 'tab:blue', 'y': 'tab:orange', 'z': 'tab:green'}
    for panel, (side, res) in zip(panels, (('before', before), ('after', after))):
        panel.set_title(f'({"a" if side == "before" else "b"}) {side}')
        panel.set_xlabel('cluster time tau (s)')
        panel.grid(True, which='both', alpha=0.3)
        if res is None:
            panel.text(0.5, 0.5, 'not given', transform=panel.transAxes, ha='center')
            continue
        for a in 'xyz':
            r = res[f'{sensor}_{a}']
            if r.allan is None:
                continue
            col = colors[a]
            panel.loglog(r.allan.tau_s, r.allan.adev, color=col, lw=1.3, label=f'{a} axis')
            iv = r.interval
            if math.isfinite(iv.level):
                panel.axhline(iv.level, color=col, ls=':', lw=0.9)
                lo = iv.lo_s if iv.lo_s is not None else r.allan.tau_s[0]
                hi = iv.hi_s if iv.hi_s is not None else r.allan.tau_s[-1]
                panel.plot([lo, hi], [iv.level, iv.level], color=col, lw=4, alpha=0.35,
                           solid_capstyle='butt')
                for val in (iv.lo_s, iv.hi_s):
                    if val is not None:
                        panel.axvline(val, color=col, ls='--', lw=0.8)
        panel.legend(fontsize=8)
    panels[0].set_ylabel(f'Allan deviation {unit}')
    fig.suptitle(f'{sensor}: Allan deviation before/after; dotted: {c:g} sigma_min, bar and '
                 'dashed lines: bias-instability interval (bar to the edge = open end)',
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _body(argv):
    args = build_parser().parse_args(argv)
    given = {p: getattr(args, p) for p in PARTS if getattr(args, p)}
    if not given:
        raise ParameterError('nothing to analyse: give at least one of --before-calibration, '
                             '--before-static, --after-calibration, --after-static')
    if not (math.isfinite(args.c) and args.c > 1):
        raise ParameterError(f'--c must be > 1, got {args.c}')
    if not (math.isfinite(args.min_edf) and args.min_edf >= 0):
        raise ParameterError(f'--min-edf must be >= 0, got {args.min_edf}')
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise ParameterError(f'--tolerance must be >= 0, got {args.tolerance}')
    gravity = resolve_gravity(args.gravity, args.latitude, args.height)
    settings = DetectorSettings(min_static_s=args.min_static_s)
    make_out_dir(args.out)            # a file in the way fails now, not after the computation
    errors, cals, statics, docs, files = {}, {}, {}, {}, {}
    if (args.before_calibration or args.after_calibration) and gravity.warning:
        print(f'{PROG}: warning: {gravity.warning}', file=sys.stderr)
    for side in ('before', 'after'):
        bags = getattr(args, f'{side}_calibration')
        if bags:
            try:
                res = run_calibration(CalibrateParams(
                    paths=tuple(bags), gravity=gravity, topic=args.topic, rate_hz=args.rate_hz,
                    settings=settings))
            except InputDataError as err:
                errors[f'{side}_calibration'] = str(err)
                print(f'{PROG}: warning: {side} calibration: {err}', file=sys.stderr)
            else:
                cals[side] = res.as_dict()
                files[side] = calibration_files(res)
        bag = getattr(args, f'{side}_static')
        if bag:
            # a static record that cannot be analysed at all is refused (exit 4, one line)
            statics[side], docs[side] = analyze_static(
                bag, topic=args.topic, rate_hz=args.rate_hz, c=args.c, min_edf=args.min_edf)
    if len(errors) == len(given):
        raise InputDataError('nothing could be analysed: ' + '; '.join(
            f'{k}: {v}' for k, v in errors.items()))
    intervals = {ch: _interval_entry(ch, statics.get('before', {}).get(ch),
                                     statics.get('after', {}).get(ch), args.tolerance)
                 for ch in CHANNELS}
    doc = {
        'c': args.c, 'tolerance': args.tolerance, 'min_edf': args.min_edf,
        'sources': {p: given.get(p) for p in PARTS},
        'bias_instability_interval': intervals,
        'summary': _summary(intervals),
        'noise_terms': {ch: _terms_entry(ch, statics.get('before', {}).get(ch),
                                         statics.get('after', {}).get(ch)) for ch in CHANNELS},
        'uniformity': _uniformity(cals.get('before'), cals.get('after')),
        'calibration': {'before': _calibration_entry(cals.get('before')),
                        'after': _calibration_entry(cals.get('after'))},
        'gravity_check': {s: (cals[s]['gravity_check'] if s in cals else None)
                          for s in ('before', 'after')},
        'static_records': {s: docs.get(s) for s in ('before', 'after')},
        'errors': errors,
        'version': __version__,
    }
    with staged_output(args.out) as stage:
        for side, named in files.items():
            (stage / side).mkdir()
            for name, text in named.items():
                atomic_write_text(stage / side / name, text)
        atomic_write_text(stage / 'reliability.json', json.dumps(doc, indent=2) + '\n')
        atomic_write_text(stage / 'reliability.md', markdown(doc))
        if not args.no_html:
            write_reliability_html(doc, statics, stage, command=[PROG, *argv])
        if statics and not args.no_figures:
            for sensor in ('accel', 'gyro'):
                plot_fig6(stage / f'fig6_{sensor}.png', sensor, statics.get('before'),
                          statics.get('after'), intervals, args.c)
    for ch, e in intervals.items():
        if e['verdict'] != 'undetermined' or statics:
            change = 'n/a' if e['change'] is None else f'{100 * e["change"]:+.0f} %'
            print(f'{ch}: {e["verdict"]} (change {change})')
    print(f'wrote {os.path.join(args.out, "reliability.json")}, reliability.md')
    return 0


def main(argv=None):
    """
    Run gyro_noise_reliability.

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


__all__ = ['main', 'build_parser', 'analyze_static']

if __name__ == '__main__':
    sys.exit(main())
