"""
ROS 2 node ``noise_analyzer``: live noise characterisation of a gyro, with diagnostics.

Subscribes ``imu/data_raw`` (``sensor_msgs/Imu``, sensor-data QoS) and, optionally,
``imu/temperature`` (``sensor_msgs/Temperature``), and runs the streaming engine of
:mod:`gyro_noise_ros.core.engine` on them: the same chunks, per-chunk numbers, sequence statistics
(paper 000 Tables 3-6) and health verdicts as the offline tool ``gyro_noise_analyze`` gives for a
recording of the same messages.

Ingestion. At 6.66 kHz a Python callback per message costs about half a core, so the subscriptions
are ``raw=True`` (serialised CDR) and sit in a callback group the executor never runs
(:class:`~gyro_noise_ros.nodes.recorder.PolledGroup`); a timer takes every queued message each
``drain_period_s`` with ``take_message`` and decodes the batch in bulk with numpy
(:func:`gyro_noise_ros.bag.decode_imu`, the decoder of the offline tool). The QoS history
(``queue_depth`` = 20,000 messages, 3 s at 6.66 kHz, 0.75 s at 4x) holds far more than one drain
period, so nothing is overwritten even when the executor thread waits for the GIL or the CPU on a
busy machine (measured: 5,000 lost messages at 4x under load, 20,000 did not; see
``bench/bench_analyzer_node.py``).

Analysis. :meth:`NoiseEngine.ingest` (cheap) runs in the executor thread; each complete chunk becomes
a job in a bounded queue (``analysis_queue_chunks`` chunks of all axes) served by one worker thread
running the heavy identification (both methods on the full order grid; numpy/scipy FFTs release the
GIL). When the queue is full the chunk is skipped (:meth:`NoiseEngine.skip`) and counted in the
diagnostics (``Chunks skipped``), so memory never grows. Results are handed back to the executor
thread, which alone mutates the engine (record, summary, health), so no lock is needed.

Outputs (topics relative to the node, ``~/``, so several analyzers can run side by side):

- ``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``): after every chunk and every
  ``diagnostics_period_s``, one status per axis named ``'<node name>: axis x'`` with the health
  verdict of :mod:`gyro_noise_ros.core.health` (level and one sentence), its items, and the last
  chunk's numbers, all with units in the keys.
- ``~/bias`` (rad/s), ``~/variance`` ((rad/s)^2), ``~/alpha_var``, ``~/alpha_corr``, ``~/f_var``,
  ``~/f_corr`` (dimensionless), ``~/offset_drift`` (rad/s^2, the sequence's least-squares slope so far,
  or over the last ``history_chunks`` chunks): ``geometry_msgs/Vector3Stamped`` per chunk with
  x, y, z = axes (NaN for an axis not analysed or whose chunk was not ``ok``), stamped with the
  chunk's first sample, ``frame_id`` of the IMU. Plot them with PlotJuggler or Foxglove.

``noise_analyzer --echo`` instead runs a small monitor that prints every ``/diagnostics`` status of
the analyzers in a compact line (what ``make demo`` shows).
"""

import math
import queue
import sys
import threading
import time
from collections import deque
from dataclasses import fields, replace

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Imu, Temperature

from ..bag import decode_imu, decode_temperature
from ..core.engine import AXES, GAP_POLICIES, EngineConfig, NoiseEngine
from ..core.fractional import DEFAULT_MEMORY, make_grid
from ..core.health import HealthThresholds
from ..errors import GyroNoiseError, ParameterError
from ._ros_common import (ParamSpec, PolledGroup, SequenceGapCounter, declare_parameter_table, diagnostic_array,
                          diagnostic_status, diagnostics_publisher, run_node, sensor_data_qos, take_all,
                          unused_callback)


NODE_NAME = 'noise_analyzer'

_DEG = 180.0 / math.pi
_NS = 1_000_000_000

