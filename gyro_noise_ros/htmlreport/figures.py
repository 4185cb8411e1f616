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
Interactive Bokeh figures of the HTML reports, decimated for display.

Every figure has pan, box and wheel zoom, reset, a hover tool and a unit on every axis. Curves are
decimated so a page stays small and quick whatever the record length: an Allan curve to at most
:data:`MAX_ALLAN_POINTS` log-spaced averaging times, a time series to at most
:data:`MAX_SERIES_POINTS` points by a min/max envelope (each bin keeps its lowest and highest
point, so spikes and steps stay visible). The full data are in the CSV files the tools write
beside the page. The decimation functions are pure numpy; Bokeh is imported inside the builders.
"""

from collections.abc import Mapping, Sequence
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from bokeh.models.renderers import DataRenderer
    from bokeh.plotting import figure

#: Largest number of averaging times drawn per Allan curve.
MAX_ALLAN_POINTS = 200
#: Largest number of points drawn per time series.
MAX_SERIES_POINTS = 1000
_TOOLS = 'pan,box_zoom,wheel_zoom,reset,save'
_WIDTH, _HEIGHT = 1000, 380


def log_decimate(tau: ArrayLike, max_points: int = MAX_ALLAN_POINTS) -> NDArray[np.int64]:
    """
    Return indices of at most ``max_points`` entries of ``tau`` spread evenly in log(tau).

    Parameters
    ----------
    tau : array_like
        Increasing positive averaging times (s).
    max_points : int
        Largest number of indices (>= 2).

    Returns
    -------
    numpy.ndarray
        Increasing indices, first and last always included.

    """
    tau = np.asarray(tau, dtype=np.float64)
    n = tau.size
    if n <= max_points:
        return np.arange(n)
    targets = np.geomspace(tau[0], tau[-1], max_points)
    idx = np.clip(np.searchsorted(tau, targets), 0, n - 1)
    # nearest of the two neighbours in log(tau)
    left = np.clip(idx - 1, 0, n - 1)
    closer = np.abs(np.log(tau[left]) - np.log(targets)) < np.abs(np.log(tau[idx])
                                                                  - np.log(targets))
    idx = np.where(closer, left, idx)
    return np.unique(np.concatenate(([0], idx, [n - 1])))


def envelope_decimate(y: ArrayLike, max_points: int = MAX_SERIES_POINTS) -> NDArray[np.int64]:
    """
    Return indices of a min/max envelope of ``y``: at most ``max_points`` points.

    The series is cut into ``max_points // 2`` bins of consecutive samples; each bin keeps the
    index of its lowest and of its highest finite value, in time order. Every extreme of the
    series is therefore kept; what is dropped lies between two kept points of its bin.

    Parameters
    ----------
    y : array_like
        The values, in time order (NaN allowed: never chosen).
    max_points : int
        Largest number of indices (>= 2).

    Returns
    -------
    numpy.ndarray
        Increasing indices.

    """
    y = np.asarray(y, dtype=np.float64)
    n = y.size
    if n <= max_points:
        return np.arange(n)
    bins = max(1, max_points // 2)
    edges = np.linspace(0, n, bins + 1).astype(np.int64)
    finite = np.isfinite(y)
    low = np.where(finite, y, np.inf)
    high = np.where(finite, y, -np.inf)
    starts = edges[:-1]
    keep = []
    # np.minimum.reduceat gives the extremes per bin; the first index reaching them is found
    # inside each bin (bins are at most n / bins long, so this loop is O(n) in total).
    mins = np.minimum.reduceat(low, starts)
    maxs = np.maximum.reduceat(high, starts)
    for b in range(bins):
        if not np.isfinite(mins[b]):
            continue
        seg_lo, seg_hi = low[edges[b]:edges[b + 1]], high[edges[b]:edges[b + 1]]
        i = edges[b] + int(np.argmax(seg_lo == mins[b]))
        j = edges[b] + int(np.argmax(seg_hi == maxs[b]))
        keep += sorted({i, j})
    return np.asarray(keep, dtype=np.int64)


def _palette(n: int) -> list[str]:
    from bokeh.palettes import Category10_10

    return [Category10_10[i % 10] for i in range(n)]


def _figure(title: str, x_label: str, y_label: str, *, x_log: bool = False,
            y_log: bool = False) -> 'figure':
    from bokeh.plotting import figure

    fig = figure(title=title, width=_WIDTH, height=_HEIGHT, tools=_TOOLS,
                 x_axis_type='log' if x_log else 'linear',
                 y_axis_type='log' if y_log else 'linear', sizing_mode='stretch_width')
    fig.xaxis.axis_label = x_label
    fig.yaxis.axis_label = y_label
    fig.toolbar.logo = None  # the logo is a link to a web site: nothing on the page reaches out
    return fig


def allan_figure(curves: Sequence[Mapping[str, Any]], *, title: str, unit: str) -> 'figure':
    """
    Log-log Allan deviation with its interval band, the fit lines and a hover at each tau.

    Parameters
    ----------
    curves : list of dict
        One per curve: ``name``; ``tau_s``, ``adev``, ``ci_low``, ``ci_high`` (arrays, the
        deviation in ``unit``); optional ``n`` (terms per tau) and ``fit`` (``[(name, tau_s,
        adev)]`` model lines in ``unit``).
    title : str, keyword-only
        Figure title.
    unit : str, keyword-only
        Unit of the deviation, e.g. ``'deg/s'``.

    Returns
    -------
    bokeh.plotting.figure

    """
    from bokeh.models import ColumnDataSource, HoverTool

    fig = _figure(title, 'averaging time tau (s)', f'Allan deviation ({unit})', x_log=True,
                  y_log=True)
    hover_renderers: list[DataRenderer] = []
    for colour, c in zip(_palette(len(curves)), curves):
        tau = np.asarray(c['tau_s'], dtype=np.float64)
        keep = log_decimate(tau)
        cols: dict[str, Any] = {k: np.asarray(c[k], dtype=np.float64)[keep]
                                for k in ('tau_s', 'adev', 'ci_low', 'ci_high')}
        cols['n'] = (np.asarray(c['n'])[keep] if c.get('n') is not None
                     else np.zeros(keep.size, dtype=np.int64))
        cols['name'] = [c['name']] * keep.size
        src = ColumnDataSource(cols)
        band = np.isfinite(cols['ci_low']) & np.isfinite(cols['ci_high'])
        if band.any():
            fig.varea(x=cols['tau_s'][band], y1=cols['ci_low'][band], y2=cols['ci_high'][band],
                      fill_color=colour, fill_alpha=0.15)
        fig.line('tau_s', 'adev', source=src, color=colour, line_width=2,
                 legend_label=c['name'])
        hover_renderers.append(fig.scatter('tau_s', 'adev', source=src, color=colour, size=4))
        for fit_name, fit_tau, fit_adev in c.get('fit') or ():
            fig.line(np.asarray(fit_tau, dtype=np.float64),
                     np.asarray(fit_adev, dtype=np.float64), color=colour,
                     line_dash='dashed', line_width=1,
                     legend_label=f"{c['name']}: {fit_name}")
    fig.add_tools(HoverTool(renderers=hover_renderers, tooltips=[
        ('curve', '@name'), ('tau (s)', '@tau_s{0.000g}'), (f'ADEV ({unit})', '@adev{0.0000e}'),
        ('interval', '@ci_low{0.000e} to @ci_high{0.000e}'), ('terms', '@n')]))
    fig.legend.location = 'bottom_left'
    fig.legend.click_policy = 'hide'
    return fig


def series_figure(series: Sequence[tuple[str, ArrayLike, ArrayLike]], *, title: str,
                  x_label: str, y_label: str, y_log: bool = False) -> 'figure':
    """
    Values over time (or any ordered x), one line with markers per series, envelope-decimated.

    Parameters
    ----------
    series : list of tuple
        ``(name, x, y)`` with arrays of equal length (NaN points are not drawn).
    title, x_label, y_label : str, keyword-only
        Title and axis labels (with units).
    y_log : bool, keyword-only
        Log y axis (values <= 0 are not drawn then).

    Returns
    -------
    bokeh.plotting.figure

    """
    from bokeh.models import ColumnDataSource, HoverTool

    fig = _figure(title, x_label, y_label, y_log=y_log)
    renderers: list[DataRenderer] = []
    for colour, (name, x, y) in zip(_palette(len(series)), series):
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        ok = np.isfinite(x) & np.isfinite(y) & ((y > 0) if y_log else True)
        x, y = x[ok], y[ok]
        keep = envelope_decimate(y)
        src = ColumnDataSource({'x': x[keep], 'y': y[keep], 'name': [name] * keep.size})
        fig.line('x', 'y', source=src, color=colour, line_width=1, legend_label=name)
        renderers.append(fig.scatter('x', 'y', source=src, color=colour, size=4,
                                     legend_label=name))
    fig.add_tools(HoverTool(renderers=renderers, tooltips=[
        ('series', '@name'), (x_label, '@x{0.000g}'), (y_label, '@y{0.000000g}')]))
    if series:
        fig.legend.click_policy = 'hide'
        fig.legend.location = 'top_left'
    return fig
