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
gyro_noise_excitation: sine-dwell and sine-sweep signal checks (paper 001 section 5.3).

Usage::

    gyro_noise_excitation BAG [BAG_AFTER] --sensor accel|gyro --axis x|y|z
        (--dwell FREQ_HZ | --sweep F0_HZ F1_HZ RATE_HZ_S) [--reference-topic T] [--topic T]
        [--harmonics H] [--frequency-tol FRACTION] [--alpha P] [--tolerance FRACTION] --out DIR

Sine dwell: estimated frequency and amplitude, per-cycle amplitude statistics (the paper's
"amplitude stability") and THD, each with the value noise alone would give and a verdict
(steady, clean); a verdict flags a defect only when significant at ``--alpha`` and larger
than ``--tolerance`` (1 % of the amplitude). Sine sweep: amplitude against instantaneous
frequency, rising and falling, and its deviation from the reference channel
(``--reference-topic``: a second ``sensor_msgs/Imu`` topic of the bag, e.g. the shaker's
feedback accelerometer) when recorded, with gain and flatness verdicts. A record that is not the
excitation asked for is refused. With BAG_AFTER, before and after side by side. The workflow
is :mod:`gyro_noise_ros.app.excitation`; writes ``excitation.json``, ``excitation.md``,
``excitation_before.png`` (``excitation_after.png``) and ``report.html``.

Exit codes: 0 ok, 2 bad option (frequency at or above Nyquist), 3 unreadable recording, 4 data
cannot be analysed (NaN/Inf samples, fewer than 3 cycles, no sine above the noise, not the
excitation asked for), 6 ``--out`` cannot be written (checked before reading anything).
"""

import argparse
import os
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.excitation import ExcitationParams, run_excitation, write_excitation
from ..calibration.excitation import (DEFAULT_ALPHA, DEFAULT_FREQUENCY_TOL, DEFAULT_HARMONICS,
                                      DEFAULT_TOLERANCE)

PROG = 'gyro_noise_excitation'
#: Options not named after the parameter they set (errors name parameters: cli/_common).
RENAMED = {'frequency_hz': '--dwell'}


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of gyro_noise_excitation.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        description='Sine dwell / sine sweep signal checks (paper 001 section 5.3).')
    p.add_argument('bags', nargs='+', metavar='BAG', help='recording, and optionally the one '
                   'taken after the stress')
    p.add_argument('--sensor', required=True, choices=('accel', 'gyro'))
    p.add_argument('--axis', required=True, choices=('x', 'y', 'z'))
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument('--dwell', type=float, metavar='FREQ_HZ', help='sine dwell frequency (Hz)')
    mode.add_argument('--sweep', type=float, nargs=3, metavar=('F0_HZ', 'F1_HZ', 'RATE_HZ_S'),
                      help='sine sweep band (Hz) and rate (Hz/s)')
    p.add_argument('--reference-topic', metavar='T',
                   help='sensor_msgs/Imu topic of the reference sensor (same axis)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic of the sensor under test')
    p.add_argument('--harmonics', type=int, default=DEFAULT_HARMONICS,
                   help='harmonics in the THD (those below Nyquist)')
    p.add_argument('--frequency-tol', type=float, default=DEFAULT_FREQUENCY_TOL,
                   metavar='FRACTION',
                   help='largest relative difference between --dwell and the measured frequency')
    p.add_argument('--alpha', type=float, default=DEFAULT_ALPHA, metavar='P',
                   help='false-alarm probability of each verdict')
    p.add_argument('--tolerance', type=float, default=DEFAULT_TOLERANCE, metavar='FRACTION',
                   help='practical tolerance of each verdict, relative to the amplitude: a defect '
                   '(amplitude stability, THD, gain deviation, its spread over frequency) is '
                   'flagged only when significant at --alpha and larger than this')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (default: from the stamps)')
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    add_overwrite_argument(p)
    p.add_argument('--no-figures', action='store_true', help='skip the PNG figures')
    p.add_argument('--no-html', action='store_true', help='write no report.html')
    return p


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    params = ExcitationParams(
        paths=tuple(args.bags), sensor=args.sensor, axis=args.axis, dwell_hz=args.dwell,
        sweep=args.sweep, reference_topic=args.reference_topic, topic=args.topic,
        harmonics=args.harmonics, rate_hz=args.rate_hz, frequency_tol=args.frequency_tol,
        alpha=args.alpha, tolerance=args.tolerance, figures=not args.no_figures)
    # refused now (a file in the way, a previous result), not after the computation
    check_out_dir(args.out, overwrite=args.overwrite)
    result = run_excitation(params)
    write_excitation(result, args.out, html=not args.no_html, command=[PROG, *argv])
    k, unit = params.display
    for side, res in result.sides.items():
        r = res.analysis
        if params.mode == 'dwell':
            print(f'{side}: {r.frequency_hz:.4f} Hz, amplitude {r.amplitude * k:.5g} {unit}, '
                  f'amplitude stability {100 * r.amplitude_stability:.3f} % '
                  f'({"steady" if r.steady else "UNSTEADY"}), THD {100 * r.thd:.3f} % '
                  f'({"clean" if r.clean else "DISTORTED"})')
        elif r.reference_up is None:
            print(f'{side}: sweep analysed in {len(r.bin_hz)} bins (no reference)')
        else:
            print(f'{side}: sweep analysed in {len(r.bin_hz)} bins, mean deviation from the '
                  f'reference {100 * r.mean_deviation:+.3f} +/- '
                  f'{100 * r.mean_deviation_sigma:.3f} % '
                  f'({"matches" if r.matches_reference else "GAIN DIFFERS"}, '
                  f'{"flat" if r.flat else "FREQUENCY-DEPENDENT"}; practical tolerance '
                  f'{100 * params.tolerance:g} %)')
    print(f'wrote {os.path.join(args.out, "excitation.json")}, excitation.md')
    return 0


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_excitation; return its exit status.

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv, renamed=RENAMED)


if __name__ == '__main__':
    sys.exit(main())