# Description and unit of every health threshold (the fields of HealthThresholds, whose module
# docstring explains the defaults); one parameter each, same name.
_THRESHOLD_DOCS = {
    'drift_ratio_warn': ('WARN when |offset drift| exceeds this multiple of the reference drift', 'x'),
    'drift_ratio_error': ('ERROR when |offset drift| exceeds this multiple of the reference drift', 'x'),
    'drift_abs_warn_deg_s_per_h': ('WARN above this |offset drift| when there is no reference',
                                   '(deg/s)/h'),
    'drift_abs_error_deg_s_per_h': ('ERROR above this |offset drift| when there is no reference',
                                    '(deg/s)/h'),
    'drift_min_sigma': ('Judge the drift only when |slope| exceeds this many standard errors', 'sigma'),
    'min_chunks': ('Chunks needed before drift, order and variance are judged', 'chunks'),
    'alpha_var_tolerance': ('WARN when the mean variance-method order leaves the reference by more '
                            '(ERROR at twice)', ''),
    'alpha_corr_tolerance': ('WARN when the mean correlation-method order leaves the reference by '
                             'more (ERROR at twice)', ''),
    'variance_ratio_tolerance': ('WARN when mean variance / reference leaves 1 +/- this (ERROR at '
                                 'twice)', ''),
    'lost_fraction_warn': ('WARN above this fraction of samples lost (from stamps)', ''),
    'lost_fraction_error': ('ERROR above this fraction of samples lost (from stamps)', ''),
    'skipped_fraction_warn': ('WARN above this fraction of chunks skipped (analysis behind)', ''),
    'skipped_fraction_error': ('ERROR above this fraction of chunks skipped (analysis behind)', ''),
    'stale_after_s': ('STALE after this long without data', 's'),
}


def _threshold_rows():
    rows = []
    for f in fields(HealthThresholds):
        description, unit = _THRESHOLD_DOCS.get(f.name, (f'Health threshold {f.name}', ''))
        default = f.default
        if isinstance(default, float):
            rows.append(ParamSpec(f.name, default, description, unit=unit, read_only=True,
                                  min_value=0.0, max_value=1.0e9))
        else:
            rows.append(ParamSpec(f.name, int(default), description, unit=unit, read_only=True,
                                  min_value=0, max_value=1_000_000))
    return tuple(rows)


#: The parameter table (``config/noise_analyzer.yaml`` lists every row with its default and unit).
PARAMETERS = (
    ParamSpec('chunk_size', 10000, 'Samples per analysed chunk (paper: 10,000)', unit='samples',
              read_only=True, min_value=4, max_value=10_000_000),
    ParamSpec('axes', 'x,y,z', 'Axes to analyse, comma-separated among x, y, z', read_only=True),
    ParamSpec('order_grid_start', 0.0, 'First fractional order of the search grid', read_only=True,
              min_value=-5.0, max_value=5.0),
    ParamSpec('order_grid_stop', 2.0, 'Last fractional order of the search grid', read_only=True,
              min_value=-5.0, max_value=5.0),
    ParamSpec('order_grid_step', 0.01, 'Step of the fractional-order grid', read_only=True,
              min_value=1.0e-6, max_value=10.0),
    ParamSpec('memory', DEFAULT_MEMORY, 'Memory length L of the truncated GL difference (paper: 1000)',
              unit='samples', read_only=True, min_value=1, max_value=10_000_000),
    ParamSpec('demean', True, 'Remove the chunk mean before the order identification', read_only=True),
    ParamSpec('max_lag', -1, 'Largest lag M of the correlation criterion J (-1: all lags)',
              unit='samples', read_only=True, min_value=-1, max_value=10_000_000),
    ParamSpec('rate_hz', 0.0, 'Nominal sample rate (0: the median stamp step of the first samples)',
              unit='Hz', read_only=True, min_value=0.0, max_value=1.0e6),
    ParamSpec('gap_factor', 1.5, 'A stamp step above this many nominal periods is a gap',
              unit='periods', read_only=True, min_value=1.0001, max_value=1.0e6),
    ParamSpec('gap_policy', 'flag', 'What a gap does to its chunk: flag (keep, count), split (restart '
              'the chunk after it), drop (leave the chunk out)', read_only=True, choices=GAP_POLICIES),
    ParamSpec('history_chunks', 0, 'Chunks per axis kept for the sequence statistics and the drift '
              '(0: the whole run; e.g. 40 judges the last minute at 6.66 kHz)', unit='chunks',
              read_only=True, min_value=0, max_value=100_000_000),
    ParamSpec('allan', True, 'Keep an incremental Allan deviation of the run (ADEV keys)',
              read_only=True),
    ParamSpec('reference_summary', '', 'summary.json of gyro_noise_analyze for a reference '
              'recording (one bag); empty: absolute drift limits only', read_only=True),
    *_threshold_rows(),
    ParamSpec('use_temperature', True, 'Subscribe imu/temperature and report the chunk mean',
              read_only=True),
    ParamSpec('hardware_id', '', 'hardware_id of the diagnostics (empty: the frame_id of the data)',
              read_only=True),
    ParamSpec('diagnostics_period_s', 1.0, 'Period of /diagnostics between chunks', unit='s',
              read_only=True, min_value=0.05, max_value=3600.0),
    ParamSpec('allan_period_s', 10.0, 'Period of the Allan deviation update in the diagnostics',
              unit='s', read_only=True, min_value=0.1, max_value=86400.0),
    ParamSpec('queue_depth', 20000, 'QoS history depth of the subscriptions', unit='messages',
              read_only=True, min_value=10, max_value=1_000_000),
    # 20 ms, not 10: each executor wake-up costs a fixed few hundred microseconds in rclpy (wait-set
    # construction) and in the per-batch numpy calls; measured ingestion at 6.66 kHz fell from 24 % to
    # 14 % of a core (bench/bench_analyzer_node.py), and the 20,000-message history covers 3 s.
    ParamSpec('drain_period_s', 0.02, 'Period of the loop taking queued messages', unit='s',
              read_only=True, min_value=0.001, max_value=0.5),
    ParamSpec('analysis_queue_chunks', 4, 'Chunks (of all axes) waiting for analysis before new ones '
              'are skipped', unit='chunks', read_only=True, min_value=1, max_value=10_000),
    ParamSpec('log_chunks', False, 'Log one line per analysed chunk', read_only=True),
)

