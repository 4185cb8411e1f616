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
The board link in one thread: open, configure, read, reconnect (pure, no ROS).

:class:`LinkReader` owns the port. It opens it (a device path or a pyserial URL), runs the
CONFIGURE handshake (:func:`.session.handshake`), then reads and decodes until the link fails or
it is stopped, hands every decoded batch to a callback, and after any failure (read/write error,
NAK, no ACK, ``data_timeout_s`` of silence) closes the port and retries every
``reconnect_period_s``. It never gives up; its state and counters are for diagnostics. The driver
node adapts it to ROS (``gyro_noise_ros.nodes.driver``).
"""

from collections.abc import Callable, Mapping
import os
import select
import threading
import time
from typing import Any

import numpy as np
import serial
from serial import serialposix
from serial.urlhandler import protocol_socket

from .protocol import Decoder
from .session import frame_interval_s, handshake, LinkConfig
from ..errors import LinkError

_READ_SIZE = 1 << 16

#: Port classes whose ``read`` is ``select`` and a read of the descriptor, with no buffer of
#: their own (a serial device on POSIX, ``socket://``): :func:`read_available` reads the
#: descriptor itself. Any other port (``loop://``, ``rfc2217://``, ``spy://``) goes through its
#: ``read``.
_UNBUFFERED = (serialposix.Serial, protocol_socket.Serial)


def _selectable(ser: Any) -> int | None:
    """Return the port's file descriptor for ``select``, or None (a port that has none)."""
    try:
        fd = ser.fileno()
    except (AttributeError, NotImplementedError, OSError, ValueError, serial.SerialException):
        return None
    return fd if isinstance(fd, int) and fd >= 0 else None


def read_available(ser: Any, fd: int | None, wait_s: float) -> bytes:
    """
    Return the bytes that have arrived, waiting at most ``wait_s`` for the first one.

    pyserial's ``read(n)`` with a timeout returns only when ``n`` bytes or the whole timeout have
    passed: a 10 ms timeout delayed every frame by up to 10 ms. With the port's timeout at 0 and
    ``select`` on its descriptor the bytes are handed on as they arrive. A port without a
    descriptor keeps pyserial's timed read (its ``timeout`` is then ``wait_s``).

    Parameters
    ----------
    ser : serial.Serial
        Open port; ``timeout`` 0 when ``fd`` is given.
    fd : int or None
        Its descriptor (:func:`_selectable`).
    wait_s : float
        Longest wait (s).

    Returns
    -------
    bytes
        Possibly empty.

    """
    if fd is None:
        return bytes(ser.read(_READ_SIZE))
    ready, _, _ = select.select([fd], [], [], wait_s)
    if not ready:
        return b''
    if type(ser) in _UNBUFFERED:
        # What their read does after its own select calls (two more per read), minus them.
        try:
            data = os.read(fd, _READ_SIZE)
        except BlockingIOError:  # readiness without data (pyserial ignores EAGAIN too)
            return b''
    else:
        data = ser.read(_READ_SIZE)
    if not data:
        # Readable but nothing to read: the peer closed (socket) or the device vanished.
        raise serial.SerialException('the port reports data but returned none (disconnected?)')
    return bytes(data)


