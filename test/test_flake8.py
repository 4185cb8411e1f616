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

flake8 checks files in a pool of forked processes. Forked from the test process, which holds the
threads of earlier tests (rclpy, Dask, numba), a worker once died of a segmentation fault and the
pool then waited for it forever; so the linter runs in a fresh interpreter of its own, with a
time limit.
"""

import json
import subprocess
import sys

from _lint_scope import EXCLUDED_DIRS, PACKAGE_ROOT
import pytest

_RUN = ('import json, sys\n'
        'from ament_flake8.main import main_with_errors\n'
        'rc, errors = main_with_errors(argv=sys.argv[1:])\n'
        'print(json.dumps([rc, errors]))\n')


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    proc = subprocess.run([sys.executable, '-c', _RUN, '--exclude', *EXCLUDED_DIRS],
                          cwd=PACKAGE_ROOT, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, f'ament_flake8 failed to run:\n{proc.stderr[-3000:]}'
    rc, errors = json.loads(proc.stdout.strip().splitlines()[-1])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