#: Numeric per-chunk topics: name -> (ChunkResult field, unit) for docs and tests.
CHUNK_TOPICS = {
    'bias': ('bias_rad_s', 'rad/s'),
    'variance': ('variance_rad2_s2', '(rad/s)^2'),
    'alpha_var': ('alpha_var', '-'),
    'alpha_corr': ('alpha_corr', '-'),
    'f_var': ('f_var', '-'),
    'f_corr': ('f_corr', '-'),
}


def parse_axes(text):
    """
    Parse the ``axes`` parameter (``'x,y,z'``, ``'z'``, ``'xyz'``) into a tuple of axis names.

    Raises
    ------
    ParameterError
        Unknown, repeated or no axis.
    """
    raw = str(text).replace(' ', '')
    names = raw.split(',') if ',' in raw else list(raw)
    names = [n for n in names if n]
    if not names or any(n not in AXES for n in names) or len(set(names)) != len(names):
        raise ParameterError(f"parameter 'axes' = {text!r} must name distinct axes among x, y, z "
                             "(e.g. 'x,y,z' or 'z')")
    return tuple(names)


def engine_config_from(params):
    """
    Build the :class:`EngineConfig` from the node's parameter values.

    Parameters
    ----------
    params : dict
        Name to value, as :func:`declare_parameter_table` returns.

    Returns
    -------
    EngineConfig

    Raises
    ------
    ParameterError
        An inconsistent combination (e.g. chunk_size below memory + 2), naming the parameter.
    """
    alphas = make_grid(params['order_grid_start'], params['order_grid_stop'], params['order_grid_step'])
    try:
        return EngineConfig(
            chunk_size=params['chunk_size'], axes=parse_axes(params['axes']), alphas=alphas,
            memory=params['memory'], demean=params['demean'],
            max_lag=None if params['max_lag'] < 0 else params['max_lag'],
            rate_hz=params['rate_hz'] or None, gap_factor=params['gap_factor'],
            gap_policy=params['gap_policy'], allan=params['allan'],
            history_chunks=params['history_chunks'])
    except ParameterError as err:
        raise ParameterError(f'parameters chunk_size/memory/max_lag/order grid: {err}') from err


