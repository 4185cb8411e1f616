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
Soak: the whole live chain at 6.66 kHz for ``--minutes`` (30 by default), with faults injected.

What a lab's 12-hour acquisition runs, in a private ROS graph (:mod:`gyro_noise_ros.rosgraph`)::

    portenta_emulator --tcp E  <->  fault proxy (this process, port P)  <->  lsm6dso32_driver
        -> noise_analyzer, imu_compensator (a poly3 model fitted first), gyro_noise_record

(``--chain``: the driver and the compensator as one ``imu_chain`` process, the same checks.)

Every consumer subscribes ``reliable:=true`` and the driver keeps 9 s of history
(``qos_depth:=60000``): the loss-free lab configuration (docs/diagnostics.md, QoS). The emulator
ramps the die temperature (20 degC/h) with a gyro sensitivity, so the compensator subtracts a
changing offset through its temperature hold.

Faults, at 1/4, 1/2 and 3/4 of the run:

1. **unplug**: the proxy drops both TCP connections and refuses the driver for ``--unplug-s``; the
   board keeps sampling. Bound: the driver's ``Samples lost`` grows by at most
   ``rate x (unplug_s + reconnect_period_s + 1 s)`` (the board's samples while nobody reads, the
   driver's retry period, connect and configure).
2. **recorder killed**: SIGKILL, restarted at once into a second bag. Both bags must be readable
   (the killed one as it is: the package's reader rolls its hot sqlite3 journal back in a copy
   and says so). Bound: the messages lost are the ones not yet committed at the kill (at most
   ``flush_period_s`` of them, checked from the stamps) plus the ones published before the new
   recorder subscribed (its restart time, measured).
3. **garbage**: ``--garbage-bytes`` seeded random bytes into the board-to-driver stream. Bound: one
   frame (``--batch`` 16 samples), the one the burst lands in (a false header in random bytes needs
   sync, version, type and a length to match: about 2**-34 per byte).

Checks: the chain kept up with the board (no sample lost to the board's full transmit buffer);
messages published by the driver = received by the analyzer = received and published by the
compensator = recorded (both bags) + the recorder's bound, with no message dropped in transport
(per-publisher sequence gaps); held offsets only where the compensator's input stopped (the unplug,
the end of the stream, the killed recorder's lease expiring: at most one decimation period, a frame
and a drain period each; ``soak.json`` keeps the compensator's counters every ``--rss-period-s``
and says when held offsets happened); with ``temperature_sync: latest`` (the compensator's
default) the age of the offset it applies within one temperature period and a frame (+10 ms)
away from the faults and the stream's first ``--settle-s`` (the driver's clock-settle burst;
every compensator status is read; ``soak.json`` ``offset_ages``); each
fault's loss within its bound; every process's RSS
sampled every ``--rss-period-s`` and its growth, plus two standard errors, under ``--rss-slope-
limit-mb-h`` (10 MB/h: 120 MB over 12 h); the analyzer's RSS less the Allan storage it states on
``/diagnostics`` (its accumulators grow by design as log2 of the record, 0.5 MiB per doubling and
axis; both slopes are printed and kept in ``soak.json``). The growth is a least-squares slope
shared by the stretches between the faults, each with its own level, after a warm-up (the first
fifth of the process's life or its first minute) and leaving out a minute after each fault (half
the faults' spacing in a run under 8 minutes): a fault may cost a one-time step (the driver's
reliable history filling for a killed reader until its lease expires), a leak grows between the
faults too. One table is printed; exit code 0 when every check passed, 1 otherwise. The logs,
bags and ``soak.json`` stay in ``--out``.

