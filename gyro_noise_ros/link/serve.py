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
The emulated board's transports: a pseudo-terminal or a loopback TCP port, and SD log files.

The pure board model (:mod:`gyro_noise_ros.link.emulator`) has no I/O and no threads; this
module serves it (``portenta_emulator``, ``docs/portenta_link.md``). :func:`serve` answers
CONFIGURE commands with ACK/NAK, streams SAMPLES frames paced in real time at the ODR
(:attr:`ServeOptions.speed` times faster) and keeps sampling while no host is connected (the
samples the host could not receive come out as a counter gap flagged FLAG_SAMPLE_LOST on the
next sample sent, like the real board whose USB buffer is full); scripted unplugs and a bounded
TX buffer model a real USB link. :func:`write_sd_logs` writes SD log files as fast as it can
instead. No argparse here: the command line builds :class:`ServeOptions` and the board.
"""

from collections.abc import Callable
import dataclasses
from dataclasses import dataclass
import json
import os
from pathlib import Path
import pty
import select
import signal
import socket
import termios
import time
import tty
from typing import Any, BinaryIO

import numpy as np

from .emulator import BoardModel, FaultInjector, truth_records
from .protocol import encode_samples
from .sdlog import FILE_NAME_FORMAT, FILE_NAME_RE, SdLogWriter
from ..errors import Interrupted, LinkError, ParameterError
from ..outputs import staged_output

#: Bytes the emulated board buffers for a slow host before it drops samples (firmware ring in
#: SDRAM):
#: 1 MiB is ~6 s of data at 6.66 kHz, so a loaded test machine does not lose samples.
TX_BUFFER_BYTES = 1 << 20


@dataclass(frozen=True)
class ServeOptions:
    """
    How the board is served.

    Attributes
    ----------
    tcp : str or None
        ``HOST:PORT`` of a loopback TCP port (port 0: any); None: a pseudo-terminal.
    link : str or None
        Pseudo-terminal only: keep a symlink at this path to the pty (survives replug).
    speed : float
        Pacing: this many times faster than real time.
    batch : int
        Samples per SAMPLES frame.
    tx_buffer_bytes : int
        Bytes buffered for a slow host before samples are dropped.
    total : int or None
        Samples to produce before stopping (None: until stopped).
    disconnect_after : int or None
        Unplug once after this many samples sent on the first connection.
    disconnect_every_s : float or None
        Unplug after every this many seconds connected.
    unplug_s : float
        How long an unplug lasts (s).

    """

    tcp: str | None = None
    link: str | None = None
    speed: float = 1.0
    batch: int = 1
    tx_buffer_bytes: int = TX_BUFFER_BYTES
    total: int | None = None
    disconnect_after: int | None = None
    disconnect_every_s: float | None = None
    unplug_s: float = 0.0


class Stopper:
    """
    A signal handler that asks the loops to stop (SIGINT, SIGTERM) and remembers the signal.

    The serving loop ends its pass and returns; the SD and bag writers call :meth:`check` once
    per block and stop with :class:`~gyro_noise_ros.errors.Interrupted` (their staged output is
    then removed).
    """

    def __init__(self) -> None:
        self.stop = False
        self.signum: int | None = None

    def __call__(self, signum: int, frame: Any) -> None:
        self.stop = True
        self.signum = signum

    def check(self) -> None:
        """Raise :class:`~gyro_noise_ros.errors.Interrupted` once a stop was asked."""
        if self.stop:
            raise Interrupted(self.signum or signal.SIGINT)


class Counters:
    """Traffic counters of one emulator run (its closing statistics line)."""

    def __init__(self) -> None:
        self.samples_generated = 0
        self.samples_sent = 0
        self.samples_unsent = 0   # generated while no host was connected or the TX buffer was full
        self.samples_overflowed = 0  # of those, lost to a full TX buffer (the host read too late)
        self.frames_sent = 0
        self.connections = 0
        self.disconnects = 0
        self.commands = 0


def stats_line(counters: Counters, faults: FaultInjector, board: BoardModel) -> str:
    """
    Return the statistics of a run as one JSON line (counters, injected faults, configuration).

    Parameters
    ----------
    counters : Counters
        Traffic counters.
    faults : FaultInjector
        The fault injector (its counts).
    board : BoardModel
        The board (next sequence number and configuration).

    Returns
    -------
    str

    """
    data = dict(vars(counters))
    data.update(dataclasses.asdict(faults.counts))
    data['seq_next'] = board.seq
    data['odr_hz'] = board.odr_hz
    data['gyro_fs_dps'] = board.gyro_fs_dps
    data['accel_fs_g'] = board.accel_fs_g
    return json.dumps(data, sort_keys=True)


def total_samples(samples: int | None, duration_s: float | None,
                  odr_hz: float) -> int | None:
    """
    Return the samples a run produces: the smaller of ``samples`` and ``duration_s`` at the ODR.

    Parameters
    ----------
    samples : int or None
        Sample count limit.
    duration_s : float or None
        Duration limit (s).
    odr_hz : float
        Output data rate (Hz).

    Returns
    -------
    int or None
        None when neither limit is given.

    """
    limits = []
    if samples is not None:
        limits.append(samples)
    if duration_s is not None:
        limits.append(int(round(duration_s * odr_hz)))
    return min(limits) if limits else None


def produce(board: BoardModel, faults: FaultInjector, counters: Counters, n: int,
            truth_fh: BinaryIO | None) -> np.ndarray:
    """
    Lose the injected FIFO overrun out of ``n`` samples, produce the rest, log the truth.

    Parameters
    ----------
    board : BoardModel
        The board.
    faults : FaultInjector
        The fault injector (``overrun(n)`` draws the samples lost inside the sensor).
    counters : Counters
        Traffic counters; ``samples_generated`` counts produced and overrun samples.
    n : int
        Samples due.
    truth_fh : file or None
        Ground-truth log (flushed, so a reader sees whole records).

    Returns
    -------
    numpy.ndarray
        The produced samples (``n`` minus the overrun).

    """
    lost_in_sensor = faults.overrun(n)
    board.sensor_overrun(lost_in_sensor)
    counters.samples_generated += lost_in_sensor
    n -= lost_in_sensor
    samples = board.next_samples(n)
    counters.samples_generated += n
    if truth_fh is not None:
        assert board.last_truth is not None  # next_samples left it
        truth_fh.write(truth_records(board.last_truth).tobytes())
        truth_fh.flush()
    return samples


@dataclass(frozen=True)
class SdOptions:
    """
    How SD log files are written.

    Attributes
    ----------
    out_dir : str
        Folder of the log files (created).
    total : int
        Samples to write.
    sequence_id : int
        Sequence id in the file headers.
    max_file_bytes : int
        Size at which a new file is started.
    batch : int
        Samples per SAMPLES frame.
    rtc_unix_s : int
        RTC time in the headers (0: none).
    corrupt : bool
        Corrupt frames as the fault injector draws.
    overruns : bool
        FIFO overruns are injected (then the samples go frame by frame).
    overwrite : bool
        ``out_dir`` was allowed to hold files (``--overwrite``): this sequence's old files there
        are replaced, all of them (a sequence half old, half new would not import).

    """

    out_dir: str
    total: int
    sequence_id: int
    max_file_bytes: int
    batch: int
    rtc_unix_s: int = 0
    corrupt: bool = False
    overruns: bool = False
    overwrite: bool = False


def write_sd_logs(board: BoardModel, faults: FaultInjector, counters: Counters,
                  truth_fh: BinaryIO | None, options: SdOptions,
                  stopper: Stopper | None = None) -> list[str]:
    """
    Write the board's samples as SD log files, as fast as possible; return their paths.

    The files are staged (:func:`~gyro_noise_ros.outputs.staged_output`) and appear in
    ``options.out_dir`` together when the last one is complete: an interrupted or failed run
    leaves none under a final name.

    Parameters
    ----------
    board : BoardModel
        The board.
    faults : FaultInjector
        Drops, corruption and overruns.
    counters : Counters
        Traffic counters.
    truth_fh : file or None
        Ground-truth log.
    options : SdOptions
        Where and how.
    stopper : Stopper, optional
        Checked once per block (SIGINT, SIGTERM).

    Returns
    -------
    list of str

    """
    corrupt = faults.corrupt if options.corrupt else None
    with staged_output(options.out_dir, parameter='out_dir') as stage:
        with SdLogWriter(stage, sequence_id=options.sequence_id, odr_hz=board.odr_hz,
                         gyro_fs_dps=board.gyro_fs_dps, accel_fs_g=board.accel_fs_g,
                         max_file_bytes=options.max_file_bytes, batch=options.batch,
                         rtc_unix_s=options.rtc_unix_s, corrupt=corrupt) as writer:
            # overruns are drawn at most once per chunk: go frame by frame when they are injected
            batch = options.batch
            chunk = batch if options.overruns else batch * max(1, 65536 // batch)
            while counters.samples_generated < options.total:
                if stopper is not None:
                    stopper.check()
                samples = produce(board, faults, counters,
                                  min(chunk, options.total - counters.samples_generated),
                                  truth_fh)
                kept = faults.drop(samples)
                writer.write_samples(kept)
                counters.samples_sent += kept.size
        names = [os.path.basename(path) for path in writer.paths]
        if options.overwrite:
            pattern = FILE_NAME_FORMAT.format(sequence=options.sequence_id, index=0)[:5] + '*'
            for old in Path(options.out_dir).glob(pattern):
                if FILE_NAME_RE.match(old.name) and old.name not in names:
                    old.unlink()
    return [os.path.join(options.out_dir, name) for name in names]


class PtyPort:
    """
    A pseudo-terminal 'USB port'.

    Unplug closes it, replug creates a new one (and moves the symlink).
    """

    def __init__(self, link: str | None = None) -> None:
        self.link = link
        self.fd: int | None = None
        self.path = ''  # the pty's device, set by plug()
        self._poll: select.poll | None = None
        self.plug()

    def plug(self) -> None:
        master, slave = pty.openpty()
        # raw: no echo, no line discipline, 8 bit clean, before any client can open it
        tty.setraw(slave)
        self.path = os.ttyname(slave)
        os.close(slave)
        os.set_blocking(master, False)
        self.fd = master
        self._poll = select.poll()
        self._poll.register(master, select.POLLIN | select.POLLOUT)
        if self.link:
            tmp = f'{self.link}.tmp{os.getpid()}'
            if os.path.lexists(tmp):
                os.unlink(tmp)
            os.symlink(self.path, tmp)
            os.replace(tmp, self.link)

    def unplug(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if self.link and os.path.lexists(self.link):
            os.unlink(self.link)

    @property
    def name(self) -> str:
        return self.link or self.path

    def connected(self) -> bool:
        if self.fd is None or self._poll is None:  # both set by plug()
            return False
        events = self._poll.poll(0)
        return not any(ev & select.POLLHUP for _, ev in events)

    def read(self) -> bytes:
        if self.fd is None:
            return b''  # unplugged (the loop reads only a connected port)
        try:
            return os.read(self.fd, 4096)
        except (BlockingIOError, InterruptedError):
            return b''
        except OSError:
            return b''  # EIO: no client

    def write(self, data: bytes) -> int:
        if self.fd is None:
            return -1  # unplugged (the loop writes only to a connected port)
        try:
            return os.write(self.fd, data)
        except (BlockingIOError, InterruptedError):
            return 0
        except OSError:
            return -1

    def drop_client(self) -> None:
        """Do nothing: a pty cannot refuse a client; a disconnect is an unplug."""

    def discard_pending(self) -> None:
        """Forget bytes the departed client did not read, so the next one starts clean."""
        if self.fd is not None:
            try:
                termios.tcflush(self.fd, termios.TCIOFLUSH)
            except OSError:
                pass

    def close(self) -> None:
        self.unplug()


class TcpPort:
    """
    A loopback TCP 'port' serving one client at a time.

    Unplug drops the client and refuses others.
    """

    def __init__(self, spec: str) -> None:
        host, _, port_text = spec.rpartition(':')
        try:
            port = int(port_text)
        except ValueError as err:
            raise ParameterError(f'{{tcp}} must be HOST:PORT, got {spec!r}',
                                 parameters=('tcp',)) from err
        host = host or '127.0.0.1'
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.listener.bind((host, port))
        except OSError as err:
            self.listener.close()
            raise LinkError(f'cannot listen on {{tcp}} {spec!r}: {err}',
                            parameters=('tcp',)) from err
        self.listener.listen(4)
        self.listener.setblocking(False)
        self.client: socket.socket | None = None
        self.plugged = True
        self.name = f'socket://{host}:{self.listener.getsockname()[1]}'

    @property
    def fd(self) -> int | None:
        return self.client.fileno() if self.client is not None else None

    def plug(self) -> None:
        self.plugged = True

    def unplug(self) -> None:
        self.drop_client()
        self.plugged = False

    def drop_client(self) -> None:
        if self.client is not None:
            try:
                self.client.close()
            except OSError:
                pass
            self.client = None

    def discard_pending(self) -> None:
        """Nothing to do: a TCP connection's buffers go with it."""

    def poll_accept(self) -> bool:
        try:
            conn, _ = self.listener.accept()
        except (BlockingIOError, InterruptedError):
            return False
        except OSError:
            return False
        if not self.plugged or self.client is not None:
            conn.close()
            return False
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.client = conn
        return True

    def connected(self) -> bool:
        return self.client is not None

    def read(self) -> bytes:
        if self.client is None:
            return b''
        try:
            data = self.client.recv(4096)
        except (BlockingIOError, InterruptedError):
            return b''
        except OSError:
            self.drop_client()
            return b''
        if not data:
            self.drop_client()  # orderly close by the host
        return data

    def write(self, data: bytes) -> int:
        if self.client is None:
            return -1
        try:
            return self.client.send(data)
        except (BlockingIOError, InterruptedError):
            return 0
        except OSError:
            self.drop_client()
            return -1

    def close(self) -> None:
        self.drop_client()
        self.listener.close()


