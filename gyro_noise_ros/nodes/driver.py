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
ROS 2 driver of the LSM6DSO32 read by an Arduino Portenta H7: ``lsm6dso32_driver``.

A managed (lifecycle) node. *configure* starts the link: the board's serial port (a device path
or a pyserial URL such as ``socket://127.0.0.1:PORT`` for the emulator) is opened and the board
configured (``link.session``), retried every ``reconnect_period_s``; *activate* publishes;
*deactivate* stops publishing (samples counted and dropped); *cleanup* and *shutdown* close the
port. ``autostart`` (default true) walks the node to active at start. Topics (REP-145; reliable
keep-last ``qos_depth``, REP-2003):

- ``imu/data_raw`` (``sensor_msgs/Imu``, one message per sample: rad/s, m/s^2, orientation
  unknown so ``orientation_covariance[0] = -1``, diagonal covariances from parameters);
- ``imu/temperature`` (``sensor_msgs/Temperature``, degC, for samples whose counter is a multiple
  of ``temperature_decimation``, so the choice survives reconnections);
- ``/diagnostics``: status ``'<node name>: link'`` (keys in ``docs/diagnostics.md``).

One reader thread owns the port: it wakes when bytes arrive, decodes (``link.protocol.Decoder``),
maps device time to the node clock without steps (``link.clock.DeviceClock``; the first
``clock_settle_s`` of an epoch held while it converges), scales to SI, serialises in bulk and
publishes each board frame's messages itself, so no queue sits between threads. A sample is
published only if its wrapping uint32 counter is ahead of the last one published
(``link.sequence.SequenceTracker``): nothing twice, every gap counted in ``Samples lost`` (the
board's count, never the stamps'). A read/write error or ``data_timeout_s`` of silence closes the
port, reports ERROR and retries; the node never exits for it. Details: docs/diagnostics.md.
"""

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import fields
import sys
import threading
import time
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
from numpy.typing import NDArray
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.publisher import Publisher
from sensor_msgs.msg import Imu, Temperature

from ._realtime import REALTIME_DOC, set_realtime_priority
from ._ros_common import (declare_parameter_table, diagnostic_array, diagnostic_status,
                          diagnostics_publisher, driver_qos, ParamSpec, run_node,
                          specs_from_dataclass, wall_timer)
from ..errors import ParameterError
from ..link import lsm6dso32
from ..link.clock import DeviceClock
from ..link.health import LinkTask, LinkThresholds
from ..link.port import hardware_id_for, validate_port
from ..link.protocol import SAMPLE_DTYPE
from ..link.reader import LinkReader
from ..link.sequence import SequenceTracker
from ..link.session import LinkConfig
from ..msgs import encode_temperature_cdr
from ..msgs.imu_rows import row_messages, RowEncoder

__all__ = ['LinkConfig', 'Lsm6dso32Driver', 'main', 'NODE_NAME', 'PARAMETERS']

NODE_NAME = 'lsm6dso32_driver'

#: ``listener(temperatures, imu)``: a node in this process given each read's published messages.
Listener = Callable[[list[bytes], list[bytes]], None]

# The largest LSM6DSO32 rate (datasheet 6.66 kHz), the one the paper records at.
_DEFAULT_ODR = max(lsm6dso32.ODRS_HZ)

#: The parameter table (see ``config/lsm6dso32_driver.yaml``).
PARAMETERS = (
    ParamSpec('port', '/dev/ttyACM0',
              'Serial device of the board or a pyserial URL such as socket://127.0.0.1:PORT',
              read_only=True),
    ParamSpec('baud_rate', 2_000_000, 'UART baud rate; ignored by USB CDC ports; a real UART '
              'needs about 2 MBd at 6.66 kHz', unit='Bd', read_only=True, min_value=9600,
              max_value=12_000_000),
    ParamSpec('frame_id', 'imu_link', 'header.frame_id of the published messages',
              pattern=r'[A-Za-z0-9_./-]+'),
    ParamSpec('hardware_id', '', 'hardware_id of the diagnostics (empty: lsm6dso32/portenta_h7/ '
              'and the USB serial number of the board, or the frame_id without one)',
              read_only=True),
    ParamSpec('autostart', True, 'Walk the lifecycle to active at start (false: a lifecycle '
              'manager or launch file drives configure and activate)', read_only=True),
    ParamSpec('odr_hz', _DEFAULT_ODR, 'Output data rate requested from the board',
              unit='Hz', read_only=True, choices=tuple(lsm6dso32.ODRS_HZ)),
    ParamSpec('gyro_full_scale_dps', 2000, 'Gyroscope full scale requested from the board',
              unit='deg/s', read_only=True, choices=tuple(lsm6dso32.GYRO_FULL_SCALES_DPS)),
    # +/-32 g, the range the paper's setup describes (0.976 mg/LSB); a static noise test would
    # resolve more with 4 g, at the risk of clipping shocks.
    ParamSpec('accel_full_scale_g', 32, 'Accelerometer full scale requested from the board',
              unit='g', read_only=True, choices=tuple(lsm6dso32.ACCEL_FULL_SCALES_G)),
    # Paper (Sierociuk et al. 2025) Table 4, reference sequence: mean chunk variance 0.003414
    # (deg/s)^2 = 1.04e-6 (rad/s)^2 at 6660 Hz, +/-2000 dps.
    ParamSpec('angular_velocity_variance_rad2_s2', 1.04e-6,
              'Diagonal of angular_velocity_covariance (0 = unknown)',
              unit='rad^2/s^2', min_value=0.0, max_value=1.0e3),
    ParamSpec('linear_acceleration_variance_m2_s4', 0.0,
              'Diagonal of linear_acceleration_covariance (0 = unknown)',
              unit='m^2/s^4', min_value=0.0, max_value=1.0e5),
    ParamSpec('temperature_variance_c2', 0.0, 'variance field of imu/temperature (0 = unknown)',
              unit='degC^2', min_value=0.0, max_value=1.0e4),
    # The sensor's temperature output updates at 52 Hz (datasheet); 128 gives 52 Hz at 6.66 kHz.
    ParamSpec('temperature_decimation', 128,
              'Publish imu/temperature for samples whose sequence number is a multiple of this',
              unit='samples', min_value=1, max_value=1_000_000),
    ParamSpec('qos_depth', 5000, 'History depth of imu/data_raw and imu/temperature (reliable, '
              'keep last)', unit='messages', read_only=True, min_value=1, max_value=1_000_000),
    ParamSpec('read_period_s', 0.01,
              'Longest wait for bytes from the port before the reader checks for a stop or a '
              'silent link (bytes are published as they arrive)',
              unit='s', read_only=True, min_value=0.0005, max_value=0.5),
    # 0.5 s: the block minimum of ~200 frames is within ~mean jitter / 200 of the transport
    # latency (docs/portenta_link.md), so the stamps start within tens of microseconds of the
    # estimate and never need a correction a reader would take for a lost sample.
    ParamSpec('clock_settle_s', 0.5,
              'At the start of a board epoch (connection to a new board, restart) the samples of '
              'the first clock_settle_s are held back while the board-to-host clock mapping '
              'converges, then published; 0: publish at once (early stamps are then corrected '
              'by compressing batches)', unit='s', read_only=True, min_value=0.0,
              max_value=10.0),
    ParamSpec('ack_timeout_s', 1.0, 'Wait for the acknowledgement of the configuration command',
              unit='s', min_value=0.01, max_value=60.0),
    ParamSpec('data_timeout_s', 2.0, 'Silence on a configured link after which it is reopened',
              unit='s', min_value=0.05, max_value=3600.0),
    ParamSpec('reconnect_period_s', 1.0, 'Wait between attempts to reopen a lost or absent port',
              unit='s', min_value=0.01, max_value=3600.0),
    ParamSpec('diagnostics_period_s', 1.0, 'Period of the link status on /diagnostics',
              unit='s', read_only=True, min_value=0.05, max_value=3600.0),
    ParamSpec('realtime_priority', 0, REALTIME_DOC, read_only=True, min_value=0,
              max_value=99),
    *specs_from_dataclass(LinkThresholds, read_only=False),
)

_THRESHOLD_NAMES = tuple(f.name for f in fields(LinkThresholds))
_OK = TransitionCallbackReturn.SUCCESS


def _diag_cov(variance: float) -> NDArray[np.float64]:
    return np.diag([variance] * 3).reshape(9)


def _warm_kernels(encoder: RowEncoder) -> None:
    """
    Compile (or load from numba's cache) the per-frame kernels now, not on the first frame.

    The clock's steady path and the encoder's scaled rows, with what a frame gives them: the
    strided fields of decoded samples.
    """
    warm = np.zeros(4, SAMPLE_DTYPE)
    warm['t_us'] = (0, 150, 300, 450)
    clock = DeviceClock(settle_s=0.0)
    clock.update(warm['t_us'][:2], 10**9)
    clock.update(warm['t_us'][2:], 10**9 + 301_000)
    encoder.rows_scaled(np.zeros(4, np.int64), warm['gyro'], warm['accel'], 1.0, 1.0)


def _publish_raw(publisher: Publisher, blobs: Iterable[bytes]) -> None:
    """Publish serialised messages: what ``Publisher.publish`` does for bytes, once per batch."""
    if not getattr(publisher, 'is_activated', True):
        return  # a lifecycle publisher publishes only while the node is active
    handle = publisher.handle
    with handle:
        publish = handle.publish_raw
        for blob in blobs:
            publish(blob)


class Lsm6dso32Driver(LifecycleNode):
    """
    The ``lsm6dso32_driver`` node (see the module docstring).

    Parameters
    ----------
    node_name : str
        Node name (default :data:`NODE_NAME`).
    listeners : sequence of callable, keyword-only
        ``listener(temperatures, imu)``, called in the reader thread after each publication
        with the serialised messages just published (lists of bytes; temperatures first, often
        none): a node in the same process takes them without a trip through DDS (``imu_chain``,
        :mod:`.chain`). Called only while the node publishes (active).
    **kwargs
        Passed to ``rclpy.lifecycle.LifecycleNode`` (``parameter_overrides``, ``context``).

    Raises
    ------
    ParameterError
        A parameter override is of the wrong type, out of range, or the port is not usable.

    """

    def __init__(self, node_name: str = NODE_NAME, *, listeners: Sequence[Listener] = (),
                 **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._listeners = tuple(listeners)
        p = declare_parameter_table(self, PARAMETERS, on_change=self._on_parameters_changed)
        self._params = p
        # Before the reader thread exists (it inherits the policy); rclpy's threads are set too.
        set_realtime_priority(p['realtime_priority'])
        self._port = validate_port(p['port'])
        self._hardware_id = p['hardware_id'] or hardware_id_for(self._port, p['frame_id'])
        self._status_name = f'{self.get_name()}: link'
        self._message_fields = self._make_message_fields(p)
        self._scales: tuple[LinkConfig | None, float, float] = (None, 0.0, 0.0)
        _warm_kernels(self._message_fields['imu_rows'])
        qos = driver_qos(p['qos_depth'])
        self._imu_pub = self.create_publisher(Imu, 'imu/data_raw', qos)
        self._temp_pub = self.create_publisher(Temperature, 'imu/temperature', qos)
        self._diag_pub = diagnostics_publisher(self)
        self._device_clock = DeviceClock(nominal_rate_hz=float(p['odr_hz']),
                                         settle_s=p['clock_settle_s'])
        # Samples whose stamps the clock holds back while its epoch settles, with their scaling.
        self._unstamped: list[tuple[np.ndarray, LinkConfig]] = []
        self._tracker = SequenceTracker(restart_window=max(1, int(round(p['odr_hz']))))
        self._reader = LinkReader(self._port, lambda: self._params, self._handle,
                                  now_ns=lambda: self.get_clock().now().nanoseconds,
                                  on_error=self._link_failed, on_streaming=self._link_up)
        # Written by the reader thread and the lifecycle callbacks, read by the diagnostics timer.
        self._lock = threading.Lock()
        self._lifecycle = 'unconfigured'
        self._activated_at = time.monotonic()
        self._counts = dict.fromkeys(('published', 'temperatures', 'lost', 'duplicates',
                                      'restarts', 'discarded', 'listener_errors'), 0)
        # Diagnostics: counters ticked by the reader thread, judged on the timer.
        self._link_task = LinkTask(LinkThresholds(**{k: p[k] for k in _THRESHOLD_NAMES}),
                                   port=self._port, period_s=p['diagnostics_period_s'],
                                   now=time.monotonic(), snapshot=self.link_snapshot())
        wall_timer(self, p['diagnostics_period_s'], self._publish_diagnostics)
        if p['autostart']:
            self.trigger_configure()
            self.trigger_activate()

    def _make_message_fields(self, p: Mapping[str, Any]) -> dict[str, Any]:
        return {
            'frame_id': p['frame_id'],
            # the Imu messages: a template with the frame_id and covariances, the stamps and
            # vectors written in
            'imu_rows': RowEncoder(p['frame_id'],
                                   _diag_cov(p['angular_velocity_variance_rad2_s2']),
                                   _diag_cov(p['linear_acceleration_variance_m2_s4'])),
            'temp_var': p['temperature_variance_c2'],
            'decimation': p['temperature_decimation'],
        }

    def _on_parameters_changed(self, changed: dict[str, Any]) -> None:
        self._params = {**self._params, **changed}
        # One attribute swap: the reader thread sees either the old or the new set, never a mix.
        self._message_fields = self._make_message_fields(self._params)
        try:
            self._link_task.thresholds = LinkThresholds(
                **{k: self._params[k] for k in _THRESHOLD_NAMES})
        except ParameterError as err:
            self.get_logger().error(f'link thresholds unchanged: {err}')

    # ------------------------------------------------------------------ lifecycle

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start the link: open the port and configure the board (retried until it works)."""
        self._set_lifecycle('inactive')
        self._reader.start()
        return _OK

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Publish the samples from now on."""
        self._set_lifecycle('active')
        return _OK

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop publishing; the link stays up and its samples are counted and dropped."""
        self._set_lifecycle('inactive')
        return _OK

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop the reader thread, which closes the port."""
        self._reader.stop()
        self._set_lifecycle('unconfigured')
        return _OK

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the port, from any state."""
        return self.on_cleanup(state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the port after a failed transition."""
        return self.on_cleanup(state)

    def _set_lifecycle(self, name: str) -> None:
        with self._lock:
            self._lifecycle = name
            if name == 'active':
                self._activated_at = time.monotonic()

    # ------------------------------------------------------------------ reader callbacks

    def _link_up(self, config: LinkConfig) -> None:
        self.get_logger().info(f'streaming from {self._port}: {config.odr_hz:g} Hz, '
                               f'+/-{config.gyro_fs_dps} dps, +/-{config.accel_fs_g} g')

    def _link_failed(self, reason: str, first: bool) -> None:
        if first:
            self.get_logger().error(f'link to {self._port}: {reason}; retrying every '
                                    f'{self._params["reconnect_period_s"]} s')

    def _handle(self, samples: np.ndarray, host_ns: int, config: LinkConfig) -> None:
        if self._lifecycle == 'active':
            self.publish_samples(samples, host_ns, config)
            return
        # Inactive: the counter advances so that activation does not count a gap as loss.
        while len(samples):
            decision = self._tracker.accept(samples['seq'])
            with self._lock:
                self._counts['discarded'] += int(np.count_nonzero(decision.keep))
            samples = samples[decision.stop:]
            if len(samples):
                self._tracker.reset()

    # ------------------------------------------------------------------ publishing

    def publish_samples(self, samples: np.ndarray, host_receive_ns: int,
                        config: LinkConfig) -> int:
        """
        Publish decoded samples: drop already published counters, stamp, scale, serialise.

        Called by the reader thread for every decoded batch while active, as it arrives; tests
        call it with known samples. The first ``clock_settle_s`` of a board epoch are held until
        the clock mapping has settled and published by a later call, in order.

        Parameters
        ----------
        samples : numpy.ndarray of ``link.protocol.SAMPLE_DTYPE``
            Decoded samples in arrival order.
        host_receive_ns : int
            Node-clock time the bytes were read, in ns.
        config : LinkConfig
            Acknowledged scaling of these samples.

        Returns
        -------
        int
            Number of ``imu/data_raw`` messages published by this call.

        """
        published = 0
        while len(samples):
            decision = self._tracker.accept(samples['seq'])
            part = samples if decision.whole else samples[:decision.stop][decision.keep]
            published += self._publish_part(part, host_receive_ns, config)
            with self._lock:
                self._counts['lost'] += decision.lost
                self._counts['duplicates'] += decision.duplicates
            samples = samples[decision.stop:]
            if len(samples):
                # The counter fell back by more than the restart window: a new board epoch.
                self._tracker.reset()
                published += self._publish_stamped(self._device_clock.flush())
                self._device_clock.reset()
                with self._lock:
                    self._counts['restarts'] += 1
                self.get_logger().warning(f'sample counter restarted at {int(samples["seq"][0])}')
        return published

    def _publish_part(self, part: np.ndarray, host_receive_ns: int, config: LinkConfig) -> int:
        if len(part) == 0:
            return 0
        # Strictly increasing across calls and clock resets, and without steps; none while a new
        # epoch settles (those samples wait in _unstamped, in order).
        stamps = self._device_clock.update(part['t_us'], host_receive_ns)
        self._unstamped.append((part, config))
        return self._publish_stamped(stamps)

    def _publish_stamped(self, stamps: np.ndarray) -> int:
        """Publish the oldest held samples that ``stamps`` belong to, in order."""
        done = 0
        while done < stamps.size:
            part, config = self._unstamped[0]
            take = min(len(part), stamps.size - done)
            if take < len(part):
                self._unstamped[0] = (part[take:], config)
                part = part[:take]
            else:
                self._unstamped.pop(0)
            self._publish_messages(part, stamps[done:done + take], config)
            done += take
        return done

    def _sensitivities(self, config: LinkConfig) -> tuple[float, float]:
        """Return (rad/s, m/s^2) per LSB of ``config``'s full scales (kept per configuration)."""
        if self._scales[0] is not config:
            self._scales = (config, lsm6dso32.gyro_sensitivity_rad_s_per_lsb(config.gyro_fs_dps),
                            lsm6dso32.accel_sensitivity_m_s2_per_lsb(config.accel_fs_g))
        return self._scales[1], self._scales[2]

    def _publish_messages(self, part: np.ndarray, stamps: np.ndarray, config: LinkConfig) -> None:
        n = len(part)
        gyro_lsb, accel_lsb = self._sensitivities(config)
        f = self._message_fields
        pick = (part['seq'] % f['decimation']) == 0
        n_temp = int(np.count_nonzero(pick))
        temperatures: list[bytes] = []
        if n_temp:  # one batch in a few at the default decimation
            # Before the Imu messages of the frame: a consumer taking both at one wake-up has the
            # newest temperature for them.
            temperatures = encode_temperature_cdr(
                stamps[pick], lsm6dso32.temperature_c(part['temp'][pick]), frame_id=f['frame_id'],
                variance=f['temp_var'])
            _publish_raw(self._temp_pub, temperatures)
        # lsm6dso32.to_si's values (the raw words times the sensitivities), written as messages
        imu = row_messages(f['imu_rows'].rows_scaled(stamps, part['gyro'], part['accel'],
                                                     gyro_lsb, accel_lsb))
        _publish_raw(self._imu_pub, imu)
        if self._listeners:
            self._hand_over(temperatures, imu)
        with self._lock:
            self._counts['published'] += n
            self._counts['temperatures'] += n_temp

    def _hand_over(self, temperatures: list[bytes], imu: list[bytes]) -> None:
        """Give the messages just published to the listeners; a failing one is logged."""
        for listener in self._listeners:
            try:
                listener(temperatures, imu)
            except Exception as err:  # noqa: BLE001 - the link and the other listeners go on
                with self._lock:
                    self._counts['listener_errors'] += 1
                self.get_logger().error(f'an in-process listener failed: {err!r}',
                                        throttle_duration_sec=5.0)

    # ------------------------------------------------------------------ diagnostics

    def link_snapshot(self) -> dict[str, Any]:
        """
        Copy the link's state and counters (for diagnostics and tests).

        Returns
        -------
        dict
            :meth:`LinkReader.snapshot` (``state``, ``last_error``, ``config``, ``connections``,
            ``streaming_since``, ``last_sample_monotonic``, ``link``), ``lifecycle`` and the
            node's counters ``published``, ``temperatures``, ``lost``, ``duplicates``,
            ``restarts``, ``discarded``.

        """
        link = self._reader.snapshot()
        with self._lock:
            return {**link, 'lifecycle': self._lifecycle, **self._counts,
                    'activated_at': self._activated_at}

    def _publish_diagnostics(self) -> None:
        self._diag_pub.publish(diagnostic_array(self.get_clock().now().to_msg(),
                                                [self.link_status()]))

    def link_status(self) -> DiagnosticStatus:
        """
        Build the ``'<node>: link'`` status from the counters since the previous call.

        The node only wraps :meth:`gyro_noise_ros.link.health.LinkTask.run` (the window judged
        with the thresholds of the parameters); the keys are listed in ``docs/diagnostics.md``.

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticStatus

        """
        status = self._link_task.run(self.link_snapshot(), time.monotonic(),
                                     drift_ppm=self._device_clock.state.drift_ppm)
        return diagnostic_status(self._status_name, self._hardware_id,
                                 bytes([status.level_byte]), status.message, status.values)

    def destroy_node(self) -> None:
        """Stop and join the reader thread (it closes the port), then destroy the node."""
        self._reader.stop()
        return super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """
    Run ``lsm6dso32_driver`` (console script); parameters via ``--ros-args -p``/``--params-file``.

    ``args`` is the command line (None: ``sys.argv``). Returns 0 on Ctrl-C or external shutdown; 2,
    with one line on stderr, for a bad parameter or an unknown ROS argument.

    """
    return run_node(Lsm6dso32Driver, args, prog=NODE_NAME, parameters=PARAMETERS,
                    summary=__doc__)


if __name__ == '__main__':
    sys.exit(main())