Run: ``.venv/bin/python bench/bench_soak.py`` (30 min), ``--minutes 3`` to validate it.
"""

import argparse
import json
import os
from pathlib import Path
import re
import select
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

from gyro_noise_ros.nodes import _dds_profile
import numpy as np

ODR_HZ = 6667.0  # the default --odr-hz: the LSM6DSO32's highest rate
BATCH = 16  # samples per frame (the emulator's --batch default)
RECONNECT_PERIOD_S = 1.0  # the driver's default
FLUSH_PERIOD_S = 0.5  # the recorder's default flush_period_s (sqlite3 commit)
TEMP_RAMP_C_PER_H = 20.0
SENSITIVITY_DPS_PER_C = '0.02,-0.02,0.01'
DRIVER_QOS_DEPTH = 60000
#: The compensator's counters kept every --rss-period-s (soak.json 'compensator_series'): when
#: a held offset happened, against the faults' times.
SERIES_KEYS = ('Messages received', 'Messages published', 'Messages waiting for a temperature',
               'Messages compensated with a held offset')
TEMPERATURE_DECIMATION = 128  # the driver's default: one temperature per 128 samples
COMPENSATOR_DRAIN_S = 0.05  # the timer drain of temperature_sync interpolate runs (the bound)
#: The compensator's age of the offset it applies (temperature_sync latest, the default): at most
#: one temperature period after the newest temperature message, unless imu/temperature stalls.
OFFSET_AGE_KEY = 'Newest sample past its offset (ms)'
#: Slack over one temperature period and a frame (ms): the frames of one read, a late wake-up.
OFFSET_AGE_SLACK_MS = 10.0
#: The lease the package's nodes announce (nodes/_dds_profile.py): a killed recorder is
#: dropped by the driver's writers after it (Fast DDS's default, 20 s, stalled the stream).
LEASE_S = _dds_profile.LEASE_S
#: Smallest share of the board's rate the compensator must receive in every FLOW_WINDOW_S
#: (outside the unplug): a live stream that stalls (a dead reader slowing the writers) fails.
FLOW_SHARE, FLOW_WINDOW_S = 0.7, 10.0


def free_port():
    """Return a loopback TCP port that was free a moment ago."""
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def rss_mb(pid):
    """Return the resident set size of a process (MB), None when it is gone."""
    try:
        with open(f'/proc/{pid}/status') as fh:
            for line in fh:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def cpu_s(pid):
    """Return utime + stime of a process (s), None when it is gone."""
    try:
        with open(f'/proc/{pid}/stat') as fh:
            fields = fh.read().rsplit(')', 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


class FaultProxy(threading.Thread):
    """
    TCP relay between the board (emulator) and the driver that can unplug and inject garbage.

    Parameters
    ----------
    upstream_port : int
        The emulator's loopback port.
    seed : int
        Seed of the garbage bytes.

    """

    def __init__(self, upstream_port, seed):
        super().__init__(daemon=True)
        self.upstream_port = upstream_port
        self.rng = np.random.default_rng(seed)
        self.listener = socket.socket()
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(('127.0.0.1', 0))
        self.listener.listen(4)
        self.port = self.listener.getsockname()[1]
        self.client = self.board = None
        self.refuse_until = 0.0
        self.connections = 0
        self.bytes_down = 0
        self.garbage_sent = 0
        self._garbage = b''
        self._unplug = None
        self._stopping = False
        self._lock = threading.Lock()

    def unplug(self, seconds):
        """Drop both connections now and refuse the driver for ``seconds``."""
        with self._lock:
            self._unplug = seconds

    def inject(self, nbytes):
        """Send ``nbytes`` random bytes to the driver before the board's next bytes."""
        with self._lock:
            self._garbage = self.rng.integers(0, 256, nbytes, dtype=np.uint8).tobytes()

    def stop(self):
        """Stop relaying and close everything."""
        self._stopping = True
        self.join(5)

    def _drop(self):
        for s in (self.client, self.board):
            if s is not None:
                try:
                    s.close()
                except OSError:
                    pass
        self.client = self.board = None
        self._down, self._up = bytearray(), bytearray()

    def _accept(self):
        conn, _ = self.listener.accept()
        if time.monotonic() < self.refuse_until or self.client is not None:
            conn.close()
            return
        try:
            board = socket.create_connection(('127.0.0.1', self.upstream_port), timeout=1.0)
        except OSError:
            conn.close()  # the board is not listening yet: the driver retries
            return
        for s in (conn, board):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            s.setblocking(False)
        self.client, self.board = conn, board
        self.connections += 1

    def _pump(self, src, buf, limit):
        """Read what ``src`` has into ``buf`` (up to ``limit`` bytes queued); False: closed."""
        if len(buf) >= limit:
            return True
        try:
            data = src.recv(65536)
        except (BlockingIOError, InterruptedError):
            return True
        except OSError:
            return False
        if not data:
            return False
        buf += data
        return True

    @staticmethod
    def _flush(dst, buf):
        """Write what ``dst`` takes of ``buf``; False: closed."""
        try:
            sent = dst.send(buf)
        except (BlockingIOError, InterruptedError):
            return True
        except OSError:
            return False
        del buf[:sent]
        return True

    def run(self):
        # Non-blocking both ways, so an unplug or a burst takes effect at once even while the
        # driver reads slowly; at most 1 MB waits for the driver (the board's own TX buffer size:
        # beyond it the board is not read, its buffer fills and it flags the samples lost).
        self._down, self._up = bytearray(), bytearray()
        try:
            while not self._stopping:
                with self._lock:
                    unplug, self._unplug = self._unplug, None
                    garbage, self._garbage = self._garbage, b''
                if unplug is not None:
                    self._drop()
                    self.refuse_until = time.monotonic() + unplug
                if garbage and self.client is not None:
                    self._down += garbage  # lands between two reads of the board's stream
                    self.garbage_sent += len(garbage)
                elif garbage:
                    with self._lock:
                        self._garbage = garbage  # no link right now: at the next connection
                # A full buffer stops reading its source (no busy loop; backpressure).
                links = [s for s, b in ((self.client, self._up), (self.board, self._down))
                         if s is not None and len(b) < 1 << 20]
                wlist = [s for s, b in ((self.client, self._down), (self.board, self._up))
                         if s is not None and b]
                ready, writable, _ = select.select([self.listener, *links], wlist, [], 0.05)
                if self.listener in ready:
                    self._accept()
                    continue
                ok = True
                if self.board in ready:
                    before = len(self._down)
                    ok = self._pump(self.board, self._down, 1 << 20)
                    self.bytes_down += len(self._down) - before
                if ok and self.client in ready:
                    ok = self._pump(self.client, self._up, 1 << 20)
                if ok and self.client in writable:
                    ok = self._flush(self.client, self._down)
                if ok and self.board in writable:
                    ok = self._flush(self.board, self._up)
                if not ok:
                    self._drop()
        finally:
            self._drop()
            self.listener.close()


def _proxy_main(upstream_port, seed):
    """
    Run the proxy in its own process (``--proxy PORT SEED``), away from the rclpy threads.

    Prints its port, then reads ``unplug SECONDS``, ``garbage BYTES`` and ``stop`` lines on stdin.
    """
    proxy = FaultProxy(upstream_port, seed)
    proxy.start()
    print(proxy.port, flush=True)
    for line in sys.stdin:
        word, _, value = line.strip().partition(' ')
        if word == 'unplug':
            proxy.unplug(float(value))
        elif word == 'garbage':
            proxy.inject(int(value))
        elif word == 'stop':
            break
    proxy.stop()
    return 0


