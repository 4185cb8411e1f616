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
configured (CONFIGURE, then its ACK; ``link.session``), retried every ``reconnect_period_s`` until
it succeeds; *activate* publishes the samples; *deactivate* stops publishing (the link stays up,
samples are counted and dropped); *cleanup* and *shutdown* close the port. ``autostart`` (default
true) walks the node to active at start, so ``lsm6dso32_driver --ros-args -p port:=...`` streams
at once. Topics (REP-145, reliable keep-last ``qos_depth`` so every subscriber receives them,
REP-2003):

- ``imu/data_raw`` (``sensor_msgs/Imu``, one message per sample: rad/s, m/s^2, orientation
  unknown so ``orientation_covariance[0] = -1``, diagonal covariances from parameters);
- ``imu/temperature`` (``sensor_msgs/Temperature``, degC, for samples whose counter is a multiple
  of ``temperature_decimation``, so the choice survives reconnections);
- ``/diagnostics``: status ``'<node name>: link'`` (keys in ``docs/diagnostics.md``).

One reader thread owns the port: it reads, decodes (``link.protocol.Decoder``), maps device time to
the node clock (``link.clock.DeviceClock``), scales to SI, serialises in bulk
(``bag.encode_imu_cdr``) and publishes the bytes itself (rclpy publishers are thread-safe), so no
queue sits between threads and the executor only runs the diagnostics timer and the lifecycle
services. A sample is published only if its wrapping uint32 counter is ahead of the last published
one (``link.sequence.SequenceTracker``): nothing twice, every gap counted in ``Samples lost``; a
counter falling back by more than one second of samples is a board restart (new epoch). Any
read/write error or ``data_timeout_s`` of silence closes the port, reports ERROR and retries; the
node never exits for it.
"""

from dataclasses import fields
import sys
import threading
import time

import numpy as np
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from sensor_msgs.msg import Imu, Temperature
import serial

from ._ros_common import (declare_parameter_table, diagnostic_array, diagnostic_status,
                          diagnostics_publisher, driver_qos, ParamSpec, run_node,
                          specs_from_dataclass, wall_timer)
from ..bag import encode_imu_cdr, encode_temperature_cdr
from ..core.health import LEVEL_BYTE
from ..errors import LinkError, ParameterError
from ..link import lsm6dso32
from ..link.clock import DeviceClock
from ..link.health import judge_link, LinkThresholds, LinkWindow
from ..link.port import hardware_id_for, validate_port
from ..link.protocol import Decoder
from ..link.sequence import SequenceTracker
from ..link.session import frame_interval_s, handshake, LinkConfig

__all__ = ['LinkConfig', 'Lsm6dso32Driver', 'main', 'NODE_NAME', 'PARAMETERS']

NODE_NAME = 'lsm6dso32_driver'

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
_COUNTERS = ('crc_errors', 'fifo_overruns', 'frames_ok', 'samples_ok')
_OK = TransitionCallbackReturn.SUCCESS


def _diag_counters(now, snapshot):
    link = snapshot['link']
    out = {k: link.get(k, 0) for k in _COUNTERS}
    out.update(time=now, published=snapshot['published'], lost=snapshot['lost'],
               restarts=snapshot['restarts'])
    return out


def _stats_dict(stats):
    return {f.name: getattr(stats, f.name) for f in fields(stats)}


def _diag_cov(variance):
    return np.diag([variance] * 3).reshape(9)


class Lsm6dso32Driver(LifecycleNode):
    """
    The ``lsm6dso32_driver`` node (see the module docstring).

    Parameters
    ----------
    node_name : str
        Node name (default :data:`NODE_NAME`).
    **kwargs
        Passed to ``rclpy.lifecycle.LifecycleNode`` (``parameter_overrides``, ``context``).

    Raises
    ------
    ParameterError
        A parameter override is of the wrong type, out of range, or the port is not usable.

    """

    def __init__(self, node_name=NODE_NAME, **kwargs):
        super().__init__(node_name, **kwargs)
        p = declare_parameter_table(self, PARAMETERS, on_change=self._on_parameters_changed)
        self._params = p
        self._port = validate_port(p['port'])
        self._thresholds = LinkThresholds(**{k: p[k] for k in _THRESHOLD_NAMES})
        self._hardware_id = p['hardware_id'] or hardware_id_for(self._port, p['frame_id'])
        self._status_name = f'{self.get_name()}: link'
        self._message_fields = self._make_message_fields(p)
        qos = driver_qos(p['qos_depth'])
        self._imu_pub = self.create_publisher(Imu, 'imu/data_raw', qos)
        self._temp_pub = self.create_publisher(Temperature, 'imu/temperature', qos)
        self._diag_pub = diagnostics_publisher(self)
        self._device_clock = DeviceClock(nominal_rate_hz=float(p['odr_hz']))
        self._tracker = SequenceTracker(restart_window=max(1, int(round(p['odr_hz']))))
        # One decoder for the node's life: reset_stream() at each connection drops a partial
        # frame but keeps the counters, so diagnostics add up over unplugs.
        self._decoder = Decoder()
        # Written by the reader thread and the lifecycle callbacks, read by the diagnostics timer.
        self._lock = threading.Lock()
        self._lifecycle = 'unconfigured'
        self._state = 'unconfigured'
        self._last_error = 'none'
        self._last_logged_error = None
        self._config = None
        self._link_stats = {}
        self._counts = dict.fromkeys(('published', 'temperatures', 'lost', 'duplicates',
                                      'restarts', 'connections', 'discarded'), 0)
        self._streaming_since = None
        self._last_sample_monotonic = None
        self._diag_prev = _diag_counters(time.monotonic(), self.link_snapshot())
        self._stop = threading.Event()
        self._reader = None
        wall_timer(self, p['diagnostics_period_s'], self._publish_diagnostics)
        if p['autostart']:
            self.trigger_configure()
            self.trigger_activate()

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

    # ------------------------------------------------------------------ lifecycle

    def on_configure(self, state):
        """Start the reader thread: open the port and configure the board (retried)."""
        self._stop = threading.Event()
        self._set_lifecycle('inactive')
        self._reader = threading.Thread(target=self._reader_loop, name='lsm6dso32_reader',
                                        daemon=True)
        self._reader.start()
        return _OK

    def on_activate(self, state):
        """Publish the samples from now on."""
        self._set_lifecycle('active')
        return _OK

    def on_deactivate(self, state):
        """Stop publishing; the link stays up and its samples are counted and dropped."""
        self._set_lifecycle('inactive')
        return _OK

    def on_cleanup(self, state):
        """Stop the reader thread, which closes the port."""
        self._stop_reader()
        self._set_lifecycle('unconfigured')
        return _OK

    def on_shutdown(self, state):
        """Close the port, from any state."""
        return self.on_cleanup(state)

    def on_error(self, state):
        """Close the port after a failed transition."""
        return self.on_cleanup(state)

    def _set_lifecycle(self, name):
        with self._lock:
            self._lifecycle = name
            if name == 'active' and self._state == 'streaming':
                self._streaming_since = time.monotonic()
            if name == 'unconfigured':
                self._state = 'unconfigured'

    def _stop_reader(self):
        self._stop.set()
        if self._reader is not None and self._reader.is_alive():
            self._reader.join(timeout=5.0)
        self._reader = None

    # ------------------------------------------------------------------ reader thread

    def _reader_loop(self):
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
            self._decoder.reset_stream()
            try:
                self._run_session(ser)
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
                except Exception:  # noqa: BLE001 - a vanished port may fail to close; it is gone
                    pass
                with self._lock:
                    self._link_stats = _stats_dict(self._decoder.stats)
            if not self._stop.is_set():
                self._stop.wait(self._params['reconnect_period_s'])

    def _run_session(self, ser):
        """Configure the board on an open port, then read until the link fails or stops."""
        self._set_state('configuring')
        with self._lock:
            self._counts['connections'] += 1
            command_id = self._counts['connections']
        p = self._params
        done = handshake(ser, self._decoder, command_id=command_id, odr_hz=p['odr_hz'],
                         gyro_fs_dps=p['gyro_full_scale_dps'], accel_fs_g=p['accel_full_scale_g'],
                         ack_timeout_s=p['ack_timeout_s'], stop=self._stop,
                         now_ns=lambda: self.get_clock().now().nanoseconds)
        if done is None:
            return
        config, after, host_ns = done
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
            self._handle(after, host_ns, config)
        last_data = now
        silence_s = max(p['data_timeout_s'], frame_interval_s(config))
        while not self._stop.is_set():
            data = ser.read(_READ_SIZE)
            now = time.monotonic()
            if not data:
                if now - last_data > silence_s:
                    raise LinkError(f'no data for {silence_s:g} s')
                continue
            last_data = now
            host_ns = self.get_clock().now().nanoseconds
            result = self._decoder.feed(data)
            if len(result.samples):
                self._handle(result.samples, host_ns, config)
            with self._lock:
                self._link_stats = _stats_dict(self._decoder.stats)
                if len(result.samples):
                    self._last_sample_monotonic = now

    def _handle(self, samples, host_ns, config):
        if self._lifecycle == 'active':
            self.publish_samples(samples, host_ns, config)
            return
        # Inactive: the counters advance so that activation does not count a gap as loss.
        while len(samples):
            decision = self._tracker.accept(samples['seq'])
            with self._lock:
                self._counts['discarded'] += int(np.count_nonzero(decision.keep))
            samples = samples[decision.stop:]
            if len(samples):
                self._tracker.reset()

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
        Publish decoded samples: drop already published counters, stamp, scale, serialise.

        Called by the reader thread for every decoded batch while active; tests call it with
        known samples.

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
                self._counts['lost'] += decision.lost
                self._counts['duplicates'] += decision.duplicates
            samples = samples[decision.stop:]
            if len(samples):
                # The counter fell back by more than the restart window: a new board epoch.
                self._tracker.reset()
                self._device_clock.reset()
                with self._lock:
                    self._counts['restarts'] += 1
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
            self._counts['published'] += n
            self._counts['temperatures'] += n_temp
        return n

    # ------------------------------------------------------------------ diagnostics

    def link_snapshot(self):
        """
        Copy the link counters (for diagnostics and tests).

        Returns
        -------
        dict
            ``state`` (of the link), ``lifecycle``, ``last_error``, ``config``, the counters
            (``published``, ``temperatures``, ``lost``, ``duplicates``, ``restarts``,
            ``connections``, ``discarded``), ``streaming_since``, ``last_sample_monotonic`` and
            ``link``, the decoder's counters summed over all connections.

        """
        with self._lock:
            return {'state': self._state, 'lifecycle': self._lifecycle,
                    'last_error': self._last_error, 'config': self._config, **self._counts,
                    'streaming_since': self._streaming_since,
                    'last_sample_monotonic': self._last_sample_monotonic,
                    'link': dict(self._link_stats)}

    def _publish_diagnostics(self):
        self._diag_pub.publish(diagnostic_array(self.get_clock().now().to_msg(),
                                                [self.link_status()]))

    def link_status(self):
        """
        Build the ``'<node>: link'`` status from the counters since the previous call.

        The level is :func:`gyro_noise_ros.link.health.judge_link` of the window with the
        thresholds of the parameters; the keys are listed in ``docs/diagnostics.md``.

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticStatus

        """
        s = self.link_snapshot()
        now = time.monotonic()
        link = s['link']
        prev, cur = self._diag_prev, _diag_counters(now, s)
        self._diag_prev = cur
        since = prev['time'] if s['streaming_since'] is None else max(prev['time'],
                                                                      s['streaming_since'])
        config = s['config']
        state = s['state']
        if s['lifecycle'] != 'active' and state in ('streaming', 'unconfigured'):
            state = 'inactive' if state == 'streaming' else state
        window = LinkWindow(
            state=state, last_error=s['last_error'], window_s=now - since,
            restarted=cur['restarts'] > prev['restarts'],
            odr_hz=None if config is None else config.odr_hz,
            seconds_since_sample=now - (s['last_sample_monotonic'] or now),
            silence_limit_s=(max(self._params['diagnostics_period_s'], frame_interval_s(config))
                             if config is not None else float('inf')),
            **{k: cur[k] - prev[k] for k in ('published', 'lost', *_COUNTERS)})
        verdict = judge_link(window, self._thresholds)

        def fmt(x):
            return '-' if x is None else format(x, 'g')

        values = [
            ('Connection', state),
            ('Port', self._port),
            ('Configured rate (Hz)', fmt(config and config.odr_hz)),
            ('Gyro full scale (deg/s)', fmt(config and config.gyro_fs_dps)),
            ('Accel full scale (g)', fmt(config and config.accel_fs_g)),
            ('Sample rate (Hz)', f'{window.rate_hz:.1f}' if state == 'streaming' else '0.0'),
            ('Samples published', s['published']),
            ('Samples lost', s['lost']),
            ('Samples flagged lost by the board', link.get('samples_flagged_lost', 0)),
            # Equal consecutive counters are removed by the decoder, older ones by the tracker.
            ('Duplicates dropped', s['duplicates'] + link.get('duplicates', 0)),
            ('Samples dropped while inactive', s['discarded']),
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

    def destroy_node(self):
        """Stop and join the reader thread (it closes the port), then destroy the node."""
        self._stop_reader()
        return super().destroy_node()


def main(args=None):
    """
    Run ``lsm6dso32_driver`` (console script); parameters via ``--ros-args -p``/``--params-file``.

    Parameters
    ----------
    args : list of str or None
        Command line (None: ``sys.argv``).

    Returns
    -------
    int
        0 on Ctrl-C or external shutdown; 2 with one line on stderr for a bad parameter or an
        unknown ROS argument.

    """
    return run_node(Lsm6dso32Driver, args, prog=NODE_NAME)


if __name__ == '__main__':
    sys.exit(main())
