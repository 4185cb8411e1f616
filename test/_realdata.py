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
Locate the third-party real recordings the tests read, or skip (fail under CI) without them.

The data sets live in ``shared/data/real`` (its README and one SOURCE.md per folder) and are
read at test time, never copied into the package: several licences forbid it. They are looked up
in the folder named by the environment variable ``GYRO_NOISE_REAL_DATA`` if it is set, else in
``../shared/data/real`` beside the repository (how CI lays it out). Without them a test skips
with one line naming where the data was expected and how to point at it; with ``CI=true`` a
missing data set fails the test, so CI cannot pass having checked nothing.
"""

import os
from pathlib import Path

import pytest

ENV_VAR = 'GYRO_NOISE_REAL_DATA'


def real_data_root():
    """
    Return the folder expected to hold the real data sets.

    Returns
    -------
    pathlib.Path
        ``$GYRO_NOISE_REAL_DATA`` if set, else ``../shared/data/real`` beside the repository.

    """
    configured = os.environ.get(ENV_VAR)
    if configured:
        return Path(configured)
    return Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'real'


def real_data(*parts):
    """
    Return the path of a real data file or folder; skip the test (fail under CI) if missing.

    Parameters
    ----------
    *parts : str
        Path components below the real-data root, e.g. ``('adis16405_static', 'x.npz')``.

    Returns
    -------
    pathlib.Path
        The existing path.

    """
    path = real_data_root().joinpath(*parts)
    if path.exists():
        return path
    message = (f'real data not found: {path} (set {ENV_VAR} to your copy of '
               f'shared/data/real, or put shared/ beside the repository)')
    if os.environ.get('CI', '').lower() in ('1', 'true', 'yes'):
        pytest.fail(message + '; CI=true requires it')
    pytest.skip(message)
