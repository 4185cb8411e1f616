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
The excitation-check workflow (paper 001 section 5.3): one or two records in, one result out.

Shared by ``gyro_noise_excitation`` (and any later report). :func:`run_excitation` reads each
record (before, and optionally after the stress), analyses the excited axis by
:func:`~gyro_noise_ros.calibration.excitation.sine_dwell` or
:func:`~gyro_noise_ros.calibration.excitation.sine_sweep` (with the reference channel when
given), and compares before and after; :func:`write_excitation` writes ``excitation.json``
(:meth:`ExcitationResult.as_dict`), ``excitation.md`` (labels and units, percentages, verdicts)
and the figures of paper 001 Figures 7-12.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
import json
import math
import os
from typing import Any

import numpy as np
from scipy.stats import norm

from .. import __version__
from ..calibration import records
from ..calibration.excitation import (DEFAULT_ALPHA, DEFAULT_FREQUENCY_TOL, DEFAULT_HARMONICS,
                                      sine_dwell, sine_sweep)
from ..errors import InputDataError, ParameterError
from ..htmlreport.excitation import write_excitation_html
from ..outputs import atomic_write_text, staged_output, StrPath
from ..plotting import pyplot, save_figure
from ..units import RAD_TO_DEG, STANDARD_GRAVITY_M_S2

SIDES = ('before', 'after')


@dataclass(frozen=True)
class ExcitationParams:
    """
    What to check and how.

    Attributes
    ----------
    paths : tuple of str
        The record, and optionally the one taken after the stress.
    sensor : str
        ``'accel'`` or ``'gyro'``.
    axis : str
        ``'x'``, ``'y'`` or ``'z'``.
    dwell_hz : float or None
        Sine dwell frequency (Hz); exactly one of ``dwell_hz`` and ``sweep``.
    sweep : tuple of float or None
        ``(f0_hz, f1_hz, rate_hz_s)`` of a sine sweep.
    reference_topic : str or None
        ``sensor_msgs/Imu`` topic of the reference sensor (sweep only).
    topic : str or None
        Topic of the sensor under test.
    harmonics : int
        Harmonics in the THD.
    rate_hz : float or None
        Nominal sample rate (Hz).
    frequency_tol : float
        Largest relative difference between the requested and the measured dwell frequency.
    alpha : float
        False-alarm probability of each verdict.
    figures : bool
        Draw the PNG figures.

    """

    paths: tuple[str, ...]
    sensor: str
    axis: str
    dwell_hz: float | None = None
    # (f0_hz, f1_hz, rate_hz_s) in sweep mode, None in dwell mode: read only where the mode is
    # known, so typed Any rather than Optional
    sweep: Any = None
    reference_topic: str | None = None
    topic: str | None = None
    harmonics: int = DEFAULT_HARMONICS
    rate_hz: float | None = None
    frequency_tol: float = DEFAULT_FREQUENCY_TOL
    alpha: float = DEFAULT_ALPHA
    figures: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, 'paths', tuple(str(p) for p in self.paths))
        if not 1 <= len(self.paths) <= 2:
            raise ParameterError(f'give one recording, or two (before and after); got '
                                 f'{len(self.paths)}')
        if self.sensor not in ('accel', 'gyro') or self.axis not in ('x', 'y', 'z'):
            raise ParameterError(f'--sensor accel|gyro and --axis x|y|z, got {self.sensor!r}, '
                                 f'{self.axis!r}')
        if (self.dwell_hz is None) == (self.sweep is None):
            raise ParameterError('give exactly one of --dwell and --sweep')
        if self.sweep is not None:
            object.__setattr__(self, 'sweep', tuple(float(v) for v in self.sweep))
        if self.harmonics < 1:
            raise ParameterError(f'--harmonics must be >= 1, got {self.harmonics}')
        if self.reference_topic and self.dwell_hz is not None:
            raise ParameterError('--reference-topic applies to --sweep')
        if not (math.isfinite(self.frequency_tol) and 0 < self.frequency_tol < 1):
            raise ParameterError(f'--frequency-tol must be in (0, 1), got '
                                 f'{self.frequency_tol!r}')
        if not (math.isfinite(self.alpha) and 0 < self.alpha < 0.5):
            raise ParameterError(f'--alpha must be in (0, 0.5), got {self.alpha!r}')

    @property
    def mode(self) -> str:
        """str: ``'dwell'`` or ``'sweep'``."""
        return 'dwell' if self.dwell_hz is not None else 'sweep'

    @property
    def unit(self) -> str:
        """str: SI unit suffix of the excited channel (``m_s2`` or ``rad_s``)."""
        return 'm_s2' if self.sensor == 'accel' else 'rad_s'

    @property
    def display(self) -> tuple[float, str]:
        """(float, str): factor from SI to the printed unit and its name (g or deg/s)."""
        return ((1.0 / STANDARD_GRAVITY_M_S2, 'g') if self.sensor == 'accel' else
                (RAD_TO_DEG, 'deg/s'))


