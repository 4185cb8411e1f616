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

1. ``noise_analyzer``, ``gyro_noise_record``, ``gyro_noise_monitor`` and ``lsm6dso32_driver``;
2. ``portenta_emulator`` on a loopback TCP port, seeded, in real time (``--speed 1``), with a
   scripted helium-like bias transient: a quiet phase, then a first-order rise of each bias;

prints the analyzer's diagnostics as they arrive (one line per chunk), and checks the story: OK in
the quiet phase, WARN (offset drift above its limit) when the bias rises. It then stops the live
part (driver first), runs ``gyro_noise_analyze`` on the recording, and prints where the report is.
The demo's thresholds are ordinary analyzer parameters; their values and reasons (absolute drift
limits over a sliding window, a lost-sample allowance for a shared host, why not ``--speed k``)
are in docs/demo.md.

Exit status: 0 when the story ran and the report was written; 1 when a component failed (its log
is named) or the drift was not detected; 2 for a bad option; 6 when ``--out`` cannot be used;
130 on Ctrl-C, 143 on SIGTERM. Every subprocess is stopped on every path; ``GYRO_NOISE_DEMO.txt``
in ``--out`` says whether the run finished. The workflow is
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
    Run the demo; return its exit code (module docstring).

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
