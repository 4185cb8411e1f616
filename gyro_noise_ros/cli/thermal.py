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
gyro_noise_thermal: fit, apply and compare temperature-drift / denoising methods (paper 002).

Usage::

    gyro_noise_thermal fit BAG [BAG ...] [--topic T] [--temperature-topic T] [--method M]
        [--scheduler ADDRESS] --out DIR
    gyro_noise_thermal apply BAG --model DIR/model.json --out OUT
    gyro_noise_thermal compare TRAIN_BAG TEST_BAG --out DIR [--methods M,M,...]
        [--scheduler ADDRESS]
    gyro_noise_thermal simulate --seed S --out DIR [--hours H] [--rate-hz R] [--compress X]
        [--storage sqlite3|mcap] [--temperature-rate-hz R] [--no-hysteresis]

``fit`` writes DIR/model.json and a training report (DIR/training.md, training.json, figures);
``apply`` writes OUT/compensated/ (rosbag2), OUT/metrics.json and OUT/report.md with figures;
``compare`` trains every method on TRAIN_BAG and scores it on TEST_BAG (never the same run) in
one table. Formats, metric definitions and exit codes: ``docs/thermal.md``.
"""

import argparse
import copy
import dataclasses
import json
import math
from pathlib import Path
import sys
import time

import numpy as np

from ._common import run_cli
from .. import __version__
from ..cluster import make_executor
from ..errors import ClusterError, GyroNoiseError, InputDataError, ParameterError
from ..outputs import make_out_dir
from ..thermal import methods as registry
from ..thermal import report
from ..thermal.bag_io import (DEFAULT_MAX_GAP_S, join_runs, read_thermal_run,
                              write_compensated)
from ..thermal.metrics import (DEFAULT_AMPLITUDE_RAD_S, DEFAULT_F_HI_HZ, DEFAULT_F_LO_HZ,
                               evaluate_method, noise_metrics, RAD2DEG)
from ..thermal.run import DEFAULT_RATE_WINDOW_S

PROG = 'gyro_noise_thermal'

#: Definitions written into metrics.json and the reports (docs/thermal.md says the same).
DEFINITIONS = {
    'arw_deg_sqrt_h': 'angle random walk: the -1/2 line of one contiguous white-noise region of '
                      'the overlapping Allan deviation, read at tau = 1 s (IEEE 952; the one '
                      'readout, core/readout.py)',
    'arw_slope': 'free log-log slope of the Allan deviation over the taus N was read from '
                 '(-0.5 = white)',
    'bias_stability_deg_h': 'Allan deviation where its usable curve stops falling (not divided '
                            'by 0.664), as datasheets and paper 002 Figure 19 quote it; the one '
                            'readout, core/readout.py; an upper bound (tables: <=) when '
                            'bias_stability_upper_bound, the curve not seen to turn up',
    'noise_path': 'white noise the size of the run noise (fixed seed) added to the run; '
                  'arw_gain is the ARW of the response of the method to it (output with minus '
                  'output without) over the ARW of that noise: the arw_ratio of the verdict, 1 '
                  'for any drift model, free of the drift that leaks into the ADEV of the output',
    'residual_drift_deg_s': 'standard deviation (ddof 1) of the means of consecutive 60-s windows',
    'minus_3db_hz': 'first frequency where the gain to injected motion falls below 1/sqrt(2) '
                    '(bound: measured / below / above the measured band)',
    'step_precursor': 'largest change of the step response in the last fifth of the window '
                      'before the step (> 0.05: non-causal)',
    'step_lead_s': 'how long before a step the response first moves by more than 5 % of it: '
                   'the look-ahead of a non-causal method, the latency a causal version of it '
                   'would add',
    'bandwidth_small_signal': 'the same injection scaled to the white-noise sigma of the run '
                              '(std of first differences / sqrt 2): what a nonlinear method '
                              'does to motion the size of the noise',
    'arw_from_bandwidth': 'ARW down by more than 10 % while motion at 0.1-1 Hz (large or '
                          'noise-sized) or a held step passes with gain below 0.9',
}


def _add_bag_options(p):
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the single Imu topic)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (default: the single one, or the one in '
                        "the Imu topic's namespace)")
    p.add_argument('--max-gap-s', type=float, default=DEFAULT_MAX_GAP_S,
                   help=f'longest accepted hole in the temperature stream, s '
                        f'({DEFAULT_MAX_GAP_S:g})')


def _add_fit_options(p):
    p.add_argument('--seed', type=int, default=0, help='seed of stochastic training (0)')
    p.add_argument('--min-range-c', type=float, default=registry.DEFAULT_MIN_RANGE_C,
                   help='smallest training temperature span, degC '
                        f'({registry.DEFAULT_MIN_RANGE_C:g})')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='Dask scheduler (tcp://host:8786): evaluate the MOPSO particles of the '
                   'parallel model on that cluster (same model; pip extra dask; docs/scale.md)')


def _add_output_options(p):
    p.add_argument('--no-figures', action='store_true', help='write no PNG figures')
    p.add_argument('--quiet', action='store_true', help='print only errors')


def _add_score_options(p):
    p.add_argument('--amplitude-deg-s', type=float, default=DEFAULT_AMPLITUDE_RAD_S * RAD2DEG,
                   help='height of the injected chirp and steps, deg/s (1)')
    p.add_argument('--f-lo-hz', type=float, default=DEFAULT_F_LO_HZ,
                   help=f'lowest frequency of the injected chirp, Hz ({DEFAULT_F_LO_HZ:g})')
    p.add_argument('--f-hi-hz', type=float, default=DEFAULT_F_HI_HZ,
                   help=f'highest frequency of the injected chirp, Hz ({DEFAULT_F_HI_HZ:g}; '
                        'capped at 0.36 x the sample rate)')
    p.add_argument('--no-small-signal', action='store_true',
                   help='skip the second injection at the size of the noise (saves one apply)')
    p.add_argument('--range-margin-c', type=float, default=registry.DEFAULT_RANGE_MARGIN_C,
                   help='refuse test temperatures further than this outside the trained range, '
                        f'degC ({registry.DEFAULT_RANGE_MARGIN_C:g}; inf disables)')


def build_parser():
    """
    Return the argument parser of gyro_noise_thermal.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, description='Temperature-drift compensation and denoising of gyro output '
        '(paper 002): fit a method, apply it with honest held-out metrics, compare all methods.')
    p.add_argument('--version', action='version', version=f'%(prog)s {__version__}')
    sub = p.add_subparsers(dest='command', required=True, metavar='COMMAND')

    f = sub.add_parser('fit', help='fit a method on one or more bags, write model.json')
    f.add_argument('bags', nargs='+', metavar='BAG', help='training recording(s)')
    f.add_argument('--out', required=True, metavar='DIR', help='output directory')
    f.add_argument('--method', default=registry.DEFAULT_METHOD,
                   help=f'method ({", ".join(registry.method_names())}; default '
                        f'{registry.DEFAULT_METHOD})')
    _add_fit_options(f)
    _add_bag_options(f)
    _add_output_options(f)

    a = sub.add_parser('apply', help='apply a model to a bag: compensated bag, metrics, report')
    a.add_argument('bag', metavar='BAG', help='recording to process (held out from training)')
    a.add_argument('--model', required=True, metavar='MODEL_JSON', help='model.json from fit')
    a.add_argument('--out', required=True, metavar='OUT', help='output directory')
    a.add_argument('--storage', choices=('sqlite3', 'mcap'),
                   help='storage of OUT/compensated (default: that of BAG; sqlite3 for ROS 1)')
    a.add_argument('--no-bag', action='store_true', help='do not write OUT/compensated')
    _add_bag_options(a)
    _add_score_options(a)
    _add_output_options(a)

    c = sub.add_parser('compare', help='train every method on one run, score on another')
    c.add_argument('train', metavar='TRAIN_BAG', help='training recording')
    c.add_argument('test', metavar='TEST_BAG', nargs='?',
                   help='held-out test recording (omit with --split-at)')
    c.add_argument('--split-at', type=float, metavar='FRACTION',
                   help='one recording only: train on its first FRACTION of time (0..1), test '
                        'on the rest (adjacent halves of one run are not independent runs; '
                        'docs/thermal.md, "Real data")')
    c.add_argument('--out', required=True, metavar='DIR', help='output directory')
    c.add_argument('--methods', default=None,
                   help='comma-separated methods (default: all known: '
                        f'{",".join(registry.method_names())})')
    _add_fit_options(c)
    _add_bag_options(c)
    _add_score_options(c)
    _add_output_options(c)

    s = sub.add_parser('simulate', help='write a seeded train/test pair of thermal bags')
    try:
        from ..thermal.simulate import add_simulate_arguments
    except ImportError:  # the simulator is optional here; _cmd_simulate says it is missing
        s.add_argument('--seed', type=int, default=0, help='seed')
        s.add_argument('--out', required=True, metavar='DIR', help='output directory')
    else:
        add_simulate_arguments(s)
    return p