@dataclass(frozen=True)
class SideResult:
    """
    The analysis of one record.

    Attributes
    ----------
    source : str
        The record.
    rate_hz : float
        Its sample rate (Hz).
    samples : int
        Samples read.
    analysis : DwellResult or SweepResult
        The numbers.
    t_s, x : numpy.ndarray
        Time (s) and the excited channel (SI), for the figures.

    """

    source: str
    rate_hz: float
    samples: int
    analysis: Any
    t_s: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)


def _lst(a: Any) -> list[float | None] | None:
    return None if a is None else [None if not math.isfinite(float(v)) else float(v)
                                   for v in np.ravel(a)]


def _num(v: Any) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


@dataclass(frozen=True)
class ExcitationResult:
    """
    Everything an excitation check reports (``excitation.json`` is :meth:`as_dict`).

    Attributes
    ----------
    params : ExcitationParams
        What was asked.
    sides : dict
        ``{'before': SideResult, 'after': SideResult}`` (after only with two records).
    version : str
        Package version.

    """

    params: ExcitationParams
    sides: dict[str, SideResult]
    version: str = __version__

    def change(self) -> dict[str, Any] | None:
        """
        Return the after/before changes of a dwell with their significance (None otherwise).

        Returns
        -------
        dict or None

        """
        if self.params.mode != 'dwell' or 'after' not in self.sides:
            return None
        b, a = self.sides['before'].analysis, self.sides['after'].analysis
        rel = a.amplitude / b.amplitude - 1.0
        rel_sig = math.hypot(a.amplitude_sigma / b.amplitude,
                             a.amplitude * b.amplitude_sigma / b.amplitude ** 2)
        p = float(2.0 * norm.sf(abs(rel) / rel_sig)) if rel_sig > 0 else float('nan')
        return {'amplitude_relative': rel, 'amplitude_relative_sigma': rel_sig,
                'amplitude_change_p': p,
                'amplitude_change_significant': bool(p < self.params.alpha),
                'frequency_hz': a.frequency_hz - b.frequency_hz,
                'amplitude_stability': a.amplitude_stability - b.amplitude_stability,
                'thd': a.thd - b.thd}

    def as_dict(self) -> dict[str, Any]:
        """
        Return the ``excitation.json`` document (SI, units in the keys, ratios not %).

        Returns
        -------
        dict

        """
        p = self.params
        u = p.unit
        doc: dict[str, Any] = {
            'sensor': p.sensor, 'axis': p.axis, 'mode': p.mode, 'unit': u, 'alpha': p.alpha,
            'nominal': ({'frequency_hz': p.dwell_hz, 'frequency_tol': p.frequency_tol}
                        if p.mode == 'dwell' else
                        dict(zip(('f0_hz', 'f1_hz', 'rate_hz_s'), p.sweep))),
            'version': self.version}
        for side, res in self.sides.items():
            r = res.analysis
            entry: dict[str, Any] = {'source': res.source, 'rate_hz': res.rate_hz,
                                     'samples': res.samples}
            if p.mode == 'dwell':
                entry.update({
                    'frequency_hz': r.frequency_hz,
                    'frequency_sigma_hz': _num(r.frequency_sigma_hz),
                    f'amplitude_{u}': r.amplitude, f'amplitude_sigma_{u}': r.amplitude_sigma,
                    f'offset_{u}': r.offset, f'cycle_amplitude_mean_{u}': r.cycle_amplitude_mean,
                    f'cycle_amplitude_std_{u}': _num(r.cycle_amplitude_std),
                    f'cycle_amplitude_min_{u}': r.cycle_amplitude_min,
                    f'cycle_amplitude_max_{u}': r.cycle_amplitude_max,
                    'amplitude_stability': _num(r.amplitude_stability),
                    'amplitude_stability_noise': _num(r.stability_noise),
                    'stability_p': _num(r.stability_p), 'steady': bool(r.steady),
                    'thd': r.thd, 'thd_noise': _num(r.thd_noise),
                    'distortion_p': _num(r.distortion_p), 'clean': bool(r.clean),
                    f'harmonics_{u}': _lst(r.harmonics), f'residual_rms_{u}': r.residual_rms,
                    'start_s': r.start_s, 'duration_s': r.duration_s, 'cycles': r.cycles})
                if p.sensor == 'accel':
                    entry['amplitude_g'] = r.amplitude / STANDARD_GRAVITY_M_S2
            else:
                entry.update({'bin_hz': _lst(r.bin_hz), f'amplitude_up_{u}': _lst(r.amplitude_up),
                              f'amplitude_down_{u}': _lst(r.amplitude_down),
                              'frequency_range_hz': _lst(r.frequency_range_hz)})
                if r.reference_up is not None:
                    dev = np.concatenate([r.deviation_up, r.deviation_down])
                    dev = dev[np.isfinite(dev)]
                    entry.update({
                        f'reference_up_{u}': _lst(r.reference_up),
                        f'reference_down_{u}': _lst(r.reference_down),
                        'deviation_up': _lst(r.deviation_up),
                        'deviation_down': _lst(r.deviation_down),
                        'max_abs_deviation': float(np.max(np.abs(dev))) if dev.size else None,
                        'mean_deviation': _num(r.mean_deviation),
                        'mean_deviation_sigma': _num(r.mean_deviation_sigma),
                        'bin_deviation_sigma': _num(r.bin_deviation_sigma),
                        'gain_p': _num(r.gain_p), 'matches_reference': r.matches_reference,
                        'flatness_p': _num(r.flatness_p), 'flat': r.flat})
            doc[side] = entry
        change = self.change()
        if change is not None:
            doc['change'] = change
        return doc


