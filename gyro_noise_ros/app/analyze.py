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
The offline analysis: bags in, summary.json and its sibling files out (paper 000).

Shared by ``gyro_noise_analyze``, bench and tools. :func:`analyze_bags` takes one
:class:`AnalyzeParams`, reads rosbag2 (sqlite3, MCAP), ROS 1 bags, CSV tables and PX4 ULogs
through :mod:`gyro_noise_ros.bag` in batches (constant memory apart from one small row per
chunk), runs :class:`gyro_noise_ros.core.engine.NoiseEngine` with the chunk identification
spread over ``jobs`` worker processes (at most ``4 x jobs`` plus one decoded batch of chunks in
flight) or a Dask cluster, and returns an :class:`AnalyzeResult` whose
:meth:`~AnalyzeResult.as_dict` is summary.json. The files (chunks.csv, summary.json,
summary.md, allan.csv, imu.yaml, curves.npz, PNG figures, report.html) are written into a
staging folder during the run and published in ``out_dir`` only when the whole run succeeded.
Formats: ``docs/offline_tool.md``.

The workflow, step by step: check every input (:func:`_open_inputs`), analyse each bag in one
read when it is static throughout, else in a prepass and a pass over its longest static segment
(:func:`_analyze_one`, :func:`_analysis_pass`), summarise it (:func:`_bag_doc`; a record shorter
than one chunk gets its Allan deviation and readout only, ``allan_only`` saying what is not
computed), refuse a run that analysed nothing (:func:`_check_analysed`), and write
(:func:`_write_results`).
"""

import collections
from collections.abc import Callable, Iterator
import contextlib
import dataclasses
from dataclasses import dataclass, field
import datetime
import functools
import math
from pathlib import Path
import sys
import time
from typing import Any

import numpy as np
import threadpoolctl

from .. import __version__
from ..analysis.csv_tables import allan_curve, ChunkCsvWriter, write_allan_csv
from ..analysis.figures import allan_curves, plot_allan, plot_curves, plot_per_chunk
from ..analysis.imu_yaml import DEFAULT_IMU_TOPIC, kalibr_noise, write_imu_yaml
from ..analysis.summary_json import (accelerometer_readout_dict, axis_summary_dict, json_num,
                                     write_json)
from ..analysis.summary_md import summary_markdown
from ..bag import find_imu_topic, ImuBagReader
from ..bag.inputs import is_table, open_imu
from ..cluster import check_jobs, DaskExecutor, make_executor
from ..core.allan import AllanAccumulator
from ..core.engine import (analyze_chunk, AXES, EngineConfig, identifier_for, NoiseEngine)
from ..core.fractional import parse_grid
from ..core.health import HealthThresholds, reference_per_axis
from ..core.plausible import mask_non_physical, MAX_RATE_RAD_S, MAX_SPECIFIC_FORCE_M_S2
from ..core.readout import read_allan
from ..core.segments import (Cut, left_out_sentence, segment_left_out, StaticSegment,
                             WindowStats)
from ..core.timebase import rescale_allan
from ..errors import InputDataError, nothing_left_error, OutputError, ParameterError
from ..htmlreport.analyze import write_analyze_html
from ..outputs import staged_output

#: The tool named in summary.json and in the warnings.
TOOL = 'gyro_noise_analyze'
#: Messages decoded per batch (bounds the decode memory: ~0.4 KB per message).
DEFAULT_BATCH = 65536
#: Chunks per bag and axis whose var(alpha), J(alpha) curves are kept for the heat maps.
DEFAULT_CURVES = 200


def _labels(paths: list[str], labels: tuple[str, ...] | None) -> list[str]:
    if labels is None:
        names = [Path(p).name[:-len(Path(p).suffix)] if Path(p).suffix in ('.bag', '.mcap', '.db3')
                 else Path(p).name for p in paths]
    else:
        if len(labels) != len(paths):
            raise ParameterError(
                f'--label needs one name per bag: {len(paths)} bag(s), {len(labels)} label(s)')
        names = list(labels)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ParameterError(f'bag labels must be unique, got duplicates {dup}; use --label')
    return names


@dataclass(frozen=True)
class AnalyzeParams:
    """
    What to analyse and how (the options of gyro_noise_analyze).

    Attributes
    ----------
    paths : tuple of str
        Bags, in table order.
    out_dir : str
        Output directory (created).
    labels : tuple of str, optional
        One unique label per bag (default: bag names).
    topic, temperature_topic : str, optional
        Topics (default: found per bag).
    config : EngineConfig
        Engine options.
    jobs : int
        Worker processes (1: analyse in this process).
    reference : str, optional
        summary.json of a reference recording (health verdicts).
    reference_bag : str, optional
        Bag label inside ``reference`` when it holds several bags.
    thresholds : HealthThresholds
        Health thresholds.
    figures : bool
        Write PNG figures.
    html : bool
        Write report.html (:mod:`..htmlreport.analyze`).
    curves : int
        Chunks per bag and axis whose curves are kept.
    batch_size : int
        Messages per decoded batch.
    progress : bool
        Show progress on stderr.
    command : tuple of str, optional
        Command line recorded in summary.json.
    start_s, end_s : float, optional
        Analyse only samples from ``start_s`` to ``end_s`` seconds after each bag's first sample.
    static : {'auto', 'off'}
        'auto': find the longest static segment (core/segments.py) and skip motion, saying so.
    scheduler : str, optional
        Dask scheduler address: the chunks go to that cluster instead of ``jobs`` local
        processes, at most ``2 x max(jobs, cluster threads)`` in flight (:mod:`..cluster`).

    Raises
    ------
    ParameterError
        An option out of its domain (checked on construction, before anything is read).

    """

    paths: tuple[str, ...]
    out_dir: str
    labels: tuple[str, ...] | None = None
    topic: str | None = None
    temperature_topic: str | None = None
    config: EngineConfig = field(default_factory=EngineConfig)
    jobs: int = 1
    reference: str | None = None
    reference_bag: str | None = None
    thresholds: HealthThresholds = field(default_factory=HealthThresholds)
    figures: bool = True
    html: bool = True
    curves: int = DEFAULT_CURVES
    batch_size: int = DEFAULT_BATCH
    progress: bool = False
    command: tuple[str, ...] | None = None
    start_s: float | None = None
    end_s: float | None = None
    static: str = 'auto'
    scheduler: str | None = None

    def __post_init__(self) -> None:
        setattr_ = functools.partial(object.__setattr__, self)
        setattr_('paths', tuple(str(p) for p in self.paths))
        setattr_('out_dir', str(self.out_dir))
        if self.labels is not None:
            setattr_('labels', tuple(self.labels))
        if self.reference is not None:
            setattr_('reference', str(self.reference))
        if self.command is not None:
            setattr_('command', tuple(self.command))
        if self.batch_size < 1:
            raise ParameterError(f'--batch-size must be >= 1, got {self.batch_size}')
        if self.static not in ('auto', 'off'):
            raise ParameterError(f"--static must be 'auto' or 'off', got {self.static!r}")
        for name, value in (('--start', self.start_s), ('--end', self.end_s)):
            if value is not None and not (math.isfinite(value) and value >= 0):
                raise ParameterError(f'{name} must be a number of seconds >= 0, got {value}')
        if self.start_s is not None and self.end_s is not None and self.end_s <= self.start_s:
            raise ParameterError(f'--end ({self.end_s:g} s) must be after --start '
                                 f'({self.start_s:g} s)')
        setattr_('jobs', int(self.jobs))
        if self.scheduler is None:
            check_jobs(self.jobs)  # local processes: no more than the machine can run
        elif self.jobs < 1:
            raise ParameterError(f'--jobs must be >= 1, got {self.jobs}')
        if self.curves < 0:
            raise ParameterError(f'--curves must be >= 0, got {self.curves}')
        self.names  # noqa: B018 (labels checked now, not after the first bag)

    @property
    def names(self) -> list[str]:
        """List of str: the bag labels (``labels``, else the bag names), unique."""
        return _labels(list(self.paths), self.labels)


@dataclass(frozen=True)
class AnalyzeResult:
    """
    Everything gyro_noise_analyze reports; :meth:`as_dict` is summary.json.

    Attributes
    ----------
    tool, version, created_utc : str
        The tool, its version and the time of the run (UTC, ISO 8601).
    command : list of str or None
        The command line.
    options : dict
        The options in effect (engine configuration, jobs, topics, reference, thresholds).
    bags : tuple of dict
        One summary per bag (``docs/offline_tool.md``: counts, time base, warnings, per-axis
        statistics, Allan readout, health verdicts).
    timing : dict
        Seconds: ``total_s``, ``decode_s``, ``wait_s`` (not in summary.json).
    files : tuple of str
        The files written, under their published names.
    alphas : numpy.ndarray
        The order grid (for curves.npz and the curve figures).
    per_chunk, curves, allan, accelerometer, accel_allan : dict
        What the figures, report.html, curves.npz, allan.csv and imu.yaml are drawn from:
        per-chunk (t, bias, variance, alpha_var, alpha_corr) rows per axis, kept var/J curves
        per (label, axis), Allan results per (label, axis), the accelerometer readouts per
        label and the accelerometer's Allan results per (label, axis).

    """

    tool: str
    version: str
    created_utc: str
    command: list[str] | None
    options: dict[str, Any]
    bags: tuple[dict[str, Any], ...]
    timing: dict[str, float] = field(default_factory=dict)
    files: tuple[str, ...] = ()
    alphas: np.ndarray | None = field(default=None, repr=False)
    per_chunk: dict[str, list] = field(default_factory=dict, repr=False)
    curves: dict[tuple, list] = field(default_factory=dict, repr=False)
    allan: dict[tuple, tuple] = field(default_factory=dict, repr=False)
    accelerometer: dict[str, dict] = field(default_factory=dict, repr=False)
    accel_allan: dict[tuple, Any] = field(default_factory=dict, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """Return summary.json as a dict (bag entries shared, not copied)."""
        return {'tool': self.tool, 'version': self.version, 'created_utc': self.created_utc,
                'command': self.command, 'options': self.options, 'bags': list(self.bags)}


class _Progress:
    """Progress on stderr: a refreshed line on a TTY, else one line per 10 % (logs, CI)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = bool(enabled)
        self.tty = self.enabled and sys.stderr.isatty()
        self._last = 0.0
        self._decile = 0

    def restart(self) -> None:
        self._last = 0.0
        self._decile = 0

    def update(self, label: str, done: int, total: int, chunks: int, started: float, *,
               final: bool = False) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        rate = done / max(now - started, 1e-9)
        if not self.tty:
            decile = int(10 * done / total) if total else 0
            if decile <= self._decile and not (final and self._decile < 10):
                return
            self._decile = 10 if final else decile
            percent = 100 if final else 10 * decile
            sys.stderr.write(f'{label}: {percent}% {done}/{total} messages, {chunks} chunks, '
                             f'{rate:,.0f} samples/s\n')
            sys.stderr.flush()
            return
        if not final and now - self._last < 0.5:
            return
        self._last = now
        pct = f'{100.0 * done / total:5.1f}%' if total else '  ?  '
        sys.stderr.write(
            f'\r{label}: {pct} {done}/{total} messages, {chunks} chunks, {rate:,.0f} samples/s   ')
        if final:
            sys.stderr.write('\n')
        sys.stderr.flush()


