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
ROS 2 node ``gyro_noise_monitor``: print the analyzers' ``/diagnostics`` as compact lines.

``gyro_noise_monitor [--filter TEXT] [--changes] [--compact]`` prints one line per status whose
name contains ``TEXT`` (default ``': axis '``, every analyzer axis), or with ``--compact`` one line
per analyzer and array (all axes, what ``make demo`` shows); with ``--changes`` (implied by
``--compact``) a status is printed again only when its level or chunk count changed. The line
format is :mod:`gyro_noise_ros.monitor_lines`.
"""

import argparse
from collections.abc import Sequence
import sys
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from ._ros_common import run_node
from ..monitor_lines import chunks_done, format_array, format_status, progress_state

NODE_NAME = 'gyro_noise_monitor'


class DiagnosticsMonitor(Node):
    """
    Print the ``/diagnostics`` statuses whose name contains ``name_filter``.

    Parameters
    ----------
    name_filter : str
        Substring of the status names to print.
    only_changes : bool
        Print a status (or node) again only when its level or chunk count changed.
    compact : bool
        One line per node and array instead of one per status.

    """

    def __init__(self, name_filter: str, *, only_changes: bool = False,
                 compact: bool = False) -> None:
        super().__init__(NODE_NAME)
        self._filter = name_filter
        self._only_changes = only_changes or compact
        self._compact = compact
        self._last: dict[str, object] = {}
        self.create_subscription(DiagnosticArray, '/diagnostics', self._on_array, 100)

    def _changed(self, key: str, state: object) -> bool:
        if self._only_changes and self._last.get(key) == state:
            return False
        self._last[key] = state
        return True

    def _on_array(self, msg: DiagnosticArray) -> None:
        mine = [s for s in msg.status if self._filter in s.name]
        if not self._compact:
            for status in mine:
                if self._changed(status.name, progress_state(status)):
                    print(format_status(status), flush=True)
            return
        by_node: dict[str, list[Any]] = {}
        for status in mine:
            by_node.setdefault(status.name.split(': ', 1)[0], []).append(status)
        for node_name, statuses in by_node.items():
            # A new line when every axis has finished the next chunk, or when a level changed; not
            # for the periodic repeats nor for one axis finishing ahead of the others.
            states = [progress_state(s) for s in statuses]
            if self._changed(node_name, (tuple(s[0] for s in states), chunks_done(states))):
                print(format_array(statuses), flush=True)


def parse_args(argv: Sequence[str]) -> argparse.Namespace:
    """Parse the monitor's own options from ``argv`` (no program name, no ROS arguments)."""
    return build_parser().parse_args(argv)


def build_parser() -> argparse.ArgumentParser:
    """
    Return the parser of the monitor's own options (as the tools' ``build_parser``).

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(prog=NODE_NAME,
                                description="Print the analyzers' /diagnostics as compact lines.")
    p.add_argument('--filter', default=': axis ', metavar='TEXT',
                   help="print statuses whose name contains TEXT (default ': axis ')")
    p.add_argument('--changes', action='store_true',
                   help='print a status again only when its level or chunk count changed')
    p.add_argument('--compact', action='store_true',
                   help='one line per analyzer and array (implies --changes)')
    return p


def main(args: list[str] | None = None) -> int:
    """
    Run the monitor until Ctrl-C.

    Parameters
    ----------
    args : list of str or None
        Command line including the program name (None: ``sys.argv``).

    Returns
    -------
    int
        0, or 2 for a bad option.

    """
    argv = sys.argv if args is None else list(args)
    try:
        plain = remove_ros_args(argv)[1:]
    except RuntimeError:  # malformed --ros-args: rclpy.init (run_node) says so in one line
        plain = []
    try:
        opts = parse_args(plain)
    except SystemExit as err:
        return int(err.code or 0)
    return run_node(lambda: DiagnosticsMonitor(opts.filter, only_changes=opts.changes,
                                               compact=opts.compact), argv, prog=NODE_NAME)


if __name__ == '__main__':
    sys.exit(main())
