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

The analogues of paper 000's Figures 2-10, in the units of :mod:`..units` at this edge (deg/s;
the Allan deviation in deg/h and mg, with the readout's N, B and K lines and points as
:func:`allan_curves` describes them for the HTML page too); matplotlib is set up by
:mod:`..plotting` (Agg backend, no display) and imported only when a figure is drawn.
"""

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.readout import B_FACTOR
from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import (ACCEL_ADEV, ACCEL_RW, ACCEL_VRW, Display, GYRO_ADEV, GYRO_ARW, GYRO_RRW,
                     RAD_TO_DEG, time_unit)

__all__ = ['allan_curves', 'allan_fit_lines', 'plot_allan', 'plot_curves', 'plot_per_chunk',
           'readout_lines', 'readout_numbers']

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
    span = max((float(np.nanmax(finite(t, v)[0])) for a in axes for _, t, v in series[a]
                if finite(t, v)[0].size), default=float('nan'))
    clock = time_unit(span)
    skipped = set()
    for ax_name, panel in zip(axes, panels[:, 0]):
        for label, t, v in series[ax_name]:
            t, v = finite(t, v)
            if t.size < 2:
                skipped.add(label)
                continue
            when = t * clock.per_si
            line, = panel.plot(when, v * scale, 'o-', ms=4, lw=0.6, label=label)
            if quantity == 'bias':
                slope, icpt = np.polyfit(t, v, 1)
                panel.plot(when, (icpt + slope * t) * scale, '--', lw=1.2, color=line.get_color(),
                           label=f'{label}: drift {slope * RAD_TO_DEG * 3600.0:+.3g} (deg/s)/h')
        panel.set_ylabel(f'{quantity} {ax_name} ({unit})')
        panel.grid(alpha=0.3)
        if panel.get_legend_handles_labels()[1]:
            # beside the panel, never over the chunks
            panel.legend(fontsize=7, loc='upper left', bbox_to_anchor=(1.01, 1.0),
                         borderaxespad=0.0)
    panels[-1, 0].set_xlabel(f'time from the first sample ({clock.unit})')
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
    panels[0, 0].legend(fontsize=7, loc='upper left', bbox_to_anchor=(0.0, -0.15),
                        borderaxespad=0.0)
    fig.suptitle(title)
    save_figure(fig, path, dpi=110, tight=True)


def plot_allan(path: StrPath, curves: Mapping[str, Sequence[Mapping[str, Any]]]) -> bool:
    """
    Draw every Allan deviation with its interval band, readout lines and points (paper Fig. 10).

    One row per sensor (gyro in :data:`..units.GYRO_ADEV`, accelerometer in
    :data:`..units.ACCEL_ADEV`), one panel per axis, the bags overlaid; the N, B and K lines of
    the readout (dashed, dotted, dash-dot) and its points (diamonds) as peers draw them; the
    legend below the panels, never over the data.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    curves : dict
        :func:`allan_curves`: ``{'gyro': [...], 'accelerometer': [...]}``.

    Returns
    -------
    bool
        True when the figure was written (False: no curve).

    """
    rows = [(sensor, unit, [c for c in curves.get(sensor) or () if len(c['tau_s'])])
            for sensor, unit in (('gyro', GYRO_ADEV.unit), ('accelerometer', ACCEL_ADEV.unit))]
    rows = [r for r in rows if r[2]]
    if not rows:
        return False
    plt = pyplot()
    axes = sorted({c['axis'] for _, _, cs in rows for c in cs})
    fig, panels = plt.subplots(len(rows), len(axes), squeeze=False,
                               figsize=(max(7.0, 4.6 * len(axes)), 3.9 * len(rows) + 1.1))
    labels = list(dict.fromkeys(c['label'] for _, _, cs in rows for c in cs))
    colours = {label: f'C{k % 10}' for k, label in enumerate(labels)}
    for (sensor, unit, cs), row in zip(rows, panels):
        for axis, panel in zip(axes, row):
            for c in (c for c in cs if c['axis'] == axis):
                _draw_curve(panel, c, colours[c['label']])
            panel.set_xscale('log')
            panel.set_yscale('log')
            panel.set_xlabel('averaging time tau (s)')
            panel.set_ylabel(f'Allan deviation ({unit})')
            panel.set_title(f'{sensor} {axis}', fontsize=10)
            panel.grid(True, which='both', alpha=0.3)
    fig.legend(handles=_legend_handles(labels, colours), loc='lower center',
               ncol=min(8, len(labels) + 4), fontsize=8, frameon=False)
    fig.suptitle('Allan deviation (band: 68.3 % interval; the readout: N on the -1/2 line at '
                 'tau = 1 s, B the flat floor, K the +1/2 line, its value at tau = 3 s)',
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    save_figure(fig, path, dpi=110)
    return True


def _draw_curve(panel: Any, c: Mapping[str, Any], colour: str) -> None:
    """One Allan curve on a panel: band, curve, readout lines and points."""
    tau = np.asarray(c['tau_s'], dtype=np.float64)
    panel.fill_between(tau, c['ci_low'], c['ci_high'], color=colour, alpha=0.15, lw=0)
    panel.plot(tau, c['adev'], 'o-', ms=2.5, lw=1.3, color=colour)
    for kind, t, v in c.get('lines') or ():
        panel.plot(t, v, ls=_DASH[kind], lw=1.1, color=colour)
    for kind, t, v, _ in c.get('points') or ():
        panel.plot([t], [v], 'D', ms=7, mfc=colour, mec='black', mew=0.8)
        panel.annotate(kind, (t, v), textcoords='offset points', xytext=(5, 5), fontsize=8)


#: matplotlib line style of each readout line (the Bokeh page uses the same three).
_DASH = {'N': '--', 'B': ':', 'K': '-.'}


def _legend_handles(labels: Sequence[str], colours: Mapping[str, str]) -> list[Any]:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=colours[label], marker='o', ms=3, label=label)
               for label in labels]
    handles += [Line2D([], [], color='0.3', ls=_DASH[k], label=text) for k, text in
                (('N', 'N: -1/2 line'), ('B', 'B: flat floor'), ('K', 'K: +1/2 line'))]
    handles.append(Line2D([], [], ls='', marker='D', mfc='0.7', mec='black',
                          label='readout points'))
    return handles


def allan_curves(doc: Mapping[str, Any], allan_store: Mapping[tuple[str, str], Any],
                 accel_allan: Mapping[tuple[str, str], Any] | None = None
                 ) -> dict[str, list[dict[str, Any]]]:
    """
    Return every Allan curve of an analysis in display units, with its readout lines and points.

    The one description both figures draw (the PNG of :func:`plot_allan` and report.html's).

    Parameters
    ----------
    doc : dict
        The summary.json document (its readouts give the lines and points).
    allan_store : dict
        ``{(label, axis): (AllanResult, noise terms, readout)}`` of the angular rate (rad/s).
    accel_allan : dict, optional
        ``{(label, axis): AllanResult}`` of the specific force (m/s^2).

    Returns
    -------
    dict
        ``{'gyro': [...], 'accelerometer': [...]}``, each curve a dict: ``label``, ``axis``,
        ``name``, ``tau_s``, ``adev``, ``ci_low``, ``ci_high`` (:data:`..units.GYRO_ADEV` or
        :data:`..units.ACCEL_ADEV`), ``n``, ``fit`` (the IEEE 952 model, gyro only), ``lines``
        and ``points`` (:func:`readout_lines`; each point with its hover text).

    """
    bags = {b['label']: b for b in doc['bags']}
    several = len(bags) > 1
    out: dict[str, list[dict[str, Any]]] = {'gyro': [], 'accelerometer': []}
    for (label, axis), (result, terms, _) in allan_store.items():
        sheet = bags[label]['axes'][axis].get('allan_datasheet')
        out['gyro'].append(_curve(label, axis, several, result, readout_numbers(sheet),
                                  GYRO_ADEV, (GYRO_ARW, GYRO_RRW), terms))
    for (label, axis), result in (accel_allan or {}).items():
        sheet = (bags[label].get('accelerometer_allan') or {}).get(axis)
        out['accelerometer'].append(_curve(
            label, axis, several, result, readout_numbers(sheet, accelerometer=True),
            ACCEL_ADEV, (ACCEL_VRW, ACCEL_RW), None))
    return out


def _curve(label: str, axis: str, several: bool, result: Any, numbers: dict[str, Any] | None,
           unit: Display, walk_units: tuple[Display, Display], terms: Any) -> dict[str, Any]:
    """One curve of :func:`allan_curves` (SI in, display units out)."""
    from .csv_tables import allan_curve

    tau, adev, lo, hi, n = allan_curve(result)
    k = unit.per_si
    lines, points = readout_lines(numbers, tau, adev)
    texts = _point_texts(numbers, unit, walk_units) if numbers else {}
    return {'label': label, 'axis': axis, 'name': f'{label} {axis}' if several else axis,
            'tau_s': tau, 'adev': adev * k, 'ci_low': lo * k, 'ci_high': hi * k, 'n': n,
            'fit': [(name, t, v * k) for name, t, v in allan_fit_lines(terms, tau)],
            'lines': [(kind, t, v * k) for kind, t, v in lines],
            'points': [(kind, t, v * k, texts.get(kind, '')) for kind, t, v in points]}


def _point_texts(numbers: Mapping[str, Any], unit: Display,
                 walk_units: tuple[Display, Display]) -> dict[str, str]:
    """Return each readout point's hover text: its number in the customary unit, where read."""
    white, walk = walk_units
    bound = '<= ' if numbers['bias_bound'] else ''
    texts = {}
    if numbers['n'] is not None:
        texts['N'] = (f"{numbers['n'] * white.per_si:.3g} {white.unit}, the -1/2 line read at "
                      f'tau = {N_TAU_S:g} s')
    if numbers['bias'] is not None and numbers['bias_tau_s'] is not None:
        texts['B'] = (f"bias stability {bound}{numbers['bias'] * unit.per_si:.3g} {unit.unit} "
                      f"at tau = {numbers['bias_tau_s']:.3g} s (B = {bound}"
                      f"{numbers['bias'] * unit.per_si / B_FACTOR:.3g} {unit.unit})")
    if numbers['k'] is not None:
        what = 'a bound' if numbers['k_bound'] else 'fitted'
        texts['K'] = (f"{'<= ' if numbers['k_bound'] else ''}{numbers['k'] * walk.per_si:.3g} "
                      f'{walk.unit}, the +1/2 line ({what}; K is its value at tau = '
                      f'{K_TAU_S:g} s)')
    return texts


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


#: Where each readout number is read, as IEEE 952 and MATLAB's allanvar read them: N on the -1/2
#: line at tau = 1 s, K on the +1/2 line at tau = 3 s; B at the bias-stability tau.
N_TAU_S = 1.0
K_TAU_S = 3.0


def readout_numbers(sheet: Mapping[str, Any] | None, *,
                    accelerometer: bool = False) -> dict[str, Any] | None:
    """
    Return the readout numbers the figures draw, in SI, from a summary.json readout entry.

    Parameters
    ----------
    sheet : dict or None
        ``allan_datasheet`` of an axis (gyro) or an ``accelerometer_allan`` entry.
    accelerometer : bool, keyword-only
        ``sheet`` is an accelerometer entry (its keys are velocity / acceleration random walk).

    Returns
    -------
    dict or None
        ``n`` (white-noise coefficient), ``bias`` (bias stability), ``bias_tau_s``,
        ``bias_bound`` (an upper bound), ``k`` (the random walk: the fitted K when resolved,
        else its bound) and ``k_bound`` (K is a bound); None values where the entry has none.

    """
    if not sheet:
        return None
    if accelerometer:
        n, bias = (sheet.get('velocity_random_walk_m_s2_per_sqrt_hz'),
                   sheet.get('bias_stability_m_s2'))
        resolved = bool(sheet.get('acceleration_random_walk_resolved'))
        k = sheet.get('acceleration_random_walk_m_s3_per_sqrt_hz' if resolved else
                      'acceleration_random_walk_bound_m_s3_per_sqrt_hz')
    else:
        n, bias = sheet.get('arw_rad_per_sqrt_s'), sheet.get('bias_stability_rad_s')
        resolved = bool(sheet.get('rate_random_walk_resolved'))
        k = sheet.get('rate_random_walk_rad_per_s_sqrt_s' if resolved else
                      'rate_random_walk_bound_rad_per_s_sqrt_s')
    return {'n': n, 'bias': bias, 'bias_tau_s': sheet.get('bias_stability_tau_s'),
            'bias_bound': bool(sheet.get('bias_stability_upper_bound')), 'k': k,
            'k_bound': not resolved}


def readout_lines(numbers: Mapping[str, Any] | None, tau: ArrayLike,
                  adev: ArrayLike) -> tuple[list[tuple[str, NDArray[np.float64],
                                                       NDArray[np.float64]]],
                                            list[tuple[str, float, float]]]:
    """
    Return the readout's N, B and K lines and its points over an Allan curve (as peers draw).

    The -1/2 line ``N / sqrt(tau)`` (IEEE 952 eq. C.3) up to three times the later of 1 s and
    the bias-stability tau, the flat line at the bias stability (``0.664 B``, eq. C.27) a decade
    either side of its tau, and the +1/2 line ``K sqrt(tau / 3)`` (eq. C.29) from a third of
    the earlier of 3 s and that tau; each kept over the curve's taus and within a factor of 3 of
    its values. The points: N at tau = 1 s, the bias stability at its tau, K at the longest tau,
    where the +1/2 line meets the curve (its bound is read there; K is the line's value at
    tau = 3 s, which a point at 3 s would show far below a curve still falling there).

    Parameters
    ----------
    numbers : dict or None
        :func:`readout_numbers` (SI); None gives no line.
    tau, adev : array_like
        The curve (s; the same unit as ``numbers``).

    Returns
    -------
    tuple
        ``([(kind, tau_s, adev)], [(kind, tau_s, adev)])``, kind 'N', 'B' or 'K'.

    """
    tau = np.asarray(tau, dtype=np.float64)
    adev = np.asarray(adev, dtype=np.float64)
    ok = np.isfinite(tau) & np.isfinite(adev) & (adev > 0) & (tau > 0)
    if numbers is None or not ok.any():
        return [], []
    t = np.geomspace(tau[ok].min(), tau[ok].max(), 64)
    low, high = adev[ok].min() / 3.0, adev[ok].max() * 3.0
    tau_b = numbers.get('bias_tau_s')
    tau_b = float(tau_b) if tau_b is not None and np.isfinite(tau_b) else float(t[-1])
    spans = {'N': (0.0, 3.0 * max(N_TAU_S, tau_b)), 'B': (tau_b / 10.0, tau_b * 10.0),
             'K': (min(K_TAU_S, tau_b) / 3.0, np.inf)}
    at = {'N': N_TAU_S, 'B': tau_b, 'K': float(t[-1])}
    lines, points = [], []
    for kind, value in (('N', numbers.get('n')), ('B', numbers.get('bias')),
                        ('K', numbers.get('k'))):
        if value is None or not np.isfinite(value) or value <= 0:
            continue
        curve = _on_line(kind, numbers, t)
        inside = (curve >= low) & (curve <= high) & (t >= spans[kind][0]) & (
            t <= spans[kind][1])
        if inside.sum() >= 2:
            lines.append((kind, t[inside], curve[inside]))
        points.append((kind, at[kind], float(_on_line(kind, numbers, np.array([at[kind]]))[0])))
    return lines, points


def _on_line(kind: str, numbers: Mapping[str, Any],
             tau: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return the readout line ``kind`` at ``tau`` (IEEE 952 eqs. C.3, C.27, C.29)."""
    if kind == 'N':
        return float(numbers['n']) / np.sqrt(tau)
    if kind == 'B':
        return np.full(tau.shape, float(numbers['bias']))
    return float(numbers['k']) * np.sqrt(tau / K_TAU_S)