# ---------------------------------------------------------------------------------------------
# fit

def _read_runs(paths, args):
    runs, bags = [], []
    for path in paths:
        run, bag = read_thermal_run(path, topic=args.topic,
                                    temperature_topic=args.temperature_topic,
                                    max_gap_s=args.max_gap_s)
        runs.append(run)
        bags.append(bag)
    return runs, bags


def _join(runs):
    # The gap keeps the trailing temperature-rate window from straddling two recordings.
    return join_runs(runs, gap_s=DEFAULT_RATE_WINDOW_S + 1.0 / runs[0].rate_hz)


def _fit(method_name, run, *, seed, sources, executor=None):
    return registry.fit_method(method_name, run, rng=np.random.default_rng(seed),
                               sources=sources, executor=executor)


def _executor(args, names):
    """Connect to --scheduler (None without one); say so when no method has work to send."""
    if args.scheduler is None:
        return None

    def distributes(name):
        try:
            return hasattr(registry.method_class(name), 'executor')
        except GyroNoiseError:  # reported by the fit itself
            return True

    pool = make_executor(1, args.scheduler, warn=lambda text: print(
        f'{PROG}: warning: {text}', file=sys.stderr, flush=True))
    if not args.quiet and not any(distributes(n) for n in names):
        print(f'{PROG}: warning: --scheduler: {", ".join(names)} has no work units to '
              'distribute (only the parallel model does); it runs here', file=sys.stderr)
    return pool


