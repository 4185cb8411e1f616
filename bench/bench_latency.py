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
Latency of the live chain at 6.66 kHz: header.stamp to a subscriber, per message, and CPU per node.

Budget (issue 31): ``imu/data_raw`` stamp -> a subscriber's callback p99 <= 3 ms, the compensator
adds p99 <= 1 ms, each node <= 20 % of one core; with ``--load 2`` (two busy loops beside the
chain) p99 <= 2x those.

The chain as README "Running it live" starts it, in a private ROS graph
(:func:`gyro_noise_ros.rosgraph.lease_domain`): ``portenta_emulator`` (real time, TCP loopback,
16-sample frames) -> ``lsm6dso32_driver`` -> ``imu_compensator`` (a full calibration and a causal
thermal model in (T, dT)). The probe is this process: raw subscriptions of ``imu/data_raw`` and
``imu/data_compensated`` (sensor-data QoS) drained by a thread that wakes on a wait set of its
own as messages arrive (:class:`gyro_noise_ros.nodes._waitset.WaitSetDrain`). Everything is on
the host's system clock (ROS time, Fast DDS's timestamps), so per message:

- ``stamp -> callback``: the probe's time after its wake-up minus header.stamp (the figure the
  budget is about; it includes the probe's own wake-up, stated separately);
- ``stamp -> DDS reception``: the subscriber's DDS reception timestamp minus header.stamp (no
  probe cost in it);
- its parts: ``stamp -> publish`` (the publisher's DDS source timestamp), itself the board's
  frame (a sample waits in the board's FIFO for the frame's newest, up to 15 periods, 2.25 ms, at
  16 samples a frame: the stamp of the newest sample of the driver's read minus the sample's) and
  the port and driver (that newest sample's stamp to the publication); ``DDS`` (reception minus
  source) and ``probe wake-up`` (callback minus reception: the probe's cost, not the chain's);
- ``compensator added``: a compensated message's reception minus the reception of the raw
  message with the same stamp (the compensator's input arrives when the probe's does).

CPU of each process from ``/proc/<pid>/stat`` over the window. ``--load N`` starts N busy loops
(``while True: pass``) at normal priority. Run: ``.venv/bin/python bench/bench_latency.py``;
``--load 2`` for the loaded row; ``--driver-param`` / ``--compensator-param name:=value`` to
compare settings side by side; ``--rt PRIO`` runs the chain under ``SCHED_FIFO`` (the nodes'
``realtime_priority``); ``--bare-relay`` puts a relay that only takes and republishes in the
compensator's place (the floor of a Python node there); ``--chain`` runs ``imu_chain`` instead of
the two nodes (one process: the driver hands each read to the compensator, no second DDS trip).
"""

import argparse
import json
import os
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_compensator import _COMPENSATOR, _param_args  # noqa: E402
from bench_driver import cpu_seconds, free_port, stop  # noqa: E402
import numpy as np  # noqa: E402

ODR = 6667.0
#: ``imu_chain`` with the compensator bench's thermal model (the same node code as
#: ``_COMPENSATOR``'s): the driver and the compensator in one process (``--chain``).
#: The CPU the compensator's part takes in the reader thread (thread time inside ``accept``) is
#: written every 0.2 s to the file given first (ns), so the window's share can be read apart.
_CHAIN = _COMPENSATOR.split('model = ')[0] + r"""
import os, threading, time
from gyro_noise_ros.nodes import chain
from gyro_noise_ros.nodes._params import running_together
spent = [0]
accept = chain.compensator.ImuCompensatorNode.accept
def timed_accept(self, temperatures, imu):
    start = time.thread_time_ns()
    accept(self, temperatures, imu)
    spent[0] += time.thread_time_ns() - start
chain.compensator.ImuCompensatorNode.accept = timed_accept
def report(path=sys.argv[1]):
    while True:
        with open(path + '.tmp', 'w') as f:
            f.write(str(spent[0]))
        os.replace(path + '.tmp', path)
        time.sleep(0.2)
threading.Thread(target=report, daemon=True).start()
model = Linear()
argv = sys.argv[2:]
with running_together((chain.driver.PARAMETERS, chain.compensator.PARAMETERS), argv):
    sys.exit(run_node(lambda: chain.build(thermal_model=model), argv, prog='bench_chain'))
"""
BUSY = 'while True: pass'
#: Publications this far apart (ns) belong to two reads of the driver (a frame is 2.4 ms).
BATCH_GAP_NS = 500_000

# A deliberately slow reader of imu/data_raw: one rclpy callback per message (the default
# executor), each busy for WORK_US, counting what it gets; prints the count on SIGINT.
_SLOW_READER = r"""
import signal, sys, time
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
work_s, reliable, depth = float(sys.argv[1]) * 1e-6, sys.argv[2] == 'reliable', int(sys.argv[3])
rclpy.init()
node = rclpy.create_node('slow_reader')
count = [0]
def on_msg(msg):
    count[0] += 1
    end = time.perf_counter() + work_s
    while time.perf_counter() < end:
        pass
qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE if reliable
                 else ReliabilityPolicy.BEST_EFFORT)