class LinkReader:
    """
    Read the board in a thread, reconnecting forever.

    Parameters
    ----------
    port : str
        Device path or pyserial URL (already validated, see :func:`.port.validate_port`).
    settings : callable
        ``settings() -> dict`` with ``baud_rate``, ``read_period_s``, ``ack_timeout_s``,
        ``data_timeout_s``, ``reconnect_period_s`` (s) and the requested ``odr_hz``,
        ``gyro_full_scale_dps``, ``accel_full_scale_g``; read at every connection.
    on_samples : callable
        ``on_samples(samples, host_ns, config)`` for every decoded batch (reader thread).
    now_ns : callable
        Clock that stamps the arrival of the bytes (ns).
    on_error : callable
        ``on_error(message, first)``: a failure; ``first`` is False while it repeats.
    on_streaming : callable
        ``on_streaming(config)`` once per successful handshake.

    """

    def __init__(self, port: str, settings: Callable[[], Mapping[str, Any]],
                 on_samples: Callable[[np.ndarray, int, LinkConfig], object], *,
                 now_ns: Callable[[], int] = time.time_ns,
                 on_error: Callable[[str, bool], object] = lambda message, first: None,
                 on_streaming: Callable[[LinkConfig], object] = lambda config: None) -> None:
        self.port = port
        self._settings = settings
        self._on_samples = on_samples
        self._now_ns = now_ns
        self._on_error = on_error
        self._on_streaming = on_streaming
        # One decoder for the reader's life: reset_stream() at each connection drops a partial
        # frame but keeps the counters, so diagnostics add up over unplugs.
        self._decoder = Decoder()
        self._lock = threading.Lock()
        self._state = 'stopped'
        self._last_error = 'none'
        self._last_logged_error: str | None = None
        self._config: LinkConfig | None = None
        self._connections = 0
        self._streaming_since: float | None = None
        self._last_sample_monotonic: float | None = None
        self._link_stats: dict[str, int] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Start the reader thread (no-op if running)."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name='lsm6dso32_reader', daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """
        Stop and join the reader thread; it closes the port.

        Parameters
        ----------
        timeout_s : float
            Longest wait for the thread (s).

        """
        self._stop.set()
        if self._thread is not None and self._thread.is_alive():
            self._thread.join(timeout=timeout_s)
        self._thread = None
        self._set_state('stopped')

    def snapshot(self) -> dict[str, Any]:
        """
        Copy the link's state and counters.

        Returns
        -------
        dict
            ``state`` (``stopped``, ``connecting``, ``configuring``, ``streaming``,
            ``disconnected``), ``last_error``, ``config`` (the acknowledged
            :class:`.session.LinkConfig` or None), ``connections``, ``streaming_since`` and
            ``last_sample_monotonic`` (``time.monotonic()`` values or None) and ``link``, the
            decoder's counters summed over all connections.

        """
        with self._lock:
            return {'state': self._state, 'last_error': self._last_error, 'config': self._config,
                    'connections': self._connections, 'streaming_since': self._streaming_since,
                    'last_sample_monotonic': self._last_sample_monotonic,
                    'link': dict(self._link_stats)}

    def _loop(self) -> None:
        while not self._stop.is_set():
            self._set_state('connecting')
            s = self._settings()
            try:
                ser = serial.serial_for_url(self.port, baudrate=s['baud_rate'],
                                            timeout=s['read_period_s'],
                                            write_timeout=s['ack_timeout_s'])
            except (serial.SerialException, OSError, ValueError) as err:
                self._failed(f'cannot open {self.port}: {err}')
                self._stop.wait(s['reconnect_period_s'])
                continue
            self._decoder.reset_stream()
            try:
                self._session(ser, s)
            except (serial.SerialException, OSError, LinkError) as err:
                self._failed(str(err) or type(err).__name__)
            except Exception as err:  # noqa: BLE001 - the reader must outlive any single failure
                if self._stop.is_set():
                    break
                self._failed(f'internal error: {err!r}')
            finally:
                try:
                    ser.close()
                except Exception:  # noqa: BLE001 - a vanished port may fail to close; it is gone
                    pass
                with self._lock:
                    self._link_stats = self._decoder.counters()
            if not self._stop.is_set():
                self._stop.wait(s['reconnect_period_s'])

    def _session(self, ser: Any, s: Mapping[str, Any]) -> None:
        self._set_state('configuring')
        with self._lock:
            self._connections += 1
            command_id = self._connections
        done = handshake(ser, self._decoder, command_id=command_id, odr_hz=s['odr_hz'],
                         gyro_fs_dps=s['gyro_full_scale_dps'], accel_fs_g=s['accel_full_scale_g'],
                         ack_timeout_s=s['ack_timeout_s'], stop=self._stop, now_ns=self._now_ns)
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
        self._on_streaming(config)
        if len(after):
            self._on_samples(after, host_ns, config)
        last_data = now
        silence_s = max(s['data_timeout_s'], frame_interval_s(config))
        fd = _selectable(ser)
        if fd is not None:
            ser.timeout = 0  # reads return what has arrived; select() waits
        while not self._stop.is_set():
            data = read_available(ser, fd, s['read_period_s'])
            now = time.monotonic()
            if not data:
                if now - last_data > silence_s:
                    raise LinkError(f'no data for {silence_s:g} s')
                continue
            last_data = now
            host_ns = self._now_ns()
            result = self._decoder.feed(data)
            if len(result.samples):
                self._on_samples(result.samples, host_ns, config)
            with self._lock:
                self._link_stats = self._decoder.counters()
                if len(result.samples):
                    self._last_sample_monotonic = now

    def _set_state(self, state: str) -> None:
        with self._lock:
            self._state = state
            if state != 'streaming':
                self._streaming_since = None

    def _failed(self, reason: str) -> None:
        with self._lock:
            first = self._last_logged_error != reason
            self._last_logged_error = reason
            self._last_error = reason
            self._state = 'disconnected'
            self._streaming_since = None
        self._on_error(reason, first)