def _in_sample(run, processed):
    out = {}
    for a, axis in enumerate('xyz'):
        raw_m = noise_metrics(run.gyro_rad_s[:, a], run.rate_hz)
        proc_m = noise_metrics(processed[:, a], run.rate_hz)
        out[axis] = {'raw_residual_drift_deg_s': _num(raw_m.residual_drift_deg_s),
                     'processed_residual_drift_deg_s': _num(proc_m.residual_drift_deg_s),
                     'raw_arw_deg_sqrt_h': _num(raw_m.arw_deg_sqrt_h),
                     'processed_arw_deg_sqrt_h': _num(proc_m.arw_deg_sqrt_h)}
    return out


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _write_json(path, doc):
    Path(path).write_text(json.dumps(registry.to_jsonable(doc), indent=1, allow_nan=False) + '\n')
    return Path(path)


def _cmd_fit(args, argv):
    out = make_out_dir(args.out)
    runs, bags = _read_runs(args.bags, args)
    run = _join(runs)
    registry.check_trainable(run, min_range_c=args.min_range_c)
    pool = _executor(args, [args.method])
    try:
        started = time.monotonic()
        model = _fit(args.method, run, seed=args.seed, sources=[str(b.path) for b in bags],
                     executor=pool)
        fit_s = time.monotonic() - started
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    files = [out / 'model.json']
    registry.save_model(model.method, files[0], training=model.training)
    processed = np.asarray(model.method.apply(run), dtype=float)
    doc = {'tool': f'{PROG} fit', 'package_version': __version__, 'command': [PROG, *argv],
           'method': model.method.name, 'causal': bool(model.method.causal),
           'seed': args.seed, 'fit_time_s': fit_s, 'training': model.training.as_dict(),
           'bags': [{'path': str(b.path), 'topic': b.topic,
                     'temperature_topic': b.temperature_topic, 'samples': int(r.t_s.size),
                     'rate_hz': r.rate_hz} for b, r in zip(bags, runs)],
           'in_sample': _in_sample(run, processed),
           'note': 'in-sample numbers (the training data itself): they flatter every method; '
                   'score on another run with apply or compare'}
    figs = []
    if not args.no_figures:
        figs.append(('Temperature and raw output (cf. Fig. 10)',
                     report.plot_run(out / 'training_fig10_run.png', run)))
        figs.append(('Raw and processed training output, whole run and a 10-s zoom (cf. Fig. 18)',
                     report.plot_output(out / 'training_fig18_output.png', run, processed,
                                        label=model.method.name)))
        figs.append(('Drift removed on the training data (cf. Fig. 17)',
                     report.plot_drift(out / 'training_fig17_drift.png', run, processed,
                                       label=model.method.name)))
        fig13 = report.plot_mode_classes(
            out / 'training_fig13_classes.png', getattr(model.method, 'fit_info', None),
            title=f'{run.name}: sample entropy and class of each mode (training)')
        if fig13 is not None:
            figs.append(('Sample entropy and class of each mode (cf. Fig. 13)', fig13))
        figs.extend(_method_figures(model.method, run, out))
    files.append(_write_json(out / 'training.json', doc))
    files.append(_write_md(out / 'training.md', _training_md(doc, figs, out)))
    files.extend(p for _, p in figs if p is not None)
    if not args.quiet:
        t = model.training
        print(f'{model.method.name}: fitted on {t.samples} samples ({t.duration_s / 3600:.3g} h, '
              f'{t.temperature_min_c:.2f}..{t.temperature_max_c:.2f} degC) in {fit_s:.1f} s')
        print(f'wrote {len(files)} files to {out}')
    return 0


