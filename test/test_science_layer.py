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
The science layer knows no command line (docs/architecture.md: no print, argparse or flag names).

Below ``app/`` a module returns numbers and raises errors; the adapters print, parse and spell
options. This test reads the syntax tree of every science module (the packages of
:data:`SCIENCE` and the package's top-level modules) and lists each ``print(...)``,
``sys.exit``/``sys.stdout``/``sys.stderr``, ``import argparse`` and string (docstrings aside)
holding a ``--flag``. An error names a parameter as ``{name}`` instead (errors.py), which the
tools spell as their option (cli/_common.py: ``option_of``).
"""

import ast
import re

from _lint_scope import PACKAGE_ROOT
import pytest

SCIENCE = ('core', 'calibration', 'thermal', 'explain', 'analysis', 'htmlreport', 'bag', 'link',
           'msgs', 'diagnostics')
_PACKAGE = PACKAGE_ROOT / 'gyro_noise_ros'
_FILES = sorted([p for d in SCIENCE for p in (_PACKAGE / d).rglob('*.py')]
                + list(_PACKAGE.glob('*.py')))
_FLAG = re.compile(r'(?<![\w-])--[a-z][a-z0-9-]*')


def _docstrings(tree):
    """Ids of the docstring nodes of a module, its classes and functions."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def command_line_traces(source, name='<module>'):
    """Return ``['name:line: what', ...]`` for each trace of a command line in ``source``."""
    tree = ast.parse(source)
    docs = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        what = None
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and (
                node.func.id == 'print'):
            what = 'print()'
        elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
              and node.value.id == 'sys' and node.attr in ('exit', 'stdout', 'stderr')):
            what = f'sys.{node.attr}'
        elif isinstance(node, ast.Import) and any(a.name == 'argparse' for a in node.names):
            what = 'import argparse'
        elif isinstance(node, ast.ImportFrom) and node.module == 'argparse':
            what = 'from argparse import'
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str)
              and id(node) not in docs and _FLAG.search(node.value)):
            what = f'the flag {_FLAG.search(node.value).group()}'
        if what:
            found.append(f'{name}:{node.lineno}: {what}')
    return found


def test_the_check_sees_each_kind_of_trace():
    snippet = '''"""Docstring: run with --out DIR (documentation may name a tool's options)."""
import argparse
import sys


def f(x):
    """Say --x here freely."""
    print(x, file=sys.stderr)
    if x:
        sys.exit(1)
    raise ValueError(f'--rate-hz {x} is bad; {{rate_hz}} is the way; a-- b, 1--2 ranges')
'''
    assert [t.split(': ', 1)[1] for t in command_line_traces(snippet)] == [
        'import argparse', 'print()', 'sys.stderr', 'sys.exit', 'the flag --rate-hz']


def test_there_are_science_modules():
    assert len(_FILES) > 100 and _PACKAGE / 'errors.py' in _FILES


@pytest.mark.parametrize('package', [*SCIENCE, 'top-level modules'])
def test_no_command_line_below_the_application(package):
    files = ([p for p in _FILES if p.parent == _PACKAGE] if package == 'top-level modules'
             else [p for p in _FILES if (_PACKAGE / package) in p.parents])
    traces = [t for p in files
              for t in command_line_traces(p.read_text(), str(p.relative_to(PACKAGE_ROOT)))]
    assert not traces, 'the adapters print, parse and name options:\n' + '\n'.join(traces)
