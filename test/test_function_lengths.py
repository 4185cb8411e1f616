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
No function of the package is longer than 80 lines of code (docs/architecture.md).

The counter is ``tools/function_lengths.py``; its rule (code lines only, nested functions count
in the one that holds them) is checked here on a snippet counted by hand.
"""

import importlib.util

from _lint_scope import PACKAGE_ROOT

_spec = importlib.util.spec_from_file_location(
    'function_lengths', PACKAGE_ROOT / 'tools' / 'function_lengths.py')
function_lengths = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(function_lengths)

LIMIT = 80

SNIPPET = '''\
"""Module docstring: not code."""


def outer(a,
          b):
    """
    Docstring lines do not count.
    """
    # a comment line does not count

    text = """a string that is not a docstring
# counts, line by line"""

    def inner():
        """Nor does a nested docstring."""
        return a  # a trailing comment: the line counts

    return inner() + b


class Thing:
    """Class docstring."""

    def method(self):
        return 1
'''


def test_the_counter_counts_code_lines_only(tmp_path):
    pkg = tmp_path / 'pkg'
    pkg.mkdir()
    (pkg / 'mod.py').write_text(SNIPPET)
    code, found = function_lengths.function_lengths(pkg / 'mod.py', pkg)
    # def outer (2 lines), text = ... (2), def inner, return a, return inner() + b
    assert {name: n for n, name in found} == {
        'pkg.mod.outer': 7, 'pkg.mod.outer.inner': 2, 'pkg.mod.Thing.method': 2}
    # the 7 lines of outer, class Thing, def method, return 1
    assert code == 10


def test_no_function_over_80_lines_of_code(capsys):
    rc = function_lengths.main(['--limit', str(LIMIT), '--modules', '0',
                                str(PACKAGE_ROOT / 'gyro_noise_ros')])
    printed = capsys.readouterr().out
    assert rc == 0, f'split these into named steps (docs/architecture.md):\n{printed}'
