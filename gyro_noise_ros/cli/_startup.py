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
Signals that reach a tool or node program before its ``main()`` runs, while it imports.

Importing numpy, numba, scipy and rosbags takes one to three seconds; a SIGINT then would end the
program with a ``KeyboardInterrupt`` traceback and a SIGTERM without a word. When the process was
started as one of this package's programs (a console script of its distribution, or
``python -m gyro_noise_ros...``), :func:`install` (called by ``cli/__init__.py`` and
``nodes/__init__.py``) ends it at once on such a signal, with the one ``interrupted`` line and
130/143 (nothing has been written yet). Once ``main()`` runs (``cli/_common.run_cli``,
``nodes/_ros_common.run_node`` call :func:`take_pending`) their own handlers take over and a
signal is only noted. Imported by another program (a test, a user's script) it does nothing.
It writes to stderr, so it lives with the adapters (cli/); the nodes import it from here.
"""

import os
import re
import signal
import sys
import threading

__all__ = ['install', 'launched_as_program', 'quiet_finalisers', 'take_pending']

_pending: list[int] = []
_main_started: list[bool] = []  # take_pending() ran: main() has its own handlers
_installed: list[bool] = []
_program: list[bool] = []  # install() found this process to be one of the package's programs
#: A console script of the distribution: pip's stub imports ``main`` from a package module,
#: setuptools' loads the entry point of the distribution by name.
_STUB = re.compile(rb'from gyro_noise_ros\.[\w.]+ import main\b|'
                   rb"load_entry_point\(\s*'gyro[-_]noise[-_]ros")
_STUB_BYTES = 1024


def launched_as_program() -> bool:
    """
    Tell whether this process runs one of the package's programs.

    Returns
    -------
    bool
        ``python -m gyro_noise_ros.*``, or a console script of the gyro_noise_ros distribution.

    """
    argv = list(getattr(sys, 'orig_argv', []))
    if '-m' in argv[:-1]:
        return argv[argv.index('-m') + 1].startswith('gyro_noise_ros.')
    script = sys.argv[0] if sys.argv else ''
    if not script or script.endswith('.py'):
        return False
    try:
        with open(script, 'rb') as fh:
            stub = fh.read(_STUB_BYTES + 1)
    except OSError:
        return False
    # only the few lines pip or setuptools write for a console script: a user's own program that
    # imports the package keeps its Ctrl-C
    return len(stub) <= _STUB_BYTES and _STUB.search(stub) is not None


def _program_name() -> str:
    """Return the name the program's messages start with (its ``PROG``), from its command line."""
    argv = list(getattr(sys, 'orig_argv', []))
    rest = sys.argv[1:2]
    if '-m' in argv[:-1]:
        module = argv[argv.index('-m') + 1]
        from importlib.metadata import entry_points

        names = [e.name for e in entry_points(group='console_scripts')
                 if e.value.split(':')[0] == module]
        name = names[0] if names else 'gyro_noise_' + module.rsplit('.', 1)[-1]
    else:
        name = os.path.basename(sys.argv[0])
    return name + (' repair' if name == 'gyro_noise_record' and rest == ['repair'] else '')


def _note(signum: int, frame: object) -> None:
    if _main_started:
        if not _pending:
            _pending.append(signum)
        return
    # still importing: nothing is written yet, so end now rather than after the imports
    suffix = '' if signum == signal.SIGINT else f' ({signal.Signals(signum).name})'
    try:
        sys.stderr.write(f'{_program_name()}: interrupted{suffix}\n')
        sys.stderr.flush()
    finally:
        os._exit(128 + signum)


def install() -> None:
    """Note SIGINT and SIGTERM until ``main()`` takes over, in a program of this package only."""
    if _installed or threading.current_thread() is not threading.main_thread():
        return
    _installed.append(True)
    if not launched_as_program():
        return
    _program.append(True)
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:  # a parent's "ignore" stays
            signal.signal(sig, _note)


def _silent(unraisable: object) -> None:
    """Drop an error raised while an object is finalised (``sys.unraisablehook``)."""


def quiet_finalisers() -> None:
    """
    Keep half-built objects of an interrupted run from printing tracebacks at exit.

    A signal that lands inside a library's constructor (llvmlite building a pass manager while
    numba compiles) leaves an object whose ``__del__`` fails when the interpreter collects it;
    Python would print ``Exception ignored in ...`` and a traceback after the one ``interrupted``
    line. Called once a run is interrupted, never on a normal run; only in a program of the
    package (a test or a user's program that calls ``main()`` keeps its hook).

    """
    if _program:
        sys.unraisablehook = _silent


def take_pending() -> int | None:
    """
    Return the signal that arrived before ``main()`` (and forget it), or None.

    Returns
    -------
    int or None

    """
    _main_started.append(True)
    return _pending.pop() if _pending else None