def _write_md(path, text):
    Path(path).write_text(text)
    return Path(path)


def _fig_md(figs, out):
    return ''.join(f'\n![{cap}]({Path(p).relative_to(out)})\n\n*{cap}*\n' for cap, p in figs)


def _method_figures(method, run, out):
    """Return the method's own figures as (caption, path or None) entries."""
    return [(caption, None if name is None else out / name)
            for name, caption in report.method_figures(method, run, out)]


def _training_md(doc, figs, out):
    t = doc['training']
    rows = [(axis, v['raw_residual_drift_deg_s'], v['processed_residual_drift_deg_s'],
             v['raw_arw_deg_sqrt_h'], v['processed_arw_deg_sqrt_h'])
            for axis, v in doc['in_sample'].items()]
    return (f'# Training report: {doc["method"]}\n\n'
            f'Trained on {", ".join(t["sources"])}: {t["samples"]} samples at '
            f'{t["rate_hz"]:.6g} Hz, temperature {t["temperature_min_c"]:.2f}..'
            f'{t["temperature_max_c"]:.2f} degC, rate {t["temperature_rate_min_c_s"]:.4g}..'
            f'{t["temperature_rate_max_c_s"]:.4g} degC/s. Causal (live-capable): '
            f'{"yes" if doc["causal"] else "no (offline only)"}. Fit time '
            f'{doc["fit_time_s"]:.1f} s.\n\n'
            f'**In-sample only** ({doc["note"]}).\n\n'
            + report.table_markdown(
                ['axis', 'raw residual drift (deg/s)', 'processed residual drift (deg/s)',
                 'raw ARW (deg/sqrt(h))', 'processed ARW (deg/sqrt(h))'],
                rows, ['', '.4g', '.4g', '.4g', '.4g'])
            + (report.figures_markdown(figs, out, method=doc['method']) if figs else ''))


# ---------------------------------------------------------------------------------------------
# apply

def _score(method, run, args, processed):
    return evaluate_method(method, run, amplitude_rad_s=args.amplitude_deg_s / RAD2DEG,
                           f_lo_hz=args.f_lo_hz, f_hi_hz=args.f_hi_hz, processed=processed,
                           small_signal=not args.no_small_signal)


def _cmd_apply(args, argv):
    model = registry.load_model(args.model)
    run, bag = read_thermal_run(args.bag, topic=args.topic,
                                temperature_topic=args.temperature_topic,
                                max_gap_s=args.max_gap_s)
    out = make_out_dir(args.out)
    t_lo, t_hi = registry.check_temperature_range(model, run.temperature_c,
                                                  margin_c=args.range_margin_c)
    if not args.no_bag and (out / 'compensated').exists():
        raise ParameterError(f'{str(out / "compensated")!r} exists; choose another --out or '
                             'remove it')
    started = time.monotonic()
    processed = np.asarray(model.method.apply(run), dtype=float)
    apply_s = time.monotonic() - started
    # the scoring applies the method again to injected runs; keep this run's diagnostics, and
    # draw the method's own figures now, while its last apply is this run (no second VMD)
    info = copy.deepcopy(getattr(model.method, 'last_info', None))
    method_figs = [] if args.no_figures else _method_figures(model.method, run, out)
    scored, processed, curves = _score(model.method, run, args, processed)
    in_sample = str(bag.path) in model.training.sources or str(Path(args.bag).resolve()) in {
        str(Path(s).resolve()) for s in model.training.sources}
    files = []
    if not args.no_bag:
        write_compensated(bag, processed, out / 'compensated', storage=args.storage)
        files.append(out / 'compensated')
    doc = {'tool': f'{PROG} apply', 'package_version': __version__, 'command': [PROG, *argv],
           'bag': str(bag.path), 'topic': bag.topic, 'temperature_topic': bag.temperature_topic,
           'samples': int(run.t_s.size), 'rate_hz': run.rate_hz,
           'duration_s': float(run.t_s[-1] - run.t_s[0]),
           'temperature_min_c': t_lo, 'temperature_max_c': t_hi,
           'model': {'path': str(args.model), 'method': model.method.name,
                     'training': model.training.as_dict(),
                     'range_margin_c': args.range_margin_c},
           'in_sample': bool(in_sample),
           'rate_mismatch': bool(abs(run.rate_hz - model.training.rate_hz)
                                 > 0.01 * model.training.rate_hz),
           'apply_time_s': apply_s, 'definitions': DEFINITIONS}
    doc.update(scored)
    figs = []
    if not args.no_figures:
        figs = _apply_figures(out, run, processed, model.method, curves, info, method_figs)
    files.append(_write_json(out / 'metrics.json', doc))
    files.append(_write_md(out / 'report.md', _apply_md(doc, figs, out)))
    files.extend(p for _, p in figs if p is not None)
    if not args.quiet:
        _print_axes(doc)
        print(f'wrote {len(files)} files to {out}')
    return 0