node.create_subscription(Imu, 'imu/data_raw', on_msg, qos)
try:
    rclpy.spin(node)
except (KeyboardInterrupt, ExternalShutdownException):
    pass
print(count[0], flush=True)
"""


# The floor of any Python node in the compensator's place: imu/data_raw taken as it arrives (the
# compensator's wait-set thread and RawTaker) and published unchanged on imu/data_compensated
# (reliable, the compensator's QoS): no decode, no calibration, no thermal model.
_BARE_RELAY = r"""
import sys
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
from gyro_noise_ros.nodes._publishers import RawTaker
from gyro_noise_ros.nodes._realtime import set_realtime_priority
from gyro_noise_ros.nodes._ros_common import PolledGroup, sensor_data_qos, unused_callback
from gyro_noise_ros.nodes._waitset import WaitSetDrain
rclpy.init()
set_realtime_priority(int(sys.argv[1]))
node = rclpy.create_node('bare_relay')
sub = node.create_subscription(Imu, 'imu/data_raw', unused_callback, sensor_data_qos(20000),
                               raw=True, callback_group=PolledGroup())
pub = node.create_publisher(Imu, 'imu/data_compensated', QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=20000, reliability=ReliabilityPolicy.RELIABLE))
taker = RawTaker(sub, Imu)
def relay():
    raws = taker.take(2000)[0]
    with pub.handle:
        for raw in raws:
            pub.handle.publish_raw(raw)
drain = WaitSetDrain(node.context, [sub], relay, timeout_s=0.05)
drain.start()
try:
    rclpy.spin(node)
except (KeyboardInterrupt, ExternalShutdownException):
    pass
drain.stop()
"""


class Probe:
    """Raw subscriptions drained by a wait-set thread; rows of stamp, source, reception, take."""

    def __init__(self, topics, reliable=False):
        import rclpy
        from sensor_msgs.msg import Imu

        from gyro_noise_ros.nodes._ros_common import PolledGroup, sensor_data_qos, unused_callback
        from gyro_noise_ros.nodes._waitset import WaitSetDrain

        self.rclpy, self.imu = rclpy, Imu
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('bench_latency_probe', context=self.context)
        group = PolledGroup()
        self.subs = {t: self.node.create_subscription(Imu, t, unused_callback,
                                                      sensor_data_qos(20000, reliable), raw=True,
                                                      callback_group=group) for t in topics}
        self.rows = {t: [] for t in topics}
        self.dds_missing = dict.fromkeys(topics, 0)
        self._last_seq = dict.fromkeys(topics)
        self.recording = False
        self._lock = threading.Lock()
        self.drain = WaitSetDrain(self.context, list(self.subs.values()), self._on_ready,
                                  timeout_s=0.1, name='latency_probe')
        self.drain.start()

    def _on_ready(self):
        now = time.time_ns()
        unpack = struct.unpack_from
        for topic, sub in self.subs.items():
            rows = self.rows[topic]
            last = self._last_seq[topic]
            with sub.handle:
                while True:
                    item = sub.handle.take_message(self.imu, True)
                    if item is None:
                        break
                    raw, info = item
                    sec, nsec = unpack('<iI', raw, 4)
                    seq = info.get('publication_sequence_number') or 0
                    if last is not None and seq > last + 1 and self.recording:
                        self.dds_missing[topic] += seq - last - 1
                    last = seq
                    if self.recording:
                        rows.append((sec * 1_000_000_000 + nsec, info['source_timestamp'],
                                     info['received_timestamp'], now))
            self._last_seq[topic] = last

    def arrays(self, topic):
        """Return the recorded rows of a topic as an (n, 4) int64 array."""
        rows = self.rows[topic]
        return np.array(rows, dtype=np.int64).reshape(-1, 4)

    def close(self):
        self.drain.stop()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def _rt(prio):
    """Return the command prefix running a process under SCHED_FIFO ``prio`` (empty for 0)."""
    return ['chrt', '-f', str(prio)] if prio else []


def start_emulator(port, batch, prio=0):
    proc = subprocess.Popen([*_rt(prio), sys.executable, '-m', 'gyro_noise_ros.cli.emulator',
                             '--tcp',
                             f'127.0.0.1:{port}', '--seed', '1', '--accel-fs-g', '32',
                             '--batch', str(batch)],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    proc.stdout.readline()  # the URL: listening from now on
    return proc


def _ros_params(pairs):
    out = []
    for pair in pairs:
        out += ['-p', pair]
    return out


def stats_ms(values_ns):
    """Return (p50, p99, max) in ms of an array of ns."""
    if values_ns.size == 0:
        return (float('nan'),) * 3
    v = values_ns / 1e6
    return float(np.percentile(v, 50)), float(np.percentile(v, 99)), float(v.max())


def _read_ns(path):
    """Return the chain's compensator CPU so far (ns), or None (no chain, not written yet)."""
    try:
        with open(path) as f:
            return int(f.read())
    except (OSError, ValueError):
        return None