def warn(text: str) -> None:
    """
    Print one warning line on stderr.

    Parameters
    ----------
    text : str
        The warning, without the program name.

    """
    print(f'{TOOL}: warning: {text}', file=sys.stderr, flush=True)


def parse_order_grid(text: str) -> np.ndarray:
    """
    Parse ``--order-grid START:STOP:STEP`` and refuse degenerate or out-of-domain grids.

    Parameters
    ----------
    text : str
        ``START:STOP:STEP``; both ends are included, so STOP - START must be a whole number of
        steps, with at least one step.

    Returns
    -------
    numpy.ndarray
        The grid.

    Raises
    ------
    ParameterError
        Negative orders or orders above 2 (the model's domain, paper 000: 0 <= alpha <= 2),
        fewer than 2 points (STOP <= START or STEP > STOP - START), STOP not on the grid.

    """
    alphas = parse_grid(text)
    start, stop, step = (float(v) for v in str(text).split(':'))
    if start < 0.0 or stop > 2.0:
        raise ParameterError(f'--order-grid {text}: orders must lie in 0..2 (the fractional-noise '
                             f'model of the paper), got {start:g}..{stop:g}')
    if stop <= start or step > stop - start:
        raise ParameterError(f'--order-grid {text}: needs at least two points (STOP > START and '
                             'STEP <= STOP - START)')
    steps = (stop - start) / step
    if abs(steps - round(steps)) > 1e-9 * max(1.0, steps):
        raise ParameterError(f'--order-grid {text}: STOP - START is not a whole number of steps, '
                             'so STOP would not be on the grid (both ends are included)')
    return alphas


