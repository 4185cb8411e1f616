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
The application layer: workflows with typed parameters and result objects.

Shared by the command-line tools (``cli/``), the ROS nodes (``nodes/``), ``bench/`` and
``tools/``: each workflow is a function taking explicit keyword parameters and returning a frozen
result object that carries every number, verdict and table the tool reports (``as_dict()`` is
what goes into its JSON), plus a ``write_<tool>(result, out_dir)`` that writes the files through
:func:`gyro_noise_ros.outputs.staged_output`. No ROS is imported here.
"""
