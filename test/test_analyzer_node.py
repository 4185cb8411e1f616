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
``noise_analyzer`` in-process: same numbers as the offline tool and the engine, skipping, refusals.

The same bag played into the node and given to the offline tool and to the engine yields identical
per-chunk numbers; the node skips chunks when analysis falls behind; bad parameters are refused.

The node runs in this process with ``parameter_overrides`` in the test's private graph
(``ros_graph`` in ``conftest.py``) and its own rclpy context; a publisher node replays the bag's
serialised messages (bytes as stored, no re-encoding).
"""

import math
import os
import subprocess
import sys
import threading
import time

from geometry_msgs.msg import Vector3Stamped
from gyro_noise_ros.app.live import CHUNK_TOPICS
from gyro_noise_ros.bag import ImuBagReader
from gyro_noise_ros.cli import analyze as analyze_cli
from gyro_noise_ros.core.engine import NoiseEngine
from gyro_noise_ros.core.simulate import simulate_fractional_noise
from gyro_noise_ros.errors import InputError, ParameterError
from gyro_noise_ros.nodes import analyzer
from gyro_noise_ros.nodes._ros_common import sensor_data_qos
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from sensor_msgs.msg import Imu, Temperature

pytestmark = pytest.mark.ros

RATE_HZ = 6660.0
# Small chunks, memory and grid keep the test fast; the comparison is exact whatever the sizes.
SMALL = {'chunk_size': 2000, 'memory': 200, 'order_grid_step': 0.05, 'diagnostics_period_s': 0.2}
DEG = 180.0 / math.pi


def _overrides(**values):
    return [Parameter(k, value=v) for k, v in values.items()]


def _make_bag(make_record, path, n, *, seed, gaps=()):
    """Write a rosbag2: fractional noise (alpha 0.6) on 3 axes, removed samples, temperature."""
    rng = np.random.default_rng(seed)
    gyro = np.column_stack([simulate_fractional_noise(n, 0.6, -0.2, 3e-3, rng=rng, memory=200)
                            for _ in range(3)])
    index = np.arange(n)
    keep = np.ones(n, bool)
    for start, length in gaps:
        keep[start:start + length] = False
    stamps = 1_700_000_000_000_000_000 + np.rint(index * 1e9 / RATE_HZ).astype(np.int64)
    t_idx = np.arange(0, n, 128)
    make_record(path, gyro[keep], stamps_ns=stamps[keep], accel_m_s2=np.zeros((keep.sum(), 3)),
                temperature_c=np.full(t_idx.size, 31.5), temperature_stamps_ns=stamps[t_idx],
                frame_id='imu_bag')
    return int(keep.sum())


def _raw_messages(path):
    """Return the bag's raw (serialised) messages in log-time order: (topic, bytes)."""
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        return [(conn.topic, raw) for conn, _, raw in reader.messages()]


def _spin_until(executor, predicate, timeout_s):
    deadline = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.02)
    return predicate()


def _replay(context, node, messages, *, block=500):
    """Publish the raw messages in blocks, each after the node has taken the previous one."""
    pub_node = rclpy.create_node('test_bag_player', context=context)
    pubs = {'/imu/data_raw': pub_node.create_publisher(Imu, 'imu/data_raw', sensor_data_qos(5000)),
            '/imu/temperature': pub_node.create_publisher(Temperature, 'imu/temperature',
                                                          sensor_data_qos(5000))}
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(pub_node)
    assert _spin_until(executor, lambda: pubs['/imu/data_raw'].get_subscription_count() > 0, 20)
    _spin_until(executor, lambda: False, 0.5)  # let the reader finish matching
    sent = 0
    for start in range(0, len(messages), block):
        for topic, raw in messages[start:start + block]:
            pubs[topic].publish(raw)
            sent += topic == '/imu/data_raw'
        assert _spin_until(executor, lambda: node.messages_received >=
                           sent, 20), (node.messages_received, sent)
    return executor, pub_node


def _fields(result):
    return {k: v for k, v in vars(result).items() if k not in ('var_curve', 'j_curve')}


def _same(a, b):
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a)
                      and math.isnan(b))