def _one_blas_thread(func: Callable) -> Callable:
    """
    Run ``func`` with one BLAS thread in this process (and so in the workers it forks).

    The identification's BLAS calls are small matrix products (it holds them to one thread
    itself, core/fractional.py); OpenBLAS' own threads gain nothing there and spin after each
    call, taking a core from the worker processes: measured 1.07x less CPU end to end with
    ``--jobs 2`` on 2 cores (docs/scale.md). The results do not change (each dot product is one
    thread's either way).
    """
    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with threadpoolctl.threadpool_limits(limits=1, user_api='blas'):
            return func(*args, **kwargs)
    return wrapper


@contextlib.contextmanager
def _writing() -> Iterator[None]:
    """Turn an OS error while writing the results (disk full, quota) into OutputError."""
    try:
        yield
    except OSError as err:
        where = f' ({err.filename})' if err.filename else ''
        raise OutputError(f'cannot write the results: {err.strerror or err}{where}') from err


class _ChunkRows(ChunkCsvWriter):
    """chunks.csv that can take back the rows of a bag (a speculative pass that was not kept)."""

    def write(self, *args: Any, **kwargs: Any) -> None:
        with _writing():
            super().write(*args, **kwargs)

    def mark(self) -> tuple[int, int]:
        self._fh.flush()
        return self._fh.tell(), self.rows

    def rollback(self, mark: tuple[int, int]) -> None:
        self._fh.flush()
        self._fh.seek(mark[0])
        self._fh.truncate()
        self.rows = mark[1]


@dataclass(frozen=True)
class _Stores:
    """Where the passes of one run put what they produce (fixed containers)."""

    csv: _ChunkRows
    per_chunk: dict[str, list] = field(default_factory=dict)
    curves: dict[tuple, list] = field(default_factory=dict)
    allan: dict[tuple, tuple] = field(default_factory=dict)
    accel_allan: dict[tuple, Any] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=lambda: {'decode_s': 0.0, 'wait_s': 0.0})


@dataclass(frozen=True)
class _Run:
    """What every bag of one run shares: the options, the reference, the workers, the stores."""

    params: AnalyzeParams
    ref: dict[str, Any]
    pool: Any
    jobs: int
    stores: _Stores


@dataclass(frozen=True)
class _Bag:
    """One bag to analyse."""

    path: str
    label: str
    topic: str


@dataclass(frozen=True)
class _PassState:
    """What one read of a bag leaves for its summary."""

    engine: NoiseEngine
    warnings: list[str]
    time_source: str
    left: dict[str, int]
    first_ns: int | None
    last_ns: int
    accel: '_AccelAllan'
    rows: dict[str, list]
    done: int
    frame_id: str | None
    storage: str
    undecodable: int
    temperature_topic: str | None
    non_physical: dict[str, int]


@_one_blas_thread
def analyze_bags(params: AnalyzeParams) -> AnalyzeResult:
    """
    Analyse bags and write the report files (the body of gyro_noise_analyze).

    Parameters
    ----------
    params : AnalyzeParams
        The bags, the output folder and the options.

    Returns
    -------
    AnalyzeResult
        Every number of summary.json, the timing and the files written.

    Raises
    ------
    GyroNoiseError
        Its subclasses with their exit codes: unreadable input (3), nothing to analyse (4), a
        lost cluster (5), unwritable output (6).

    """
    config = params.config
    ref = reference_per_axis(params.reference, config.axes,
                             bag=params.reference_bag) if params.reference is not None else {}
    with contextlib.ExitStack() as stack:
        # Every file is written into a hidden staging folder inside --out and published there
        # only when the whole run succeeded: an error or an interrupt leaves no result.
        first_reader = None
        try:
            topics, first_reader = _open_inputs(params)
            out = stack.enter_context(staged_output(params.out_dir))
            started = time.perf_counter()
            result = _run_bags(params, ref, topics, out, first_reader)
        finally:
            if first_reader is not None:
                first_reader.close()  # idempotent; open here only when the run failed before it
        files = _write_results(out, result, figures=params.figures, html=params.html)
        result = dataclasses.replace(
            result, timing={'total_s': time.perf_counter() - started, **result.timing})
    # the files under their published names
    return dataclasses.replace(
        result, files=tuple(str(Path(params.out_dir) / Path(f).name) for f in files))


def _open_inputs(params: AnalyzeParams) -> tuple[list[str], ImuBagReader | None]:
    """
    Resolve every bag's topic before any long work; return them and the first bag's reader.

    Fail fast on any unreadable bag or unresolvable topic before hours of work on the others.
    The first bag's reader stays open for its analysis: opening a sqlite3 bag counts its
    messages (a scan of the whole table, about 0.25 s per million messages).
    """
    topics, first_reader = [], None
    try:
        for i, p in enumerate(params.paths):
            if is_table(p):
                topics.append(_open(p, params.topic, params.temperature_topic,
                                    params.config.rate_hz).topic)
            elif i == 0:
                first_reader = _open(p, params.topic, params.temperature_topic,
                                     params.config.rate_hz)
                topics.append(first_reader.topic)
            else:
                topics.append(find_imu_topic(p, params.topic))
    except BaseException:
        if first_reader is not None:
            first_reader.close()
        raise
    return topics, first_reader


