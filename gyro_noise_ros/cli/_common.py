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
Shared plumbing of the command-line tools: one clear line and a documented exit code on error.

The exit codes and their meanings are owned by :data:`gyro_noise_ros.errors.EXIT_CODES` (the
README's table). :func:`run_cli` turns a :class:`~gyro_noise_ros.errors.GyroNoiseError` into its
code and one line, and SIGINT (Ctrl-C) and SIGTERM into an interrupt: every cleanup path runs
(staged outputs are removed), one ``<prog>: interrupted`` line is printed and the code is 130 or
143. The same cause gives the same code in every tool: a CSV that is empty, has the wrong header
or a non-numeric value is unreadable (3); a CSV with a header and no rows is readable but holds
nothing to analyse (4).
"""

import argparse
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
import logging
import math
import os
import signal
import sys
import threading
from typing import Any

from ._startup import quiet_finalisers, take_pending
from ..errors import (EXIT_INTERNAL, EXIT_INTERRUPTED, GyroNoiseError, Interrupted,
                      interrupted_exit_code, ParameterError)
from ..outputs import check_out_dir, free_bytes, OVERWRITE

__all__ = ['add_overwrite_argument', 'check_fits_disk', 'check_out_dir', 'EXIT_INTERRUPTED',
           'finite_float', 'option_of', 'OVERWRITE_BAG_HELP', 'OVERWRITE_FOLDER_HELP',
           'OVERWRITE_OPTION', 'run_cli', 'stop_signals', 'WarningLines']


class WarningLines(logging.Handler):
    """
    Say each warning the package logs (a killed recording read anyway) once, as one stderr line.

    The line is ``<prog>: warning: <message>``, the tools' form; a message said before in the
    same run is not repeated (a tool may open one bag several times).

    Parameters
    ----------
    prog : str
        Program name used as the line's prefix.

    """

    def __init__(self, prog: str) -> None:
        super().__init__(logging.WARNING)
        self.prog = prog
        self.said: set[str] = set()

    def emit(self, record: logging.LogRecord) -> None:
        """Print the record's message unless it was said already."""
        text = record.getMessage()
        if text not in self.said:
            self.said.add(text)
            print(f'{self.prog}: warning: {text}', file=sys.stderr, flush=True)


#: The option that lets a run replace existing data (``outputs.OVERWRITE``), in every tool.
OVERWRITE_OPTION = '--' + OVERWRITE
#: ``--overwrite`` help of a tool's output folder and of a new bag.
OVERWRITE_FOLDER_HELP = ('write into an --out folder that is not empty: files of the same names '
                         'are replaced, the others kept (without it such a folder is refused, '
                         'exit 6)')
OVERWRITE_BAG_HELP = ('replace an existing bag at --out when the new one is complete (a bag '
                      'folder only; without it an existing target is refused, exit 6)')


def add_overwrite_argument(parser: argparse.ArgumentParser | Any,
                           help_text: str = OVERWRITE_FOLDER_HELP) -> None:
    """
    Add ``--overwrite``, the one spelling every tool uses to let a run replace existing data.

    ``parser`` is a parser or an argument group, ``help_text`` what it lets replace
    (:data:`OVERWRITE_FOLDER_HELP`, :data:`OVERWRITE_BAG_HELP`).

    """
    parser.add_argument(OVERWRITE_OPTION, action='store_true', help=help_text)


def finite_float(text: str) -> float:
    """
    Parse a finite number (argparse ``type=``): ``nan`` and ``inf`` are refused by argparse.

    Parameters
    ----------
    text : str
        The option's value.

    Returns
    -------
    float

    """
    try:
        value = float(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from err
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'expected a finite number, got {text!r}')
    return value


def check_fits_disk(path: str | os.PathLike[str], need_bytes: float, what: str) -> None:
    """
    Refuse (exit code 2) a run whose output would not fit on the disk that holds ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        Where the output goes (need not exist yet).
    need_bytes : float
        Its estimated size (B).
    what : str
        The options that size it, for the message (e.g. ``'--samples 40000000'``).

    Raises
    ------
    ParameterError
        More than the free space (as an unprivileged user sees it).

    """
    free = free_bytes(path)
    if free is not None and need_bytes > free:
        raise ParameterError(f'{what} makes about {need_bytes / 2**30:.3g} GiB of output, more '
                             f'than the {free / 2**30:.3g} GiB free for {str(path)!r}')


#: Delay before a swallowed stop is delivered again (s).
REDELIVER_S = 0.05


class _StopRequest:
    """
    The signal handler of :func:`stop_signals`, and what it does when its exception is lost.

    The handler raises :class:`~gyro_noise_ros.errors.Interrupted` in whatever Python code runs
    at that moment. Where Python cannot propagate an exception (a ctypes callback such as
    llvmlite's object-cache hook while numba compiles, a ``__del__``), it reports it to
    ``sys.unraisablehook`` and goes on: the run would end normally, the signal ignored. The hook
    here notices that and sends the signal again a moment later, outside such code. While the
    cleanup of a raised stop runs, further signals are not raised again (the cleanup must end).
    """

    def __init__(self) -> None:
        self.raised = False
        self.signum: int = signal.SIGINT
        self.active = True
        self.lock = threading.Lock()
        self.previous_hook = sys.unraisablehook

    def handler(self, signum: int, frame: Any) -> None:
        if self.raised:
            return
        self.raised, self.signum = True, signum
        raise Interrupted(signum)

    def unraisable(self, unraisable: Any) -> None:
        if not isinstance(unraisable.exc_value, Interrupted):
            self.previous_hook(unraisable)
            return
        self.raised = False
        timer = threading.Timer(REDELIVER_S, self._redeliver)
        timer.daemon = True
        timer.start()

    def _redeliver(self) -> None:
        with self.lock:
            if self.active:
                os.kill(os.getpid(), self.signum)

    def close(self) -> None:
        with self.lock:
            self.active = False
        sys.unraisablehook = self.previous_hook


@contextmanager
def stop_signals() -> Iterator[None]:
    """
    Turn SIGINT and SIGTERM into :class:`~gyro_noise_ros.errors.Interrupted` while the block runs.

    In the main thread only (elsewhere Python cannot install handlers); a signal the parent set
    to be ignored stays ignored. A stop whose exception Python had to drop is delivered again
    (:class:`_StopRequest`). The previous handlers come back at the end.

    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    request = _StopRequest()
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            old[sig] = signal.signal(sig, request.handler)
    sys.unraisablehook = request.unraisable
    try:
        early = take_pending()  # a signal while the program imported its libraries
        if early is not None:
            raise Interrupted(early)
        yield
    finally:
        request.close()
        for sig, handler in old.items():
            signal.signal(sig, handler)


def option_of(parameter: str, renamed: Mapping[str, str] | None = None) -> str:
    """
    Return the command-line option of a parameter an error names.

    Parameters
    ----------
    parameter : str
        The parameter's name in the package (``min_range_c``).
    renamed : mapping, optional
        The tool's options whose name is not the parameter's (``{'start_s': '--start'}``).

    Returns
    -------
    str
        ``renamed[parameter]``, else ``--`` and the name with dashes (``--min-range-c``).

    """
    if renamed and parameter in renamed:
        return renamed[parameter]
    return '--' + parameter.replace('_', '-')


def run_cli(prog: str, body: Callable[[list[str]], int | None],
            argv: Sequence[str] | None, *, renamed: Mapping[str, str] | None = None) -> int:
    """
    Run ``body(argv)`` and turn deliberate errors into one line on stderr and an exit code.

    An error's parameters are spelled as the tool's options (:func:`option_of`). Meanwhile the
    warnings the package logs are said on stderr by a :class:`WarningLines`.

    Parameters
    ----------
    prog : str
        Program name used as the message prefix.
    body : callable
        ``body(argv) -> int``; may raise :class:`GyroNoiseError`.
    argv : list of str or None
        Arguments without the program name; ``None`` means ``sys.argv[1:]``.
    renamed : mapping, optional, keyword-only
        Passed to :func:`option_of`.

    Returns
    -------
    int
        The process exit code (``errors.EXIT_CODES``).

    """
    package_log = logging.getLogger('gyro_noise_ros')
    lines = WarningLines(prog)
    package_log.addHandler(lines)
    try:
        with stop_signals():
            return int(body(sys.argv[1:] if argv is None else list(argv)) or 0)
    except GyroNoiseError as err:
        print(f'{prog}: error: {err.spelled(lambda name: option_of(name, renamed))}',
              file=sys.stderr)
        return err.exit_code
    except SystemExit as err:  # argparse: a usage error (2, said) or --help/--version (0)
        return err.code if isinstance(err.code, int) else int(err.code is not None) * 2
    except KeyboardInterrupt as err:
        quiet_finalisers()
        code = interrupted_exit_code(err)
        print(f'{prog}: interrupted' + ('' if code == EXIT_INTERRUPTED else
                                        f' ({signal.Signals(code - 128).name})'),
              file=sys.stderr)
        return code
    except MemoryError as err:
        print(f'{prog}: error: out of memory ({err})', file=sys.stderr)
        return EXIT_INTERNAL
    finally:
        package_log.removeHandler(lines)
