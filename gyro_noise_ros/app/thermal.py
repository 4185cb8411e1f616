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
The thermal workflows of ``gyro_noise_thermal``: fit, apply, compare, simulate, export.

Each is a function of explicit keyword parameters returning a frozen result object
(:class:`FitResult`, :class:`ApplyResult`, :class:`CompareResult`, :class:`SimulateResult`,
:class:`ExportResult`) whose ``as_dict()`` is exactly what the tool writes as JSON, plus a
``write_*(result, out_dir)`` that writes every file through
:func:`~gyro_noise_ros.outputs.staged_output` (an interrupted or failed run leaves no file under
its final name, no ``model.json`` that looks finished). The command line
(:mod:`gyro_noise_ros.cli.thermal`) only parses options, calls one workflow, prints and returns
the exit code. Definitions of every number: ``docs/thermal.md``.
"""

from collections.abc import Callable, Sequence
import copy
from dataclasses import dataclass, field, replace
import json
import math
from pathlib import Path
import tempfile
import time
from typing import Any, cast

import numpy as np

from .. import __version__
from ..errors import ClusterError, GyroNoiseError, InputDataError, ParameterError
from ..formatting import finite_or_none as _num
from ..htmlreport.thermal import write_apply_html, write_compare_html
from ..outputs import staged_output, StrPath
from ..thermal import methods as registry
from ..thermal.bag_io import (DEFAULT_MAX_GAP_S, join_runs, read_thermal_run,
                              write_compensated)
from ..thermal.figures import (apply_figures, compare_figures, Figures, method_figures,
                               training_figures)
from ..thermal.metrics import (DEFAULT_AMPLITUDE_RAD_S, DEFAULT_F_HI_HZ, DEFAULT_F_LO_HZ,
                               evaluate_method, noise_metrics, residual_drift,
                               residual_drift_deg_s, yardstick)
# bandwidth_cell, COMPARE_HEADER, COMPARE_SPECS and table_cells are handed on for the command line
from ..thermal.report import (apply_markdown, bandwidth_cell, compare_csv, COMPARE_HEADER,
                              compare_markdown, compare_rows, COMPARE_SPECS, table_cells,
                              training_markdown)
from ..thermal.run import check_temperature_readings, DEFAULT_RATE_WINDOW_S, temperature_rate_c_s
from ..units import RAD_TO_DEG, STANDARD_GRAVITY_M_S2

__all__ = ['ApplyResult', 'BagOptions', 'COMPARE_HEADER', 'COMPARE_SPECS', 'CompareResult',
           'DEFINITIONS', 'ExportResult', 'FitResult', 'ScoreOptions', 'SimulateResult',
           'apply_model', 'bandwidth_cell', 'check_method_names', 'compare', 'export', 'fit',
           'oracle_scores', 'simulate', 'split_run', 'table_cells', 'write_apply',
           'write_compare', 'write_export', 'write_fit', 'write_simulate']

PROG = 'gyro_noise_thermal'
#: A method's own figures, drawn before the output folder exists: (caption, file name or None,
#: PNG bytes or None).
_MethodFigures = tuple[tuple[str, str | None, bytes | None], ...]

#: Definitions written into metrics.json and the reports (docs/thermal.md says the same).
DEFINITIONS = {
    'arw_deg_sqrt_h': 'angle random walk: the slope -1/2 line fitted to the overlapping Allan '
                      'deviation over tau 0.32..3.2 s, read at tau = 1 s (IEEE 952)',
    'arw_slope': 'free log-log slope of the Allan deviation over the same taus (-0.5 = white)',
    'bias_stability_deg_h': 'minimum of the Allan deviation (not divided by 0.664), as '
                            'datasheets and paper 002 Figure 19 quote it; an upper bound '
                            '(tables: <=) when bias_stability_upper_bound, the curve not seen '
                            'to turn up',
    'noise_path': 'white noise the size of the run noise (fixed seed) added to the run; '
                  'arw_gain is the ARW of the response of the method to it (output with minus '
                  'output without) over the ARW of that noise: the arw_ratio of the verdict, 1 '
                  'for any drift model, free of the drift that leaks into the ADEV of the output',
    'residual_drift_deg_s': 'standard deviation (ddof 1) of the means of consecutive 60-s windows',
    'minus_3db_hz': 'first frequency where the gain to injected motion falls below 1/sqrt(2) '
                    '(bound: measured / below / above the measured band)',
    'step_precursor': 'largest change of the step response in the last fifth of the window '
                      'before the step (> 0.05: non-causal)',
    'step_lead_s': 'how long before a step the response first moves by more than 5 % of it: '
                   'the look-ahead of a non-causal method, the latency a causal version of it '
                   'would add',
    'bandwidth_small_signal': 'the same injection scaled to the white-noise sigma of the run '
                              '(std of first differences / sqrt 2): what a nonlinear method '
                              'does to motion the size of the noise',
    'arw_from_bandwidth': 'ARW down by more than 10 % while motion at 0.1-1 Hz (large or '
                          'noise-sized) or a held step passes with gain below 0.9',
    'range': 'samples of the run outside the trained range of T and of dT (the causal 10-s '
             'slope, start-up backfilled), and what the method does there',
    'yardstick': 'residual drift per axis over the noise floor (floor: "noise", the test run\'s '
                 'own noise, for bags of gyro_noise_thermal simulate; "white", the white noise '
                 'of its size, a lower bound, otherwise) and over the residual drift of poly3 '
                 '(the form PX4 and ArduPilot evaluate) on the same run: 0.2 is five times '
                 'better than poly3',
}


@dataclass(frozen=True)
class BagOptions:
    """
    How a recording is read (``--topic``, ``--temperature-topic``, ``--max-gap-s``).

    Attributes
    ----------
    topic : str or None
        sensor_msgs/Imu topic (None: the single one).
    temperature_topic : str or None
        sensor_msgs/Temperature topic (None: the single one, or the Imu topic's namespace's).
    max_gap_s : float
        Longest accepted hole in the temperature stream (s).

    """

    topic: str | None = None
    temperature_topic: str | None = None
    max_gap_s: float = DEFAULT_MAX_GAP_S

    def read(self, path: StrPath) -> tuple[Any, Any]:
        """Read one bag: ``(ThermalRun, ThermalBag)``."""
        return read_thermal_run(path, topic=self.topic, temperature_topic=self.temperature_topic,
                                max_gap_s=self.max_gap_s)


@dataclass(frozen=True)
class ScoreOptions:
    """
    How a processed run is scored (``apply`` and ``compare``).

    Attributes
    ----------
    amplitude_deg_s : float
        Height of the injected chirp and steps (deg/s).
    f_lo_hz, f_hi_hz : float
        Band of the injected chirp (Hz).
    small_signal : bool
        Repeat the injection at the size of the noise.
    range_margin_c : float
        Refuse test temperatures further than this outside the trained range (degC; inf off).
    strict : bool
        ``apply`` refuses (exit code 4) a run more than ``methods.MAX_OUTSIDE_SHARE`` of which
        lies outside the trained range of T or dT (without it: a warning).
    max_offset_deg_s : float
        ``apply`` refuses a run whose gyro sits further than this from the model's drift on an
        axis: a model of another sensor (deg/s; inf off; ``methods.check_same_sensor``).

    """

    amplitude_deg_s: float = DEFAULT_AMPLITUDE_RAD_S * RAD_TO_DEG
    f_lo_hz: float = DEFAULT_F_LO_HZ
    f_hi_hz: float = DEFAULT_F_HI_HZ
    small_signal: bool = True
    range_margin_c: float = registry.DEFAULT_RANGE_MARGIN_C
    strict: bool = False
    max_offset_deg_s: float = registry.MAX_SENSOR_OFFSET_DEG_S


def _json(doc: dict[str, Any]) -> str:
    return json.dumps(registry.to_jsonable(doc), indent=1, allow_nan=False) + '\n'


def _write(path: StrPath, text: str) -> Path:
    Path(path).write_text(text)
    return Path(path)


def _residual_drift(x: Any, rate_hz: float) -> list[float | None]:
    """Std (ddof 1) of consecutive 60-s window means per axis, in x's unit (None if < 2)."""
    return [_num(v) for v in residual_drift(x, rate_hz)]


