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
The application layer: workflows shared by the command-line tools, the nodes, bench and tools.

Each module takes typed parameters (a frozen dataclass or keyword arguments), returns a frozen
result dataclass carrying every number, verdict and table the tool reports (``as_dict()`` is
exactly its JSON), and writes its files through :func:`gyro_noise_ros.outputs.staged_output`.
It imports the science below it (``core``, ``calibration``, ...) and never ROS or argparse.
"""
