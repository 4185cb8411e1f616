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

Exit codes (documented in the README):

====  ==========================================================================
0     success
1     unexpected internal error (a bug: please report the message)
2     bad command line or parameter value (argparse uses 2 as well)
3     a recording cannot be read (missing, corrupt, no or ambiguous topic, wrong type)
4     the data cannot be analysed (NaN/Inf or non-physical values, too short, constant,
      nothing left to analyse after ``--start``/``--end``)
5     the Portenta link cannot be used, or the Dask cluster is lost
6     an output cannot be written (``--out`` not writable, a file in the way, disk full)
130   interrupted (Ctrl-C, SIGTERM where a tool turns it into an interrupt); nothing is left
      under the outputs' final names
====  ==========================================================================

The same cause gives the same code in every tool: a CSV that is empty, has the wrong header
or a non-numeric value is unreadable (3); a CSV with a header and no rows is readable but holds
nothing to analyse (4).
"""

from collections.abc import Callable, Mapping, Sequence
import logging
import os
from pathlib import Path
import sys

from ..errors import GyroNoiseError, OutputError

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


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


def check_out_option(path: str | os.PathLike[str], *, option: str = '--out') -> None:
    """
    Refuse an output folder that cannot be made, before any long work (nothing is created).

    Parameters
    ----------
    path : str or os.PathLike
        The folder named by the user (may not exist yet).
    option : str, keyword-only
        How the user named it, for the message.

    Raises
    ------
    OutputError
        ``path`` is an existing file, lies under a file, or its nearest existing folder cannot be
        written (as root every folder is writable: the staging step then finds the rest).

    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise OutputError(f'{option} {str(out)!r} is an existing file, not a folder')
    ancestor = out
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.exists():
        return
    if not ancestor.is_dir():
        raise OutputError(f'{option} {str(out)!r} cannot be created: {str(ancestor)!r} is a '
                          'file')
    if not os.access(ancestor, os.W_OK | os.X_OK):
        what = 'is not writable' if ancestor == out else (
            f'cannot be created: {str(ancestor)!r} is not writable')
        raise OutputError(f'{option} {str(out)!r} {what}: permission denied')


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
        The process exit code.

    """
    package_log = logging.getLogger('gyro_noise_ros')
    lines = WarningLines(prog)
    package_log.addHandler(lines)
    try:
        return int(body(sys.argv[1:] if argv is None else list(argv)) or 0)
    except GyroNoiseError as err:
        print(f'{prog}: error: {err.spelled(lambda name: option_of(name, renamed))}',
              file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print(f'{prog}: interrupted', file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError as err:
        print(f'{prog}: error: out of memory ({err})', file=sys.stderr)
        return EXIT_INTERNAL
    finally:
        package_log.removeHandler(lines)
