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
The parallel model's own figures: analogues of paper 002's Figures 11, 12 and 14-17.

Input: a fitted :class:`.parallel.ParallelModel` (its ``axes``, ``options``, ``fit_info``,
``network_grid``), a run and what the model's ``apply`` kept of it at plot size (per axis: the
input, modes and parts as min/max envelopes of :data:`PANEL_POINTS` points, a zoom, the drift
part on the network's grid; rad/s). Outputs, in deg/s: :func:`parallel_figures` draws
fig11_mopso.png (the MOPSO archive, when the model keeps it), fig12_modes.png (the VMD modes),
fig14_tfpf.png (the mixed part before and after TFPF), fig15_denoised.png, fig16_elman.png (the
network before and after BAS) and fig17_drift_part.png, with :func:`plot_mopso`,
:func:`plot_modes`, :func:`plot_before_after` and :func:`plot_network`. The model calls it from
its ``report_figures`` hook (:func:`.figures.method_figures`); this module does not import the
model.
"""

from collections.abc import Mapping, Sequence
import inspect
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .figures import AXES, CLASS_COLOURS
from .run import ThermalRun
from ..outputs import StrPath
from ..plotting import pyplot, save_figure
from ..units import RAD_TO_DEG

__all__ = ['PANEL_POINTS', 'parallel_figures', 'plot_before_after', 'plot_modes', 'plot_mopso',
           'plot_network']

#: Points per trace of the narrower panels of the method figures (two per pixel column).
PANEL_POINTS = 1600

# The panel rows of plot_network: per axis, the panels of its row.
_PanelRows = list[list[dict[str, Any]]]


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
        on the ``t_h`` grid (e.g. :func:`..plotting.envelope`), ``center_freqs_hz`` and
        ``classes`` (one per mode, ascending centre frequency).
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
                       color=CLASS_COLOURS.get(cls, 'tab:blue'))
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
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in CLASS_COLOURS.values()]
    fig.legend(handles, list(CLASS_COLOURS), fontsize=8, loc='upper right', ncol=3)
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
        :func:`..plotting.envelope` of each), ``zoom_t_s`` (time, s) with ``zoom_before`` and
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


def parallel_figures(model: Any, run: ThermalRun, parts: Sequence[Mapping[str, Any]],
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
        The fitted model (:class:`.parallel.ParallelModel`: its ``axes``, ``options``,
        ``fit_info`` and ``network_grid(run, q)`` are read).
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


def _mopso_figure(model: Any, out_dir: Path, name: str) -> tuple[str | None, str]:
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


def _network_panels(model: Any, run: ThermalRun,
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
