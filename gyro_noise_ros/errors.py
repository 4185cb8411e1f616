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
Error hierarchy shared by the core, the link, the bag I/O and the command-line tools.

Every error the package raises on purpose derives from :class:`GyroNoiseError`; the command-line
tools and the nodes turn each class into one clear line and its exit code. Messages name the
offending argument and its value; an argument a caller chose is named by its parameter
(``{start_s}``), which each adapter spells its own way (:meth:`GyroNoiseError.spelled`). This
module owns the exit codes: :data:`EXIT_CODES` is the README's table (``tools/exit_codes.py``
prints it with the options spelled, ``test/test_bad_input.py`` compares them).
"""

from collections.abc import Callable, Sequence
import signal
from typing import Self

#: Exit codes of every tool and node, with the README's wording (the one owner of the codes); an
#: option is written as its parameter in braces, which ``tools/exit_codes.py`` spells.
EXIT_CODES = {
    0: 'success (never when nothing was analysed)',
    1: 'unexpected internal error (a bug: please report the message)',
    2: 'bad command line or parameter value, or an unknown node parameter (also a size or rate '
       'whose data cannot fit in memory or on the disk, a `{chunk_size}` whose order tables would '
       "need more than half of the machine's memory)",
    3: 'an input cannot be read (missing, corrupt, wrong format: an empty CSV, wrong CSV headers, '
       'a non-numeric value, a binary calibration or model file; no or ambiguous topic, wrong '
       'message type)',
    4: 'the data cannot be analysed (NaN/Inf or non-physical values such as 1e300 rad/s or a '
       'time stamp of 1e308 s, too short for any Allan deviation, constant, a CSV with a header '
       'and no rows, nothing left after `{start_s}`/`{end_s}`); `gyro_noise_analyze` analyses a '
       'record shorter than one chunk by its Allan deviation alone, saying so (exit 0)',
    5: 'the Portenta link cannot be used, or the Dask scheduler of `{scheduler}` cannot be '
       'reached or failed',
    6: 'an output cannot be written (not writable, under a file, disk full) or would replace '
       'existing data (an `{out}` folder that is not empty, an existing bag or file: give '
       '`{overwrite}`)',
    130: "interrupted by SIGINT (Ctrl-C): nothing under the outputs' final names (results are "
         'staged and published at the end; a recorder closes its bag)',
    143: 'interrupted by SIGTERM, as 130',
}
EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_INTERRUPTED = 128 + signal.SIGINT
EXIT_TERMINATED = 128 + signal.SIGTERM


class GyroNoiseError(Exception):
    """
    Base class of every deliberate error in gyro_noise_ros.

    Parameters
    ----------
    message : str
        One sentence. A parameter of the call that failed is written as its name in braces
        (``'{start_s} 12 s is past the record end 10 s'``) and listed in ``parameters``; other
        braces are kept as they are.
    parameters : sequence of str, keyword-only
        The parameter names the message holds in braces.

    """

    exit_code = 1

    def __init__(self, message: str = '', *, parameters: Sequence[str] = ()) -> None:
        super().__init__(message)
        self.parameters = tuple(parameters)

    def spelled(self, spell: Callable[[str], str] | None = None) -> str:
        """
        Return the message with each parameter spelled by ``spell`` (default: its bare name).

        Parameters
        ----------
        spell : callable, optional
            Parameter name -> the caller's name for it (a tool: its option, ``--start``).

        Returns
        -------
        str

        """
        text = str(self.args[0]) if self.args else ''
        for name in self.parameters:
            text = text.replace('{' + name + '}', spell(name) if spell else name)
        return text

    def prefixed(self, prefix: str) -> Self:
        """Return the same error with ``prefix`` before its message (its parameters kept)."""
        message = str(self.args[0]) if self.args else ''
        return type(self)(prefix + message, parameters=self.parameters)

    def __str__(self) -> str:
        """Return the message with the bare parameter names."""
        return self.spelled()


class ParameterError(GyroNoiseError, ValueError):
    """An option or argument has a value outside its documented range."""

    exit_code = 2


class UnstableModelError(ParameterError):
    """Simulation parameters describe an unstable (non-stationary) noise model."""


class InputDataError(GyroNoiseError, ValueError):
    """Samples cannot be analysed: NaN/Inf, too short, constant, or otherwise unusable."""

    exit_code = 4


class InputError(GyroNoiseError):
    """An input file cannot be read: missing, corrupt, binary where text is expected."""

    exit_code = 3


class BagError(InputError):
    """A recording cannot be read: missing, corrupt, no/ambiguous topic, wrong message type."""


class LinkError(GyroNoiseError):
    """The Portenta link cannot be used: bad port, no acknowledgement, bad configuration."""

    exit_code = 5


class OutputError(GyroNoiseError):
    """An output cannot be written: a folder not writable, a file in the way, disk full."""

    exit_code = 6


class Interrupted(KeyboardInterrupt):
    """
    A stop request by signal: a ``KeyboardInterrupt``, so every cleanup path runs for it.

    Parameters
    ----------
    signum : int
        The signal (``signal.SIGINT`` or ``signal.SIGTERM``).

    """

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signum)
        self.signum = int(signum)


def interrupted_exit_code(err: BaseException | None = None) -> int:
    """
    Return the exit code of an interrupt: 128 + the signal (130 for Ctrl-C, 143 for SIGTERM).

    ``err`` is the ``KeyboardInterrupt`` caught (an :class:`Interrupted` carries its signal).

    """
    return 128 + getattr(err, 'signum', signal.SIGINT)


class ClusterError(GyroNoiseError):
    """A Dask scheduler cannot be reached, or its cluster failed in the run."""

    exit_code = 5


def nothing_left_error(*, start_s: float | None = None, end_s: float | None = None,
                       record_end_s: float | None = None,
                       label: str | None = None) -> InputDataError:
    """
    Return the error of a ``start_s``/``end_s`` window that selects no sample (exit code 4).

    Parameters
    ----------
    start_s, end_s : float, optional, keyword-only
        The window (s after the record's first sample).
    record_end_s : float, optional, keyword-only
        The last sample's time (s after the first).
    label : str, optional, keyword-only
        Which record, as a message prefix.

    Returns
    -------
    InputDataError

    """
    prefix = f'{label}: ' if label else ''
    if start_s is not None and record_end_s is not None and start_s > record_end_s:
        why = f'{{start_s}} {start_s:g} s is past the record end {record_end_s:.6g} s'
    else:
        window = ' and '.join(f'{{{name}}} {value:g} s' for name, value in
                              (('start_s', start_s), ('end_s', end_s)) if value is not None)
        why = f'no sample between {window or "the window bounds"}'
        if record_end_s is not None:
            why += f' (the record spans 0-{record_end_s:.6g} s)'
    return InputDataError(f'{prefix}nothing left to analyse: {why}',
                          parameters=('start_s', 'end_s'))
