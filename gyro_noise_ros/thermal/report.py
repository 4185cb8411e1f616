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

import math
from pathlib import Path
import re

import numpy as np

__all__ = ['PAPER_FIGURES', 'envelope', 'figure_numbers', 'figures_markdown', 'method_figures',
           'plot_allan', 'plot_bandwidth', 'plot_before_after', 'plot_drift', 'plot_mode_classes',
           'plot_modes', 'plot_mopso', 'plot_network', 'plot_output', 'plot_run', 'plot_steps',
           'table_markdown']

DEG = 180.0 / math.pi
AXES = 'xyz'
#: Points per trace in time plots (longer runs are reduced to min/max envelopes of blocks).
_MAX_POINTS = 4000
#: Points per trace of the narrower panels of the method figures (two per pixel column).
PANEL_POINTS = 1600


def _pyplot():
    import matplotlib

    matplotlib.use('Agg', force=True)
    import matplotlib.pyplot as plt

    return plt


def envelope(t, y, max_points=_MAX_POINTS):
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


def _window_means(t, y, window_s):
    n = int(round(window_s / np.median(np.diff(t)))) if t.size > 1 else 1
    k = t.size // max(n, 1)
    if k < 1:
        return t[:1], y[:1]
    return (t[:k * n].reshape(k, n).mean(axis=1),
            y[:k * n].reshape(k, n, *y.shape[1:]).mean(axis=1))


def _save(fig, plt, path, *, tight=True):
    if tight:
        fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def plot_run(path, run):
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
    plt = _pyplot()
    fig, panels = plt.subplots(4, 1, figsize=(9, 8), sharex=True)
    h = run.t_s / 3600.0
    panels[0].plot(*_thin(h, run.temperature_c), color='tab:red', lw=0.8)
    panels[0].set_ylabel('temperature (degC)')
    for a, panel in enumerate(panels[1:]):
        panel.plot(*_thin(h, run.gyro_rad_s[:, a] * DEG), lw=0.4, color='0.5')
        tm, ym = _window_means(run.t_s, run.gyro_rad_s[:, a], 60.0)
        panel.plot(tm / 3600.0, ym * DEG, color='k', lw=1.0, label='60-s means')
        panel.set_ylabel(f'{AXES[a]} (deg/s)')
        panel.legend(fontsize=7, loc='upper right')
    panels[-1].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: temperature and raw gyro output (cf. paper Fig. 10)', fontsize=10)
    return _save(fig, plt, path)


def plot_output(path, run, processed, *, label):
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
    plt = _pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(11, 8), gridspec_kw={'width_ratios': [3, 1]})
    h = run.t_s / 3600.0
    mid = run.t_s.size // 2
    zoom = slice(mid, min(mid + int(10 * run.rate_hz), run.t_s.size))
    for a in range(3):
        left, right = panels[a]
        left.plot(*_thin(h, run.gyro_rad_s[:, a] * DEG), lw=0.4, color='0.6', label='raw')
        left.plot(*_thin(h, processed[:, a] * DEG), lw=0.4, color='tab:blue', label=label)
        left.set_ylabel(f'{AXES[a]} (deg/s)')
        right.plot(run.t_s[zoom], run.gyro_rad_s[zoom, a] * DEG, lw=0.6, color='0.6')
        right.plot(run.t_s[zoom], processed[zoom, a] * DEG, lw=0.8, color='tab:blue')
        right.set_xlabel('time (s), 10-s zoom')
    panels[0][0].legend(fontsize=7, loc='upper right')
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: raw and {label} output (cf. paper Fig. 18)', fontsize=10)
    return _save(fig, plt, path)