def _read_runs(paths: Sequence[str], options: BagOptions) -> tuple[list[Any], list[Any]]:
    runs: list[Any] = []
    bags: list[Any] = []
    for path in paths:
        run, bag = options.read(path)
        runs.append(run)
        bags.append(bag)
    return runs, bags


def _join(runs: list[Any]) -> Any:
    # The gap keeps the trailing temperature-rate window from straddling two recordings.
    return join_runs(runs, gap_s=DEFAULT_RATE_WINDOW_S + 1.0 / runs[0].rate_hz)


def _method_figures(method: Any, run: Any) -> _MethodFigures:
    """Draw the method's own figures now (its last apply is ``run``); keep them in memory."""
    with tempfile.TemporaryDirectory(prefix='gyro_noise_thermal_') as tmp:
        out = []
        for name, caption in method_figures(method, run, Path(tmp)):
            data = None if name is None else (Path(tmp) / name).read_bytes()
            out.append((caption, name, data))
    return tuple(out)


def _put_method_figures(figures: _MethodFigures, out: Path) -> Figures:
    """Write in-memory method figures into ``out``; return (caption, path or None) entries."""
    entries: Figures = []
    for caption, name, data in figures:
        if name is None:
            entries.append((caption, None))
            continue
        path = out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(cast(bytes, data))  # a figure with a name has its bytes
        entries.append((caption, path))
    return entries


def _executor(scheduler: str | None, names: Sequence[str],
              warn: Callable[[str], None] | None) -> Any:
    """Connect to a Dask scheduler (None without one); say so when no method distributes."""
    if scheduler is None:
        return None
    from ..cluster import make_executor

    def distributes(name: str) -> bool:
        try:
            return hasattr(registry.method_class(name), 'executor')
        except GyroNoiseError:  # reported by the fit itself
            return True

    pool = make_executor(1, scheduler, warn=warn)
    if warn is not None and not any(distributes(n) for n in names):
        warn(f'--scheduler: {", ".join(names)} has no work units to distribute (only the '
             'parallel model does); it runs here')
    return pool


def _fit_model(name: str, run: Any, *, seed: int, sources: Sequence[str],
               executor: Any = None) -> Any:
    return registry.fit_method(name, run, rng=np.random.default_rng(seed), sources=sources,
                               executor=executor)


def _in_sample(run: Any, processed: np.ndarray) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for a, axis in enumerate('xyz'):
        raw_m = noise_metrics(run.gyro_rad_s[:, a], run.rate_hz)
        proc_m = noise_metrics(processed[:, a], run.rate_hz)
        out[axis] = {'raw_residual_drift_deg_s': _num(raw_m.residual_drift_deg_s),
                     'processed_residual_drift_deg_s': _num(proc_m.residual_drift_deg_s),
                     'raw_arw_deg_sqrt_h': _num(raw_m.arw_deg_sqrt_h),
                     'processed_arw_deg_sqrt_h': _num(proc_m.arw_deg_sqrt_h)}
    return out


def _accel_block(accel_poly: Any, run: Any, processed_accel: np.ndarray) -> dict[str, Any]:
    """Per-axis residual drift (60-s means) of the accelerometer, raw and processed (mg)."""
    mg = 1e3 / STANDARD_GRAVITY_M_S2
    raw = _residual_drift(run.accel_m_s2, run.rate_hz)
    proc = _residual_drift(processed_accel, run.rate_hz)
    return {'method': 'poly3 (relative to T_ref)', 't_ref_c': accel_poly.t_ref_c,
            'axes': {axis: {'raw_residual_drift_mg': None if r is None else r * mg,
                            'processed_residual_drift_mg': None if p is None else p * mg}
                     for axis, r, p in zip('xyz', raw, proc)}}


def _rate(run: Any, method: Any) -> np.ndarray:
    window = float(getattr(method, 'rate_window_s', DEFAULT_RATE_WINDOW_S))
    return temperature_rate_c_s(run.t_s, run.temperature_c, window_s=window, start='nan')


def _range(model: Any, run: Any) -> Any:
    method = model.method
    return registry.range_report(model.training, run.temperature_c, _rate(run, method),
                                 treatment=getattr(method, 'out_of_range',
                                                   'not stated by the method'),
                                 uses_temperature=getattr(method, 'uses_temperature', True),
                                 uses_rate=getattr(method, 'uses_rate', True))


# ---------------------------------------------------------------------------------------------
# fit


@dataclass(frozen=True)
class FitResult:
    """
    A fitted model, what it was trained on and its in-sample numbers.

    Attributes
    ----------
    model : ThermalModel
        The fitted method, its accelerometer polynomial and its training summary.
    run : ThermalRun
        The (joined) training data.
    bags : tuple of dict
        Per recording: path, topics, samples, rate.
    processed : numpy.ndarray
        ``method.apply(run)`` (n, 3), rad/s.
    fit_time_s : float
        Wall time of the fit (s).
    seed : int
        Seed of the fit.
    in_sample : dict
        Per axis raw and processed residual drift and ARW (in-sample: flattering).
    accel : dict or None
        The accelerometer's in-sample residual drift, raw and compensated (mg).
    method_figures : tuple
        (caption, file name or None, PNG bytes or None) of the method's own figures.
    command : tuple of str
        The command line, for the record.
    input_notes : tuple of str
        What reading the bags noticed (implausible temperatures dropped).
    warnings : tuple of str
        What reading the bags changed and calls for a look (a temperature in kelvin, converted).

    """

    model: Any
    run: Any
    bags: tuple[dict[str, Any], ...]
    processed: np.ndarray
    fit_time_s: float
    seed: int
    in_sample: dict[str, Any]
    accel: dict[str, Any] | None
    method_figures: _MethodFigures = ()
    command: tuple[str, ...] = ()
    input_notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def notes(self) -> tuple[str, ...]:
        """Return the bags' notes, then the fit's (e.g. a method fitted without its dT term)."""
        return self.input_notes + tuple(self.model.notes)

    def model_dict(self) -> dict[str, Any]:
        """
        Return the model.json document.

        Returns
        -------
        dict

        """
        return registry.model_document(self.model.method, training=self.model.training,
                                       accel=self.model.accel, autopilot=self.model.autopilot)

    def as_dict(self) -> dict[str, Any]:
        """
        Return training.json.

        Returns
        -------
        dict

        """
        m = self.model
        return registry.to_jsonable({
            'tool': f'{PROG} fit', 'package_version': __version__,
            'command': [PROG, *self.command], 'method': m.method.name,
            'causal': bool(m.method.causal), 'seed': self.seed, 'fit_time_s': self.fit_time_s,
            'training': m.training.as_dict(), 'bags': list(self.bags),
            'in_sample': self.in_sample, 'accel': self.accel, 'notes': list(self.notes),
            'warnings': list(self.warnings),
            'terms': list(getattr(m.method, 'terms', None) or []) or None,
            'out_of_range': getattr(m.method, 'out_of_range', None),
            'note': 'in-sample numbers (the training data itself): they flatter every method; '
                    'score on another run with apply or compare'})


