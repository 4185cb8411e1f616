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
Memory of the live analysis over many chunks, faster than real time (docs/scale.md, memory).

``--mode live``: :class:`LiveAnalysis` alone, fed white noise in 2,000-sample batches with the
node's summary/health cadence. ``--mode node``: a ``NoiseAnalyzerNode`` in this process, in a
private ROS graph (:mod:`gyro_noise_ros.rosgraph`), fed serialised ``sensor_msgs/Imu`` (and a
temperature every 128 samples) either straight into its ingestion (``--feed direct``) or through
a publisher and its real subscription (``--feed dds``); its own ``drain`` collects and publishes
the chunks, and this loop calls what its timers would, on *data* time: ``publish_diagnostics``
every 1 s (the Allan update every 10 s), the publisher check every 1 s, ``malloc_trim`` every
10 s. Every ``--every`` chunks it prints the RSS, Python's allocated blocks, glibc's heap
(``mallinfo2``: bytes in use, free, in mmaps) and the CPU seconds; ``--trace A,B`` starts
tracemalloc at chunk A and compares snapshots at A + every and B by traceback. The slopes are
least squares over the samples from ``--warmup`` chunks on, per 1,000 chunks.

Run: ``nice -n 10 .venv/bin/python bench/bench_live_memory.py --mode node --chunks 3000``.
"""

import argparse
import ctypes
import gc
import json
import sys
import time
import tracemalloc

import numpy as np

RATE_HZ = 6667.0
BATCH = 2000
TEMPERATURE_DECIMATION = 128


class _Mallinfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        'arena', 'ordblks', 'smblks', 'hblks', 'hblkhd', 'usmblks', 'fsmblks', 'uordblks',
        'fordblks', 'keepcost')]


_LIBC = ctypes.CDLL(None)
_LIBC.mallinfo2.restype = _Mallinfo2
_LIBC.malloc_trim.argtypes = [ctypes.c_size_t]


def rss_mb():
    """Return this process's resident set size (MB)."""
    with open('/proc/self/status') as fh:
        for line in fh:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    return float('nan')


def owners(live):
    """Return the bytes held by the state that grows with the run, by owner (MB)."""
    from gyro_noise_ros.core import allan

    engine = live.engine
    accs = engine._allan._acc or {}
    rows = sum(store._buf.nbytes for store in engine._book._rows.values())
    tracker = engine._stamps._timebase
    return {'allan_mb': sum(a.nbytes for a in accs.values()) / 2 ** 20,
            'rows_mb': rows / 2 ** 20,
            'timebase_mb': (tracker._blocks.nbytes + tracker._jn_rows.nbytes) / 2 ** 20,
            'results': len(live.results),
            'edf_cache': allan._edf_cached.cache_info().currsize,
            'skew_cache': allan._skewness_cached.cache_info().currsize}


def sample(chunks, live):
    """Return one row of measurements after ``chunks`` chunks."""
    info = _LIBC.mallinfo2()
    return {'chunks': chunks, 'rss_mb': rss_mb(), 'blocks': sys.getallocatedblocks(),
            'heap_used_mb': info.uordblks / 2 ** 20, 'heap_free_mb': info.fordblks / 2 ** 20,
            'mmap_mb': info.hblkhd / 2 ** 20, 'cpu_s': time.process_time(), **owners(live)}


def slope_per_1000(rows, key, warmup):
    """Least-squares slope of ``key`` per 1,000 chunks over rows from ``warmup`` on, and its SE."""
    x = np.array([r['chunks'] for r in rows if r['chunks'] >= warmup], float)
    y = np.array([r[key] for r in rows if r['chunks'] >= warmup], float)
    if x.size < 3:
        return float('nan'), float('nan')
    a = np.vstack([x, np.ones_like(x)]).T
    coef, res, _, _ = np.linalg.lstsq(a, y, rcond=None)
    dof = x.size - 2
    resid = y - a @ coef
    se = np.sqrt(resid @ resid / dof / np.sum((x - x.mean()) ** 2))
    return 1000.0 * coef[0], 1000.0 * se


class Tracer:
    """tracemalloc started at chunk A, snapshots at A + every and at B, compared by traceback."""

    def __init__(self, spec, every, frames):
        self.start, self.stop = (int(v) for v in spec.split(',')) if spec else (-1, -1)
        self.every, self.frames = every, frames
        self.first = None
        self.report = []

    def at(self, chunks):
        """Act on reaching ``chunks``."""
        if self.start < 0:
            return
        if chunks >= self.start and not tracemalloc.is_tracing() and self.first is None:
            tracemalloc.start(self.frames)
        elif self.first is None and chunks >= self.start + self.every:
            gc.collect()
            self.first = (chunks, tracemalloc.take_snapshot())
        elif self.first is not None and chunks >= self.stop and tracemalloc.is_tracing():
            gc.collect()
            second = tracemalloc.take_snapshot()
            tracemalloc.stop()
            filters = [tracemalloc.Filter(False, tracemalloc.__file__)]
            diff = second.filter_traces(filters).compare_to(
                self.first[1].filter_traces(filters), 'traceback')
            span = chunks - self.first[0]
            print(f'tracemalloc: chunks {self.first[0]} -> {chunks}, top growth:')
            for stat in diff[:12]:
                per = stat.size_diff / span
                self.report.append({'bytes': stat.size_diff, 'count': stat.count_diff,
                                    'bytes_per_chunk': per,
                                    'where': [str(f) for f in stat.traceback]})
                print(f'  {stat.size_diff / 1024:+9.1f} kB ({per:+8.1f} B/chunk, '
                      f'{stat.count_diff:+d} blocks)')
                for line in stat.traceback.format()[-2 * min(6, self.frames):]:
                    print('      ' + line)


