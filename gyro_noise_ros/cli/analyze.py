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
gyro_noise_analyze.

Characterise gyro noise in rosbags (paper 000 Tables 3-6, Figs. 2-10), ROS-free.

Usage::

    gyro_noise_analyze BAG [BAG ...] [--topic T] [--axis x|y|z|all] [--chunk-size N]
        [--order-grid START:STOP:STEP] [--memory L] [--jobs N] [--scheduler ADDRESS]
        [--reference SUMMARY] [--label NAME ...] --out DIR

Reads rosbag2 (sqlite3, MCAP) and ROS 1 bags through :mod:`gyro_noise_ros.bag`, streams them in
batches (constant memory apart from one small row per chunk), runs
:class:`gyro_noise_ros.core.engine.NoiseEngine` with the chunk identification spread over
``--jobs`` worker processes (at most ``4 x jobs`` plus one decoded batch of chunks in flight),
and writes chunks.csv,
summary.json, summary.md, allan.csv, imu.yaml, curves.npz, PNG figures and report.html into DIR.
Formats and exit codes: ``docs/offline_tool.md``.
"""

import argparse
import collections
import contextlib
import dataclasses
import datetime
import functools
import math
import os
from pathlib import Path
import sys
import time

import numpy as np
import threadpoolctl

from ._common import run_cli
from .. import __version__, report
from ..bag import find_imu_topic, ImuBagReader
from ..bag.tabular import is_table, TableImuReader
from ..cluster import make_executor
from ..core.engine import analyze_chunk, AXES, EngineConfig, GAP_POLICIES, NoiseEngine
from ..core.fractional import DEFAULT_MEMORY, parse_grid
from ..core.health import HealthThresholds, reference_per_axis
from ..core.plausible import mask_non_physical, MAX_RATE_RAD_S, MAX_SPECIFIC_FORCE_M_S2
from ..errors import InputDataError, nothing_left_error, OutputError, ParameterError
from ..htmlreport.analyze import write_analyze_html
from ..outputs import staged_output

PROG = 'gyro_noise_analyze'

#: Messages decoded per batch (bounds the decode memory: ~0.4 KB per message).
DEFAULT_BATCH = 65536
#: Chunks per bag and axis whose var(alpha), J(alpha) curves are kept for the heat maps.
DEFAULT_CURVES = 200


def build_parser():
    """
    Return the argument parser of gyro_noise_analyze.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(
        prog=PROG,
        description='Characterise MEMS gyro noise in rosbags, CSV tables and PX4 ULogs: '
        'per-chunk bias, variance and '
        'fractional order (variance and correlation methods), Allan deviation, health verdicts.')
    p.add_argument(
        'bags', nargs='+', metavar='BAG',
        help='rosbag2 directory, .db3 or .mcap file, ROS 1 .bag file, CSV table or PX4 .ulg '
        '(order kept in tables)')
    p.add_argument('--out', required=True, metavar='DIR',
                   help='output directory (created if missing)')
    p.add_argument('--topic',
                   help='sensor_msgs/Imu topic (default: the single Imu topic of each bag)')
    p.add_argument('--temperature-topic',
                   help='sensor_msgs/Temperature topic (default: found automatically)')
    p.add_argument('--axis', default='all', choices=[*AXES, 'all'],
                   help='axis to analyse (default: all)')
    p.add_argument('--chunk-size', type=int, default=10000, metavar='N',
                   help='samples per chunk (10000)')
    p.add_argument('--order-grid', default='0:2:0.01', metavar='START:STOP:STEP',
                   help='order grid, both ends included (0:2:0.01)')
    p.add_argument('--memory', type=int, default=DEFAULT_MEMORY, metavar='L',
                   help='memory L of the truncated GL difference (1000)')
    p.add_argument('--max-lag', type=int, default=None, metavar='M',
                   help='largest lag in J (default: all)')
    p.add_argument('--no-demean', action='store_true',
                   help='do not remove the chunk mean before identification')
    p.add_argument('--rate-hz', type=float, default=None,
                   help='nominal sample rate (default: from the stamps)')
    p.add_argument('--gap-factor', type=float, default=1.5,
                   help='a stamp step above this many nominal periods is a gap (1.5)')
    p.add_argument(
        '--gap-policy', default='flag', choices=GAP_POLICIES,
        help='flag: keep chunks with gaps and count; split: restart the chunk after a gap; '
        'drop: leave chunks with gaps out of the statistics (default: flag)')
    p.add_argument('--start', type=float, default=None, metavar='S',
                   help='analyse from S seconds after the first sample of each bag')
    p.add_argument('--end', type=float, default=None, metavar='S',
                   help='analyse up to S seconds after the first sample of each bag')
    p.add_argument(
        '--static', default='auto', choices=('auto', 'off'),
        help='auto: find the longest static segment and skip motion, saying so (default); '
        'off: analyse everything')
    p.add_argument(
        '--jobs', type=int, default=None, metavar='N',
        help='worker processes for the identification (default: all cores; 1 = in-process)')
    p.add_argument(
        '--scheduler', metavar='ADDRESS',
        help='Dask scheduler (tcp://host:8786): identify the chunks on that cluster instead of '
        'local processes (pip extra dask; docs/scale.md)')
    p.add_argument(
        '--reference', metavar='SUMMARY',
        help='summary.json of a reference recording: adds health verdicts per bag and axis')
    p.add_argument('--reference-bag', metavar='LABEL',
                   help='bag label inside a --reference summary that holds several bags')
    p.add_argument('--label', nargs='+', metavar='NAME',
                   help='one label per bag for tables and figures')
    p.add_argument('--curves', type=int, default=DEFAULT_CURVES, metavar='N',
                   help=f'chunks per bag and axis whose var/J curves are kept for heat maps '
                        f'({DEFAULT_CURVES}; 0 = none)')
    p.add_argument('--no-figures', action='store_true', help='write no PNG figures')
    p.add_argument('--no-html', action='store_true',
                   help='write no report.html (the interactive one-file report)')
    p.add_argument('--no-allan', action='store_true', help='skip the Allan deviation')
    p.add_argument(
        '--allan-taus', default='dense', choices=('octave', 'dense'),
        help='Allan averaging times: octave (1, 2, 4, ... samples) or dense (~10 per decade)')
    p.add_argument('--batch-size', type=int, default=DEFAULT_BATCH, metavar='N',
                   help=f'messages decoded per batch ({DEFAULT_BATCH})')
    p.add_argument('--quiet', action='store_true', help='print only errors')
    p.add_argument('--version', action='version', version=f'%(prog)s {__version__}')
    return p


