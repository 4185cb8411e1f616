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
        [--after-calibration BAG [BAG ...]] [--after-static BAG] [--tolerance 0.3]
        [--taus 1 10 30 100] [--alpha 0.05] [--c 2] [--min-edf 0] [--topic T]
        [--gravity M_S2 | --latitude DEG [--height M]] [--min-static-s S] [--rate-hz HZ]
        [--no-figures] [--no-html] --out DIR

Any part may be absent; the report covers what was given. The workflow is
:mod:`gyro_noise_ros.app.reliability`: the verdict per sensor from the Allan deviation of the
static records at averaging times fixed before the data (beyond / within / undetermined with
the record length that would decide, against +/- tolerance), paper 001's bias-instability
interval as an indicator, the noise terms; from the calibrations Table 6 before/after, gyro and
cross-axis terms, uniformity, the gravity check; temperatures. Writes ``reliability.json``,
``reliability.md``, ``report.html``, ``fig6_*.png``, ``adev_*.csv`` and ``before/`` ``after/``
calibration files into DIR.

Exit codes: 0 ok (a verdict may be undetermined, see the report), 2 bad option or nothing given,
3 unreadable recording, 4 a static record that cannot be analysed (too short for the longest
fixed tau, constant, not static: one line naming it), two static records that are not one sensor
at one rate, or every given part failed, 6 ``--out`` cannot be written (checked first).
"""

import argparse
import os
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.calibrate import resolve_gravity
from ..app.reliability import (PARTS, ReliabilityParams, run_reliability, SENSORS,
                               STATIC_MODES, write_reliability)
from ..calibration import noise_change
from ..calibration.interval import DEFAULT_ALPHA, DEFAULT_C, DEFAULT_MIN_EDF
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
    p.add_argument('--tolerance', type=float, default=noise_change.DEFAULT_TOLERANCE,
                   help='band of the verdict: largest relative change of the Allan deviation at '
                        'a fixed tau that is still within (paper 001: 0.5)')
    p.add_argument('--taus', type=float, nargs='+', default=list(noise_change.DEFAULT_TAUS_S),
                   metavar='S', help='averaging times of the verdict (s), fixed before the data')
    p.add_argument('--alpha', type=float, default=DEFAULT_ALPHA,
                   help='family-wise one-sided level of "beyond" per sensor (Holm)')
    p.add_argument('--c', type=float, default=DEFAULT_C,
                   help='indicator: the interval where ADEV < c * sigma_min (paper: 2)')
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
    p.add_argument('--static', default='auto', choices=STATIC_MODES,
                   help='static records: auto: analyse the longest static segment, cutting '
                   'motion and saying so (the rule of gyro_noise_analyze; default); off: '
                   'analyse every sample')
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
        c=args.c, tolerance=args.tolerance, alpha=args.alpha, taus_s=tuple(args.taus),
        min_edf=args.min_edf,
        topic=args.topic, gravity=gravity, rate_hz=args.rate_hz,
        settings=DetectorSettings(min_static_s=args.min_static_s), figures=not args.no_figures,
        static=args.static)
    # refused now (a file in the way, a previous result), not after the computation
    check_out_dir(args.out, overwrite=args.overwrite)
    if (args.before_calibration or args.after_calibration) and gravity.warning:
        print(f'{PROG}: warning: {gravity.warning}', file=sys.stderr)
    result = run_reliability(params)
    for line in result.warnings():
        print(f'{PROG}: warning: {line}', file=sys.stderr)
    write_reliability(result, args.out, html=not args.no_html, command=(PROG, *argv))
    doc = result.as_dict()
    for side, st in result.statics.items():
        if st is not None and st.cut:
            print(f'{side} static record: {st.cut}')
    if any(result.statics.values()):
        for sensor in SENSORS:
            e = doc['overall'][sensor]
            print(f'{sensor}: {e["verdict"]}: {e["sentence"]}')
        for sensor in SENSORS:
            e = doc['interval_indicator'][sensor]
            print(f'{sensor} indicator (bias-instability interval): {e["verdict"]} '
                  f'({e["basis"]})')
    print(f'wrote {os.path.join(args.out, "reliability.json")}, reliability.md')
    return 0


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_reliability; return its exit status.

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv)


__all__ = ['main', 'build_parser']

if __name__ == '__main__':
    sys.exit(main())
