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
``imu_chain``: ``lsm6dso32_driver`` and ``imu_compensator`` in one process, no second DDS trip.

For a loop that needs the compensated gyro within a millisecond. Run as two processes, the
compensator takes each message back out of DDS: a second trip through the middleware and a
wake-up of its own thread, which is most of its CPU and of the latency it adds (docs/scale.md).
Here the driver's reader thread hands each read over to the compensator right after publishing
it (:meth:`~.compensator.ImuCompensatorNode.accept`, the serialised messages themselves) and the
compensator publishes ``imu/data_compensated`` from that thread: the same topics, messages,
parameters and diagnostics as the two nodes' own executables, the same bytes on
``imu/data_compensated`` (the compensator's steps unchanged, with ``temperature_sync`` ``latest``
or ``interpolate``). What differs: the compensator subscribes to nothing (another publisher on
``imu/data_raw``, a bag being played, is not compensated; its ``reliable`` and ``queue_depth``
do not apply), and a stalled compensator stalls the driver's next read (the board buffers it).

Parameters: each node's own, as its executable takes them. ``-p NAME:=VALUE`` and a parameter
file's ``/**`` section reach both nodes (each takes the names it has; a name neither has is
refused); a section keyed by node name (``lsm6dso32_driver:``, ``imu_compensator:``) reaches that
node only. ``config/lsm6dso32_driver.yaml`` and ``config/imu_compensator.yaml`` list them.
``realtime_priority`` is the process's (every thread, the reader's included): give it once, with
``-p``; where the two sections differ, the driver's non-zero value wins (it is set last).
"""

from collections.abc import Sequence
import sys
from typing import Any

from . import compensator, driver
from ._params import parameter_help, running_together
from ._ros_common import run_node
from ..thermal.run import ThermalMethod

PROG = 'imu_chain'

__all__ = ['build', 'main', 'PROG']


def build(*, thermal_model: ThermalMethod | None = None,
          **kwargs: Any) -> tuple[driver.Lsm6dso32Driver, compensator.ImuCompensatorNode]:
    """
    Build the two nodes: the compensator first, so that it gets the driver's first read.

    Parameters
    ----------
    thermal_model : ThermalMethod or None, keyword-only
        Passed to the compensator (embedding, tests).
    **kwargs
        Passed to both nodes (``parameter_overrides``, ``context``).

    Returns
    -------
    tuple
        ``(driver, compensator)``: destroy them in this order (the driver's thread stops first).

    """
    comp = compensator.ImuCompensatorNode(thermal_model=thermal_model, in_process=True, **kwargs)
    try:
        return driver.Lsm6dso32Driver(listeners=[comp.accept], **kwargs), comp
    except BaseException:
        comp.destroy_node()
        raise


def help_text() -> str:
    """``--help``: what the program does, then both nodes' parameter tables."""
    first = ' '.join((__doc__ or '').strip().split('\n\n')[0].split())
    parts = [f'usage: {PROG} [--help] [--ros-args [-p NAME:=VALUE ...] [--params-file FILE] '
             '[-r __ns:=/NAMESPACE] ...]', '', first, '',
             'The parameters of each node, as its own executable takes them; -p and a /** '
             'section reach both nodes, a section keyed by node name only that node.', '']
    for name, table in ((driver.NODE_NAME, driver.PARAMETERS),
                        (compensator.NODE_NAME, compensator.PARAMETERS)):
        parts += [f'== {name} ==', parameter_help(name, table).split('\n', 2)[2]]
    return '\n'.join(parts)


def main(args: Sequence[str] | None = None) -> int:
    """Run the chain until Ctrl-C or SIGTERM; exit code 2 for a bad parameter (one line)."""
    argv = list(sys.argv if args is None else args)
    with running_together((driver.PARAMETERS, compensator.PARAMETERS), argv):
        return run_node(build, argv, prog=PROG,
                        parameters=(*driver.PARAMETERS, *compensator.PARAMETERS),
                        help_text=help_text())


if __name__ == '__main__':
    sys.exit(main())
