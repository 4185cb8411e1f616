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
The ``gyro_noise_explain`` workflow: read a recording, run the discrepancy loop per axis, write.

Three steps, each usable on its own (the command line runs them in order, docs/discrepancy.md):

1. :func:`prepare_explain` reads the recording once through the one input layer
   (:mod:`gyro_noise_ros.bag.inputs`), builds each axis' :class:`~..explain.inputs.Measurement`,
   keeps the window and the static segment asked for, and refuses bad input (exit codes 3 and 4)
   before any long work;
2. :func:`run_explain` runs :func:`gyro_noise_ros.explain.workflow.explain` on each axis and
   returns an :class:`ExplainRun` carrying every number, verdict and line the tool reports;
3. :func:`write_explain` writes ``explain.json``, ``report.md``, ``report.html`` and the
   figures, one folder per axis plus an index when there are several, all or nothing
   (:func:`gyro_noise_ros.outputs.staged_output`).

``ExplainRun.as_dict()`` is exactly the top ``explain.json`` (the index of a multi-axis run, the
axis' own document otherwise); ``AxisExplained.as_dict()`` is exactly an axis' ``explain.json``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
import json
import math
from pathlib import Path

from ..bag.inputs import read_imu, recorded_axes
from ..core.timebase import RATE_RANGE_HZ
from ..errors import OutputError, ParameterError
from ..explain import report, workflow
from ..explain.inputs import cut_record, from_record
from ..htmlreport.explain import write_explain_html
from ..outputs import staged_output, StrPath

__all__ = ['AxisExplained', 'ExplainInput', 'ExplainParams', 'ExplainRun', 'MAX_RECORDS',
           'RATE_RANGE_HZ', 'check_output', 'prepare_explain', 'run_explain', 'write_explain']

#: Most ensemble members or bootstrap records: each costs a simulated copy of the record (time
#: and memory), 16 and 20 are the defaults; beyond this the number is a typo, not a wish.
MAX_RECORDS = 10000
AXIS_CHOICES = ('x', 'y', 'z', 'all')
STATIC_CHOICES = ('auto', 'off')


@dataclass(frozen=True)
class ExplainParams:
    """
    What to explain and how (the options of ``gyro_noise_explain``).

    Attributes
    ----------
    path : str
        Recording: rosbag2 / ROS 1 bag, CSV or PX4 ULog (:mod:`gyro_noise_ros.bag.inputs`).
    axis : str
        ``'x'``, ``'y'``, ``'z'`` or ``'all'`` (the axes the input holds, one folder each).
    topic, temperature_topic : str or None
        Imu and Temperature topics (naming a temperature topic makes temperature required).
    rate_hz : float or None
        Nominal rate (Hz): required for a CSV without a time column, else it overrides the
        estimate from the stamps.
    require_temperature : bool
        Refuse an input without temperature.
    start_s, end_s : float or None
        Analyse from / up to this many seconds after the first sample.
    static : str
        ``'auto'``: keep the longest static segment; ``'off'``: everything.
    seed : int
        Ensemble seed (>= 0).
    ensemble : int
        Members per ensemble (4 .. :data:`MAX_RECORDS`).
    max_steps : int
        Most effects to add (>= 0).
    bootstrap : int
        Records simulated for the parameter uncertainties (0: off, else 5 ..
        :data:`MAX_RECORDS`).

    Raises
    ------
    ParameterError
        A value outside its range (exit code 2), said with the option's name.

    """

    path: str
    axis: str = 'all'
    topic: str | None = None
    temperature_topic: str | None = None
    rate_hz: float | None = None
    require_temperature: bool = False
    start_s: float | None = None
    end_s: float | None = None
    static: str = 'auto'
    seed: int = 0
    ensemble: int = 16
    max_steps: int = 6
    bootstrap: int = workflow.DEFAULT_BOOTSTRAP

    def __post_init__(self) -> None:
        object.__setattr__(self, 'path', str(self.path))
        if self.axis not in AXIS_CHOICES:
            raise ParameterError(f"--axis must be one of {', '.join(AXIS_CHOICES)}, got "
                                 f'{self.axis!r}')
        if self.static not in STATIC_CHOICES:
            raise ParameterError(f"--static must be 'auto' or 'off', got {self.static!r}")
        if not 4 <= self.ensemble <= MAX_RECORDS:
            raise ParameterError(
                f'--ensemble must be 4 to {MAX_RECORDS} members, got {self.ensemble}')
        if self.max_steps < 0:
            raise ParameterError(f'--max-steps must be >= 0, got {self.max_steps}')
        if self.seed < 0:
            raise ParameterError(f'--seed must be >= 0, got {self.seed}')
        if self.bootstrap != 0 and not 5 <= self.bootstrap <= MAX_RECORDS:
            raise ParameterError(f'--bootstrap must be 0 (off) or 5 to {MAX_RECORDS} records, '
                                 f'got {self.bootstrap}')
        if self.rate_hz is not None and not RATE_RANGE_HZ[0] <= self.rate_hz <= RATE_RANGE_HZ[1]:
            raise ParameterError(f'--rate-hz must be {RATE_RANGE_HZ[0]:g} to '
                                 f'{RATE_RANGE_HZ[1]:g} Hz, got {self.rate_hz}')
        for name, value in (('--start', self.start_s), ('--end', self.end_s)):
            if value is not None and not (value >= 0 and math.isfinite(value)):
                raise ParameterError(f'{name} must be a number of seconds >= 0, got {value}')
        if self.start_s is not None and self.end_s is not None and self.end_s <= self.start_s:
            raise ParameterError(
                f'--end ({self.end_s:g} s) must be after --start ({self.start_s:g} s)')


@dataclass(frozen=True)
class ExplainInput:
    """
    The recording read and cut, one :class:`~..explain.inputs.Measurement` per axis.

    Attributes
    ----------
    params : ExplainParams
        What was asked.
    measurements : tuple of Measurement
        One per axis analysed, in x, y, z order.
    left_out : tuple of dict
        Per axis (the same for every axis: one window for all), the samples left out:
        ``before_start``, ``after_end``, ``motion`` and, when motion was cut,
        ``static_segment_s``, ``static_segments_s`` and ``cut_s`` (s after the first sample;
        :func:`gyro_noise_ros.explain.inputs.cut_record`).
    warnings : tuple of str
        What the user must know about the input (the samples left out, in the sentence
        ``gyro_noise_analyze`` prints, and the stamp warnings of the first axis), one line each.

    """

    params: ExplainParams
    measurements: tuple
    left_out: tuple
    warnings: tuple


@dataclass(frozen=True)
class AxisExplained:
    """
    The result of one axis.

    Attributes
    ----------
    axis : str
        ``'x'``, ``'y'`` or ``'z'``.
    result : gyro_noise_ros.explain.workflow.ExplainResult
        The workflow's result (baseline, steps, gaps, comparisons, uncertainties).
    left_out : dict
        Samples left out before the analysis (:class:`ExplainInput`).
    folder : str
        Sub-folder of the output ('' for a single axis, ``axis_<a>`` otherwise).

    """

    axis: str
    result: workflow.ExplainResult
    left_out: dict
    folder: str = ''

    @property
    def verdict(self) -> str:
        """Return the one-paragraph verdict of the axis (as the report says it)."""
        return report.verdict(self.result)

    @property
    def parameter_lines(self) -> list:
        """Return one line per named effect: its parameters as value ± stderr, or bounds."""
        return report.parameter_lines(self.result)

    def as_dict(self) -> dict:
        """Return exactly this axis' ``explain.json`` (docs/discrepancy.md)."""
        data = self.result.to_dict()
        data['input']['left_out'] = dict(self.left_out)
        data['verdict'] = self.verdict
        return data


@dataclass(frozen=True)
class ExplainRun:
    """
    The result of ``gyro_noise_explain``: every axis analysed.

    Attributes
    ----------
    params : ExplainParams
        What was asked.
    axes : tuple of AxisExplained
        One per axis, in x, y, z order.
    warnings : tuple of str
        Warnings about the input (:class:`ExplainInput`).

    """

    params: ExplainParams
    axes: tuple
    warnings: tuple = field(default=())

    @property
    def indexed(self) -> bool:
        """Tell whether the run writes one folder per axis and an index (several axes)."""
        return len(self.axes) > 1

    def as_dict(self) -> dict:
        """Return exactly the top ``explain.json``: the index, or the single axis' document."""
        if not self.indexed:
            return self.axes[0].as_dict()
        return {'axes': {a.axis: {'verdict': a.verdict,
                                  'explain_json': f'{a.folder}/explain.json',
                                  'report_md': f'{a.folder}/report.md'} for a in self.axes}}


def prepare_explain(params: ExplainParams) -> ExplainInput:
    """
    Read the recording once and cut each axis to what is analysed (module doc, step 1).

    Parameters
    ----------
    params : ExplainParams
        What to explain.

    Returns
    -------
    ExplainInput

    Raises
    ------
    BagError
        The recording cannot be read (exit code 3).
    InputDataError
        It holds nothing to analyse: NaN/Inf, non-physical, constant, too short, nothing left
        after the window, a temperature asked for and missing (exit code 4).
    ParameterError
        A CSV without a time column and no ``rate_hz`` (exit code 2).

    """
    axes = recorded_axes(params.path) if params.axis == 'all' else (params.axis,)
    require_temperature = params.require_temperature or params.temperature_topic is not None
    record = read_imu(params.path, topic=params.topic,
                      temperature_topic=params.temperature_topic, rate_hz=params.rate_hz,
                      gyro_axes=axes)
    # every axis is checked whole first (NaN, non-physical, constant: exit 4 naming the sample)
    for axis in axes:
        from_record(record, axis=axis, rate_hz=params.rate_hz,
                    require_temperature=require_temperature)
    # then one window for every axis, by the rule analyze uses (core/segments.py), said once
    cut, left, sentence = cut_record(record, start_s=params.start_s, end_s=params.end_s,
                                     static=params.static, window_names=('--start', '--end'))
    measurements = tuple(from_record(cut, axis=axis, rate_hz=params.rate_hz,
                                     require_temperature=require_temperature) for axis in axes)
    first = measurements[0]
    warnings = ([sentence] if sentence else []) + list(first.timebase.warnings
                                                       if first.timebase else ())
    return ExplainInput(params=params, measurements=measurements,
                        left_out=(left,) * len(measurements), warnings=tuple(warnings))


def run_explain(prepared: ExplainInput, *, progress: Callable[[str], None] | None = None,
                mapper: Callable = map) -> ExplainRun:
    """
    Run the discrepancy workflow on every axis of a prepared input (module doc, step 2).

    Parameters
    ----------
    prepared : ExplainInput
        From :func:`prepare_explain`.
    progress : callable, optional, keyword-only
        Called with one-line status texts (``axis x (1 of 3)``, then the workflow's own).
    mapper : callable, keyword-only
        ``map``-like scheduler of the ensemble members and bootstrap records (a Dask
        executor's ``map``); the result does not depend on it.

    Returns
    -------
    ExplainRun

    """
    params = prepared.params
    count = len(prepared.measurements)
    axes = []
    for k, (meas, left) in enumerate(zip(prepared.measurements, prepared.left_out)):
        if progress is not None and count > 1:
            progress(f'axis {meas.axis} ({k + 1} of {count})')
        # through the module, so a test (or a scheduler) can put another workflow in its place
        result = workflow.explain(meas, seed=params.seed, ensemble=params.ensemble,
                                  max_steps=params.max_steps, bootstrap=params.bootstrap,
                                  progress=progress, mapper=mapper)
        axes.append(AxisExplained(axis=meas.axis, result=result, left_out=left,
                                  folder=f'axis_{meas.axis}' if count > 1 else ''))
    return ExplainRun(params=params, axes=tuple(axes), warnings=prepared.warnings)


def check_output(out_dir: StrPath) -> None:
    """
    Make sure the outputs can be staged in ``out_dir`` before the long work (nothing is written).

    Parameters
    ----------
    out_dir : str or os.PathLike
        The output folder (created if missing, as the run would).

    Raises
    ------
    OutputError
        It cannot be created or written (exit code 6).

    """
    with staged_output(out_dir):
        pass


def write_explain(run: ExplainRun, out_dir: StrPath, *, html: bool = True,
                  command: Sequence[str] | None = None) -> list:
    """
    Write every axis' explain.json, report.md, report.html and figures, and the index (step 3).

    Parameters
    ----------
    run : ExplainRun
        From :func:`run_explain`.
    out_dir : str or os.PathLike
        Output folder (created); the files appear there together, or not at all.
    html : bool, keyword-only
        Write each axis' report.html beside its explain.json (:mod:`..htmlreport.explain`).
    command : sequence of str, optional, keyword-only
        The command line, shown in report.html.

    Returns
    -------
    list of str
        The files written, relative to ``out_dir``.

    Raises
    ------
    OutputError
        A file cannot be written (exit code 6).

    """
    files = []
    with staged_output(out_dir) as stage:
        for axis in run.axes:
            folder = stage / axis.folder
            try:
                folder.mkdir(exist_ok=True)
            except OSError as err:
                raise OutputError(
                    f'cannot create {str(folder)!r}: {err.strerror or err}') from err
            data = axis.as_dict()
            written = report.write_files(axis.result, folder, data=data)
            if html:
                written = [*written, write_explain_html(axis.result, folder, command=command,
                                                        data=data).name]
            files += [str(Path(axis.folder) / name) if axis.folder else name for name in written]
        if run.indexed:
            files += _write_index(stage, run)
    return files


def _write_index(stage: Path, run: ExplainRun) -> list:
    """One report.md and explain.json for a multi-axis run: every axis' verdict and report."""
    lines = ['# gyro_noise_explain: all axes', '']
    for axis in run.axes:
        lines.append(f'* axis {axis.axis}: {axis.verdict}')
        lines += [f'  * {line}' for line in axis.parameter_lines]
    try:
        for axis in run.axes:
            text = (stage / axis.folder / 'report.md').read_text()
            text = text.replace('](', f']({axis.folder}/').replace('\n# ', '\n## ')
            if text.startswith('# '):
                text = '#' + text
            lines += ['', f'<!-- axis {axis.axis} -->', text]
        (stage / 'report.md').write_text('\n'.join(lines) + '\n')
        (stage / 'explain.json').write_text(json.dumps(run.as_dict(), indent=2) + '\n')
    except OSError as err:
        raise OutputError(f'cannot write the results: {err.strerror or err}') from err
    return ['explain.json', 'report.md']
