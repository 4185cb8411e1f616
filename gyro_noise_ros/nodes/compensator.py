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
ROS 2 node ``imu_compensator``: calibration and thermal drift compensation after the driver.

REP-145: the driver publishes what the device reports (``imu/data_raw``); this node applies the
six-position calibration (bias, scale factor, misalignment of accelerometer and gyro,
:mod:`gyro_noise_ros.calibration.apply`) and, given a causal thermal model, subtracts the gyro
offset it predicts from the die temperature and its rate (:mod:`gyro_noise_ros.thermal.live`,
evaluated per ``imu/temperature`` message, interpolated onto the gyro stamps) and, when the model
has one, the accelerometer's temperature-dependent offset change. It publishes
``imu/data_compensated`` (``sensor_msgs/Imu``, reliable keep-last deep queue per REP-2003) with
the header stamp, frame_id, orientation and covariances of each input message unchanged, and
``/diagnostics`` status ``'<node>: compensation'``. Ingestion: raw subscriptions, decoded and
re-encoded in bulk. See ``docs/compensation.md``.

Latency is a budget (``docs/scale.md``): by default the subscriptions are drained as messages
arrive, by a thread waiting on a wait set of its own (:class:`~._waitset.WaitSetDrain`), and each
gyro sample gets the newest thermal offset at once (``temperature_sync: latest``; temperature
moves over seconds, the cost in the thermal residual is measured in ``docs/compensation.md``).
``temperature_sync: interpolate`` keeps the previous behaviour: a gyro sample waits for a
temperature at or after its stamp, so its offset is interpolated between two temperature messages
(:class:`~gyro_noise_ros.thermal.live.TemperatureGate`, bounded by ``max_temperature_wait_s``;
past it the sample gets the newest offset and is counted), at the price of up to one temperature
period (19 ms at 52 Hz) of latency; ``drain_period_s`` > 0 drains on a timer instead.
"""

from collections.abc import Mapping, Sequence
import math
import sys
import threading
import time
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
import numpy as np
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription
from sensor_msgs.msg import Imu, Temperature

from ._realtime import REALTIME_DOC, set_realtime_priority
from ._ros_common import (declare_parameter_table, diagnostic_array, diagnostic_status,
                          diagnostics_publisher, ParamSpec, PolledGroup, run_node, sensor_data_qos,
                          SequenceGapCounter, take_all, unused_callback)
from ._waitset import WaitSetDrain
from ..bag import decode_temperature
from ..calibration.apply import (Calibration, calibration_from_parameters, KEYS,
                                 load_calibration)
from ..diagnostics.compensation import CompensationTask, CompensationThresholds
from ..errors import BagError, ParameterError
from ..msgs import (decode_imu_spans, frame_id_of, join_raws, patch_imu_spans,
                    TEMPERATURE_TAIL_F8)
from ..msgs.imu_rows import (patch_rows, row_messages, RowCorrector, RowEncoder, RowLayout,
                             rows_stamps, rows_tail, rows_vectors)
from ..thermal.live import (BEYOND_ACTIONS, LiveDriftEvaluator, load_live, TEMPERATURE_SYNCS,
                            TemperatureGate)
from ..thermal.run import DEFAULT_RATE_WINDOW_S, ThermalMethod

NODE_NAME = 'imu_compensator'

#: Imu messages compensated at a time (0.3 s at 6.66 kHz); a backlog goes in several batches.
MAX_BATCH = 2000


class ArrayParamSpec(ParamSpec):
    """A table row whose value is a fixed-length array of doubles (``default`` a list)."""

    @property
    def ros_type(self) -> int:
        """``PARAMETER_DOUBLE_ARRAY``."""
        return ParameterType.PARAMETER_DOUBLE_ARRAY

    def check(self, value: Any) -> None:
        """Refuse a wrong length or a non-finite element, naming the parameter."""
        values = list(value)
        if len(values) != len(self.default) or not all(math.isfinite(v) for v in values):
            raise ParameterError(f"parameter '{self.name}' = {values!r} must be "
                                 f'{len(self.default)} finite numbers (write 0.0, not 0)')


_CAL_DOC = {
    'accel_bias_m_s2': 'Accelerometer bias b, x y z',
    'accel_scale_factor': 'Accelerometer scale-factor errors S, x y z (-0.0002 = -0.02 %)',
    'accel_misalignment': 'Accelerometer cross-axis matrix M, 3x3 row-major, zero diagonal',
    'gyro_bias_rad_s': 'Gyro bias b, x y z',
    'gyro_scale_factor': 'Gyro scale-factor errors S, x y z',
    'gyro_misalignment': 'Gyro cross-axis matrix M, 3x3 row-major, zero diagonal',
}

#: The parameter table (``config/imu_compensator.yaml`` lists every row with default and unit).
PARAMETERS = (
    ParamSpec('calibration_file', '', 'calibration.yaml of gyro_noise_calibrate; empty: the '
              'calibration parameters below (e.g. --params-file calibration.yaml)',
              read_only=True),
    *(ArrayParamSpec(key, [0.0] * KEYS[key][0], _CAL_DOC[key] + '; measured = (I + diag(S) + M)'
                     ' @ true + b', unit=KEYS[key][1], read_only=True) for key in _CAL_DOC),
    ParamSpec('calibration_gravity_m_s2', 9.80665, 'Local gravity the calibration used (reported)',
              unit='m/s^2', read_only=True, min_value=9.7, max_value=9.9),
    ParamSpec('thermal_model_file', '', 'model.json of gyro_noise_thermal fit (a causal method); '
              'empty: no thermal compensation', read_only=True),
    ParamSpec('temperature_rate_window_s', 0.0, 'Trailing window of the temperature rate dT '
              f"(0: the model's own, else {DEFAULT_RATE_WINDOW_S:g} s)", unit='s',
              read_only=True, min_value=0.0, max_value=3600.0),
    ParamSpec('temperature_margin_c', -1.0, 'Trusted margin beyond the trained temperature range '
              "(-1: the model's own, else 5 degC)", unit='degC', read_only=True, min_value=-1.0,
              max_value=200.0),
    ParamSpec('out_of_range_action', 'hold', 'Beyond the margin the offset is never extrapolated: '
              'hold the last trusted one, or none (calibration only)', read_only=True,
              choices=BEYOND_ACTIONS),
    ParamSpec('temperature_timeout_s', 2.0, 'WARN when the newest temperature is older than this '
              '(the offset is held meanwhile)', unit='s', read_only=True, min_value=0.01,
              max_value=3600.0),
    ParamSpec('temperature_wait_s', 2.0, 'With a thermal model, Imu messages that arrive before '
              'the first offset wait this long (plus the rate window for a model that uses dT, '
              'which needs its window filled) for it, then are dropped and counted: they are '
              'never published uncorrected on the compensated topic', unit='s',
              read_only=True, min_value=0.0, max_value=60.0),
    ParamSpec('temperature_sync', 'latest', 'With a thermal model: latest applies the newest '
              'offset to each gyro sample as it arrives (lowest latency); interpolate holds a '
              'sample until a temperature at or after its stamp is known and interpolates the '
              'offset (up to one temperature period, 19 ms at 52 Hz, more latency)',
              read_only=True, choices=TEMPERATURE_SYNCS),
    # 10 s: a lost imu/temperature message (52 Hz) is resent after the writer's next heartbeat,
    # Fast DDS's default period 3 s (the 6.66 kHz Imu stream is repaired sooner, by heartbeats
    # piggybacked on its data), plus the NACK response and the drain period; a lost repair costs
    # another period. Runs at load 13 with a 1 s bound held 2,000-15,000 samples per run past it
    # (test_compensator_e2e); with 4 s, every soak run (bench/bench_soak.py) held 222-2,434
    # samples when a killed reliable subscriber's lease expired, and a run with 8 s waited 7.1 s
    # on time there and held none. The normal wait is one temperature period (19 ms at 52 Hz)
    # plus the drain period; the bound costs latency and memory only while temperatures stall.
    ParamSpec('max_temperature_wait_s', 10.0, 'With temperature_sync interpolate, a gyro sample '
              'newer than the latest temperature waits up to this long for the next one, so its '
              'offset is interpolated, never held from an older temperature; past it the sample '
              'gets the latest offset and is counted (0: never wait, the latest offset at once)',
              unit='s', read_only=True, min_value=0.0, max_value=60.0),
    ParamSpec('accel_thermal', True, "Also subtract the thermal model's accelerometer offset "
              'change when model.json has one', read_only=True),
    ParamSpec('reliable', False, 'Subscribe imu/data_raw reliable (retransmitted; matches only '
              'a reliable publisher such as the driver) instead of sensor-data best effort, so a '
              'busy host drops no message that would leave a gap in the compensated stream; '
              'imu/temperature is always best effort (a lost one costs a period, a resent one '
              'would hold the newer ones back)', read_only=True),
    ParamSpec('queue_depth', 20000, 'QoS history depth of the subscriptions', unit='messages',
              read_only=True, min_value=10, max_value=1_000_000),
    ParamSpec('output_queue_depth', 20000, 'History depth of the reliable imu/data_compensated '
              'publisher', unit='messages', read_only=True, min_value=10, max_value=1_000_000),
    # 0: a thread wakes on the subscriptions' wait set as messages arrive (bench/bench_latency.py:
    # the compensator adds p99 < 1 ms). A period (the previous default, 0.05 s) drains on a timer
    # instead: fewer wake-ups, up to the period of added latency.
    ParamSpec('drain_period_s', 0.0, 'Period of the timer taking queued messages; 0: take them '
              'as they arrive (a wait-set thread, lowest latency)', unit='s', read_only=True,
              min_value=0.0, max_value=0.5),
    ParamSpec('diagnostics_period_s', 1.0, 'Period of /diagnostics', unit='s', read_only=True,
              min_value=0.05, max_value=3600.0),
    ParamSpec('stale_after_s', 5.0, 'ERROR after this long without imu/data_raw', unit='s',
              read_only=True, min_value=0.1, max_value=3600.0),
    ParamSpec('hardware_id', '', 'hardware_id of the diagnostics (empty: the frame_id of the '
              'data)', read_only=True),
    ParamSpec('realtime_priority', 0, REALTIME_DOC, read_only=True, min_value=0, max_value=99),
)


def calibration_from(p: Mapping[str, Any]) -> tuple[Calibration, str]:
    """Build the calibration from the parameter values: the file, or the parameters (not both)."""
    if not p['calibration_file']:
        values = {key: p[key] if key == 'calibration_gravity_m_s2' else list(p[key])
                  for key in KEYS}
        return calibration_from_parameters(values, source='parameter'), 'parameters'
    changed = [key for key in _CAL_DOC if any(list(p[key]))]
    if changed:
        raise ParameterError(f"give either 'calibration_file' or the calibration parameters, not "
                             f"both (set: {', '.join(changed)})")
    return load_calibration(p['calibration_file']), f"file {p['calibration_file']}"


def row_corrector(calibration: Calibration) -> RowCorrector:
    """
    Return the compiled pass of the usual batch, ready (compiled or loaded from numba's cache).

    Warmed with what a batch gives it: read-only rows of received messages, an offset per
    message and none, so the first batch compiles nothing.
    """
    gyro, accel = calibration.gyro, calibration.accel
    corrector = RowCorrector(None if gyro.is_identity else gyro.inverse, gyro.bias,
                             None if accel.is_identity else accel.inverse, accel.bias)
    rows = RowLayout().rows(row_messages(RowEncoder('').rows(np.zeros(2, np.int64),
                                                             np.zeros((2, 3)), np.zeros((2, 3)))))
    assert rows is not None  # one layout
    for offset in (None, np.zeros((2, 3))):
        corrector.rows(rows, offset, offset)
    return corrector


class ImuCompensatorNode(Node):
    """
    Calibration and thermal compensation node (see the module docstring).

    Parameters
    ----------
    thermal_model : ThermalMethod or None, keyword-only
        A causal model object used instead of ``thermal_model_file`` (embedding, tests).
    in_process : bool, keyword-only
        No subscriptions: the driver in the same process hands each read over (:meth:`accept`;
        ``imu_chain``, :mod:`.chain`).
    **kwargs
        Passed to :class:`rclpy.node.Node` (e.g. ``parameter_overrides``).

    """

    def __init__(self, *, thermal_model: ThermalMethod | None = None, in_process: bool = False,
                 **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        p = declare_parameter_table(self, PARAMETERS)
        self._p = p
        # Before the drain thread exists (it inherits the policy); rclpy's threads are set too.
        set_realtime_priority(p['realtime_priority'])
        self._status_name = f'{self.get_name()}: compensation'
        self.calibration, self._cal_source = calibration_from(p)
        self._setup_thermal(p, thermal_model)
        # Diagnostics: counters ticked on the hot path, judged on the timer.
        self._diag = CompensationTask(
            CompensationThresholds(stale_after_s=p['stale_after_s'],
                                   temperature_timeout_s=p['temperature_timeout_s'],
                                   temperature_wait_s=p['temperature_wait_s'],
                                   max_temperature_wait_s=p['max_temperature_wait_s']),
            calibration=self.calibration, calibration_source=self._cal_source,
            out_of_range_action=p['out_of_range_action'], now=time.monotonic(),
            temperature_sync=p['temperature_sync'])
        self.counts = self._diag.counts
        # Before the first offset (the first temperature, plus the rate window for a model using
        # dT) samples wait, then are dropped; with temperature_sync interpolate they also wait
        # for an offset at or after their stamp (bounded).
        start_up_s = 0.0 if self.thermal is None else self.thermal.start_up_s
        self._gate = TemperatureGate(p['max_temperature_wait_s'],
                                     p['temperature_wait_s'] + start_up_s,
                                     wait_for_newer=p['temperature_sync'] == 'interpolate')
        self._transport = SequenceGapCounter()
        self._layout = RowLayout()
        self._corrector = row_corrector(self.calibration)
        self._temp_layout = RowLayout(TEMPERATURE_TAIL_F8)
        self._frame_id = ''
        self._offset = None
        self._accel_offset = None
        # The drain (its thread or the timer) and the diagnostics (the executor) share the state.
        self._lock = threading.Lock()
        self._imu_sub: Subscription | None = None
        self._temp_sub: Subscription | None = None
        if not in_process:
            group = PolledGroup()
            qos = sensor_data_qos(p['queue_depth'], p['reliable'])
            self._imu_sub = self.create_subscription(Imu, 'imu/data_raw', unused_callback, qos,
                                                     raw=True, callback_group=group)
            # Temperatures best effort whatever `reliable` says: only the newest one counts, and
            # a reliable stream delivered in order holds every newer temperature back until a
            # lost one is repaired (Fast DDS: up to a heartbeat period, 3 s), a stale offset all
            # that time.
            self._temp_sub = self.create_subscription(
                Temperature, 'imu/temperature', unused_callback,
                sensor_data_qos(p['queue_depth'], False), raw=True, callback_group=group)
        out_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=p['output_queue_depth'],
                             reliability=ReliabilityPolicy.RELIABLE)
        self._pub = self.create_publisher(Imu, 'imu/data_compensated', out_qos)
        self._diag_pub = diagnostics_publisher(self)
        self._waiter: WaitSetDrain | None = None
        if p['drain_period_s'] > 0:
            self.create_timer(p['drain_period_s'], self.drain)
        else:
            # 50 ms without data: the gate's time-outs and the start-up drop still run (in
            # process, only they: the driver's thread brings the data).
            subs = [sub for sub in (self._temp_sub, self._imu_sub) if sub is not None]
            self._waiter = WaitSetDrain(self.context, subs, self.drain, timeout_s=0.05,
                                        name='imu_compensator_drain')
            self._waiter.start()
        self.create_timer(p['diagnostics_period_s'], self.publish_diagnostics)
        model = 'none' if self.thermal is None else self.thermal.name
        source = ("the driver's reads in this process" if self._imu_sub is None else
                  self._imu_sub.topic_name)
        self.get_logger().info(f'compensating {source} -> '
                               f'{self._pub.topic_name}: calibration from {self._cal_source}, '
                               f'thermal model {model}, temperature sync '
                               f'{p["temperature_sync"]}')

    def _setup_thermal(self, p: Mapping[str, Any], thermal_model: ThermalMethod | None) -> None:
        margin = None if p['temperature_margin_c'] < 0 else p['temperature_margin_c']
        range_c = rate_range = accel_model = None
        notes: Sequence[str] = ()
        if thermal_model is None and p['thermal_model_file']:
            live = load_live(p['thermal_model_file'])
            thermal_model, range_c, rate_range = live.method, live.range_c, live.rate_range_c_s
            margin = live.margin_c if margin is None else margin
            accel_model = live.accel if p['accel_thermal'] else None
            notes = live.notes
        window = p['temperature_rate_window_s'] or None
        self.thermal = None if thermal_model is None else LiveDriftEvaluator(
            thermal_model, range_c=range_c, rate_window_s=window, margin_c=margin,
            beyond=p['out_of_range_action'], rate_range_c_s=rate_range)
        self.thermal_accel = None if accel_model is None else LiveDriftEvaluator(
            accel_model, range_c=range_c, margin_c=margin, beyond=p['out_of_range_action'])
        for note in notes:
            self.get_logger().warning(note)

    def drain(self) -> None:
        """Take queued temperatures and Imu messages, compensate them, publish."""
        with self._lock:
            if self._imu_sub is None:  # in process: the data come through accept()
                self._step((), (), ())
                return
            while True:
                # A backlog (a stalled stream resuming) goes through in bounded batches: one
                # large batch would grow the heap for good.
                raws, _, sequence = take_all(self._imu_sub, Imu, MAX_BATCH)
                # Temperatures after the Imu take: the driver publishes a read's temperature
                # before its Imu messages, and one participant's messages reach this one in
                # order, so every temperature published before the newest sample taken is then
                # known. Taken first, a pause between the two takes (a preempted thread) lets
                # samples newer than a temperature not yet taken through with the one before it,
                # older than them by a period plus the pause (the likely cause of an offset
                # 31.8 ms older than its sample in session 5's 60-minute soak; bound 31.6 ms).
                assert self._temp_sub is not None  # subscribed with imu/data_raw
                self._step(raws, sequence, take_all(self._temp_sub, Temperature)[0])
                if len(raws) < MAX_BATCH:
                    break

    def accept(self, temperatures: Sequence[bytes], imu: Sequence[bytes]) -> None:
        """
        Compensate one read of the driver running in this process (``in_process``).

        Called in the driver's reader thread right after it published ``temperatures`` (its
        ``imu/temperature`` messages, serialised) and ``imu`` (its ``imu/data_raw`` messages),
        in that order, as :meth:`drain` gets them from DDS: the same steps, without the second
        trip through the middleware.
        """
        with self._lock:
            for start in range(0, max(len(imu), 1), MAX_BATCH):
                self._step(imu[start:start + MAX_BATCH], (), temperatures if start == 0 else ())

    def _step(self, raws: Sequence[bytes], sequence: Sequence[int],
              temperatures: Sequence[bytes]) -> None:
        """Add the temperatures, then compensate and publish the Imu messages (lock held)."""
        self._add_temperatures(temperatures)
        if raws:
            self.compensate(raws, sequence)
        elif self.thermal is not None and self._gate.waiting:
            self._release()  # a new temperature or a timeout lets held samples go

    def _add_temperatures(self, raws: Sequence[bytes]) -> None:
        if not raws or self.thermal is None:
            return
        self.counts['temperatures'] += len(raws)
        stamp_ns: np.ndarray | tuple[()]
        temperature_c: np.ndarray | tuple[()]
        rows = self._temp_layout.rows(raws)
        if rows is not None:  # one layout (the usual): a few numpy calls
            stamp_ns = rows_stamps(rows)
            temperature_c = rows_tail(rows, TEMPERATURE_TAIL_F8)[:, 0]
        else:
            try:
                stamp_ns, temperature_c = decode_temperature(raws)
            except BagError as err:  # a corrupt message: drop the batch, count it, go on
                self.thermal.rejected += len(raws)
                self.get_logger().error(f'temperature batch dropped: {err}',
                                        throttle_duration_sec=5.0)
                stamp_ns, temperature_c = (), ()
        if self.thermal.add_temperature(stamp_ns, temperature_c):
            self._diag.tick_temperature(time.monotonic())
        if self.thermal_accel is not None:
            self.thermal_accel.add_temperature(stamp_ns, temperature_c)

    def compensate(self, raws: Sequence[bytes], sequence: Sequence[int] = ()) -> None:
        """Decode a batch of raw Imu messages, correct them, publish the results."""
        self.counts['received'] += len(raws)
        self._transport.update(sequence)
        self._diag.tick_data(time.monotonic())
        rows = self._layout.rows(raws)
        spans = None
        keep = None
        if rows is not None:  # one layout: a few numpy calls (the usual batch, a board frame)
            stamp_ns = rows_stamps(rows)
        else:
            buf, starts, lengths = join_raws(raws)
            keep, stamp_ns, gyro, accel = decode_imu_spans(buf, starts, lengths, False, True)
            if keep is not None:
                self.counts['undecodable'] += len(raws) - keep.size
                starts, lengths = starts[keep], lengths[keep]
            spans = (buf, starts, lengths)
        if not stamp_ns.size:
            return
        if not self._frame_id:
            self._frame_id = frame_id_of(raws[0 if keep is None else int(keep[0])], False) or ''
        if rows is not None:
            if self._at_once():  # calibrated and corrected in one compiled pass (_emit)
                self._emit(None, rows, stamp_ns, None, None)
                return
            gyro, accel = rows_vectors(rows)
        gyro, accel = self.calibration.apply(gyro, accel)
        if self._at_once():
            self._emit(spans, rows, stamp_ns, gyro, accel)
            return
        # Before the first temperature there is no offset: publishing these uncorrected on a
        # topic named compensated would be a wrong number given calmly (the gate drops them after
        # temperature_wait_s); with temperature_sync interpolate, samples also wait for a
        # temperature at or after their stamp.
        self._gate.push((spans, rows, stamp_ns, gyro, accel), stamp_ns, time.monotonic())
        self._release()

    def _at_once(self) -> bool:
        """Tell whether a batch is published at once: no model, or offsets known and not held."""
        return self.thermal is None or (not self._gate.wait_for_newer and not self._gate.waiting
                                        and self.thermal.offset_stamp_ns is not None)

    def _release(self) -> None:
        assert self.thermal is not None  # called only with a thermal model
        for batch, i, j, _ in self._gate.release(self.thermal.offset_stamp_ns, time.monotonic()):
            spans, rows, stamp_ns, gyro, accel = batch
            if spans is not None:
                buf, starts, lengths = spans
                spans = (buf, starts[i:j], lengths[i:j])
            self._emit(spans, None if rows is None else rows[i:j], stamp_ns[i:j], gyro[i:j],
                       accel[i:j])

    def _emit(self, spans: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
              rows: np.ndarray | None, stamp_ns: np.ndarray, gyro: np.ndarray | None,
              accel: np.ndarray | None) -> None:
        """
        Subtract the thermal offsets, publish.

        ``spans`` (buf, starts, lengths) without rows; ``gyro`` and ``accel`` calibrated, or
        both None: the rows' own vectors, calibrated here in the same compiled pass.
        """
        offset = accel_offset = None
        thermal = self.thermal
        if thermal is not None:
            offset = thermal.drift_at(stamp_ns)
            assert offset is not None  # the gate releases samples only after a temperature
            self._offset = offset[-1]
            newest = thermal.offset_stamp_ns
            if newest is not None:  # how much newer the sample is than the offset it got
                self._diag.tick_offset_age(int(stamp_ns[-1]) - newest)
        if self.thermal_accel is not None:
            accel_offset = self.thermal_accel.drift_at(stamp_ns)
            if accel_offset is not None:
                self._accel_offset = accel_offset[-1]
        if gyro is None or accel is None:
            assert rows is not None  # the usual batch: rows as received
            raws = row_messages(self._corrector.rows(rows, offset, accel_offset))
        else:
            if offset is not None:
                gyro -= offset
            if accel_offset is not None:
                accel -= accel_offset
            if rows is not None:
                raws = patch_rows(rows, gyro, accel)
            else:
                assert spans is not None  # a batch has rows or spans
                raws = patch_imu_spans(*spans, gyro, accel)
        handle = self._pub.handle
        with handle:  # what Publisher.publish does per message for bytes, once per batch
            publish = handle.publish_raw
            for raw in raws:
                publish(raw)
        self.counts['published'] += stamp_ns.size

    def diagnostics(self, record: bool = False) -> DiagnosticArray:
        """
        Build the ``DiagnosticArray`` of the current state (one status, see the task).

        ``record``: this status is published, so the late samples it reports are not reported
        again (the periodic timer passes True).
        """
        with self._lock:
            status = self._diag.run(
                time.monotonic(), thermal=self.thermal, thermal_accel=self.thermal_accel,
                offset=self._offset, accel_offset=self._accel_offset, hold=self._gate,
                transport_missing=self._transport.missing, record=record)
        hardware_id = self._p['hardware_id'] or self._frame_id or 'unknown'
        return diagnostic_array(self.get_clock().now().to_msg(), [diagnostic_status(
            self._status_name, hardware_id, bytes([status.level_byte]), status.message,
            status.values)])

    def publish_diagnostics(self) -> None:
        """Publish :meth:`diagnostics` on ``/diagnostics``."""
        self._diag_pub.publish(self.diagnostics(record=True))

    def destroy_node(self) -> None:
        """Stop the drain thread, then destroy the node."""
        if self._waiter is not None:
            self._waiter.stop()
        return super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Run the node until Ctrl-C or SIGTERM; exit code 2 for a bad parameter (one line)."""
    return run_node(ImuCompensatorNode, args, prog=NODE_NAME, parameters=PARAMETERS,
                    summary=__doc__)


if __name__ == '__main__':
    sys.exit(main())
