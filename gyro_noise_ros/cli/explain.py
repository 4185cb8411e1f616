"""
gyro_noise_explain: find where the simulation and the measurement disagree, name the missing effect,
add it, show the gap shrink (see docs/discrepancy.md).

Usage::

    gyro_noise_explain INPUT [--topic T] [--temperature-topic T] [--axis x|y|z] [--seed S] --out DIR
                       [--ensemble N] [--max-steps K] [--rate-hz HZ] [--require-temperature] [--quiet]

INPUT is a rosbag2 directory / .db3 / .mcap, a ROS 1 .bag, or a .csv with the columns documented in
:mod:`gyro_noise_ros.explain.inputs`. Writes DIR/explain.json, DIR/report.md and PNG figures; prints a
short verdict. Exit codes: see :mod:`gyro_noise_ros.cli._common`.
"""

import argparse
import sys

from ._common import run_cli

PROG = 'gyro_noise_explain'


def build_parser():
    """Return the argument parser."""
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split('\n\n')[0].strip())
    p.add_argument('input', metavar='INPUT', help='rosbag2 / ROS 1 bag, PX4 ULog (.ulg), or CSV (time_s, '
                   'gyro_*_rad_s, optional temperature_c)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the only one)')
    p.add_argument('--temperature-topic', help='sensor_msgs/Temperature topic (naming it makes temperature '
                   'required)')
    p.add_argument('--axis', choices=('x', 'y', 'z'), default='z', help='gyro axis (default z)')
    p.add_argument('--seed', type=int, default=0, help='ensemble seed (default 0)')
    p.add_argument('--out', required=True, help='output directory')
    p.add_argument('--ensemble', type=int, default=16, help='ensemble members (default 16, >= 4)')
    p.add_argument('--max-steps', type=int, default=6, help='most effects to add (default 6)')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (Hz); required for a CSV without '
                   'time_s, else overrides the mean rate of the stamps')
    p.add_argument('--require-temperature', action='store_true',
                   help='fail unless the input has a temperature')
    p.add_argument('--quiet', action='store_true', help='print only the verdict')
    return p


def _check_options(args):
    """Refuse bad options before the (possibly long) load of the input."""
    from pathlib import Path

    from ..errors import ParameterError

    if args.ensemble < 4:
        raise ParameterError(f'--ensemble must be >= 4 members, got {args.ensemble}')
    if args.max_steps < 0:
        raise ParameterError(f'--max-steps must be >= 0, got {args.max_steps}')
    if args.seed < 0:
        raise ParameterError(f'--seed must be >= 0, got {args.seed}')
    if args.rate_hz is not None and not (args.rate_hz > 0 and args.rate_hz < float('inf')):
        raise ParameterError(f'--rate-hz must be a positive number, got {args.rate_hz}')
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ParameterError(f'--out {str(out)!r} exists and is not a directory')


def _body(argv):
    from ..explain.inputs import load_input
    from ..explain.report import verdict, write_outputs
    from ..explain.workflow import explain

    args = build_parser().parse_args(argv)
    _check_options(args)
    meas = load_input(args.input, topic=args.topic, temperature_topic=args.temperature_topic, axis=args.axis,
                      rate_hz=args.rate_hz, require_temperature=args.require_temperature)
    progress = None if args.quiet else (lambda text: print(text, file=sys.stderr, flush=True))
    result = explain(meas, seed=args.seed, ensemble=args.ensemble, max_steps=args.max_steps, progress=progress)
    out = write_outputs(result, args.out)
    print(f'{PROG}: {verdict(result)} ({out / "explain.json"})')
    return 0


def main(argv=None):
    """Entry point of ``gyro_noise_explain``; returns the exit code."""
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