def thresholds_from(params):
    """Build :class:`HealthThresholds` from the parameter values (same names)."""
    return HealthThresholds(**{f.name: params[f.name] for f in fields(HealthThresholds)})


def warm_up(config):
    """
    Run the analysis path once on synthetic data so the first real chunk does not stall.

    Builds (and caches) the order identifier of ``config``, plans its FFTs, and compiles or loads the
    numba kernels of the Allan accumulator.

    Parameters
    ----------
    config : EngineConfig
    """
    rng = np.random.default_rng(0)
    n = int(config.chunk_size) + 1
    engine = NoiseEngine(replace(config, rate_hz=config.rate_hz or 1000.0))
    stamps = np.arange(n, dtype=np.int64) * int(_NS / (config.rate_hz or 1000.0))
    jobs = engine.ingest(stamps, rng.standard_normal((n, 3)) * 1e-3)
    for job in jobs[:1]:
        engine.record(engine.analyze(job))
    engine.summary(allan=config.allan)


def _fmt(value, digits=4):
    if value is None or not math.isfinite(value):
        return 'nan'
    return f'{value:.{digits}g}'


def _level_byte(level):
    return bytes([{'OK': 0, 'WARN': 1, 'ERROR': 2, 'STALE': 3}[level]])


class NoiseAnalyzerNode(Node):
    """
    Live noise characterisation node (see the module docstring).

    Parameters
    ----------
    **kwargs
        Passed to :class:`rclpy.node.Node` (e.g. ``parameter_overrides`` in tests).

    Raises
    ------
    ParameterError
        A parameter is invalid (one clear line through :func:`main`).
    """

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        p = declare_parameter_table(self, PARAMETERS)
        self.config = engine_config_from(p)
        self.thresholds = thresholds_from(p)
        self.engine = NoiseEngine(self.config, reference=p['reference_summary'] or None,
                                  thresholds=self.thresholds)
        self._params = p
        self._hardware_id = p['hardware_id']
        self._frame_id = ''
        t0 = time.monotonic()
        warm_up(self.config)
        self.get_logger().info(f'analysis warmed up in {time.monotonic() - t0:.2f} s')

        self.messages_received = 0
        self.messages_undecodable = 0
        self._transport = SequenceGapCounter()
        self._last_data = None
        self._temperature = None  # (stamp_ns array, degC array) of the latest temperatures
        self._ingest_error = ''  # why the latest rejected batch was rejected
        self._rejected_batches = 0
        self._last_batch_rejected = False
        self._last = {}  # axis -> latest ChunkResult
        self._chunks = {}  # chunk index -> {axis: ChunkResult} until all axes are in
        self.results = deque(maxlen=10_000)  # recent ChunkResults in completion order (tests, tools)
        self._allan_keys = {}
        self._allan_due = 0.0

        self._jobs = queue.Queue(maxsize=p['analysis_queue_chunks'] * len(self.config.axes))
        self._done = queue.SimpleQueue()
        self._stop = threading.Event()
        self._worker = threading.Thread(target=self._work, name='noise_analyzer_worker', daemon=True)
        self._worker.start()

        group = PolledGroup()
        qos = sensor_data_qos(p['queue_depth'])
        self._imu_sub = self.create_subscription(Imu, 'imu/data_raw', unused_callback, qos, raw=True,
                                                 callback_group=group)
        self._temperature_sub = None
        if p['use_temperature']:
            self._temperature_sub = self.create_subscription(
                Temperature, 'imu/temperature', unused_callback, qos, raw=True, callback_group=group)
        self._diag_pub = diagnostics_publisher(self)
        topic_qos = QoSProfile(depth=100)
        self._chunk_pubs = {name: self.create_publisher(Vector3Stamped, '~/' + name, topic_qos)
                            for name in (*CHUNK_TOPICS, 'offset_drift')}
        self.create_timer(p['drain_period_s'], self.drain)
        self.create_timer(p['diagnostics_period_s'], self.publish_diagnostics)
        self.get_logger().info(
            f'analysing {self._imu_sub.topic_name} axes {",".join(self.config.axes)}, chunks of '
            f'{self.config.chunk_size} samples, orders {self.config.alphas[0]:g}:'
            f'{self.config.alphas[-1]:g} ({self.config.alphas.size} points), '
            + ('reference ' + p['reference_summary'] if p['reference_summary'] else
               'absolute drift limits'))

    # ---- worker -----------------------------------------------------------------------------------

    def _work(self):
        # The OS thread id lets a profiler (bench/bench_analyzer_node.py) split the node's CPU time
        # between ingestion (executor thread) and analysis (this thread).
        self.get_logger().info(f'analysis worker started (native thread id {threading.get_native_id()})')
        while not self._stop.is_set():
            try:
                job = self._jobs.get(timeout=0.2)
            except queue.Empty:
                continue
            try:
                self._done.put((job, self.engine.analyze(job), None))
            except Exception as err:  # noqa: BLE001 - reported in diagnostics, the node goes on
                self._done.put((job, None, err))

    # ---- ingestion (executor thread) -----------------------------------------------------------

    def drain(self):
        """Take the queued messages, feed the engine, queue the chunks, publish finished ones."""
        if self._temperature_sub is not None:
            raws, _, _ = take_all(self._temperature_sub, Temperature)
            if raws:
                stamp_ns, temperature_c = decode_temperature(raws)
                if self._temperature is not None:
                    # Keep the previous latest message so samples between the two batches are
                    # interpolated, as the offline tool does over the whole bag.
                    stamp_ns = np.concatenate((self._temperature[0][-1:], stamp_ns))
                    temperature_c = np.concatenate((self._temperature[1][-1:], temperature_c))
                order = np.argsort(stamp_ns, kind='stable')
                self._temperature = (stamp_ns[order], temperature_c[order])
        raws, _, sequence = take_all(self._imu_sub, Imu)
        if raws:
            self._ingest(raws, sequence)
        self._collect()

    def _ingest(self, raws, sequence):
        self.messages_received += len(raws)
        self._transport.update(sequence)
        self._last_data = time.monotonic()
        batch = decode_imu(raws, skip_undecodable=True)
        self.messages_undecodable += len(raws) - len(batch)
        if not len(batch):
            return
        if not self._frame_id:
            self._frame_id = batch.frame_id
        try:
            jobs = self.engine.ingest(batch.stamp_ns, batch.gyro, self._temperature_at(batch.stamp_ns))
        except GyroNoiseError as err:
            self._ingest_error = str(err)
            self._rejected_batches += 1
            self._last_batch_rejected = True
            self.get_logger().error(f'samples rejected: {err}', throttle_duration_sec=5.0)
            return
        self._last_batch_rejected = False
        for job in jobs:
            try:
                self._jobs.put_nowait(job)
            except queue.Full:
                self._finished(self.engine.skip(job, 'analysis fell behind'))

    def _temperature_at(self, stamp_ns):
        if self._temperature is None:
            return None
        t_stamp, t_value = self._temperature
        if t_stamp.size == 1:
            return float(t_value[0])
        # Linear between temperature messages, held constant after the latest (the offline tool,
        # which sees the whole bag, interpolates towards the next one there instead).
        return np.interp(stamp_ns.astype(np.float64), t_stamp.astype(np.float64), t_value)

    def _collect(self):
        while True:
            try:
                job, result, err = self._done.get_nowait()
            except queue.Empty:
                return
            if err is not None:
                self.get_logger().error(f'analysis of chunk {job.chunk} axis {job.axis} failed: {err}')
                result = self.engine.skip(job, f'analysis failed: {err}')
            else:
                self.engine.record(result)
            self._finished(result)

    def _finished(self, result):
        self.results.append(result)
        self._last[result.axis] = result
        if self._params['log_chunks']:
            self.get_logger().info(
                f'chunk {result.chunk} axis {result.axis}: {result.status}, bias '
                f'{_fmt(result.bias_rad_s * _DEG)} deg/s, alpha {_fmt(result.alpha_var)} (var) '
                f'{_fmt(result.alpha_corr)} (corr)')
        per_chunk = self._chunks.setdefault(result.chunk, {})
        per_chunk[result.axis] = result
        if len(per_chunk) == len(self.config.axes):
            del self._chunks[result.chunk]
            self._publish_chunk(per_chunk)
            self.publish_diagnostics()

    # ---- outputs ------------------------------------------------------------------------------------

    def _publish_chunk(self, per_axis):
        first = next(iter(per_axis.values()))
        msg = Vector3Stamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(first.stamp_start_ns), _NS)
        msg.header.frame_id = self._frame_id

        def values(get):
            out = []
            for axis in AXES:
                r = per_axis.get(axis)
                out.append(float(get(r)) if r is not None and r.status == 'ok' else math.nan)
            return out

        for name, (field, _) in CHUNK_TOPICS.items():
            msg.vector.x, msg.vector.y, msg.vector.z = values(lambda r, f=field: getattr(r, f))
            self._chunk_pubs[name].publish(msg)
        summaries = self.engine.summary(allan=False)
        msg.vector.x, msg.vector.y, msg.vector.z = values(
            lambda r: summaries[r.axis].sequence.drift.slope)
        self._chunk_pubs['offset_drift'].publish(msg)

    def _update_allan(self, summaries):
        now = time.monotonic()
        if not self.config.allan or now < self._allan_due:
            return
        self._allan_due = now + self._params['allan_period_s']
        try:
            with_allan = self.engine.summary(allan=True)
        except GyroNoiseError as err:
            self.get_logger().warn(f'Allan deviation not available: {err}', throttle_duration_sec=60.0)
            return
        for axis, s in with_allan.items():
            self._allan_keys[axis] = allan_values(s)

    def diagnostics(self):
        """
        Build the ``DiagnosticArray`` of the current state (one status per analysed axis).

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticArray
        """
        since = None if self._last_data is None else time.monotonic() - self._last_data
        summaries = self.engine.summary(allan=False)
        self._update_allan(summaries)
        verdicts = self.engine.health(seconds_since_data=since, summaries=summaries)
        counts = next(iter(summaries.values())).stream
        hardware_id = self._hardware_id or self._frame_id or 'unknown'
        statuses = []
        for axis, verdict in verdicts.items():
            s = summaries[axis]
            last = self._last.get(axis)
            values = [(k, v) for k, v, _ in verdict.items]
            if last is not None:
                values += [
                    ('Last chunk', f'{last.chunk} ({last.status})'),
                    ('Bias (deg/s)', _fmt(last.bias_rad_s * _DEG)),
                    ('Variance ((deg/s)^2)', _fmt(last.variance_rad2_s2 * _DEG ** 2)),
                    ('Last chunk fractional order, variance method', _fmt(last.alpha_var, 3)),
                    ('Last chunk fractional order, correlation method', _fmt(last.alpha_corr, 3)),
                    ('Last chunk f, variance method', _fmt(last.f_var)),
                    ('Last chunk f, correlation method', _fmt(last.f_corr)),
                    ('Last chunk samples lost', str(last.samples_lost)),
                    ('Temperature (degC)', _fmt(last.temperature_c, 4)),
                ]
            values += self._allan_keys.get(axis) or allan_values(None)
            values += [
                ('Samples received', str(counts.samples)),
                ('Sample rate (Hz)', _fmt(counts.rate_hz, 6)),
                ('Gaps', str(counts.gaps)),
                ('Chunk size (samples)', str(self.config.chunk_size)),
                ('Analysis queue (chunks)', str(self._jobs.qsize())),
                ('Messages dropped before the node', str(self._transport.missing)),
                ('Messages undecodable', str(self.messages_undecodable)),
                ('Mean temperature (degC)', _fmt(s.temperature_mean_c, 4)),
            ]
            level, message = verdict.level, verdict.message
            if self._rejected_batches:
                values.append(('Batches rejected', str(self._rejected_batches)))
                values.append(('Last rejection', self._ingest_error))
                # ERROR while data arrives but is rejected (rather than STALE for 'no chunk yet');
                # once batches are accepted again only the count stays.
                silent = since is not None and since > self.thresholds.stale_after_s
                if self._last_batch_rejected and not silent:
                    level, message = 'ERROR', f'Samples rejected: {self._ingest_error}.'
            statuses.append(diagnostic_status(f'{self.get_name()}: axis {axis}', hardware_id,
                                              _level_byte(level), message, values))
        return diagnostic_array(self.get_clock().now().to_msg(), statuses)

    def publish_diagnostics(self):
        """Publish :meth:`diagnostics` on ``/diagnostics``."""
        self._diag_pub.publish(self.diagnostics())

    def destroy_node(self):
        self._stop.set()
        self._worker.join(timeout=5.0)
        return super().destroy_node()