@pytest.mark.timeout(180)
def test_bag_through_node_equals_offline_tool_and_engine(context, tmp_path, make_record):
    bag = tmp_path / 'ref'
    n = 6 * 2000 + 700
    # Two gaps (5 and 1 samples) so samples_lost and gaps are compared too.
    kept = _make_bag(make_record, bag, n, seed=11, gaps=((3000, 5), (7400, 1)))
    node = analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(**SMALL))
    received = {name: [] for name in CHUNK_TOPICS}
    listener = rclpy.create_node('test_chunk_listener', context=context)
    for name in received:
        listener.create_subscription(Vector3Stamped, f'/noise_analyzer/{name}',
                                     lambda m, name=name: received[name].append(m), 100)
    executor = None
    try:
        executor, player = _replay(context, node, _raw_messages(bag))
        executor.add_node(listener)
        chunks = kept // 2000
        assert _spin_until(executor, lambda: len(node.results) == 3 * chunks
                           and all(len(v) == chunks for v in received.values()), 60)
        node_results = sorted(node.results, key=lambda r: (r.chunk, r.axis))
        diag = node.diagnostics()
        storage = {a: node.engine.allan_nbytes(a) for a in 'xyz'}
    finally:
        if executor is not None:
            executor.shutdown()
        node.destroy_node()
    # Each axis states its Allan accumulator's memory: at least the level-0 phase history
    # (2 * 2**15 + 1 points), no ring row yet at this length.
    for status in diag.status:
        held = storage[status.name[-1]]
        assert (2 * 2 ** 15 + 1) * 8 <= held < 2 ** 20
        values = {kv.key: kv.value for kv in status.values}
        assert values['Allan storage (MiB)'] == f'{held / 2 ** 20:.2f}'

    # The engine on the bag, with the node's configuration.
    engine = NoiseEngine(node.config)
    direct = []
    with ImuBagReader(bag) as reader:
        t_stamp, t_value = reader.read_temperature()
        for batch in reader.iter_batches(3000):
            temp = np.interp(batch.stamp_ns.astype(float), t_stamp.astype(float), t_value)
            direct += [engine.analyze(job)
                       for job in engine.ingest(batch.stamp_ns, batch.gyro, temp)]
    direct.sort(key=lambda r: (r.chunk, r.axis))
    assert len(direct) == len(node_results) == 3 * chunks
    for mine, theirs in zip(node_results, direct):
        a, b = _fields(mine), _fields(theirs)
        assert all(_same(a[k], b[k])
                   for k in a), {k: (a[k], b[k]) for k in a if not _same(a[k], b[k])}
    assert sum(r.samples_lost for r in node_results if r.axis == 'x') == 6
    assert {r.temperature_c for r in node_results} == {31.5}

    # The offline tool on the same bag: chunks.csv holds every number losslessly (repr).
    out = tmp_path / 'report'
    rc = analyze_cli.main([str(bag), '--out', str(out), '--jobs', '1', '--chunk-size', '2000',
                           '--memory', '200', '--order-grid', '0:2:0.05', '--no-figures',
                           '--no-allan', '--quiet'])
    assert rc == 0
    import csv
    with open(out / 'chunks.csv') as fh:
        rows = sorted(csv.DictReader(fh), key=lambda r: (int(r['chunk']), r['axis']))
    assert len(rows) == len(node_results)
    for row, r in zip(rows, node_results):
        assert (row['axis'], int(row['chunk']), int(row['samples']), int(row['samples_lost']),
                int(row['stamp_start_ns'])) == (r.axis, r.chunk, r.samples, r.samples_lost,
                                                r.stamp_start_ns)
        for col, value in (('alpha_var', r.alpha_var), ('f_var', r.f_var),
                           ('alpha_corr', r.alpha_corr), ('f_corr', r.f_corr),
                           ('t_start_s', r.t_start_s)):
            assert float(row[col]) == value, (col, row[col], value)
        bias_col = next(c for c in row if c.startswith('bias'))
        var_col = next(c for c in row if c.startswith('variance'))
        assert float(row[bias_col]) == pytest.approx(r.bias_rad_s * DEG, rel=1e-15, abs=0)
        assert float(row[var_col]) == pytest.approx(
            r.variance_rad2_s2 * DEG ** 2, rel=1e-15, abs=0)

    # The per-chunk topics carry the same numbers, x/y/z = axes, stamped with the chunk start.
    by_key = {(r.chunk, r.axis): r for r in node_results}
    for name, (field, _) in CHUNK_TOPICS.items():
        for chunk, msg in enumerate(received[name]):
            assert msg.header.frame_id == 'imu_bag'
            stamp = msg.header.stamp.sec * 10 ** 9 + msg.header.stamp.nanosec
            assert stamp == by_key[(chunk, 'x')].stamp_start_ns
            got = (msg.vector.x, msg.vector.y, msg.vector.z)
            assert got == tuple(getattr(by_key[(chunk, a)], field) for a in 'xyz'), (name, chunk)