def _apply_figures(out, run, processed, method, curves, info, method_figs):
    name = method.name
    figs = [('Temperature and raw output (cf. Fig. 10)',
             report.plot_run(out / 'fig10_run.png', run))]
    fig13 = report.plot_mode_classes(out / 'fig13_classes.png', info,
                                     title=f'{run.name}: sample entropy and class of each mode')
    if fig13 is not None:
        figs.append(('Sample entropy and class of each mode (cf. Fig. 13)', fig13))
    figs.extend(method_figs)
    figs.append(('Raw and processed output, whole run and a 10-s zoom (cf. Fig. 18)',
                 report.plot_output(out / 'fig18_output.png', run, processed, label=name)))
    figs.append(('Drift removed, 60-s means, against time and temperature (cf. Fig. 17)',
                 report.plot_drift(out / 'fig17_drift.png', run, processed, label=name)))
    allan = {label: {axis: c[key] for axis, c in curves.items()}
             for label, key in (('raw', 'allan_raw'), (name, 'allan_processed'))}
    figs.append(('Allan deviation raw and processed (cf. Fig. 19)',
                 report.plot_allan(out / 'fig19_allan.png', allan,
                                   title=f'{run.name}: Allan deviation, raw and {name}')))
    responses = {name: {a: c['frequency'] for a, c in curves.items()}}
    steps = {name: {a: c['step'] for a, c in curves.items()}}
    if 'frequency_small' in curves['x']:
        responses[f'{name} small'] = {a: c['frequency_small'] for a, c in curves.items()}
        steps[f'{name} small'] = {a: c['step_small'] for a, c in curves.items()}
    small = responses.pop(f'{name} small', None)
    figs.append(('Response to injected motion (large and noise-sized): gain, phase, group delay',
                 report.plot_bandwidth(out / 'bandwidth.png', responses,
                                       small=None if small is None else {name: small},
                                       title=f'{name}: response to an injected chirp')))
    figs.append(('Mean normalised step response (t < 0: before the step)',
                 report.plot_steps(out / 'steps.png', steps,
                                   title=f'{name}: response to injected steps')))
    return figs


def _axis_rows(axes):
    rows = []
    for axis, v in axes.items():
        raw, proc, bw = v['raw'], v['processed'], v['bandwidth']
        rows.append((axis, raw['arw_deg_sqrt_h'], proc['arw_deg_sqrt_h'],
                     (v.get('noise_path') or {}).get('arw_gain'),
                     report.bias_stability_cell(raw), report.bias_stability_cell(proc),
                     raw['residual_drift_deg_s'], proc['residual_drift_deg_s'],
                     _bw_cell(bw), report.minus_3db_cell(v.get('bandwidth_small_signal')),
                     v['verdict']['small_signal_low_band_min_gain'],
                     bw['step_delay_50_s'], bw.get('step_lead_s'), v['verdict']['live_capable']))
    return rows


_bw_cell = report.minus_3db_cell

_AXIS_HEADER = ['axis', 'ARW raw (deg/sqrt(h))', 'ARW processed (deg/sqrt(h))',
                'ARW gain, noise path', 'bias stability raw (deg/h)',
                'bias stability processed (deg/h)',
                'residual drift raw (deg/s)', 'residual drift processed (deg/s)',
                '-3 dB, 1 deg/s motion (Hz)', '-3 dB, noise-sized motion (Hz)',
                'noise-sized min gain 0.1-1 Hz', 'step delay 50 % (s)',
                'look-ahead before a step (s)', 'live-capable']
_AXIS_SPECS = ['', '.4g', '.4g', '.3g', '', '', '.4g', '.4g', '', '', '.3g', '.3g', '.3g', '']


