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
``gyro_noise_record repair`` for a killed recording.

``gyro_noise_record --ros-args ...`` runs the ROS 2 recorder node (the console script is
:mod:`gyro_noise_ros.nodes.record_main`). ``gyro_noise_record repair BAG [--out FIXED]`` needs no
ROS at all (rclpy is not even imported): it writes the complete rosbag2 (``metadata.yaml``
included, counts consistent) that a recorder killed by ``kill -9`` or a power loss would have left
at its last flush, from its MCAP or sqlite3 file, never modifying the input
(:func:`gyro_noise_ros.bag.repair.repair_bag`).

Example::

    gyro_noise_record repair run1 --out run1_fixed
"""

import argparse
import sys

from ._common import add_overwrite_argument, OVERWRITE_BAG_HELP, run_cli

PROG = 'gyro_noise_record repair'


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of ``gyro_noise_record repair``.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG, description='Write a complete rosbag2 (metadata.yaml included) from a '
        'recording whose recorder was killed; the input is only read.')
    p.add_argument('bag', metavar='BAG',
                   help='the recording: a bag folder, or its .db3 / .mcap file')
    p.add_argument('--out', help='new bag folder (default: BAG_repaired)')
    add_overwrite_argument(p, OVERWRITE_BAG_HELP)
    p.add_argument('--storage', choices=('sqlite3', 'mcap'),
                   help="storage of the new bag (default: the input's)")
    return p


def _repair(argv: list[str]) -> int:
    from ..bag.repair import repair_bag

    args = build_parser().parse_args(argv)
    res = repair_bag(args.bag, args.out, storage=args.storage, overwrite=args.overwrite)
    for topic, msgtype, count in res.topics:
        print(f'{topic}  {msgtype}  {count} messages')
    span = ((res.end_ns - res.start_ns) / 1e9
            if res.start_ns is not None and res.end_ns is not None else 0.0)
    print(f'{PROG}: wrote {res.messages} messages ({span:.3f} s) to {res.out} ({res.storage})',
          flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    """
    Run ``repair`` (the first argument must be ``repair``; the node: ``nodes.record_main``).

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; None: ``sys.argv[1:]``.

    Returns
    -------
    int
        repair: 0, 2 (bad command line, ROS 1 input), 3 (input unreadable), 6 (``--out``
        exists without ``--overwrite``, cannot be written, disk full), 130/143 (interrupted:
        nothing left under ``--out``); 2 without ``repair``.

    """
    args = sys.argv[1:] if argv is None else list(argv)
    if args[:1] == ['repair']:
        return run_cli(PROG, _repair, args[1:])
    # the node is gyro_noise_ros.nodes.record_main (the console script), above this layer
    print(f'{PROG}: error: this module runs `{PROG} repair ...`; the recorder node is '
          f'`{PROG} --ros-args ...` (python -m gyro_noise_ros.nodes.record_main)', file=sys.stderr)
    return 2


if __name__ == '__main__':
    sys.exit(main())