def fit(*, bags: Sequence[str], method: str = registry.DEFAULT_METHOD, seed: int = 0,
        min_range_c: float = registry.DEFAULT_MIN_RANGE_C, bag_options: BagOptions = BagOptions(),
        accel: bool = True, scheduler: str | None = None,
        warn: Callable[[str], None] | None = None, figures: bool = True,
        command: Sequence[str] = ()) -> FitResult:
    """
    Fit one method on one or more recordings (``gyro_noise_thermal fit``).

    Parameters
    ----------
    bags : sequence of str
        Training recordings (joined end to end, a rate window apart).
    method : str, keyword-only
        ``--method`` name.
    seed : int, keyword-only
        Seed of stochastic training.
    min_range_c : float, keyword-only
        Smallest training temperature span (degC, finite, >= 0).
    bag_options : BagOptions, keyword-only
        Topics and gap limit.
    accel : bool, keyword-only
        Also fit the accelerometer's polynomial when the bags carry accelerometer data.
    scheduler : str, optional, keyword-only
        Dask scheduler for the parallel model's MOPSO particles.
    warn : callable, optional, keyword-only
        Called with one line of text for warnings.
    figures : bool, keyword-only
        Draw the method's own figures (kept in the result).
    command : sequence of str, keyword-only
        The command line, recorded.

    Returns
    -------
    FitResult

    """
    min_range_c = registry.check_min_range(min_range_c)
    registry.method_class(method)   # an unknown name fails before the bags are read
    runs, infos = _read_runs(bags, bag_options)
    run = _join(runs)
    registry.check_trainable(run, min_range_c=min_range_c, method=method)
    pool = _executor(scheduler, [method], warn)
    try:
        started = time.monotonic()
        model = registry.fit_method(method, run, rng=np.random.default_rng(seed),
                                    sources=[str(b.path) for b in infos], executor=pool,
                                    accel=accel)
        fit_s = time.monotonic() - started
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    processed = np.asarray(model.method.apply(run), dtype=float)
    method_figs = _method_figures(model.method, run) if figures else ()
    accel_doc = None
    if model.accel is not None:
        processed_accel = run.accel_m_s2 - model.accel.drift_rad_s(run.temperature_c, 0.0)
        accel_doc = _accel_block(model.accel, run, processed_accel)
    bag_docs = tuple({'path': str(b.path), 'topic': b.topic,
                      'temperature_topic': b.temperature_topic, 'samples': int(r.t_s.size),
                      'rate_hz': r.rate_hz, 'accelerometer': r.accel_m_s2 is not None,
                      'temperature_readings': b.temperature_samples,
                      'temperature_dropped': b.temperature_dropped,
                      'temperature_period_s': b.temperature_period_s}
                     for b, r in zip(infos, runs))
    return FitResult(model=model, run=run, bags=bag_docs, processed=processed,
                     fit_time_s=fit_s, seed=int(seed), in_sample=_in_sample(run, processed),
                     accel=accel_doc, method_figures=method_figs, command=tuple(command),
                     input_notes=tuple(n for b in infos for n in b.notes),
                     warnings=tuple(w for b in infos for w in b.warnings))


def write_fit(result: FitResult, out_dir: StrPath, *, figures: bool = True) -> list[Path]:
    """
    Write model.json, training.json, training.md and the figures (staged).

    Parameters
    ----------
    result : FitResult
        From :func:`fit`.
    out_dir : str or os.PathLike
        The ``--out`` folder.
    figures : bool, keyword-only
        Write PNG figures.

    Returns
    -------
    list of pathlib.Path
        The files, under their final names.

    """
    doc = result.as_dict()
    method = result.model.method
    with staged_output(out_dir) as stage:
        files = [_write(stage / 'model.json', json.dumps(result.model_dict(), indent=1,
                                                         allow_nan=False) + '\n')]
        figs: Figures = []
        if figures:
            figs = training_figures(stage, result.run, result.processed, method=method.name,
                                    fit_info=getattr(method, 'fit_info', None))
            figs.extend(_put_method_figures(result.method_figures, stage))
        files.append(_write(stage / 'training.json', _json(doc)))
        files.append(_write(stage / 'training.md', training_markdown(doc, figs, stage)))
        files.extend(p for _, p in figs if p is not None)
        names = [p.relative_to(stage) for p in files]
    return [Path(out_dir) / n for n in names]


# ---------------------------------------------------------------------------------------------
# apply


def _check_injection_length(run: Any, score: ScoreOptions) -> None:
    """Refuse a run too short for the injected chirp: unusable input (exit 4), one line."""
    duration = float(run.t_s.size / run.rate_hz)
    # metrics.make_injection: the chirp takes at most 30 % of the run and needs 20 periods of
    # f_lo
    if 0.3 * duration * score.f_lo_hz < 20.0:
        need = 20.0 / score.f_lo_hz / 0.3
        raise InputDataError(f'run {run.name!r} is {duration:.4g} s long; measuring the response '
                             f'down to {score.f_lo_hz:g} Hz needs {need:.4g} s (raise --f-lo-hz '
                             'to score a shorter run)')


def _score(method: Any, run: Any, score: ScoreOptions, processed: np.ndarray) -> Any:
    return evaluate_method(method, run, amplitude_rad_s=score.amplitude_deg_s / RAD_TO_DEG,
                           f_lo_hz=score.f_lo_hz, f_hi_hz=score.f_hi_hz, processed=processed,
                           small_signal=score.small_signal)


@dataclass(frozen=True)
class ApplyResult:
    """
    A model applied to one recording, scored.

    Attributes
    ----------
    doc : dict
        metrics.json (see :meth:`as_dict`).
    run : ThermalRun
        The recording.
    bag : ThermalBag
        Where it came from (to write the compensated copy).
    processed : numpy.ndarray
        Processed gyro (n, 3), rad/s.
    processed_accel : numpy.ndarray or None
        Compensated accelerometer (n, 3), m/s^2 (None without an accelerometer model or data).
    curves : dict
        Per-axis responses and Allan curves, for the figures.
    info : object
        The method's own diagnostics of this run (``last_info``), for the figures.
    method_figures : tuple
        (caption, file name or None, PNG bytes or None).
    notes : tuple of str
        What the run and the model noticed (model from another package version, temperature
        readings dropped, how much of the run lies outside the trained range).
    warnings : tuple of str
        What calls for a look before trusting the output (more than
        ``methods.MAX_OUTSIDE_SHARE`` outside the trained range).

    """

    doc: dict[str, Any]
    run: Any
    bag: Any
    processed: np.ndarray
    processed_accel: np.ndarray | None
    curves: dict[str, Any]
    info: Any = None
    method_figures: _MethodFigures = ()
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """
        Return metrics.json.

        Returns
        -------
        dict

        """
        return self.doc


