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
``noise_analyzer`` ingestion.

Sustained message rate and CPU share of one core at 1x and 4x of 6.66 kHz.

A publisher process (this script, ``publish`` mode) sends pre-serialised ``sensor_msgs/Imu`` paced
every millisecond; one subscriber process at a time receives them, measured from ``/proc`` (utime +
stime) over the publishing window:

1. ``callback`` baseline: a plain rclpy subscription with a Python callback per message (the naive
   node);
2. ``null`` baseline: the ingestion floor, a polled ``raw=True`` subscription drained with
   ``take_message`` every 10 ms (the pattern measured in ``../shared/ROS_ON_PIP.md``) that only
   counts;
3. the real ``noise_analyzer`` (default parameters: chunks of 10,000, full 0:2:0.01 grid, both
   methods, Allan deviation), its CPU split into the analysis worker thread
   (``/proc/<pid>/task/<tid>``) and the rest (ingestion: take every ``drain_period_s`` = 50 ms,
   bulk decode, gap detection, chunking, diagnostics; DDS receive threads are counted here, as in
   the baselines).

Received counts come from the subscriber (its exit line; the analyzer's ``Samples received`` on
``/diagnostics``, read here). Targets: ingestion <= 25 % of one core at 6.66 kHz; no loss
at 4x.