def allan_values(summary):
    """
    Diagnostic key/values of an axis' Allan deviation: ADEV at 1 s, its minimum, fitted noise terms.

    Parameters
    ----------
    summary : AxisSummary or None
        With ``allan`` (and possibly ``noise_terms``) filled in; None or no Allan result gives
        ``'n/a'`` values (the keys stay, so dashboards see a stable set).

    Returns
    -------
    list of (str, str)
    """
    out = {'ADEV at 1 s (deg/s)': 'n/a', 'ADEV minimum (deg/s)': 'n/a', 'ADEV minimum at tau (s)': 'n/a',
           'Angle random walk (deg/sqrt(h))': 'n/a', 'Bias instability (deg/h)': 'n/a'}
    result = None if summary is None else summary.allan
    if result is not None:
        tau = np.asarray(result.tau_s, dtype=np.float64)
        adev = np.asarray(result.adev, dtype=np.float64)
        good = np.isfinite(adev) & (adev > 0)
        tau, adev = tau[good], adev[good]
        # Octave taus rarely hit 1 s exactly: interpolate in log-log (ADEV is a power law between
        # neighbouring octaves); no extrapolation, so 'n/a' until the run is 4 s long (tau <= N/4).
        if tau.size > 1 and tau[0] <= 1.0 <= tau[-1]:
            out['ADEV at 1 s (deg/s)'] = _fmt(float(np.exp(np.interp(0.0, np.log(tau), np.log(adev))))
                                              * _DEG)
        if tau.size:
            i = int(np.argmin(adev))
            out['ADEV minimum (deg/s)'] = _fmt(adev[i] * _DEG)
            out['ADEV minimum at tau (s)'] = _fmt(tau[i])
    terms = None if summary is None else summary.noise_terms
    if terms is not None:
        try:
            customary = terms.customary()
            out['Angle random walk (deg/sqrt(h))'] = _fmt(customary.angle_random_walk_deg_per_sqrt_h)
            out['Bias instability (deg/h)'] = _fmt(customary.bias_instability_deg_per_h)
        except (AttributeError, TypeError, ValueError):
            pass
    return list(out.items())