def apply_model(*, bag: str, model_path: str, bag_options: BagOptions = BagOptions(),
                score: ScoreOptions = ScoreOptions(), figures: bool = True,
                command: Sequence[str] = ()) -> ApplyResult:
    """
    Apply a model.json to a recording and score it (``gyro_noise_thermal apply``).

    Parameters
    ----------
    bag : str
        The recording (held out from training).
    model_path : str
        model.json of ``fit``.
    bag_options : BagOptions, keyword-only
        Topics and gap limit.
    score : ScoreOptions, keyword-only
        Injection and range margin.
    figures : bool, keyword-only
        Draw the method's own figures now (kept in the result).
    command : sequence of str, keyword-only
        The command line, recorded.

    Returns
    -------
    ApplyResult

    """
    model = registry.load_model(model_path)
    run, info_bag = bag_options.read(bag)
    t_lo, t_hi = registry.check_temperature_range(model, run.temperature_c,
                                                  margin_c=score.range_margin_c)
    _check_injection_length(run, score)
    rng, offsets, warnings = _apply_checks(model, run, score)
    warnings = list(info_bag.warnings) + warnings
    started = time.monotonic()
    processed = np.asarray(model.method.apply(run), dtype=float)
    apply_s = time.monotonic() - started
    # the scoring applies the method again to injected runs; keep this run's diagnostics, and
    # draw the method's own figures now, while its last apply is this run (no second VMD)
    info = copy.deepcopy(getattr(model.method, 'last_info', None))
    method_figs = _method_figures(model.method, run) if figures else ()
    scored, processed, curves = _score(model.method, run, score, processed)
    sources = {str(Path(s).resolve()) for s in model.training.sources}
    in_sample = (str(info_bag.path) in model.training.sources
                 or str(Path(bag).resolve()) in sources)
    processed_accel, accel_doc = None, None
    if model.accel is not None and run.accel_m_s2 is not None:
        processed_accel = run.accel_m_s2 - model.accel.drift_rad_s(run.temperature_c, 0.0)
        accel_doc = _accel_block(model.accel, run, processed_accel)
        accel_doc['out_of_range'] = model.accel.out_of_range
    notes = list(model.notes) + list(info_bag.notes)
    if rng.outside:
        notes.append(f'{rng.text()}')
    doc = {'tool': f'{PROG} apply', 'package_version': __version__,
           'command': [PROG, *command], 'bag': str(info_bag.path), 'topic': info_bag.topic,
           'temperature_topic': info_bag.temperature_topic, 'samples': int(run.t_s.size),
           'rate_hz': run.rate_hz, 'duration_s': float(run.t_s[-1] - run.t_s[0]),
           'temperature_min_c': t_lo, 'temperature_max_c': t_hi,
           'model': {'path': str(model_path), 'method': model.method.name,
                     'package_version': model.package_version,
                     'training': model.training.as_dict(),
                     'range_margin_c': score.range_margin_c},
           'in_sample': bool(in_sample),
           'rate_mismatch': bool(abs(run.rate_hz - model.training.rate_hz)
                                 > 0.01 * model.training.rate_hz),
           'range': rng.as_dict(), 'accel': accel_doc, 'notes': notes,
           'warnings': list(warnings), 'sensor_offset_deg_s': offsets,
           'temperature_readings': {'read': info_bag.temperature_samples,
                                    'dropped': info_bag.temperature_dropped,
                                    'period_s': info_bag.temperature_period_s},
           'apply_time_s': apply_s, 'definitions': DEFINITIONS}
    doc.update(scored)
    doc['yardstick'] = _apply_yardstick(model, run, scored)
    return ApplyResult(doc=registry.to_jsonable(doc), run=run, bag=info_bag,
                       processed=processed, processed_accel=processed_accel, curves=curves,
                       info=info, method_figures=method_figs, notes=tuple(notes),
                       warnings=tuple(warnings))


def _apply_checks(model: Any, run: Any, score: ScoreOptions) -> tuple[Any, list[float],
                                                                      list[str]]:
    """Refuse what cannot be applied; return the range report, the offsets and the warnings."""
    if getattr(model.method, 'uses_rate', False):
        check_temperature_readings(run, model.training.rate_window_s)
    offsets = registry.check_same_sensor(model, run, max_offset_deg_s=score.max_offset_deg_s)
    rng = _range(model, run)
    warning = rng.warning()
    if warning and score.strict:
        raise registry.TemperatureRangeError(f'--strict: {warning}')
    return rng, offsets, [] if warning is None else [warning]


def _apply_yardstick(model: Any, run: Any, scored: dict[str, Any]) -> dict[str, Any]:
    """Set the residual drift against the run's white-noise floor and the model's poly3."""
    residual = [scored['axes'][a]['processed']['residual_drift_deg_s'] for a in 'xyz']
    poly3 = model.poly3()
    p3 = None
    if poly3 is not None:
        p3 = residual_drift_deg_s(run.gyro_rad_s - poly3.drift_rad_s(run.temperature_c, 0.0),
                                  run.rate_hz)
    return dict(scored['yardstick'], **yardstick(
        [math.nan if v is None else v for v in residual], scored['yardstick']['floor_deg_s'],
        poly3_deg_s=p3))


def write_apply(result: ApplyResult, out_dir: StrPath, *, figures: bool = True,
                write_bag: bool = True, storage: str | None = None,
                html: bool = True) -> list[Path]:
    """
    Write OUT/compensated/ (rosbag2), metrics.json, report.md, report.html, figures (staged).

    Parameters
    ----------
    result : ApplyResult
        From :func:`apply_model`.
    out_dir : str or os.PathLike
        The ``--out`` folder.
    figures : bool, keyword-only
        Write PNG figures.
    write_bag : bool, keyword-only
        Write the compensated bag.
    storage : {'sqlite3', 'mcap'}, optional, keyword-only
        Its storage (default: the input's).
    html : bool, keyword-only
        Write report.html (:mod:`..htmlreport.thermal`).

    Returns
    -------
    list of pathlib.Path
        The files (and the bag folder), under their final names.

    """
    doc = result.doc
    with staged_output(out_dir) as stage:
        files: list[Path] = []
        if write_bag:
            write_compensated(result.bag, result.processed, stage / 'compensated',
                              storage=storage, accel_m_s2=result.processed_accel)
            files.append(stage / 'compensated')
        figs: Figures = []
        if figures:
            figs = apply_figures(stage, result.run, result.processed, method=doc['method'],
                                 curves=result.curves, info=result.info,
                                 own=_put_method_figures(result.method_figures, stage))
        files.append(_write(stage / 'metrics.json', _json(doc)))
        files.append(_write(stage / 'report.md', apply_markdown(doc, figs, stage)))
        if html:
            files.append(write_apply_html(doc, result.run, result.processed, result.curves,
                                          stage))
        files.extend(p for _, p in figs if p is not None)
        names = [p.relative_to(stage) for p in files]
    return [Path(out_dir) / n for n in names]


# ---------------------------------------------------------------------------------------------
# compare


def _same_run(a: Any, b: Any) -> bool:
    if a.t_s.size != b.t_s.size:
        return False
    return bool(np.array_equal(a.gyro_rad_s, b.gyro_rad_s))


