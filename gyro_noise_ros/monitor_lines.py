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
One-line forms of the analyzer's diagnostics, and their parser (pure, no ROS).

``gyro_noise_monitor`` (``gyro_noise_ros.nodes.monitor``) prints these lines; ``make demo``
(``gyro_noise_ros.cli.demo``) reads them back with :func:`parse_axis_parts`, so the format and its
parser live side by side.

A status is anything shaped like ``diagnostic_msgs/DiagnosticStatus``: ``name``, ``level`` (int
or one byte), ``message`` and ``values`` (items with ``key`` and ``value``).
"""

from collections.abc import Iterable, Sequence
import re
from typing import Any

LEVEL_NAMES = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}

_ECHO_KEYS = (('Bias (deg/s)', 'bias'), ('Fractional order, variance method', 'a_var'),
              ('Fractional order, correlation method', 'a_corr'),
              ('Offset drift ((deg/s)/h)', 'drift (deg/s)/h'), ('Samples lost', 'lost'),
              ('Chunks analysed', 'chunks'), ('Chunks skipped', 'skipped'))

#: One axis part of a :func:`format_array` line: axis, level, drift ((deg/s)/h).
AXIS_PART = re.compile(r'\b([xyz]) (OK|WARN|ERROR|STALE) bias \S+ drift (\S+)')


def level_of(status: Any) -> int:
    """
    Return the level of a status as an int (0 OK, 1 WARN, 2 ERROR, 3 STALE).

    Parameters
    ----------
    status : DiagnosticStatus-like
        One status.

    Returns
    -------
    int

    """
    level = status.level
    return level[0] if isinstance(level, (bytes, bytearray)) else int(level)


def values_of(status: Any) -> dict[str, str]:
    """Return the key/values of a DiagnosticStatus-like ``status`` as a dict."""
    return {kv.key: kv.value for kv in status.values}


def format_status(status: Any) -> str:
    """
    Return the compact one-line form of one analyzer status (level, name, key numbers, message).

    Parameters
    ----------
    status : DiagnosticStatus-like
        One status.

    Returns
    -------
    str

    """
    level = LEVEL_NAMES.get(level_of(status), '?')
    values = values_of(status)
    numbers = ' '.join(f'{short}={values[key]}' for key, short in _ECHO_KEYS if key in values)
    return f'{level:<5} {status.name}: {numbers} | {status.message}'


def format_array(statuses: Sequence[Any]) -> str:
    """
    Return one line for all axes of one analyzer (the ``--compact`` form ``make demo`` prints).

    Parameters
    ----------
    statuses : list of DiagnosticStatus-like
        The axis statuses of one node from one ``DiagnosticArray``.

    Returns
    -------
    str
        ``'<worst level> chunk <n> | x OK bias .. drift .. a ../.. | ... | lost N -- axis: msg'``.

    """
    levels = [level_of(status) for status in statuses]
    worst_i = max(range(len(statuses)), key=lambda i: (levels[i], -i))
    parts: list[str] = []
    chunk = lost = '?'
    for status, level in zip(statuses, levels):
        v = values_of(status)
        axis = status.name.rsplit(' ', 1)[-1]
        chunk = v.get('Last chunk', '-').split(' ')[0]
        lost = v.get('Samples lost', '?').split(' ')[0]
        parts.append(f"{axis} {LEVEL_NAMES.get(level, '?')} bias {v.get('Bias (deg/s)', '-')} "
                     f"drift {v.get('Offset drift ((deg/s)/h)', '-')} "
                     f"a {v.get('Last chunk fractional order, variance method', '-')}/"
                     f"{v.get('Last chunk fractional order, correlation method', '-')}")
    worst = statuses[worst_i]
    head = f'{LEVEL_NAMES.get(levels[worst_i], "?"):<5} chunk {chunk:>4}'
    tail = f'lost {lost}'
    if levels[worst_i]:
        tail += f' -- axis {worst.name.rsplit(" ", 1)[-1]}: {worst.message}'
    return ' | '.join([head, *parts, tail])


def progress_state(status: Any) -> tuple[int, str | None, str | None]:
    """
    Return what makes a status worth printing again: level and chunk counts.

    Parameters
    ----------
    status : DiagnosticStatus-like
        One status.

    Returns
    -------
    tuple
        (level, chunks analysed, chunks skipped) as found in the status.

    """
    values = values_of(status)
    return (level_of(status), values.get('Chunks analysed'), values.get('Chunks skipped'))


def chunks_done(states: Iterable[tuple[int, str | None, str | None]]) -> int:
    """
    Return the chunks every axis has finished (analysed plus skipped).

    ``states`` are the :func:`progress_state` of each axis.
    """
    return min(int(a or 0) + int(str(b or '0').split(' ')[0]) for _, a, b in states)


def parse_axis_parts(line: str) -> list[tuple[str, str, float]]:
    """
    Read the axis parts back from a :func:`format_array` line.

    Parameters
    ----------
    line : str
        A line printed by ``gyro_noise_monitor --compact``.

    Returns
    -------
    list of (str, str, float)
        (axis, level, drift in (deg/s)/h; NaN where not a number) for each axis in the line.

    """
    out: list[tuple[str, str, float]] = []
    for axis, level, drift in AXIS_PART.findall(line):
        try:
            value = float(drift)
        except ValueError:
            value = float('nan')
        out.append((axis, level, value))
    return out
