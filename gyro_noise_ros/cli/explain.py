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

    gyro_noise_explain INPUT [--topic T] [--temperature-topic T] [--axis x|y|z|all] [--seed S]
                       --out DIR [--ensemble N] [--max-steps K] [--bootstrap B] [--rate-hz HZ]
                       [--require-temperature] [--start S] [--end S] [--static auto|off]
                       [--scheduler ADDRESS] [--quiet]

INPUT is any recording ``gyro_noise_analyze`` reads (:mod:`gyro_noise_ros.bag.inputs`: a rosbag2
folder / .db3 / .mcap, a ROS 1 .bag, a CSV, a PX4 .ulg). Writes DIR/explain.json, DIR/report.md
and PNG figures; prints a short verdict and the named effects' parameters as value ± standard
error (parametric bootstrap of the final model, ``--bootstrap`` records), or the bound the record
gives for a time scale it does not resolve. The workflow is
:mod:`gyro_noise_ros.app.explain`; this module only parses, calls it and prints. Exit codes: see
:mod:`gyro_noise_ros.cli._common`.
"""

import argparse
from pathlib import Path
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.explain import (check_output, ExplainParams, MAX_RECORDS, prepare_explain,
                           run_explain, write_explain)
from ..outputs import removed_if_unused

PROG = 'gyro_noise_explain'
#: Options not named after the parameter they set (errors name parameters: cli/_common).
RENAMED = {'start_s': '--start', 'end_s': '--end'}


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser."""
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split('\n\n')[0].strip())
    p.add_argument('input', metavar='INPUT',
                   help='rosbag2 / ROS 1 bag, PX4 ULog (.ulg), or CSV (time_s, '
                   'gyro_*_rad_s or gyro_*_dps, optional temperature_c; the spellings of '
                   'docs/offline_tool.md)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the only one)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (naming it makes temperature required)')
    p.add_argument('--axis', choices=('x', 'y', 'z', 'all'), default='all',
                   help='gyro axis (default all: one run, one report, a subdirectory per axis)')
    p.add_argument('--seed', type=int, default=0, help='ensemble seed (default 0)')
    p.add_argument('--out', required=True, help='output directory')
    add_overwrite_argument(p)
    p.add_argument('--ensemble', type=int, default=16, help='ensemble members (default 16, >= 4)')
    p.add_argument('--max-steps', type=int, default=6, help='most effects to add (default 6)')
    p.add_argument('--bootstrap', type=int, default=20, metavar='B',
                   help='records simulated from the final model for the standard errors of the '
                   f'effect parameters (default 20; 0: off, else 5 to {MAX_RECORDS})')
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


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    # bad options and an unusable --out are refused before the (possibly long) load of the input
    params = ExplainParams(path=args.input, axis=args.axis, topic=args.topic,
                           temperature_topic=args.temperature_topic, rate_hz=args.rate_hz,
                           require_temperature=args.require_temperature, start_s=args.start,
                           end_s=args.end, static=args.static, seed=args.seed,
                           ensemble=args.ensemble, max_steps=args.max_steps,
                           bootstrap=args.bootstrap)
    check_out_dir(args.out, overwrite=args.overwrite)
    with removed_if_unused(args.out):
        return _explain(args, argv, params)


def _explain(args: argparse.Namespace, argv: list[str], params: ExplainParams) -> int:
    from ..cluster import make_executor

    prepared = prepare_explain(params)
    for text in prepared.warnings:
        _say(f'{PROG}: warning: {text}')
    check_output(args.out)   # the input proved readable: the output must take the results
    pool = None
    if args.scheduler is not None:
        pool = make_executor(1, args.scheduler, warn=lambda text: _say(f'{PROG}: warning: {text}'))
    try:
        run = run_explain(prepared, progress=None if args.quiet else _say,
                          mapper=map if pool is None else pool.map)
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    write_explain(run, args.out, html=not args.no_html, command=(PROG, *argv))
    for axis in run.axes:
        print(f'{PROG}: axis {axis.axis}: {axis.verdict} '
              f'({Path(args.out) / axis.folder / "explain.json"})')
        for line in axis.parameter_lines:
            print(f'{PROG}: axis {axis.axis}:   {line}')
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``gyro_noise_explain``; returns the exit code."""
    return run_cli(PROG, _body, argv, renamed=RENAMED)


if __name__ == '__main__':
    sys.exit(main())
