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
Pure diagnostic tasks of nodes whose status spans several science packages (no ROS).

Every node's ``/diagnostics`` status has the shape of a diagnostic_updater task: counters bumped
cheaply on the hot path, and on the timer a pure task that takes their differences, picks the
level from explicit limits in a thresholds dataclass and returns a
:class:`gyro_noise_ros.core.items.TaskStatus` (level, one-sentence message, key/values); the node
only wraps it in a ``DiagnosticStatus``. A task lives beside the science it judges when there is
one: the driver's link in :mod:`gyro_noise_ros.link.health`, the analyzer's axes in
:mod:`gyro_noise_ros.core.health`. The compensator judges the calibration, the thermal model's
state and its own throughput at once, so its task lives here
(:mod:`.compensation`) rather than in ``calibration/`` or ``thermal/``, neither of which should
import the other.
"""
