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
gyro_noise_calibrate: static calibration of accelerometer and gyro (paper 001, imu_tk).

Usage::

    gyro_noise_calibrate BAG [BAG ...] [--mode six-position|multi-pose] [--topic T]
        [--gravity M_S2 | --latitude DEG [--height M]] [--alpha P] [--gyro-turns auto|off]
        [--min-static-s S] [--window-s S] [--accel-std-max M_S2] [--gyro-rate-max RAD_S]
        [--merge-tol M_S2] [--trim-windows N] [--max-tilt-deg DEG] [--rate-hz HZ] --out DIR

``six-position`` (default): one recording holding the six static dwells (any order, turns in
between) or six recordings; paper 001 eqs. 3-4 with a consistency test that names and refuses a
tilted dwell. ``multi-pose``: any number (>= 9) of static poses in arbitrary attitudes, fitted by
|a| = g. With the turns recorded, the gyro's scale factor and misalignment come from integrating
them. The workflow is :mod:`gyro_noise_ros.app.calibrate`; writes ``calibration.json``,
``calibration.yaml`` (ROS 2 parameter file for ``imu_compensator``) and ``calibration.md``.
Exit codes: 0 ok, 2 bad option, 3 unreadable recording, 4 the dwells cannot give a calibration
(missing, duplicate, tilted or inconsistent, too short, never static, all-zero accelerometer,
all NaN), 6 ``--out`` cannot be written (checked before reading anything);
``docs/reliability.md``.
"""

import argparse
import os
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.calibrate import (CalibrateParams, GYRO_TURNS, MODES, resolve_gravity,
                             run_calibration, write_calibration)
from ..calibration.calibrate_report import table6_rows
from ..calibration.multipose import gravity_check_words
from ..calibration.sixpos import DEFAULT_ALPHA
from ..calibration.static import DetectorSettings
from ..units import MG_TO_M_S2

PROG = 'gyro_noise_calibrate'


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of gyro_noise_calibrate.

    Returns
    -------
    argparse.ArgumentParser

    """
    d = DetectorSettings()
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        description='Static calibration: six-position (paper 001 eqs. 3-4) or multi-pose '
        '(|a| = g, imu_tk): accelerometer bias, scale factor and cross-axis terms with '
        'uncertainties, gyro bias, gyro scale factor and misalignment from the turns, '
        'consistency and leave-one-out gravity checks.')
    p.add_argument('bags', nargs='+', metavar='BAG',
                   help='one recording with every dwell and the turns between them, or one '
                        'recording per dwell (rosbag2 or ROS 1)')
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    add_overwrite_argument(p)
    p.add_argument('--no-html', action='store_true', help='write no report.html')
    p.add_argument('--mode', choices=MODES, default='six-position',
                   help='six aligned dwells, or >= 9 static poses in any attitude')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the single Imu topic)')
    g = p.add_mutually_exclusive_group()
    g.add_argument('--gravity', type=float, metavar='M_S2', help='local gravity (m/s^2)')
    g.add_argument('--latitude', type=float, metavar='DEG',
                   help='geodetic latitude (deg) for WGS-84 normal gravity')
    p.add_argument('--height', type=float, default=0.0, metavar='M',
                   help='ellipsoidal height (m), with --latitude')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (default: from the stamps)')
    p.add_argument('--alpha', type=float, default=DEFAULT_ALPHA, metavar='P',
                   help='false-alarm probability of the consistency (tilt) test and of the '
                        'gravity check, per calibration')
    p.add_argument('--gyro-turns', choices=GYRO_TURNS, default='auto',
                   help='gyro scale factor and misalignment from the turns between the dwells '
                        '(auto: when the turns determine them)')
    det = p.add_argument_group('static-dwell detector (docs/reliability.md)')
    det.add_argument('--min-static-s', type=float, default=d.min_static_s,
                     help='shortest usable dwell (s)')
    det.add_argument('--window-s', type=float, default=d.window_s, help='detector window (s)')
    det.add_argument('--accel-std-max', type=float, default=d.accel_std_max_m_s2, metavar='M_S2',
                     help='largest per-axis accel std of a static window (m/s^2)')
    det.add_argument('--gyro-rate-max', type=float, default=d.gyro_rate_max_rad_s,
                     metavar='RAD_S',
                     help='largest distance of a static window gyro mean from the median (rad/s)')
    det.add_argument('--merge-tol', type=float, default=d.merge_tol_m_s2, metavar='M_S2',
                     help='largest mean change between windows of one dwell (m/s^2)')
    det.add_argument('--trim-windows', type=int, default=d.trim_windows,
                     help='windows dropped at each end of a dwell')
    det.add_argument('--max-tilt-deg', type=float, default=d.max_tilt_deg,
                     help='six-position: largest angle between a dwell and its axis (deg); '
                          'smaller tilts are judged by the consistency test')
    return p


def settings_from_args(args: argparse.Namespace) -> DetectorSettings:
    """Return the :class:`DetectorSettings` of gyro_noise_calibrate's parsed arguments."""
    return DetectorSettings(window_s=args.window_s, accel_std_max_m_s2=args.accel_std_max,
                            gyro_rate_max_rad_s=args.gyro_rate_max, merge_tol_m_s2=args.merge_tol,
                            trim_windows=args.trim_windows, min_static_s=args.min_static_s,
                            max_tilt_deg=args.max_tilt_deg)


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    params = CalibrateParams(
        paths=tuple(args.bags), mode=args.mode, topic=args.topic, rate_hz=args.rate_hz,
        gravity=resolve_gravity(args.gravity, args.latitude, args.height),
        settings=settings_from_args(args), alpha=args.alpha, gyro_turns=args.gyro_turns)
    # refused now (a file in the way, a previous result), not after the computation
    check_out_dir(args.out, overwrite=args.overwrite)
    result = run_calibration(params)
    write_calibration(result, args.out, html=not args.no_html, command=[PROG, *argv])
    for line in result.warnings():
        print(f'{PROG}: warning: {line}', file=sys.stderr)
    doc = result.as_dict()
    for d in result.dwells:
        print(f'dwell {d.describe()}')
    for name, value, sig in table6_rows(doc):
        unit = 'mg' if name.startswith('b') else '%'
        print(f'{name} = {value:.4f} +/- {sig:.4f} {unit}')
    if result.gyro is not None:
        for i, ax in enumerate('xyz'):
            if result.gyro.estimated[i, i]:
                print(f'gyro S{ax} = {100 * result.gyro.scale_factor[i]:.4f} +/- '
                      f'{100 * result.gyro.scale_factor_sigma[i]:.4f} %')
    verdict = gravity_check_words(doc['gravity_check'])
    if result.gravity_check:
        worst = max(result.gravity_check, key=lambda c: abs(c.z))
        verdict += (f', largest |a| - g {worst.residual_m_s2 / MG_TO_M_S2:+.4f} mg '
                    f'({worst.z:+.1f} sigma, {worst.label})')
    print(f'gravity check (leave-one-out): {verdict}')
    print(f'wrote {os.path.join(args.out, "calibration.json")}, calibration.yaml, calibration.md')
    return 0


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_calibrate; return its exit status.

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
