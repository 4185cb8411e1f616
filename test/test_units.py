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
The unit factors of ``gyro_noise_ros.units``: the same doubles as before, and the only ones.

The modules that defined their own factor now import it; their outputs stay bit-identical only
if each shared constant is the exact double the module computed itself, so the values are
checked against every expression they replaced. A module-level assignment of a degree/radian
or gravity factor anywhere else in the package fails the scan below.
"""

import math
import re

from _lint_scope import PACKAGE_ROOT
from gyro_noise_ros import units
import numpy as np
import pytest

# Module-level definitions of a unit factor: NAME = 180/pi, pi/180, 9.80665 (with optional
# annotation). Factors written inline in an expression are not constants and are left alone.
_DEFINITION = re.compile(
    r'^[A-Za-z_][A-Za-z0-9_]*[ \t]*(?::[^=\n]+)?=[ \t]*'
    r'(?:180(?:\.0*)?[ \t]*/[ \t]*(?:np|numpy|math)\.pi'
    r'|(?:np|numpy|math)\.pi[ \t]*/[ \t]*180(?:\.0*)?'
    r'|9\.80665)[ \t]*(?:#.*)?$', re.MULTILINE)

# Modules other helpers were editing when the factors moved (one-line import swaps were not
# possible there); each still defines its own copy, to be replaced by an import from units.
_NOT_YET_MOVED: set = set()


def test_degree_factors_are_the_doubles_the_modules_computed():
    assert units.RAD_TO_DEG == 180.0 / math.pi == 180.0 / np.pi
    assert units.DEG_TO_RAD == math.pi / 180.0 == np.pi / 180.0 == math.radians(1.0)
    # the two are not exact reciprocals in floating point: each direction has its own constant
    assert units.RAD_TO_DEG * units.DEG_TO_RAD == pytest.approx(1.0, rel=1e-15)


def test_gravity_and_hour_factors():
    assert units.STANDARD_GRAVITY_M_S2 == 9.80665
    # both orders the modules used give the same double (IEEE multiplication commutes)
    assert units.MG_TO_M_S2 == 9.80665 * 1e-3 == 1e-3 * 9.80665
    assert units.S_PER_H == 3600.0


def test_no_module_defines_its_own_factor():
    found = []
    for path in sorted((PACKAGE_ROOT / 'gyro_noise_ros').rglob('*.py')):
        rel = path.relative_to(PACKAGE_ROOT).as_posix()
        if rel == 'gyro_noise_ros/units.py' or rel in _NOT_YET_MOVED:
            continue
        for match in _DEFINITION.finditer(path.read_text(encoding='utf-8')):
            found.append(f'{rel}: {match.group(0).strip()}')
    assert not found, 'import the factor from gyro_noise_ros.units instead:\n' + '\n'.join(found)
    # the list of modules still to move stays true: each really still defines one
    for rel in _NOT_YET_MOVED:
        assert _DEFINITION.search((PACKAGE_ROOT / rel).read_text(encoding='utf-8')), rel


def test_the_scan_finds_a_definition():
    # guard the pattern itself: each form the package used must match
    for line in ('DEG = 180.0 / math.pi', '_DEG = 180.0 / np.pi', 'DEG = np.pi / 180.0',
                 'RAD2DEG: float = 180 / math.pi', 'STANDARD_GRAVITY = 9.80665'):
        assert _DEFINITION.search(line), line
    assert not _DEFINITION.search('x = y * 180.0 / np.pi')
    # a match never runs over a line end (a docstring line with a colon above a definition)
    assert _DEFINITION.search('of :class:`X` and\n_RAD_TO_DEG = 180.0 / math.pi').group(0) == (
        '_RAD_TO_DEG = 180.0 / math.pi')