class _Link:
    """
    The state of one serving loop: the port, the pacing, the connection and the TX buffer.

    Each pass of :func:`serve` calls the steps in order: :meth:`track_connection`,
    :meth:`host_to_board`, :meth:`sample`, :meth:`board_to_host`, :meth:`scripted_unplug`,
    :meth:`wait`.
    """

    def __init__(self, board: BoardModel, faults: FaultInjector, options: ServeOptions,
                 counters: Counters, truth_fh: BinaryIO | None,
                 port: PtyPort | TcpPort) -> None:
        self.board, self.faults, self.options = board, faults, options
        self.counters, self.truth_fh, self.port = counters, truth_fh, port
        self.outbuf = bytearray()
        # pacing segment (restarts at an ODR change)
        self.seg_t0, self.seg_n0 = time.monotonic(), 0
        self.paced_odr = board.odr_hz
        self.period = 1.0 / (board.odr_hz * options.speed)
        self.was_connected = False
        self.connected_since: float | None = None
        self.sent_this_connection = 0
        self.disconnect_after = options.disconnect_after
        self.unplugged_until: float | None = None

    def track_connection(self, now: float) -> bool:
        """Replug when due, accept a TCP client, count (dis)connections; return connected."""
        port, counters = self.port, self.counters
        if self.unplugged_until is not None and now >= self.unplugged_until:
            port.plug()
            self.unplugged_until = None
        if isinstance(port, TcpPort) and self.unplugged_until is None and port.client is None:
            port.poll_accept()
        connected = self.unplugged_until is None and port.connected()
        if connected and not self.was_connected:
            counters.connections += 1
            self.connected_since = now
            self.sent_this_connection = 0
            self.outbuf.clear()
        if self.was_connected and not connected:
            counters.disconnects += 1
            self.outbuf.clear()
            port.discard_pending()
        self.was_connected = connected
        return connected

    def host_to_board(self, now: float) -> bool:
        """Hand the host's bytes to the board, queue its replies; return still connected."""
        data = self.port.read()
        connected = self.port.connected()
        if data:
            board = self.board
            reply = board.handle_bytes(data)
            self.counters.commands = board.command_stats.commands
            if reply:
                self.outbuf += reply  # acks are never dropped
                if board.odr_hz != self.paced_odr:
                    self.paced_odr = board.odr_hz
                    self.seg_t0, self.seg_n0 = now, self.counters.samples_generated
                    self.period = 1.0 / (board.odr_hz * self.options.speed)
        return connected

    def sample(self, now: float, connected: bool) -> None:
        """Produce the samples due; frame them into the TX buffer, or count them lost."""
        counters, faults, batch = self.counters, self.faults, self.options.batch
        due = self.seg_n0 + int((now - self.seg_t0) / self.period)
        if self.options.total is not None:
            due = min(due, self.options.total)
        n = due - counters.samples_generated
        if n <= 0:
            return
        samples = produce(self.board, faults, counters, n, self.truth_fh)
        if not connected:
            faults.note_lost(n, carry_flags=int(np.bitwise_or.reduce(samples['flags'])))
            counters.samples_unsent += n
            return
        kept = faults.drop(samples)
        for start in range(0, kept.size, batch):
            frame = encode_samples(kept[start:start + batch])
            if len(self.outbuf) + len(frame) > self.options.tx_buffer_bytes:
                # buffer full: this frame and the rest of the batch are lost, the next is flagged
                faults.note_lost(kept.size - start,
                                 carry_flags=int(np.bitwise_or.reduce(kept['flags'][start:])))
                counters.samples_unsent += kept.size - start
                counters.samples_overflowed += kept.size - start
                break
            self.outbuf += faults.corrupt(frame)
            counters.samples_sent += min(batch, kept.size - start)
            self.sent_this_connection += min(batch, kept.size - start)
            counters.frames_sent += 1

    def board_to_host(self) -> None:
        """Write what the port takes of the TX buffer."""
        written = self.port.write(bytes(self.outbuf[:65536]))
        if written > 0:
            del self.outbuf[:written]

    def scripted_unplug(self, now: float) -> None:
        """Unplug after ``disconnect_after`` samples or every ``disconnect_every_s``."""
        options = self.options
        unplug = False
        if self.disconnect_after is not None and (self.sent_this_connection
                                                  >= self.disconnect_after):
            unplug, self.disconnect_after = True, None
        # connected_since is set at the first connection; this runs only while connected
        if (options.disconnect_every_s and self.connected_since is not None
                and now - self.connected_since >= options.disconnect_every_s):
            unplug = True
        if unplug:
            self.port.unplug()
            self.unplugged_until = now + options.unplug_s
            self.counters.disconnects += 1
            self.was_connected = False
            self.outbuf.clear()

    def wait(self, connected: bool) -> None:
        """Sleep until the next frame is due or the host speaks."""
        port = self.port
        wait = max(0.001, min(0.02, self.seg_t0 + (self.counters.samples_generated - self.seg_n0
                                                   + self.options.batch)
                              * self.period - time.monotonic()))
        rlist: list[int | socket.socket] = (
            [port.fd] if (connected and port.fd is not None) else [])
        if isinstance(port, TcpPort) and port.client is None:
            rlist.append(port.listener)
        wlist = [port.fd] if (connected and self.outbuf and port.fd is not None) else []
        try:
            select.select(rlist, wlist, [], wait)
        except (OSError, ValueError):
            time.sleep(wait)


