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
The PNG figures of ``gyro_noise_thermal`` every method gets: analogues of paper 002's Figures.

Inputs: a run (:class:`.run.ThermalRun`: time s, gyro rad/s, temperature degC), a method's
processed output (rad/s), the Allan curves and the responses to injected motion of the scoring
(:mod:`.metrics`), a method's mode diagnostics. Outputs, converted to deg/s (deg/h for the
Allan deviation) at this edge: :func:`plot_run` (Fig. 10, temperature and raw output),
:func:`plot_output` (Fig. 18, raw and processed), :func:`plot_drift` (Fig. 17, the drift
removed, 60-s means, against time and temperature), :func:`plot_allan` (Fig. 19),
:func:`plot_mode_classes` (Fig. 13, sample entropy and class of each mode), and the costs the
paper does not draw: :func:`plot_bandwidth` (gain, phase, group delay) and :func:`plot_steps`.
:func:`training_figures`, :func:`apply_figures` and :func:`compare_figures` draw the set of each
command's report; :func:`method_figures` asks a method for its own (the parallel model's:
:mod:`.parallel_figures`). Long traces are min/max envelopes (:func:`..plotting.envelope`).
"""

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .metrics import FrequencyResponse, StepResponse
from .run import ThermalRun
from ..outputs import StrPath
from ..plotting import envelope, pyplot, save_figure
from ..units import RAD_TO_DEG

__all__ = ['AXES', 'CLASS_COLOURS', 'Figures', 'apply_figures', 'compare_figures',
           'method_figures', 'plot_allan', 'plot_bandwidth', 'plot_drift', 'plot_mode_classes',
           'plot_output', 'plot_run', 'plot_steps', 'training_figures']

AXES = 'xyz'
#: Figures of a report: (caption citing the paper figure, PNG file or None when the method has
#: no such figure, the caption saying why).
Figures = list[tuple[str, Path | None]]


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
    panels[0].plot(*envelope(h, run.temperature_c), color='tab:red', lw=0.8)
    panels[0].set_ylabel('temperature (degC)')
    for a, panel in enumerate(panels[1:]):
        panel.plot(*envelope(h, run.gyro_rad_s[:, a] * RAD_TO_DEG), lw=0.4, color='0.5')
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
        left.plot(*envelope(h, run.gyro_rad_s[:, a] * RAD_TO_DEG), lw=0.4, color='0.6',
                  label='raw')
        left.plot(*envelope(h, processed[:, a] * RAD_TO_DEG), lw=0.4, color='tab:blue',
                  label=label)
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


#: Colour of each class of mode (drift, mixed, noise) in every figure that shows the classes.
CLASS_COLOURS = {'drift': 'tab:red', 'mixed': 'tab:orange', 'noise': 'tab:gray'}


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
        panel.bar(idx, ent, color=[CLASS_COLOURS.get(c, 'tab:blue') for c in classes])
        if freqs.size == ent.size:
            for i, f in zip(idx, freqs):
                panel.annotate(f'{f:.3g} Hz', (i, 0), rotation=90, fontsize=6, ha='center',
                               va='bottom', xytext=(0, 2), textcoords='offset points')
        panel.set_xlabel('IMF (index, by ascending centre frequency)')
        panel.set_ylabel(f'sample entropy, axis {AXES[a]} (nats)')
        panel.set_xticks(idx)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in CLASS_COLOURS.values()]
    panels[0].legend(handles, list(CLASS_COLOURS), fontsize=7)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=100, tight=True)


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


def training_figures(out: Path, run: ThermalRun, processed: NDArray[Any], *, method: str,
                     fit_info: Any) -> Figures:
    """
    Draw the generic figures of a training report (``fit``) into ``out``.

    Parameters
    ----------
    out : pathlib.Path
        The report folder.
    run : ThermalRun
        The training run.
    processed : numpy.ndarray
        The method's output on it (n, 3), rad/s.
    method : str, keyword-only
        The method's name.
    fit_info : object, keyword-only
        The method's ``fit_info`` (its modes' classes draw Fig. 13; anything else: no Fig. 13).

    Returns
    -------
    Figures
        training_fig10_run.png, training_fig18_output.png, training_fig17_drift.png and, when
        the method classes modes, training_fig13_classes.png.

    """
    figs: Figures = [
        ('Temperature and raw output (cf. Fig. 10)',
         plot_run(out / 'training_fig10_run.png', run)),
        ('Raw and processed training output, whole run and a 10-s zoom (cf. Fig. 18)',
         plot_output(out / 'training_fig18_output.png', run, processed, label=method)),
        ('Drift removed on the training data (cf. Fig. 17)',
         plot_drift(out / 'training_fig17_drift.png', run, processed, label=method))]
    fig13 = plot_mode_classes(
        out / 'training_fig13_classes.png', fit_info,
        title=f'{run.name}: sample entropy and class of each mode (training)')
    if fig13 is not None:
        figs.append(('Sample entropy and class of each mode (cf. Fig. 13)', fig13))
    return figs


def apply_figures(out: Path, run: ThermalRun, processed: NDArray[Any], *, method: str,
                  curves: Mapping[str, Any], info: Any, own: Figures) -> Figures:
    """
    Draw the figures of an apply report (``apply``) into ``out``, the method's own among them.

    Parameters
    ----------
    out : pathlib.Path
        The report folder.
    run : ThermalRun
        The run the model was applied to.
    processed : numpy.ndarray
        The method's output (n, 3), rad/s.
    method : str, keyword-only
        The method's name.
    curves : dict, keyword-only
        Per axis the scoring's curves: ``allan_raw``, ``allan_processed`` (tau_s, adev_rad_s),
        ``frequency``, ``step`` and, with the noise-sized injection, ``frequency_small``,
        ``step_small`` (:func:`.metrics.evaluate_method`).
    info : object, keyword-only
        The method's diagnostics of this run (``last_info``: Fig. 13 when it classes modes).
    own : Figures, keyword-only
        The method's own figures, already in ``out`` (:func:`method_figures`).

    Returns
    -------
    Figures
        fig10_run.png, fig13_classes.png (when the method classes modes), ``own``,
        fig18_output.png, fig17_drift.png, fig19_allan.png, bandwidth.png, steps.png.

    """
    figs: Figures = [('Temperature and raw output (cf. Fig. 10)',
                      plot_run(out / 'fig10_run.png', run))]
    fig13 = plot_mode_classes(out / 'fig13_classes.png', info,
                              title=f'{run.name}: sample entropy and class of each mode')
    if fig13 is not None:
        figs.append(('Sample entropy and class of each mode (cf. Fig. 13)', fig13))
    figs.extend(own)
    figs.append(('Raw and processed output, whole run and a 10-s zoom (cf. Fig. 18)',
                 plot_output(out / 'fig18_output.png', run, processed, label=method)))
    figs.append(('Drift removed, 60-s means, against time and temperature (cf. Fig. 17)',
                 plot_drift(out / 'fig17_drift.png', run, processed, label=method)))
    allan = {label: {axis: c[key] for axis, c in curves.items()}
             for label, key in (('raw', 'allan_raw'), (method, 'allan_processed'))}
    figs.append(('Allan deviation raw and processed (cf. Fig. 19)',
                 plot_allan(out / 'fig19_allan.png', allan,
                            title=f'{run.name}: Allan deviation, raw and {method}')))
    responses = {method: {a: c['frequency'] for a, c in curves.items()}}
    steps = {method: {a: c['step'] for a, c in curves.items()}}
    if 'frequency_small' in curves['x']:
        responses[f'{method} small'] = {a: c['frequency_small'] for a, c in curves.items()}
        steps[f'{method} small'] = {a: c['step_small'] for a, c in curves.items()}
    small = responses.pop(f'{method} small', None)
    figs.append(('Response to injected motion (large and noise-sized): gain, phase, group delay',
                 plot_bandwidth(out / 'bandwidth.png', responses,
                                small=None if small is None else {method: small},
                                title=f'{method}: response to an injected chirp')))
    figs.append(('Mean normalised step response (t < 0: before the step)',
                 plot_steps(out / 'steps.png', steps,
                            title=f'{method}: response to injected steps')))
    return figs


def compare_figures(out: Path, test: ThermalRun,
                    curves: Mapping[str, Any]) -> list[tuple[str, Path]]:
    """
    Draw the figures of a held-out comparison (``compare``) into ``out``.

    Parameters
    ----------
    out : pathlib.Path
        The report folder.
    test : ThermalRun
        The test run (its name titles the Allan figure).
    curves : dict
        Per method, per axis the scoring's curves (as :func:`apply_figures`).

    Returns
    -------
    list of (str, pathlib.Path)
        compare_allan.png (every method), compare_bandwidth.png and compare_steps.png (axis x).

    """
    first = next(iter(curves.values()))
    allan = {'raw': {axis: c['allan_raw'] for axis, c in first.items()}}
    for name, cur in curves.items():
        allan[name] = {axis: c['allan_processed'] for axis, c in cur.items()}
    return [
        ('Allan deviation of every method on the test run (cf. Fig. 19)',
         plot_allan(out / 'compare_allan.png', allan,
                    title=f'{test.name}: Allan deviation per method (held out)')),
        ('Response to injected motion, axis x',
         plot_bandwidth(out / 'compare_bandwidth.png',
                        {n: {'x': c['x']['frequency']} for n, c in curves.items()},
                        small={n: {'x': c['x']['frequency_small']}
                               for n, c in curves.items() if 'frequency_small' in c['x']},
                        title='gain (1 deg/s motion solid, noise-sized dashed), phase, '
                              'group delay to an injected chirp (axis x)')),
        ('Mean normalised step response, axis x',
         plot_steps(out / 'compare_steps.png',
                    {n: {'x': c['x']['step']} for n, c in curves.items()},
                    title='response to injected steps (axis x)')),
    ]