# ---- the --echo monitor -------------------------------------------------------------------------------

_LEVEL_NAMES = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
_ECHO_KEYS = (('Bias (deg/s)', 'bias'), ('Fractional order, variance method', 'a_var'),
              ('Fractional order, correlation method', 'a_corr'),
              ('Offset drift ((deg/s)/h)', 'drift (deg/s)/h'), ('Samples lost', 'lost'),
              ('Chunks analysed', 'chunks'), ('Chunks skipped', 'skipped'))


def format_status(status):
    """
    Compact one-line form of an analyzer ``DiagnosticStatus`` (level, name, key numbers, message).

    Parameters
    ----------
    status : diagnostic_msgs.msg.DiagnosticStatus

    Returns
    -------
    str
    """
    level = _LEVEL_NAMES.get(status.level[0] if isinstance(status.level, bytes) else status.level, '?')
    values = {kv.key: kv.value for kv in status.values}
    numbers = ' '.join(f'{short}={values[key]}' for key, short in _ECHO_KEYS if key in values)
    return f'{level:<5} {status.name}: {numbers} | {status.message}'


def format_array(statuses):
    """
    One line for all axes of one analyzer (the ``--compact`` form ``make demo`` prints).

    Parameters
    ----------
    statuses : list of diagnostic_msgs.msg.DiagnosticStatus
        The axis statuses of one node from one ``DiagnosticArray``.

    Returns
    -------
    str
        ``'<worst level> chunk <n> | x OK bias .. drift .. a ../.. | ... | lost N: <axis>: <message>'``.
    """
    levels = [status.level[0] if isinstance(status.level, bytes) else status.level for status in statuses]
    worst_i = max(range(len(statuses)), key=lambda i: (levels[i], -i))
    parts = []
    chunk = lost = '?'
    for status, level in zip(statuses, levels):
        v = {kv.key: kv.value for kv in status.values}
        axis = status.name.rsplit(' ', 1)[-1]
        chunk = v.get('Last chunk', '-').split(' ')[0]
        lost = v.get('Samples lost', '?').split(' ')[0]
        parts.append(f"{axis} {_LEVEL_NAMES.get(level, '?')} bias {v.get('Bias (deg/s)', '-')} "
                     f"drift {v.get('Offset drift ((deg/s)/h)', '-')} "
                     f"a {v.get('Last chunk fractional order, variance method', '-')}/"
                     f"{v.get('Last chunk fractional order, correlation method', '-')}")
    worst = statuses[worst_i]
    head = f'{_LEVEL_NAMES.get(levels[worst_i], "?"):<5} chunk {chunk:>4}'
    tail = f'lost {lost}'
    if levels[worst_i]:
        tail += f' -- axis {worst.name.rsplit(" ", 1)[-1]}: {worst.message}'
    return ' | '.join([head, *parts, tail])


