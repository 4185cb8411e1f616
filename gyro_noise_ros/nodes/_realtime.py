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
Real-time scheduling of a node's threads: ``SCHED_FIFO`` for the latency-critical chain.

A stabilisation loop needs the driver and the compensator to run when a sample arrives, not when
the scheduler gets round to them beside other busy processes: the usual answer on Linux is
``SCHED_FIFO`` (what ``chrt -f PRIO`` does). :func:`set_realtime_priority` gives it to every
thread the process has (rclpy's and Fast DDS's included; threads made later inherit it from the
thread that makes them). Measured effect and the limits it needs: ``docs/scale.md`` (latency).
This module imports no ROS; the node modules call it from their ``realtime_priority`` parameter.
"""

import os

from ..errors import ParameterError

#: The parameter's documentation, shared by the nodes' tables.
REALTIME_DOC = ('SCHED_FIFO priority of every thread of the process running the node (a '
                'container: all its nodes), 1-99 (as chrt -f); 0: normal scheduling. Keeps '
                'the latency with busy processes beside the chain (docs/scale.md); needs '
                'CAP_SYS_NICE or an rtprio limit (limits.conf)')


def set_realtime_priority(priority: int, *, parameter: str = 'realtime_priority',
                          task_dir: str = '/proc/self/task') -> int:
    """
    Put every thread of this process under ``SCHED_FIFO`` at ``priority`` (0: leave them).

    Parameters
    ----------
    priority : int
        1-99, or 0 for normal scheduling (nothing is changed).
    parameter : str, keyword-only
        The parameter's name, for the error.
    task_dir : str, keyword-only
        Directory listing the process's thread ids (Linux ``/proc/self/task``).

    Returns
    -------
    int
        Threads changed (0 when ``priority`` is 0).

    Raises
    ------
    ParameterError
        ``priority`` outside 0-99, or the system refuses ``SCHED_FIFO`` (no permission, not
        Linux): one line naming the parameter and what would allow it.

    """
    if isinstance(priority, bool) or not isinstance(priority, int) or not 0 <= priority <= 99:
        raise ParameterError(f"parameter '{parameter}' = {priority!r} must be an integer 0-99")
    if priority == 0:
        return 0
    policy = getattr(os, 'SCHED_FIFO', None)
    if policy is None or not os.path.isdir(task_dir):
        raise ParameterError(f"parameter '{parameter}' = {priority}: SCHED_FIFO is not available "
                             'on this system (Linux only); set it to 0')
    param = os.sched_param(priority)
    changed = 0
    for tid in sorted(int(name) for name in os.listdir(task_dir) if name.isdigit()):
        try:
            os.sched_setscheduler(tid, policy, param)
        except ProcessLookupError:  # a thread that ended since the listing
            continue
        except OSError as err:
            raise ParameterError(
                f"parameter '{parameter}' = {priority}: SCHED_FIFO refused ({err.strerror}); "
                'run with CAP_SYS_NICE (e.g. as root, or `setcap cap_sys_nice+ep` on the '
                'interpreter) or an rtprio limit >= the priority (/etc/security/limits.conf), '
                'or set it to 0') from err
        changed += 1
    return changed