Run: ``.venv/bin/python bench/bench_analyzer_node.py [--seconds 10] [--rates 6660,26640]``.
The machine is shared and has 2 cores: numbers vary from run to run; the ratios are the point.
"""

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time

TICK = os.sysconf('SC_CLK_TCK')
RATE_HZ = 6660.0


def cpu_seconds(pid, tid=None):
    """Return utime + stime of a process (or one of its threads), in seconds."""
    path = f'/proc/{pid}/stat' if tid is None else f'/proc/{pid}/task/{tid}/stat'
    with open(path) as fh:
        fields = fh.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


# ---- child modes
# -----------------------------------------------------------------------------------

def _publish(rate_hz, seconds):
    import numpy as np
    import rclpy
    from sensor_msgs.msg import Imu

    from gyro_noise_ros.msgs import encode_imu_cdr
    from gyro_noise_ros.nodes._ros_common import sensor_data_qos

    n = int(rate_hz * seconds)
    rng = np.random.default_rng(0)
    stamps = 10 ** 18 + np.rint(np.arange(n) * 1e9 / rate_hz).astype(np.int64)
    blobs = encode_imu_cdr(stamps, rng.standard_normal((n, 3)) * 0.004, np.zeros((n, 3)))
    rclpy.init()
    node = rclpy.create_node('bench_publisher')
    pub = node.create_publisher(Imu, 'imu/data_raw', sensor_data_qos(5000))
    while pub.get_subscription_count() < 1:
        time.sleep(0.05)
    time.sleep(1.0)
    print('start', flush=True)
    t0 = time.monotonic()
    i = 0
    while i < n:
        due = min(n, int((time.monotonic() - t0) * rate_hz) + 1)
        while i < due:
            pub.publish(blobs[i])
            i += 1
        time.sleep(0.001)
    print(f'published {i} {time.monotonic() - t0:.3f}', flush=True)
    time.sleep(1.0)
    node.destroy_node()
    rclpy.try_shutdown()


def _subscribe(mode, depth):
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from sensor_msgs.msg import Imu

    from gyro_noise_ros.nodes._ros_common import sensor_data_qos
    from gyro_noise_ros.nodes._ros_common import PolledGroup, take_all

    rclpy.init()
    node = rclpy.create_node(f'bench_{mode}')
    count = [0]
    if mode == 'callback':
        def on_msg(msg):
            count[0] += 1
        node.create_subscription(Imu, 'imu/data_raw', on_msg, sensor_data_qos(depth))
    else:
        sub = node.create_subscription(Imu, 'imu/data_raw', lambda m: None, sensor_data_qos(depth),
                                       raw=True, callback_group=PolledGroup())

        def drain():
            count[0] += len(take_all(sub, Imu)[0])
        node.create_timer(0.01, drain)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        print(f'received {count[0]}', flush=True)
        node.destroy_node()
        rclpy.try_shutdown()


# ---- the measurement
# ---------------------------------------------------------------------------------

def _analyzer_received(lease, timeout_s=5.0):
    """Latest 'Samples received' of noise_analyzer on /diagnostics (None if none arrived)."""
    lease.export()
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    got = {}
    try:
        node = rclpy.create_node('bench_listener', context=ctx)

        def on_array(msg):
            for s in msg.status:
                if s.name.startswith('noise_analyzer: axis'):
                    v = {kv.key: kv.value for kv in s.values}
                    got.update(received=int(v['Samples received']), lost=v['Samples lost'],
                               skipped=v['Chunks skipped'], analysed=v['Chunks analysed'])
        node.create_subscription(DiagnosticArray, '/diagnostics', on_array, 10)
        ex = rclpy.executors.SingleThreadedExecutor(context=ctx)
        ex.add_node(node)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and 'received' not in got:
            ex.spin_once(timeout_sec=0.1)
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)
    return got


def _run(kind, rate_hz, seconds, depth, analyzer_params=()):
    from gyro_noise_ros.rosgraph import lease_domain

    with lease_domain() as lease:  # a private graph per run, checked free and held
        return _run_in(lease, kind, rate_hz, seconds, depth, analyzer_params)


def _run_in(lease, kind, rate_hz, seconds, depth, analyzer_params):
    env = lease.env(dict(os.environ, PYTHONUNBUFFERED='1'))
    here = os.path.abspath(__file__)
    if kind == 'analyzer':
        cmd = [sys.executable, '-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args', '-p',
               f'queue_depth:={depth}']
        for param in analyzer_params:
            cmd += ['-p', param]
    else:
        cmd = [sys.executable, here, 'subscribe', kind, str(depth)]
    log = tempfile.NamedTemporaryFile('w+', suffix='.log', delete=False)
    sub = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=log, text=True)
    worker_tid = None
    if kind == 'analyzer':
        # Wait for warm-up; the worker's thread id comes in the log.
        deadline = time.monotonic() + 120
        text = ''
        while time.monotonic() < deadline and not ('analysing ' in text
                                                   and 'native thread id' in text):
            time.sleep(0.2)
            text = open(log.name).read()
        worker_tid = int(text.split('native thread id ', 1)[1].split(')', 1)[0])
    pub = subprocess.Popen([sys.executable, here, 'publish', str(rate_hz), str(seconds)], env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert pub.stdout.readline().strip() == 'start'
        c0, w0, t0 = (
            cpu_seconds(sub.pid),
            cpu_seconds(sub.pid, worker_tid) if worker_tid else 0.0,
            time.monotonic(),
        )
        line = pub.stdout.readline().split()
        published = int(line[1])
        time.sleep(0.5)
        c1, w1, t1 = (
            cpu_seconds(sub.pid),
            cpu_seconds(sub.pid, worker_tid) if worker_tid else 0.0,
            time.monotonic(),
        )
        pub.communicate(timeout=30)
        extra = {}
        if kind == 'analyzer':
            extra = _analyzer_received(lease)
            received = extra.pop('received', -1)
        sub.send_signal(2)
        out, _ = sub.communicate(timeout=30)
        if kind != 'analyzer':
            received = int(out.split()[-1])
    finally:
        for p in (pub, sub):
            if p.poll() is None:
                p.kill()
                p.communicate()
        log.close()
        os.unlink(log.name)
    wall = t1 - t0
    return dict(kind=kind, rate=rate_hz, published=published, received=received,
                cpu=(c1 - c0) / wall, worker=(w1 - w0) / wall, **extra)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seconds', type=float, default=10.0, help='publishing time per run (s)')
    parser.add_argument('--queue-depth', type=int, default=5000,
                        help='QoS history depth of every subscriber (the analyzer: queue_depth)')
    parser.add_argument(
        '-p', '--param', action='append', default=[], metavar='NAME:=VALUE',
        help='extra noise_analyzer parameter (repeatable), e.g. -p drain_period_s:=0.02')
    parser.add_argument('--kinds', default='callback,null,analyzer',
                        help='subscribers to measure, among callback, null, analyzer')
    parser.add_argument('--rates', default=f'{RATE_HZ:g},{4 * RATE_HZ:g}',
                        help='comma-separated rates (Hz)')
    args = parser.parse_args(argv)
    rates = [float(r) for r in args.rates.split(',')]
    print('command:', shlex.join([sys.executable, *sys.argv]))
    print(f'{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start')
    rows = []
    for rate in rates:
        for kind in args.kinds.split(','):
            rows.append(_run(kind, rate, args.seconds, args.queue_depth, args.param))
            r = rows[-1]
            print(f'  measured {kind:<9} at {rate:7.0f} Hz: {r["received"]}/{r["published"]} '
                  'messages, ' f'{100 * r["cpu"]:.1f} % of a core', flush=True)
    print()
    print(
        f'{"rate (Hz)":>9} | {"subscriber":<22} | {"received/published":>19} | {"CPU total":>9} | '
        f'{"ingestion":>9} | {"analysis":>8} | vs null')
    for r in rows:
        null = next((x for x in rows if x['rate'] == r['rate'] and x['kind'] == 'null'), None)
        ingest = r['cpu'] - r['worker']
        name = {'callback': 'callback per message', 'null': 'null raw drain (floor)',
                'analyzer': 'noise_analyzer'}[r['kind']]
        analysis = f'{100 * r["worker"]:7.1f}%' if r['kind'] == 'analyzer' else f'{"-":>8}'
        print(f'{r["rate"]:9.0f} | {name:<22} | {r["received"]:>9}/{r["published"]:<9} | '
              f'{100 * r["cpu"]:8.1f}% | ' f'{100 * ingest:8.1f}% | {analysis} | '
              + (f'x{ingest / null["cpu"]:.2f}' if null else '-'))
        if r['kind'] == 'analyzer':
            print(f'{"":9} | {"":22}   samples lost {r.get("lost")}, chunks analysed '
                  f'{r.get("analysed")}, ' f'skipped {r.get("skipped")}')
    print(f'load average {os.getloadavg()[0]:.2f} at the end')
    return 0


if __name__ == '__main__':
    if len(sys.argv) > 1 and sys.argv[1] == 'publish':
        sys.exit(_publish(float(sys.argv[2]), float(sys.argv[3])))
    if len(sys.argv) > 1 and sys.argv[1] == 'subscribe':
        sys.exit(_subscribe(sys.argv[2], int(sys.argv[3])))
    sys.exit(main())
