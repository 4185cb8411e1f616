#!/usr/bin/env python3
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
Count the wrappers whose docstrings outweigh them: one-statement functions with long docstrings.

A wrapper is a function whose body after its docstring is a single simple statement, on one
line or several (``return f(x, scale=2)`` over three lines; not an ``if``, ``with`` or ``try``
block). Its contract is what it adds to the function it wraps: a summary line, the parameters
that differ and a pointer such as ``:func:`f```. A wrapper whose docstring runs to ``--limit``
lines (10) or more is listed (issue 34; ``tools/docstring_lengths.py`` lists the one-line subset
beside the modules).

Usage::

    python tools/wrapper_docstrings.py [--limit 10] [--exclude LIST] [--max N] [ROOT ...]

Prints the count and the wrappers, longest docstring first; ROOT defaults to ``gyro_noise_ros``.
``--exclude`` names a file listing paths (one a line, relative to the current folder) to skip.
Exits 1 when more than ``--max`` wrappers are listed (with ``--max``), 0 otherwise. Needs only the
standard library.
"""

import argparse
import ast
from pathlib import Path
import sys


#: Statements that hold a block: a function made of one of them is not a wrapper.
_COMPOUND = (ast.If, ast.For, ast.AsyncFor, ast.While, ast.With, ast.AsyncWith, ast.Try,
             ast.Match, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)


def wrappers(source: str, limit: int = 10) -> list[tuple[int, str, int]]:
    """
    Return the one-simple-statement functions of ``source`` with docstrings of ``limit``+ lines.

    Parameters
    ----------
    source : str
        Python source text.
    limit : int
        Docstring lines (from the opening to the closing quotes) from which a wrapper is listed.

    Returns
    -------
    list of (int, str, int)
        ``(docstring lines, qualified name, line of the def)`` in source order; methods and nested
        functions are named ``Outer.name``.

    """
    found: list[tuple[int, str, int]] = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                body = child.body
                if (len(body) == 2 and isinstance(body[0], ast.Expr)
                        and isinstance(body[0].value, ast.Constant)
                        and isinstance(body[0].value.value, str)
                        and not isinstance(body[1], _COMPOUND)):
                    lines = (body[0].end_lineno or body[0].lineno) - body[0].lineno + 1
                    if lines >= limit:
                        found.append((lines, prefix + child.name, child.lineno))
                visit(child, f'{prefix}{child.name}.')
            elif isinstance(child, ast.ClassDef):
                visit(child, f'{prefix}{child.name}.')

    visit(ast.parse(source), '')
    return found


def main(argv: list[str] | None = None) -> int:
    """Print the count and the long-docstring wrappers; exit 1 when over ``--max``."""
    parser = argparse.ArgumentParser(description=(__doc__ or '').split('\n\n')[0].strip())
    parser.add_argument('roots', nargs='*', default=['gyro_noise_ros'], metavar='ROOT')
    parser.add_argument('--limit', type=int, default=10,
                        help='docstring lines from which a wrapper is listed (default 10)')
    parser.add_argument('--exclude', type=Path, metavar='LIST',
                        help='file of paths (one a line) whose wrappers are not listed')
    parser.add_argument('--max', type=int, metavar='N',
                        help='exit 1 when more than N wrappers are listed')
    args = parser.parse_args(argv)
    skip = set()
    if args.exclude is not None:
        skip = {line.strip() for line in args.exclude.read_text(encoding='utf-8').splitlines()
                if line.strip()}
    rows = []
    for root in map(Path, args.roots):
        for path in sorted([root] if root.is_file() else root.rglob('*.py')):
            if path.as_posix() in skip:
                continue
            rows += [(n, f'{path.as_posix()}:{line} {name}')
                     for n, name, line in wrappers(path.read_text(encoding='utf-8'), args.limit)]
    rows.sort(key=lambda row: (-row[0], row[1]))
    print(f'{len(rows)} one-statement functions with docstrings of {args.limit}+ lines'
          + (f' (skipping the {len(skip)} paths in {args.exclude})' if skip else '') + ':')
    for n, name in rows:
        print(f'{n:6d}  {name}')
    return 1 if args.max is not None and len(rows) > args.max else 0


if __name__ == '__main__':
    sys.exit(main())
