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
The participant profile of the package's nodes: a dead subscriber is dropped in 3 s, not 20.

A reliable writer keeps every message for each matched reliable reader until that reader
acknowledges it or leaves the graph. A reader killed with ``kill -9`` (a crashed recorder) never
leaves: the writer keeps it until its participant's lease expires, 20 s by default in Fast DDS,
and meanwhile each write costs time in proportion to the history depth. Measured on the 2-core
test machine (a publisher at 6.66 kHz, a live reader beside a reliable one killed -9; docs/scale.md
"A subscriber killed -9"): at depth 60,000 (the lab configuration) the live reader received
1,000-2,000 messages/s for ~20 s, then nothing for 2-3 s, then the backlog; at depth 10,000
4,600/s; at 5,000 (the driver's default) it kept up. With the dead reader's participant
announcing a 3-s lease it is dropped within seconds and the live reader dips for a second.

The lease is announced by each participant for itself, so every node of the package announces
``LEASE_S`` (re-announced every ``ANNOUNCE_S``): :func:`use_package_profile` points Fast DDS at
``fastdds_participant.xml`` before ``rclpy.init``, unless the user chose a profile file
(``FASTRTPS_DEFAULT_PROFILES_FILE`` or ``FASTDDS_DEFAULT_PROFILES_FILE`` set: theirs is used as
given) or another middleware (``RMW_IMPLEMENTATION`` other than ``rmw_fastrtps_cpp``).
Subscribers outside the package (``ros2 bag record``, rviz) keep their own lease: give them a
profile with a short ``leaseDuration`` too, or keep the driver's ``qos_depth`` at its default.
"""

import os
from pathlib import Path

#: The profile file shipped beside this module.
PROFILE = Path(__file__).with_name('fastdds_participant.xml')
#: Lease the package's participants announce, and how often they re-announce it (s).
LEASE_S, ANNOUNCE_S = 3.0, 0.5
_USER_FILES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')


def use_package_profile() -> bool:
    """
    Use the package's participant profile for this process (before ``rclpy.init``).

    Returns
    -------
    bool
        True when the profile was set; False when the user's choice stands (a profile file of
        their own, another middleware) or the file is missing.

    """
    rmw = os.environ.get('RMW_IMPLEMENTATION', '')
    if rmw not in ('', 'rmw_fastrtps_cpp') or any(os.environ.get(k) for k in _USER_FILES):
        return False
    if not PROFILE.is_file():
        return False
    os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(PROFILE)
    return True
