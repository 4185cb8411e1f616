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
The PNG figures of an analysis: bias and variance per chunk, var(alpha) and J(alpha), Allan.

The analogues of paper 000's Figures 2-10, converted to deg/s at this edge; matplotlib is set up
by :mod:`..plotting` (Agg backend, no display) and imported only when a figure is drawn.
"""

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import RAD_TO_DEG

__all__ = ['allan_fit_lines', 'plot_allan', 'plot_curves', 'plot_per_chunk']

_DEG2 = RAD_TO_DEG ** 2


def plot_per_chunk(path: StrPath, series: Mapping[str, Sequence[tuple[str, ArrayLike, ArrayLike]]],
                   *, quantity: str) -> bool:
    """
    Plot bias or variance per chunk over time, one panel per axis, bags overlaid (paper Figs. 2-5).

    Markers are visible (not single pixels); on the bias figure each bag's least-squares drift line
    (the Table 3 slope) is drawn and named in the legend. A bag with fewer than 2 chunks is not
    plotted (a single point shows nothing over time) and the title says so; when no bag has 2
    chunks no figure is written.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    series : dict
        ``{axis: [(label, t_mid_s array, value array in rad/s or (rad/s)^2), ...]}``.
    quantity : {'bias', 'variance'}, keyword-only
        Which quantity the values are.

    Returns
    -------
    bool
        True when the figure was written.

    """
    def finite(t: ArrayLike,
               v: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        t, v = np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64)
        ok = np.isfinite(t) & np.isfinite(v)
        return t[ok], v[ok]

    axes = list(series)
    if not any(finite(t, v)[0].size >= 2 for a in axes for _, t, v in series[a]):
        return False
    plt = pyplot()
    fig, panels = plt.subplots(len(axes), 1, figsize=(10, 2.8 * len(axes) + 0.8), squeeze=False,
                               sharex=True)
    scale, unit = (RAD_TO_DEG, 'deg/s') if quantity == 'bias' else (_DEG2, '(deg/s)$^2$')
    skipped = set()
    for ax_name, panel in zip(axes, panels[:, 0]):
        for label, t, v in series[ax_name]:
            t, v = finite(t, v)
            if t.size < 2:
                skipped.add(label)
                continue
            hours = t / 3600.0
            line, = panel.plot(hours, v * scale, 'o-', ms=4, lw=0.6, label=label)
            if quantity == 'bias':
                slope, icpt = np.polyfit(t, v, 1)
                panel.plot(hours, (icpt + slope * t) * scale, '--', lw=1.2, color=line.get_color(),
                           label=f'{label}: drift {slope * RAD_TO_DEG * 3600.0:+.3g} (deg/s)/h')
        panel.set_ylabel(f'{quantity} {ax_name} ({unit})')
        panel.grid(alpha=0.3)
        if panel.get_legend_handles_labels()[1]:
            panel.legend(fontsize=7, ncol=2)
    panels[-1, 0].set_xlabel('time from the first sample (h)')
    title = f'Chunk {quantity} per chunk (markers: chunks'
    title += '; dashed: least-squares drift, Table 3)' if quantity == 'bias' else ')'
    if skipped:
        title += f"\nnot plotted (fewer than 2 chunks): {', '.join(sorted(skipped))}"
    fig.suptitle(title, fontsize=10)
    save_figure(fig, path, dpi=110, tight=True)
    return True


def plot_curves(path: StrPath, alphas: NDArray[np.floating[Any]], chunks: NDArray[Any],
                var_curves: ArrayLike, j_curves: ArrayLike, *, title: str) -> None:
    """
    Plot var(alpha) and J(alpha) stacked over chunks as heat maps (paper Figs. 6-9).

    Each chunk's curve is shown as log10(curve / its minimum), so the colour reads "how much worse
    than the best order of that chunk" and the minimum line is visible whatever the chunk's noise
    level; the chosen orders are overlaid as dots.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    alphas : numpy.ndarray
        Order grid.
    chunks : numpy.ndarray
        Chunk indices of the rows.
    var_curves, j_curves : numpy.ndarray
        ``(len(chunks), len(alphas))`` curves.
    title : str
        Figure title.

    """
    plt = pyplot()
    fig, panels = plt.subplots(1, 2, figsize=(11, 4.2), squeeze=False)
    for panel, curves, name in ((panels[0, 0], var_curves, 'var(w)'),
                                (panels[0, 1], j_curves, 'J')):
        curves = np.asarray(curves, dtype=np.float64)
        low = np.nanmin(curves, axis=1, keepdims=True)
        rel = np.log10(curves / low)
        extent = (alphas[0], alphas[-1], chunks[-1] + 0.5, chunks[0]
                  - 0.5) if len(chunks) else None
        im = panel.imshow(rel, aspect='auto', extent=extent, cmap='viridis',
                          interpolation='nearest')
        best = alphas[np.nanargmin(curves, axis=1)]
        panel.plot(best, chunks, 'r.', ms=3, label='minimum')
        panel.set_xlabel('order alpha')
        panel.set_ylabel('chunk')
        panel.set_title(f'log10({name}(alpha) / min)')
        fig.colorbar(im, ax=panel)
    panels[0, 0].legend(fontsize=7, loc='lower right')
    fig.suptitle(title)
    save_figure(fig, path, dpi=110, tight=True)


def plot_allan(path: StrPath,
               series: Mapping[str, Sequence[tuple[str, ArrayLike, ArrayLike, ArrayLike, ArrayLike,
                                                   Sequence[tuple[str, ArrayLike, ArrayLike]]]]],
               *, confidence: float = 0.683) -> None:
    """
    Overlay every bag's Allan deviation with confidence bands and fitted terms (paper Fig. 10).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    series : dict
        ``{axis: [(label, tau_s, adev, ci_low, ci_high, fit_lines), ...]}`` in rad/s; ``fit_lines``
        is a list of ``(name, tau_s, adev)`` model curves (may be empty).
    confidence : float, keyword-only
        Two-sided confidence of the bands (named in the legend).

    """
    plt = pyplot()
    axes = list(series)
    fig, panels = plt.subplots(1, len(axes), figsize=(max(7.0, 5.5 * len(axes)), 4.8),
                               squeeze=False)
    for ax_name, panel in zip(axes, panels[0]):
        for label, tau, adev, lo, hi, fits in series[ax_name]:
            line, = panel.loglog(tau, np.asarray(adev) * RAD_TO_DEG, 'o-', ms=3, lw=1.3,
                                 label=label)
            panel.fill_between(tau, np.asarray(lo) * RAD_TO_DEG, np.asarray(hi) * RAD_TO_DEG,
                               color=line.get_color(), alpha=0.15, lw=0,
                               label=f'{label}: {100 * confidence:.1f} % interval')
            for k, (name, ftau, fadev) in enumerate(fits):
                panel.loglog(ftau, np.asarray(fadev) * RAD_TO_DEG, ls='--', lw=0.8,
                             color=line.get_color(), label=f'{label}: IEEE 952 fit' if k == 0
                             else None)
        panel.set_xlabel('tau (s)')
        panel.set_ylabel(f'Allan deviation {ax_name} (deg/s)')
        panel.grid(True, which='both', alpha=0.3)
        panel.legend(fontsize=7)
    fig.suptitle(f'Allan deviation (markers: measured; bands: {100 * confidence:.1f} % confidence '
                 'interval; dashed: fitted IEEE 952 noise terms)', fontsize=10)
    save_figure(fig, path, dpi=110, tight=True)


def allan_fit_lines(terms: object,
                    tau: NDArray[Any]) -> list[tuple[str, NDArray[Any], NDArray[np.float64]]]:
    """
    Return ``[(name, tau_s, adev_rad_s)]`` curves of the fitted noise terms (Allan figure).

    Parameters
    ----------
    terms : object or None
        Noise-term fit of :mod:`..core.allan` (anything with a ``model_adev(tau)`` or ``adev(tau)``
        method, or ``term_adev(name, tau)``); None gives no lines.
    tau : numpy.ndarray
        Averaging times (s).

    Returns
    -------
    list

    """
    if terms is None or len(tau) == 0:
        return []
    lo, hi = getattr(terms, 'tau_min_s', None), getattr(terms, 'tau_max_s', None)
    if lo is not None and hi is not None:
        tau = np.asarray(tau, dtype=np.float64)
        # only where it was fitted: band-limited short taus are left out of the fit
        tau = tau[(tau >= lo * (1 - 1e-9)) & (tau <= hi * (1 + 1e-9))]
        if tau.size == 0:
            return []
    for name in ('model_adev', 'adev'):
        fn = getattr(terms, name, None)
        if callable(fn):
            try:
                return [('fit', tau, np.asarray(fn(tau), dtype=np.float64))]
            except (TypeError, ValueError):
                return []
    return []