class ProxyProcess:
    """The :class:`FaultProxy` in a child process, driven by lines on its stdin."""

    def __init__(self, upstream_port, seed, log):
        self.proc = subprocess.Popen([sys.executable, os.path.abspath(__file__), '--proxy',
                                      str(upstream_port), str(seed)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=log, text=True)
        self.port = int(self.proc.stdout.readline())

    def send(self, line):
        self.proc.stdin.write(line + '\n')
        self.proc.stdin.flush()

    def unplug(self, seconds):
        """Drop both connections and refuse the driver for ``seconds``."""
        self.send(f'unplug {seconds}')

    def inject(self, nbytes):
        """Send ``nbytes`` random bytes to the driver."""
        self.send(f'garbage {nbytes}')

    def stop(self):
        """Stop the proxy process."""
        if self.proc.poll() is None:
            try:
                self.send('stop')
                self.proc.wait(10)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait(5)


class Diagnostics:
    """The latest value set of every status on ``/diagnostics``, spun in a thread."""

    def __init__(self):
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('soak_diagnostics', context=self.context)
        self.latest = {}
        self.offset_ages = []  # (monotonic s, the compensator's newest offset age in ms)
        self._lock = threading.Lock()
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._on, 100)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _on(self, msg):
        with self._lock:
            for s in msg.status:
                values = {kv.key: kv.value for kv in s.values}
                self.latest[s.name] = (values, s.level[0], s.message, time.monotonic())
                if s.name == 'imu_compensator: compensation' and OFFSET_AGE_KEY in values:
                    # Every status, not the latest only: the age is the maximum of its period.
                    try:
                        age = float(values[OFFSET_AGE_KEY])
                    except ValueError:
                        continue
                    self.offset_ages.append((time.monotonic(), age))

    def _spin(self):
        while self._rclpy.ok(context=self.context):
            try:
                self.executor.spin_once(timeout_sec=0.1)
            except Exception:  # noqa: BLE001 - shutting down
                break

    def values(self, name):
        """Return the latest key/value dict of a status ({} before any)."""
        with self._lock:
            return dict(self.latest.get(name, ({},))[0])

    def close(self):
        """Stop spinning and shut the context down."""
        self._rclpy.try_shutdown(context=self.context)
        self._thread.join(5)


class Chain:
    """The processes of the run; their logs in ``out/logs``; RSS and CPU sampled."""

    def __init__(self, out):
        self.logs = out / 'logs'
        self.logs.mkdir(parents=True, exist_ok=True)
        self.procs = {}     # name -> Popen
        self.rss = {}       # name -> [(t, MB)]
        self.cpu = {}       # name -> [first (t, s), last (t, s)]

    def start(self, name, argv, stdout=None):
        log = open(self.logs / f'{name}.log', 'w')
        proc = subprocess.Popen([sys.executable, *argv], stdout=stdout or log, stderr=log,
                                text=True)
        self.procs[name] = proc
        self.rss[name] = []
        return proc

    def log_text(self, name):
        return (self.logs / f'{name}.log').read_text(errors='replace')

    def wait_for_log(self, name, pattern, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if re.search(pattern, self.log_text(name)):
                return
            if self.procs[name].poll() is not None:
                break
            time.sleep(0.2)
        raise RuntimeError(f'{name} never logged {pattern!r}: {self.log_text(name)[-1500:]}')

    def sample(self, t):
        for name, proc in self.procs.items():
            if proc.poll() is None:
                mb, c = rss_mb(proc.pid), cpu_s(proc.pid)
                if mb is not None:
                    self.rss[name].append((t, mb))
                if c is not None:
                    span = self.cpu.setdefault(name, [(t, c), (t, c)])
                    span[1] = (t, c)

    def stop(self, name, sig=signal.SIGINT, timeout_s=60.0):
        proc = self.procs[name]
        if proc.poll() is None:
            proc.send_signal(sig)
            try:
                proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)
        return proc.returncode

    def stop_all(self):
        for name in list(self.procs)[::-1]:
            self.stop(name, timeout_s=30.0)


def _train_model(out, chain):
    """Write a training bag with the emulator, fit poly3 on it; return model.json's path."""
    bag = out / 'train_bag'
    argv = ['-m', 'gyro_noise_ros.cli.emulator', '--write-bag', str(bag), '--duration-s', '40',
            '--seed', '7', '--accel-fs-g', '32', '--temp-c', '24',
            '--temp-drift-c-per-h', '2700',  # 24 -> 54 degC in 40 s: the soak's span and more
            '--temp-sensitivity-dps-per-c', SENSITIVITY_DPS_PER_C,
            '--bag-temperature-decimation', '128']
    done = subprocess.run([sys.executable, *argv], capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise RuntimeError(f'training bag: {done.stderr[-1500:]}')
    fit = out / 'model'
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.thermal', 'fit', str(bag),
                           '--method', 'poly3', '--no-figures', '--quiet', '--out', str(fit)],
                          capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise RuntimeError(f'thermal fit: {done.stderr[-1500:]}')
    shutil.rmtree(bag, ignore_errors=True)
    return fit / 'model.json'


def _count(values, key):
    try:
        return int(str(values.get(key, '')).split()[0])
    except (ValueError, IndexError):
        return None


def _held(diag):
    """Return the compensator's cumulative count of samples released with a held offset."""
    return _count(diag.values('imu_compensator: compensation'),
                  'Messages compensated with a held offset')


def _per_publisher(text):
    """Parse 'name N (d dropped); ...' into {name: (N, d)}."""
    return {m.group(1): (int(m.group(2)), int(m.group(3)))
            for m in re.finditer(r'(\S+) (\d+) \((\d+) dropped\)', text or '')}


def _bag_stamps(path):
    """
    Read every Imu stamp of a bag with the package's reader; return (stamps, recovery note).

    A killed bag (no metadata.yaml, a hot sqlite3 journal) is read as it is: the reader rolls the
    journal back in a copy, never in the user's file, and says so in its note.
    """
    from gyro_noise_ros.bag import ImuBagReader

    with ImuBagReader(path) as reader:
        stamps = [b.stamp_ns for b in reader.iter_batches(100000)]
        note = reader.recovery
    return (np.concatenate(stamps) if stamps else np.zeros(0, np.int64)), note