class TypeCounter:
    """Counts of gc-tracked objects by type at chunks A and B (cheap beside tracemalloc)."""

    def __init__(self, spec):
        self.marks = [int(v) for v in spec.split(',')] if spec else []
        self.first = None
        self.report = {}

    @staticmethod
    def _counts():
        gc.collect()
        counts = {}
        for obj in gc.get_objects():
            kind = type(obj)
            name = f"{kind.__dict__.get('__module__', '')}.{kind.__name__}"
            counts[name] = counts.get(name, 0) + 1
        return counts

    def at(self, chunks):
        """Act on reaching ``chunks``."""
        if not self.marks or chunks < self.marks[0]:
            return
        self.marks.pop(0)
        counts = self._counts()
        if self.first is None:
            self.first = (chunks, counts)
            return
        previous, self.first = self.first, (chunks, counts)
        self._print(previous, chunks, counts)

    def _print(self, first, chunks, counts):
        span = chunks - first[0]
        diff = sorted(((n - first[1].get(k, 0), k) for k, n in counts.items()),
                      reverse=True)
        print(f'gc objects: chunks {first[0]} -> {chunks}, most grown types:')
        for d, k in diff[:8]:
            print(f'  {d:+8d} ({d / span:+.2f}/chunk) {k}')
            self.report.setdefault(f'{first[0]}-{chunks}', {})[k] = d


def _noise(rng, n):
    return rng.normal(0.0, 0.01, (n, 3))


def run_live(args, on_chunks):
    """Feed :class:`LiveAnalysis` alone (the node's summary and health calls on data time)."""
    from gyro_noise_ros.app.live import engine_config_from, LiveAnalysis
    from gyro_noise_ros.nodes.analyzer import PARAMETERS

    live = LiveAnalysis(engine_config_from({p.name: p.default for p in PARAMETERS}))
    rng = np.random.default_rng(1)
    next_ns, done, calls = 0, 0, 0
    while done < args.chunks:
        stamps = next_ns + (np.arange(BATCH) * (1e9 / RATE_HZ)).astype(np.int64)
        next_ns = int(stamps[-1] + 1e9 / RATE_HZ)
        live.ingest(stamps, _noise(rng, BATCH))
        calls += 1
        if calls % 3 == 0:  # ~1 s of data: a diagnostics period
            live.engine.health(seconds_since_data=0.0, summaries=live.engine.summary(allan=False))
        if calls % 33 == 0:  # ~10 s: the Allan period
            live.engine.summary(allan=True)
        done += len(live.collect()[1])
        while live.queue_size > 2:  # never skip: wait for the worker
            time.sleep(0.005)
            done += len(live.collect()[1])
        on_chunks(done, live)
    live.stop()


def run_node(args, on_chunks):
    """Feed an in-process ``NoiseAnalyzerNode`` in a private graph (see the module docstring)."""
    from gyro_noise_ros.rosgraph import lease_domain

    with lease_domain() as lease:
        lease.export()
        import rclpy
        from rclpy.qos import QoSProfile
        from sensor_msgs.msg import Imu, Temperature

        from gyro_noise_ros.msgs import encode_imu_cdr, encode_temperature_cdr
        from gyro_noise_ros.nodes.analyzer import NoiseAnalyzerNode

        rclpy.init()
        try:
            node = NoiseAnalyzerNode(parameter_overrides=[
                rclpy.parameter.Parameter('reliable', value=True)])
            feeder = rclpy.create_node('bench_live_memory_feeder')
            qos = QoSProfile(depth=20000, reliability=rclpy.qos.ReliabilityPolicy.RELIABLE)
            imu_pub = feeder.create_publisher(Imu, 'imu/data_raw', qos)
            temp_pub = feeder.create_publisher(Temperature, 'imu/temperature', qos)
            if args.feed == 'dds':
                deadline = time.monotonic() + 20
                while (imu_pub.get_subscription_count() < 1
                       or temp_pub.get_subscription_count() < 1):
                    if time.monotonic() > deadline:
                        raise SystemExit('the analyzer did not match the feeder in 20 s')
                    time.sleep(0.05)
                time.sleep(1.0)
            _node_loop(args, node, imu_pub, temp_pub, encode_imu_cdr, encode_temperature_cdr,
                       on_chunks)
            node.destroy_node()
            feeder.destroy_node()
        finally:
            rclpy.try_shutdown()