def _run_bags(params: AnalyzeParams, ref: dict[str, Any], topics: list[str], out: Path,
              first_reader: ImuBagReader | None) -> AnalyzeResult:
    """Analyse every bag into the staging folder ``out`` (chunks.csv only); return the result."""
    jobs = params.jobs
    if jobs > 1 and params.scheduler is None:
        # Worker processes are forked from this one: build the identifier and load its
        # compiled kernels once here, so each worker inherits them instead of redoing it.
        _warm_identifier(params.config)
    pool = make_executor(jobs, params.scheduler, warn=warn)
    if params.scheduler is not None:
        assert isinstance(pool, DaskExecutor)  # make_executor's executor for a scheduler
        jobs = max(jobs, pool.nthreads)
    with _writing():
        stores = _Stores(csv=_ChunkRows(out / 'chunks.csv'))
    run = _Run(params=params, ref=ref, pool=pool, jobs=jobs, stores=stores)
    bag_docs = []
    try:
        for i, (path, label, topic) in enumerate(zip(params.paths, params.names, topics)):
            bag = _Bag(path=path, label=label, topic=topic)
            bag_docs.append(_analyze_one(run, bag, _Progress(params.progress),
                                         reader=first_reader if i == 0 else None))
    finally:
        stores.csv.close()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    _check_analysed(bag_docs, params.config)
    # the readout objects themselves are for imu.yaml, not for summary.json
    accel_readouts = {b['label']: b.pop('_accelerometer_readouts') for b in bag_docs}
    return AnalyzeResult(
        tool=TOOL, version=__version__,
        created_utc=datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ'),
        command=list(params.command) if params.command is not None else None,
        options=_options(params, ref, jobs, pool), bags=tuple(bag_docs),
        timing=stores.timing, alphas=params.config.alphas, per_chunk=stores.per_chunk,
        curves=stores.curves, allan=stores.allan, accelerometer=accel_readouts,
        accel_allan=stores.accel_allan)


def _options(params: AnalyzeParams, ref: dict[str, Any], jobs: int, pool: Any) -> dict[str, Any]:
    """Return the ``options`` entry of summary.json."""
    thresholds = params.thresholds
    return {
        **params.config.as_dict(),
        'jobs': jobs,
        'topic': params.topic,
        'temperature_topic': params.temperature_topic,
        'reference': params.reference,
        'reference_bag': params.reference_bag,
        'thresholds': (
            {k: getattr(thresholds, k) for k in thresholds.__dataclass_fields__}
            if ref
            else None
        ),
        'curves': params.curves,
        'batch_size': params.batch_size,
        'scheduler': pool.address if params.scheduler is not None else None,
    }


def _check_analysed(bag_docs: list[dict[str, Any]], config: EngineConfig) -> None:
    """
    Never succeed having analysed nothing: say why a bag has no analysed chunk.

    A bag shorter than one chunk is analysed by its Allan deviation alone (``allan_only``); it
    is refused only when that has no readout either (too short for any averaging time, or
    ``--no-allan``).
    """
    for b in bag_docs:
        if b.get('allan_only'):
            if not any(a.get('allan_datasheet') for a in b['axes'].values()):
                raise InputDataError(
                    f"{b['label']}: too short to analyse: {b['samples']} samples, no complete "
                    f'chunk of {config.chunk_size} and '
                    + ('no Allan deviation (--no-allan)' if not config.allan else
                       'too few for an Allan deviation to read'))
            continue
        if not any(a['chunks'] for a in b['axes'].values()):
            why = '; '.join(
                f"{axis}: {a['chunks_nan']} chunk(s) with NaN/Inf or non-physical values, "
                f"{a['chunks_dropped']} dropped for loss, {a['chunks_failed']} not "
                'identifiable (constant?)' for axis, a in b['axes'].items())
            raise InputDataError(f"{b['label']}: no chunk could be analysed ({why})")


def _write_results(out: Path, result: AnalyzeResult, *, figures: bool,
                   html: bool = True) -> list[Path]:
    """Write summary.json and everything drawn from the result into ``out``; return the files."""
    doc = result.as_dict()
    with _writing():
        files = [out / 'chunks.csv']
        write_json(out / 'summary.json', doc)
        (out / 'summary.md').write_text(summary_markdown(doc))
        files += [out / 'summary.json', out / 'summary.md']
        allan_files, imu_yaml = _write_allan_outputs(out, doc, result, figures)
        files += allan_files
        if result.curves:
            arrays: dict[str, Any] = {'alphas': result.alphas}
            for (label, axis), rows in result.curves.items():
                arrays[f'{label}/{axis}/chunk'] = np.array([r[0] for r in rows], dtype=np.int64)
                arrays[f'{label}/{axis}/var'] = np.array([r[1] for r in rows])
                arrays[f'{label}/{axis}/j'] = np.array([r[2] for r in rows])
            np.savez_compressed(out / 'curves.npz', **arrays)
            files.append(out / 'curves.npz')
        if figures:
            files += _write_figures(out, result.alphas, result.per_chunk, result.curves)
        if html:
            files.append(write_analyze_html(out, doc, result.per_chunk, result.allan,
                                            accel_allan=result.accel_allan, imu_yaml=imu_yaml))
    return files


def _warm_identifier(config: EngineConfig) -> None:
    """Identify one synthetic chunk with the configuration's cached identifier (kernels load)."""
    ident = identifier_for(*config.identifier_key())
    ident(np.random.default_rng(0).standard_normal(config.chunk_size))


def _open(path: str, topic: str | None, temperature_topic: str | None,
          rate_hz: float | None) -> Any:
    # the one input layer: what analyze reads, explain reads, with the same refusals
    return open_imu(path, topic=topic, temperature_topic=temperature_topic, rate_hz=rate_hz)


