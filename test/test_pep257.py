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
The package passes ament_pep257 (docstring conventions, as ``colcon test`` checks them).

Run from the package root; ament_pep257 itself skips folders starting with '.' or '_'.
"""

from _lint_scope import EXCLUDED_DIRS, PACKAGE_ROOT
from ament_pep257.main import main
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257(monkeypatch):
    monkeypatch.chdir(PACKAGE_ROOT)
    rc = main(argv=['--exclude', *EXCLUDED_DIRS, '--', '.'])
    assert rc == 0, 'Found code style errors / warnings (listed above)'