def serve(board: BoardModel, faults: FaultInjector, options: ServeOptions, *,
          counters: Counters, stopper: Stopper, truth_fh: BinaryIO | None = None,
          warm: BoardModel | None = None, on_port: Callable[[str], None] | None = None) -> int:
    """
    Serve the board on a pseudo-terminal or TCP port until stopped or ``options.total`` is sent.

    Parameters
    ----------
    board : BoardModel
        The board.
    faults : FaultInjector
        Drops, corruption, overruns.
    options : ServeOptions
        Port, pacing, limits and scripted unplugs.
    counters : Counters, keyword-only
        Traffic counters (updated as the loop runs).
    stopper : Stopper, keyword-only
        Ends the loop when set (a signal handler).
    truth_fh : file, optional, keyword-only
        Ground-truth log.
    warm : BoardModel, optional, keyword-only
        A twin of the board whose first frame is drawn before the pacing clock starts, so that
        compiling the numba kernels does not come out as a burst.
    on_port : callable, optional, keyword-only
        Called once with the port's name (the pty path or its symlink, or
        ``socket://HOST:PORT``) when it is open (the emulator prints it).

    Returns
    -------
    int
        Exit status 0.

    """
    if warm is not None:
        warm.next_samples(options.batch)
    port = TcpPort(options.tcp) if options.tcp else PtyPort(options.link)
    if on_port is not None:
        on_port(port.name)
    link = _Link(board, faults, options, counters, truth_fh, port)
    try:
        while not stopper.stop:
            now = time.monotonic()
            connected = link.track_connection(now)
            if connected:
                connected = link.host_to_board(now)
            link.sample(now, connected)
            if connected and link.outbuf:
                link.board_to_host()
            if connected:
                link.scripted_unplug(now)
            if (options.total is not None and counters.samples_generated >= options.total
                    and not link.outbuf):
                break
            link.wait(connected)
    finally:
        port.close()
    return 0