def split_run(run: Any, fraction: float) -> tuple[Any, Any, float]:
    """
    Split one run in time: the first ``fraction`` of its duration, and the rest.

    Parameters
    ----------
    run : ThermalRun
        The recording.
    fraction : float
        Share of the duration (0 < fraction < 1) that goes to the first part.

    Returns
    -------
    first, rest : ThermalRun
        ``rest`` has its times counted from its own first sample, as a separate recording would;
        both keep the whole run's ``rate_hz``.
    cut_s : float
        Time of the cut (s from the run's first sample).

    """
    if not (math.isfinite(fraction) and 0.0 < fraction < 1.0):
        raise ParameterError(f'--split-at must be between 0 and 1, got {fraction!r}')
    t = run.t_s
    cut_s = float(t[0] + fraction * (t[-1] - t[0]))
    k = int(np.searchsorted(t, cut_s, side='left'))
    if k < 3 or t.size - k < 3:
        raise InputDataError(f'run {run.name!r}: --split-at {fraction:g} leaves fewer than 3 '
                             'samples on one side')
    accel = run.accel_m_s2

    def part(sl: slice, t_part: np.ndarray, name: str) -> Any:
        return replace(run, t_s=t_part, gyro_rad_s=run.gyro_rad_s[sl],
                       temperature_c=run.temperature_c[sl],
                       accel_m_s2=None if accel is None else accel[sl], name=name)

    first = part(slice(None, k), t[:k], f'{run.name} [0, {cut_s:.1f}) s')
    rest = part(slice(k, None), t[k:] - t[k], f'{run.name} [{cut_s:.1f}, {t[-1]:.1f}] s')
    return first, rest, cut_s


def _compare_runs(train: str, test: str | None, split_at: float | None,
                  options: BagOptions) -> tuple[Any, Any, str, str, dict[str, Any] | None,
                                                tuple[Any, ...]]:
    """Read TRAIN_BAG and TEST_BAG, or split TRAIN_BAG in time (--split-at); and their bags."""
    if split_at is not None:
        if test is not None:
            raise ParameterError('--split-at takes one recording (TRAIN_BAG only), got two')
        if not (math.isfinite(split_at) and 0.0 < split_at < 1.0):
            raise ParameterError(f'--split-at must be between 0 and 1, got {split_at!r}')
        whole, bag = options.read(train)
        first, rest, cut_s = split_run(whole, split_at)
        split = {'fraction': split_at, 'cut_s': cut_s, 'duration_s': float(whole.t_s[-1]),
                 'note': 'train and test are adjacent parts of one run (one power-on, one '
                         'temperature history): not independent runs'}
        end_s = split['duration_s']
        return (first, rest, f'{bag.path} [0, {cut_s:.1f}) s',
                f'{bag.path} [{cut_s:.1f}, {end_s:.1f}] s', split, (bag,))
    if test is None:
        raise ParameterError('compare needs TRAIN_BAG and TEST_BAG, or one bag and --split-at')
    if Path(train).resolve() == Path(test).resolve():
        raise ParameterError('TRAIN_BAG and TEST_BAG are the same recording; a method must be '
                             'scored on a run it was not trained on')
    (a, a_bag), (b, b_bag) = options.read(train), options.read(test)
    if _same_run(a, b):
        raise ParameterError('TRAIN_BAG and TEST_BAG hold the same samples; a method must be '
                             'scored on a run it was not trained on')
    return a, b, str(a_bag.path), str(b_bag.path), None, (a_bag, b_bag)


def _simulated_truth(bag_path: StrPath) -> tuple[Any, Any] | None:
    """Return the simulation's truth beside a bag of ``simulate`` (``<label>_truth.npz``)."""
    from ..thermal.simulate import load_truth, model_from_settings

    bag = Path(bag_path)
    truth_file = bag.parent / f'{bag.name}_truth.npz'
    settings_file = bag.parent / 'simulation.json'
    if not (truth_file.is_file() and settings_file.is_file()):
        return None
    try:
        settings = json.loads(settings_file.read_text())
        return load_truth(truth_file), model_from_settings(settings)
    except (OSError, ValueError, KeyError, TypeError):
        return None


def oracle_scores(train: Any, train_truth: Any, test: Any, test_truth: Any,
                  model: Any) -> dict[str, Any]:
    """
    Score the least-squares oracles on a simulated pair (residual drift per axis, deg/s).

    Parameters
    ----------
    train, test : ThermalRun
        The runs.
    train_truth, test_truth : ThermalTruth
        Their truths.
    model : ThermalModel
        The simulated device.

    Returns
    -------
    dict
        ``true_terms`` and ``measured_terms``: per axis residual drift (deg/s), and the mean.

    """
    from ..thermal.oracle import oracle_residual

    out: dict[str, Any] = {}
    for key, measured in (('true_terms', False), ('measured_terms', True)):
        res = oracle_residual(train, train_truth, test, test_truth, model, measured=measured)
        axes = {axis: _num(noise_metrics(res[:, a], test.rate_hz).residual_drift_deg_s)
                for a, axis in enumerate('xyz')}
        finite = [v for v in axes.values() if v is not None]
        out[key] = {'axes': axes, 'mean_residual_drift_deg_s':
                    float(np.mean(finite)) if finite else None}
    return out


@dataclass(frozen=True)
class CompareResult:
    """
    Every method trained on one run and scored on another.

    Attributes
    ----------
    summary : dict
        compare.json (see :meth:`as_dict`).
    rows : list of tuple
        The table's values, raw input and oracles first: the columns of compare.csv
        (:data:`COMPARE_HEADER` plus the bias-stability upper-bound flag last; numbers as
        numbers, :func:`table_cells` formats them as compare.md shows them).
    curves : dict
        Per method the per-axis responses and Allan curves, for the figures.
    test : ThermalRun
        The test run.
    errors : dict
        Method -> why it was not scored.

    """

    summary: dict[str, Any]
    rows: list[tuple[Any, ...]]
    curves: dict[str, Any]
    test: Any
    errors: dict[str, str] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """
        Return compare.json.

        Returns
        -------
        dict

        """
        return self.summary


def check_method_names(names: Sequence[str]) -> list[str]:
    """
    Refuse an empty list or an unknown name before any work (one line, exit 2).

    Parameters
    ----------
    names : list of str
        ``--methods`` entries.

    Returns
    -------
    list of str

    """
    if not names:
        raise ParameterError('--methods names no method')
    known = registry.method_names()
    unknown = [n for n in names if n not in known]
    if unknown:
        raise registry.MethodUnavailableError(
            f'unknown method(s) {", ".join(repr(n) for n in unknown)} in --methods (known: '
            f'{", ".join(known)})')
    return list(names)


