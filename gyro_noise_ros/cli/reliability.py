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
        [--alpha 0.05] [--min-edf 0] [--topic T] [--gravity M_S2 | --latitude DEG [--height M]]
        [--min-static-s S] [--rate-hz HZ] [--no-figures] [--no-html] --out DIR

Any part may be absent; the report covers what was given. The workflow is
:mod:`gyro_noise_ros.app.reliability`: per channel of the static records the bias-instability
interval (paper 001 section 6) with the uncertainty of its width, the change tested against the
+/- tolerance band (``beyond``, ``physiological``, or ``undetermined`` with the record length that
would decide), one verdict per sensor, the noise terms with their uncertainties; from the
calibrations Table 6 before/after with the change +/- sigma, gyro bias and cross-axis terms, the
uniformity indicators, the gravity check; temperatures of every record and dwell. Writes
``reliability.json``, ``reliability.md``, ``fig6_accel.png``, ``fig6_gyro.png``,
``adev_before.csv``, ``adev_after.csv`` and ``before/`` ``after/`` calibration files into DIR.

Exit codes: 0 ok (some parts may be undetermined, see the report), 2 bad option or nothing
given, 3 unreadable recording, 4 a static record that cannot be analysed at all (too short for
the Allan analysis, constant, not static: one line naming it), or every given part failed, 6
``--out`` cannot be written (checked before reading anything).
"""

import argparse
import os
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.calibrate import resolve_gravity
from ..app.reliability import (PARTS, ReliabilityParams, run_reliability, SENSORS,
                               write_reliability)
from ..calibration.interval import DEFAULT_ALPHA, DEFAULT_C, DEFAULT_MIN_EDF, DEFAULT_TOLERANCE
from ..calibration.static import DetectorSettings

PROG = 'gyro_noise_reliability'


def build_parser() -> argparse.ArgumentParser:
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
    p.add_argument('--alpha', type=float, default=DEFAULT_ALPHA,
                   help='one-sided level of each test of a verdict (0.05: 95 %% one-sided '
                        'bounds)')
    p.add_argument('--min-edf', type=float, default=DEFAULT_MIN_EDF,
                   help='sigma_min only among taus with at least this many degrees of freedom, '
                        "on top of the Allan readout's rule (0: the readout's bias stability)")
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    add_overwrite_argument(p)
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


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    gravity = resolve_gravity(args.gravity, args.latitude, args.height)
    params = ReliabilityParams(
        before_calibration=tuple(args.before_calibration or ()),
        before_static=args.before_static,
        after_calibration=tuple(args.after_calibration or ()), after_static=args.after_static,
        c=args.c, tolerance=args.tolerance, alpha=args.alpha, min_edf=args.min_edf,
        topic=args.topic, gravity=gravity, rate_hz=args.rate_hz,
        settings=DetectorSettings(min_static_s=args.min_static_s), figures=not args.no_figures)
    # refused now (a file in the way, a previous result), not after the computation
    check_out_dir(args.out, overwrite=args.overwrite)
    if (args.before_calibration or args.after_calibration) and gravity.warning:
        print(f'{PROG}: warning: {gravity.warning}', file=sys.stderr)
    result = run_reliability(params)
    for line in result.warnings():
        print(f'{PROG}: warning: {line}', file=sys.stderr)
    write_reliability(result, args.out, html=not args.no_html, command=(PROG, *argv))
    doc = result.as_dict()
    if any(result.statics.values()):
        for ch, e in doc['bias_instability_interval'].items():
            change = ('n/a' if e['change'] is None else
                      f'{100 * e["change"]:+.0f} %' + (
                          '' if e['change_sd'] is None else f' +/- {100 * e["change_sd"]:.0f} %'))
            print(f'{ch}: {e["verdict"]} (change {change})')
        for s in SENSORS:
            print(f'{s}: {doc["overall"][s]["verdict"]} ({doc["overall"][s]["basis"]})')
    print(f'wrote {os.path.join(args.out, "reliability.json")}, reliability.md')
    return 0


def main(argv: list[str] | None = None) -> int:
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


__all__ = ['main', 'build_parser']

if __name__ == '__main__':
    sys.exit(main())