def _slope_mb_h(series, breaks=(), skip_fraction=0.2, skip_s=60.0, settle_s=60.0):
    """
    Least-squares RSS slope (MB/h) and its standard error: a leak, told from a step at a fault.

    The warm-up is the first fifth of the series or its first minute, whichever is longer: the
    imports, the JIT, the allocator's arenas and the driver's 60,000-message history filling.
    A fault may cost a process a one-time step (the driver's reliable history filling for a
    killed reader until its lease expires, a consumer's queue absorbing a backlog); a leak grows
    between the faults too. So the series is cut at each time in ``breaks`` (the faults), the
    ``settle_s`` after each is left out, and one line per segment is fitted with its own level and
    a slope shared by all segments: that slope is the growth while nothing happens.
    """
    if len(series) < 5:
        return float('nan'), float('nan')
    t = np.array([p[0] for p in series])
    mb = np.array([p[1] for p in series])
    keep = t >= t[0] + max(skip_fraction * (t[-1] - t[0]), skip_s)
    segment = np.zeros(t.size, dtype=int)
    for b in sorted(breaks):
        keep &= ~((t >= b) & (t < b + settle_s))
        segment += t >= b
    t, mb, segment = t[keep] / 3600.0, mb[keep], segment[keep]
    labels = [s for s in np.unique(segment) if np.count_nonzero(segment == s) >= 2]
    inside = np.isin(segment, labels)
    t, mb, segment = t[inside], mb[inside], segment[inside]
    if t.size < len(labels) + 3:
        return float('nan'), float('nan')
    # Centre t within each segment: the slope column is then orthogonal to the levels.
    tc = t.copy()
    for s in labels:
        tc[segment == s] -= t[segment == s].mean()
    design = np.column_stack([*(segment == s for s in labels), tc]).astype(float)
    coef, *_ = np.linalg.lstsq(design, mb, rcond=None)
    resid = mb - design @ coef
    dof = t.size - len(labels) - 1
    se = np.sqrt(resid @ resid / dof / (tc @ tc))
    return float(coef[-1]), float(se)


def run(args):
    """Run the soak; return (passed, report dict)."""
    from gyro_noise_ros.rosgraph import lease_domain

    lease = lease_domain(candidates=None if args.domain_id is None else [args.domain_id])
    lease.export()
    os.environ['PYTHONUNBUFFERED'] = '1'
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix='soak_'))
    out.mkdir(parents=True, exist_ok=True)
    print(f'soak: {args.minutes:g} min at {args.odr_hz:g} Hz; ROS_DOMAIN_ID={lease.domain_id} '
          f'(localhost only); output in {out}', flush=True)
    chain = Chain(out)
    report = {'minutes': args.minutes, 'odr_hz': args.odr_hz, 'chain': args.chain,
              'domain_id': lease.domain_id, 'faults': [],
              'cores': os.cpu_count(), 'load_start': os.getloadavg()}
    diag = proxy = None
    try:
        model = _train_model(out, chain)
        board_port = free_port()
        # Its own process: in this one the rclpy listener's threads would take turns with it.
        proxy = ProxyProcess(board_port, args.seed, open(chain.logs / 'proxy.log', 'w'))
        reliable = ['-p', 'reliable:=true']
        chain.start('noise_analyzer', ['-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args',
                                       *reliable])
        wait = ([] if args.max_temperature_wait_s is None else
                ['-p', f'max_temperature_wait_s:={float(args.max_temperature_wait_s)!r}'])
        if args.temperature_sync is not None:
            wait += ['-p', f'temperature_sync:={args.temperature_sync}']
        compensation = ['-p', f'thermal_model_file:={model}', *reliable, *wait]
        link = ['-p', f'port:=socket://127.0.0.1:{proxy.port}', '-p',
                f'qos_depth:={args.driver_qos_depth}', '-p', f'odr_hz:={float(args.odr_hz)!r}']
        # --chain: one imu_chain process stands for both (started where the driver is)
        driver_name, comp_name = (('imu_chain',) * 2 if args.chain
                                  else ('lsm6dso32_driver', 'imu_compensator'))
        if not args.chain:
            chain.start(comp_name, ['-m', 'gyro_noise_ros.nodes.compensator', '--ros-args',
                                    *compensation])
        bags = [out / 'bag_1', out / 'bag_2']
        for bag in bags:
            shutil.rmtree(bag, ignore_errors=True)
        chain.start('recorder_1', ['-m', 'gyro_noise_ros.nodes.recorder', '--ros-args', '-p',
                                   f'output:={bags[0]}', *reliable])
        if args.chain:
            chain.start(driver_name, ['-m', 'gyro_noise_ros.nodes.chain', '--ros-args', *link,
                                      *compensation])
        else:
            chain.start(driver_name, ['-m', 'gyro_noise_ros.nodes.driver', '--ros-args', *link])
        chain.wait_for_log('noise_analyzer', r'analysing ', 180)
        chain.wait_for_log(comp_name, r'compensating ', 180)
        chain.wait_for_log('recorder_1', r'recording ', 180)
        diag = Diagnostics()
        deadline = time.monotonic() + 120
        while not (diag.values('lsm6dso32_driver: link') and diag.values(
                'imu_compensator: compensation') and diag.values('noise_analyzer: axis x')):
            dead = [n for n, p in chain.procs.items() if p.poll() is not None]
            if dead:
                raise RuntimeError(f'{dead[0]} exited: {chain.log_text(dead[0])[-1500:]}')
            if time.monotonic() > deadline:
                raise RuntimeError('no /diagnostics from the nodes after 120 s (discovery?)')
            time.sleep(0.2)
        chain.start('portenta_emulator', [
            '-m', 'gyro_noise_ros.cli.emulator', '--tcp', f'127.0.0.1:{board_port}', '--seed',
            str(args.seed), '--accel-fs-g', '32', '--temp-c', '25', '--temp-drift-c-per-h',
            str(TEMP_RAMP_C_PER_H), '--temp-sensitivity-dps-per-c', SENSITIVITY_DPS_PER_C,
            '--stats-out', str(out / 'emulator_stats.json')], stdout=subprocess.DEVNULL)
        chain.wait_for_log(driver_name, r'streaming from', 180)
        t0 = time.monotonic()
        duration = 60.0 * args.minutes
        print(f'soak: streaming; faults at {duration / 4:.0f}, {duration / 2:.0f} and '
              f'{3 * duration / 4:.0f} s', flush=True)
        schedule = [(duration / 4, 'unplug'), (duration / 2, 'recorder killed'),
                    (3 * duration / 4, 'garbage')]
        pending = []  # faults whose loss is read once the link has settled
        series = report['compensator_series'] = []  # [t, *SERIES_KEYS] every rss period
        report['analyzer_allan_mb'] = []  # [t, MB] the analyzer's Allan storage, 3 axes
        next_rss = t0
        while True:
            now = time.monotonic()
            if now >= next_rss:
                chain.sample(now - t0)
                allan = _allan_storage_mb(diag)
                if allan is not None:  # beside the analyzer's RSS sample of the same time
                    report['analyzer_allan_mb'].append([now - t0, allan])
                next_rss += args.rss_period_s
                comp = diag.values('imu_compensator: compensation')
                series.append([round(now - t0, 1), *(_count(comp, key) for key in SERIES_KEYS)])
            if schedule and now - t0 >= schedule[0][0]:
                _, kind = schedule.pop(0)
                link = diag.values('lsm6dso32_driver: link')
                fault = {'kind': kind, 'at_s': round(now - t0, 1),
                         'lost_before': _count(link, 'Samples lost'),
                         'discarded_before': _count(link, 'Bytes discarded')}
                if kind == 'unplug':
                    proxy.unplug(args.unplug_s)
                    fault['bound'] = int(args.odr_hz * (args.unplug_s + RECONNECT_PERIOD_S + 1.0))
                elif kind == 'garbage':
                    proxy.inject(args.garbage_bytes)
                    fault['bound'] = BATCH
                    fault['bytes'] = args.garbage_bytes
                else:
                    fault['kill_wall_ns'] = time.time_ns()
                    chain.procs['recorder_1'].kill()
                    chain.procs['recorder_1'].wait(10)
                    chain.start('recorder_2', ['-m', 'gyro_noise_ros.nodes.recorder',
                                               '--ros-args', '-p', f'output:={bags[1]}',
                                               *reliable])
                report['faults'].append(fault)
                pending.append((now + args.settle_s, fault))
                print(f'soak: {kind} at {now - t0:.0f} s', flush=True)
            for due, fault in list(pending):
                if now >= due:
                    link = diag.values('lsm6dso32_driver: link')
                    fault['lost_after'] = _count(link, 'Samples lost')
                    fault['discarded_after'] = _count(link, 'Bytes discarded')
                    pending.remove((due, fault))
            if now - t0 >= duration and not pending:
                break
            time.sleep(0.05)
        report['offset_ages'] = [[round(t - t0, 1), age] for t, age in diag.offset_ages
                                 if t >= t0]
        # The end: the board stops; everything published must reach every consumer. The
        # compensator's last samples, newer than the last temperature, are released with a held
        # offset after max_temperature_wait_s: counted apart.
        report['held_before_end'] = _held(diag)
        chain.stop('portenta_emulator')
        report['emulator'] = json.loads((out / 'emulator_stats.json').read_text())
        counts = _settle(diag)
        report.update(counts)
        chain.sample(time.monotonic() - t0)
        rc2 = chain.stop('recorder_2')
        summary = next((ln for ln in chain.log_text('recorder_2').splitlines()
                        if ln.startswith('gyro_noise_record: received')), '')
        report['recorder_2_exit'] = rc2
        report['recorder_2_summary'] = summary
        for name in dict.fromkeys((comp_name, 'noise_analyzer', driver_name)):
            chain.stop(name)
        report['load_end'] = os.getloadavg()
        report['logs'] = str(chain.logs)
        report['bags'] = [str(b) for b in bags]
        return _judge(args, chain, report, bags)
    finally:
        if diag is not None:
            diag.close()
        if proxy is not None:
            proxy.stop()
        chain.stop_all()
        lease.release()


