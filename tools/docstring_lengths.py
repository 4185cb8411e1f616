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
List module docstrings over the limit and one-line functions with long docstrings.

A module docstring's length is its lines from the opening to the closing quotes; the contract of
a module (what it holds, its inputs and outputs, units, the paper's equations) fits in
``--module-limit`` lines (25), while measurements and history go to docs/. A one-line function
(one statement on one line after its docstring: a wrapper) whose docstring runs to
``--wrapper-limit`` lines (10) or more is listed too: its contract is short.

Usage::

    python tools/docstring_lengths.py [--module-limit 25] [--wrapper-limit 10] [ROOT ...]

Prints both lists (longest first); ROOT defaults to ``gyro_noise_ros``. Exits 1 when a module
docstring is over the limit, 0 otherwise (the wrappers are listed, not counted). Needs only the
standard library.
"""

import argparse
import ast
from pathlib import Path
import sys


def _docstring(node):
    """Return the docstring expression of a module, class or function, or None."""
    body = node.body
    if (body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
            and isinstance(body[0].value.value, str)):
        return body[0]
    return None


def docstring_lengths(source):
    """
    Return the module docstring's length and the one-line functions with their docstrings' lengths.

    Parameters
    ----------
    source : str
        Python source text.

    Returns
    -------
    int
        Lines of the module docstring (0 without one).
    list of (int, str, int)
        ``(docstring lines, qualified name, line of the def)`` of each function whose body after
        its docstring is one statement on one line.

    """
    tree = ast.parse(source)
    doc = _docstring(tree)
    module = doc.end_lineno - doc.lineno + 1 if doc else 0
    wrappers = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                fdoc = _docstring(child)
                rest = child.body[1:] if fdoc else child.body
                if fdoc and len(rest) == 1 and rest[0].lineno == rest[0].end_lineno:
                    wrappers.append((fdoc.end_lineno - fdoc.lineno + 1, prefix + child.name,
                                     child.lineno))
                visit(child, f'{prefix}{child.name}.')
            elif isinstance(child, ast.ClassDef):
                visit(child, f'{prefix}{child.name}.')

    visit(tree, '')
    return module, wrappers


def scan(roots):
    """
    Return the module docstring lengths and the one-line functions of every file under ``roots``.

    Parameters
    ----------
    roots : iterable of pathlib.Path
        Folders (or files) to scan.

    Returns
    -------
    list of (int, str)
        ``(lines, path)`` per module.
    list of (int, str)
        ``(docstring lines, 'path:line name')`` per one-line function.

    """
    modules, wrappers = [], []
    for root in roots:
        for path in sorted([root] if root.is_file() else root.rglob('*.py')):
            lines, found = docstring_lengths(path.read_text(encoding='utf-8'))
            modules.append((lines, path.as_posix()))
            wrappers += [(n, f'{path.as_posix()}:{line} {name}') for n, name, line in found]
    return modules, wrappers


def main(argv=None):
    """Print the long module docstrings and wrappers; exit 1 when a module is over the limit."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('roots', nargs='*', default=['gyro_noise_ros'], metavar='ROOT')
    parser.add_argument('--module-limit', type=int, default=25,
                        help='lines a module docstring may have (default 25)')
    parser.add_argument('--wrapper-limit', type=int, default=10,
                        help='docstring lines from which a one-line function is listed '
                        '(default 10)')
    args = parser.parse_args(argv)
    modules, wrappers = scan(map(Path, args.roots))
    over = sorted((m for m in modules if m[0] > args.module_limit), key=lambda m: (-m[0], m[1]))
    print(f'{len(over)} of {len(modules)} module docstrings over {args.module_limit} lines:')
    for n, name in over:
        print(f'{n:6d}  {name}')
    long = sorted((w for w in wrappers if w[0] >= args.wrapper_limit),
                  key=lambda w: (-w[0], w[1]))
    print(f'\n{len(long)} one-line functions with docstrings of {args.wrapper_limit}+ lines:')
    for n, name in long:
        print(f'{n:6d}  {name}')
    return 1 if over else 0


if __name__ == '__main__':
    sys.exit(main())
