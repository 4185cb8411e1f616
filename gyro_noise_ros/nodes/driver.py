"""
ROS 2 driver of the LSM6DSO32 read by an Arduino Portenta H7: ``lsm6dso32_driver``.

Opens the board's serial port (a device path or any pyserial URL, e.g. ``socket://127.0.0.1:PORT``
for the emulator), configures output data rate and full scales, waits for the board's
acknowledgement, and from then on publishes every sample:

- ``imu/data_raw`` (``sensor_msgs/Imu``, one message per sample, REP-145: rad/s, m/s^2, orientation
  unknown so ``orientation_covariance[0] = -1``, diagonal covariances from parameters, sensor-data QoS);
- ``imu/temperature`` (``sensor_msgs/Temperature``, degC, one of every ``temperature_decimation``
  samples, chosen by sequence counter so the choice survives reconnections);
- ``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``): status ``'<node name>: link'``.

Threads. One reader thread owns the port: it reads, decodes (``link.protocol.Decoder``), maps device
time to the node clock (``link.clock.DeviceClock``: stamps are monotonic and free of USB receive
jitter), scales to SI (``link.lsm6dso32.to_si``), serialises the messages in bulk with numpy
(``bag.encode_imu_cdr``) and publishes the serialised bytes itself; rclpy publishers are thread-safe,
and publishing where the data is decoded avoids a queue between threads (nothing unbounded: if
publishing falls behind, reads wait and the board's own buffer overflows, which the board flags).
The executor only runs the diagnostics timer, so nothing ever blocks it.

Losses and duplicates. The board numbers samples with a wrapping uint32 counter. The node publishes
a sample only if its counter is ahead of the last published one (modulo 2**32), so nothing is ever
published twice, also when a reconnected board re-sends buffered samples; every counter gap between
published samples, within a connection or across an unplug, is counted in ``Samples lost``. A counter
that falls back by more than one second of samples is a board restart: the node starts a new epoch
(clock estimator reset, stamps still monotonic) instead of waiting for the old count.

Unplug. Any read/write error or ``data_timeout_s`` of silence (at least three full frames at low
rates) closes the port, reports ERROR with the reason and retries every ``reconnect_period_s`` until the port is back; the node never exits for it.
"""

import sys
import threading
import time
from dataclasses import dataclass, fields

import numpy as np
import serial
from rclpy.node import Node
from sensor_msgs.msg import Imu, Temperature

from ..bag import encode_imu_cdr, encode_temperature_cdr
from ..errors import LinkError, ParameterError
from ..link import lsm6dso32
from ..link.clock import DeviceClock
from ..link.health import judge_link, LinkThresholds, LinkWindow
from ..link.protocol import Decoder, encode_configure, MAX_SAMPLES_PER_FRAME
from ..link.sequence import SequenceTracker
from ..core.health import LEVEL_BYTE
from ._ros_common import (declare_parameter_table, diagnostic_array, diagnostic_status,
                          diagnostics_publisher, ParamSpec, run_node, sensor_data_qos,
                          specs_from_dataclass)

NODE_NAME = 'lsm6dso32_driver'

# The largest LSM6DSO32 rate (datasheet 6.66 kHz), the one the paper records at.
_DEFAULT_ODR = max(lsm6dso32.ODRS_HZ)

#: The parameter table (see ``config/lsm6dso32_driver.yaml``).
PARAMETERS = (
    ParamSpec('port', '/dev/ttyACM0',
              'Serial device of the board or a pyserial URL such as socket://127.0.0.1:PORT',
              read_only=True),
    ParamSpec('baud_rate', 2_000_000,
              'UART baud rate; ignored by USB CDC ports; a real UART needs about 2 MBd at 6.66 kHz',
              unit='Bd', read_only=True, min_value=9600, max_value=12_000_000),
    ParamSpec('frame_id', 'imu_link', 'header.frame_id of the published messages',
              pattern=r'[A-Za-z0-9_./-]+'),
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
    ParamSpec('qos_depth', 5000, 'History depth of imu/data_raw and imu/temperature (sensor-data QoS)',
              unit='messages', read_only=True, min_value=1, max_value=1_000_000),
    ParamSpec('read_period_s', 0.01,
              'Longest wait of one port read; batches samples and bounds the publishing latency',
              unit='s', read_only=True, min_value=0.0005, max_value=0.5),
    ParamSpec('ack_timeout_s', 1.0, 'Wait for the acknowledgement of the configuration command',
              unit='s', min_value=0.01, max_value=60.0),
    ParamSpec('data_timeout_s', 2.0, 'Silence on a configured link after which it is reopened',
              unit='s', min_value=0.05, max_value=3600.0),
    ParamSpec('reconnect_period_s', 1.0, 'Wait between attempts to reopen a lost or absent port',
              unit='s', min_value=0.01, max_value=3600.0),
    ParamSpec('diagnostics_period_s', 1.0, 'Period of the link status on /diagnostics',
              unit='s', read_only=True, min_value=0.05, max_value=3600.0),
    *specs_from_dataclass(LinkThresholds, read_only=False),
)

