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
The package passes ament_copyright (for colcon users: ament_copyright is not on PyPI).

Without the module the test is skipped with the reason; ``test_license_headers.py`` checks
the same headers without it.
"""

from _lint_scope import PACKAGE_ROOT
import pytest

try:
    from ament_copyright.main import main
except ImportError:  # pragma: no cover - depends on the installation
    main = None


@pytest.mark.copyright
@pytest.mark.linter
@pytest.mark.skipif(main is None, reason='ament_copyright is not installed (it is not on PyPI; '
                    'colcon users get it from ros-jazzy-ament-copyright); '
                    'test_license_headers.py checks the headers instead')
def test_copyright(monkeypatch):
    monkeypatch.chdir(PACKAGE_ROOT)
    # ament_copyright skips folders starting with '.' or '_' itself; its --exclude takes file
    # names, not folders (a build/ tree holds copies of these same files, headers included)
    rc = main(argv=['.'])
    assert rc == 0, 'Found errors (listed above)'