def _select(stamps: np.ndarray, first_ns: int, start_s: float | None, end_s: float | None,
            segment: StaticSegment | None, left: dict[str, int]) -> np.ndarray:
    """Return the mask of samples inside --start/--end and the static segment; count the rest."""
    rel = stamps - first_ns
    keep = np.ones(stamps.shape[0], dtype=bool)
    # a window bound past any int64 ns stamp (--start 1e308) is past every record's end
    limit_s = 9.2e9  # s, below 2**63 ns
    if start_s is not None:
        before = rel < int(round(min(start_s, limit_s) * 1e9))
        left['before_start'] += int(before.sum())
        keep &= ~before
    if end_s is not None:
        after = rel > int(round(min(end_s, limit_s) * 1e9))
        left['after_end'] += int((after & keep).sum())
        keep &= ~after
    if segment is not None and not segment.static_throughout:
        moving = (stamps < segment.start_ns) | (stamps >= segment.end_ns)
        left['motion'] += int((moving & keep).sum())
        keep &= ~moving
    return keep


def _static_prepass(run: _Run, bag: _Bag) -> StaticSegment | None:
    """Read stamps and rates once to find the longest static segment (core/segments.py)."""
    params = run.params
    stats = WindowStats()
    first = None
    log_time = False
    with _open(bag.path, bag.topic, params.temperature_topic, params.config.rate_hz) as reader:
        for batch in _plausible(reader.iter_batches(params.batch_size), None):
            stamps = batch.stamp_ns
            if first is None and _stamps_unusable(stamps) and not _stamps_unusable(batch.log_ns):
                log_time = True
            if log_time:
                stamps = batch.log_ns
            if first is None:
                first = int(stamps[0])
            keep = _select(stamps, first, params.start_s, params.end_s, None,
                           {'before_start': 0, 'after_end': 0, 'motion': 0})
            stats.update(stamps[keep], batch.gyro[keep])
    return stats.segment()


def _plausible(batches: Iterator[Any], counts: dict[str, int] | None) -> Iterator[Any]:
    """Yield the batches with non-physical values as NaN (core/plausible.py), counted."""
    for batch in batches:
        gyro, n_gyro = mask_non_physical(batch.gyro, MAX_RATE_RAD_S)
        accel, n_accel = mask_non_physical(batch.accel, MAX_SPECIFIC_FORCE_M_S2)
        if n_gyro or n_accel:
            if counts is not None:
                counts['gyro'] += n_gyro
                counts['accel'] += n_accel
            batch = dataclasses.replace(batch, gyro=gyro, accel=accel)
        yield batch


def _stamps_unusable(stamps: np.ndarray) -> bool:
    """
    Tell whether the first batch's stamps cannot be a time base (then the log time is tried).

    Equal consecutive stamps are a normal time base (a packet of samples stamped once); only
    stamps that go backwards (shuffled) or never advance (a driver that leaves the header stamp
    at zero) are unusable. A batch too small to tell is usable.
    """
    steps = np.diff(stamps)
    if steps.size == 0:
        return False
    if np.count_nonzero(steps < 0) > 0.1 * steps.size:
        return True
    # 64 equal stamps in a row would be one packet of 64 samples or more: no advance at all
    return steps.size >= 64 and not np.any(steps > 0)