@pytest.mark.timeout(120)
def test_falls_behind_by_skipping_with_a_bounded_queue(context):
    node = analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
        **SMALL, analysis_queue_chunks=1, rate_hz=RATE_HZ))
    real = node.engine.analyze
    gate = threading.Event()
    high_water = []

    def slow(job, **kw):
        high_water.append(node.live.queue_size)
        gate.wait(timeout=30)  # hold the worker until every chunk has been ingested
        return real(job, **kw)

    node.engine.analyze = slow
    rng = np.random.default_rng(5)
    chunks = 8
    n = chunks * 2000
    stamps = (np.arange(n) * 1e9 / RATE_HZ).astype(np.int64) + 10 ** 18
    from gyro_noise_ros.msgs import encode_imu_cdr

    messages = [('/imu/data_raw', raw) for raw in
                encode_imu_cdr(stamps, rng.standard_normal((n, 3)) * 1e-3, np.zeros((n, 3)))]
    executor = None
    try:
        executor, _ = _replay(context, node, messages, block=1000)
        gate.set()
        assert _spin_until(executor, lambda: len(node.results)
                           == 3 * chunks, 60), len(node.results)
        diag = node.diagnostics()
    finally:
        if executor is not None:
            executor.shutdown()
        node.destroy_node()
    statuses = {r.status for r in node.results}
    skipped = [r for r in node.results if r.status == 'skipped']
    analysed = [r for r in node.results if r.status == 'ok']
    # One job in the worker and at most 1 x 3 axes in the queue: at most 4 jobs were ever held.
    assert max(high_water) <= 3
    assert statuses <= {'ok', 'skipped'} and skipped and analysed
    assert len(skipped) + len(analysed) == 3 * chunks
    for status in diag.status:
        values = {kv.key: kv.value for kv in status.values}
        axis = status.name[-1]
        n_skipped = sum(r.axis == axis for r in skipped)
        assert values['Chunks skipped'] == f'{n_skipped} of {chunks}'
        # More than half of the chunks skipped is above the default ERROR fraction (0.5); between
        # 0.1 and 0.5 WARN.
        assert status.level == (b'\x02' if n_skipped > chunks / 2 else b'\x01')
        assert 'skipped' in status.message


@pytest.mark.timeout(120)
def test_unusable_stamps_give_error_not_a_crash(context):
    # Every stamp equal: the sample rate cannot be estimated, so the engine rejects the batches
    # once the samples held for the estimate are in (equal stamps alone are one packet: normal).
    from gyro_noise_ros.msgs import encode_imu_cdr
    from gyro_noise_ros.core.engine import RATE_ESTIMATE_SAMPLES

    node = analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(**SMALL))
    n = RATE_ESTIMATE_SAMPLES + 75
    messages = [('/imu/data_raw', raw) for raw in
                encode_imu_cdr(np.full(n, 10 ** 18), np.zeros((n, 3)), np.zeros((n, 3)))]
    executor = None
    try:
        executor, _ = _replay(context, node, messages, block=300)
        diag = node.diagnostics()
    finally:
        if executor is not None:
            executor.shutdown()
        node.destroy_node()
    for status in diag.status:
        values = {kv.key: kv.value for kv in status.values}
        assert status.level == b'\x02', (status.level, status.message)
        assert status.message.startswith('Samples rejected: ') and 'sample rate' in status.message
        assert int(values['Batches rejected']) >= 1


