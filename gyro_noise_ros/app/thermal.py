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
                               DRIFT_WINDOW_S, evaluate_method, noise_metrics)
# bandwidth_cell, COMPARE_HEADER, COMPARE_SPECS and table_cells are handed on for the command line
from ..thermal.report import (apply_markdown, bandwidth_cell, compare_csv, COMPARE_HEADER,
                              compare_markdown, compare_rows, COMPARE_SPECS, table_cells,
                              training_markdown)
from ..thermal.run import DEFAULT_RATE_WINDOW_S, temperature_rate_c_s
from ..units import RAD_TO_DEG, STANDARD_GRAVITY_M_S2

__all__ = ['ApplyResult', 'BagOptions', 'COMPARE_HEADER', 'COMPARE_SPECS', 'CompareResult',
           'DEFINITIONS', 'ExportResult', 'FitResult', 'HELDOUT_METHODS', 'HELDOUT_PAIRS',
           'ScoreOptions', 'SimulateResult', 'apply_model', 'bandwidth_cell',
           'check_method_names', 'compare', 'export', 'fit', 'heldout_scores', 'oracle_scores',
           'simulate', 'split_run', 'table_cells', 'write_apply', 'write_compare',
           'write_export', 'write_fit', 'write_simulate']

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
    'ratio_to_oracle': 'mean residual drift over the axes divided by that of least squares on '
                       "the simulator's true drift terms, trained on the training run (bags "
                       'written by gyro_noise_thermal simulate only)',
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

    """

    amplitude_deg_s: float = DEFAULT_AMPLITUDE_RAD_S * RAD_TO_DEG
    f_lo_hz: float = DEFAULT_F_LO_HZ
    f_hi_hz: float = DEFAULT_F_HI_HZ
    small_signal: bool = True
    range_margin_c: float = registry.DEFAULT_RANGE_MARGIN_C


def _json(doc: dict[str, Any]) -> str:
    return json.dumps(registry.to_jsonable(doc), indent=1, allow_nan=False) + '\n'


def _write(path: StrPath, text: str) -> Path:
    Path(path).write_text(text)
    return Path(path)


def _residual_drift(x: Any, rate_hz: float) -> list[float | None]:
    """Std (ddof 1) of consecutive 60-s window means per axis, in x's unit (None if < 2)."""
    x = np.asarray(x, dtype=float)
    window = int(round(DRIFT_WINDOW_S * rate_hz))
    k = x.shape[0] // window if window >= 1 else 0
    if k < 2:
        return [None] * x.shape[1]
    means = x[:k * window].reshape(k, window, -1).mean(axis=1)
    return [float(v) for v in np.std(means, axis=0, ddof=1)]


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
                                                   'not stated by the method'))


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

    def model_dict(self) -> dict[str, Any]:
        """
        Return the model.json document.

        Returns
        -------
        dict

        """
        return registry.model_document(self.model.method, training=self.model.training,
                                       accel=self.model.accel)

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
            'in_sample': self.in_sample, 'accel': self.accel, 'notes': list(m.notes),
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
                      'rate_hz': r.rate_hz, 'accelerometer': r.accel_m_s2 is not None}
                     for b, r in zip(infos, runs))
    return FitResult(model=model, run=run, bags=bag_docs, processed=processed,
                     fit_time_s=fit_s, seed=int(seed), in_sample=_in_sample(run, processed),
                     accel=accel_doc, method_figures=method_figs, command=tuple(command))


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
        Warnings (model from another package version, run outside the trained range).

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
    rng = _range(model, run)
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
    notes = list(model.notes)
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
           'apply_time_s': apply_s, 'definitions': DEFINITIONS}
    doc.update(scored)
    return ApplyResult(doc=registry.to_jsonable(doc), run=run, bag=info_bag,
                       processed=processed, processed_accel=processed_accel, curves=curves,
                       info=info, method_figures=method_figs, notes=tuple(notes))


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
                  options: BagOptions) -> tuple[Any, Any, str, str, dict[str, Any] | None]:
    """Read TRAIN_BAG and TEST_BAG, or split TRAIN_BAG in time (--split-at)."""
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
                f'{bag.path} [{cut_s:.1f}, {end_s:.1f}] s', split)
    if test is None:
        raise ParameterError('compare needs TRAIN_BAG and TEST_BAG, or one bag and --split-at')
    if Path(train).resolve() == Path(test).resolve():
        raise ParameterError('TRAIN_BAG and TEST_BAG are the same recording; a method must be '
                             'scored on a run it was not trained on')
    (a, a_bag), (b, b_bag) = options.read(train), options.read(test)
    if _same_run(a, b):
        raise ParameterError('TRAIN_BAG and TEST_BAG hold the same samples; a method must be '
                             'scored on a run it was not trained on')
    return a, b, str(a_bag.path), str(b_bag.path), None


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
    run_a, run_b, train_label, test_label, split = _compare_runs(train, test, split_at,
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
            doc['range'] = _range(model, run_b).as_dict()
            results[name], curves[name] = doc, cur
            say(f'{name}: scored (fit {fit_s:.1f} s, apply {apply_s:.1f} s)')
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    if not results:
        raise InputDataError('no method could be trained and scored: '
                             + '; '.join(f'{k}: {v}' for k, v in errors.items()))
    oracle = None
    if split is None:
        # without --split-at, _compare_runs has refused a missing TEST_BAG
        a_truth, b_truth = _simulated_truth(train), _simulated_truth(cast(str, test))
        if a_truth is not None and b_truth is not None:
            oracle = oracle_scores(run_a, a_truth[0], run_b, b_truth[0], b_truth[1])
            base = oracle['true_terms']['mean_residual_drift_deg_s']
            for doc in results.values():
                drift = [v['processed']['residual_drift_deg_s'] for v in doc['axes'].values()]
                doc['ratio_to_oracle'] = (None if base is None or None in drift
                                          else float(np.mean(drift)) / base)
    summary = registry.to_jsonable({
        'tool': f'{PROG} compare', 'package_version': __version__,
        'command': [PROG, *command], 'train': train_label, 'test': test_label, 'split': split,
        'seed': seed, 'train_rate_hz': run_a.rate_hz, 'test_rate_hz': run_b.rate_hz,
        'train_temperature_c': [float(run_a.temperature_c.min()),
                                float(run_a.temperature_c.max())],
        'test_temperature_c': [float(run_b.temperature_c.min()),
                               float(run_b.temperature_c.max())],
        'definitions': DEFINITIONS, 'methods': results, 'errors': errors, 'oracle': oracle,
        'best_held_out': _best(results)})
    return CompareResult(summary=summary, rows=compare_rows(summary), curves=curves,
                         test=run_b, errors=errors)


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
    A model's polynomial as PX4 and ArduPilot parameters.

    Attributes
    ----------
    model_path : str
        The model.json exported.
    px4 : list of (str, value, int)
        ``TC_*`` parameters (name, value, MAVLink type).
    ardupilot : list of (str, float)
        ``INS_TCAL*`` (and offset) parameters.
    notes : tuple of str
        What loading the model noticed.
    accel : bool
        Whether the accelerometer's polynomial was exported too.

    """

    model_path: str
    px4: list[tuple[str, Any, int]]
    ardupilot: list[tuple[str, Any]]
    notes: tuple[str, ...] = ()
    accel: bool = False

    def as_dict(self) -> dict[str, Any]:
        """
        Return export.json.

        Returns
        -------
        dict

        """
        return registry.to_jsonable({
            'tool': f'{PROG} export', 'package_version': __version__,
            'model': self.model_path, 'accelerometer': self.accel, 'notes': list(self.notes),
            'px4': {name: value for name, value, _ in self.px4},
            'ardupilot': dict(self.ardupilot),
            'references': {
                'px4': 'https://docs.px4.io/main/en/advanced_config/'
                       'sensor_thermal_calibration.html',
                'ardupilot': 'https://ardupilot.org/copter/docs/common-imutempcal.html'}})


def export(*, model_path: str, px4_instance: int = 0, gyro_device_id: int = 0,
           accel_device_id: int = 0, ardupilot_imu: int = 1, gyro_offsets: bool = True,
           cal_temp_c: float | None = None) -> ExportResult:
    """
    Turn a poly3 model.json into PX4 and ArduPilot parameters (``gyro_noise_thermal export``).

    Parameters
    ----------
    model_path : str
        model.json of ``fit --method poly3``.
    px4_instance : int, keyword-only
        PX4 sensor instance (0..2).
    gyro_device_id, accel_device_id : int, keyword-only
        PX4 ``TC_G0_ID`` / ``TC_A0_ID``.
    ardupilot_imu : int, keyword-only
        ArduPilot IMU number (1..3).
    gyro_offsets : bool, keyword-only
        Also write ArduPilot's gyro offsets and CALTEMP (the whole model).
    cal_temp_c : float, optional, keyword-only
        ArduPilot CALTEMP of those offsets (default the model's T_ref).

    Returns
    -------
    ExportResult

    """
    from ..thermal.export import (ardupilot_parameters, calibration_of, px4_parameters)

    model = registry.load_model(model_path)
    gyro = calibration_of(model.method)
    accel = None if model.accel is None else calibration_of(model.accel, unit='m/s^2')
    px4 = px4_parameters(gyro, accel, instance=px4_instance, gyro_device_id=gyro_device_id,
                         accel_device_id=accel_device_id)
    ardupilot = ardupilot_parameters(gyro, accel, imu=ardupilot_imu, cal_temp_c=cal_temp_c,
                                     gyro_offsets=gyro_offsets)
    return ExportResult(model_path=str(model_path), px4=px4, ardupilot=ardupilot,
                        notes=model.notes, accel=accel is not None)


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

    comment = f'model {result.model_path}, gyro_noise_ros {__version__}'
    with staged_output(out_dir) as stage:
        write_px4_params(stage / 'thermal_px4.params', result.px4, comment=comment)
        write_ardupilot_parm(stage / 'thermal_ardupilot.parm', result.ardupilot,
                             comment=comment)
        _write(stage / 'export.json', _json(result.as_dict()))
    return [Path(out_dir) / n for n in ('thermal_px4.params', 'thermal_ardupilot.parm',
                                        'export.json')]


# ---------------------------------------------------------------------------------------------
# held-out shapes (the docs' comparison table)

#: Train -> test shape pairs of the held-out table: a replicate, then runs shaped differently.
HELDOUT_PAIRS = (('heating', 'heating'), ('heating', 'cooling'), ('heating', 'cycle'),
                 ('staircase', 'cool_reheat'), ('cycle', 'sine'))
#: Methods of the held-out table: (label, --method, options).
HELDOUT_METHODS: tuple[tuple[str, str, dict[str, object]], ...] = (
    ('poly3', 'poly3', {}), ('linear_tdt', 'linear_tdt', {}),
    ('linear_tdt rate_degree=3', 'linear_tdt', {'rate_degree': 3}),
    ('bp', 'bp', {}), ('bp shortcut=False', 'bp', {'shortcut': False}))


def heldout_scores(*, pairs: Sequence[tuple[str, str]] = HELDOUT_PAIRS,
                   methods: Sequence[tuple[str, str, dict[str, Any]]] = HELDOUT_METHODS,
                   seeds: Sequence[int] = (1, 2, 3, 4, 5), rate_hz: float = 20.0,
                   hours: float = 1.0,
                   progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """
    Score methods on simulated held-out pairs against the least-squares oracle.

    For every pair and seed: :func:`~gyro_noise_ros.thermal.simulate.simulate_pair` (training
    run ``hours`` long at ``rate_hz``, the test run its whole profile at the same compression),
    each method fitted on the training run and applied to the test run, the residual drift
    (std of 60-s means, deg/s) averaged over the three axes; the same for the raw test run and
    the two oracles (:func:`oracle_scores`).

    Parameters
    ----------
    pairs : sequence of (str, str), keyword-only
        Train and test shapes.
    methods : sequence of (str, str, dict), keyword-only
        (label, method name, constructor options).
    seeds : sequence of int, keyword-only
        Seeds of the pairs.
    rate_hz, hours : float, keyword-only
        Sample rate (Hz) and training run length (h).
    progress : callable, optional, keyword-only
        Called with one line per pair and seed.

    Returns
    -------
    list of dict
        One row per pair and method (``raw``, the oracles, then ``methods``): ``train``,
        ``test``, ``method``, ``per_seed_deg_s``, ``mean_deg_s``, ``ratio_to_oracle`` (mean over
        seeds of the method / mean of the true-terms oracle), ``seed_ratios`` (per seed),
        ``rate_outside_fraction`` (share of test samples outside the trained dT range, mean
        over seeds; None for the rows without a model).

    """
    from ..thermal.simulate import make_profile, simulate_pair, ThermalModel

    model = ThermalModel()
    rows = []
    for train_shape, test_shape in pairs:
        scores: dict[str, list[Any]] = {}
        outside: dict[str, list[dict[str, Any]]] = {}
        for seed in seeds:
            (_, train, ta), (_, test, tb) = simulate_pair(
                seed=seed, rate_hz=rate_hz, hours=hours, model=model,
                profile=make_profile(train_shape), test_profile=make_profile(test_shape))
            oracle = oracle_scores(train, ta, test, tb, model)
            raw: list[Any] = [
                _num(noise_metrics(test.gyro_rad_s[:, a], rate_hz).residual_drift_deg_s)
                for a in range(3)]
            scores.setdefault('raw', []).append(float(np.mean(raw)))
            scores.setdefault('oracle: true terms', []).append(
                oracle['true_terms']['mean_residual_drift_deg_s'])
            scores.setdefault('oracle: measured T, dT', []).append(
                oracle['measured_terms']['mean_residual_drift_deg_s'])
            for label, name, options in methods:
                fitted = registry.fit_method(name, train, rng=np.random.default_rng(seed),
                                             accel=False, **options)
                out = np.asarray(fitted.method.apply(test), dtype=float)
                drift = [noise_metrics(out[:, a], rate_hz).residual_drift_deg_s
                         for a in range(3)]
                scores.setdefault(label, []).append(float(np.mean(drift)))
                outside.setdefault(label, []).append(_range(fitted, test).as_dict())
            if progress is not None:
                progress(f'{train_shape} -> {test_shape}, seed {seed}: done')
        base = np.asarray(scores['oracle: true terms'])
        for label, per_seed in scores.items():
            values = np.asarray(per_seed)
            reps = outside.get(label)
            rows.append({
                'train': train_shape, 'test': test_shape, 'method': label,
                'per_seed_deg_s': values.tolist(), 'mean_deg_s': float(values.mean()),
                'ratio_to_oracle': float(values.mean() / base.mean()),
                'seed_ratios': (values / base).tolist(),
                'rate_outside_fraction': None if reps is None else float(np.mean(
                    [(r['rate_below'] + r['rate_above']) / r['samples'] for r in reps]))})
    return rows