def _allan_storage_mb(diag):
    """Return the analyzer's Allan storage over its three axes (MiB), None until all report it."""
    try:
        return sum(float(diag.values(f'noise_analyzer: axis {a}')['Allan storage (MiB)'])
                   for a in 'xyz')
    except (KeyError, ValueError):
        return None


def _beyond_allan(series, allan):
    """Return the analyzer's RSS less its Allan storage (by design log2 of the record), by time."""
    held = {round(t, 3): mb for t, mb in allan}
    return [(t, mb - held[round(t, 3)]) for t, mb in series if round(t, 3) in held]


def _settle(diag, timeout_s=120.0):
    """After the board stopped: wait until the counts stop moving; return them."""
    last, stable_since = None, time.monotonic()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        link = diag.values('lsm6dso32_driver: link')
        comp = diag.values('imu_compensator: compensation')
        axis = diag.values('noise_analyzer: axis x')
        analyzer = _per_publisher(axis.get('Messages per publisher'))
        counts = {
            'published': _count(link, 'Samples published'),
            'driver_lost': _count(link, 'Samples lost'),
            'crc_errors': _count(link, 'CRC errors'),
            'bytes_discarded': _count(link, 'Bytes discarded'),
            'analyzer_received': sum(n for n, _ in analyzer.values()),
            'analyzer_dropped': sum(d for _, d in analyzer.values()),
            'analyzer_publishers': len(analyzer),
            'analyzer_chunks': _count(axis, 'Chunks analysed'),
            'analyzer_skipped': _count(axis, 'Chunks skipped'),
            'compensator_received': _count(comp, 'Messages received'),
            'compensator_published': _count(comp, 'Messages published'),
            'compensator_dropped': _count(comp, 'Messages dropped before the node'),
            'compensator_late': _count(comp, 'Messages compensated with a held offset'),
            'compensator_first_dropped': _count(
                comp, 'Messages dropped waiting for the first temperature'),
            'compensator_longest_wait_s': comp.get('Longest wait for a temperature (s)'),
            'compensator_waiting': _count(comp, 'Messages waiting for a temperature'),
        }
        published = counts['published'] or 0
        # Caught up: every consumer received everything, and the compensator holds nothing back
        # (its last samples, newer than the last temperature, wait max_temperature_wait_s).
        caught_up = (published and published == counts['analyzer_received'] == counts[
            'compensator_received'] and counts['compensator_waiting'] == 0)
        # A driver status older than what a consumer already reports is stale (a starved host
        # publishes diagnostics late): wait for it.
        fresh = published >= max(counts['analyzer_received'] or 0,
                                 counts['compensator_received'] or 0)
        if counts != last:
            last, stable_since = counts, time.monotonic()
        # Everything received, or nothing moved for 20 s; the checks then say which count fell
        # short.
        elif published and fresh and (caught_up and time.monotonic() - stable_since > 3.0
                                      or time.monotonic() - stable_since > 20.0):
            return counts
        time.sleep(0.5)
    return last or {}