@pytest.mark.timeout(120)
def test_a_second_publisher_is_counted_apart_named_and_warns(context):
    from gyro_noise_ros.bag import encode_imu_cdr

    node = analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
        **SMALL, rate_hz=RATE_HZ))
    lines = []  # what the node's 1 s timer logs
    check = node._imu_watch.check
    node._imu_watch.check = lambda n: lines.extend(check(n)) or lines[len(lines):]
    players = [rclpy.create_node(name, context=context) for name in ('player_a', 'player_b')]
    pubs = [p.create_publisher(Imu, 'imu/data_raw', sensor_data_qos(5000)) for p in players]
    executor = SingleThreadedExecutor(context=context)
    for n in (node, *players):
        executor.add_node(n)
    n = 3000
    stamps = 10 ** 18 + (np.arange(n) * 1e9 / RATE_HZ).astype(np.int64)
    raws = encode_imu_cdr(stamps, np.zeros((n, 3)), np.zeros((n, 3)))
    try:
        assert _spin_until(executor, lambda: all(p.get_subscription_count() for p in pubs), 20)
        _spin_until(executor, lambda: False, 0.5)
        # Every third message from b: 2000 from a, 1000 from b, interleaved.
        for k, raw in enumerate(raws):
            pubs[k % 3 == 2].publish(raw)
            if k % 500 == 499:
                assert _spin_until(executor, lambda: node.messages_received > k, 20)
        assert _spin_until(executor, lambda: node.messages_received == n, 20)
        assert _spin_until(executor, lambda: len(lines) == 2, 5)  # the next check
        diag = node.diagnostics()
    finally:
        executor.shutdown()
        node.destroy_node()
    assert [severity for severity, _ in lines] == ['info', 'warn']
    assert lines[1][1].startswith('another publisher on /imu/data_raw: /player_b (besides '
                                  '/player_a); the analysis mixes their samples')
    for status in diag.status:
        values = {kv.key: kv.value for kv in status.values}
        assert values['Publishers'] == '2'
        assert values['Messages per publisher'] == ('/player_a 2000 (0 dropped); /player_b 1000 '
                                                    '(0 dropped)')
        assert values['Messages dropped before the node'] == '0'
        assert status.level >= b'\x01'


def test_bad_parameters_are_refused_in_process(context):
    for bad, words in (({'axes': 'x,w'}, "'axes'"), ({'chunk_size': 100}, 'chunk_size'),
                       ({'order_grid_start': 1.0, 'order_grid_stop': 0.5}, 'stop'),
                       ({'reference_warn_sigma': 20.0}, 'reference_error_sigma')):
        with pytest.raises(ParameterError, match=words):
            analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(**bad))
    # a reference that cannot be read is an unreadable input (exit code 3), as in every tool
    with pytest.raises(InputError, match='cannot be read'):
        analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
            reference_summary='/nonexistent/summary.json'))


def test_bad_parameter_exits_2_with_one_line():
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args',
                           '-p', 'gap_policy:=ignore'], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ))
    assert done.returncode == 2
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert lines[-1].startswith('noise_analyzer: error:'), done.stderr
    assert "'gap_policy'" in lines[-1], done.stderr
    assert 'Traceback' not in done.stderr


def test_a_reference_of_several_bags_is_chosen_by_reference_bag(context, tmp_path):
    from test_health import AXIS, write_summary

    two = write_summary(tmp_path / 'ref.json', [
        {'label': 'a', 'path': 'a', 'axes': {a: AXIS for a in 'xyz'}},
        {'label': 'b', 'path': 'b', 'axes': {a: AXIS for a in 'xyz'}}])
    # without it the node names its own parameter (was "choose one with bag")
    with pytest.raises(ParameterError, match='choose one with reference_bag'):
        analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
            reference_summary=str(two)))
    with pytest.raises(ParameterError, match="reference_bag 'c' is not in reference summary"):
        analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
            reference_summary=str(two), reference_bag='c'))
    node = analyzer.NoiseAnalyzerNode(context=context, parameter_overrides=_overrides(
        reference_summary=str(two), reference_bag='b'))
    try:
        assert {r.source.rsplit(':', 2)[1] for r in node.engine.reference.values()} == {'b'}
    finally:
        node.destroy_node()