def _apply_md(doc, figs, out):
    inj = doc['injection']
    warn = ''
    if doc['in_sample']:
        warn += ('\n**Warning: this bag is one the model was trained on; the numbers are '
                 'in-sample and flatter the method.**\n')
    if doc['rate_mismatch']:
        warn += (f'\n**Warning: sample rate {doc["rate_hz"]:.6g} Hz differs from the training '
                 f'rate {doc["model"]["training"]["rate_hz"]:.6g} Hz.**\n')
    verdicts = ''.join(f'- **{axis}**: {v["verdict"]["text"]}\n'
                       for axis, v in doc['axes'].items())
    return (f'# {doc["method"]} on {doc["bag"]}\n\n'
            f'{doc["samples"]} samples at {doc["rate_hz"]:.6g} Hz '
            f'({doc["duration_s"] / 3600:.3g} h), temperature {doc["temperature_min_c"]:.2f}..'
            f'{doc["temperature_max_c"]:.2f} degC; model trained on '
            f'{", ".join(doc["model"]["training"]["sources"])}. Method causal (live-capable): '
            f'{"yes" if doc["causal"] else "no (offline only)"}.\n{warn}\n'
            + report.table_markdown(_AXIS_HEADER, _axis_rows(doc['axes']), _AXIS_SPECS)
            + f'\nBandwidth cost measured with a chirp {inj["f_lo_hz"]:g}..'
              f'{inj["f_hi_hz"]:.3g} Hz and steps of {inj["amplitude_deg_s"]:.3g} deg/s added '
              f'to the run{_small_text(inj)}.\n\n'
            + verdicts + '\n## Definitions\n\n'
            + ''.join(f'- `{k}`: {v}\n' for k, v in doc['definitions'].items())
            + (report.figures_markdown(figs, out, method=doc['method']) if figs else ''))


def _small_text(inj):
    amp = inj.get('small_signal_amplitude_deg_s')
    return '' if amp is None else f', and again at {amp:.3g} deg/s (the size of the noise)'


def _print_axes(doc):
    for axis, v in doc['axes'].items():
        raw, proc = v['raw'], v['processed']
        print(f"{axis}: ARW {_f(raw['arw_deg_sqrt_h'])} -> {_f(proc['arw_deg_sqrt_h'])} "
              f"deg/sqrt(h), bias stability {_f(raw['bias_stability_deg_h'])} -> "
              f"{_f(proc['bias_stability_deg_h'])} deg/h, residual drift "
              f"{_f(raw['residual_drift_deg_s'])} -> {_f(proc['residual_drift_deg_s'])} deg/s, "
              f"-3 dB {_bw_cell(v['bandwidth'])} Hz")


def _f(v):
    return 'n/a' if v is None else f'{v:.4g}'


# ---------------------------------------------------------------------------------------------
# compare

def _same_run(a, b):
    if a.t_s.size != b.t_s.size:
        return False
    return bool(np.array_equal(a.gyro_rad_s, b.gyro_rad_s))


def split_run(run, fraction):
    """
    Split one run in time: the first ``fraction`` of its duration, and the rest.

    Parameters
    ----------
    run : ThermalRun
        The recording.
    fraction : float
        Share of the duration (0 < fraction < 1) that goes to the first part.

    Returns
    -------
    first, rest : ThermalRun
        ``rest`` has its times counted from its own first sample, as a separate recording would;
        both keep the whole run's ``rate_hz``.
    cut_s : float
        Time of the cut (s from the run's first sample).

    """
    if not (math.isfinite(fraction) and 0.0 < fraction < 1.0):
        raise ParameterError(f'--split-at must be between 0 and 1, got {fraction!r}')
    t = run.t_s
    cut_s = float(t[0] + fraction * (t[-1] - t[0]))
    k = int(np.searchsorted(t, cut_s, side='left'))
    if k < 3 or t.size - k < 3:
        raise InputDataError(f'run {run.name!r}: --split-at {fraction:g} leaves fewer than 3 '
                             'samples on one side')
    first = dataclasses.replace(run, t_s=t[:k], gyro_rad_s=run.gyro_rad_s[:k],
                                temperature_c=run.temperature_c[:k],
                                name=f'{run.name} [0, {cut_s:.1f}) s')
    rest = dataclasses.replace(run, t_s=t[k:] - t[k], gyro_rad_s=run.gyro_rad_s[k:],
                               temperature_c=run.temperature_c[k:],
                               name=f'{run.name} [{cut_s:.1f}, {t[-1]:.1f}] s')
    return first, rest, cut_s