def _channel(params: ExcitationParams, accel: np.ndarray, gyro: np.ndarray) -> np.ndarray:
    i = 'xyz'.index(params.axis)
    return (accel if params.sensor == 'accel' else gyro)[:, i]


def _analyse(path: str, params: ExcitationParams) -> SideResult:
    try:
        rate, t, accel, gyro = records.read_imu(path, topic=params.topic, rate_hz=params.rate_hz)
    except IndexError as err:
        raise InputDataError(f'recording {path!r} holds no Imu samples') from err
    x = _channel(params, accel, gyro)
    if params.mode == 'dwell':
        assert params.dwell_hz is not None  # dwell mode: required by the parameters
        dwell = sine_dwell(x, rate, params.dwell_hz, harmonics=params.harmonics,
                           frequency_tol=params.frequency_tol, alpha=params.alpha)
        return SideResult(str(path), rate, int(x.size), dwell, t, x)
    ref = None
    if params.reference_topic:
        # both topics share the bag's clock: absolute stamps, reference put on the sensor's
        _, ta, _, _ = records.read_imu(path, topic=params.topic, rate_hz=params.rate_hz,
                                       t0_ns=0)
        _, rt, racc, rgyr = records.read_imu(path, topic=params.reference_topic, t0_ns=0)
        ref = np.interp(ta, rt, _channel(params, racc, rgyr))
    f0, f1, rate_hz_s = params.sweep
    r = sine_sweep(x, rate, f0, f1, rate_hz_s, reference=ref, alpha=params.alpha)
    return SideResult(str(path), rate, int(x.size), r, t, x)


def run_excitation(params: ExcitationParams) -> ExcitationResult:
    """
    Analyse the record(s) (module docstring).

    Parameters
    ----------
    params : ExcitationParams
        What to check.

    Returns
    -------
    ExcitationResult

    Raises
    ------
    InputDataError
        NaN/Inf, too few cycles, no sine, a record that is not the excitation asked for.
    BagError
        A recording cannot be read.

    """
    sides: dict[str, SideResult] = {}
    for side, path in zip(SIDES, params.paths):
        try:
            sides[side] = _analyse(path, params)
        except InputDataError as err:
            raise err.prefixed(f'{side} record {path!r}: ') from err
    return ExcitationResult(params, sides)


def _pct(v: float | None, spec: str = '.3f') -> str:
    return 'n/a' if v is None or not math.isfinite(v) else f'{format(100.0 * v, spec)} %'


def _significance(change: dict[str, Any]) -> str:
    return 'significant' if change['amplitude_change_significant'] else 'within noise'


