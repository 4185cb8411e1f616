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

Every figure has pan, box and wheel zoom, reset, a hover tool, a unit on every axis, its legend
beside the plot (never over the data) and, on a log axis, a label in every decade. Curves are
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
#: Largest number of points of a series drawn with markers (more: the line alone).
_MARKED_POINTS = 250
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


def log_ticks(low: float, high: float) -> tuple[list[float], list[float]]:
    """
    Return major and minor ticks of a log axis from ``low`` to ``high``: a label in every decade.

    Up to two decades the labels are 1, 2 and 5 times a power of ten; up to five, 1 and 3; wider,
    the powers of ten. Minor ticks are every integer multiple of each power.

    Parameters
    ----------
    low, high : float
        The data's range (> 0); non-finite or non-positive gives one decade about 1.

    Returns
    -------
    tuple of list of float
        ``(major, minor)`` ticks, covering ``[low, high]`` with a decade of margin.

    """
    if not (np.isfinite(low) and np.isfinite(high) and 0 < low <= high):
        low, high = 0.1, 10.0
    first, last = int(np.floor(np.log10(low))) - 1, int(np.ceil(np.log10(high))) + 1
    decades = np.log10(high / low)
    mantissas = (1, 2, 5) if decades <= 2.2 else (1, 3) if decades <= 5 else (1,)
    # from the decimal text, so a label reads 0.3, never 0.30000000000000004
    major = [float(f'{m}e{k}') for k in range(first, last + 1) for m in mantissas]
    minor = [float(f'{m}e{k}') for k in range(first, last + 1) for m in range(1, 10)]
    return major, minor


def _log_axis(axis: Any, values: Sequence[NDArray[np.float64]]) -> None:
    """Label a log axis in every decade of ``values`` (plain numbers, ``%g``)."""
    from bokeh.models import FixedTicker, PrintfTickFormatter

    finite = [v[np.isfinite(v) & (v > 0)] for v in values]
    finite = [v for v in finite if v.size]
    lo = min(float(v.min()) for v in finite) if finite else float('nan')
    hi = max(float(v.max()) for v in finite) if finite else float('nan')
    major, minor = log_ticks(lo, hi)
    axis.ticker = FixedTicker(ticks=major, minor_ticks=minor)
    axis.formatter = PrintfTickFormatter(format='%g')


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


def _legend_outside(fig: 'figure', items: list[Any]) -> None:
    """Put the legend right of the plot (never over the data); a click hides an entry."""
    from bokeh.models.annotations import Legend

    if not items:
        return
    fig.add_layout(Legend(items=items, click_policy='hide', label_text_font_size='8pt',
                          spacing=0), 'right')


def _item(label: str, renderers: list[Any]) -> Any:
    """Return a legend entry that shows or hides all of ``renderers`` together."""
    from bokeh.models.annotations import LegendItem

    return LegendItem(label=label, renderers=renderers)


#: Line style of each readout line (N: -1/2 slope, B: flat, K: +1/2 slope), as peers draw them.
_READOUT_DASH = {'N': 'dashed', 'B': 'dotted', 'K': 'dashdot'}


def _allan_curve(fig: 'figure', c: Mapping[str, Any], colour: str) -> tuple[Any, list[Any]]:
    """Draw one curve (band, line, points, readout lines); return its hover renderer, items."""
    from bokeh.models import ColumnDataSource

    tau = np.asarray(c['tau_s'], dtype=np.float64)
    keep = log_decimate(tau)
    cols: dict[str, Any] = {k: np.asarray(c[k], dtype=np.float64)[keep]
                            for k in ('tau_s', 'adev', 'ci_low', 'ci_high')}
    cols['n'] = (np.asarray(c['n'])[keep] if c.get('n') is not None
                 else np.zeros(keep.size, dtype=np.int64))
    cols['name'] = [c['name']] * keep.size
    src = ColumnDataSource(cols)
    main: list[Any] = []
    band = np.isfinite(cols['ci_low']) & np.isfinite(cols['ci_high'])
    if band.any():
        main.append(fig.varea(x=cols['tau_s'][band], y1=cols['ci_low'][band],
                              y2=cols['ci_high'][band], fill_color=colour, fill_alpha=0.15))
    main.append(fig.line('tau_s', 'adev', source=src, color=colour, line_width=2))
    dots = fig.scatter('tau_s', 'adev', source=src, color=colour, size=4)
    items = [_item(c['name'], [*main, dots])]
    lines: list[Any] = [
        fig.line(np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64), color=colour,
                 line_width=1.5, line_dash=_READOUT_DASH.get(kind, 'dashed'))
        for kind, t, v in c.get('lines') or ()]
    if lines:
        items.append(_item(f"{c['name']}: N, B, K lines", lines))
    model: list[Any] = [
        fig.line(np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64), color=colour,
                 line_dash='dashed', line_width=1, line_alpha=0.6, visible=False)
        for _, t, v in c.get('fit') or ()]
    if model:
        items.append(_item(f"{c['name']}: IEEE 952 model", model))
    return dots, items