class _Progress:
    """Progress on stderr: a refreshed line on a TTY, else one line per 10 % (logs, CI)."""

    def __init__(self, enabled):
        self.enabled = bool(enabled)
        self.tty = self.enabled and sys.stderr.isatty()
        self._last = 0.0
        self._decile = 0

    def restart(self):
        self._last = 0.0
        self._decile = 0

    def update(self, label, done, total, chunks, started, *, final=False):
        if not self.enabled:
            return
        now = time.monotonic()
        rate = done / max(now - started, 1e-9)
        if not self.tty:
            decile = int(10 * done / total) if total else 0
            if decile <= self._decile and not (final and self._decile < 10):
                return
            self._decile = 10 if final else decile
            pct = 100 if final else 10 * decile
            sys.stderr.write(f'{label}: {pct}% {done}/{total} messages, {chunks} chunks, '
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


def _labels(paths, labels):
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


def _one_blas_thread(func):
    """
    Run ``func`` with one BLAS thread in this process (and so in the workers it forks).

    The identification's only BLAS call is a matrix-vector product of 8 orders (``'exact'``);
    OpenBLAS' own threads gain nothing there and spin after each call, taking a core from the
    worker processes: measured 1.07x less CPU end to end with ``--jobs 2`` on 2 cores
    (docs/scale.md). The results do not change (each dot product is one thread's either way).
    """
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpoolctl.threadpool_limits(limits=1, user_api='blas'):
            return func(*args, **kwargs)
    return wrapper


@_one_blas_thread
def analyze_bags(paths, *, out_dir, labels=None, topic=None, temperature_topic=None, config=None,
                 jobs=1, reference=None, reference_bag=None, thresholds=None, figures=True,
                 curves=DEFAULT_CURVES, batch_size=DEFAULT_BATCH, progress=False, command=None,
                 start_s=None, end_s=None, static='auto', scheduler=None, html=True):
    """
    Analyse bags and write the report files (the body of gyro_noise_analyze, callable from Python).

    Parameters
    ----------
    paths : list of str or os.PathLike
        Bags, in table order.
    out_dir : str or os.PathLike, keyword-only
        Output directory (created).
    labels : list of str, optional
        One unique label per bag (default: bag names).
    topic, temperature_topic : str, optional
        Topics (default: found per bag).
    config : EngineConfig, optional
        Engine options.
    jobs : int
        Worker processes (1: analyse in this process).
    reference : str or os.PathLike, optional
        summary.json of a reference recording (health verdicts).
    reference_bag : str, optional
        Bag label inside ``reference`` when it holds several bags.
    thresholds : HealthThresholds, optional
        Health thresholds (default: :class:`HealthThresholds()`).
    figures : bool
        Write PNG figures.
    html : bool
        Write report.html (:mod:`..htmlreport.analyze`).
    curves : int
        Chunks per bag and axis whose curves are kept.
    batch_size : int
        Messages per decoded batch.
    progress : bool
        Show progress on a terminal.
    command : list of str, optional
        Command line recorded in summary.json.
    start_s, end_s : float, optional
        Analyse only samples from ``start_s`` to ``end_s`` seconds after each bag's first sample.
    static : {'auto', 'off'}
        'auto': find the longest static segment (core/segments.py) and skip motion, saying so.
    scheduler : str, optional
        Dask scheduler address: the chunks go to that cluster instead of ``jobs`` local
        processes, at most ``2 x max(jobs, cluster threads)`` in flight (:mod:`..cluster`).

    Returns
    -------
    dict
        The summary.json document plus ``'_timing'`` (seconds: total, decode, analysis wait) and
        ``'_files'`` (written paths).

    """
    config = config if config is not None else EngineConfig()
    if static not in ('auto', 'off'):
        raise ParameterError(f"--static must be 'auto' or 'off', got {static!r}")
    for name, value in (('--start', start_s), ('--end', end_s)):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise ParameterError(f'{name} must be a number of seconds >= 0, got {value}')
    if start_s is not None and end_s is not None and end_s <= start_s:
        raise ParameterError(f'--end ({end_s:g} s) must be after --start ({start_s:g} s)')
    select = (start_s, end_s, static)
    jobs = int(jobs)
    if jobs < 1:
        raise ParameterError(f'--jobs must be >= 1, got {jobs}')
    if curves < 0:
        raise ParameterError(f'--curves must be >= 0, got {curves}')
    names = _labels([str(p) for p in paths], labels)
    thresholds = thresholds if thresholds is not None else HealthThresholds()
    ref = reference_per_axis(str(reference), config.axes,
                             bag=reference_bag) if reference is not None else {}
    with contextlib.ExitStack() as stack:
        # Every file is written into a hidden staging folder inside --out and published there
        # only when the whole run succeeded: an error or an interrupt leaves no result.
        first_reader = None
        try:
            # Fail fast on any unreadable bag or unresolvable topic before hours of work on the
            # others. The first bag's reader stays open for its analysis: opening a sqlite3 bag
            # counts its messages (a scan of the whole table, about 0.25 s per million messages).
            topics = []
            for i, p in enumerate(paths):
                if is_table(p):
                    topics.append(_open(p, topic, temperature_topic, config.rate_hz).topic)
                elif i == 0:
                    first_reader = ImuBagReader(p, topic=topic,
                                                temperature_topic=temperature_topic)
                    topics.append(first_reader.topic)
                else:
                    topics.append(find_imu_topic(p, topic))
            out = stack.enter_context(staged_output(out_dir))

            started = time.perf_counter()
            timing = {'decode_s': 0.0, 'wait_s': 0.0}
            if jobs > 1 and scheduler is None:
                # Worker processes are forked from this one: build the identifier and load its
                # compiled kernels once here, so each worker inherits them instead of redoing it.
                _warm_identifier(config)
            pool = make_executor(jobs, scheduler, warn=warn)
            if scheduler is not None:
                jobs = max(jobs, pool.nthreads)
            with _writing():
                csv_writer = _ChunkRows(out / 'chunks.csv')
            bag_docs, per_chunk, curve_store, allan_store = [], {}, {}, {}
            try:
                for i, (path, label, imu_topic) in enumerate(zip(paths, names, topics)):
                    doc = _analyze_one(path, label, imu_topic, temperature_topic, config, ref,
                                       thresholds, pool, jobs, select, csv_writer, per_chunk,
                                       curve_store, allan_store, curves, batch_size,
                                       _Progress(progress), timing,
                                       reader=first_reader if i == 0 else None)
                    bag_docs.append(doc)
            finally:
                csv_writer.close()
                if pool is not None:
                    pool.shutdown(wait=True, cancel_futures=True)
        finally:
            if first_reader is not None:
                first_reader.close()  # idempotent; open here only when the run failed before it

        if not any(a['chunks'] + a['chunks_nan'] + a['chunks_dropped'] + a['chunks_failed']
                   for b in bag_docs for a in b['axes'].values()):
            counts = ', '.join(f"{b['label']}: {b['samples']} samples" for b in bag_docs)
            raise InputDataError(
                f'no complete chunk of {config.chunk_size} samples in any bag ({counts}); '
                'lower --chunk-size (>= memory + 2)')
        for b in bag_docs:
            if not any(a['chunks'] for a in b['axes'].values()):
                # Never exit 0 having analysed nothing: say why each axis has no analysed chunk.
                why = '; '.join(
                    f"{axis}: {a['chunks_nan']} chunk(s) with NaN/Inf or non-physical values, "
                    f"{a['chunks_dropped']} dropped for loss, {a['chunks_failed']} not "
                    'identifiable (constant?)' for axis, a in b['axes'].items())
                raise InputDataError(f"{b['label']}: no chunk could be analysed ({why})")
        # the readout objects themselves are for imu.yaml, not for summary.json
        accel_readouts = {b['label']: b.pop('_accelerometer_readouts') for b in bag_docs}

        doc = {
            'tool': PROG,
            'version': __version__,
            'created_utc': datetime.datetime.now(datetime.timezone.utc).strftime(
                '%Y-%m-%dT%H:%M:%SZ'),
            'command': list(command) if command is not None else None,
            'options': {
                **config.as_dict(),
                'jobs': jobs,
                'topic': topic,
                'temperature_topic': temperature_topic,
                'reference': str(reference) if reference is not None else None,
                'reference_bag': reference_bag,
                'thresholds': (
                    {k: getattr(thresholds, k) for k in thresholds.__dataclass_fields__}
                    if ref
                    else None
                ),
                'curves': curves,
                'batch_size': batch_size,
                'scheduler': pool.address if scheduler is not None else None,
            },
            'bags': bag_docs,
        }
        with _writing():
            files = [out / 'chunks.csv']
            report.write_json(out / 'summary.json', doc)
            (out / 'summary.md').write_text(report.summary_markdown(doc))
            files += [out / 'summary.json', out / 'summary.md']
            files += _write_allan_outputs(out, doc, allan_store, accel_readouts, figures)
            if curve_store:
                arrays = {'alphas': config.alphas}
                for (label, axis), rows in curve_store.items():
                    arrays[f'{label}/{axis}/chunk'] = np.array([r[0] for r in rows],
                                                               dtype=np.int64)
                    arrays[f'{label}/{axis}/var'] = np.array([r[1] for r in rows])
                    arrays[f'{label}/{axis}/j'] = np.array([r[2] for r in rows])
                np.savez_compressed(out / 'curves.npz', **arrays)
                files.append(out / 'curves.npz')
            if figures:
                files += _write_figures(out, config, per_chunk, curve_store)
            if html:
                files.append(write_analyze_html(out, doc, per_chunk, allan_store))
        doc['_timing'] = {'total_s': time.perf_counter() - started, **timing}
        doc['_files'] = [str(f) for f in files]
    # the files under their published names
    doc['_files'] = [str(Path(out_dir) / Path(f).name) for f in doc['_files']]
    return doc


def _warm_identifier(config):
    """Identify one synthetic chunk with the configuration's cached identifier (kernels load)."""
    from ..core.engine import identifier_for

    ident = identifier_for(*config.identifier_key())
    ident(np.random.default_rng(0).standard_normal(config.chunk_size))


def _open(path, topic, temperature_topic, rate_hz):
    if is_table(path):
        return TableImuReader(path, topic=topic, temperature_topic=temperature_topic,
                              rate_hz=rate_hz)
    return ImuBagReader(path, topic=topic, temperature_topic=temperature_topic)


def _select(stamps, first_ns, start_s, end_s, segment, left):
    """Return the mask of samples inside --start/--end and the static segment; count the rest."""
    rel = stamps - first_ns
    keep = np.ones(stamps.shape[0], dtype=bool)
    if start_s is not None:
        before = rel < int(round(start_s * 1e9))
        left['before_start'] += int(before.sum())
        keep &= ~before
    if end_s is not None:
        after = rel > int(round(end_s * 1e9))
        left['after_end'] += int((after & keep).sum())
        keep &= ~after
    if segment is not None and not segment.static_throughout:
        moving = (stamps < segment.start_ns) | (stamps >= segment.end_ns)
        left['motion'] += int((moving & keep).sum())
        keep &= ~moving
    return keep


def _static_prepass(path, topic, temperature_topic, rate_hz, batch_size, start_s, end_s):
    """Read stamps and rates once to find the longest static segment (core/segments.py)."""
    from ..core.segments import WindowStats

    stats = WindowStats()
    first = None
    log_time = False
    with _open(path, topic, temperature_topic, rate_hz) as reader:
        for batch in _plausible(reader.iter_batches(batch_size), None):
            stamps = batch.stamp_ns
            if first is None and _stamps_unusable(stamps) and not _stamps_unusable(batch.log_ns):
                log_time = True
            if log_time:
                stamps = batch.log_ns
            if first is None:
                first = int(stamps[0])
            keep = _select(stamps, first, start_s, end_s, None,
                           {'before_start': 0, 'after_end': 0, 'motion': 0})
            stats.update(stamps[keep], batch.gyro[keep])
    return stats.segment()


def _plausible(batches, counts):
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


def _check_chunk_fits(count, label, config):
    """Refuse a record shorter than one chunk before reading it (``count``: 0 = unknown)."""
    if not count:
        return
    shortest = config.memory + 2
    if count < shortest:
        raise InputDataError(
            f'{label}: too short to analyse: {count} samples; the shortest chunk the order '
            f'identification takes is memory L + 2 = {shortest} samples')
    if count < config.chunk_size:
        raise ParameterError(
            f'--chunk-size {config.chunk_size} is larger than the record {label} ({count} '
            f'samples): give at most {count} (and at least memory L + 2 = {shortest})')


def _stamps_unusable(stamps):
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


def warn(text):
    """
    Print one warning line on stderr.

    Parameters
    ----------
    text : str
        The warning, without the program name.

    """
    print(f'{PROG}: warning: {text}', file=sys.stderr, flush=True)


@contextlib.contextmanager
def _writing():
    """Turn an OS error while writing the results (disk full, quota) into OutputError."""
    try:
        yield
    except OSError as err:
        where = f' ({err.filename})' if err.filename else ''
        raise OutputError(f'cannot write the results: {err.strerror or err}{where}') from err


class _ChunkRows(report.ChunkCsvWriter):
    """chunks.csv that can take back the rows of a bag (a speculative pass that was not kept)."""

    def write(self, *args, **kwargs):
        with _writing():
            return super().write(*args, **kwargs)

    def mark(self):
        self._fh.flush()
        return self._fh.tell(), self.rows

    def rollback(self, mark):
        self._fh.flush()
        self._fh.seek(mark[0])
        self._fh.truncate()
        self.rows = mark[1]


class _MotionWatch:
    """
    The static-segment statistics of the prepass, gathered during the analysis pass instead.

    The same batches and selection as :func:`_static_prepass` go into the same
    :class:`..core.segments.WindowStats`, so :meth:`segment` is the prepass' segment. Each time
    the window count has grown by a quarter the provisional segment is looked at; when it already
    shows motion the pass is abandoned (the record will need the prepass anyway). Motion that
    only the end of a record reveals costs the analysis twice.
    """

    def __init__(self):
        from ..core.segments import WindowStats

        self.stats = WindowStats()
        self._next_check = 64

    def update(self, stamps, gyro):
        self.stats.update(stamps, gyro)

    def moving(self):
        windows = len(self.stats._rows)
        if windows < self._next_check:
            return False
        self._next_check = windows + max(1, windows // 4)
        seg = self.stats.segment()
        return seg is not None and not seg.static_throughout

    def segment(self):
        return self.stats.segment()


def _analyze_one(path, label, imu_topic, temperature_topic, config, ref, thresholds, pool, jobs,
                 select, csv_writer, per_chunk, curve_store, allan_store, curves, batch_size,
                 progress, timing, *, reader=None):
    """Analyse one bag (``reader``: the bag already open, used by its first pass)."""
    args = (path, label, imu_topic, temperature_topic, config, ref, thresholds, pool, jobs,
            select, csv_writer, curve_store, curves, batch_size, progress, timing)
    start_s, end_s, static = select
    if static != 'auto':
        state = _analysis_pass(*args, segment=None, watch=None, say=warn, reader=reader)
        return _bag_doc(state, path, label, imu_topic, config, ref, select, None, per_chunk,
                        allan_store)
    # One read of the bag when it is static throughout (the usual noise recording): the pass
    # gathers the prepass' statistics while it analyses everything; only when they show motion
    # are its rows taken back and the bag read twice, as before (prepass, then the segment).
    mark = csv_writer.mark()
    watch = _MotionWatch()
    state = _analysis_pass(*args, segment=None, watch=watch, say=warn, reader=reader)
    if state is not None:
        segment = watch.segment()
        if segment is None or segment.static_throughout:
            return _bag_doc(state, path, label, imu_topic, config, ref, select, segment,
                            per_chunk, allan_store)
    csv_writer.rollback(mark)
    for axis in config.axes:
        curve_store.pop((label, axis), None)
    progress.restart()
    segment = _static_prepass(path, imu_topic, temperature_topic, config.rate_hz, batch_size,
                              start_s, end_s)
    # the first pass already printed the warnings of the stream's start
    state = _analysis_pass(*args, segment=segment, watch=None, say=lambda text: None)
    return _bag_doc(state, path, label, imu_topic, config, ref, select, segment, per_chunk,
                    allan_store)


def _analysis_pass(path, label, imu_topic, temperature_topic, config, ref, thresholds, pool, jobs,
                   select, csv_writer, curve_store, curves, batch_size, progress, timing, *,
                   segment, watch, say, reader=None):
    """
    Read the bag once and analyse it; None when ``watch`` saw motion (pass abandoned).

    ``reader``: the bag already open (closed at the end of the pass), else it is opened here.
    """
    engine = NoiseEngine(config, reference=ref or None, thresholds=thresholds)
    warnings = []
    time_source = 'header'
    start_s, end_s, static = select
    left = {'before_start': 0, 'after_end': 0, 'motion': 0}
    first_ns = None
    last_ns = -2 ** 63
    if reader is None:
        reader = _open(path, imu_topic, temperature_topic, config.rate_hz)
    with reader:
        _check_chunk_fits(reader.message_count, label, config)
        temps = reader.read_temperature()
        if temps is not None and temps[0].size:
            order = np.argsort(temps[0], kind='stable')
            t_stamp, t_value = temps[0][order].astype(np.float64), temps[1][order]
        else:
            t_stamp = t_value = None
        est_chunks = max(1, reader.message_count // config.chunk_size)
        stride = max(1, math.ceil(est_chunks / curves)) if curves else 0
        kept = collections.Counter()
        inflight = collections.deque()
        # Room for one decoded batch of chunks beyond the workers' own: the workers keep busy
        # while this process decodes the next batch.
        max_inflight = 4 * jobs + len(config.axes) * (batch_size // config.chunk_size + 1)
        rows = {a: [] for a in config.axes}
        done = 0
        t0 = time.monotonic()
        frame_id = None

        def want_curves(job):
            return bool(stride) and job.chunk % stride == 0 and kept[job.axis] < curves

        def finish(result):
            engine.record(result)
            csv_writer.write(label, result)
            rows[result.axis].append((result.t_mid_s, result.bias_rad_s, result.variance_rad2_s2,
                                      result.alpha_var, result.alpha_corr))
            if result.var_curve is not None:
                curve_store.setdefault((label, result.axis), []).append(
                    (result.chunk, result.var_curve, result.j_curve))

        def submit(jobs_list):
            for job in jobs_list:
                keep = want_curves(job)
                if keep:
                    kept[job.axis] += 1
                if pool is None:
                    finish(analyze_chunk(job, curves=keep))
                    continue
                inflight.append(pool.submit(analyze_chunk, job, curves=keep))
                while len(inflight) > max_inflight:
                    w0 = time.perf_counter()
                    result = inflight.popleft().result()
                    timing['wait_s'] += time.perf_counter() - w0
                    finish(result)

        accel = _AccelAllan(config.allan and config.allan_taus)
        non_physical = {'gyro': 0, 'accel': 0}
        batches = _plausible(reader.iter_batches(batch_size), non_physical)
        while True:
            d0 = time.perf_counter()
            batch = next(batches, None)
            timing['decode_s'] += time.perf_counter() - d0
            if batch is None:
                break
            frame_id = frame_id or batch.frame_id
            stamps = batch.stamp_ns
            if done == 0 and _stamps_unusable(stamps):
                if _stamps_unusable(batch.log_ns) or time_source == 'log':
                    raise InputDataError(
                        f'{label}: neither the header stamps nor the log times increase: '
                        'no time base')
                time_source = 'log'
                warnings.append(
                    "header stamps are not increasing (shuffled?): the recorder's log time is "
                    'used as the time base')
                say(f'{label}: {warnings[-1]}')
            if time_source == 'log':
                stamps = batch.log_ns
            if first_ns is None:
                first_ns = int(stamps[0])
            last_ns = max(last_ns, int(stamps.max()))
            keep = _select(stamps, first_ns, start_s, end_s, segment, left)
            done += len(batch)
            if watch is not None:
                watch.update(stamps[keep], batch.gyro[keep])
                if watch.moving():
                    for fut in inflight:
                        fut.cancel()
                    return None
            if not keep.any():
                continue
            gyro_b, accel_b = batch.gyro, batch.accel
            if not keep.all():
                stamps, gyro_b, accel_b = stamps[keep], gyro_b[keep], accel_b[keep]
            temp = None
            if t_stamp is not None:
                # Temperature is published slower than the IMU: linear interpolation at the IMU
                # stamps, held constant before the first and after the last temperature message.
                temp = np.interp(stamps.astype(np.float64), t_stamp, t_value)
            submit(engine.ingest(stamps, gyro_b, temp))
            accel.update(accel_b, engine.counts().rate_hz)
            progress.update(label, done, reader.message_count, engine.counts().chunks, t0)
        if done and left['before_start'] + left['after_end'] >= done:
            raise nothing_left_error(start_s=start_s, end_s=end_s, label=label,
                                     record_end_s=(last_ns - first_ns) / 1e9)
        submit(engine.flush())
        while inflight:
            w0 = time.perf_counter()
            result = inflight.popleft().result()
            timing['wait_s'] += time.perf_counter() - w0
            finish(result)
        progress.update(label, done, reader.message_count, engine.counts().chunks, t0, final=True)
        storage, undecodable = reader.storage, reader.undecodable_count
        temperature_topic_used = reader.temperature_topic
    return {'engine': engine, 'warnings': warnings, 'time_source': time_source, 'left': left,
            'first_ns': first_ns, 'last_ns': last_ns, 'accel': accel, 'rows': rows, 'done': done,
            'frame_id': frame_id, 'storage': storage, 'undecodable': undecodable,
            'temperature_topic': temperature_topic_used, 'non_physical': non_physical}


def _bag_doc(state, path, label, imu_topic, config, ref, select, segment, per_chunk,
             allan_store):
    """Summarise one analysed bag: its entry in summary.json (and the per-axis stores)."""
    engine, warnings, left = state['engine'], state['warnings'], state['left']
    first_ns, accel, rows = state['first_ns'], state['accel'], state['rows']
    done, frame_id, time_source = state['done'], state['frame_id'], state['time_source']
    storage, undecodable = state['storage'], state['undecodable']
    temperature_topic_used = state['temperature_topic']
    non_physical = state['non_physical']
    start_s, end_s, static = select
    counts = engine.counts()
    accel.update(None, counts.rate_hz)
    accel_readouts = accel.readouts(counts.rate_hz)
    summaries = engine.summary(allan=config.allan)
    verdicts = engine.health(summaries=summaries) if ref else {}
    tb = counts.timebase
    for text in (tb.warnings if tb is not None else ()):
        warnings.append(text)
        warn(f'{label}: {text}')
    if counts.out_of_order:
        text = (f'{counts.out_of_order} stamp(s) earlier than the latest before them: counted as '
                'out of order, not reordered (each also leaves a one-sample gap)')
        warnings.append(text)
        warn(f'{label}: {text}')
    if counts.longest_gaps:
        t_s, length_s, missing = counts.longest_gaps[0]
        text = (f'{counts.gaps} stamp gap(s), {counts.samples_lost} sample(s) missing; the '
                f'longest {length_s:.6g} s at t = {t_s:.3f} s after the first sample ({missing} '
                'samples missing)')
        warnings.append(text)
        warn(f'{label}: {text}')
    left_out = dict(left)
    if segment is not None and not segment.static_throughout and first_ns is not None:
        # The segments end on window boundaries; a time range never runs past the last sample.
        end_ns = min(segment.end_ns, state['last_ns'])
        left_out['static_segment_s'] = [(segment.start_ns - first_ns) / 1e9,
                                        (end_ns - first_ns) / 1e9]
        left_out['static_segments_s'] = [[(a - first_ns) / 1e9,
                                          (min(b, state['last_ns']) - first_ns) / 1e9]
                                         for a, b in segment.segments]
    if any(non_physical.values()):
        text = (f"{non_physical['gyro']} angular rate value(s) beyond {MAX_RATE_RAD_S:g} rad/s "
                f"and {non_physical['accel']} specific force value(s) beyond "
                f'{MAX_SPECIFIC_FORCE_M_S2:g} m/s^2 are not measurements (corrupt record or '
                'wrong unit): treated as NaN, their chunks left out')
        warnings.append(text)
        warn(f'{label}: {text}')
    if counts.chunks and counts.tail_samples > 0.1 * counts.samples:
        size = config.chunk_size
        better = counts.samples // (counts.chunks + 1) if counts.chunks else counts.samples
        hint = (f'; --chunk-size {better} would cut {counts.chunks + 1} chunks'
                if better >= config.memory + 2 else '')
        text = (f'{counts.tail_samples} of {counts.samples} samples '
                f'({100.0 * counts.tail_samples / counts.samples:.0f} %) after the last complete '
                'chunk of '
                f'{size} are not in the chunk tables (they are in the Allan deviation){hint}')
        warnings.append(text)
        warn(f'{label}: {text}')
    if any(left.values()):
        parts = [f'{left["before_start"]} before --start'] if left['before_start'] else []
        parts += [f'{left["after_end"]} after --end'] if left['after_end'] else []
        if left['motion']:
            a, b = left_out['static_segment_s']
            parts.append(f'{left["motion"]} in motion (analysing the longest static segment, '
                         f't = {a:.1f}-{b:.1f} s after the first sample)')
        text = f'{sum(left.values())} of {done} samples left out: ' + ', '.join(parts)
        warnings.append(text)
        warn(f'{label}: {text}')
    for axis, s in summaries.items():
        per_chunk.setdefault(axis, []).append((label, np.array(rows[axis]).reshape(-1, 5)))
        if s.allan is not None:
            allan_store[(label, axis)] = (s.allan, s.noise_terms, s.readout)
    return {
        'label': label,
        'path': str(path),
        'topic': imu_topic,
        'storage': storage,
        'frame_id': frame_id,
        'temperature_topic': temperature_topic_used,
        'messages': done,
        'undecodable_messages': undecodable,
        'non_physical_values': dict(non_physical),
        'rate_hz': report._json_num(counts.rate_hz),
        'rate_method': counts.rate_method,
        'time_source': time_source,
        'stamps_bursty': counts.bursty,
        'stamp_jitter_s': report._json_num(counts.jitter_s),
        'timebase': tb.as_dict() if tb is not None else None,
        'warnings': warnings,
        'left_out': left_out,
        'window_s': [start_s, end_s],
        'static_detection': static,
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
        'tail_samples': counts.tail_samples,
        'discarded_samples': counts.discarded_samples,
        'discarded_partials': counts.discarded_partials,
        'allan_status': engine.allan_status,
        'accelerometer_allan': {a: report.accelerometer_readout_dict(r)
                                for a, r in accel_readouts.items()},
        '_accelerometer_readouts': accel_readouts,
        'axes': {
            axis: report.axis_summary_dict(s, verdict=verdicts.get(axis))
            for axis, s in summaries.items()
        },
    }


class _AccelAllan:
    """
    Allan deviation of the accelerometer axes, for the accelerometer_* keys of imu.yaml.

    The IEEE 952 model is fitted to the specific-force rate in m/s^2 exactly as to the angular
    rate: the fitted "angle random walk" is then the velocity random walk (m/s/sqrt(s) =
    m/s^2/sqrt(Hz), Kalibr's accelerometer_noise_density) and the "rate random walk" the
    acceleration random walk (m/s^3/sqrt(Hz), accelerometer_random_walk). Samples wait until the
    engine knows the sample rate.
    """

    def __init__(self, taus):
        self.taus = taus or None
        self.acc = None
        self.pending = []

    def update(self, accel, rate_hz):
        if self.taus is None:
            return
        if accel is not None:
            self.pending.append(np.asarray(accel, dtype=np.float64))
        if not math.isfinite(rate_hz) or not self.pending:
            return
        from ..core.allan import AllanAccumulator

        if self.acc is None:
            self.acc = [AllanAccumulator(rate_hz, taus=self.taus) for _ in AXES]
        for block in self.pending:
            for k, acc in enumerate(self.acc):
                col = block[:, k]
                acc.update(col[np.isfinite(col)])
        self.pending = []

    def readouts(self, rate_hz):
        """Return ``{axis: core.readout.AllanReadout or None}`` of the accelerometer axes."""
        if self.acc is None:
            return {}
        from ..core.readout import read_allan
        from ..core.timebase import rescale_allan

        out = {}
        for axis, acc in zip(AXES, self.acc):
            try:
                out[axis] = read_allan(rescale_allan(acc.result(), rate_hz))
            except (InputDataError, ParameterError, ValueError):
                out[axis] = None  # e.g. a constant (all-zero) accelerometer: nothing to read
        return out


def _write_allan_outputs(out, doc, allan_store, accel_readouts, figures):
    """Write allan.csv (always, possibly header-only), imu.yaml and the Allan figure."""
    entries, fig_series = [], {}
    for (label, axis), (result, terms, _) in allan_store.items():
        tau, adev, lo, hi, n = report.allan_curve(result)
        entries.append((label, axis, tau, adev, lo, hi, n))
        fig_series.setdefault(axis, []).append((label, tau, adev, lo, hi,
                                                report.allan_fit_lines(terms, tau)))
    report.write_allan_csv(out / 'allan.csv', entries)
    files = [out / 'allan.csv']
    first = doc['bags'][0]
    gyro = [allan_store[(first['label'], a)][2] for a in first['axes']
            if (first['label'], a) in allan_store]
    record_s = first['duration_s']
    accel = accel_readouts.get(first['label']) or {}
    accel_noise = (report.kalibr_noise(list(accel.values()), record_s=record_s)
                   if any(r is not None for r in accel.values()) else None)
    topic, note = first['topic'], ''
    if first['storage'] in ('csv', 'ulog'):
        # a table or a ULog has no ROS topic: name the usual raw IMU topic and say so
        topic = report.DEFAULT_IMU_TOPIC
        what = (f"a {first['storage']} file" if first['topic'] == first['storage']
                else f"a {first['storage']} file ({first['topic']})")
        note = f'the input was {what}, not a bag: set the topic your IMU driver publishes'
    report.write_imu_yaml(out / 'imu.yaml', rostopic=topic, rostopic_note=note,
                          update_rate_hz=first['rate_hz'] or float('nan'),
                          gyroscope=report.kalibr_noise(gyro, record_s=record_s),
                          accelerometer=accel_noise,
                          source=f"from bag {first['label']} ({first['path']}), largest over axes "
                          f"{', '.join(first['axes'])}")
    files.append(out / 'imu.yaml')
    if figures and fig_series:
        report.plot_allan(out / 'allan.png', fig_series)
        files.append(out / 'allan.png')
    return files


def _safe(name):
    return ''.join(c if c.isalnum() or c in '-_.' else '_' for c in name)


def _write_figures(out, config, per_chunk, curve_store):
    files = []
    bias = {a: [(label, r[:, 0], r[:, 1]) for label, r in v] for a, v in per_chunk.items()}
    var = {a: [(label, r[:, 0], r[:, 2]) for label, r in v] for a, v in per_chunk.items()}
    for name, data, quantity in (('bias.png', bias, 'bias'), ('variance.png', var, 'variance')):
        if report.plot_per_chunk(out / name, data, quantity=quantity):
            files.append(out / name)
    for (label, axis), rows in curve_store.items():
        path = out / f'curves_{_safe(label)}_{axis}.png'
        report.plot_curves(path, config.alphas, np.array([r[0] for r in rows]),
                           np.array([r[1] for r in rows]), np.array([r[2] for r in rows]),
                           title=f'{label}, axis {axis}: var(alpha) and J(alpha) over chunks')
        files.append(path)
    return files


def parse_order_grid(text):
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


def _body(argv):
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as err:  # argparse: usage errors exit 2, --help/--version 0
        return err.code if isinstance(err.code, int) else 2
    alphas = parse_order_grid(args.order_grid)
    axes = AXES if args.axis == 'all' else (args.axis,)
    if args.batch_size < 1:
        raise ParameterError(f'--batch-size must be >= 1, got {args.batch_size}')
    config = EngineConfig(chunk_size=args.chunk_size, axes=axes, alphas=alphas, memory=args.memory,
                          demean=not args.no_demean, max_lag=args.max_lag, rate_hz=args.rate_hz,
                          gap_factor=args.gap_factor, gap_policy=args.gap_policy,
                          allan=not args.no_allan, allan_taus=args.allan_taus)
    jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
    doc = analyze_bags(args.bags, out_dir=args.out, labels=args.label, topic=args.topic,
                       temperature_topic=args.temperature_topic, config=config, jobs=jobs,
                       reference=args.reference, reference_bag=args.reference_bag,
                       figures=not args.no_figures, curves=args.curves,
                       batch_size=args.batch_size, progress=not args.quiet, command=[PROG, *argv],
                       start_s=args.start, end_s=args.end, static=args.static,
                       scheduler=args.scheduler, html=not args.no_html)
    if not args.quiet:
        _print_summary(doc)
    return 0


def _order_text(axis_doc, key):
    # A mean over two separate basins (the model's 0/1 alias) is a number no chunk is near.
    if axis_doc.get(key + '_multimodal'):
        return 'modes ' + report._modes_text(axis_doc[key + '_modes'])
    return report._fmt(axis_doc[key + '_mean'], '.3f')


def _print_summary(doc):
    for b in doc['bags']:
        print(
            f"{b['label']}: {b['samples']} samples on {b['topic']} ({b['storage']}), "
            f"{b['duration_s']:.1f} s at {b['rate_hz'] or float('nan'):.6g} Hz ({b['rate_method']}"
            f"{', bursty stamps' if b['stamps_bursty'] else ''}, stamp jitter "
            f"{1e3 * (b['stamp_jitter_s'] or float('nan')):.3g} ms), {b['samples_lost']} lost in "
            f"{b['gaps']} gap(s), {b['clock_steps']} clock step(s), "
            f"{b['out_of_order_stamps']} out-of-order stamp(s), "
            f"{b['equal_stamps']} equal to the one before, "
            f"{b['tail_samples']} tail sample(s) not analysed")
        for axis, a in b['axes'].items():
            line = (f"  {axis}: {a['chunks']} chunks, drift "
                    f"{report._fmt(a['offset_drift_deg_s_per_h'], '.5f')} "
                    f"(deg/s)/h, variance {report._fmt(a['mean_variance_deg2_s2'], '.5g')} "
                    '(deg/s)^2, ' f"order var {_order_text(a, 'alpha_var')}, corr "
                    f"{_order_text(a, 'alpha_corr')}")
            sheet = a.get('allan_datasheet')
            if sheet:
                line += ', ' + report.readout_text(sheet)
            if a['nan_samples']:
                line += f", {a['nan_samples']} NaN sample(s)"
            if 'health' in a:
                line += f" -> {a['health']['level']}: {a['health']['message']}"
            print(line)
    t = doc['_timing']
    print(f"time {t['total_s']:.1f} s (decode {t['decode_s']:.1f} s)")
    out = Path(doc['_files'][0]).parent
    print(f'wrote {len(doc["_files"])} files to {out}: '
          + ', '.join(Path(f).name for f in doc['_files']))


def main(argv=None):
    """
    Run gyro_noise_analyze.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: sys.argv[1:]).

    Returns
    -------
    int
        Exit code (docs/offline_tool.md).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