def _check_offset_age(args, report, check, slack_s):
    """Check that the offset applied is at most a temperature period old away from the faults."""
    bound_ms = 1e3 * (TEMPERATURE_DECIMATION + BATCH) / args.odr_hz + OFFSET_AGE_SLACK_MS
    worst = {'elsewhere': 0.0, 'start-up': 0.0,
             **{f['kind']: 0.0 for f in report['faults']}}
    for t, age in report.get('offset_ages', []):
        if t > args.minutes * 60.0:
            continue  # the end of the stream
        fault = next((f for f in report['faults'] if f['at_s'] < t <= f['at_s'] + args.settle_s
                      + (LEASE_S if f['kind'] == 'recorder killed' else 0.0) + slack_s), None)
        # The stream's first settle_s is a transient like a fault's: the driver publishes the
        # samples it held while its clock settled (clock_settle_s) in one burst.
        key = fault['kind'] if fault else 'start-up' if t <= args.settle_s else 'elsewhere'
        worst[key] = max(worst[key], age)
    report['offset_age_ms'] = worst
    check('offset age within a temperature period', worst['elsewhere'] <= bound_ms,
          f"largest age of the applied offset {worst['elsewhere']:.1f} ms away from the faults "
          f"(bound {bound_ms:.1f} ms); in the first {args.settle_s:g} s {worst['start-up']:.0f} "
          'ms; at the faults '
          + ', '.join(f"{f['kind']} {worst[f['kind']]:.0f} ms" for f in report['faults']))


def _check_flow(args, report, check):
    """Check that the compensator received the stream at its rate in each window but the unplug."""
    series = [(p[0], p[1]) for p in report.get('compensator_series', []) if p[1] is not None]
    quiet = [(f['at_s'], f['at_s'] + args.unplug_s + RECONNECT_PERIOD_S + args.settle_s)
             for f in report['faults'] if f['kind'] == 'unplug']
    worst = None  # (share of the rate, window start)
    for i, (t0, n0) in enumerate(series):
        if t0 < args.settle_s:
            continue  # the start: the driver's clock settling, the first matches
        end = next(((t, n) for t, n in series[i + 1:] if t >= t0 + FLOW_WINDOW_S), None)
        if end is None or any(a < end[0] and t0 < b for a, b in quiet):
            continue
        share = (end[1] - n0) / (args.odr_hz * (end[0] - t0))
        if worst is None or share < worst[0]:
            worst = (share, t0)
    report['flow_worst'] = worst
    check('the stream kept flowing', worst is not None and worst[0] >= FLOW_SHARE,
          'no window to judge' if worst is None else
          f"the compensator received at least {100 * worst[0]:.0f} % of the board's rate in "
          f'every {FLOW_WINDOW_S:g}-s window (lowest from {worst[1]:.0f} s; bound '
          f'{100 * FLOW_SHARE:.0f} %; the unplug left out)')


