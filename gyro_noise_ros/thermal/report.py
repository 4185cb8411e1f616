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
Figures and Markdown of gyro_noise_thermal: analogues of paper 002's Figures 10-19.

Generic figures (every method): Figure 10 (temperature and raw output against time),
Figure 18 (raw and processed output), Figure 17 (the drift a method removed, 60-s means,
against time and temperature), Figure 19 (Allan deviation raw and processed), and the cost
figures the paper does not have (gain, phase, group delay and step response to injected motion).
Figure 13 (sample entropy and class of each mode) is drawn from a method's ``fit_info`` /
``last_info`` (per-axis dicts with ``sample_entropy``, ``classes``, ``center_freqs_hz``, as the
parallel model keeps them). The other method-specific figures (the paper's Figures 11, 12 and
14-17: the MOPSO archive, the modes, the mixed part before and after TFPF, the denoised output,
the network before and after BAS, the drift part and its compensation) come from the method
itself when it offers ``report_figures(run, out_dir) -> [(file name or None, caption), ...]``
(:func:`method_figures`; the parallel model's uses :func:`plot_mopso`, :func:`plot_modes`,
:func:`plot_before_after` and :func:`plot_network`). :func:`figures_markdown` writes the
report's figure section: one row per paper figure 10-19 naming its analogue, or saying in one
line why the method has none. Everything is converted to deg/s at this edge; long runs are
reduced to min/max envelopes (:func:`envelope`); matplotlib runs on the Agg backend.
"""

from collections.abc import Iterable, Mapping, Sequence
import inspect
import math
from pathlib import Path
import re
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .metrics import FrequencyResponse, StepResponse
from .run import ThermalRun
from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import RAD_TO_DEG

if TYPE_CHECKING:
    from .parallel import ParallelModel

__all__ = ['PAPER_FIGURES', 'envelope', 'figure_numbers', 'figures_markdown', 'method_figures',
           'plot_allan', 'plot_bandwidth', 'plot_before_after', 'plot_drift', 'plot_mode_classes',
           'plot_modes', 'plot_mopso', 'plot_network', 'plot_output', 'plot_run', 'plot_steps',
           'parallel_figures', 'table_markdown', 'bias_stability_cell']

AXES = 'xyz'
#: Points per trace in time plots (longer runs are reduced to min/max envelopes of blocks).
_MAX_POINTS = 4000
#: Points per trace of the narrower panels of the method figures (two per pixel column).
PANEL_POINTS = 1600

# The panel rows of plot_network: per axis, the panels of its row.
_PanelRows = list[list[dict[str, Any]]]


def envelope(t: NDArray[Any], y: NDArray[Any],
             max_points: int = _MAX_POINTS) -> tuple[NDArray[Any], NDArray[Any]]:
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


_thin = envelope


def _window_means(t: NDArray[Any], y: NDArray[Any],
                  window_s: float) -> tuple[NDArray[Any], NDArray[Any]]:
    n = int(round(window_s / np.median(np.diff(t)))) if t.size > 1 else 1
    k = t.size // max(n, 1)
    if k < 1:
        return t[:1], y[:1]
    return (t[:k * n].reshape(k, n).mean(axis=1),
            y[:k * n].reshape(k, n, *y.shape[1:]).mean(axis=1))


def plot_run(path: StrPath, run: ThermalRun) -> Path:
    """
    Plot temperature and raw angular rate against time (paper Figure 10).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    run : ThermalRun
        The recording.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(4, 1, figsize=(9, 8), sharex=True)
    h = run.t_s / 3600.0
    panels[0].plot(*_thin(h, run.temperature_c), color='tab:red', lw=0.8)
    panels[0].set_ylabel('temperature (degC)')
    for a, panel in enumerate(panels[1:]):
        panel.plot(*_thin(h, run.gyro_rad_s[:, a] * RAD_TO_DEG), lw=0.4, color='0.5')
        tm, ym = _window_means(run.t_s, run.gyro_rad_s[:, a], 60.0)
        panel.plot(tm / 3600.0, ym * RAD_TO_DEG, color='k', lw=1.0, label='60-s means')
        panel.set_ylabel(f'{AXES[a]} (deg/s)')
        panel.legend(fontsize=7, loc='upper right')
    panels[-1].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: temperature and raw gyro output (cf. paper Fig. 10)', fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_output(path: StrPath, run: ThermalRun, processed: NDArray[Any], *, label: str) -> Path:
    """
    Overlay raw and processed output, whole run and a 10-s zoom (paper Figure 18).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    run : ThermalRun
        Raw data.
    processed : numpy.ndarray
        Processed rate (n, 3), rad/s.
    label : str
        Method name.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(11, 8), gridspec_kw={'width_ratios': [3, 1]})
    h = run.t_s / 3600.0
    mid = run.t_s.size // 2
    zoom = slice(mid, min(mid + int(10 * run.rate_hz), run.t_s.size))
    for a in range(3):
        left, right = panels[a]
        left.plot(*_thin(h, run.gyro_rad_s[:, a] * RAD_TO_DEG), lw=0.4, color='0.6', label='raw')
        left.plot(*_thin(h, processed[:, a] * RAD_TO_DEG), lw=0.4, color='tab:blue', label=label)
        left.set_ylabel(f'{AXES[a]} (deg/s)')
        right.plot(run.t_s[zoom], run.gyro_rad_s[zoom, a] * RAD_TO_DEG, lw=0.6, color='0.6')
        right.plot(run.t_s[zoom], processed[zoom, a] * RAD_TO_DEG, lw=0.8, color='tab:blue')
        right.set_xlabel('time (s), 10-s zoom')
    panels[0][0].legend(fontsize=7, loc='upper right')
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: raw and {label} output (cf. paper Fig. 18)', fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_drift(path: StrPath, run: ThermalRun, processed: NDArray[Any], *, label: str) -> Path:
    """
    Plot the drift the method removed against time and temperature, 60-s means (paper Fig. 17).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    run : ThermalRun
        Raw data.
    processed : numpy.ndarray
        Processed rate (n, 3), rad/s.
    label : str
        Method name.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(11, 8))
    tm, raw_m = _window_means(run.t_s, run.gyro_rad_s, 60.0)
    _, rem_m = _window_means(run.t_s, run.gyro_rad_s - processed, 60.0)
    _, proc_m = _window_means(run.t_s, processed, 60.0)
    _, temp_m = _window_means(run.t_s, run.temperature_c, 60.0)
    for a in range(3):
        left, right = panels[a]
        left.plot(tm / 3600, raw_m[:, a] * RAD_TO_DEG, color='0.4', lw=1.0, label='raw')
        left.plot(tm / 3600, rem_m[:, a] * RAD_TO_DEG, color='tab:red', lw=1.0, label='removed')
        left.plot(tm / 3600, proc_m[:, a] * RAD_TO_DEG, color='tab:blue', lw=1.0, label='residual')
        left.set_ylabel(f'{AXES[a]} 60-s mean (deg/s)')
        right.plot(temp_m, raw_m[:, a] * RAD_TO_DEG, '.', ms=2, color='0.4')
        right.plot(temp_m, rem_m[:, a] * RAD_TO_DEG, '.', ms=2, color='tab:red')
        right.set_xlabel('temperature (degC)')
    panels[0][0].legend(fontsize=7)
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: drift removed by {label} (cf. paper Fig. 17)', fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_allan(path: StrPath, curves: Mapping[str, Mapping[str, tuple[ArrayLike, ArrayLike]]], *,
               title: str) -> Path:
    """
    Overlay Allan deviations per axis (paper Figure 19).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    curves : dict
        ``{label: {axis: (tau_s, adev_rad_s)}}``.
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(1, 3, figsize=(14, 4.6))
    for a, panel in enumerate(panels):
        for label, per_axis in curves.items():
            tau, adev = per_axis[AXES[a]]
            panel.loglog(tau, np.asarray(adev) * RAD_TO_DEG * 3600.0, lw=1.1, label=label)
        panel.axvline(1.0, color='0.7', lw=0.6, ls=':')
        panel.set_xlabel('tau (s)')
        panel.set_ylabel(f'Allan deviation {AXES[a]} (deg/h)')
        panel.grid(True, which='both', alpha=0.3)
    panels[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_bandwidth(path: StrPath, responses: Mapping[str, Mapping[str, FrequencyResponse]], *,
                   title: str,
                   small: Mapping[str, Mapping[str, FrequencyResponse]] | None = None) -> Path:
    """
    Plot gain, phase and group delay against frequency, one line per label and axis.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    responses : dict
        ``{label: {axis: FrequencyResponse}}``, the response to the large injection.
    title : str
        Figure title.
    small : dict, optional
        The same for the noise-sized injection, drawn dashed in the same colour (gain only:
        its phase is that of a response mostly made of noise). Each measured -3 dB corner is
        marked on its curve.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    small = small or {}

    def gain_line(fr: FrequencyResponse, name: str, style: str, colour: Any = None) -> Any:
        line, = panels[0].semilogx(fr.frequency_hz, 20 * np.log10(np.maximum(fr.gain, 1e-6)),
                                   lw=1.0, ls=style, label=name, color=colour)
        if fr.minus_3db_bound == 'measured':
            panels[0].plot([fr.minus_3db_hz], [-3.0], 'o', ms=5, mfc='none',
                           color=line.get_color())
        return line

    for label, per_axis in responses.items():
        for axis, fr in per_axis.items():
            if fr.frequency_hz.size == 0:
                continue
            name = f'{label} {axis}' if len(per_axis) > 1 else label
            line = gain_line(fr, name, '-')
            # phase and delay of a response that is mostly not the input mean nothing
            ok = np.where(fr.coherence >= 0.5, 1.0, np.nan)
            panels[1].semilogx(fr.frequency_hz, fr.phase_deg * ok, lw=1.0,
                               color=line.get_color())
            panels[2].semilogx(fr.frequency_hz, fr.group_delay_s * 1e3 * ok, lw=1.0,
                               color=line.get_color())
            fr_small = small.get(label, {}).get(axis)
            if fr_small is not None and fr_small.frequency_hz.size:
                gain_line(fr_small, f'{name}, noise-sized', '--', line.get_color())
    panels[0].axhline(-3.0, color='0.6', ls=':', lw=0.8)
    panels[0].set_ylabel('gain (dB); dashed: noise-sized motion; o: -3 dB')
    panels[1].set_ylabel('phase (deg), coherence >= 0.5')
    panels[2].set_ylabel('group delay (ms), coherence >= 0.5')
    panels[2].set_xlabel('frequency (Hz)')
    for p in panels:
        p.grid(True, which='both', alpha=0.3)
    panels[0].legend(fontsize=7, ncol=2)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_steps(path: StrPath, steps: Mapping[str, Mapping[str, StepResponse]], *,
               title: str) -> Path:
    """
    Plot the mean normalised step responses.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    steps : dict
        ``{label: {axis: StepResponse}}``.
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(1, 2, figsize=(12, 4.5))
    zoom = 0.5
    for label, per_axis in steps.items():
        for axis, st in per_axis.items():
            name = f'{label} {axis}' if len(per_axis) > 1 else label
            line, = panels[0].plot(st.t_s, st.response, lw=1.0, label=name)
            near = np.abs(st.t_s) <= zoom
            panels[1].plot(st.t_s[near], st.response[near], lw=1.0, marker='.', ms=3,
                           color=line.get_color())
    for panel, what in zip(panels, ('whole window', f'+/-{zoom:g} s')):
        panel.axvline(0.0, color='0.6', lw=0.8, ls=':')
        panel.axhline(1.0, color='0.6', lw=0.8, ls=':')
        panel.set_xlabel(f'time from the step (s), {what}')
        panel.grid(True, alpha=0.3)
    panels[0].set_ylabel('response / step (ratio)')
    panels[0].legend(fontsize=7, ncol=2)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


_CLASS_COLOURS = {'drift': 'tab:red', 'mixed': 'tab:orange', 'noise': 'tab:gray'}


def plot_mode_classes(path: StrPath, info: Any, *, title: str) -> Path | None:
    """
    Plot each mode's sample entropy coloured by its class, per axis (paper Figure 13).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    info : list of dict or None
        Per axis: ``sample_entropy`` and ``classes`` (one per mode), optionally
        ``center_freqs_hz``, as the parallel model's ``fit_info`` / ``last_info``; anything
        else (None included) draws nothing.
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path or None
        None when ``info`` lacks those keys.

    """
    try:
        rows = [(np.asarray(ax['sample_entropy'], dtype=float), list(ax['classes']),
                 np.asarray(ax.get('center_freqs_hz', []), dtype=float)) for ax in info]
    except (KeyError, TypeError, ValueError):
        return None
    if len(rows) != 3 or any(e.size != len(c) for e, c, _ in rows):
        return None
    plt = pyplot()
    fig, panels = plt.subplots(1, 3, figsize=(14, 4.2))
    for a, (panel, (ent, classes, freqs)) in enumerate(zip(panels, rows)):
        idx = np.arange(1, ent.size + 1)
        panel.bar(idx, ent, color=[_CLASS_COLOURS.get(c, 'tab:blue') for c in classes])
        if freqs.size == ent.size:
            for i, f in zip(idx, freqs):
                panel.annotate(f'{f:.3g} Hz', (i, 0), rotation=90, fontsize=6, ha='center',
                               va='bottom', xytext=(0, 2), textcoords='offset points')
        panel.set_xlabel('IMF (index, by ascending centre frequency)')
        panel.set_ylabel(f'sample entropy, axis {AXES[a]} (nats)')
        panel.set_xticks(idx)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in _CLASS_COLOURS.values()]
    panels[0].legend(handles, list(_CLASS_COLOURS), fontsize=7)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_mopso(path: StrPath, axes: Sequence[Mapping[str, Any] | None], *, title: str) -> Path:
    """
    Plot the final MOPSO archive and the picked point per axis (paper Figure 11).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    axes : list of dict or None
        Per axis (three): ``fuzzy_entropy``, ``permutation_entropy``, ``k``, ``alpha`` (one per
        archive point) and ``pick`` = (k, alpha, fuzzy entropy, permutation entropy); None for
        an axis without an archive.
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    from matplotlib.ticker import MaxNLocator

    fig, panels = plt.subplots(2, 3, figsize=(14, 7.5))
    for a in range(3):
        front, space = panels[0][a], panels[1][a]
        ax = axes[a] if a < len(axes) else None
        if ax is None:
            for panel in (front, space):
                panel.text(0.5, 0.5, 'no archive recorded', ha='center', va='center',
                           transform=panel.transAxes)
        else:
            fe = np.asarray(ax['fuzzy_entropy'], dtype=float)
            pe = np.asarray(ax['permutation_entropy'], dtype=float)
            order = np.argsort(fe)
            front.plot(fe[order], pe[order], 'o-', ms=4, lw=0.6, color='tab:blue',
                       label=f'archive ({fe.size} points)')
            k, alpha, fe_pick, pe_pick = ax['pick']
            front.plot([fe_pick], [pe_pick], '*', ms=14, color='tab:red',
                       label=f'picked K = {int(k)}, alpha = {alpha:.0f}')
            space.plot(np.asarray(ax['k'], dtype=float), np.asarray(ax['alpha'], dtype=float),
                       'o', ms=4, color='tab:blue', label='archive')
            space.plot([k], [alpha], '*', ms=14, color='tab:red', label='picked')
            space.xaxis.set_major_locator(MaxNLocator(integer=True))
            front.legend(fontsize=7)
            space.legend(fontsize=7)
        front.set_xlabel(f'mean fuzzy entropy of the modes, axis {AXES[a]} (nats)')
        front.set_ylabel('mean permutation entropy (normalised, 0-1)')
        space.set_xlabel('K (number of modes)')
        space.set_ylabel('alpha (bandwidth penalty, dimensionless)')
        for panel in (front, space):
            panel.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_modes(path: StrPath, axes: Sequence[Mapping[str, Any]], *, title: str) -> Path:
    """
    Plot the input and each VMD mode against time, per axis, coloured by class (paper Fig. 12).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    axes : list of dict
        Per axis (three): ``t_h`` (time, h), ``input`` and ``modes`` (list, one per mode), rad/s,
        on the ``t_h`` grid (e.g. :func:`envelope`), ``center_freqs_hz`` and ``classes`` (one
        per mode, ascending centre frequency).
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    rows = 1 + max(len(ax['modes']) for ax in axes)
    fig, panels = plt.subplots(rows, 3, figsize=(14, 1.6 + 0.95 * rows), sharex='col',
                               squeeze=False)
    for a, ax in enumerate(axes):
        col = panels[:, a]
        col[0].plot(ax['t_h'], np.asarray(ax['input']) * RAD_TO_DEG, lw=0.4, color='k')
        col[0].set_ylabel(f'{AXES[a]} input (deg/s)', fontsize=7)
        col[0].set_title(f'axis {AXES[a]}', fontsize=9)
        labelled = zip(ax['modes'], ax['center_freqs_hz'], ax['classes'])
        for i, (mode, f_hz, cls) in enumerate(labelled):
            panel = col[i + 1]
            panel.plot(ax['t_h'], np.asarray(mode) * RAD_TO_DEG, lw=0.4,
                       color=_CLASS_COLOURS.get(cls, 'tab:blue'))
            panel.set_ylabel(f'IMF{i + 1} (deg/s)', fontsize=7)
            panel.text(0.01, 0.95, f'{cls}, centre {f_hz:.3g} Hz', transform=panel.transAxes,
                       fontsize=7, va='top', ha='left',
                       bbox={'facecolor': 'white', 'alpha': 0.7, 'lw': 0})
        for panel in col[len(ax['modes']) + 1:]:
            panel.set_visible(False)
        col[len(ax['modes'])].set_xlabel('time (h)')
        col[len(ax['modes'])].xaxis.set_tick_params(labelbottom=True)
        for panel in col:
            panel.tick_params(labelsize=7)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in _CLASS_COLOURS.values()]
    fig.legend(handles, list(_CLASS_COLOURS), fontsize=8, loc='upper right', ncol=3)
    fig.suptitle(title, fontsize=10)
    # fixed margins: tight_layout over up to 39 panels costs more than drawing them
    top = 1.0 - 0.75 / fig.get_figheight()
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.55 / fig.get_figheight(), top=top,
                        wspace=0.25, hspace=0.35)
    return save_figure(fig, path, dpi=100)


def plot_before_after(path: StrPath, axes: Sequence[Mapping[str, Any]], *, title: str, before: str,
                      after: str) -> Path:
    """
    Overlay a signal before and after a processing step: whole run and a zoom (Figs. 14, 15).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    axes : list of dict
        Per axis (three): ``t_h`` (time, h) with ``before`` and ``after`` on it (rad/s, e.g.
        :func:`envelope` of each), ``zoom_t_s`` (time, s) with ``zoom_before`` and
        ``zoom_after`` (rad/s, every sample of a short stretch), ``name`` (what the signal is).
    title : str
        Figure title.
    before, after : str
        Legend labels.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(12, 8), gridspec_kw={'width_ratios': [3, 2]})
    for a, ax in enumerate(axes):
        left, right = panels[a]
        left.plot(ax['t_h'], np.asarray(ax['before']) * RAD_TO_DEG, lw=0.4, color='0.6',
                  label=before)
        left.plot(ax['t_h'], np.asarray(ax['after']) * RAD_TO_DEG, lw=0.4, color='tab:blue',
                  label=after)
        left.set_ylabel(f'{AXES[a]} {ax["name"]} (deg/s)', fontsize=8)
        zt = np.asarray(ax['zoom_t_s'])
        right.plot(zt, np.asarray(ax['zoom_before']) * RAD_TO_DEG, lw=0.6, color='0.6')
        right.plot(zt, np.asarray(ax['zoom_after']) * RAD_TO_DEG, lw=0.9, color='tab:blue')
        span = zt[-1] - zt[0] if zt.size > 1 else 0.0
        right.set_xlabel(f'time (s), {span:.3g}-s zoom')
        right.set_ylabel(f'{AXES[a]} (deg/s)', fontsize=8)
    panels[0][0].legend(fontsize=7, loc='upper right')
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def plot_network(path: StrPath, axes: Sequence[Sequence[Mapping[str, Any]]], *,
                 title: str) -> Path:
    """
    Plot rows of panels of slow series against time, one row per axis (paper Figs. 16, 17).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    axes : list of list of dict
        Per axis (three rows), the panels of the row: ``title``, ``t_h`` (time, h) and
        ``lines``: a list of (label, values in rad/s on ``t_h``, colour).
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = pyplot()
    cols = max(len(row) for row in axes)
    fig, panels = plt.subplots(3, cols, figsize=(6 * cols + 1, 8), squeeze=False,
                               sharex=True)
    for a, row in enumerate(axes):
        for c, cell in enumerate(row):
            panel = panels[a][c]
            for label, values, colour in cell['lines']:
                panel.plot(cell['t_h'], np.asarray(values) * RAD_TO_DEG, lw=1.0, color=colour,
                           label=label)
            panel.set_ylabel(f'{AXES[a]} (deg/s)')
            panel.set_title(cell['title'], fontsize=8)
            panel.legend(fontsize=7)
            panel.grid(True, alpha=0.3)
    for panel in panels[-1]:
        panel.set_xlabel('time (h)')
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


def _rms_deg_s(x: ArrayLike) -> float:
    return float(np.degrees(np.sqrt(np.mean(np.square(x))))) if np.size(x) else float('nan')


def parallel_figures(model: 'ParallelModel', run: ThermalRun, parts: Sequence[Mapping[str, Any]],
                     out_dir: StrPath) -> list[tuple[str | None, str]]:
    """
    Draw the parallel model's own figures (paper Figures 11, 12 and 14-17) for a run.

    MOPSO is never re-run: Figure 11 is drawn from the model's ``fit_info``, which exists only
    in the process that fitted the model; otherwise its entry has no file name and its caption
    says where the figure is. Figure 13 (sample entropy and class of each mode) is the report's
    generic figure (:func:`plot_mode_classes`).

    Parameters
    ----------
    model : ParallelModel
        The fitted model (its ``axes``, ``options``, ``fit_info``, ``network_grid``).
    run : ThermalRun
        The run the figures describe.
    parts : list of dict
        Per axis, what the model's ``apply`` kept of that run at plot size (envelopes of the
        input, modes and parts; a zoom; the drift part on the network's grid).
    out_dir : pathlib.Path
        Existing directory the PNG files are written to.

    Returns
    -------
    list of (str or None, str)
        File name relative to ``out_dir`` (None: no figure) and a caption citing the paper
        figure it mirrors ('Fig. N').

    """
    assert model.axes is not None  # fitted
    out_dir = Path(out_dir)
    name = run.name or 'run'
    figs = [_mopso_figure(model, out_dir, name)]
    plot_modes(out_dir / 'fig12_modes.png', [
        {'t_h': p['t_h'], 'input': p['input'], 'modes': p['modes'],
         'center_freqs_hz': p['center_freqs_hz'], 'classes': p['classes']} for p in parts],
        title=f'{name}: VMD modes with the trained K and alpha, coloured by class')
    ks = ', '.join(str(ax['k']) for ax in model.axes)
    figs.append(('fig12_modes.png', f'VMD of the run into K = {ks} modes (x, y, z), each '
                 'with its class and centre frequency, min/max envelopes of long runs '
                 '(cf. Fig. 12)'))
    zoom_t = [np.asarray(run.t_s)[p['zoom']] for p in parts]
    n_mixed = [p['classes'].count('mixed') for p in parts]
    plot_before_after(out_dir / 'fig14_tfpf.png', [
        {'t_h': p['t_h'], 'before': p['mixed_in'], 'after': p['mixed_out'],
         'zoom_t_s': zt, 'zoom_before': p['zoom_mixed_in'],
         'zoom_after': p['zoom_mixed_out'], 'name': f'mixed part ({m} modes)'}
        for p, zt, m in zip(parts, zoom_t, n_mixed)],
        title=f'{name}: sum of the mixed modes before and after TFPF '
              f'(window {int(model.options["tfpf_window"])} samples)',
        before='mixed part', after='after TFPF')
    empty = ', '.join(a for a, m in zip(AXES, n_mixed) if m == 0)
    figs.append(('fig14_tfpf.png', 'Sum of the mixed modes before and after time-frequency '
                 'peak filtering, whole run and a zoom of 20 TFPF windows (cf. Fig. 14)'
                 + (f'; no mode of axis {empty} is classed mixed on this run, so it shows '
                    'zeros' if empty else '')))
    plot_before_after(out_dir / 'fig15_denoised.png', [
        {'t_h': p['t_h'], 'before': p['input'], 'after': p['denoised'],
         'zoom_t_s': zt, 'zoom_before': np.asarray(run.gyro_rad_s)[p['zoom'], a],
         'zoom_after': p['zoom_denoised'], 'name': 'output'}
        for a, (p, zt) in enumerate(zip(parts, zoom_t))],
        title=f'{name}: raw output and denoised output (noise modes dropped, mixed part '
              'TFPF-filtered, drift part not yet compensated)',
        before='raw', after='denoised')
    figs.append(('fig15_denoised.png', 'Raw output and the denoised output before drift '
                 'compensation: mixed part after TFPF plus the drift part (cf. Fig. 15)'))
    net16, net17 = _network_panels(model, run, parts)
    plot_network(out_dir / 'fig16_elman.png', net16,
                 title=f'{name}: drift part and its prediction from [T, dT]: a random start, '
                       'after beetle antennae search, after the local refinement')
    figs.append(('fig16_elman.png', 'Drift part (sum of the drift modes, block means on the '
                 "network's grid) and the drift model's prediction from temperature and its "
                 'rate: with network weights drawn as BAS draws its start (seed 0; the '
                 "fit's own start is not stored), after BAS, and after the L-BFGS refinement "
                 '(the fitted model) (cf. Fig. 16)'))
    plot_network(out_dir / 'fig17_drift_part.png', net17,
                 title=f'{name}: drift part, its prediction and its compensation')
    figs.append(('fig17_drift_part.png', 'Drift part and its prediction (a), and the '
                 'compensated drift part, drift minus prediction (b) (cf. Fig. 17)'))
    return figs


def _mopso_figure(model: 'ParallelModel', out_dir: Path, name: str) -> tuple[str | None, str]:
    info = model.fit_info or []
    archives: list[Any] = [ax.get('mopso') for ax in info]
    keys = ('archive_fuzzy_entropy', 'archive_permutation_entropy', 'archive_k',
            'archive_alpha')
    if len(archives) != 3 or not all(a and all(k in a for k in keys) for a in archives):
        return (None, 'the MOPSO archive (Fig. 11) is drawn by `fit` beside model.json '
                      '(fig11_mopso.png of the training report); model.json keeps only '
                      'the picked K and alpha')
    assert model.axes is not None  # fitted
    axes = []
    for arch, ax in zip(archives, model.axes):
        fit = ax.get('fitness', {})
        axes.append({'fuzzy_entropy': arch['archive_fuzzy_entropy'],
                     'permutation_entropy': arch['archive_permutation_entropy'],
                     'k': arch['archive_k'], 'alpha': arch['archive_alpha'],
                     'pick': (ax['k'], ax['alpha'], fit.get('fuzzy_entropy', np.nan),
                              fit.get('permutation_entropy', np.nan))})
    plot_mopso(out_dir / 'fig11_mopso.png', axes,
               title=f'{name}: final MOPSO archive (Pareto front) and the picked '
                     '(K, alpha), per axis')
    return ('fig11_mopso.png', 'Final MOPSO archive: the Pareto front of mean fuzzy and '
            'permutation entropy, and the archive in (K, alpha), with the picked point '
            '(cf. Fig. 11; the paper also shows the swarm per iteration)')


def _network_panels(model: 'ParallelModel', run: ThermalRun,
                    parts: Sequence[Mapping[str, Any]]) -> tuple[_PanelRows, _PanelRows]:
    """Return the panel rows of Figures 16 and 17 (the drift part on the network's grid)."""
    from .elman import DriftModel, fit_elman

    # the distribution fit_elman draws BAS's start from (it is not stored with the model)
    scale = inspect.signature(fit_elman).parameters['init_scale'].default
    rows16, rows17 = [], []
    assert model.axes is not None  # fitted
    for ax, p in zip(model.axes, parts):
        drift_model = DriftModel.from_dict(ax['elman'])
        grid, t_h = model.network_grid(run, p['q'])
        net = drift_model.network
        start = scale * np.random.default_rng(0).standard_normal(net.theta.size)
        actual, after = p['drift_blocks'], drift_model.predict(grid)
        stages = [('random start', drift_model.predict(grid, theta=start), 'tab:orange')]
        if net.theta_bas is not None:
            stages.append(('after BAS', drift_model.predict(grid, theta=net.theta_bas),
                           'tab:purple'))
        stages.append(('after BAS and refinement (fitted)' if net.theta_bas is not None
                       else 'after BAS (fitted)', after, 'tab:blue'))
        rows16.append([{'title': f'{label}: rms error {_rms_deg_s(pred - actual):.3g} deg/s',
                        't_h': t_h,
                        'lines': [('drift part', actual, 'k'), ('prediction', pred, colour)]}
                       for label, pred, colour in stages])
        rows17.append([
            {'title': '(a) drift part and its prediction from [T, dT]', 't_h': t_h,
             'lines': [('drift part', actual, 'k'), ('prediction', after, 'tab:blue')]},
            {'title': '(b) compensated drift part (drift part - prediction): rms '
                      f'{_rms_deg_s(actual - after):.3g} deg/s', 't_h': t_h,
             'lines': [('compensated drift part', actual - after, 'tab:green')]}])
    return rows16, rows17


#: Paper 002's result figures: number -> (what it shows, why a method may have no analogue;
#: None for the generic figures every method gets). Figures 1-9 show the device, the algorithms
#: and the test rig.
PAPER_FIGURES = {
    10: ('temperature and gyro output against time', None),
    11: ('MOPSO particles and the Pareto front of (K, alpha)',
         'it chooses no VMD parameters by MOPSO'),
    12: ('the VMD modes (IMFs) of the output', 'it does not decompose the output into modes'),
    13: ('sample entropy and class of each IMF', 'it has no modes classified by sample entropy'),
    14: ('the mixed modes before and after TFPF', 'it has no mixed part filtered by TFPF'),
    15: ('the output before and after denoising alone',
         'it has no separate denoising stage (its whole output is the Fig. 18 analogue)'),
    16: ("the Elman network's prediction before and after BAS",
         'it has no network whose weights beetle antennae search optimises'),
    17: ('the drift part, its prediction and its compensation', None),
    18: ('the final output after denoising and compensation', None),
    19: ('Allan deviation before and after processing', None),
}

_FIG_REF = re.compile(r'\bFigs?\.\s*(\d+(?:\s*(?:,|-|and)\s*\d+)*)')


def figure_numbers(caption: str) -> list[int]:
    """
    Return the paper figure numbers a caption cites ('Fig. 12', 'Figs. 15, 18', 'Figs. 12-14').

    Parameters
    ----------
    caption : str
        Figure caption.

    Returns
    -------
    list of int
        Sorted, without repeats.

    """
    found: set[int] = set()
    for group in _FIG_REF.findall(caption):
        for part in re.split(r'\s*(?:,|and)\s*', group):
            ends = [int(v) for v in re.split(r'\s*-\s*', part) if v]
            found.update(range(ends[0], ends[-1] + 1))
    return sorted(found)


def figures_markdown(figs: Iterable[tuple[str, StrPath | None]], out: Path, *, method: str) -> str:
    """
    Write a report's figure section: paper figures 10-19 and their analogues, then the images.

    Parameters
    ----------
    figs : list of (str, path or None)
        (caption, PNG path) per figure; a caption cites the paper figures it mirrors as 'Fig. N'
        or 'Figs. N, M' (:func:`figure_numbers`). A None path is a figure the method has no
        analogue for, the caption saying why.
    out : pathlib.Path
        Report directory (image links are relative to it).
    method : str
        Method name, for the lines about missing analogues.

    Returns
    -------
    str
        Markdown.

    """
    drawn = [(cap, Path(p)) for cap, p in figs if p is not None]
    said = [cap for cap, p in figs if p is None]
    rows = []
    for num, (shows, missing) in PAPER_FIGURES.items():
        files = [f'`{p.relative_to(out)}`' for cap, p in drawn if num in figure_numbers(cap)]
        why = [cap for cap in said if num in figure_numbers(cap)]
        if files:
            here = ', '.join(files)
        elif why:
            here = f'none: {why[0]}'
        elif missing is None:
            here = 'not drawn in this report' + ('' if num != 19 else ' (`apply` draws the '
                                                 'Allan deviations of a held-out run)')
        else:
            here = f'no analogue for `{method}`: {missing}'
        rows.append(f'| {num} | {shows} | {here} |')
    order = sorted(range(len(drawn)), key=lambda i: (min(figure_numbers(drawn[i][0]) or [99]),
                                                     i))
    images = ''.join(f'\n![{drawn[i][0]}]({drawn[i][1].relative_to(out)})\n\n*{drawn[i][0]}*\n'
                     for i in order)
    return ('\n## Figures\n\nPaper 002 shows its results in Figures 10-19 (1-9 are the device, '
            f'the algorithms and the rig). Their analogues for `{method}` on this run:\n\n'
            '| paper figure | shows | here |\n|---|---|---|\n' + '\n'.join(rows) + '\n'
            + images)


def method_figures(method: Any, run: ThermalRun, out_dir: StrPath) -> list[tuple[str | None, str]]:
    """
    Ask the method for its own figures (paper Figures 11, 12, 14-17), if it offers any.

    Parameters
    ----------
    method : ThermalMethod
        Fitted method; used only if it has ``report_figures(run, out_dir)``.
    run : ThermalRun
        The data the figures describe.
    out_dir : pathlib.Path
        Where to write them.

    Returns
    -------
    list of (str or None, str)
        (file name relative to ``out_dir``, caption); a None name is a paper figure the method
        has no analogue for, its caption saying why. Empty for a method without the hook.

    """
    hook = getattr(method, 'report_figures', None)
    if not callable(hook):
        return []
    return [(None if name is None else str(name), str(caption))
            for name, caption in hook(run, Path(out_dir))]


def bias_stability_cell(metrics: Mapping[str, Any], spec: str = '.4g') -> str:
    """
    Format a bias stability: the value, or '<= value' when the readout gives an upper bound.

    Parameters
    ----------
    metrics : dict
        ``bias_stability_deg_h`` and ``bias_stability_upper_bound`` (metrics.json keys).
    spec : str
        Number format.

    Returns
    -------
    str

    """
    value = metrics.get('bias_stability_deg_h')
    if value is None or not math.isfinite(value):
        return 'n/a'
    return ('<= ' if metrics.get('bias_stability_upper_bound') else '') + format(value, spec)


def _cell(value: Any, spec: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, str):
        return value
    return format(value, spec)


def table_markdown(header: Sequence[str], rows: Iterable[Sequence[Any]],
                   specs: Sequence[str]) -> str:
    """
    Format a Markdown table.

    Parameters
    ----------
    header : sequence of str
        Column titles (with units).
    rows : sequence of sequence
        Cell values (None/NaN shown as n/a, bools as yes/no).
    specs : sequence of str
        Format spec per column for numbers.

    Returns
    -------
    str

    """
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for row in rows:
        lines.append('| ' + ' | '.join(_cell(v, s) for v, s in zip(row, specs)) + ' |')
    return '\n'.join(lines) + '\n'
