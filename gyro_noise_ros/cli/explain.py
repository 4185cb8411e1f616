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
gyro_noise_explain: name the effect a gyro noise model misses, add it, show the gap shrink.

Finds where the simulation and the measurement disagree (see docs/discrepancy.md).

Usage::

    gyro_noise_explain INPUT [--topic T] [--temperature-topic T] [--axis x|y|z] [--seed S]
                       --out DIR [--ensemble N] [--max-steps K] [--bootstrap B] [--rate-hz HZ]
                       [--require-temperature] [--scheduler ADDRESS] [--quiet]

INPUT is a rosbag2 directory / .db3 / .mcap, a ROS 1 .bag, or a .csv with the columns documented in
:mod:`gyro_noise_ros.explain.inputs`. Writes DIR/explain.json, DIR/report.md and PNG figures;
prints a short verdict and the named effects' parameters as value ± standard error (parametric
bootstrap of the final model, ``--bootstrap`` records). Exit codes: see
:mod:`gyro_noise_ros.cli._common`.
"""

import argparse
from pathlib import Path
import sys

from ._common import check_out_option, run_cli

PROG = 'gyro_noise_explain'
#: Most ensemble members or bootstrap records: each costs a simulated copy of the record (time
#: and memory), 16 and 20 are the defaults; beyond this the number is a typo, not a wish.
MAX_RECORDS = 10000
#: Sample rates --rate-hz accepts (Hz): every gyro samples inside; outside, the record's times
#: overflow or vanish in floating point.
RATE_RANGE_HZ = (1e-3, 1e9)


def build_parser():
    """Return the argument parser."""
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split('\n\n')[0].strip())
    p.add_argument('input', metavar='INPUT',
                   help='rosbag2 / ROS 1 bag, PX4 ULog (.ulg), or CSV (time_s, '
                   'gyro_*_rad_s, optional temperature_c)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the only one)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (naming it makes temperature ' 'required)')
    p.add_argument('--axis', choices=('x', 'y', 'z', 'all'), default='all',
                   help='gyro axis (default all: one run, one report, a subdirectory per axis)')
    p.add_argument('--seed', type=int, default=0, help='ensemble seed (default 0)')
    p.add_argument('--out', required=True, help='output directory')
    p.add_argument('--ensemble', type=int, default=16, help='ensemble members (default 16, >= 4)')
    p.add_argument('--max-steps', type=int, default=6, help='most effects to add (default 6)')
    p.add_argument('--bootstrap', type=int, default=20, metavar='B',
                   help='records simulated from the final model for the standard errors of the '
                   'effect parameters (default 20; 0: off, else >= 5)')
    p.add_argument('--rate-hz', type=float,
                   help='nominal sample rate (Hz); required for a CSV without '
                   'time_s, else overrides the mean rate of the stamps')
    p.add_argument('--require-temperature', action='store_true',
                   help='fail unless the input has a temperature')
    p.add_argument('--start', type=float, default=None, metavar='S',
                   help='analyse from S seconds after the first sample')
    p.add_argument('--end', type=float, default=None, metavar='S',
                   help='analyse up to S seconds after the first sample')
    p.add_argument('--static', default='auto', choices=('auto', 'off'),
                   help='auto: keep the longest static segment, skipping motion (default)')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='Dask scheduler (tcp://host:8786): evaluate the ensemble members on that '
                   'cluster (same result; pip extra dask; docs/scale.md)')
    p.add_argument('--quiet', action='store_true', help='print only the verdict')
    p.add_argument('--no-html', action='store_true',
                   help='write no report.html (one per axis, beside its explain.json)')
    return p


def _check_options(args):
    """Refuse bad options and an unusable --out before the (possibly long) load of the input."""
    from ..errors import ParameterError

    if not 4 <= args.ensemble <= MAX_RECORDS:
        raise ParameterError(f'--ensemble must be 4 to {MAX_RECORDS} members, got {args.ensemble}')
    if args.max_steps < 0:
        raise ParameterError(f'--max-steps must be >= 0, got {args.max_steps}')
    if args.seed < 0:
        raise ParameterError(f'--seed must be >= 0, got {args.seed}')
    if args.bootstrap != 0 and not 5 <= args.bootstrap <= MAX_RECORDS:
        raise ParameterError(f'--bootstrap must be 0 (off) or 5 to {MAX_RECORDS} records, got '
                             f'{args.bootstrap}')
    if args.rate_hz is not None and not RATE_RANGE_HZ[0] <= args.rate_hz <= RATE_RANGE_HZ[1]:
        raise ParameterError(f'--rate-hz must be {RATE_RANGE_HZ[0]:g} to {RATE_RANGE_HZ[1]:g} Hz, '
                             f'got {args.rate_hz}')
    for name, value in (('--start', args.start), ('--end', args.end)):
        if value is not None and not (value >= 0 and value < float('inf')):
            raise ParameterError(f'{name} must be a number of seconds >= 0, got {value}')
    if args.start is not None and args.end is not None and args.end <= args.start:
        raise ParameterError(f'--end ({args.end:g} s) must be after --start ({args.start:g} s)')
    check_out_option(args.out)


def _left_out_lines(left):
    parts = [f'{left["before_start"]} before --start'] if left['before_start'] else []
    parts += [f'{left["after_end"]} after --end'] if left['after_end'] else []
    if left['motion']:
        a, b = left['static_segment_s']
        parts.append(
            f'{left["motion"]} in motion (the longest static segment, t = {a:.1f}-{b:.1f} s, '
            'is analysed)')
    return [f'samples left out: {", ".join(parts)}'] if parts else []


def _body(argv):
    from ..cluster import make_executor

    args = build_parser().parse_args(argv)
    _check_options(args)
    pool = None
    if args.scheduler is not None:
        pool = make_executor(1, args.scheduler, warn=lambda text: print(
            f'{PROG}: warning: {text}', file=sys.stderr, flush=True))
    try:
        return _run(args, map if pool is None else pool.map, [PROG, *argv])
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)


def _run(args, map_fn, command):
    from contextlib import ExitStack

    from ..explain.inputs import available_axes, load_input, select
    from ..explain.report import parameter_lines, verdict, write_files
    from ..explain.workflow import explain
    from ..htmlreport.explain import write_explain_html
    from ..outputs import staged_output

    axes = available_axes(args.input) if args.axis == 'all' else (args.axis,)
    progress = None if args.quiet else (lambda text: print(text, file=sys.stderr, flush=True))
    out_root = Path(args.out)
    results = {}
    with ExitStack() as stack:
        stage = None
        for k, axis in enumerate(axes):
            meas = load_input(args.input, topic=args.topic,
                              temperature_topic=args.temperature_topic, axis=axis,
                              rate_hz=args.rate_hz, require_temperature=args.require_temperature)
            meas, left = select(meas, start_s=args.start, end_s=args.end, static=args.static)
            if stage is None:
                # Created once the input proved readable; every axis is written into it and
                # published together at the end: an interrupted run leaves no result behind.
                stage = stack.enter_context(staged_output(out_root))
            if k == 0:
                for text in _left_out_lines(left) + list(meas.timebase.warnings if meas.timebase
                                                         else ()):
                    print(f'{PROG}: warning: {text}', file=sys.stderr, flush=True)
            if progress is not None and len(axes) > 1:
                progress(f'axis {axis} ({k + 1} of {len(axes)})')
            result = explain(meas, seed=args.seed, ensemble=args.ensemble,
                             max_steps=args.max_steps, bootstrap=args.bootstrap,
                             progress=progress, mapper=map_fn)
            sub = f'axis_{axis}' if len(axes) > 1 else ''
            write_files(result, _mkdir(stage / sub))
            if not args.no_html:
                write_explain_html(result, stage / sub, command=command)
            results[axis] = (result, sub)
            print(f'{PROG}: axis {axis}: {verdict(result)} '
                  f'({out_root / sub / "explain.json"})')
            for line in parameter_lines(result):
                print(f'{PROG}: axis {axis}:   {line}')
        if len(axes) > 1:
            _write_index(stage, results, verdict, parameter_lines)
    return 0


def _mkdir(folder):
    from ..errors import OutputError

    try:
        folder.mkdir(exist_ok=True)
    except OSError as err:
        raise OutputError(f'cannot create {str(folder)!r}: {err.strerror or err}') from err
    return folder


def _write_index(stage, results, verdict, parameter_lines):
    """
    One report for the run.

    Every axis' verdict and report, figures linked from the subdirectories.
    """
    import json

    from ..errors import OutputError

    lines = ['# gyro_noise_explain: all axes', '']
    for axis, (result, _) in results.items():
        lines.append(f'* axis {axis}: {verdict(result)}')
        lines += [f'  * {line}' for line in parameter_lines(result)]
    index = {'axes': {}}
    try:
        for axis, (result, sub) in results.items():
            text = (stage / sub / 'report.md').read_text()
            text = text.replace('](', f']({sub}/').replace('\n# ', '\n## ')
            if text.startswith('# '):
                text = '#' + text
            lines += ['', f'<!-- axis {axis} -->', text]
            index['axes'][axis] = {'verdict': verdict(result),
                                   'explain_json': f'{sub}/explain.json',
                                   'report_md': f'{sub}/report.md'}
        (stage / 'report.md').write_text('\n'.join(lines) + '\n')
        (stage / 'explain.json').write_text(json.dumps(index, indent=2) + '\n')
    except OSError as err:
        raise OutputError(f'cannot write the results: {err.strerror or err}') from err


def main(argv=None):
    """Entry point of ``gyro_noise_explain``; returns the exit code."""
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
