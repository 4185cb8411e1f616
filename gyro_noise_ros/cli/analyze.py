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
gyro_noise_analyze.

Characterise gyro noise in rosbags (paper 000 Tables 3-6, Figs. 2-10), ROS-free.

Usage::

    gyro_noise_analyze BAG [BAG ...] [--topic T] [--axis x|y|z|all] [--chunk-size N]
        [--order-grid START:STOP:STEP] [--memory L] [--jobs N] [--scheduler ADDRESS]
        [--reference SUMMARY] [--label NAME ...] --out DIR

The workflow is :func:`gyro_noise_ros.app.analyze.analyze_bags`: it reads rosbag2 (sqlite3,
MCAP), ROS 1 bags, CSV tables and PX4 ULogs in batches, identifies the chunks on ``--jobs``
worker processes (or a Dask cluster) and writes chunks.csv, summary.json, summary.md, allan.csv,
imu.yaml, curves.npz, PNG figures and report.html into DIR. Formats and exit codes:
``docs/offline_tool.md``.
"""

import argparse
from pathlib import Path
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from .. import __version__
from ..analysis.summary_md import fmt, modes_text, readout_text
from ..app.analyze import (analyze_bags, AnalyzeParams, AnalyzeResult, DEFAULT_BATCH,
                           DEFAULT_CURVES, parse_order_grid, TOOL)
from ..cluster import usable_cpus
from ..core.engine import AXES, EngineConfig, GAP_POLICIES
from ..core.fractional import DEFAULT_MEMORY
from ..errors import ParameterError

PROG = TOOL
#: Options not named after the parameter they set (errors name parameters: cli/_common).
RENAMED = {'start_s': '--start', 'end_s': '--end', 'bag': '--reference-bag'}


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of gyro_noise_analyze.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG,
        description='Characterise MEMS gyro noise in rosbags, CSV tables and PX4 ULogs: '
        'per-chunk bias, variance and '
        'fractional order (variance and correlation methods), Allan deviation, health verdicts.')
    p.add_argument(
        'bags', nargs='+', metavar='BAG',
        help='rosbag2 directory, .db3 or .mcap file, ROS 1 .bag file, CSV table or PX4 .ulg '
        '(order kept in tables)')
    p.add_argument('--out', required=True, metavar='DIR',
                   help='output directory (created if missing)')
    add_overwrite_argument(p)
    p.add_argument('--topic',
                   help='sensor_msgs/Imu topic (default: the single Imu topic of each bag)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (default: found automatically)')
    p.add_argument('--axis', default='all', choices=[*AXES, 'all'],
                   help='axis to analyse (default: all)')
    p.add_argument('--chunk-size', type=int, default=10000, metavar='N',
                   help='samples per chunk (10000)')
    p.add_argument('--order-grid', default='0:2:0.01', metavar='START:STOP:STEP',
                   help='order grid, both ends included (0:2:0.01)')
    p.add_argument('--memory', type=int, default=DEFAULT_MEMORY, metavar='L',
                   help='memory L of the truncated GL difference (1000)')
    p.add_argument('--max-lag', type=int, default=None, metavar='M',
                   help='largest lag in J (default: all)')
    p.add_argument('--no-demean', action='store_true',
                   help='do not remove the chunk mean before identification')
    p.add_argument('--rate-hz', type=float, default=None,
                   help='nominal sample rate (default: from the stamps)')
    p.add_argument('--gap-factor', type=float, default=1.5,
                   help='a stamp step above this many nominal periods is a gap (1.5)')
    p.add_argument(
        '--gap-policy', default='flag', choices=GAP_POLICIES,
        help='flag: keep chunks with gaps and count; split: restart the chunk after a gap; '
        'drop: leave chunks with gaps out of the statistics (default: flag)')
    p.add_argument('--start', type=float, default=None, metavar='S',
                   help='analyse from S seconds after the first sample of each bag')
    p.add_argument('--end', type=float, default=None, metavar='S',
                   help='analyse up to S seconds after the first sample of each bag')
    p.add_argument(
        '--static', default='auto', choices=('auto', 'off'),
        help='auto: find the longest static segment and skip motion, saying so (default); '
        'off: analyse everything')
    p.add_argument(
        '--jobs', type=int, default=None, metavar='N',
        help='worker processes for the identification (default: all cores; 1 = in-process)')
    p.add_argument(
        '--scheduler', metavar='ADDRESS',
        help='Dask scheduler (tcp://host:8786): identify the chunks on that cluster instead of '
        'local processes (pip extra dask; docs/scale.md)')
    p.add_argument(
        '--reference', metavar='SUMMARY',
        help='summary.json of a reference recording: adds health verdicts per bag and axis')
    p.add_argument('--reference-bag', metavar='LABEL',
                   help='the bag (its label) of a --reference summary that holds several bags')
    # extend: --label a b c and --label a --label b --label c both give one label per bag
    p.add_argument('--label', nargs='+', action='extend', metavar='NAME',
                   help='one label per bag for tables and figures (--label a b or '
                   '--label a --label b)')
    p.add_argument('--curves', type=int, default=DEFAULT_CURVES, metavar='N',
                   help=f'chunks per bag and axis whose var/J curves are kept for heat maps '
                        f'({DEFAULT_CURVES}; 0 = none)')
    p.add_argument('--no-figures', action='store_true', help='write no PNG figures')
    p.add_argument('--no-html', action='store_true',
                   help='write no report.html (the interactive one-file report)')
    p.add_argument('--no-allan', action='store_true', help='skip the Allan deviation')
    p.add_argument(
        '--allan-taus', default='dense', choices=('octave', 'dense'),
        help='Allan averaging times: octave (1, 2, 4, ... samples) or dense (~10 per decade)')
    p.add_argument('--batch-size', type=int, default=DEFAULT_BATCH, metavar='N',
                   help=f'messages decoded per batch ({DEFAULT_BATCH})')
    p.add_argument('--quiet', action='store_true', help='print only errors')
    p.add_argument('--version', action='version', version=f'%(prog)s {__version__}')
    return p


def _body(argv: list[str]) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as err:  # argparse: usage errors exit 2, --help/--version 0
        return err.code if isinstance(err.code, int) else 2
    if args.reference_bag is not None and args.reference is None:
        raise ParameterError('--reference-bag names a bag of a --reference summary: give '
                             '--reference SUMMARY too')
    check_out_dir(args.out, overwrite=args.overwrite)
    alphas = parse_order_grid(args.order_grid)
    axes = AXES if args.axis == 'all' else (args.axis,)
    config = EngineConfig(chunk_size=args.chunk_size, axes=axes, alphas=alphas, memory=args.memory,
                          demean=not args.no_demean, max_lag=args.max_lag, rate_hz=args.rate_hz,
                          gap_factor=args.gap_factor, gap_policy=args.gap_policy,
                          allan=not args.no_allan, allan_taus=args.allan_taus)
    jobs = args.jobs if args.jobs is not None else usable_cpus()
    params = AnalyzeParams(
        paths=tuple(args.bags), out_dir=args.out, labels=args.label, topic=args.topic,
        temperature_topic=args.temperature_topic, config=config, jobs=jobs,
        reference=args.reference, reference_bag=args.reference_bag,
        figures=not args.no_figures, curves=args.curves, batch_size=args.batch_size,
        progress=not args.quiet, command=(PROG, *argv), start_s=args.start, end_s=args.end,
        static=args.static, scheduler=args.scheduler, html=not args.no_html)
    result = analyze_bags(params)
    if not args.quiet:
        _print_summary(result)
    return 0


def _order_text(axis_doc: dict, key: str) -> str:
    # A mean over two separate basins (the model's 0/1 alias) is a number no chunk is near.
    if axis_doc.get(key + '_multimodal'):
        return 'modes ' + modes_text(axis_doc[key + '_modes'])
    return fmt(axis_doc[key + '_mean'], '.3f')


def _print_summary(result: AnalyzeResult) -> None:
    for b in result.bags:
        print(
            f"{b['label']}: {b['samples']} samples on {b['topic']} ({b['storage']}), "
            f"{b['duration_s']:.1f} s at {b['rate_hz'] or float('nan'):.6g} Hz ({b['rate_method']}"
            f"{', bursty stamps' if b['stamps_bursty'] else ''}, stamp jitter "
            f"{1e3 * (b['stamp_jitter_s'] or float('nan')):.3g} ms), {b['samples_lost']} lost in "
            f"{b['gaps']} gap(s), {b['clock_steps']} clock step(s), "
            f"{b['out_of_order_stamps']} out-of-order stamp(s), "
            f"{b['equal_stamps']} equal to the one before, "
            + ('Allan deviation only (shorter than one chunk)' if b.get('allan_only') else
               f"{b['tail_samples']} tail sample(s) not in a chunk"))
        for axis, a in b['axes'].items():
            line = (f'  {axis}: Allan deviation only' if b.get('allan_only') else
                    f"  {axis}: {a['chunks']} chunks, drift "
                    f"{fmt(a['offset_drift_deg_s_per_h'], '.5f')} "
                    f"(deg/s)/h, variance {fmt(a['mean_variance_deg2_s2'], '.5g')} "
                    '(deg/s)^2, ' f"order var {_order_text(a, 'alpha_var')}, corr "
                    f"{_order_text(a, 'alpha_corr')}")
            sheet = a.get('allan_datasheet')
            if sheet:
                line += ', ' + readout_text(sheet)
            if a['nan_samples']:
                line += f", {a['nan_samples']} NaN sample(s)"
            if 'health' in a:
                line += f" -> {a['health']['level']}: {a['health']['message']}"
            print(line)
    t = result.timing
    print(f"time {t['total_s']:.1f} s (decode {t['decode_s']:.1f} s)")
    out = Path(result.files[0]).parent
    print(f'wrote {len(result.files)} files to {out}: '
          + ', '.join(Path(f).name for f in result.files))


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_analyze; return its exit code (docs/offline_tool.md).

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv, renamed=RENAMED)


if __name__ == '__main__':
    sys.exit(main())
