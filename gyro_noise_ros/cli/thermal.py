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
gyro_noise_thermal: fit, apply, compare, simulate and export temperature-drift methods (paper 002).

Usage::

    gyro_noise_thermal fit BAG [BAG ...] [--topic T] [--temperature-topic T] [--method M]
        [--scheduler ADDRESS] --out DIR
    gyro_noise_thermal apply BAG --model DIR/model.json --out OUT
    gyro_noise_thermal compare TRAIN_BAG TEST_BAG --out DIR [--methods M,M,...]
        [--scheduler ADDRESS]
    gyro_noise_thermal simulate --seed S --out DIR [--shape SHAPE] [--test-shape SHAPE]
        [--hours H] [--rate-hz R] [--compress X] [--storage sqlite3|mcap]
        [--temperature-rate-hz R] [--no-hysteresis]
    gyro_noise_thermal export --model DIR/model.json --out DIR [--px4-instance I]
        [--px4-gyro-id N] [--px4-accel-id N] [--ardupilot-imu K] [--no-gyro-offsets]

Each command is argparse -> one workflow of :mod:`gyro_noise_ros.app.thermal` -> printing and
the exit code. Formats, metric definitions and exit codes: ``docs/thermal.md``.
"""

import argparse
from collections.abc import Callable, Iterable
from dataclasses import replace
import math
import sys
from typing import TypeAlias

from ._common import add_overwrite_argument, check_out_dir, run_cli
from .. import __version__
from ..app import thermal as app
from ..core.fractional import physical_memory_bytes
from ..errors import ParameterError
from ..outputs import free_bytes
from ..thermal import methods as registry
from ..thermal.bag_io import DEFAULT_MAX_GAP_S
from ..thermal.metrics import DEFAULT_AMPLITUDE_RAD_S, DEFAULT_F_HI_HZ, DEFAULT_F_LO_HZ
from ..units import RAD_TO_DEG

PROG = app.PROG
#: Profile shapes of ``simulate`` (``thermal.simulate.SHAPES``; listed here so the parser does
#: not import the simulator).
SHAPES = ('oven', 'heating', 'cooling', 'staircase', 'staircase_down', 'cycle', 'cool_reheat',
          'soak', 'sine')
#: Memory and disk of ``simulate`` per gyro sample (train and test together), measured: 1 h
#: against 0.25 h at 100 Hz (540,000 more samples) took 270 MB more peak RSS (/usr/bin/time) and
#: 276 MB more output (sqlite3 bags and truth): about 500 B each, rounded up.
SIMULATE_BYTES_PER_SAMPLE = 512


#: argparse's sub-command handle (``add_subparsers()``).
_Subparsers: TypeAlias = 'argparse._SubParsersAction[argparse.ArgumentParser]'


def _add_bag_options(p: argparse.ArgumentParser) -> None:
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the single Imu topic)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (default: the single one, or the one in '
                        "the Imu topic's namespace)")
    p.add_argument('--max-gap-s', type=float, default=DEFAULT_MAX_GAP_S,
                   help=f'longest accepted hole in the temperature stream, s '
                        f'({DEFAULT_MAX_GAP_S:g})')


def _add_fit_options(p: argparse.ArgumentParser) -> None:
    p.add_argument('--seed', type=int, default=0, help='seed of stochastic training (0)')
    p.add_argument('--min-range-c', type=float, default=registry.DEFAULT_MIN_RANGE_C,
                   help='smallest training temperature span, degC, finite and >= 0 '
                        f'({registry.DEFAULT_MIN_RANGE_C:g})')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='Dask scheduler (tcp://host:8786): evaluate the MOPSO particles of the '
                   'parallel model on that cluster (same model; pip extra dask; docs/scale.md)')


def _add_output_options(p: argparse.ArgumentParser) -> None:
    add_overwrite_argument(p)
    p.add_argument('--no-figures', action='store_true', help='write no PNG figures')
    p.add_argument('--quiet', action='store_true', help='print only errors')


def _add_score_options(p: argparse.ArgumentParser) -> None:
    p.add_argument('--amplitude-deg-s', type=float, default=DEFAULT_AMPLITUDE_RAD_S * RAD_TO_DEG,
                   help='height of the injected chirp and steps, deg/s (1)')
    p.add_argument('--f-lo-hz', type=float, default=DEFAULT_F_LO_HZ,
                   help=f'lowest frequency of the injected chirp, Hz ({DEFAULT_F_LO_HZ:g}; '
                        'the run must be 66.7 / f_lo s long)')
    p.add_argument('--f-hi-hz', type=float, default=DEFAULT_F_HI_HZ,
                   help=f'highest frequency of the injected chirp, Hz ({DEFAULT_F_HI_HZ:g}; '
                        'capped at 0.36 x the sample rate)')
    p.add_argument('--no-small-signal', action='store_true',
                   help='skip the second injection at the size of the noise (saves one apply)')
    p.add_argument('--range-margin-c', type=float, default=registry.DEFAULT_RANGE_MARGIN_C,
                   help='refuse test temperatures further than this outside the trained range, '
                        f'degC ({registry.DEFAULT_RANGE_MARGIN_C:g}; inf disables)')


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of gyro_noise_thermal.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, description='Temperature-drift compensation and denoising of gyro output '
        '(paper 002): fit a method, apply it with honest held-out metrics, compare all methods, '
        'simulate held-out runs of other shapes, export PX4/ArduPilot parameters.')
    p.add_argument('--version', action='version', version=f'%(prog)s {__version__}')
    sub = p.add_subparsers(dest='command', required=True, metavar='COMMAND')
    _add_fit_command(sub)
    _add_apply_command(sub)
    _add_compare_command(sub)
    _add_simulate_command(sub)
    _add_export_command(sub)
    return p


def _add_fit_command(sub: _Subparsers) -> None:
    """Add ``fit``: a method fitted on training bags, written as model.json."""
    f = sub.add_parser('fit', help='fit a method on one or more bags, write model.json')
    f.add_argument('bags', nargs='+', metavar='BAG', help='training recording(s)')
    f.add_argument('--out', required=True, metavar='DIR', help='output directory')
    f.add_argument('--method', default=registry.DEFAULT_METHOD,
                   help=f'method ({", ".join(registry.method_names())}; default '
                        f'{registry.DEFAULT_METHOD})')
    f.add_argument('--no-accel', action='store_true',
                   help='do not fit the accelerometer polynomial (fitted when the bags carry '
                        'linear acceleration)')
    _add_fit_options(f)
    _add_bag_options(f)
    _add_output_options(f)


def _add_apply_command(sub: _Subparsers) -> None:
    """Add ``apply``: a model applied to a held-out bag, with metrics and a report."""
    a = sub.add_parser('apply', help='apply a model to a bag: compensated bag, metrics, report')
    a.add_argument('bag', metavar='BAG', help='recording to process (held out from training)')
    a.add_argument('--model', required=True, metavar='MODEL_JSON', help='model.json from fit')
    a.add_argument('--out', required=True, metavar='OUT', help='output directory')
    a.add_argument('--storage', choices=('sqlite3', 'mcap'),
                   help='storage of OUT/compensated (default: that of BAG; sqlite3 for ROS 1)')
    a.add_argument('--no-bag', action='store_true', help='do not write OUT/compensated')
    a.add_argument('--strict', action='store_true',
                   help='refuse (exit 4) a run more than '
                        f'{100 * registry.MAX_OUTSIDE_SHARE:g} %% of which lies outside the '
                        'trained range of T or dT (default: a warning)')
    a.add_argument('--max-offset-deg-s', type=float, default=registry.MAX_SENSOR_OFFSET_DEG_S,
                   help="refuse a run whose gyro sits further than this from the model's drift "
                        'on an axis, a model of another sensor, deg/s '
                        f'({registry.MAX_SENSOR_OFFSET_DEG_S:g}; inf disables)')
    _add_bag_options(a)
    _add_score_options(a)
    _add_output_options(a)
    a.add_argument('--no-html', action='store_true', help='write no report.html')


def _add_compare_command(sub: _Subparsers) -> None:
    """Add ``compare``: every method trained on one run and scored on another."""
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
    c.add_argument('--no-html', action='store_true', help='write no report.html')


def _add_simulate_command(sub: _Subparsers) -> None:
    """Add ``simulate``: a seeded train/test pair of thermal bags."""
    s = sub.add_parser('simulate', help='write a seeded train/test pair of thermal bags')
    s.add_argument('--seed', type=int, default=0, help='seed of the train/test pair')
    s.add_argument('--out', required=True, metavar='DIR',
                   help='output directory (train/, test/, truth)')
    s.add_argument('--shape', choices=SHAPES, default='oven',
                   help="training run's oven profile (oven: paper 002's; docs/thermal_data.md)")
    s.add_argument('--test-shape', choices=SHAPES,
                   help="test run's profile (default: the training one, a replicate)")
    s.add_argument('--hours', type=float,
                   help='training run length (h); default: the whole profile')
    s.add_argument('--compress', type=float,
                   help='time compression of the oven experiment (default: fill --hours)')
    s.add_argument('--rate-hz', type=float, default=100.0, help='gyro sample rate (Hz)')
    s.add_argument('--storage', choices=('sqlite3', 'mcap'), default='sqlite3')
    s.add_argument('--temperature-rate-hz', type=float, default=52.0,
                   help='rate of the Temperature messages (Hz)')
    s.add_argument('--no-hysteresis', action='store_true',
                   help='switch the bias hysteresis off')
    add_overwrite_argument(s)


def _add_export_command(sub: _Subparsers) -> None:
    """Add ``export``: a poly3 model as PX4 and ArduPilot parameters."""
    e = sub.add_parser('export', help="a model's poly3 as PX4 TC_* and ArduPilot INS_TCAL* "
                                      'parameters, with the residual each firmware leaves')
    e.add_argument('--model', required=True, metavar='MODEL_JSON',
                   help='model.json of fit (a poly3, or any method with the poly3 fit adds)')
    e.add_argument('--out', required=True, metavar='DIR', help='output directory')
    e.add_argument('--px4-instance', type=int, default=0,
                   help='PX4 calibration instance 0..3 (TC_G0..TC_G3; 0)')
    e.add_argument('--px4-gyro-id', type=int, default=None,
                   help="PX4 TC_G<i>_ID: the gyro's 24-bit device id, as PX4 shows it in "
                        'CAL_GYRO<i>_ID (without it the block is written with TC_G_ENABLE 0)')
    e.add_argument('--px4-accel-id', type=int, default=None,
                   help="PX4 TC_A<i>_ID: the accelerometer's device id (CAL_ACC<i>_ID; without "
                        'it TC_A_ENABLE 0)')
    e.add_argument('--axes', default='x,y,z',
                   help="the autopilot's sensor X, Y, Z as signed axes of the recording, e.g. "
                        '--axes=-y,x,z (x,y,z); docs/thermal.md, "On the vehicle"')
    e.add_argument('--predict', nargs='+', default=[], metavar='BAG',
                   help='recordings to predict the residual each firmware leaves on (besides '
                        'the training sources named in model.json)')
    e.add_argument('--ardupilot-imu', type=int, default=1, help='ArduPilot IMU 1..3 (1)')
    e.add_argument('--no-gyro-offsets', action='store_true',
                   help='do not write INS_GYROFFS_*/INS_GYR<k>_CALTEMP (leave them to the '
                        "autopilot's boot calibration)")
    e.add_argument('--cal-temp-c', type=float,
                   help="ArduPilot CALTEMP of the exported gyro offsets (default: the model's "
                        'T_ref)')
    _add_bag_options(e)
    _add_output_options(e)


def _warn(args: argparse.Namespace) -> Callable[[str], None] | None:
    if args.quiet:
        return None
    return lambda text: print(f'{PROG}: warning: {text}', file=sys.stderr, flush=True)


def _bag_options(args: argparse.Namespace) -> app.BagOptions:
    return app.BagOptions(topic=args.topic, temperature_topic=args.temperature_topic,
                          max_gap_s=args.max_gap_s)


def _score_options(args: argparse.Namespace) -> app.ScoreOptions:
    for option, value in (('--amplitude-deg-s', args.amplitude_deg_s),
                          ('--f-lo-hz', args.f_lo_hz), ('--f-hi-hz', args.f_hi_hz)):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f'{option} must be a finite number > 0, got {value!r}')
    if not args.f_hi_hz > args.f_lo_hz:
        raise ParameterError(f'--f-hi-hz {args.f_hi_hz:g} must be above --f-lo-hz '
                             f'{args.f_lo_hz:g}')
    if not args.range_margin_c >= 0:  # inf disables the refusal; NaN and < 0 are refused
        raise ParameterError(f'--range-margin-c must be >= 0 (inf: off), got '
                             f'{args.range_margin_c!r}')
    return app.ScoreOptions(amplitude_deg_s=args.amplitude_deg_s, f_lo_hz=args.f_lo_hz,
                            f_hi_hz=args.f_hi_hz, small_signal=not args.no_small_signal,
                            range_margin_c=args.range_margin_c)


def _print_warnings(warnings: Iterable[str], args: argparse.Namespace) -> None:
    if not args.quiet:
        for text in warnings:
            print(f'{PROG}: warning: {text}', file=sys.stderr)


def _print_notes(notes: Iterable[str], args: argparse.Namespace) -> None:
    if not args.quiet:
        for note in notes:
            print(f'{PROG}: note: {note}', file=sys.stderr)


def _check_seed(args: argparse.Namespace) -> None:
    if args.seed < 0:  # numpy's SeedSequence takes non-negative integers
        raise ParameterError(f'--seed must be >= 0, got {args.seed}')


def _cmd_fit(args: argparse.Namespace, argv: list[str]) -> int:
    _check_seed(args)
    result = app.fit(bags=args.bags, method=args.method, seed=args.seed,
                     min_range_c=args.min_range_c, bag_options=_bag_options(args),
                     accel=not args.no_accel, scheduler=args.scheduler, warn=_warn(args),
                     figures=not args.no_figures, command=argv)
    files = app.write_fit(result, args.out, figures=not args.no_figures)
    _print_notes(result.notes, args)
    _print_warnings(result.warnings, args)
    if not args.quiet:
        t = result.model.training
        accel = ' (+ accelerometer polynomial)' if result.model.accel is not None else ''
        terms = getattr(result.model.method, 'terms', None)
        chosen = f' [terms {" ".join(terms)}, by blocked CV]' if terms else ''
        print(f'{result.model.method.name}{chosen}{accel}: fitted on {t.samples} samples '
              f'({t.duration_s / 3600:.3g} h, {t.temperature_min_c:.2f}..'
              f'{t.temperature_max_c:.2f} degC) in {result.fit_time_s:.1f} s')
        print(f'wrote {len(files)} files to {args.out}')
    return 0


def _f(v: float | None) -> str:
    return 'n/a' if v is None else f'{v:.4g}'


def _corner(bandwidth: dict) -> str:
    """Say where the -3 dB corner is: at a frequency, or beyond the measured band."""
    cell = app.bandwidth_cell(bandwidth)
    return {'> band': 'above the measured band', '< band': 'below the measured band'}.get(
        cell, f'at {cell} Hz')


def _cmd_apply(args: argparse.Namespace, argv: list[str]) -> int:
    score = replace(_score_options(args), strict=args.strict,
                    max_offset_deg_s=args.max_offset_deg_s)
    result = app.apply_model(bag=args.bag, model_path=args.model, bag_options=_bag_options(args),
                             score=score, figures=not args.no_figures, command=argv)
    files = app.write_apply(result, args.out, figures=not args.no_figures,
                            write_bag=not args.no_bag, storage=args.storage,
                            html=not args.no_html)
    _print_notes(result.notes, args)
    _print_warnings(result.warnings, args)
    if not args.quiet:
        yard = result.doc['yardstick']
        for a, (axis, v) in enumerate(result.doc['axes'].items()):
            raw, proc = v['raw'], v['processed']
            print(f"{axis}: ARW {_f(raw['arw_deg_sqrt_h'])} -> {_f(proc['arw_deg_sqrt_h'])} "
                  f"deg/sqrt(h), bias stability {_f(raw['bias_stability_deg_h'])} -> "
                  f"{_f(proc['bias_stability_deg_h'])} deg/h, residual drift "
                  f"{_f(raw['residual_drift_deg_s'])} -> {_f(proc['residual_drift_deg_s'])} "
                  f"deg/s ({_f(yard['over_floor'][a])} x the white-noise floor, "
                  f"{_f((yard.get('over_poly3') or [None] * 3)[a])} x poly3), "
                  f"-3 dB {_corner(v['bandwidth'])}")
        print(f'wrote {len(files)} files to {args.out}')
    return 0


def _cmd_compare(args: argparse.Namespace, argv: list[str]) -> int:
    _check_seed(args)
    names = None
    if args.methods is not None:
        names = [m.strip() for m in args.methods.split(',') if m.strip()]
    say = None if args.quiet else (lambda text: print(text, file=sys.stderr, flush=True))
    result = app.compare(train=args.train, test=args.test, split_at=args.split_at,
                         methods=names, seed=args.seed, min_range_c=args.min_range_c,
                         bag_options=_bag_options(args), score=_score_options(args),
                         scheduler=args.scheduler, warn=_warn(args), progress=say,
                         command=argv)
    files = app.write_compare(result, args.out, figures=not args.no_figures,
                              html=not args.no_html)
    _print_notes(result.summary.get('notes') or (), args)
    _print_warnings(result.summary.get('warnings') or (), args)
    if not args.quiet:
        from ..thermal import report

        print(report.table_markdown(app.COMPARE_HEADER, app.table_cells(result.rows),
                                    app.COMPARE_SPECS))
        print(f'wrote {len(files)} files to {args.out}')
    return 0


def _cmd_simulate(args: argparse.Namespace, argv: list[str]) -> int:
    try:
        import gyro_noise_ros.thermal.simulate  # noqa: F401 - the simulator is optional
    except ImportError as err:
        raise registry.MethodUnavailableError(
            f'the thermal simulator is not available (gyro_noise_ros.thermal.simulate: '
            f'{err})') from err
    _check_seed(args)
    _check_simulate_size(args)
    result = app.simulate(seed=args.seed, hours=args.hours, rate_hz=args.rate_hz,
                          compress=args.compress, shape=args.shape, test_shape=args.test_shape,
                          hysteresis=not args.no_hysteresis, storage=args.storage,
                          temperature_rate_hz=args.temperature_rate_hz)
    paths = app.write_simulate(result, args.out)
    print(f'wrote {", ".join(str(p) for p in paths)}')
    return 0


def _check_simulate_size(args: argparse.Namespace) -> None:
    """Refuse a run whose samples cannot fit in half the memory or on the disk (exit code 2)."""
    from ..thermal import simulate as sim

    for option, value in (('--hours', args.hours), ('--compress', args.compress),
                          ('--rate-hz', args.rate_hz),
                          ('--temperature-rate-hz', args.temperature_rate_hz)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ParameterError(f'{option} must be a finite number > 0, got {value!r}')
    train_s, comp = sim.resolve_timing(sim.make_profile(args.shape), hours=args.hours,
                                       compress=args.compress)
    test_s = train_s if args.test_shape is None else sim.resolve_timing(
        sim.make_profile(args.test_shape), compress=comp)[0]
    need = (train_s + test_s) * args.rate_hz * SIMULATE_BYTES_PER_SAMPLE
    memory, free = physical_memory_bytes(), free_bytes(args.out)
    run = (f'--hours {args.hours:g}' if args.hours is not None else
           f'--compress {args.compress:g}' if args.compress is not None else
           f'--shape {args.shape} (its whole profile)')
    for have, where in ((None if memory is None else memory / 2, "half of this machine's memory"),
                        (free, f'the free space of {args.out!r}')):
        if have is not None and not need <= have:
            raise ParameterError(
                f'{run} at --rate-hz {args.rate_hz:g} makes {train_s + test_s:.3g} s of '
                f'samples (train and test), about {need / 2**30:.3g} GiB: more than {where} '
                f'({have / 2**30:.3g} GiB); shorten the run or lower --rate-hz')


def _cmd_export(args: argparse.Namespace, argv: list[str]) -> int:
    result = app.export(model_path=args.model, px4_instance=args.px4_instance,
                        gyro_device_id=args.px4_gyro_id, accel_device_id=args.px4_accel_id,
                        ardupilot_imu=args.ardupilot_imu,
                        gyro_offsets=not args.no_gyro_offsets, cal_temp_c=args.cal_temp_c,
                        axes=args.axes, predict=args.predict, bag_options=_bag_options(args))
    files = app.write_export(result, args.out)
    _print_notes(result.notes, args)
    _print_warnings(result.warnings, args)
    if not args.quiet:
        for p in result.predicted:
            print(_prediction_line(p))
        print(f'wrote {", ".join(str(p) for p in files)}')
    return 0


#: The rows of export's prediction, in print order: (key of residual_deg_s, label).
_PREDICTION_ROWS = (('raw', 'raw'), ('method', 'the model itself'), ('model', 'the cubic'),
                    ('px4', 'as PX4 applies it'), ('ardupilot', 'as ArduPilot applies it'))


def _prediction_line(p: dict) -> str:
    """Return one line of the residual drift each firmware leaves on one recording."""
    r = p['residual_deg_s']
    parts = ', '.join(f'{label} {" / ".join(_f(v) for v in r[key])}'
                      for key, label in _PREDICTION_ROWS if key in r)
    return f'{p["bag"]} ({p["role"]}): residual drift x / y / z (deg/s): {parts}'


_COMMANDS = {'fit': _cmd_fit, 'apply': _cmd_apply, 'compare': _cmd_compare,
             'simulate': _cmd_simulate, 'export': _cmd_export}


def _body(argv: list[str]) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as err:  # argparse: usage errors exit 2, --help/--version 0
        return err.code if isinstance(err.code, int) else 2
    # refused now (a file in the way, a previous result), not after the computation
    check_out_dir(args.out, overwrite=args.overwrite)
    return _COMMANDS[args.command](args, argv)


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_thermal; return its exit code (docs/thermal.md).

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
