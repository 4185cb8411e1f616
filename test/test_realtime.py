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
``realtime_priority`` of the driver and the compensator (``nodes/_realtime.py``).

The function is pure OS (no ROS): 0 changes nothing, a bad value or a refusal is one line naming
the parameter, and where the system allows it every thread of a process, those started before and
after the call, runs under ``SCHED_FIFO`` (checked in a child process, so this one stays normal).
"""

import errno
import os
import subprocess
import sys

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.nodes import _realtime
import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, 'SCHED_FIFO'), reason='SCHED_FIFO is Linux only')


def test_zero_changes_nothing(monkeypatch):
    def refuse(*_args):
        raise AssertionError('sched_setscheduler called for priority 0')
    monkeypatch.setattr(os, 'sched_setscheduler', refuse)
    assert _realtime.set_realtime_priority(0) == 0


@pytest.mark.parametrize('value', [-1, 100, True, 1.5, '10'])
def test_bad_values_name_the_parameter(value):
    with pytest.raises(ParameterError, match="parameter 'realtime_priority'"):
        _realtime.set_realtime_priority(value)


def test_refusal_is_one_line_with_the_remedy(monkeypatch):
    def refuse(*_args):
        raise PermissionError(errno.EPERM, 'Operation not permitted')
    monkeypatch.setattr(os, 'sched_setscheduler', refuse)
    with pytest.raises(ParameterError) as info:
        _realtime.set_realtime_priority(50, parameter='realtime_priority')
    text = str(info.value)
    assert '\n' not in text
    assert "'realtime_priority' = 50" in text and 'Operation not permitted' in text
    assert 'CAP_SYS_NICE' in text and 'set it to 0' in text


_CHILD = r"""
import os, sys, threading, time
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.nodes._realtime import set_realtime_priority
stop = threading.Event()
before = threading.Thread(target=stop.wait)
before.start()
try:
    changed = set_realtime_priority(7)
except ParameterError as err:
    print('REFUSED', err)
    stop.set()
    sys.exit(0)
after = threading.Thread(target=stop.wait)
after.start()
time.sleep(0.05)
tids = sorted(int(t) for t in os.listdir('/proc/self/task'))
print(changed, len(tids), all(os.sched_getscheduler(t) == os.SCHED_FIFO for t in tids),
      all(os.sched_getparam(t).sched_priority == 7 for t in tids))
stop.set()
"""


def test_every_thread_runs_fifo_or_the_refusal_is_clear():
    # Whether this machine allows SCHED_FIFO is not the code's choice: both outcomes are checked.
    out = subprocess.run([sys.executable, '-c', _CHILD], capture_output=True, text=True,
                         timeout=60, check=True).stdout.strip()
    if out.startswith('REFUSED'):
        assert "'realtime_priority' = 7: SCHED_FIFO refused" in out
        return
    changed, threads, fifo, priority = out.split()
    assert int(changed) >= 2  # the main thread and the one started before the call
    assert int(threads) == int(changed) + 1  # and the one started after it
    assert fifo == 'True' and priority == 'True'