class _MotionWatch:
    """
    The static-segment statistics of the prepass, gathered during the analysis pass instead.

    The same batches and selection as :func:`_static_prepass` go into the same
    :class:`..core.segments.WindowStats`, so :meth:`segment` is the prepass' segment. Each time
    the window count has grown by a quarter the provisional segment is looked at; when it already
    shows motion the pass is abandoned (the record will need the prepass anyway). Motion that
    only the end of a record reveals costs the analysis twice.
    """

    def __init__(self) -> None:
        self.stats = WindowStats()
        self._next_check = 64

    def update(self, stamps: np.ndarray, gyro: np.ndarray) -> None:
        self.stats.update(stamps, gyro)

    def moving(self) -> bool:
        windows = self.stats.windows
        if windows < self._next_check:
            return False
        self._next_check = windows + max(1, windows // 4)
        seg = self.stats.segment()
        return seg is not None and not seg.static_throughout

    def segment(self) -> StaticSegment | None:
        return self.stats.segment()


def _analyze_one(run: _Run, bag: _Bag, progress: _Progress, *,
                 reader: ImuBagReader | None = None) -> dict[str, Any]:
    """Analyse one bag (``reader``: the bag already open, used by its first pass)."""
    if run.params.static != 'auto':
        state = _analysis_pass(run, bag, progress, segment=None, watch=None, say=warn,
                               reader=reader)
        assert state is not None  # only a watched pass is abandoned
        return _bag_doc(run, bag, state, None)
    # One read of the bag when it is static throughout (the usual noise recording): the pass
    # gathers the prepass' statistics while it analyses everything; only when they show motion
    # are its rows taken back and the bag read twice, as before (prepass, then the segment).
    mark = run.stores.csv.mark()
    watch = _MotionWatch()
    state = _analysis_pass(run, bag, progress, segment=None, watch=watch, say=warn, reader=reader)
    if state is not None:
        segment = watch.segment()
        if segment is None or segment.static_throughout:
            return _bag_doc(run, bag, state, segment)
    run.stores.csv.rollback(mark)
    for axis in run.params.config.axes:
        run.stores.curves.pop((bag.label, axis), None)
    progress.restart()
    segment = _static_prepass(run, bag)
    # the first pass already printed the warnings of the stream's start
    state = _analysis_pass(run, bag, progress, segment=segment, watch=None,
                           say=lambda text: None)
    assert state is not None  # only a watched pass is abandoned
    return _bag_doc(run, bag, state, segment)


class _ChunkFeed:
    """
    The chunks of one pass on their way to the workers and back, in order.

    Each finished chunk goes to the engine, chunks.csv, the per-chunk rows and (every
    ``stride``-th chunk, at most ``curves`` per axis) the kept var/J curves. Room for one decoded
    batch of chunks beyond the workers' own: the workers keep busy while this process decodes
    the next batch.
    """

    def __init__(self, run: _Run, bag: _Bag, engine: NoiseEngine, message_count: int) -> None:
        params, config = run.params, run.params.config
        self.run, self.label, self.engine = run, bag.label, engine
        est_chunks = max(1, message_count // config.chunk_size)
        self.stride = max(1, math.ceil(est_chunks / params.curves)) if params.curves else 0
        self.kept: collections.Counter[str] = collections.Counter()
        self.inflight: collections.deque[Any] = collections.deque()  # futures
        self.max_inflight = (4 * run.jobs
                             + len(config.axes) * (params.batch_size // config.chunk_size + 1))
        self.rows: dict[str, list] = {a: [] for a in config.axes}

    def _want_curves(self, job: Any) -> bool:
        return (bool(self.stride) and job.chunk % self.stride == 0
                and self.kept[job.axis] < self.run.params.curves)

    def _finish(self, result: Any) -> None:
        stores = self.run.stores
        self.engine.record(result)
        stores.csv.write(self.label, result)
        self.rows[result.axis].append((result.t_mid_s, result.bias_rad_s,
                                       result.variance_rad2_s2, result.alpha_var,
                                       result.alpha_corr))
        if result.var_curve is not None:
            stores.curves.setdefault((self.label, result.axis), []).append(
                (result.chunk, result.var_curve, result.j_curve))

    def _wait_one(self) -> None:
        timing = self.run.stores.timing
        w0 = time.perf_counter()
        result = self.inflight.popleft().result()
        timing['wait_s'] += time.perf_counter() - w0
        self._finish(result)

    def submit(self, jobs_list: list[Any]) -> None:
        """Identify the chunks (here or on the workers), finishing the oldest beyond the room."""
        pool = self.run.pool
        for job in jobs_list:
            keep = self._want_curves(job)
            if keep:
                self.kept[job.axis] += 1
            if pool is None:
                self._finish(analyze_chunk(job, curves=keep))
                continue
            self.inflight.append(pool.submit(analyze_chunk, job, curves=keep))
            while len(self.inflight) > self.max_inflight:
                self._wait_one()

    def drain(self) -> None:
        """Finish every chunk still in flight."""
        while self.inflight:
            self._wait_one()

    def cancel(self) -> None:
        """Cancel the chunks in flight (an abandoned pass)."""
        for fut in self.inflight:
            fut.cancel()


def _read_temperature(reader: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Return the temperature stamps (float64, sorted) and values of the bag, or (None, None)."""
    temps = reader.read_temperature()
    if temps is not None and temps[0].size:
        order = np.argsort(temps[0], kind='stable')
        return temps[0][order].astype(np.float64), temps[1][order]
    return None, None


class _TimeBase:
    """The stamps of one pass: the header stamps, or the log time when those are unusable."""

    def __init__(self, label: str, warnings: list[str], say: Callable[[str], None]) -> None:
        self.label, self.warnings, self.say = label, warnings, say
        self.source = 'header'
        self.first_ns: int | None = None
        self.last_ns = -2 ** 63

    def stamps(self, batch: Any, first_batch: bool) -> np.ndarray:
        """Return the batch's stamps in the time base (chosen at the first batch)."""
        stamps = batch.stamp_ns
        if first_batch and _stamps_unusable(stamps):
            if _stamps_unusable(batch.log_ns) or self.source == 'log':
                raise InputDataError(
                    f'{self.label}: neither the header stamps nor the log times increase: '
                    'no time base')
            self.source = 'log'
            self.warnings.append(
                "header stamps are not increasing (shuffled?): the recorder's log time is "
                'used as the time base')
            self.say(f'{self.label}: {self.warnings[-1]}')
        if self.source == 'log':
            stamps = batch.log_ns
        if self.first_ns is None:
            self.first_ns = int(stamps[0])
        self.last_ns = max(self.last_ns, int(stamps.max()))
        return stamps


def _analysis_pass(run: _Run, bag: _Bag, progress: _Progress, *,
                   segment: StaticSegment | None, watch: _MotionWatch | None,
                   say: Callable[[str], None],
                   reader: Any | None = None) -> _PassState | None:
    """
    Read the bag once and analyse it; None when ``watch`` saw motion (pass abandoned).

    ``reader``: the bag already open (closed at the end of the pass), else it is opened here.
    """
    params, config, timing = run.params, run.params.config, run.stores.timing
    label = bag.label
    engine = NoiseEngine(config, reference=run.ref or None, thresholds=params.thresholds)
    warnings: list[str] = []
    left = {'before_start': 0, 'after_end': 0, 'motion': 0}
    timebase = _TimeBase(label, warnings, say)
    if reader is None:
        reader = _open(bag.path, bag.topic, params.temperature_topic, config.rate_hz)
    with reader:
        t_stamp, t_value = _read_temperature(reader)
        feed = _ChunkFeed(run, bag, engine, reader.message_count)
        done = 0
        t0 = time.monotonic()
        frame_id = None
        accel = _AccelAllan(config.allan and config.allan_taus)
        non_physical = {'gyro': 0, 'accel': 0}
        batches = _plausible(reader.iter_batches(params.batch_size), non_physical)
        while True:
            d0 = time.perf_counter()
            batch = next(batches, None)
            timing['decode_s'] += time.perf_counter() - d0
            if batch is None:
                break
            frame_id = frame_id or batch.frame_id
            stamps = timebase.stamps(batch, done == 0)
            assert timebase.first_ns is not None  # set by the first batch's stamps
            keep = _select(stamps, timebase.first_ns, params.start_s, params.end_s, segment,
                           left)
            done += len(batch)
            if watch is not None:
                watch.update(stamps[keep], batch.gyro[keep])
                if watch.moving():
                    feed.cancel()
                    return None
            if not keep.any():
                continue
            gyro_b, accel_b = batch.gyro, batch.accel
            if not keep.all():
                stamps, gyro_b, accel_b = stamps[keep], gyro_b[keep], accel_b[keep]
            temp = None
            if t_stamp is not None and t_value is not None:  # both or neither
                # Temperature is published slower than the IMU: linear interpolation at the IMU
                # stamps, held constant before the first and after the last temperature message.
                temp = np.interp(stamps.astype(np.float64), t_stamp, t_value)
            feed.submit(engine.ingest(stamps, gyro_b, temp))
            accel.update(accel_b, engine.counts().rate_hz)
            progress.update(label, done, reader.message_count, engine.counts().chunks, t0)
        if done and left['before_start'] + left['after_end'] >= done:
            assert timebase.first_ns is not None  # set by the first batch's stamps
            raise nothing_left_error(start_s=params.start_s, end_s=params.end_s, label=label,
                                     record_end_s=(timebase.last_ns - timebase.first_ns) / 1e9)
        feed.submit(engine.flush())
        feed.drain()
        progress.update(label, done, reader.message_count, engine.counts().chunks, t0, final=True)
        return _PassState(
            engine=engine, warnings=warnings, time_source=timebase.source, left=left,
            first_ns=timebase.first_ns, last_ns=timebase.last_ns, accel=accel, rows=feed.rows,
            done=done, frame_id=frame_id, storage=reader.storage,
            undecodable=reader.undecodable_count, temperature_topic=reader.temperature_topic,
            non_physical=non_physical)


def _bag_warnings(bag: _Bag, state: _PassState, segment: StaticSegment | None,
                  config: EngineConfig) -> tuple[list[str], dict[str, Any]]:
    """Return one bag's warnings (each also printed) and its ``left_out`` entry."""
    warnings, left, first_ns = state.warnings, state.left, state.first_ns
    counts = state.engine.counts()
    label = bag.label

    def add(text: str) -> None:
        warnings.append(text)
        warn(f'{label}: {text}')

    tb = counts.timebase
    for text in (tb.warnings if tb is not None else ()):
        add(text)
    if counts.out_of_order:
        add(f'{counts.out_of_order} stamp(s) earlier than the latest before them: counted as '
            'out of order, not reordered (each also leaves a one-sample gap)')
    if counts.longest_gaps:
        t_s, length_s, missing = counts.longest_gaps[0]
        add(f'{counts.gaps} stamp gap(s), {counts.samples_lost} sample(s) missing; the '
            f'longest {length_s:.6g} s at t = {t_s:.3f} s after the first sample ({missing} '
            'samples missing)')
    left_out: dict[str, Any] = dict(left)
    cuts: tuple[Cut, ...] = ()
    if segment is not None and not segment.static_throughout and first_ns is not None:
        # the one owner of the rule says what was cut (core/segments.py), as explain does
        left_out.update(segment_left_out(segment, first_ns, state.last_ns))
        cuts = segment.cuts(first_ns, state.last_ns)
    non_physical = state.non_physical
    if any(non_physical.values()):
        add(f"{non_physical['gyro']} angular rate value(s) beyond {MAX_RATE_RAD_S:g} rad/s "
            f"and {non_physical['accel']} specific force value(s) beyond "
            f'{MAX_SPECIFIC_FORCE_M_S2:g} m/s^2 are not measurements (corrupt record or '
            'wrong unit): treated as NaN, their chunks left out')
    if counts.chunks and counts.tail_samples > 0.1 * counts.samples:
        size = config.chunk_size
        better = counts.samples // (counts.chunks + 1) if counts.chunks else counts.samples
        hint = (f'; --chunk-size {better} would cut {counts.chunks + 1} chunks'
                if better >= config.memory + 2 else '')
        add(f'{counts.tail_samples} of {counts.samples} samples '
            f'({100.0 * counts.tail_samples / counts.samples:.0f} %) after the last complete '
            'chunk of '
            f'{size} are not in the chunk tables (they are in the Allan deviation){hint}')
    only = _allan_only(counts, config)
    if only:
        add(f'Allan deviation only: {only}')
    if any(left.values()):
        span = left_out.get('static_segment_s')
        add(left_out_sentence(state.done, before_start=left['before_start'],
                              after_end=left['after_end'], motion=left['motion'],
                              segment_s=None if span is None else (span[0], span[1]), cuts=cuts,
                              window_names=('--start', '--end')))
    return warnings, left_out


def _bag_doc(run: _Run, bag: _Bag, state: _PassState,
             segment: StaticSegment | None) -> dict[str, Any]:
    """Summarise one analysed bag: its entry in summary.json (and the per-axis stores)."""
    params, config, stores = run.params, run.params.config, run.stores
    engine, label = state.engine, bag.label
    counts = engine.counts()
    state.accel.update(None, counts.rate_hz)
    accel_readouts = state.accel.readouts(counts.rate_hz)
    summaries = engine.summary(allan=config.allan)
    verdicts = engine.health(summaries=summaries) if run.ref else {}
    tb = counts.timebase
    warnings, left_out = _bag_warnings(bag, state, segment, config)
    for axis, s in summaries.items():
        stores.per_chunk.setdefault(axis, []).append(
            (label, np.array(state.rows[axis]).reshape(-1, 5)))
        if s.allan is not None:
            stores.allan[(label, axis)] = (s.allan, s.noise_terms, s.readout)
    for axis, curve in getattr(state.accel, 'curves', {}).items():
        stores.accel_allan[(label, axis)] = curve
    return {
        'label': label,
        'path': str(bag.path),
        'topic': bag.topic,
        'storage': state.storage,
        'frame_id': state.frame_id,
        'temperature_topic': state.temperature_topic,
        'messages': state.done,
        'undecodable_messages': state.undecodable,
        'non_physical_values': dict(state.non_physical),
        'rate_hz': json_num(counts.rate_hz),
        'rate_method': counts.rate_method,
        'time_source': state.time_source,
        'stamps_bursty': counts.bursty,
        'stamp_jitter_s': json_num(counts.jitter_s),
        'timebase': tb.as_dict() if tb is not None else None,
        'warnings': warnings,
        'left_out': left_out,
        'window_s': [params.start_s, params.end_s],
        'static_detection': params.static,
        'duration_s': counts.duration_s,
        'samples': counts.samples,
        'samples_lost': counts.samples_lost,
        'gaps': counts.gaps,
        'out_of_order_stamps': counts.out_of_order,
        'clock_steps': counts.clock_steps,
        'equal_stamps': counts.equal_stamps,
        'longest_gaps': [{'start_s': t, 'length_s': d, 'missing_samples': m}
                         for t, d, m in counts.longest_gaps],
        'chunks_cut': counts.chunks,
        'allan_only': _allan_only(counts, config),
        'tail_samples': counts.tail_samples,
        'discarded_samples': counts.discarded_samples,
        'discarded_partials': counts.discarded_partials,
        'allan_status': engine.allan_status,
        'accelerometer_allan': {a: accelerometer_readout_dict(r)
                                for a, r in accel_readouts.items()},
        '_accelerometer_readouts': accel_readouts,
        'axes': {
            axis: axis_summary_dict(s, verdict=verdicts.get(axis))
            for axis, s in summaries.items()
        },
    }


def _allan_only(counts: Any, config: EngineConfig) -> str | None:
    """Return why a bag is analysed by its Allan deviation alone (no complete chunk), or None."""
    if counts.chunks:
        return None
    shortest = config.memory + 2
    fits = (f'--chunk-size {counts.samples} or less (at least memory L + 2 = {shortest}) would '
            'identify one chunk' if counts.samples >= shortest else
            f'the order identification needs at least memory L + 2 = {shortest} samples')
    return (f'{counts.samples} samples, shorter than one chunk of {config.chunk_size}: the '
            'fractional order and the chunk statistics (paper Tables 3-6, offset drift) are not '
            f'computed; {fits}')


class _AccelAllan:
    """
    Allan deviation of the accelerometer axes, for the accelerometer_* keys of imu.yaml.

    The IEEE 952 model is fitted to the specific-force rate in m/s^2 exactly as to the angular
    rate: the fitted "angle random walk" is then the velocity random walk (m/s/sqrt(s) =
    m/s^2/sqrt(Hz), Kalibr's accelerometer_noise_density) and the "rate random walk" the
    acceleration random walk (m/s^3/sqrt(Hz), accelerometer_random_walk). Samples wait until the
    engine knows the sample rate.
    """

    def __init__(self, taus: Any) -> None:
        self.taus = taus or None
        self.acc: list[AllanAccumulator] | None = None
        self.pending: list[np.ndarray] = []

    def update(self, accel: np.ndarray | None, rate_hz: float) -> None:
        if self.taus is None:
            return
        if accel is not None:
            self.pending.append(np.asarray(accel, dtype=np.float64))
        if not math.isfinite(rate_hz) or not self.pending:
            return
        if self.acc is None:
            self.acc = [AllanAccumulator(rate_hz, taus=self.taus) for _ in AXES]
        for block in self.pending:
            for k, acc in enumerate(self.acc):
                col = block[:, k]
                acc.update(col[np.isfinite(col)])
        self.pending = []

    def readouts(self, rate_hz: float) -> dict[str, Any]:
        """
        Return ``{axis: core.readout.AllanReadout or None}`` of the accelerometer axes.

        Each axis' Allan curve (``core.allan.AllanResult``, m/s^2) is kept in :attr:`curves`
        for the report's figure.
        """
        self.curves: dict[str, Any] = {}
        if self.acc is None:
            return {}
        out: dict[str, Any] = {}
        for axis, acc in zip(AXES, self.acc):
            try:
                result = rescale_allan(acc.result(), rate_hz)
                out[axis] = read_allan(result)
                self.curves[axis] = result
            except (InputDataError, ParameterError, ValueError):
                out[axis] = None  # e.g. a constant (all-zero) accelerometer: nothing to read
        return out


def _write_allan_outputs(out: Path, doc: dict[str, Any], result: AnalyzeResult,
                         figures: bool) -> tuple[list[Path], str]:
    """Write allan.csv (always, possibly header-only), imu.yaml and the Allan figure."""
    allan_store, accel_readouts = result.allan, result.accelerometer
    entries: list[tuple] = []
    for (label, axis), (res, _, _) in allan_store.items():
        entries.append((label, axis, *allan_curve(res)))
    write_allan_csv(out / 'allan.csv', entries)
    files = [out / 'allan.csv']
    first = doc['bags'][0]
    gyro = {a: allan_store[(first['label'], a)][2] for a in first['axes']
            if (first['label'], a) in allan_store}
    record_s = first['duration_s']
    accel = accel_readouts.get(first['label']) or {}
    accel_noise = (kalibr_noise(accel, record_s=record_s)
                   if any(r is not None for r in accel.values()) else None)
    topic, note = first['topic'], ''
    if first['storage'] in ('csv', 'ulog'):
        # a table or a ULog has no ROS topic: name the usual raw IMU topic and say so
        topic = DEFAULT_IMU_TOPIC
        what = (f"a {first['storage']} file" if first['topic'] == first['storage']
                else f"a {first['storage']} file ({first['topic']})")
        note = f'the input was {what}, not a bag: set the topic your IMU driver publishes'
    imu_yaml = write_imu_yaml(out / 'imu.yaml', rostopic=topic, rostopic_note=note,
                              update_rate_hz=first['rate_hz'] or float('nan'),
                              gyroscope=kalibr_noise(gyro, record_s=record_s),
                              accelerometer=accel_noise,
                              source=f"from bag {first['label']} ({first['path']}), largest over "
                              f"axes {', '.join(first['axes'])}")
    files.append(out / 'imu.yaml')
    if figures and allan_store:
        plot_allan(out / 'allan.png', allan_curves(doc, allan_store, result.accel_allan))
        files.append(out / 'allan.png')
    return files, imu_yaml


def _safe(name: str) -> str:
    return ''.join(c if c.isalnum() or c in '-_.' else '_' for c in name)


def _write_figures(out: Path, alphas: np.ndarray | None, per_chunk: dict[str, list],
                   curve_store: dict[tuple, list]) -> list[Path]:
    files = []
    bias = {a: [(label, r[:, 0], r[:, 1]) for label, r in v] for a, v in per_chunk.items()}
    var = {a: [(label, r[:, 0], r[:, 2]) for label, r in v] for a, v in per_chunk.items()}
    for name, data, quantity in (('bias.png', bias, 'bias'), ('variance.png', var, 'variance')):
        if plot_per_chunk(out / name, data, quantity=quantity):
            files.append(out / name)
    for (label, axis), rows in curve_store.items():
        path = out / f'curves_{_safe(label)}_{axis}.png'
        assert alphas is not None  # curves are computed on the order grid
        plot_curves(path, alphas, np.array([r[0] for r in rows]),
                    np.array([r[1] for r in rows]), np.array([r[2] for r in rows]),
                    title=f'{label}, axis {axis}: var(alpha) and J(alpha) over chunks')
        files.append(path)
    return files