def plot_drift(path, run, processed, *, label):
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
    plt = _pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(11, 8))
    tm, raw_m = _window_means(run.t_s, run.gyro_rad_s, 60.0)
    _, rem_m = _window_means(run.t_s, run.gyro_rad_s - processed, 60.0)
    _, proc_m = _window_means(run.t_s, processed, 60.0)
    _, temp_m = _window_means(run.t_s, run.temperature_c, 60.0)
    for a in range(3):
        left, right = panels[a]
        left.plot(tm / 3600, raw_m[:, a] * DEG, color='0.4', lw=1.0, label='raw')
        left.plot(tm / 3600, rem_m[:, a] * DEG, color='tab:red', lw=1.0, label='removed')
        left.plot(tm / 3600, proc_m[:, a] * DEG, color='tab:blue', lw=1.0, label='residual')
        left.set_ylabel(f'{AXES[a]} 60-s mean (deg/s)')
        right.plot(temp_m, raw_m[:, a] * DEG, '.', ms=2, color='0.4')
        right.plot(temp_m, rem_m[:, a] * DEG, '.', ms=2, color='tab:red')
        right.set_xlabel('temperature (degC)')
    panels[0][0].legend(fontsize=7)
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(f'{run.name}: drift removed by {label} (cf. paper Fig. 17)', fontsize=10)
    return _save(fig, plt, path)