def _readout_points(fig: 'figure', curves: Sequence[Mapping[str, Any]],
                    colours: Sequence[str]) -> Any | None:
    """Mark every curve's readout points; return their renderer (hover) or None."""
    from bokeh.models import ColumnDataSource

    rows = [(colour, name, float(t), float(v), text)
            for colour, c in zip(colours, curves)
            for name, t, v, text in c.get('points') or ()
            if np.isfinite(t) and np.isfinite(v) and v > 0]
    if not rows:
        return None
    colour, name, tau, adev, text = (list(x) for x in zip(*rows))
    src = ColumnDataSource({'colour': colour, 'name': name, 'tau_s': tau, 'adev': adev,
                            'text': text})
    return fig.scatter('tau_s', 'adev', source=src, marker='diamond', size=13,
                       fill_color='colour', line_color='black', line_width=1.2)


def allan_figure(curves: Sequence[Mapping[str, Any]], *, title: str, unit: str) -> 'figure':
    """
    Log-log Allan deviation: interval band, readout lines and points, hover at each tau.

    Parameters
    ----------
    curves : list of dict
        One per curve: ``name``; ``tau_s``, ``adev``, ``ci_low``, ``ci_high`` (arrays, the
        deviation in ``unit``); optional ``n`` (terms per tau), ``lines`` (``[(kind, tau_s,
        adev)]`` with kind 'N', 'B' or 'K': the readout's -1/2, flat and +1/2 lines),
        ``points`` (``[(name, tau_s, adev, text)]``: the readout points, marked, ``text`` shown
        on hover) and ``fit`` (``[(name, tau_s, adev)]``: the IEEE 952 model, hidden until its
        legend entry is clicked).
    title : str, keyword-only
        Figure title.
    unit : str, keyword-only
        Unit of the deviation, e.g. ``'deg/h'``.

    Returns
    -------
    bokeh.plotting.figure

    """
    from bokeh.models import HoverTool

    fig = _figure(title, 'averaging time tau (s)', f'Allan deviation ({unit})', x_log=True,
                  y_log=True)
    colours = _palette(len(curves))
    hover: list[Any] = []
    items: list[Any] = []
    for colour, c in zip(colours, curves):
        dots, its = _allan_curve(fig, c, colour)
        hover.append(dots)
        items += its
    # printf %.3g: three significant digits whatever the decade (0.00106 to 0.00113)
    fig.add_tools(HoverTool(renderers=hover, tooltips=[
        ('curve', '@name'), ('tau (s)', '@tau_s{%.3g}'), (f'ADEV ({unit})', '@adev{%.3g}'),
        ('interval', '@ci_low{%.3g} to @ci_high{%.3g}'), ('terms', '@n')],
        formatters={'@tau_s': 'printf', '@adev': 'printf', '@ci_low': 'printf',
                    '@ci_high': 'printf'}))
    points = _readout_points(fig, curves, colours)
    if points is not None:
        fig.add_tools(HoverTool(renderers=[points], tooltips=[('', '@name: @text')]))
    _log_axis(fig.xaxis[0], [np.asarray(c['tau_s'], dtype=np.float64) for c in curves])
    _log_axis(fig.yaxis[0], [np.asarray(c['adev'], dtype=np.float64) for c in curves])
    _legend_outside(fig, items)
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
    items = []
    ys = []
    for colour, (name, x, y) in zip(_palette(len(series)), series):
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        ok = np.isfinite(x) & np.isfinite(y) & ((y > 0) if y_log else True)
        x, y = x[ok], y[ok]
        ys.append(y)
        keep = envelope_decimate(y)
        src = ColumnDataSource({'x': x[keep], 'y': y[keep], 'name': [name] * keep.size})
        line = fig.line('x', 'y', source=src, color=colour, line_width=1)
        # markers where points are few (one per chunk); a dense trace is its line, hover on it
        dots = fig.scatter('x', 'y', source=src, color=colour, size=4,
                           alpha=1.0 if keep.size <= _MARKED_POINTS else 0.0)
        renderers.append(dots)
        items.append(_item(name, [line, dots]))
    fig.add_tools(HoverTool(renderers=renderers, tooltips=[
        ('series', '@name'), (x_label, '@x{%.4g}'), (y_label, '@y{%.4g}')],
        formatters={'@x': 'printf', '@y': 'printf'}))
    if y_log:
        _log_axis(fig.yaxis[0], ys)
    _legend_outside(fig, items)
    return fig