def _judge(args, chain, report, bags):
    checks = []

    def check(name, ok, detail):
        checks.append((name, bool(ok), detail))

    stamps = []
    for bag in bags:
        try:
            got, note = _bag_stamps(bag)
            stamps.append(got)
            if note:
                report.setdefault('recovery', {})[bag.name] = note
        except Exception as err:  # noqa: BLE001 - an unreadable bag is a failed check
            stamps.append(None)
            check(f'{bag.name} readable', False, f'{type(err).__name__}: {err}')
    if all(s is not None for s in stamps):
        check('both bags readable', True, f'{stamps[0].size} + {stamps[1].size} Imu messages')
    recorded = sum(s.size for s in stamps if s is not None)
    published = report.get('published') or 0
    period_ns = 1e9 / args.odr_hz
    kill = next(f for f in report['faults'] if f['kind'] == 'recorder killed')
    if all(s is not None and s.size for s in stamps):
        gap = int(round((stamps[1][0] - stamps[0][-1]) / period_ns)) - 1
        uncommitted_s = (kill['kill_wall_ns'] - stamps[0][-1]) / 1e9
        down_s = (stamps[1][0] - kill['kill_wall_ns']) / 1e9
        kill.update(lost=gap, uncommitted_s=round(uncommitted_s, 2), restart_s=round(down_s, 2),
                    bound=int(args.odr_hz * (FLUSH_PERIOD_S + 0.5 + max(down_s, 0.0))))
        # The stamps say how much was lost around the kill; the counts must agree with them to a
        # few samples (stamp jitter of the driver's device-to-host clock mapping).
        check('published = recorded + lost at the kill', abs(published - recorded - gap) <= 3,
              f'{published} = {recorded} + {gap} (difference {published - recorded - gap})')
        check('recorder kill: uncommitted within flush_period_s',
              uncommitted_s <= FLUSH_PERIOD_S + 0.5,
              f'last committed stamp {uncommitted_s:.2f} s before the kill (bound '
              f'{FLUSH_PERIOD_S:g} s commit period + 0.5 s), new recorder receiving after '
              f'{down_s:.2f} s')
    emulator = report.get('emulator', {})
    # Samples the board could not send because nobody read its 1 MB transmit buffer in time (the
    # chain did not keep up with real time: every other number of the run is then suspect). The
    # board's other unsent samples were made while no host was connected: before the driver's
    # first connection and during the unplug.
    overflowed = emulator.get('samples_overflowed')
    check('the chain kept up with the board', overflowed == 0,
          f'{overflowed} board samples lost to a full transmit buffer; '
          f"{emulator.get('samples_unsent')} of {emulator.get('samples_generated')} not sent in "
          'all (the rest while no host was connected: start-up and the unplug)')
    check('published = analysed', report.get('analyzer_received') == published,
          f"{report.get('analyzer_received')} received by noise_analyzer "
          f"({report.get('analyzer_publishers')} publisher)")
    check('published = compensated', report.get('compensator_received') == published
          and report.get('compensator_published') == published
          - (report.get('compensator_first_dropped') or 0),
          f"{report.get('compensator_received')} received, "
          f"{report.get('compensator_published')} published by imu_compensator")
    recorder_dropped = re.search(r'(\d+) dropped in transport',
                                 report.get('recorder_2_summary', ''))
    check('nothing dropped in transport', report.get('analyzer_dropped') == 0
          and report.get('compensator_dropped') == 0
          and recorder_dropped is not None and recorder_dropped[1] == '0',
          f"analyzer {report.get('analyzer_dropped')}, compensator "
          f"{report.get('compensator_dropped')}, recorder_2 "
          f"{recorder_dropped[1] if recorder_dropped else '(no summary line)'}")
    # A held offset is right only where the compensator's input stopped for longer than
    # max_temperature_wait_s: at the unplug, at the end of the stream, and when the killed
    # recorder's DDS lease expires (Fast DDS keeps a killed reader matched for its participant
    # lease, LEASE_S as the package's nodes announce it; with Fast DDS's default 20 s the
    # driver's reliable writers slowed every other reader for 25-60 s). Each stop holds at most
    # the samples newer than the last temperature the node took: one decimation period, a frame
    # and one drain period of Imu taken after it. Anywhere else it means a stalled temperature
    # stream alone. Attributed by time: the compensator's counters every --rss-period-s.
    held_total = report.get('compensator_late') or 0
    held_end = held_total - (report.get('held_before_end') or 0)
    rises, prev = [], 0
    for point in report.get('compensator_series', []):
        held = point[1 + SERIES_KEYS.index('Messages compensated with a held offset')]
        if held is not None and held > prev:
            rises.append([point[0], held - prev])
            prev = held
    slack_s = args.rss_period_s + 1.0  # the series' period and the diagnostics period
    by_fault = {}
    for t, n in rises:
        if t > args.minutes * 60.0:
            continue  # the end: counted as held_end
        fault = next((f for f in report['faults'] if f['at_s'] < t <= f['at_s'] + args.settle_s
                      + (LEASE_S if f['kind'] == 'recorder killed' else 0.0) + slack_s), None)
        key = fault['kind'] if fault else 'elsewhere'
        by_fault[key] = by_fault.get(key, 0) + n
    held_elsewhere = by_fault.pop('elsewhere', 0)
    report['held'] = {**{f['kind']: by_fault.get(f['kind'], 0) for f in report['faults']},
                      'end': held_end, 'elsewhere': held_elsewhere, 'rises_at_s': rises}
    per_stop = TEMPERATURE_DECIMATION + BATCH + int(np.ceil(COMPENSATOR_DRAIN_S * args.odr_hz))
    worst = max([held_end, *by_fault.values()])
    check('held offsets only where the input stopped',
          held_elsewhere == 0 and worst <= per_stop,
          f'{held_total} held-offset samples: '
          + ', '.join(f"{by_fault.get(f['kind'], 0)} at the {f['kind']}"
                      for f in report['faults'])
          + f', {held_end} at the end, {held_elsewhere} elsewhere (bound {per_stop} per stop, 0 '
          f"elsewhere); longest on-time wait {report.get('compensator_longest_wait_s')} s"
          + ''.join(f'; +{n} by {t:.0f} s' for t, n in rises[:5]))
    _check_offset_age(args, report, check, slack_s)
    _check_flow(args, report, check)
    fault_lost = 0
    for fault in report['faults']:
        if fault['kind'] == 'recorder killed':
            continue
        lost = (fault.get('lost_after') or 0) - (fault.get('lost_before') or 0)
        fault['lost'] = lost
        fault_lost += lost
        extra, reached = '', True
        if fault['kind'] == 'garbage':
            # The evidence that the burst reached the decoder: the bytes it skipped.
            # A driver lagging behind the board reads the burst late (the proxy queues it behind
            # the board's bytes): the count at the end of the run is the evidence then, and any
            # loss it caused after the settle counts against "no loss outside the faults".
            before = fault.get('discarded_before') or 0
            skipped = (fault.get('discarded_after') or 0) - before
            by_end = (report.get('bytes_discarded') or 0) - before
            extra = f', bytes discarded by the decoder +{skipped}'
            if by_end != skipped:
                extra += f' within the settle, +{by_end} by the end'
            reached = skipped > 0 or by_end > 0
        check(f"{fault['kind']}: samples lost within bound", lost <= fault['bound'] and reached,
              f"{lost} lost (bound {fault['bound']}){extra}")
    total_lost = report.get('driver_lost') or 0
    check('no loss outside the faults', total_lost - fault_lost == 0,
          f'{total_lost} lost in all, {fault_lost} at the faults')
    report['rss'] = {}
    report['rss_series_mb'] = {name: [[round(t, 1), round(mb, 1)] for t, mb in series]
                               for name, series in chain.rss.items()}
    # A minute after each fault is left out of the fit (half the spacing of a short run's faults).
    breaks = [f['at_s'] for f in report['faults']]
    after_fault_s = min(60.0, 60.0 * args.minutes / 8)
    for name, series in chain.rss.items():
        slope, se = _slope_mb_h(series, breaks, settle_s=after_fault_s)
        span = chain.cpu.get(name)
        cpu = (100.0 * (span[1][1] - span[0][1]) / (span[1][0] - span[0][0])
               if span and span[1][0] > span[0][0] else float('nan'))
        report['rss'][name] = {
            'first_mb': series[0][1] if series else None,
            'last_mb': series[-1][1] if series else None,
            'samples': len(series), 'slope_mb_h': slope, 'slope_se_mb_h': se, 'cpu_pct': cpu}
        judged, what = (slope, se), ''
        if name == 'noise_analyzer':
            # Its Allan accumulators grow by design as log2 of the record (0.5 MiB per doubling
            # and axis once their rows fill: 9 MB/h at 15 minutes, 0.1 at 12 h); the analyzer
            # states them ('Allan storage (MiB)'): a leak is growth beyond them.
            beyond = _beyond_allan(series, report.get('analyzer_allan_mb', []))
            judged = _slope_mb_h(beyond, breaks, settle_s=after_fault_s)
            report['rss'][name].update(beyond_allan_slope_mb_h=judged[0],
                                       beyond_allan_slope_se_mb_h=judged[1])
            what = (f' beyond its Allan storage; RSS itself {slope:+.1f} +/- {se:.1f}, the '
                    f'storage {report["analyzer_allan_mb"][-1][1]:.1f} MB at the end'
                    if beyond else '')
        if len(series) >= 5:
            # Flat means under the limit by two standard errors: a run too short or too noisy to
            # tell fails as inconclusive rather than passing by luck.
            limit = args.rss_slope_limit_mb_h
            g, g_se = judged
            check(f'{name}: RSS flat', 2.0 * g_se < limit and g + 2.0 * g_se < limit,
                  f'{g:+.1f} +/- {g_se:.1f} MB/h{what} (limit {limit:g}, slope + 2 SE)'
                  + (' inconclusive' if 2.0 * g_se >= limit else '')
                  if np.isfinite(g) else 'too few samples between the faults to fit')
    report['checks'] = [{'check': n, 'passed': ok, 'detail': d} for n, ok, d in checks]
    return all(ok for _, ok, _ in checks), report