def run(args):
    """Start the chain, record the window; return a result dict."""
    topics = ['imu/data_raw'] + ([] if args.no_compensator else ['imu/data_compensated'])
    if args.rt:  # the probe (this process, its DDS and wait-set threads made below) too
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(args.rt))
    probe = Probe(topics, args.probe_reliable)
    if args.rt:  # the busy loops and anything else this thread starts run at normal priority
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    port = free_port()
    accept_file = os.path.join(tempfile.mkdtemp(prefix='bench_chain_'), 'accept_ns')
    # The emulator stands in for the board, which has a processor of its own: above the chain
    # (chrt), so the host's scheduling of the chain never delays the board's frames; the nodes:
    # their parameter.
    procs = {'portenta_emulator': start_emulator(port, args.batch,
                                                 min(args.rt + 10, 99) if args.rt else 0)}
    rt_param = ['-p', f'realtime_priority:={args.rt}'] if args.rt else []
    load = [subprocess.Popen([sys.executable, '-c', BUSY]) for _ in range(args.load)]
    try:
        link = ['-p', f'port:=socket://127.0.0.1:{port}', '-p', 'reconnect_period_s:=0.2']
        compensation = ['-p', 'temperature_rate_window_s:=2.0', *_param_args(True)]
        if args.chain:
            procs['imu_chain'] = subprocess.Popen(
                [sys.executable, '-c', _CHAIN, accept_file, '--ros-args', *link, *compensation,
                 *rt_param,
                 *_ros_params(args.driver_param), *_ros_params(args.compensator_param)],
                stderr=subprocess.DEVNULL)
        else:
            procs['lsm6dso32_driver'] = subprocess.Popen(
                [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args', *link,
                 *rt_param, *_ros_params(args.driver_param)], stderr=subprocess.DEVNULL)
        if args.slow_reader is not None:
            procs['slow reader'] = subprocess.Popen(
                [sys.executable, '-c', _SLOW_READER, str(args.slow_reader), args.slow_qos,
                 str(args.slow_depth)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                text=True)
        if args.bare_relay:
            procs['bare relay'] = subprocess.Popen(
                [sys.executable, '-c', _BARE_RELAY, str(args.rt)], stderr=subprocess.DEVNULL)
        elif not (args.no_compensator or args.chain):
            procs['imu_compensator'] = subprocess.Popen(
                [sys.executable, '-c', _COMPENSATOR, 'thermal', '--ros-args', *compensation,
                 *rt_param, *_ros_params(args.compensator_param)], stderr=subprocess.DEVNULL)
        time.sleep(args.warmup)
        cpu0 = {n: cpu_seconds(p.pid) for n, p in procs.items()}
        accept0 = _read_ns(accept_file)
        probe_cpu0, t0 = time.process_time(), time.monotonic()
        probe.recording = True
        time.sleep(args.seconds)
        probe.recording = False
        t1 = time.monotonic()
        cpu1 = {n: cpu_seconds(p.pid) for n, p in procs.items()}
        accept1 = _read_ns(accept_file)
        probe_cpu1 = time.process_time()
        for name, proc in procs.items():
            assert proc.poll() is None, f'{name} exited early'
    finally:
        for proc in load:
            proc.kill()
            proc.wait()
        for name in ('slow reader', 'bare relay', 'imu_compensator', 'lsm6dso32_driver',
                     'imu_chain', 'portenta_emulator'):
            if name in procs:
                stop(procs[name])
        probe.close()
        shutil.rmtree(os.path.dirname(accept_file), ignore_errors=True)
    if 'slow reader' in procs:
        out = procs['slow reader'].stdout.read().split()
        slow_count = int(out[-1]) if out else None
    wall = t1 - t0
    result = {'load': args.load, 'rt': args.rt, 'batch': args.batch, 'seconds': wall,
              'slow_reader': None if args.slow_reader is None else {
                  'work_us': args.slow_reader, 'qos': args.slow_qos, 'depth': args.slow_depth,
                  'received': slow_count},
              'cpu_pct': {n: 100 * (cpu1[n] - cpu0[n]) / wall for n in procs},
              'chain_compensator_cpu_pct': (None if accept0 is None or accept1 is None
                                            else 100 * (accept1 - accept0) / 1e9 / wall),
              'probe_cpu_pct': 100 * (probe_cpu1 - probe_cpu0) / wall,
              'probe_wakeups': probe.drain.wakeups, 'dds_missing': probe.dds_missing}
    raw = probe.arrays('imu/data_raw')
    result['raw_rate_hz'] = raw.shape[0] / wall
    stamp, source, received, take = raw.T
    # A read batch: messages the driver published in one go (one board frame, or several read
    # together); its newest sample is the one the board sent last.
    order = np.argsort(stamp, kind='stable')
    s_stamp, s_source = stamp[order], source[order]
    batch = np.concatenate(([0], np.cumsum(np.diff(s_source) > BATCH_GAP_NS)))
    newest = np.maximum.reduceat(s_stamp, np.flatnonzero(np.diff(batch, prepend=-1)))[batch]
    lat = {'raw: stamp -> callback': take - stamp,
           'raw: stamp -> DDS reception': received - stamp,
           'raw: stamp -> publish (board frame, port, driver)': source - stamp,
           'raw:   the board frame (stamp -> newest sample of its read)': newest - s_stamp,
           'raw:   port and driver (newest sample -> publish)': s_source - newest,
           'raw: DDS (reception - publish)': received - source,
           'raw: probe wake-up (callback - reception)': take - received}
    if not args.no_compensator:
        comp = probe.arrays('imu/data_compensated')
        result['compensated_rate_hz'] = comp.shape[0] / wall
        c_stamp, c_source, c_received, c_take = comp.T
        lat['compensated: stamp -> callback'] = c_take - c_stamp
        lat['compensated: stamp -> DDS reception'] = c_received - c_stamp
        # Match by stamp: a compensated message keeps its raw message's stamp.
        order = np.argsort(stamp)
        idx = np.searchsorted(stamp[order], c_stamp)
        idx = np.clip(idx, 0, stamp.size - 1)
        hit = stamp[order][idx] == c_stamp
        lat['compensator added (reception - raw reception)'] = (
            c_received[hit] - received[order][idx[hit]])
        result['compensated_matched'] = int(hit.sum())
    result['latency_ms'] = {k: stats_ms(v) for k, v in lat.items()}
    # Samples missing from what the probe received, by the stamps (more than 1.5 periods apart):
    # lost by the transport to the probe, or, on the compensated topic, before the compensator.
    period = 1e9 / ODR
    result['missing_by_stamps'] = {
        topic: int(np.sum(np.maximum(np.rint(d[d > 1.5 * period] / period) - 1, 0)))
        for topic in probe.rows for d in [np.diff(np.sort(probe.arrays(topic)[:, 0]))]}
    return result


def print_result(result, argv):
    print(f'command: {shlex.join([sys.executable] + argv)}')
    print(f'load average at the end: {os.getloadavg()[0]:.2f}; {os.cpu_count()} cores; '
          f'{result["load"]} busy loop(s) beside the chain; '
          + (f'chain under SCHED_FIFO {result["rt"]}; ' if result.get('rt') else '')
          + 'emulator frames of '
          f'{result["batch"]} samples; window {result["seconds"]:.1f} s')
    print(f'received imu/data_raw {result["raw_rate_hz"]:.0f} msg/s'
          + (f', imu/data_compensated {result["compensated_rate_hz"]:.0f} msg/s'
             if 'compensated_rate_hz' in result else '')
          + f'; lost by the transport to the probe {result["dds_missing"]}; samples missing '
          f'by the stamps {result["missing_by_stamps"]}')
    print(f'{"latency (ms)":58s} {"p50":>7s} {"p99":>7s} {"max":>7s}')
    for name, (p50, p99, mx) in result['latency_ms'].items():
        print(f'{name:58s} {p50:7.2f} {p99:7.2f} {mx:7.2f}')
    slow = result.get('slow_reader')
    if slow:
        print(f"slow reader ({slow['qos']}, depth {slow['depth']}, {slow['work_us']:g} us per "
              f"callback): received {slow['received']} messages over the whole run")
    print(f'{"CPU (% of one core)":58s}')
    for name, pct in result['cpu_pct'].items():
        print(f'  {name:56s} {pct:7.1f}')
        if name == 'imu_chain' and result.get('chain_compensator_cpu_pct') is not None:
            print(f'    {"of which the compensator (its accept, thread time)":54s} '
                  f'{result["chain_compensator_cpu_pct"]:7.1f}')
    print(f'  {"probe (this process, " + str(result["probe_wakeups"]) + " wake-ups)":56s} '
          f'{result["probe_cpu_pct"]:7.1f}')


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seconds', type=float, default=20.0, help='measurement window (s)')
    parser.add_argument('--warmup', type=float, default=8.0,
                        help='wait after start before measuring (s)')
    parser.add_argument('--load', type=int, default=0, help='busy loops beside the chain')
    parser.add_argument('--batch', type=int, default=16, help="the emulator's samples per frame")
    parser.add_argument('--no-compensator', action='store_true', help='driver only')
    parser.add_argument('--bare-relay', action='store_true',
                        help="a bare relay in the compensator's place (take as it arrives, "
                             'publish unchanged): the floor of a Python node there')
    parser.add_argument('--chain', action='store_true',
                        help='the driver and the compensator in one process (imu_chain): the '
                             'compensator gets each read from the driver, not through DDS')
    parser.add_argument('--slow-reader', type=float, metavar='WORK_US',
                        help='add a reader of imu/data_raw with one callback per message, each '
                             'busy for WORK_US (0: the callback alone)')
    parser.add_argument('--slow-qos', choices=('reliable', 'best_effort'), default='reliable',
                        help="the slow reader's reliability (default: rclpy's default QoS)")
    parser.add_argument('--slow-depth', type=int, default=10,
                        help="the slow reader's history depth (default: rclpy's usual 10)")
    parser.add_argument('--driver-param', action='append', default=[], metavar='NAME:=VALUE')
    parser.add_argument('--compensator-param', action='append', default=[],
                        metavar='NAME:=VALUE')
    parser.add_argument('--probe-reliable', action='store_true',
                        help='the probe subscribes reliable (default: sensor-data best effort)')
    parser.add_argument('--rt', type=int, default=0, metavar='PRIO',
                        help='run the driver and compensator with realtime_priority:=PRIO, the '
                             'probe (the loop) under SCHED_FIFO PRIO and the emulator (the board) '
                             'at PRIO + 10 (chrt -f); the busy loops stay at normal priority; 0: '
                             'normal scheduling')
    parser.add_argument('--json', help='also write the result here')
    args = parser.parse_args(argv)
    from gyro_noise_ros.rosgraph import lease_domain

    lease = lease_domain()  # a private graph, held until this process exits
    lease.export()
    result = run(args)
    print_result(result, sys.argv if argv is None else ['bench/bench_latency.py', *argv])
    if args.json:
        with open(args.json, 'w') as fh:
            json.dump(result, fh, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