class DiagnosticsEcho(Node):
    """
    Print the ``/diagnostics`` statuses whose name contains ``name_filter`` (``--echo`` mode).

    One line per status, or with ``compact`` one line per node and array (all axes); with
    ``only_changes`` a status (or node) is printed again only when its level or chunk count changed.
    """

    def __init__(self, name_filter, *, only_changes=False, compact=False):
        super().__init__('noise_analyzer_echo')
        self._filter = name_filter
        self._only_changes = only_changes
        self._compact = compact
        self._last = {}
        self.create_subscription(DiagnosticArray, '/diagnostics', self._on_array, 100)

    def _changed(self, key, state):
        if self._only_changes and self._last.get(key) == state:
            return False
        self._last[key] = state
        return True

    @staticmethod
    def _state(status):
        values = {kv.key: kv.value for kv in status.values}
        return (status.level, values.get('Chunks analysed'), values.get('Chunks skipped'))

    def _on_array(self, msg):
        mine = [s for s in msg.status if self._filter in s.name]
        if not self._compact:
            for status in mine:
                if self._changed(status.name, self._state(status)):
                    print(format_status(status), flush=True)
            return
        by_node = {}
        for status in mine:
            by_node.setdefault(status.name.split(': ', 1)[0], []).append(status)
        for node_name, statuses in by_node.items():
            # A new line when every axis has finished the next chunk, or when a level changed; not
            # for the periodic repeats nor for one axis finishing ahead of the others.
            states = [self._state(s) for s in statuses]
            done = min(int(a or 0) + int(str(b or '0').split(' ')[0]) for _, a, b in states)
            if self._changed(node_name, (tuple(lvl for lvl, _, _ in states), done)):
                print(format_array(statuses), flush=True)