def _verdict(ok: bool | None, yes: str, no: str, p: float) -> str:
    if ok is None:
        return 'n/a'
    return f'{yes if ok else no} (p = {p:.2g})'


def markdown(result: ExcitationResult) -> str:
    """
    Return ``excitation.md``: quantities with units, percentages and verdicts.

    Parameters
    ----------
    result : ExcitationResult
        The check.

    Returns
    -------
    str

    """
    p = result.params
    k, unit = p.display
    sides = list(result.sides)
    what = (f'sine dwell at {p.dwell_hz:g} Hz' if p.mode == 'dwell' else
            f'sine sweep {p.sweep[0]:g}-{p.sweep[1]:g} Hz at {p.sweep[2]:g} Hz/s')
    out = [f'# Excitation check: {what}, {p.sensor} {p.axis} (paper 001 section 5.3)', '',
           "Verdicts are statistical tests against each record's own noise, false-alarm "
           f'probability {p.alpha:g} each (docs/reliability.md).', '',
           '| quantity | ' + ' | '.join(sides) + ' |', '|---|' + '---|' * len(sides)]

    def row(label: str, fn: Callable[[Any], str]) -> None:
        out.append(f'| {label} | ' + ' | '.join(fn(result.sides[s].analysis) for s in sides)
                   + ' |')

    row('record', lambda r: '')
    out.pop()
    out.append('| record | ' + ' | '.join(result.sides[s].source for s in sides) + ' |')
    if p.mode == 'dwell':
        row('frequency (Hz)', lambda r: f'{r.frequency_hz:.5f} +/- {r.frequency_sigma_hz:.1e}')
        row(f'amplitude ({unit})', lambda r: f'{r.amplitude * k:.5g} +/- '
            f'{r.amplitude_sigma * k:.2g}')
        row(f'offset ({unit})', lambda r: f'{r.offset * k:.5g}')
        row(f'per-cycle amplitude mean / min / max ({unit})',
            lambda r: f'{r.cycle_amplitude_mean * k:.5g} / {r.cycle_amplitude_min * k:.5g} / '
                      f'{r.cycle_amplitude_max * k:.5g}')
        row('amplitude stability (std / mean of the cycles)',
            lambda r: _pct(r.amplitude_stability))
        row('stability from noise alone', lambda r: _pct(r.stability_noise))
        row('stability verdict', lambda r: _verdict(r.steady, 'steady', 'UNSTEADY',
                                                    r.stability_p))
        row('THD (harmonics 2..H over the fundamental)', lambda r: _pct(r.thd))
        row('THD from noise alone', lambda r: _pct(r.thd_noise))
        row('distortion verdict', lambda r: _verdict(r.clean, 'clean', 'DISTORTED',
                                                     r.distortion_p))
        row('harmonics 2..H (of the fundamental)',
            lambda r: ', '.join(_pct(h / r.harmonics[0], '.3f') for h in r.harmonics[1:])
            or 'none below Nyquist')
        row('excited span analysed (s)', lambda r: f'{r.start_s:.2f} + {r.duration_s:.2f} '
            f'({r.cycles} cycles)')
        change = result.change()
        if change:
            out += ['', '## After / before', '',
                    f'- amplitude: {_pct(change["amplitude_relative"])} +/- '
                    f'{_pct(change["amplitude_relative_sigma"])} '
                    f'({_significance(change)}, p = {change["amplitude_change_p"]:.2g})',
                    f'- frequency: {change["frequency_hz"]:+.5f} Hz',
                    f'- amplitude stability: {100 * change["amplitude_stability"]:+.3f} '
                    f'percentage points',
                    f'- THD: {100 * change["thd"]:+.3f} percentage points']
        return '\n'.join(out) + '\n'
    row('frequency covered, 5th-95th percentile (Hz)',
        lambda r: f'{r.frequency_range_hz[0]:.3f} - {r.frequency_range_hz[1]:.3f}')
    row('mean deviation from the reference', lambda r: (
        'no reference' if r.reference_up is None else
        f'{_pct(r.mean_deviation)} +/- {_pct(r.mean_deviation_sigma)}'))
    row('gain verdict', lambda r: _verdict(r.matches_reference, 'matches the reference',
                                           'GAIN DIFFERS', r.gain_p))
    row('deviation noise per bin', lambda r: _pct(r.bin_deviation_sigma))
    row('flatness verdict', lambda r: _verdict(r.flat, 'flat', 'FREQUENCY-DEPENDENT',
                                               r.flatness_p))
    for s in sides:
        r = result.sides[s].analysis
        out += ['', f'## {s}: amplitude per frequency bin ({unit})', '',
                '| f (Hz) | rising | falling | reference rising | reference falling | '
                'deviation rising | deviation falling |', '|---|---|---|---|---|---|---|']

        def cell(arr: np.ndarray | None, i: int, scale: float = k) -> str:
            if arr is None or not math.isfinite(arr[i]):
                return 'n/a'
            return f'{arr[i] * scale:.5g}'

        for i, f in enumerate(r.bin_hz):
            out.append(f'| {f:.3f} | {cell(r.amplitude_up, i)} | {cell(r.amplitude_down, i)} | '
                       f'{cell(r.reference_up, i)} | {cell(r.reference_down, i)} | '
                       f'{_pct(None if r.deviation_up is None else r.deviation_up[i])} | '
                       f'{_pct(None if r.deviation_down is None else r.deviation_down[i])} |')
    return '\n'.join(out) + '\n'