_READ_SIZE = 1 << 16
_THRESHOLD_NAMES = tuple(f.name for f in fields(LinkThresholds))


@dataclass(frozen=True)
class LinkConfig:
    """Configuration the board acknowledged: rate in Hz, full scales in deg/s and g."""

    odr_hz: float
    gyro_fs_dps: int
    accel_fs_g: int


def _frame_interval_s(config):
    """Longest normal silence of a link: three full frames (the firmware may batch up to 128)."""
    return 3.0 * MAX_SAMPLES_PER_FRAME / config.odr_hz


def _diag_counters(now, snapshot):
    link = snapshot['link']
    out = {k: link.get(k, 0) for k in ('crc_errors', 'fifo_overruns', 'frames_ok', 'samples_ok')}
    out.update(time=now, published=snapshot['published'], lost=snapshot['lost'],
               restarts=snapshot['restarts'])
    return out


def _stats_dict(stats):
    return {f.name: getattr(stats, f.name) for f in fields(stats)}


def _diag_cov(variance):
    return np.diag([variance] * 3).reshape(9)


class Lsm6dso32Driver(Node):
    """
    The ``lsm6dso32_driver`` node (see the module docstring).

    Parameters
    ----------
    node_name : str
        Node name (default :data:`NODE_NAME`).
    **kwargs
        Passed to ``rclpy.node.Node`` (e.g. ``parameter_overrides``, ``context``).

    Raises
    ------
    ParameterError
        A parameter override is of the wrong type, out of range, or the port is not a usable name.

    """

    def __init__(self, node_name=NODE_NAME, **kwargs):
        super().__init__(node_name, **kwargs)
        p = declare_parameter_table(self, PARAMETERS, on_change=self._on_parameters_changed)
        self._params = p
        port = p['port'].strip()
        if not port:
            raise ParameterError("parameter 'port' is empty: give a device path or a pyserial URL")
        try:
            serial.serial_for_url(port, do_not_open=True)
        except (ValueError, serial.SerialException) as err:
            raise ParameterError(f"parameter 'port' = {port!r} is not usable: {err}") from err
        self._thresholds = LinkThresholds(**{k: p[k] for k in _THRESHOLD_NAMES})
        self._port = port
        self._hardware_id = f'lsm6dso32@{port}'
        self._status_name = f'{self.get_name()}: link'
        self._message_fields = self._make_message_fields(p)

        qos = sensor_data_qos(p['qos_depth'])
        self._imu_pub = self.create_publisher(Imu, 'imu/data_raw', qos)
        self._temp_pub = self.create_publisher(Temperature, 'imu/temperature', qos)
        self._diag_pub = diagnostics_publisher(self)

        self._device_clock = DeviceClock(nominal_rate_hz=float(p['odr_hz']))
        self._tracker = SequenceTracker(restart_window=max(1, int(round(p['odr_hz']))))

        # Everything below is written by the reader thread and read by the diagnostics timer.
        self._lock = threading.Lock()
        self._state = 'connecting'
        self._last_error = 'none'
        self._last_logged_error = None
        self._config = None
        self._link_stats = {}
        self._published = 0
        self._temperatures = 0
        self._lost = 0
        self._duplicates = 0
        self._restarts = 0
        self._connections = 0
        self._streaming_since = None
        self._last_sample_monotonic = None
        self._diag_prev = _diag_counters(time.monotonic(), self.link_snapshot())

        self._stop = threading.Event()
        self._reader = threading.Thread(target=self._reader_loop, name='lsm6dso32_reader', daemon=True)
        self._reader.start()
        self._diag_timer = self.create_timer(p['diagnostics_period_s'], self._publish_diagnostics)

    # ------------------------------------------------------------------ parameters

    def _make_message_fields(self, p):
        return {
            'frame_id': p['frame_id'],
            'gyro_cov': _diag_cov(p['angular_velocity_variance_rad2_s2']),
            'accel_cov': _diag_cov(p['linear_acceleration_variance_m2_s4']),
            'temp_var': p['temperature_variance_c2'],
            'decimation': p['temperature_decimation'],
        }

    def _on_parameters_changed(self, changed):
        self._params = {**self._params, **changed}
        # One attribute swap: the reader thread sees either the old or the new set, never a mix.
        self._message_fields = self._make_message_fields(self._params)
        try:
            self._thresholds = LinkThresholds(**{k: self._params[k] for k in _THRESHOLD_NAMES})
        except ParameterError as err:
            self.get_logger().error(f'link thresholds unchanged: {err}')

    # ------------------------------------------------------------------ reader thread

    def _reader_loop(self):
        # One decoder for the node's life: reset_stream() at each connection drops a partial frame
        # but keeps the counters, so diagnostics add up over unplugs.
        decoder = Decoder()
        while not self._stop.is_set():
            self._set_state('connecting')
            try:
                ser = serial.serial_for_url(self._port, baudrate=self._params['baud_rate'],
                                            timeout=self._params['read_period_s'],
                                            write_timeout=self._params['ack_timeout_s'])
            except (serial.SerialException, OSError, ValueError) as err:
                self._link_failed(f'cannot open {self._port}: {err}')
                self._stop.wait(self._params['reconnect_period_s'])
                continue
            decoder.reset_stream()
            try:
                self._run_session(ser, decoder)
            except (serial.SerialException, OSError, LinkError) as err:
                self._link_failed(str(err) or type(err).__name__)
            except Exception as err:  # noqa: BLE001 - the reader must outlive any single failure
                if self._stop.is_set() or not self.context.ok():
                    break
                self.get_logger().error(f'reader thread: {err!r}')
                self._link_failed(f'internal error: {err!r}')
            finally:
                try:
                    ser.close()
                except Exception:  # noqa: BLE001 - closing a vanished port may fail; it is gone anyway
                    pass
                with self._lock:
                    self._link_stats = _stats_dict(decoder.stats)
            if not self._stop.is_set():
                self._stop.wait(self._params['reconnect_period_s'])
        self._set_state('stopped')

    def _run_session(self, ser, decoder):
        """Configure the board on an open port, then publish until the link fails or the node stops."""
        self._set_state('configuring')
        with self._lock:
            self._connections += 1
            command_id = self._connections
        p = self._params
        ser.write(encode_configure(command_id=command_id, odr_hz=p['odr_hz'],
                                   gyro_fs_dps=p['gyro_full_scale_dps'],
                                   accel_fs_g=p['accel_full_scale_g']))
        deadline = time.monotonic() + p['ack_timeout_s']
        ack = None
        while ack is None:
            if self._stop.is_set():
                return
            if time.monotonic() > deadline:
                raise LinkError(f'no acknowledgement of the configuration within {p["ack_timeout_s"]} s')
            data = ser.read(_READ_SIZE)
            if not data:
                continue
            host_ns = self.get_clock().now().nanoseconds
            result = decoder.feed(data)
            for ack_index, candidate in enumerate(result.acks):
                if candidate.command_id == command_id:
                    ack = candidate
                    # Samples before the acknowledgement may carry the previous configuration's
                    # scaling: they are dropped, and the counter gap counts them as lost.
                    after = result.samples[result.ack_positions[ack_index]:]
                    break
        if not ack.ok:
            raise LinkError(f'the board refused odr {p["odr_hz"]} Hz, gyro {p["gyro_full_scale_dps"]} '
                            f'dps, accel {p["accel_full_scale_g"]} g: {ack.message}')
        config = LinkConfig(float(ack.odr_hz), int(ack.gyro_fs_dps), int(ack.accel_fs_g))
        now = time.monotonic()
        with self._lock:
            self._config = config
            self._last_logged_error = None
            self._streaming_since = now
            self._last_sample_monotonic = now
            self._state = 'streaming'
        self.get_logger().info(f'streaming from {self._port}: {config.odr_hz:g} Hz, '
                               f'+/-{config.gyro_fs_dps} dps, +/-{config.accel_fs_g} g')
        if len(after):
            self.publish_samples(after, host_ns, config)
        last_data = now
        silence_s = max(p['data_timeout_s'], _frame_interval_s(config))
        while not self._stop.is_set():
            data = ser.read(_READ_SIZE)
            now = time.monotonic()
            if not data:
                if now - last_data > silence_s:
                    raise LinkError(f'no data for {silence_s:g} s')
                continue
            last_data = now
            host_ns = self.get_clock().now().nanoseconds
            result = decoder.feed(data)
            if len(result.samples):
                self.publish_samples(result.samples, host_ns, config)
            with self._lock:
                self._link_stats = _stats_dict(decoder.stats)
                if len(result.samples):
                    self._last_sample_monotonic = now

    def _set_state(self, state):
        with self._lock:
            self._state = state
            if state != 'streaming':
                self._streaming_since = None

    def _link_failed(self, reason):
        with self._lock:
            first = self._last_logged_error != reason
            self._last_logged_error = reason
            self._last_error = reason
            self._state = 'disconnected'
            self._streaming_since = None
        if first:
            self.get_logger().error(f'link to {self._port}: {reason}; retrying every '
                                    f'{self._params["reconnect_period_s"]} s')

    # ------------------------------------------------------------------ publishing

    def publish_samples(self, samples, host_receive_ns, config):
        """
        Publish decoded samples: drop already published counters, stamp, scale, serialise, publish.

        Called by the reader thread for every decoded batch; tests call it with known samples.

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
            Number of ``imu/data_raw`` messages published.

        """
        published = 0
        while len(samples):
            decision = self._tracker.accept(samples['seq'])
            part = samples[:decision.stop][decision.keep]
            published += self._publish_part(part, host_receive_ns, config)
            with self._lock:
                self._lost += decision.lost
                self._duplicates += decision.duplicates
            samples = samples[decision.stop:]
            if len(samples):
                # The counter fell back by more than the restart window: a new board epoch.
                self._tracker.reset()
                self._device_clock.reset()
                with self._lock:
                    self._restarts += 1
                self.get_logger().warning(f'sample counter restarted at {int(samples["seq"][0])}')
        return published

    def _publish_part(self, part, host_receive_ns, config):
        n = len(part)
        if n == 0:
            return 0
        # Strictly increasing across calls and clock resets (DeviceClock's monotonic floor).
        stamps = self._device_clock.update(part['t_us'], host_receive_ns)
        si = lsm6dso32.to_si(part, gyro_fs_dps=config.gyro_fs_dps, accel_fs_g=config.accel_fs_g)
        f = self._message_fields
        publish = self._imu_pub.publish
        for blob in encode_imu_cdr(stamps, si.gyro_rad_s, si.accel_m_s2, frame_id=f['frame_id'],
                                   angular_velocity_covariance=f['gyro_cov'],
                                   linear_acceleration_covariance=f['accel_cov']):
            publish(blob)
        pick = (part['seq'] % f['decimation']) == 0
        n_temp = int(np.count_nonzero(pick))
        if n_temp:  # one batch in a few at the default decimation
            publish = self._temp_pub.publish
            for blob in encode_temperature_cdr(stamps[pick], np.asarray(si.temperature_c)[pick],
                                               frame_id=f['frame_id'], variance=f['temp_var']):
                publish(blob)
        with self._lock:
            self._published += n
            self._temperatures += n_temp
        return n

    # ------------------------------------------------------------------ diagnostics

    def link_snapshot(self):
        """
        Copy of the link counters (for diagnostics and tests).

        Returns
        -------
        dict
            ``state``, ``last_error``, ``config``, ``published``, ``temperatures``, ``lost``,
            ``duplicates``, ``restarts``, ``connections``, ``streaming_since``,
            ``last_sample_monotonic`` and the decoder's counters summed over all connections.

        """
        with self._lock:
            link = dict(self._link_stats)
            return {
                'state': self._state, 'last_error': self._last_error, 'config': self._config,
                'published': self._published, 'temperatures': self._temperatures,
                'lost': self._lost, 'duplicates': self._duplicates, 'restarts': self._restarts,
                'connections': self._connections, 'streaming_since': self._streaming_since,
                'last_sample_monotonic': self._last_sample_monotonic, 'link': link,
            }

    def _publish_diagnostics(self):
        self._diag_pub.publish(diagnostic_array(self.get_clock().now().to_msg(),
                                                [self.link_status()]))

    def link_status(self):
        """
        Build the ``'<node>: link'`` status from the counters since the previous call.

        The level comes from :func:`gyro_noise_ros.link.health.judge_link` (its module doc lists
        the checks) with the limits of the parameters.

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticStatus

        """
        s = self.link_snapshot()
        now = time.monotonic()
        link = s['link']
        prev, self._diag_prev = self._diag_prev, _diag_counters(now, s)
        since = prev['time'] if s['streaming_since'] is None else max(prev['time'],
                                                                      s['streaming_since'])
        cur = self._diag_prev
        config = s['config']
        silence = (max(self._params['diagnostics_period_s'], _frame_interval_s(config))
                   if config is not None else float('inf'))
        window = LinkWindow(
            state=s['state'], last_error=s['last_error'], window_s=now - since,
            **{k: cur[k] - prev[k] for k in ('published', 'lost', 'crc_errors', 'fifo_overruns',
                                             'frames_ok', 'samples_ok')},
            restarted=cur['restarts'] > prev['restarts'],
            odr_hz=None if config is None else config.odr_hz,
            seconds_since_sample=now - (s['last_sample_monotonic'] or now),
            silence_limit_s=silence)
        verdict = judge_link(window, self._thresholds)

        def fmt(x, spec='g'):
            return '-' if x is None else format(x, spec)

        values = [
            ('Connection', s['state']),
            ('Port', self._port),
            ('Configured rate (Hz)', fmt(config and config.odr_hz)),
            ('Gyro full scale (deg/s)', fmt(config and config.gyro_fs_dps)),
            ('Accel full scale (g)', fmt(config and config.accel_fs_g)),
            ('Sample rate (Hz)', f'{window.rate_hz:.1f}' if s['state'] == 'streaming' else '0.0'),
            ('Samples published', s['published']),
            ('Samples lost', s['lost']),
            ('Samples flagged lost by the board', link.get('samples_flagged_lost', 0)),
            # Equal consecutive counters are removed by the decoder, older ones by the tracker.
            ('Duplicates dropped', s['duplicates'] + link.get('duplicates', 0)),
            ('CRC errors', link.get('crc_errors', 0)),
            ('Resyncs', link.get('resyncs', 0)),
            ('Bytes discarded', link.get('bytes_discarded', 0)),
            ('Frames ok', link.get('frames_ok', 0)),
            ('Sensor FIFO overruns', link.get('fifo_overruns', 0)),
            ('Clock drift (ppm)', f'{self._device_clock.state.drift_ppm:.1f}'),
            ('Connections', s['connections']),
            ('Counter restarts', s['restarts']),
            ('Temperature messages', s['temperatures']),
            ('Last error', s['last_error']),
        ]
        return diagnostic_status(self._status_name, self._hardware_id,
                                 bytes([LEVEL_BYTE[verdict.level]]), verdict.message, values)

    # ------------------------------------------------------------------ shutdown

    def destroy_node(self):
        """Stop and join the reader thread (it closes the port), then destroy the node."""
        self._stop.set()
        if self._reader.is_alive():
            self._reader.join(timeout=5.0)
        return super().destroy_node()


def main(args=None):
    """
    Run ``lsm6dso32_driver`` (console script); parameters via ``--ros-args -p`` / ``--params-file``.

    Returns
    -------
    int
        0 on Ctrl-C or external shutdown; 2 with one line on stderr for a bad parameter.

    """
    return run_node(Lsm6dso32Driver, args, prog=NODE_NAME)


if __name__ == '__main__':
    sys.exit(main())
