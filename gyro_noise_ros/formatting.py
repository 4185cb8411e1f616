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
"""

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ['finite_list', 'finite_or_none', 'fmt_or_na', 'percent', 'plus_minus']


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
    """
    Return the values of an array, flattened, as floats; None for NaN, infinite or None.

    Parameters
    ----------
    values : array_like
        Numbers (any shape; a None element counts as NaN).

    Returns
    -------
    list of float or None

    """
    return [finite_or_none(v) for v in np.asarray(values, dtype=float).ravel()]


def fmt_or_na(value: float | None, spec: str) -> str:
    """
    Return ``format(value, spec)``, or ``'n/a'`` for None.

    Parameters
    ----------
    value : float or None
        The number.
    spec : str
        ``format()`` spec.

    Returns
    -------
    str

    """
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