def echo_main(args):
    """Run the ``--echo`` monitor until Ctrl-C (``--filter TEXT``, ``--changes``, ``--compact``)."""
    name_filter = ': axis '
    compact = '--compact' in args
    only_changes = '--changes' in args or compact
    if '--filter' in args:
        i = args.index('--filter')
        if i + 1 >= len(args):
            print(f'{NODE_NAME}: error: --filter needs a value', file=sys.stderr)
            return 2
        name_filter = args[i + 1]
    return run_node(lambda: DiagnosticsEcho(name_filter, only_changes=only_changes, compact=compact), args,
                    prog=f'{NODE_NAME} --echo')


def main(args=None):
    """
    Run the analyzer node (or, with ``--echo``, the diagnostics monitor) until Ctrl-C or SIGTERM.

    Parameters
    ----------
    args : list of str or None
        Command line (``--ros-args -p chunk_size:=10000 --params-file config/noise_analyzer.yaml``);
        None: ``sys.argv``.

    Returns
    -------
    int
        0, or 2 for a bad parameter.
    """
    argv = sys.argv if args is None else list(args)
    if '--echo' in argv:
        return echo_main([a for a in argv if a != '--echo'])
    return run_node(NoiseAnalyzerNode, args, prog=NODE_NAME)


if __name__ == '__main__':
    sys.exit(main())
