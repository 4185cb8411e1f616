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
List the package's longest functions and modules, in lines of code.

A function's lines of code are the lines from its ``def`` to its last statement that hold a
token of code: blank lines, comment lines and the lines of docstrings (its own and those of the
functions and classes nested in it) do not count; a nested function or class counts in the one
that holds it, and is also listed on its own. A module's count is the same over the whole file.

Usage::

    python tools/function_lengths.py [--limit 80] [--top 20] [--modules 10] [ROOT ...]

Prints the functions over ``--limit`` (all of them) or, with ``--top N``, the N longest, then the
``--modules`` longest modules; ROOT defaults to ``gyro_noise_ros``. Exits 1 when a function is
over the limit, so it can guard the rule; 0 otherwise. Needs only the standard library.
"""

import argparse
import ast
import io
from pathlib import Path
import sys
import tokenize

_NOT_CODE = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT,
             tokenize.DEDENT, tokenize.ENCODING, tokenize.ENDMARKER}


def code_lines(source):
    """
    Return the set of line numbers of ``source`` that hold code, docstrings left out.

    Parameters
    ----------
    source : str
        Python source text.

    Returns
    -------
    set of int
        1-based line numbers.

    """
    lines = set()
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type not in _NOT_CODE:
            lines.update(range(tok.start[0], tok.end[0] + 1))
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if (body and isinstance(body[0], ast.Expr)
                    and isinstance(body[0].value, ast.Constant)
                    and isinstance(body[0].value.value, str)):
                lines.difference_update(range(body[0].lineno, body[0].end_lineno + 1))
    return lines


def function_lengths(path, root):
    """
    Return the lines of code of one file and of every function in it.

    Parameters
    ----------
    path : pathlib.Path
        A Python file.
    root : pathlib.Path
        The folder module names are taken relative to (its parent, so they start with the
        package name).

    Returns
    -------
    int
        The file's lines of code.
    list of tuple
        ``[(lines of code, 'module.qualified_name'), ...]``, one per function.

    """
    source = path.read_text(encoding='utf-8')
    lines = code_lines(source)
    module = '.'.join(path.relative_to(root.parent).with_suffix('').parts)
    out = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                span = range(child.lineno, child.end_lineno + 1)
                out.append((sum(1 for n in span if n in lines), f'{module}.{prefix}{child.name}'))
                visit(child, f'{prefix}{child.name}.')
            elif isinstance(child, ast.ClassDef):
                visit(child, f'{prefix}{child.name}.')
            else:
                visit(child, prefix)

    visit(ast.parse(source), '')
    return len(lines), out


def main(argv=None):
    """Print the long functions and modules; exit 1 when a function is over the limit."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('roots', nargs='*', default=['gyro_noise_ros'], metavar='ROOT')
    parser.add_argument('--limit', type=int, default=80,
                        help='lines of code a function may have (default 80)')
    parser.add_argument('--top', type=int, default=0,
                        help='list the N longest functions instead of those over the limit')
    parser.add_argument('--modules', type=int, default=10,
                        help='how many of the longest modules to list (default 10)')
    args = parser.parse_args(argv)
    functions, modules = [], []
    for root in map(Path, args.roots):
        for path in sorted(root.rglob('*.py')):
            code, found = function_lengths(path, root)
            functions += found
            total = len(path.read_text(encoding='utf-8').splitlines())
            modules.append((code, total, path.as_posix()))
    functions.sort(key=lambda f: (-f[0], f[1]))
    over = [f for f in functions if f[0] > args.limit]
    shown = functions[:args.top] if args.top else over
    print(f'{len(over)} of {len(functions)} functions over {args.limit} lines of code'
          + (f'; the {len(shown)} longest:' if args.top else ':'))
    for n, name in shown:
        print(f'{n:6d}  {name}')
    if args.modules:
        modules.sort(key=lambda m: (-m[0], m[2]))
        print(f'\nthe {args.modules} longest modules (lines of code, lines):')
        for code, total, name in modules[:args.modules]:
            print(f'{code:6d} {total:6d}  {name}')
    return 1 if over else 0


if __name__ == '__main__':
    sys.exit(main())