def _compare_runs(args):
    """Read TRAIN_BAG and TEST_BAG, or split TRAIN_BAG in time (--split-at)."""
    def read(path):
        return read_thermal_run(path, topic=args.topic, temperature_topic=args.temperature_topic,
                                max_gap_s=args.max_gap_s)

    if args.split_at is not None:
        if args.test is not None:
            raise ParameterError('--split-at takes one recording (TRAIN_BAG only), got two')
        if not (math.isfinite(args.split_at) and 0.0 < args.split_at < 1.0):
            raise ParameterError(f'--split-at must be between 0 and 1, got {args.split_at!r}')
        whole, bag = read(args.train)
        train, test, cut_s = split_run(whole, args.split_at)
        split = {'fraction': args.split_at, 'cut_s': cut_s, 'duration_s': float(whole.t_s[-1]),
                 'note': 'train and test are adjacent parts of one run (one power-on, one '
                         'temperature history): not independent runs'}
        end_s = split['duration_s']
        return (train, test, f'{bag.path} [0, {cut_s:.1f}) s',
                f'{bag.path} [{cut_s:.1f}, {end_s:.1f}] s', split)
    if args.test is None:
        raise ParameterError('compare needs TRAIN_BAG and TEST_BAG, or one bag and --split-at')
    if Path(args.train).resolve() == Path(args.test).resolve():
        raise ParameterError('TRAIN_BAG and TEST_BAG are the same recording; a method must be '
                             'scored on a run it was not trained on')
    (train, train_bag), (test, test_bag) = read(args.train), read(args.test)
    if _same_run(train, test):
        raise ParameterError('TRAIN_BAG and TEST_BAG hold the same samples; a method must be '
                             'scored on a run it was not trained on')
    return train, test, str(train_bag.path), str(test_bag.path), None


def _cmd_compare(args, argv):
    names = (registry.method_names() if args.methods is None
             else [m.strip() for m in args.methods.split(',') if m.strip()])
    if not names:
        raise ParameterError('--methods names no method')
    train, test, train_label, test_label, split = _compare_runs(args)
    registry.check_trainable(train, min_range_c=args.min_range_c)
    out = make_out_dir(args.out)
    results, errors, curves = {}, {}, {}
    pool = _executor(args, names)
    for name in names:
        try:
            started = time.monotonic()
            model = _fit(name, train, seed=args.seed, sources=[train_label], executor=pool)
            fit_s = time.monotonic() - started
            registry.check_temperature_range(model, test.temperature_c,
                                             margin_c=args.range_margin_c)
            started = time.monotonic()
            processed = np.asarray(model.method.apply(test), dtype=float)
            apply_s = time.monotonic() - started
            doc, processed, cur = _score(model.method, test, args, processed)
        except ClusterError:
            pool.shutdown(cancel_futures=True)  # the cluster failed, not the method: stop
            raise
        except Exception as err:  # noqa: BLE001 - reported in the table, see below
            # One method failing (missing module, a fit that diverges, a bug in it) must not
            # hide the others; its error is reported in compare.json and compare.md.
            errors[name] = f'{type(err).__name__}: {err}'
            if not args.quiet:
                print(f'{name}: not scored: {errors[name]}', file=sys.stderr)
            continue
        doc['fit_time_s'], doc['apply_time_s'] = fit_s, apply_s
        doc['model'] = registry.to_jsonable(model.method.to_dict())
        results[name], curves[name] = doc, cur
        if not args.quiet:
            print(f'{name}: scored (fit {fit_s:.1f} s, apply {apply_s:.1f} s)')
    if pool is not None:
        pool.shutdown(cancel_futures=True)
    if not results:
        raise InputDataError('no method could be trained and scored: '
                             + '; '.join(f'{k}: {v}' for k, v in errors.items()))
    summary = {'tool': f'{PROG} compare', 'package_version': __version__,
               'command': [PROG, *argv], 'train': train_label, 'test': test_label,
               'split': split,
               'seed': args.seed, 'train_rate_hz': train.rate_hz, 'test_rate_hz': test.rate_hz,
               'train_temperature_c': [float(train.temperature_c.min()),
                                       float(train.temperature_c.max())],
               'test_temperature_c': [float(test.temperature_c.min()),
                                      float(test.temperature_c.max())],
               'definitions': DEFINITIONS, 'methods': results, 'errors': errors,
               'best_held_out': _best(results)}
    figs = []
    if not args.no_figures:
        figs = _compare_figures(out, test, curves)
    files = [_write_json(out / 'compare.json', summary)]
    rows = report.compare_rows(results)
    files.append(_write_csv(out / 'compare.csv', rows))
    files.append(_write_md(out / 'compare.md', _compare_md(summary, rows, figs, out)))
    files.extend(p for _, p in figs)
    if not args.quiet:
        print(report.compare_markdown(rows))
        print(f'wrote {len(files)} files to {out}')
    return 0


