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
Numbers at the edges: one helper per job, for every document and report (pure, no ROS).

A tool's JSON document holds a finite number or null (JSON has no NaN): :func:`finite_or_none`
and :func:`finite_list`. Its Markdown prints them with a format spec, ``n/a`` for null:
:func:`fmt_or_na`, :func:`plus_minus` (a value and its standard uncertainty) and
:func:`percent` (a ratio as a percentage). Units are converted by the caller (:mod:`.units`).

A report that shows a document's numbers never copies them: a cell holds a :class:`Num` (a JSON
Pointer, RFC 6901, into the document and a format), a :class:`Unit` or plain text, and
:func:`cell_text` (Markdown) or the HTML page (``htmlreport/page.py``) looks each value up, so
summary.md and report.html say the same number from the same place.
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ['Aside', 'Key', 'Num', 'Unit', 'cell_text', 'finite_list', 'finite_or_none',
           'fmt_or_na', 'format_value', 'percent', 'plus_minus', 'pointer', 'resolve_pointer']


def finite_or_none(value: Any) -> float | None:
    """
    Return ``value`` as a float, or None when it is None, NaN or infinite.

    Parameters
    ----------
    value : float or None
        Any number ``float()`` takes (numpy scalars included).

    Returns
    -------
    float or None

    """
    if value is None:
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def finite_list(values: ArrayLike) -> list[float | None]:
    """Return an array's values (any shape, flattened) as floats; None for NaN, inf or None."""
    return [finite_or_none(v) for v in np.asarray(values, dtype=float).ravel()]


def fmt_or_na(value: float | None, spec: str) -> str:
    """Return ``format(value, spec)``, or ``'n/a'`` for None."""
    return 'n/a' if value is None else format(value, spec)


def plus_minus(value: float | None, sigma: float | None, spec: str, scale: float = 1.0) -> str:
    """
    Return ``'value +/- sigma'`` in one unit: both times ``scale``, both with ``spec``.

    The uncertainty drops a leading ``+`` of the spec (a signed change, an unsigned sigma).

    Parameters
    ----------
    value : float or None
        The value (None: ``'n/a'``).
    sigma : float or None
        Its standard uncertainty (None: the value alone).
    spec : str
        ``format()`` spec.
    scale : float
        Unit factor applied to both (e.g. 100 for %).

    Returns
    -------
    str

    """
    if value is None:
        return 'n/a'
    if sigma is None:
        return format(value * scale, spec)
    return f'{format(value * scale, spec)} +/- {format(sigma * scale, spec.lstrip("+"))}'


def percent(ratio: float | None, spec: str) -> str:
    """
    Return a ratio as a percentage (``'12.3 %'``), or ``'n/a'`` for None, NaN or infinity.

    Parameters
    ----------
    ratio : float or None
        The ratio (0.123 is 12.3 %).
    spec : str
        ``format()`` spec of the percentage.

    Returns
    -------
    str

    """
    if ratio is None or not math.isfinite(ratio):
        return 'n/a'
    return f'{format(100.0 * ratio, spec)} %'


@dataclass(frozen=True)
class Num:
    """
    One value of a JSON document, shown in a report.

    Attributes
    ----------
    pointer : str
        JSON Pointer (RFC 6901) into the document, e.g. ``/bags/0/axes/x/chunks``.
    fmt : str
        ``format()`` spec for numbers (ignored for strings and booleans).
    prefix : str
        Text before the value (e.g. ``'<= '`` for an upper bound); no digits.
    scale : float
        Unit conversion at the edge: the report shows ``value * scale`` (e.g. m/s^2 -> mg when
        the JSON is SI and the table customary); 1 shows the JSON value itself.

    """

    pointer: str
    fmt: str = '.6g'
    prefix: str = ''
    scale: float = 1.0


@dataclass(frozen=True)
class Key:
    """
    A JSON key name shown in a table cell (as code; its digits are a unit, not a number).

    Attributes
    ----------
    name : str
        The key, e.g. ``noise_density_m_s2_per_sqrt_hz``.

    """

    name: str


@dataclass(frozen=True)
class Unit:
    """
    A unit written after a value (``'m/s^2/sqrt(Hz)'``: its digits are exponents, not numbers).

    Attributes
    ----------
    name : str
        The unit in the package's ASCII spelling.

    """

    name: str


@dataclass(frozen=True)
class Aside:
    """
    Parts shown under the main ones, smaller (the SI value of a customary one, where it was read).

    Attributes
    ----------
    parts : tuple
        Plain text, :class:`Num` and :class:`Unit` parts.

    """

    parts: tuple


def pointer(*parts: str | int) -> str:
    """Build a JSON Pointer from keys and list indices, outermost first (escaping ~ and /)."""
    return ''.join('/' + str(p).replace('~', '~0').replace('/', '~1') for p in parts)


def resolve_pointer(doc: dict[str, Any] | list[Any], pointer: str) -> Any:
    """
    Return the value at a JSON Pointer (RFC 6901) in ``doc``.

    Parameters
    ----------
    doc : dict or list
        The JSON document.
    pointer : str
        ``''`` (the whole document) or ``/key/0/...`` with ``~1`` for ``/`` and ``~0`` for ``~``.

    Returns
    -------
    object

    Raises
    ------
    KeyError
        A key or index that the document does not have.

    """
    value = doc
    if pointer == '':
        return value
    if not pointer.startswith('/'):
        raise KeyError(f'JSON pointer must start with "/", got {pointer!r}')
    for raw in pointer[1:].split('/'):
        key = raw.replace('~1', '/').replace('~0', '~')
        if isinstance(value, list):
            try:
                value = value[int(key)]
            except (ValueError, IndexError) as err:
                raise KeyError(f'{pointer}: no index {key!r}') from err
        elif isinstance(value, dict):
            if key not in value:
                raise KeyError(f'{pointer}: no key {key!r}')
            value = value[key]
        else:
            raise KeyError(f'{pointer}: {key!r} inside a {type(value).__name__}')
    return value


def format_value(value: object, fmt: str, scale: float = 1.0) -> str:
    """
    Format one JSON value for a report: None as ``n/a``, booleans as yes/no.

    Parameters
    ----------
    value : object
        A JSON scalar.
    fmt : str
        ``format()`` spec applied to numbers.
    scale : float
        Factor applied to numbers first (a unit conversion).

    Returns
    -------
    str

    """
    if value is None:
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, int) and fmt in ('', 'd') and scale == 1.0:
        return str(value)
    if isinstance(value, (int, float)):
        return format(value * scale if scale != 1.0 else value, fmt)
    return str(value)


def cell_text(doc: dict[str, Any] | list[Any],
              cell: 'str | Num | Key | Unit | Aside | Sequence[Any]') -> str:
    """
    Return a report cell as plain text (a Markdown table cell), each value looked up in ``doc``.

    Parameters
    ----------
    doc : dict or list
        The JSON document.
    cell : str, Num, Key, Unit, Aside or tuple of them
        The cell's parts; an :class:`Aside` follows after ``'; '`` (what a page shows on a
        smaller line of its own).

    Returns
    -------
    str

    """
    parts = cell if isinstance(cell, (tuple, list)) else (cell,)
    out = []
    for part in parts:
        if isinstance(part, Num):
            out.append(part.prefix + format_value(resolve_pointer(doc, part.pointer), part.fmt,
                                                  part.scale))
        elif isinstance(part, (Key, Unit)):
            out.append(part.name)
        elif isinstance(part, Aside):
            out.append('; ' + cell_text(doc, part.parts))
        else:
            out.append(str(part))
    return ''.join(out)
