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
What the lint tests scan: the package root and the folders they leave out.

ament_flake8 and ament_pep257 scan the directory they run in (``colcon test`` runs them from
the package root) and skip folders whose name starts with '.' or '_' (``.venv``, ``.git``,
``__pycache__``). Build trees, install spaces and demo results are excluded by name here.
"""

from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parent.parent

# by folder name, at any depth (flake8 matches exclude patterns against each path's basename)
EXCLUDED_DIRS = ('build', 'install', 'log', 'demo_out', 'out')

# the source folders whose every .py file carries the licence header
SOURCE_DIRS = ('gyro_noise_ros', 'test', 'bench', 'tools', 'docs/scripts', 'launch')
