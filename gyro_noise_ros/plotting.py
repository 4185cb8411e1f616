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
The one matplotlib set-up of every module that draws: Agg backend, one style, save-and-close.

The tools write PNG files and must run without a display (a robot, CI, a Dask worker), so the
backend is Agg, chosen once here before pyplot is first imported. matplotlib is imported only
when a figure is drawn: importing a tool stays fast, and ``--no-figures`` never loads it. A long
trace is drawn as its min/max :func:`envelope` (numpy only; the parallel thermal model keeps its
plot-sized parts with it).
"""

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ['ENVELOPE_POINTS', 'STYLE', 'envelope', 'pyplot', 'save_figure']

#: rcParams every figure of the package is drawn with (on top of matplotlib's defaults): a white
#: background in any viewer's dark mode, and legends that do not hide the traces.
STYLE: dict[str, Any] = {
    'figure.facecolor': 'white',
    'savefig.facecolor': 'white',
    'legend.framealpha': 0.8,
}

#: Points per trace in time plots (longer runs are reduced to min/max envelopes of blocks).
ENVELOPE_POINTS = 4000

_ready = False


def pyplot() -> Any:
    """
    Return ``matplotlib.pyplot`` on the Agg backend with :data:`STYLE` applied.

    The backend and the style are set on the first call only; later calls return the module.

    Returns
    -------
    module
        ``matplotlib.pyplot``.

    """
    global _ready
    import matplotlib
    if not _ready:
        # force: a caller that imported pyplot on another backend would otherwise keep it
        matplotlib.use('Agg', force=True)
        import matplotlib.style
        matplotlib.style.use(STYLE)
        _ready = True
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig: Any, path: Any, *, dpi: float, tight: bool = False,
                bbox_inches: str | None = None) -> Path:
    """
    Write ``fig`` to ``path`` and close it (also when writing fails, so no figure leaks).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The image file; its suffix picks the format.
    dpi : float, keyword-only
        Resolution (dots per inch).
    tight : bool, keyword-only
        Run ``fig.tight_layout()`` first.
    bbox_inches : str, optional, keyword-only
        Passed to ``savefig`` (``'tight'`` crops to the drawn area).

    Returns
    -------
    pathlib.Path
        ``path``.

    """
    plt = pyplot()
    try:
        if tight:
            fig.tight_layout()
        fig.savefig(path, dpi=dpi, bbox_inches=bbox_inches)
    finally:
        plt.close(fig)
    return Path(path)


def envelope(t: NDArray[Any], y: NDArray[Any],
             max_points: int = ENVELOPE_POINTS) -> tuple[NDArray[Any], NDArray[Any]]:
    """
    Reduce a long trace to a min/max envelope of at most about ``max_points`` points.

    Parameters
    ----------
    t : numpy.ndarray
        Abscissa (n,).
    y : numpy.ndarray
        Values (n,).
    max_points : int
        Points kept; shorter traces are returned as they are.

    Returns
    -------
    tuple of numpy.ndarray
        (t, y) of the envelope: each block's first abscissa twice, its minimum and maximum.

    """
    n = t.size
    if n <= max_points:
        return t, y
    block = int(math.ceil(n / (max_points // 2)))
    k = n // block
    tb = t[:k * block].reshape(k, block)[:, 0]
    yb = y[:k * block].reshape(k, block)
    return np.repeat(tb, 2), np.column_stack([yb.min(axis=1), yb.max(axis=1)]).ravel()