def plot_allan(path, curves, *, title):
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
    plt = _pyplot()
    fig, panels = plt.subplots(1, 3, figsize=(14, 4.6))
    for a, panel in enumerate(panels):
        for label, per_axis in curves.items():
            tau, adev = per_axis[AXES[a]]
            panel.loglog(tau, np.asarray(adev) * DEG * 3600.0, lw=1.1, label=label)
        panel.axvline(1.0, color='0.7', lw=0.6, ls=':')
        panel.set_xlabel('tau (s)')
        panel.set_ylabel(f'Allan deviation {AXES[a]} (deg/h)')
        panel.grid(True, which='both', alpha=0.3)
    panels[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return _save(fig, plt, path)


def plot_bandwidth(path, responses, *, title):
    """
    Plot gain, phase and group delay against frequency, one line per label and axis.

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    responses : dict
        ``{label: {axis: FrequencyResponse}}``.
    title : str
        Figure title.

    Returns
    -------
    pathlib.Path

    """
    plt = _pyplot()
    fig, panels = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for label, per_axis in responses.items():
        for axis, fr in per_axis.items():
            if fr.frequency_hz.size == 0:
                continue
            name = f'{label} {axis}' if len(per_axis) > 1 else label
            line, = panels[0].semilogx(fr.frequency_hz, 20 * np.log10(np.maximum(fr.gain, 1e-6)),
                                       lw=1.0, label=name)
            # phase and delay of a response that is mostly not the input mean nothing
            ok = np.where(fr.coherence >= 0.5, 1.0, np.nan)
            panels[1].semilogx(fr.frequency_hz, fr.phase_deg * ok, lw=1.0,
                               color=line.get_color())
            panels[2].semilogx(fr.frequency_hz, fr.group_delay_s * 1e3 * ok, lw=1.0,
                               color=line.get_color())
    panels[0].axhline(-3.0, color='0.6', ls=':', lw=0.8)
    panels[0].set_ylabel('gain (dB)')
    panels[1].set_ylabel('phase (deg), coherence >= 0.5')
    panels[2].set_ylabel('group delay (ms), coherence >= 0.5')
    panels[2].set_xlabel('frequency (Hz)')
    for p in panels:
        p.grid(True, which='both', alpha=0.3)
    panels[0].legend(fontsize=7, ncol=2)
    fig.suptitle(title, fontsize=10)
    return _save(fig, plt, path)


def plot_steps(path, steps, *, title):
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
    plt = _pyplot()
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
    return _save(fig, plt, path)


_CLASS_COLOURS = {'drift': 'tab:red', 'mixed': 'tab:orange', 'noise': 'tab:gray'}


def plot_mode_classes(path, info, *, title):
    """
    Plot each mode's sample entropy coloured by its class, per axis (paper Figure 13).

    Parameters
    ----------
    path : str or os.PathLike
        PNG file.
    info : list of dict
        Per axis: ``sample_entropy`` and ``classes`` (one per mode), optionally
        ``center_freqs_hz``, as the parallel model's ``fit_info`` / ``last_info``.
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
    plt = _pyplot()
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
    return _save(fig, plt, path)


def plot_mopso(path, axes, *, title):
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
    plt = _pyplot()
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
    return _save(fig, plt, path)


def plot_modes(path, axes, *, title):
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
    plt = _pyplot()
    rows = 1 + max(len(ax['modes']) for ax in axes)
    fig, panels = plt.subplots(rows, 3, figsize=(14, 1.6 + 0.95 * rows), sharex='col',
                               squeeze=False)
    for a, ax in enumerate(axes):
        col = panels[:, a]
        col[0].plot(ax['t_h'], np.asarray(ax['input']) * DEG, lw=0.4, color='k')
        col[0].set_ylabel(f'{AXES[a]} input (deg/s)', fontsize=7)
        col[0].set_title(f'axis {AXES[a]}', fontsize=9)
        labelled = zip(ax['modes'], ax['center_freqs_hz'], ax['classes'])
        for i, (mode, f_hz, cls) in enumerate(labelled):
            panel = col[i + 1]
            panel.plot(ax['t_h'], np.asarray(mode) * DEG, lw=0.4,
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
    return _save(fig, plt, path, tight=False)


def plot_before_after(path, axes, *, title, before, after):
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
    plt = _pyplot()
    fig, panels = plt.subplots(3, 2, figsize=(12, 8), gridspec_kw={'width_ratios': [3, 2]})
    for a, ax in enumerate(axes):
        left, right = panels[a]
        left.plot(ax['t_h'], np.asarray(ax['before']) * DEG, lw=0.4, color='0.6', label=before)
        left.plot(ax['t_h'], np.asarray(ax['after']) * DEG, lw=0.4, color='tab:blue',
                  label=after)
        left.set_ylabel(f'{AXES[a]} {ax["name"]} (deg/s)', fontsize=8)
        zt = np.asarray(ax['zoom_t_s'])
        right.plot(zt, np.asarray(ax['zoom_before']) * DEG, lw=0.6, color='0.6')
        right.plot(zt, np.asarray(ax['zoom_after']) * DEG, lw=0.9, color='tab:blue')
        span = zt[-1] - zt[0] if zt.size > 1 else 0.0
        right.set_xlabel(f'time (s), {span:.3g}-s zoom')
        right.set_ylabel(f'{AXES[a]} (deg/s)', fontsize=8)
    panels[0][0].legend(fontsize=7, loc='upper right')
    panels[-1][0].set_xlabel('time (h)')
    fig.suptitle(title, fontsize=10)
    return _save(fig, plt, path)


def plot_network(path, axes, *, title):
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
    plt = _pyplot()
    cols = max(len(row) for row in axes)
    fig, panels = plt.subplots(3, cols, figsize=(6 * cols + 1, 8), squeeze=False,
                               sharex=True)
    for a, row in enumerate(axes):
        for c, cell in enumerate(row):
            panel = panels[a][c]
            for label, values, colour in cell['lines']:
                panel.plot(cell['t_h'], np.asarray(values) * DEG, lw=1.0, color=colour,
                           label=label)
            panel.set_ylabel(f'{AXES[a]} (deg/s)')
            panel.set_title(cell['title'], fontsize=8)
            panel.legend(fontsize=7)
            panel.grid(True, alpha=0.3)
    for panel in panels[-1]:
        panel.set_xlabel('time (h)')
    fig.suptitle(title, fontsize=10)
    return _save(fig, plt, path)


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


def figure_numbers(caption):
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
    found = set()
    for group in _FIG_REF.findall(caption):
        for part in re.split(r'\s*(?:,|and)\s*', group):
            ends = [int(v) for v in re.split(r'\s*-\s*', part) if v]
            found.update(range(ends[0], ends[-1] + 1))
    return sorted(found)


def figures_markdown(figs, out, *, method):
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


def method_figures(method, run, out_dir):
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


def _cell(value, spec):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, str):
        return value
    return format(value, spec)


def table_markdown(header, rows, specs):
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
