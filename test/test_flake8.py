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
The package passes ament_flake8 (the check ``colcon test`` runs on every ament_python package).

ament_flake8 scans the current directory, so the test runs from the package root whatever
directory pytest was started in. Folders starting with '.' or '_' (``.venv``, ``__pycache__``)
are skipped by ament_flake8 itself; build output and demo results are excluded here.
"""

from _lint_scope import EXCLUDED_DIRS, PACKAGE_ROOT
from ament_flake8.main import main_with_errors
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8(monkeypatch):
    monkeypatch.chdir(PACKAGE_ROOT)
    rc, errors = main_with_errors(argv=['--exclude', *EXCLUDED_DIRS])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
