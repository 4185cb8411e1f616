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
(:meth:`ExcitationResult.as_dict`) and, rendered from it and the records by
:mod:`..calibration.excitation_report` and :mod:`..htmlreport.excitation`, ``excitation.md``
(labels and units, percentages, verdicts), ``report.html`` and the figures of paper 001
Figures 7-12.
"""

from collections.abc import Sequence
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
                                      DEFAULT_TOLERANCE, sine_dwell, sine_sweep)
from ..calibration.excitation_report import display_unit, excitation_markdown, plot_excitation
from ..errors import InputDataError, ParameterError
from ..formatting import finite_list, finite_or_none
from ..htmlreport.excitation import write_excitation_html
from ..outputs import atomic_write_text, staged_output, StrPath
from ..units import STANDARD_GRAVITY_M_S2

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
    tolerance : float
        Practical tolerance of each verdict (relative; a significant defect within it is no
        defect: :mod:`..calibration.excitation`).
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
    tolerance: float = DEFAULT_TOLERANCE
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
        if not (math.isfinite(self.tolerance) and 0 <= self.tolerance < 1):
            raise ParameterError(f'--tolerance must be a fraction in [0, 1), got '
                                 f'{self.tolerance!r}')

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
        return display_unit(self.sensor)


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
    return None if a is None else finite_list(a)


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
            'tolerance': p.tolerance,
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
                    'frequency_sigma_hz': finite_or_none(r.frequency_sigma_hz),
                    f'amplitude_{u}': r.amplitude, f'amplitude_sigma_{u}': r.amplitude_sigma,
                    f'offset_{u}': r.offset, f'cycle_amplitude_mean_{u}': r.cycle_amplitude_mean,
                    f'cycle_amplitude_std_{u}': finite_or_none(r.cycle_amplitude_std),
                    f'cycle_amplitude_min_{u}': r.cycle_amplitude_min,
                    f'cycle_amplitude_max_{u}': r.cycle_amplitude_max,
                    'amplitude_stability': finite_or_none(r.amplitude_stability),
                    'amplitude_stability_noise': finite_or_none(r.stability_noise),
                    'stability_p': finite_or_none(r.stability_p), 'steady': bool(r.steady),
                    'thd': r.thd, 'thd_noise': finite_or_none(r.thd_noise),
                    'distortion_p': finite_or_none(r.distortion_p), 'clean': bool(r.clean),
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
                        'mean_deviation': finite_or_none(r.mean_deviation),
                        'mean_deviation_sigma': finite_or_none(r.mean_deviation_sigma),
                        'bin_deviation_sigma': finite_or_none(r.bin_deviation_sigma),
                        'gain_p': finite_or_none(r.gain_p),
                        'matches_reference': r.matches_reference,
                        'flatness_p': finite_or_none(r.flatness_p),
                        'deviation_spread': finite_or_none(r.deviation_spread), 'flat': r.flat})
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
                           frequency_tol=params.frequency_tol, alpha=params.alpha,
                           tolerance=params.tolerance)
        return SideResult(str(path), rate, int(x.size), dwell, t, x)
    ref = None
    if params.reference_topic:
        # both topics share the bag's clock: absolute stamps, reference put on the sensor's
        _, ta, _, _ = records.read_imu(path, topic=params.topic, rate_hz=params.rate_hz,
                                       t0_ns=0)
        _, rt, racc, rgyr = records.read_imu(path, topic=params.reference_topic, t0_ns=0)
        ref = np.interp(ta, rt, _channel(params, racc, rgyr))
    f0, f1, rate_hz_s = params.sweep
    r = sine_sweep(x, rate, f0, f1, rate_hz_s, reference=ref, alpha=params.alpha,
                   tolerance=params.tolerance)
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
    doc = result.as_dict()
    records = {side: (res.t_s, res.x) for side, res in result.sides.items()}
    with staged_output(out_dir) as stage:
        atomic_write_text(stage / 'excitation.json', json.dumps(doc, indent=2) + '\n')
        atomic_write_text(stage / 'excitation.md', excitation_markdown(doc))
        if html:
            write_excitation_html(doc, records, stage, command=command)
            names.append('report.html')
        if result.params.figures:
            for side, (t_s, x) in records.items():
                plot_excitation(stage / f'excitation_{side}.png', doc, side, t_s, x)
                names.append(f'excitation_{side}.png')
    return [os.path.join(str(out_dir), n) for n in names]