def _print(report, passed):
    load = ', '.join(f'{report[k][0]:.1f}' for k in ('load_start', 'load_end') if k in report)
    # A starved chain (load well above the cores) fails the checks by lag, not by a fault: say so.
    minutes, odr, cores = report['minutes'], report['odr_hz'], report['cores']
    print(f'\n{minutes:g} min at {odr:g} Hz, {cores} cores, 1-min load average at the start and '
          f'the end: {load}')
    print('\nprocess             RSS first  RSS last  slope (MB/h)       CPU %  samples')
    for name, r in report['rss'].items():
        first = '-' if r['first_mb'] is None else f"{r['first_mb']:.0f}"
        last = '-' if r['last_mb'] is None else f"{r['last_mb']:.0f}"
        print(f"{name:18s} {first:>9s} {last:>9s}  {r['slope_mb_h']:+7.1f} +/- "
              f"{r['slope_se_mb_h']:5.1f}  {r['cpu_pct']:6.1f}  {r['samples']:7d}")
    analyzer = report['rss'].get('noise_analyzer', {})
    if 'beyond_allan_slope_mb_h' in analyzer:
        print('noise_analyzer beyond its Allan storage: '
              f"{analyzer['beyond_allan_slope_mb_h']:+.1f} +/- "
              f"{analyzer['beyond_allan_slope_se_mb_h']:.1f} MB/h")
    print('\nfault               at (s)   lost  bound')
    for f in report['faults']:
        print(f"{f['kind']:18s} {f['at_s']:7.0f} {f.get('lost', '-')!s:>6s} "
              f"{f.get('bound', '-')!s:>6s}")
    print('\ncheck                                          result  detail')
    for c in report['checks']:
        print(f"{c['check']:46s} {'pass' if c['passed'] else 'FAIL':6s}  {c['detail']}")
    print(f"\nsoak: {'every check passed' if passed else 'FAILED'}", flush=True)


def main(argv=None):
    """Run the soak; return 0 when every check passed, 1 otherwise."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=30.0, help='length of the run (min)')
    parser.add_argument('--out', help='directory for logs, bags, soak.json (default: a temp dir)')
    parser.add_argument('--odr-hz', type=float, default=ODR_HZ,
                        help='output data rate the driver requests (Hz; an LSM6DSO32 rate)')
    parser.add_argument('--seed', type=int, default=8, help='seed of the board and the garbage')
    parser.add_argument('--unplug-s', type=float, default=2.0, help='length of the unplug (s)')
    parser.add_argument('--garbage-bytes', type=int, default=4096, help='size of the burst')
    parser.add_argument('--rss-period-s', type=float, default=5.0, help='RSS sampling period')
    parser.add_argument('--settle-s', type=float, default=15.0,
                        help='wait after a fault before its loss is read (s)')
    parser.add_argument('--driver-qos-depth', type=int, default=DRIVER_QOS_DEPTH,
                        help="the driver's qos_depth (messages of reliable history)")
    parser.add_argument('--max-temperature-wait-s', type=float, default=None,
                        help="the compensator's max_temperature_wait_s (default: the node's)")
    parser.add_argument('--temperature-sync', choices=('latest', 'interpolate'),
                        help="the compensator's temperature_sync (default: the node's, latest)")
    parser.add_argument('--chain', action='store_true',
                        help='the driver and the compensator as one imu_chain process')
    parser.add_argument('--rss-slope-limit-mb-h', type=float, default=10.0,
                        help='largest RSS slope called flat (MB/h)')
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID to hold (checked free); default: any free one')
    parser.add_argument('--proxy', nargs=2, type=int, metavar=('PORT', 'SEED'),
                        help=argparse.SUPPRESS)  # internal: run the fault proxy process
    args = parser.parse_args(argv)
    if args.proxy:
        return _proxy_main(*args.proxy)
    if not args.minutes * 60 / 4 > args.settle_s:
        parser.error(f'--minutes {args.minutes:g}: faults must be more than --settle-s apart')
    print('command:', shlex.join([sys.executable, *sys.argv]), flush=True)
    try:
        passed, report = run(args)
    except (RuntimeError, OSError, subprocess.SubprocessError) as err:
        print(f'soak: error: {err}', file=sys.stderr, flush=True)
        return 1
    Path(report['logs']).parent.joinpath('soak.json').write_text(
        json.dumps(report, indent=1, default=str))
    _print(report, passed)
    return 0 if passed else 1


if __name__ == '__main__':
    sys.exit(main())
