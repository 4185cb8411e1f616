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
The scripts outside the package (docs/scripts, bench, tools) name only what the package has.

They run rarely (a table for the docs, a benchmark), so a renamed constant breaks them silently:
``lsm.STANDARD_GRAVITY`` survived the move to ``units.STANDARD_GRAVITY_M_S2`` in
docs/scripts/reliability_verdicts.py until the script was next run. mypy does not see it (the
scripts are not in its files, their functions untyped). This test reads every script's syntax
tree, resolves each ``from gyro_noise_ros... import NAME`` and each attribute read off an
imported package module (``module.NAME``), and checks that the package has the name.
"""

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted(p for d in ('docs/scripts', 'bench', 'tools') for p in (ROOT / d).glob('*.py'))


def _package_names(tree):
    """Yield (lineno, module, name) for every package name the script uses."""
    aliases = {}  # local name -> module path of an imported package module
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith('gyro_noise_ros'):
                    yield node.lineno, a.name, None
                    if a.asname:
                        aliases[a.asname] = a.name
        elif isinstance(node, ast.ImportFrom) and (node.module or '').startswith(
                'gyro_noise_ros'):
            for a in node.names:
                full = f'{node.module}.{a.name}'
                try:
                    importlib.import_module(full)  # a submodule: usable as a module alias
                    aliases[a.asname or a.name] = full
                except ImportError:
                    yield node.lineno, node.module, a.name
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in aliases and isinstance(node.ctx, ast.Load)):
            yield node.lineno, aliases[node.value.id], node.attr


def test_there_are_scripts_to_check():
    assert len(SCRIPTS) > 20, SCRIPTS


@pytest.mark.parametrize('script', SCRIPTS, ids=lambda p: f'{p.parent.name}/{p.name}')
def test_script_names_exist_in_the_package(script):
    tree = ast.parse(script.read_text(), filename=str(script))
    missing = []
    for lineno, module, name in _package_names(tree):
        try:
            mod = importlib.import_module(module)
        except ImportError as err:
            missing.append(f'{script.name}:{lineno}: import {module}: {err}')
            continue
        if name is not None and not hasattr(mod, name):
            missing.append(f'{script.name}:{lineno}: {module} has no {name!r}')
    assert not missing, '\n'.join(missing)


def test_the_check_sees_a_renamed_constant(tmp_path):
    """The check itself: the bug it was written for is found."""
    tree = ast.parse('from gyro_noise_ros.link import lsm6dso32 as lsm\n'
                     'g = lsm.STANDARD_GRAVITY\n'
                     'from gyro_noise_ros.units import RAD_TO_DEG, DEG\n')
    found = {(m, n) for _, m, n in _package_names(tree)}
    assert ('gyro_noise_ros.link.lsm6dso32', 'STANDARD_GRAVITY') in found
    assert ('gyro_noise_ros.units', 'DEG') in found
    assert not hasattr(importlib.import_module('gyro_noise_ros.link.lsm6dso32'),
                       'STANDARD_GRAVITY')