def _best(results):
    """Pick the lowest mean residual drift among live-capable full-bandwidth methods."""
    best, score = None, math.inf
    for name, doc in results.items():
        axes = doc['axes'].values()
        live = all(v['verdict']['live_capable'] for v in axes)
        full = all(not v['verdict']['arw_from_bandwidth'] for v in axes)
        drift = [v['processed']['residual_drift_deg_s'] for v in axes]
        if not (live and full) or any(d is None for d in drift):
            continue
        s = float(np.mean(drift))
        if s < score:
            best, score = name, s
    return {'method': best, 'mean_residual_drift_deg_s': _num(score),
            'rule': 'lowest mean residual drift on the test run among methods that are '
                    'live-capable and do not gain ARW by removing bandwidth'}


def _write_csv(path, rows):
    import csv

    keys = [key for _, key, _ in report.COMPARE_COLUMNS]
    keys.insert(keys.index('bias_stability_deg_h') + 1, 'bias_stability_upper_bound')
    with open(path, 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(keys)
        for row in rows:
            w.writerow(['' if row.get(k) is None else row[k] for k in keys])
    return Path(path)


def _compare_md(summary, rows, figs, out):
    errs = ''.join(f'- {k}: {v}\n' for k, v in summary['errors'].items())
    best = summary['best_held_out']
    verdicts = ''.join(f'- **{name}** {axis}: {v["verdict"]["text"]}\n'
                       for name, doc in summary['methods'].items()
                       for axis, v in doc['axes'].items())
    return (f'# Held-out comparison\n\nTrained on {summary["train"]} '
            f'({summary["train_temperature_c"][0]:.2f}..{summary["train_temperature_c"][1]:.2f}'
            f' degC), scored on {summary["test"]} ({summary["test_temperature_c"][0]:.2f}..'
            f'{summary["test_temperature_c"][1]:.2f} degC), seed {summary["seed"]}.\n\n'
            + (f'**One recording split in time at {summary["split"]["fraction"]:g} of its '
               f'length: {summary["split"]["note"]}.**\n\n' if summary.get('split') else '')
            + report.compare_markdown(rows)
            + f'\nBest held-out ({best["rule"]}): **{best["method"]}**.\n\n'
            + (f'Not scored:\n\n{errs}\n' if errs else '')
            + '## Verdicts\n\n' + verdicts + '\n## Definitions\n\n'
            + ''.join(f'- `{k}`: {v}\n' for k, v in summary['definitions'].items())
            + _fig_md(figs, out))


def _compare_figures(out, test, curves):
    first = next(iter(curves.values()))
    allan = {'raw': {axis: c['allan_raw'] for axis, c in first.items()}}
    for name, cur in curves.items():
        allan[name] = {axis: c['allan_processed'] for axis, c in cur.items()}
    return [
        ('Allan deviation of every method on the test run (cf. Fig. 19)',
         report.plot_allan(out / 'compare_allan.png', allan,
                           title=f'{test.name}: Allan deviation per method (held out)')),
        ('Response to injected motion, axis x',
         report.plot_bandwidth(out / 'compare_bandwidth.png',
                               {n: {'x': c['x']['frequency']} for n, c in curves.items()},
                               small={n: {'x': c['x']['frequency_small']}
                                      for n, c in curves.items() if 'frequency_small' in c['x']},
                               title='gain (1 deg/s motion solid, noise-sized dashed), phase, '
                                     'group delay to an injected chirp (axis x)')),
        ('Mean normalised step response, axis x',
         report.plot_steps(out / 'compare_steps.png',
                           {n: {'x': c['x']['step']} for n, c in curves.items()},
                           title='response to injected steps (axis x)')),
    ]


# ---------------------------------------------------------------------------------------------
# simulate

def _cmd_simulate(args, argv):
    try:
        from ..thermal.simulate import simulate_from_args
    except ImportError as err:
        raise registry.MethodUnavailableError(
            f'the thermal simulator is not available (gyro_noise_ros.thermal.simulate: '
            f'{err})') from err
    make_out_dir(args.out)
    result = simulate_from_args(args)
    paths = result if isinstance(result, (list, tuple)) else [result]
    print(f'wrote {", ".join(str(p) for p in paths)}')
    return 0


_COMMANDS = {'fit': _cmd_fit, 'apply': _cmd_apply, 'compare': _cmd_compare,
             'simulate': _cmd_simulate}


def _body(argv):
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as err:  # argparse: usage errors exit 2, --help/--version 0
        return err.code if isinstance(err.code, int) else 2
    return _COMMANDS[args.command](args, argv)


def main(argv=None):
    """
    Run gyro_noise_thermal.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: sys.argv[1:]).

    Returns
    -------
    int
        Exit code (docs/thermal.md).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
