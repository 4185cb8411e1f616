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
``make demo``: the whole story on one machine, from an emulated board to the offline report.

``python -m gyro_noise_ros.cli.demo --out demo_out [--quick]`` starts, as subprocesses in a private
ROS graph (a ``ROS_DOMAIN_ID`` checked free on this host and held while the demo runs,
localhost-only discovery: :func:`gyro_noise_ros.rosgraph.lease_domain`, as the tests use):

1. ``noise_analyzer`` (live analysis, diagnostics), ``gyro_noise_record`` (the bag), the
   diagnostics monitor (``gyro_noise_monitor``) and ``lsm6dso32_driver`` (which retries its port
   until the board is there);
2. ``portenta_emulator`` on a loopback TCP port, seeded, with a scripted helium-like bias
   transient: a quiet phase, then a first-order rise of the bias of every axis;

prints the analyzer's diagnostics as they arrive (one line per chunk: level, bias, drift and orders
per axis; the message of any axis that is not OK), and checks the story: the verdict is OK in the
quiet phase and turns WARN (offset drift above its limit) when the bias rises. It then stops the
live part (driver first, so the recorder and analyzer take the last messages, then recorder,
analyzer, monitor, emulator), runs ``gyro_noise_analyze`` on the recording, and ends by printing
where the tables and figures are.

Demo settings, and why (every one is an ordinary parameter of the tools):

- The board runs at real time (``--speed 1``) and the transient is compressed instead (seconds, not
  the paper's hours): the driver maps device time onto host time, so at ``--speed k`` the stamps
  would run k times fast and every rate-dependent number would be off by k; and five processes at
  6.66 kHz already take about one of the two cores. ``--speed`` is available for faster machines.
- Drift is judged by absolute limits over the last ``history_chunks`` chunks (a sliding window, so
  the verdict follows the transient): WARN above 1 (deg/s)/h, ERROR above 100 (deg/s)/h. The
  emulated quiet bias drifts by a few hundredths of (deg/s)/h; the scripted rise starts at
  ``amplitude / tau`` = 6 (deg/s)/h (36 in ``--quick``).
- Samples lost: WARN above 5 %, ERROR above 25 % of the expected samples (the tools' defaults are
  0.01 % and 1 %). On a busy shared machine the DDS transport drops some messages when a receiving
  process is not scheduled for tens of milliseconds; the losses are still counted and printed, but
  they should not hide the drift story. ``docs/demo.md`` explains how to read them.

Exit status: 0 when the story ran and the report was written; 1 when a component failed (its log
is named) or the drift was not detected; 2 for a bad option; 6 when ``--out`` cannot be used (a
file, a folder that is not a previous demo output, a previous demo output without
``--overwrite``, not writable); 130 on Ctrl-C, 143 on SIGTERM. Every subprocess is stopped on
every path. ``GYRO_NOISE_DEMO.txt`` in ``--out`` says whether the run finished; the
report folder appears only complete (``gyro_noise_analyze`` stages its files). The workflow is
:func:`gyro_noise_ros.app.demo.run_demo`.
"""

import argparse
from pathlib import Path
import sys

from ._common import add_overwrite_argument, check_out_dir, run_cli
from ..app.demo import DemoParams, run_demo, TOOL

PROG = TOOL


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of the demo.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(prog=PROG, description='Emulated board -> driver -> live analyzer '
                                'and recorder -> offline report, with a helium-like bias '
                                'transient.')
    p.add_argument('--out', default='demo_out', metavar='DIR',
                   help='output directory (created; a previous demo output there is replaced '
                        'with --overwrite)')
    add_overwrite_argument(p, 'replace the previous demo output in --out (make demo gives it; '
                              'a folder that is not a demo output is never replaced)')
    p.add_argument('--quick', action='store_true', help='short story (about 1 minute) for tests')
    p.add_argument('--seed', type=int, default=1, help='seed of the emulated sensor')
    p.add_argument('--speed', type=float, default=1.0,
                   help='emulator pace as a multiple of real time (see the module doc before '
                   'raising it)')
    p.add_argument('--storage', default='sqlite3', choices=('sqlite3', 'mcap'), help='bag storage')
    p.add_argument('--jobs', type=int, default=2, help='worker processes of the offline analysis')
    p.add_argument('--domain-id', type=int, default=None,
                   help='ROS_DOMAIN_ID (default: one in 1..101 checked free on this host and held '
                   'while the demo runs)')
    return p


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    params = DemoParams(out=args.out, quick=args.quick, seed=args.seed, speed=args.speed,
                        storage=args.storage, jobs=args.jobs, domain_id=args.domain_id,
                        overwrite=args.overwrite)
    # a file in the way or an unwritable folder (whether it holds a demo output: run_demo)
    check_out_dir(Path(params.out), overwrite=True)
    result = run_demo(params)
    _print_outputs(result.report, result.elapsed_s)
    return 0


def _print_outputs(report: Path, elapsed_s: float) -> None:
    names = ['report.html', 'summary.md', 'summary.json', 'chunks.csv', 'allan.csv', 'imu.yaml']
    print(f'\n{PROG}: done in {elapsed_s:.0f} s. Tables and figures:', flush=True)
    for name in names:
        path = report / name
        if path.exists():
            print(f'  {path}')
    for path in sorted(report.glob('*.png')):
        print(f'  {path}')
    print(f'  (open {report / "report.html"} first; docs/demo.md explains every number)',
          flush=True)


def main(argv: list[str] | None = None) -> int:
    """
    Run the demo.

    Parameters
    ----------
    argv : list of str or None
        Arguments without the program name (None: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code (module doc).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