def compare(*, train: str, test: str | None = None, split_at: float | None = None,
            methods: Sequence[str] | None = None, seed: int = 0,
            min_range_c: float = registry.DEFAULT_MIN_RANGE_C,
            bag_options: BagOptions = BagOptions(), score: ScoreOptions = ScoreOptions(),
            scheduler: str | None = None, warn: Callable[[str], None] | None = None,
            progress: Callable[[str], None] | None = None,
            command: Sequence[str] = ()) -> CompareResult:
    """
    Train every method on one run and score it on another (``gyro_noise_thermal compare``).

    Parameters
    ----------
    train : str
        Training recording.
    test : str, optional
        Held-out recording (None with ``split_at``).
    split_at : float, optional
        One recording only: train on its first fraction of time, test on the rest.
    methods : sequence of str, optional
        Methods (default: every known one). An unknown name is refused before any work.
    seed : int, keyword-only
        Seed of stochastic training.
    min_range_c : float, keyword-only
        Smallest training temperature span (degC).
    bag_options : BagOptions, keyword-only
        Topics and gap limit.
    score : ScoreOptions, keyword-only
        Injection and range margin.
    scheduler : str, optional, keyword-only
        Dask scheduler for the parallel model.
    warn, progress : callable, optional, keyword-only
        Called with one line of text: warnings, and per method what happened.
    command : sequence of str, keyword-only
        The command line, recorded.

    Returns
    -------
    CompareResult

    """
    names = check_method_names(registry.method_names() if methods is None else list(methods))
    min_range_c = registry.check_min_range(min_range_c)
    run_a, run_b, train_label, test_label, split, infos = _compare_runs(train, test, split_at,
                                                                        bag_options)
    registry.check_trainable(run_a, min_range_c=min_range_c)
    _check_injection_length(run_b, score)
    say = progress or (lambda text: None)
    results: dict[str, dict[str, Any]] = {}
    errors: dict[str, str] = {}
    curves: dict[str, Any] = {}
    pool = _executor(scheduler, names, warn)
    try:
        for name in names:
            try:
                registry.check_trainable(run_a, min_range_c=min_range_c, method=name)
                started = time.monotonic()
                model = _fit_model(name, run_a, seed=seed, sources=[train_label],
                                   executor=pool)
                fit_s = time.monotonic() - started
                registry.check_temperature_range(model, run_b.temperature_c,
                                                 margin_c=score.range_margin_c)
                started = time.monotonic()
                processed = np.asarray(model.method.apply(run_b), dtype=float)
                apply_s = time.monotonic() - started
                doc, processed, cur = _score(model.method, run_b, score, processed)
            except ClusterError:
                raise   # the cluster failed, not the method: stop
            except Exception as err:  # noqa: BLE001 - reported in the table, see below
                # One method failing (missing module, a fit that diverges, a bug in it) must
                # not hide the others; its error is reported in compare.json and compare.md.
                errors[name] = f'{type(err).__name__}: {err}'
                say(f'{name}: not scored: {errors[name]}')
                continue
            doc['fit_time_s'], doc['apply_time_s'] = fit_s, apply_s
            doc['model'] = registry.to_jsonable(model.method.to_dict())
            rep = _range(model, run_b)
            doc['range'] = dict(rep.as_dict(), warning=rep.warning())
            results[name], curves[name] = doc, cur
            say(f'{name}: scored (fit {fit_s:.1f} s, apply {apply_s:.1f} s)')
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    if not results:
        raise InputDataError('no method could be trained and scored: '
                             + '; '.join(f'{k}: {v}' for k, v in errors.items()))
    truth = None if split is not None else (_simulated_truth(train),
                                            _simulated_truth(cast(str, test)))
    summary = registry.to_jsonable({
        'tool': f'{PROG} compare', 'package_version': __version__,
        'command': [PROG, *command], 'train': train_label, 'test': test_label, 'split': split,
        'seed': seed, 'train_rate_hz': run_a.rate_hz, 'test_rate_hz': run_b.rate_hz,
        'train_temperature_c': [float(run_a.temperature_c.min()),
                                float(run_a.temperature_c.max())],
        'test_temperature_c': [float(run_b.temperature_c.min()),
                               float(run_b.temperature_c.max())],
        'definitions': DEFINITIONS, 'notes': [n for b in infos for n in b.notes],
        'methods': results, 'errors': errors, **_yardsticks(run_a, run_b, results, truth)})
    summary['warnings'] = [w for b in infos for w in b.warnings] + summary['warnings']
    return CompareResult(summary=summary, rows=compare_rows(summary), curves=curves,
                         test=run_b, errors=errors)


def _yardsticks(run_a: Any, run_b: Any, results: dict[str, dict[str, Any]],
                truth: tuple[Any, Any] | None) -> dict[str, Any]:
    """Each method against the noise floor and poly3; the ranking; the oracle, the warnings."""
    first = next(iter(results.values()))
    oracle, floor, kind = None, np.array(first['yardstick']['floor_deg_s'], dtype=float), 'white'
    if truth is not None and truth[0] is not None and truth[1] is not None:
        (a_truth, _), (b_truth, device) = truth
        oracle = oracle_scores(run_a, a_truth, run_b, b_truth, device)
        floor, kind = residual_drift_deg_s(b_truth.noise_rad_s, run_b.rate_hz), 'noise'
    p3 = _poly3_reference(run_a, run_b, results)
    warnings = []
    for name, doc in results.items():
        residual = [v['processed']['residual_drift_deg_s'] for v in doc['axes'].values()]
        doc['yardstick'] = yardstick([math.nan if v is None else v for v in residual], floor,
                                     poly3_deg_s=p3, floor=kind)
        if doc['range'].get('warning'):
            warnings.append(f'{name}: {doc["range"]["warning"]}')
    ranking = sorted(results, key=lambda n: (results[n]['yardstick']['mean_over_floor']
                                             is None, results[n]['yardstick']['mean_over_floor']
                                             or 0.0))
    return {'floor': {'kind': kind, 'deg_s': [float(v) for v in floor],
                      'definition': _FLOOR_DEFINITIONS[kind]},
            'poly3_deg_s': None if p3 is None else [float(v) for v in p3],
            'oracle': oracle, 'warnings': warnings,
            'ranking': [{'method': n, 'mean_over_floor':
                         results[n]['yardstick']['mean_over_floor'],
                         'mean_over_poly3': results[n]['yardstick'].get('mean_over_poly3'),
                         'live_capable': all(v['verdict']['live_capable']
                                             for v in results[n]['axes'].values())}
                        for n in ranking],
            'best_held_out': _best(results)}


#: What the floor of compare.json is, by kind.
_FLOOR_DEFINITIONS = {
    'noise': "residual drift of the test run's own noise (the simulation's truth): what a "
             'perfect drift model would leave',
    'white': "the test run's white-noise level over the band of the 60-s means, ARW / "
             'sqrt(60 s) per axis (the Allan readout of the raw run): what a perfect drift model '
             'would leave if the noise were white; slow noise (bias instability) is not in it'}


def _poly3_reference(run_a: Any, run_b: Any,
                     results: dict[str, dict[str, Any]]) -> np.ndarray | None:
    """poly3's residual drift on the test run: the scored row, else poly3 fitted here."""
    if 'poly3' in results:
        return np.array([math.nan if v['processed']['residual_drift_deg_s'] is None
                         else v['processed']['residual_drift_deg_s']
                         for v in results['poly3']['axes'].values()])
    from ..thermal.baselines import TemperaturePolynomial

    poly = TemperaturePolynomial()
    try:
        poly.fit(run_a, rng=np.random.default_rng(0))
    except InputDataError:
        return None
    return residual_drift_deg_s(poly.apply(run_b), run_b.rate_hz)


