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
Count the package's functions whose signatures carry type hints, per subpackage.

A function is typed when every parameter (``self`` and ``cls`` of methods aside) and its return
are annotated; an ``__init__`` with at least one annotated parameter may leave out ``-> None``,
as mypy allows. A function is public when its name does not start with one underscore (dunder
methods are public), it is not nested in a function, and no class holding it is private.

Usage::

    python tools/type_coverage.py [--all] [--list] [ROOT]

Prints, per subpackage (top-level modules under ``.``), public functions typed / public
functions, and with ``--all`` the same over every function, private and nested included. With
``--list`` it names each untyped function. Exits 1 when a counted function is untyped, 0
otherwise. ROOT defaults to ``gyro_noise_ros``. Needs only the standard library.
"""

import argparse
import ast
from pathlib import Path
import sys


def _typed(node):
    args = node.args
    params = args.posonlyargs + args.args + args.kwonlyargs
    if params and params[0].arg in ('self', 'cls') and isinstance(
            getattr(node, 'parent', None), ast.ClassDef):
        params = params[1:]
    params = params + [a for a in (args.vararg, args.kwarg) if a is not None]
    if any(p.annotation is None for p in params):
        return False
    if node.returns is not None:
        return True
    return node.name == '__init__' and bool(params)


def functions(path):
    """
    Yield ``(qualified name, line, public, typed)`` for every function in one file.

    Parameters
    ----------
    path : pathlib.Path
        A Python source file.

    Yields
    ------
    tuple of (str, int, bool, bool)
        The dotted name inside the module, the line of the ``def``, whether the function is
        public, and whether its signature is fully annotated.

    """
    tree = ast.parse(path.read_text(encoding='utf-8'))

    def walk(node, prefix, public, in_function):
        for child in ast.iter_child_nodes(node):
            child.parent = node
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = child.name
                private = name.startswith('_') and not (
                    name.startswith('__') and name.endswith('__'))
                is_public = public and not private and not in_function
                yield prefix + name, child.lineno, is_public, _typed(child)
                yield from walk(child, prefix + name + '.', False, True)
            elif isinstance(child, ast.ClassDef):
                yield from walk(child, prefix + child.name + '.',
                                public and not child.name.startswith('_'), in_function)
            else:
                yield from walk(child, prefix, public, in_function)

    yield from walk(tree, '', True, False)


def main(argv=None):
    """Print the per-subpackage counts; return 1 when a counted function is untyped."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('root', nargs='?', default='gyro_noise_ros')
    parser.add_argument('--all', action='store_true',
                        help='count private and nested functions too')
    parser.add_argument('--list', action='store_true', help='name each untyped function')
    options = parser.parse_args(argv)
    root = Path(options.root)
    totals = {}
    missing = []
    for path in sorted(root.rglob('*.py')):
        relative = path.relative_to(root)
        group = relative.parts[0] if len(relative.parts) > 1 else '.'
        for name, line, public, typed in functions(path):
            if not (public or options.all):
                continue
            done, count = totals.get(group, (0, 0))
            totals[group] = (done + typed, count + 1)
            if not typed:
                missing.append(f'{path}:{line}: {name}')
    what = 'functions' if options.all else 'public functions'
    print(f'{"subpackage":<14} typed / {what}')
    for group, (done, count) in sorted(totals.items()):
        print(f'{group:<14} {done:>5} / {count}')
    done = sum(d for d, _ in totals.values())
    count = sum(c for _, c in totals.values())
    print(f'{"total":<14} {done:>5} / {count}')
    if options.list:
        print('\n'.join(missing))
    return 1 if missing else 0


if __name__ == '__main__':
    sys.exit(main())