def _node_loop(args, node, imu_pub, temp_pub, encode_imu, encode_temp, on_chunks):
    rng = np.random.default_rng(1)
    period = 1e9 / RATE_HZ
    first = 10 ** 18
    index, done = 0, 0
    due_diag, due_allan, due_trim = 1e9, 10e9, 10e9
    chunks_out = [0]
    publish_chunk = node._publish_chunk

    def counting(per_axis):
        chunks_out[0] += 1
        publish_chunk(per_axis)
    node._publish_chunk = counting
    while done < args.chunks:
        k = np.arange(index, index + BATCH)
        stamps = first + np.rint(k * period).astype(np.int64)
        raws = encode_imu(stamps, _noise(rng, BATCH), np.zeros((BATCH, 3)))
        t_idx = k[k % TEMPERATURE_DECIMATION == 0]
        temps = encode_temp(first + np.rint(t_idx * period).astype(np.int64),
                            25.0 + 1e-6 * t_idx)
        index += BATCH
        if args.feed == 'dds':
            for raw in temps:
                temp_pub.publish(raw)
            for raw in raws:
                imu_pub.publish(raw)
            time.sleep(0.002)
        else:
            node.live.temperature.add(*_decode_temperature(temps))
            node._ingest(raws)
        node.drain()
        while node.live.queue_size > 2 * len(node.config.axes):  # never skip: wait
            time.sleep(0.005)
            node.drain()
        data_ns = index * period
        if data_ns >= due_diag:
            due_diag += 1e9
            if data_ns >= due_allan:
                due_allan += 10e9
                node._allan_due = 0.0
            node.publish_diagnostics()
            node._check_publishers()
        if data_ns >= due_trim:
            due_trim += 10e9
            _LIBC.malloc_trim(0)
        done = chunks_out[0]
        on_chunks(done, node.live)


def _decode_temperature(raws):
    from gyro_noise_ros.bag import decode_temperature
    return decode_temperature(raws)


def main(argv=None):
    """Run the chosen mode and print the samples, the slopes and the tracemalloc comparison."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--mode', choices=('live', 'node'), default='node')
    parser.add_argument('--feed', choices=('direct', 'dds'), default='direct',
                        help='node mode: into _ingest, or through a publisher and the '
                        'subscription')
    parser.add_argument('--chunks', type=int, default=3000, help='chunks (of all axes) to run')
    parser.add_argument('--every', type=int, default=100, help='chunks between two samples')
    parser.add_argument('--warmup', type=int, default=1200,
                        help='chunks before the slopes start (past the result cap)')
    parser.add_argument('--trace', default='', help='A,B: tracemalloc from chunk A, compare '
                        'A+every with B (e.g. 1200,2400)')
    parser.add_argument('--types', default='', help='A,B: count gc-tracked objects by type at '
                        'chunks A and B and print the types that grew')
    parser.add_argument('--frames', type=int, default=8, help='tracemalloc traceback depth')
    parser.add_argument('--json', default='', help='write the samples and slopes here')
    args = parser.parse_args(argv)
    rows = []
    tracer = Tracer(args.trace, args.every, args.frames)
    types = TypeCounter(args.types)
    print('chunks  RSS (MB)  blocks  heap used  heap free  mmap (MB)  CPU (s)  Allan  rows  '
          'timeb  results  edf  skew')

    due = [0]

    def on_chunks(done, live):
        tracer.at(done)
        types.at(done)
        if done >= due[0]:
            due[0] = (done // args.every + 1) * args.every
            row = sample(done, live)
            rows.append(row)
            print(f"{done:6d}  {row['rss_mb']:8.1f}  {row['blocks']:7d}  "
                  f"{row['heap_used_mb']:9.2f}  {row['heap_free_mb']:9.2f}  "
                  f"{row['mmap_mb']:9.2f}  {row['cpu_s']:7.1f}  {row['allan_mb']:6.2f}  "
                  f"{row['rows_mb']:5.2f}  {row['timebase_mb']:5.2f}  {row['results']:5d}  "
                  f"{row['edf_cache']:5d}  {row['skew_cache']:5d}", flush=True)

    (run_node if args.mode == 'node' else run_live)(args, on_chunks)
    slopes = {key: slope_per_1000(rows, key, args.warmup)
              for key in ('rss_mb', 'blocks', 'heap_used_mb', 'mmap_mb')}
    for key, (s, se) in slopes.items():
        print(f'slope from chunk {args.warmup}: {key} {s:+.3f} +/- {se:.3f} per 1,000 chunks')
    if args.json:
        with open(args.json, 'w') as fh:
            json.dump({'args': vars(args), 'samples': rows, 'slopes_per_1000_chunks': slopes,
                       'tracemalloc': tracer.report,
                       'gc_types': types.report}, fh, indent=1)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
