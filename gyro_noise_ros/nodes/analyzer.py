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
ROS 2 node ``noise_analyzer``: live noise characterisation of a gyro, with diagnostics.

Subscribes ``imu/data_raw`` (``sensor_msgs/Imu``) and, optionally, ``imu/temperature``, with
sensor-data QoS, and runs the streaming engine (:mod:`gyro_noise_ros.core.engine`) on them: the
same chunks, per-chunk numbers, sequence statistics (paper 000 Tables 3-6) and health verdicts as
``gyro_noise_analyze`` gives for a recording of the same messages.

Ingestion: ``raw=True`` subscriptions in a callback group the executor never runs
(``PolledGroup``), drained every ``drain_period_s`` by a wall-clock timer and decoded in bulk
(:func:`gyro_noise_ros.bag.decode_imu`); the QoS history (``queue_depth`` messages) holds far more
than one drain period. Analysis: :meth:`NoiseEngine.ingest` runs in the executor thread; each
complete chunk is a job in a bounded queue (``analysis_queue_chunks``) served by one worker
thread; a full queue skips the chunk (counted); results come back to the executor thread, which
alone mutates the engine.

Outputs: ``/diagnostics``, one status ``'<node name>: axis x'`` per axis after every chunk and
every ``diagnostics_period_s`` (:mod:`..core.health`, :mod:`..core.items`); per chunk,
``geometry_msgs/Vector3Stamped`` (x, y, z = axes) on ``~/bias`` (rad/s), ``~/variance``
((rad/s)^2), ``~/alpha_var``, ``~/alpha_corr``, ``~/f_var``, ``~/f_corr`` (dimensionless) and
``~/offset_drift`` (rad/s^2). Messages are counted per publisher (:mod:`._publishers`); a second
publisher of the data turns the statuses WARN. Keys, topics, costs and sim-time playback:
docs/demo.md (the analyzer node) and docs/diagnostics.md; ``gyro_noise_monitor`` prints the
statuses as lines.
"""

from collections.abc import Callable, Mapping
import math
import operator
import sys
import threading
import time
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Imu, Temperature

from ._publishers import PublisherWatch, RawTaker
from ._ros_common import (declare_parameter_table, diagnostic_array, diagnostic_status,
                          diagnostics_publisher, ParamSpec, PolledGroup, run_node, sensor_data_qos,
                          specs_from_dataclass, take_all, unused_callback, wall_timer)
from ..app.live import CHUNK_TOPICS, engine_config_from, LiveAnalysis, thresholds_from
from ..bag import decode_imu, decode_temperature
from ..core.engine import AXES, GAP_POLICIES, warm_up
from ..core.fractional import DEFAULT_MEMORY
from ..core.health import axis_status, HealthThresholds, reference_per_axis, ReferenceStats
from ..core.items import allan_items, fmt, last_chunk_items, stream_items
from ..core.results import AxisSummary, ChunkResult
from ..errors import GyroNoiseError
from ..units import RAD_TO_DEG


NODE_NAME = 'noise_analyzer'

#: Messages ingested at a time (0.3 s at 6.66 kHz); a larger backlog goes in several batches.
MAX_BATCH = 2000

_NS = 1_000_000_000


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
    ParamSpec('memory', DEFAULT_MEMORY,
              'Memory length L of the truncated GL difference (paper: 1000)',
              unit='samples', read_only=True, min_value=1, max_value=10_000_000),
    ParamSpec('demean', True, 'Remove the chunk mean before the order identification',
              read_only=True),
    ParamSpec('max_lag', -1, 'Largest lag M of the correlation criterion J (-1: all lags)',
              unit='samples', read_only=True, min_value=-1, max_value=10_000_000),
    ParamSpec('rate_hz', 0.0,
              'Nominal sample rate (0: the median stamp step of the first samples)',
              unit='Hz', read_only=True, min_value=0.0, max_value=1.0e6),
    ParamSpec('gap_factor', 1.5, 'A stamp step above this many nominal periods is a gap',
              unit='periods', read_only=True, min_value=1.0001, max_value=1.0e6),
    ParamSpec('gap_policy', 'flag', 'What a gap does to its chunk: flag (keep, count), split '
              '(restart the chunk after it), drop (leave the chunk out)', read_only=True,
              choices=GAP_POLICIES),
    ParamSpec('history_chunks', 0,
              'Chunks per axis kept for the sequence statistics and the drift '
              '(0: the whole run; e.g. 40 judges the last minute at 6.66 kHz)', unit='chunks',
              read_only=True, min_value=0, max_value=100_000_000),
    ParamSpec('allan', True, 'Keep an incremental Allan deviation of the run (ADEV keys)',
              read_only=True),
    ParamSpec('reference_summary', '', 'summary.json of gyro_noise_analyze for a reference '
              'recording; empty: absolute drift limits only', read_only=True),
    ParamSpec('reference_bag', '', 'The bag of reference_summary to compare with when it holds '
              'several (its label, path or file name); empty: its only bag', read_only=True),
    *specs_from_dataclass(HealthThresholds, read_only=True),
    ParamSpec('use_temperature', True, 'Subscribe imu/temperature and report the chunk mean',
              read_only=True),
    ParamSpec('hardware_id', '',
              'hardware_id of the diagnostics (empty: the frame_id of the data)',
              read_only=True),
    ParamSpec('diagnostics_period_s', 1.0, 'Period of /diagnostics between chunks', unit='s',
              read_only=True, min_value=0.05, max_value=3600.0),
    ParamSpec('allan_period_s', 10.0, 'Period of the Allan deviation update in the diagnostics',
              unit='s', read_only=True, min_value=0.1, max_value=86400.0),
    ParamSpec('reliable', False, 'Subscribe reliable (retransmitted; matches only a reliable '
              'publisher such as the driver) instead of sensor-data best effort, so a busy host '
              'drops no message that would count as a lost sample', read_only=True),
    ParamSpec('queue_depth', 20000, 'QoS history depth of the subscriptions', unit='messages',
              read_only=True, min_value=10, max_value=1_000_000),
    # 50 ms, not 10 or 20: each executor wake-up costs a fixed few hundred microseconds in rclpy
    # (wait-set construction) and in the per-batch numpy calls; measured ingestion at 6.66 kHz fell
    # from 24 % to 14 % of a core from 10 to 20 ms (bench/bench_analyzer_node.py), and the decode
    # and engine ingest of the same second from 3.3 % to 2.3 % from 20 to 50 ms (one thread, in
    # process); the 20,000-message history covers 3 s, and the analysis has no latency budget.
    ParamSpec('drain_period_s', 0.05, 'Period of the loop taking queued messages', unit='s',
              read_only=True, min_value=0.001, max_value=0.5),
    ParamSpec('analysis_queue_chunks', 4,
              'Chunks (of all axes) waiting for analysis before new ones '
              'are skipped', unit='chunks', read_only=True, min_value=1, max_value=10_000),
    ParamSpec('log_chunks', False, 'Log one line per analysed chunk', read_only=True),
)


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

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        p = declare_parameter_table(self, PARAMETERS)
        self._params = p
        self.config = engine_config_from(p)
        self.thresholds = thresholds_from(p)
        t0 = time.monotonic()
        warm_up(self.config)
        self.get_logger().info(f'analysis warmed up in {time.monotonic() - t0:.2f} s')

        # The OS thread id lets a profiler (bench/bench_analyzer_node.py) split the node's CPU
        # time between ingestion (executor thread) and analysis (the worker).
        def worker_started() -> None:
            self.get_logger().info(
                f'analysis worker started (native thread id {threading.get_native_id()})')

        self.live = LiveAnalysis(
            self.config, reference=self._reference(p), thresholds=self.thresholds,
            queue_chunks=p['analysis_queue_chunks'], on_worker_start=worker_started)
        self.engine = self.live.engine
        self.results = self.live.results  # recent ChunkResults in completion order (tests)
        self._hardware_id = p['hardware_id']
        self._frame_id = ''
        self.messages_received = 0
        self.messages_undecodable = 0
        self._last_data: float | None = None
        self._allan_keys: dict[str, list[tuple[str, str]]] = {}
        self._allan_due = 0.0

        group = PolledGroup()
        qos = sensor_data_qos(p['queue_depth'], p['reliable'])
        self._imu_sub = self.create_subscription(Imu, 'imu/data_raw', unused_callback, qos,
                                                 raw=True, callback_group=group)
        self._temperature_sub = None
        if p['use_temperature']:
            self._temperature_sub = self.create_subscription(
                Temperature, 'imu/temperature', unused_callback, qos, raw=True,
                callback_group=group)
        self._imu_watch = PublisherWatch(
            self._imu_sub.topic_name, 'the analysis mixes their samples (remap or namespace one '
            'of them)')
        self._imu_taker = RawTaker(self._imu_sub, Imu, self.get_logger())
        wall_timer(self, 1.0, self._check_publishers)
        self._diag_pub = diagnostics_publisher(self)
        topic_qos = QoSProfile(depth=100)
        self._chunk_pubs = {name: self.create_publisher(Vector3Stamped, '~/' + name, topic_qos)
                            for name in (*CHUNK_TOPICS, 'offset_drift')}
        wall_timer(self, p['drain_period_s'], self.drain)
        wall_timer(self, p['diagnostics_period_s'], self.publish_diagnostics)
        alphas = self.config.alphas
        assert alphas is not None  # EngineConfig fills the default grid
        self.get_logger().info(
            f'analysing {self._imu_sub.topic_name} axes {",".join(self.config.axes)}, chunks of '
            f'{self.config.chunk_size} samples, orders {alphas[0]:g}:'
            f'{alphas[-1]:g} ({alphas.size} points), '
            + ('reference ' + p['reference_summary'] if p['reference_summary'] else
               'absolute drift limits'))

    # ---- ingestion (executor thread) ---------------------------------------

    def _reference(self, p: Mapping[str, Any]) -> dict[str, ReferenceStats] | None:
        """Return the reference statistics per axis of ``reference_summary`` (its bag)."""
        if not p['reference_summary']:
            return None
        try:
            return reference_per_axis(p['reference_summary'], self.config.axes,
                                      bag=p['reference_bag'] or None)
        except GyroNoiseError as err:   # the summary's 'bag' is this node's reference_bag
            raise type(err)(err.spelled(lambda name: {'bag': 'reference_bag'}.get(name, name))
                            ) from err

    def drain(self) -> None:
        """Take the queued messages, feed the engine, queue the chunks, publish finished ones."""
        if self._temperature_sub is not None:
            raws, _, _ = take_all(self._temperature_sub, Temperature)
            if raws:
                self.live.temperature.add(*decode_temperature(raws))
        while True:
            # A backlog (the host stalled) goes through in bounded batches: one large batch would
            # grow the heap for good (its temporaries, freed later, leave holes).
            raws, _, sequence, gids = self._imu_taker.take(MAX_BATCH)
            if raws:
                self._imu_watch.update(gids, sequence, time.monotonic())
                self._ingest(raws)
            if len(raws) < MAX_BATCH:
                break
        results, chunks = self.live.collect()
        for result in results:
            if result.status != 'ok' and result.message.startswith('analysis failed'):
                self.get_logger().error(f'chunk {result.chunk} axis {result.axis}: '
                                        f'{result.message}')
            elif self._params['log_chunks']:
                self.get_logger().info(
                    f'chunk {result.chunk} axis {result.axis}: {result.status}, bias '
                    f'{fmt(result.bias_rad_s * RAD_TO_DEG)} deg/s, '
                    f'alpha {fmt(result.alpha_var)} (var) '
                    f'{fmt(result.alpha_corr)} (corr)')
        for per_axis in chunks:
            self._publish_chunk(per_axis)
            self.publish_diagnostics()

    def _check_publishers(self) -> None:
        for severity, line in self._imu_watch.check(self):
            if severity == 'warn':  # rclpy refuses two severities from one call site
                self.get_logger().warn(line)
            else:
                self.get_logger().info(line)

    def _ingest(self, raws: list[bytes]) -> None:
        self.messages_received += len(raws)
        self._last_data = time.monotonic()
        batch = decode_imu(raws, skip_undecodable=True)
        self.messages_undecodable += len(raws) - len(batch)
        if not len(batch):
            return
        # The diagnostics' hardware_id follows the frame of the data (a remapped or replaced
        # sensor shows under its new frame at once).
        self._frame_id = batch.frame_id or self._frame_id
        error = self.live.ingest(batch.stamp_ns, batch.gyro)
        if error:
            self.get_logger().error(f'samples rejected: {error}', throttle_duration_sec=5.0)

    # ---- outputs -----------------------------------------------------------

    def _publish_chunk(self, per_axis: Mapping[str, ChunkResult]) -> None:
        first = next(iter(per_axis.values()))
        msg = Vector3Stamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(first.stamp_start_ns), _NS)
        msg.header.frame_id = self._frame_id

        def values(get: Callable[[ChunkResult], float]) -> list[float]:
            out: list[float] = []
            for axis in AXES:
                r = per_axis.get(axis)
                out.append(float(get(r)) if r is not None and r.status == 'ok' else math.nan)
            return out

        for name, (field, _) in CHUNK_TOPICS.items():
            msg.vector.x, msg.vector.y, msg.vector.z = values(operator.attrgetter(field))
            self._chunk_pubs[name].publish(msg)
        summaries = self.engine.summary(allan=False)
        msg.vector.x, msg.vector.y, msg.vector.z = values(
            lambda r: summaries[r.axis].sequence.drift.slope)
        self._chunk_pubs['offset_drift'].publish(msg)

    def _update_allan(self, summaries: Mapping[str, AxisSummary]) -> None:
        now = time.monotonic()
        if not self.config.allan or now < self._allan_due:
            return
        self._allan_due = now + self._params['allan_period_s']
        try:
            with_allan = self.engine.summary(allan=True)
        except GyroNoiseError as err:
            self.get_logger().warn(f'Allan deviation not available: {err}',
                                   throttle_duration_sec=60.0)
            return
        for axis, s in with_allan.items():
            self._allan_keys[axis] = allan_items(s)

    def diagnostics(self) -> DiagnosticArray:
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
        active = self._imu_watch.active(time.monotonic())
        statuses = []
        for axis, verdict in verdicts.items():
            s = summaries[axis]
            last = self.live.last.get(axis)
            values = [(k, v) for k, v, _ in verdict.items]
            if last is not None:
                values += last_chunk_items(last)
            values += self._allan_keys.get(axis) or allan_items(None)
            values += stream_items(counts, chunk_size=self.config.chunk_size,
                                   mean_temperature_c=s.temperature_mean_c)
            values += [
                ('Analysis queue (chunks)', str(self.live.queue_size)),
                ('Allan storage (MiB)', f'{self.engine.allan_nbytes(axis) / 2 ** 20:.2f}'),
                ('Messages dropped before the node', str(self._imu_watch.counts.missing)),
                ('Messages undecodable', str(self.messages_undecodable)),
                ('Publishers', str(len(active))),
                ('Messages per publisher', self._imu_watch.summary()),
            ]
            live = self.live
            status = axis_status(verdict, values, rejected_batches=live.rejected_batches,
                                 last_rejection=live.last_rejection,
                                 rejecting=live.last_batch_rejected, seconds_since_data=since,
                                 thresholds=self.thresholds, publishers=len(active))
            statuses.append(diagnostic_status(f'{self.get_name()}: axis {axis}', hardware_id,
                                              bytes([status.level_byte]), status.message,
                                              status.values))
        return diagnostic_array(self.get_clock().now().to_msg(), statuses)

    def publish_diagnostics(self) -> None:
        """Publish :meth:`diagnostics` on ``/diagnostics``."""
        self._diag_pub.publish(self.diagnostics())

    def destroy_node(self) -> None:
        """Stop the worker thread, then destroy the node."""
        self.live.stop()
        self._imu_taker.close()
        return super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """
    Run the analyzer node until Ctrl-C or SIGTERM; return 0, or 2 for a bad parameter.

    ``args`` is the command line (``--ros-args -p chunk_size:=10000 --params-file ...``; None:
    ``sys.argv``).

    """
    return run_node(NoiseAnalyzerNode, args, prog=NODE_NAME, parameters=PARAMETERS,
                    summary=__doc__)


if __name__ == '__main__':
    sys.exit(main())