def _best(results: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Pick the lowest mean residual drift among live-capable full-bandwidth methods."""
    best: str | None = None
    score = math.inf
    for name, doc in results.items():
        axes = doc['axes'].values()
        live = all(v['verdict']['live_capable'] for v in axes)
        full = all(not v['verdict']['arw_from_bandwidth'] for v in axes)
        drift = [v['processed']['residual_drift_deg_s'] for v in axes]
        if not (live and full) or any(d is None for d in drift):
            continue
        s = float(np.mean(drift))
        if s < score:
            best, score = name, s
    return {'method': best, 'mean_residual_drift_deg_s': _num(score),
            'rule': 'lowest mean residual drift on the test run among methods that are '
                    'live-capable and do not gain ARW by removing bandwidth'}


def write_compare(result: CompareResult, out_dir: StrPath, *, figures: bool = True,
                  html: bool = True) -> list[Path]:
    """
    Write compare.json, compare.csv, compare.md, report.html and the figures (staged).

    Parameters
    ----------
    result : CompareResult
        From :func:`compare`.
    out_dir : str or os.PathLike
        The ``--out`` folder.
    figures : bool, keyword-only
        Write PNG figures.
    html : bool, keyword-only
        Write report.html (:mod:`..htmlreport.thermal`).

    Returns
    -------
    list of pathlib.Path

    """
    doc = result.summary
    with staged_output(out_dir) as stage:
        figs = compare_figures(stage, result.test, result.curves) if figures else []
        files = [_write(stage / 'compare.json', _json(doc)),
                 _write(stage / 'compare.csv', compare_csv(doc)),
                 _write(stage / 'compare.md', compare_markdown(doc, figs, stage))]
        if html:
            files.append(write_compare_html(doc, result.curves, stage))
        files.extend(p for _, p in figs)
        names = [p.relative_to(stage) for p in files]
    return [Path(out_dir) / n for n in names]


# ---------------------------------------------------------------------------------------------
# simulate


@dataclass(frozen=True)
class SimulateResult:
    """
    A simulated train/test pair, in memory.

    Attributes
    ----------
    pair : list
        ``[('train', run, truth), ('test', run, truth)]`` (:func:`simulate_pair`).
    settings : dict
        simulation.json (see :meth:`as_dict`).

    """

    pair: list[tuple[str, Any, Any]]
    settings: dict[str, Any]

    def as_dict(self) -> dict[str, Any]:
        """
        Return simulation.json.

        Returns
        -------
        dict

        """
        return self.settings


def simulate(*, seed: int = 0, hours: float | None = None, rate_hz: float = 100.0,
             compress: float | None = None, shape: str = 'oven',
             test_shape: str | None = None, hysteresis: bool = True,
             storage: str = 'sqlite3',
             temperature_rate_hz: float | None = None) -> SimulateResult:
    """
    Simulate a seeded train/test pair (``gyro_noise_thermal simulate``).

    Parameters
    ----------
    seed : int, keyword-only
        Seed of both runs.
    hours, compress : float, optional, keyword-only
        Training run length and time compression (the test run shares the compression).
    rate_hz : float, keyword-only
        Gyro sample rate (Hz).
    shape : str, keyword-only
        Training profile (``thermal.simulate.SHAPES``).
    test_shape : str, optional, keyword-only
        Test profile (None: the training one, a replicate run).
    hysteresis : bool, keyword-only
        Keep the bias hysteresis.
    storage : {'sqlite3', 'mcap'}, keyword-only
        Recorded in the settings (used by :func:`write_simulate`).
    temperature_rate_hz : float, optional, keyword-only
        Rate of the Temperature messages (default 52 Hz).

    Returns
    -------
    SimulateResult

    """
    from ..thermal import simulate as sim

    if storage not in ('sqlite3', 'mcap'):
        raise ParameterError(f"storage must be 'sqlite3' or 'mcap', got {storage!r}")
    for label, value in (('--rate-hz', rate_hz), ('--temperature-rate-hz', temperature_rate_hz)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ParameterError(f'{label} must be > 0, got {value!r}')
    temp_rate = sim.TEMPERATURE_RATE_HZ if temperature_rate_hz is None else temperature_rate_hz
    model = sim.ThermalModel() if hysteresis else sim.ThermalModel(hysteresis_half_width_c=0.0)
    profile = sim.make_profile(shape)
    test_profile = None if test_shape is None else sim.make_profile(test_shape)
    pair = sim.simulate_pair(seed=seed, rate_hz=rate_hz, hours=hours, compress=compress,
                             model=model, profile=profile, test_profile=test_profile,
                             temperature_rate_hz=temp_rate)
    settings = sim.pair_settings(pair, seed=seed, rate_hz=rate_hz, hours=hours, storage=storage,
                                 model=model, profile=profile, test_profile=test_profile,
                                 temperature_rate_hz=temp_rate)
    return SimulateResult(pair=pair, settings=settings)


def write_simulate(result: SimulateResult, out_dir: StrPath) -> tuple[Path, Path]:
    """
    Write train/, test/ (rosbag2), their truth and simulation.json (staged).

    Parameters
    ----------
    result : SimulateResult
        From :func:`simulate`.
    out_dir : str or os.PathLike
        The ``--out`` folder.

    Returns
    -------
    tuple of pathlib.Path
        ``(train_bag, test_bag)`` under their final names.

    """
    from ..thermal.simulate import write_pair

    with staged_output(out_dir) as stage:
        write_pair(stage, result.pair, result.settings, storage=result.settings['storage'])
    return Path(out_dir) / 'train', Path(out_dir) / 'test'


# ---------------------------------------------------------------------------------------------
# export


@dataclass(frozen=True)
class ExportResult:
    """
    A model's polynomial as PX4 and ArduPilot parameters, and what each firmware would leave.

    Attributes
    ----------
    model_path : str
        The model.json exported.
    px4 : list of (str, value, int)
        ``TC_*`` parameters (name, value, MAVLink type).
    ardupilot : list of (str, float)
        ``INS_TCAL*`` (and offset) parameters.
    notes : tuple of str
        What loading and exporting noticed (which poly3 is exported, ranges).
    accel : bool
        Whether the accelerometer's polynomial was exported too.
    exported : dict
        ``method`` (the model's), ``form`` (always ``poly3``), ``source`` (``'the model'`` or
        ``'the poly3 fitted beside it'``), ``axes`` (the autopilot's axes in the recording's).
    warnings : tuple of str
        What makes a file do nothing on the vehicle (a block written disabled: no device id).
    devices : dict
        The PX4 device ids given, decoded (``thermal.export.px4_device_id``).
    predicted : list of dict
        Per recording (the training sources still readable, then ``--predict``): ``bag``,
        ``role`` and ``residual_deg_s``: ``raw``, ``model`` (the exported cubic at every
        sample), ``px4``, ``ardupilot`` (as each firmware applies it) and ``method`` (the fitted
        method itself), per axis, deg/s.

    """

    model_path: str
    px4: list[tuple[str, Any, int]]
    ardupilot: list[tuple[str, Any]]
    notes: tuple[str, ...] = ()
    accel: bool = False
    exported: dict[str, Any] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    devices: dict[str, Any] = field(default_factory=dict)
    predicted: tuple[dict[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """
        Return export.json.

        Returns
        -------
        dict

        """
        return registry.to_jsonable({
            'tool': f'{PROG} export', 'package_version': __version__,
            'model': self.model_path, 'accelerometer': self.accel, 'exported': self.exported,
            'notes': list(self.notes), 'warnings': list(self.warnings),
            'px4_devices': self.devices, 'predicted': list(self.predicted),
            'px4': {name: value for name, value, _ in self.px4},
            'ardupilot': dict(self.ardupilot),
            'references': {
                'px4': 'https://docs.px4.io/main/en/advanced_config/'
                       'sensor_thermal_calibration.html',
                'ardupilot': 'https://ardupilot.org/copter/docs/common-imutempcal.html'}})


def export(*, model_path: str, px4_instance: int = 0, gyro_device_id: int | None = None,
           accel_device_id: int | None = None, ardupilot_imu: int = 1, gyro_offsets: bool = True,
           cal_temp_c: float | None = None, axes: str = 'x,y,z', predict: Sequence[str] = (),
           bag_options: BagOptions = BagOptions()) -> ExportResult:
    """
    Turn a model's poly3 into PX4 and ArduPilot parameters (``gyro_noise_thermal export``).

    Parameters
    ----------
    model_path : str
        model.json of ``fit``: a poly3, or any method fitted with its companion poly3
        (``ThermalModel.autopilot``, model.json format 3).
    px4_instance : int, keyword-only
        PX4 calibration instance (0..3).
    gyro_device_id, accel_device_id : int or None, keyword-only
        PX4 ``TC_G<i>_ID`` / ``TC_A<i>_ID`` (None: that block written disabled, with a warning).
    ardupilot_imu : int, keyword-only
        ArduPilot IMU number (1..3).
    gyro_offsets : bool, keyword-only
        Also write ArduPilot's gyro offsets and CALTEMP (the whole model).
    cal_temp_c : float, optional, keyword-only
        ArduPilot CALTEMP of those offsets (default the model's T_ref).
    axes : str, keyword-only
        The autopilot's X, Y, Z as signed axes of the recording (``thermal.export.remap_axes``).
    predict : sequence of str, keyword-only
        Recordings to predict each firmware's residual on, besides the training sources.
    bag_options : BagOptions, keyword-only
        How those are read.

    Returns
    -------
    ExportResult

    """
    from ..thermal.export import (ardupilot_notes, ardupilot_parameters, calibration_of,
                                  px4_device_id, px4_parameters, remap_axes)

    model = registry.load_model(model_path)
    own = getattr(model.method, 'as_poly3', None)
    poly = (own() if own is not None else None) or model.poly3()
    if poly is None:
        raise ParameterError(f'model {model_path!r} ({model.method.name}) carries no poly3 for '
                             'the autopilots (a model file written before format 3): fit it '
                             'again, fit now adds the poly3 PX4 and ArduPilot evaluate')
    gyro = calibration_of(poly)
    accel = None if model.accel is None else calibration_of(model.accel, unit='m/s^2')
    fw_gyro, fw_accel = (None if c is None else remap_axes(c, axes) for c in (gyro, accel))
    px4 = px4_parameters(fw_gyro, fw_accel, instance=px4_instance,
                         gyro_device_id=gyro_device_id, accel_device_id=accel_device_id)
    ardupilot = ardupilot_parameters(fw_gyro, fw_accel, imu=ardupilot_imu,
                                     cal_temp_c=cal_temp_c, gyro_offsets=gyro_offsets)
    devices = {label: px4_device_id(dev, option) for label, dev, option in (
        ('gyro', gyro_device_id, 'px4_gyro_id'), ('accel', accel_device_id, 'px4_accel_id'))
        if dev}
    notes = list(model.notes) + list(ardupilot_notes(gyro))
    itself = poly is model.method or poly is not model.poly3()
    exported = {'method': model.method.name, 'form': 'poly3', 'axes': axes,
                'source': 'the model' if itself else 'the poly3 fitted beside it'}
    if itself and poly is not model.method:
        notes.append(f'exported: {model.method.name} itself (its terms are a polynomial in T '
                     'alone, the form PX4 and ArduPilot evaluate)')
    elif not itself:
        name = model.method.name
        notes.append(f'exported: the poly3 fitted beside {name} on the same training run (PX4 '
                     f'and ArduPilot evaluate a cubic in T only; what {name} models beyond it '
                     'stays on the ground, and the prediction says what that costs)')
    return ExportResult(model_path=str(model_path), px4=px4, ardupilot=ardupilot,
                        notes=tuple(notes), accel=accel is not None, exported=exported,
                        warnings=_px4_id_warnings(gyro_device_id, accel_device_id, accel),
                        devices=devices,
                        predicted=_predictions(model, gyro, cal_temp_c, predict, bag_options))


def _px4_id_warnings(gyro_id: int | None, accel_id: int | None, accel: Any) -> tuple[str, ...]:
    out = []
    for what, dev, option, flag, cal in (('gyro', gyro_id, '--px4-gyro-id', 'TC_G_ENABLE',
                                          'CAL_GYRO0_ID'),
                                         ('accelerometer', accel_id, '--px4-accel-id',
                                          'TC_A_ENABLE', 'CAL_ACC0_ID')):
        if not dev and (what == 'gyro' or accel is not None):
            out.append(f'no {option}: the PX4 {what} block is written with {flag} 0 (id 0 '
                       f'matches no sensor); give the id PX4 shows as {cal}')
    return tuple(out)


def _predictions(model: Any, gyro: Any, cal_temp_c: float | None, predict: Sequence[str],
                 bag_options: BagOptions) -> tuple[dict[str, Any], ...]:
    """Each firmware's residual on the training sources still readable and on ``predict``."""
    from ..thermal.export import firmware_residuals

    bags = [(s, 'training') for s in model.training.sources if Path(s).exists()]
    bags += [(s, 'predict') for s in predict]
    out = []
    for path, role in bags:
        run, _ = bag_options.read(path)
        residual = firmware_residuals(gyro, run.t_s, run.gyro_rad_s, run.temperature_c,
                                      cal_temp_c=cal_temp_c)
        if model.poly3() is not model.method:
            processed = np.asarray(model.method.apply(run), dtype=float)
            residual['method'] = [float(v) for v in residual_drift_deg_s(processed,
                                                                         run.rate_hz)]
        out.append({'bag': str(path), 'role': role, 'residual_deg_s': residual})
    return tuple(out)


def write_export(result: ExportResult, out_dir: StrPath) -> list[Path]:
    """
    Write thermal_px4.params, thermal_ardupilot.parm and export.json (staged).

    Parameters
    ----------
    result : ExportResult
        From :func:`export`.
    out_dir : str or os.PathLike
        The ``--out`` folder.

    Returns
    -------
    list of pathlib.Path

    """
    from ..thermal.export import write_ardupilot_parm, write_px4_params

    head = f'model {result.model_path}, gyro_noise_ros {__version__}'
    # the PX4 file says why a block is disabled; both say which poly3 they carry
    px4_comment = '\n'.join([head, *(f'WARNING: {w}' for w in result.warnings), *result.notes])
    comment = '\n'.join([head, *result.notes])
    with staged_output(out_dir) as stage:
        write_px4_params(stage / 'thermal_px4.params', result.px4, comment=px4_comment)
        write_ardupilot_parm(stage / 'thermal_ardupilot.parm', result.ardupilot,
                             comment=comment)
        _write(stage / 'export.json', _json(result.as_dict()))
    return [Path(out_dir) / n for n in ('thermal_px4.params', 'thermal_ardupilot.parm',
                                        'export.json')]