def plot(path: StrPath, params: ExcitationParams, label: str, side: SideResult) -> None:
    """
    Draw the whole acquisition and the waveform detail (paper 001 Figures 7-12).

    Parameters
    ----------
    path : path
        PNG file.
    params : ExcitationParams
        What was asked.
    label : str
        'before' or 'after'.
    side : SideResult
        The record and its analysis.

    """
    plt = pyplot()
    scale, unit = params.display
    t, x, result = side.t_s, side.x, side.analysis
    fig, (pa, pb) = plt.subplots(1, 2, figsize=(11, 4.2))
    pa.plot(t, x * scale, lw=0.5)
    pa.set_xlabel('time (s)')
    pa.set_ylabel(f'{params.sensor} {params.axis} ({unit})')
    pa.set_title(f'(a) whole acquisition, {label}')
    if params.mode == 'dwell':
        lo = int(result.start_s * side.rate_hz)
        n = int(4 * side.rate_hz / result.frequency_hz)
        pb.plot(t[lo:lo + n], x[lo:lo + n] * scale, '.-', lw=0.8, ms=3)
        pb.set_xlabel('time (s)')
        pb.set_title(f'(b) wave form: {result.frequency_hz:.3f} Hz, amplitude '
                     f'{result.amplitude * scale:.4g} {unit}, THD {100 * result.thd:.2f} %',
                     fontsize=9)
    else:
        pb.plot(result.bin_hz, result.amplitude_up * scale, 'o-', label='rising frequency')
        pb.plot(result.bin_hz, result.amplitude_down * scale, 's-', label='falling frequency')
        if result.reference_up is not None:
            pb.plot(result.bin_hz, result.reference_up * scale, 'k--', lw=1, label='reference')
        pb.set_xlabel('instantaneous frequency (Hz)')
        pb.set_ylabel(f'amplitude ({unit})')
        pb.set_title('(b) amplitude against frequency', fontsize=9)
        pb.legend(fontsize=8)
    for panel in (pa, pb):
        panel.grid(True, alpha=0.3)
    save_figure(fig, path, dpi=110, tight=True)


def write_excitation(result: ExcitationResult, out_dir: StrPath, *, html: bool = True,
                     command: Sequence[str] | None = None) -> list[str]:
    """
    Write excitation.json, .md, report.html and the figures (published together or not at all).

    Parameters
    ----------
    result : ExcitationResult
        The check.
    out_dir : str or os.PathLike
        Output folder (created).
    html : bool, keyword-only
        Write report.html (:mod:`..htmlreport.excitation`).
    command : sequence of str, optional, keyword-only
        The command line, shown on report.html.

    Returns
    -------
    list of str
        The files written.

    """
    names = ['excitation.json', 'excitation.md']
    with staged_output(out_dir) as stage:
        atomic_write_text(stage / 'excitation.json',
                          json.dumps(result.as_dict(), indent=2) + '\n')
        atomic_write_text(stage / 'excitation.md', markdown(result))
        if html:
            write_excitation_html(result, stage, command=command)
            names.append('report.html')
        if result.params.figures:
            for side, res in result.sides.items():
                plot(stage / f'excitation_{side}.png', result.params, side, res)
                names.append(f'excitation_{side}.png')
    return [os.path.join(str(out_dir), n) for n in names]
