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
Counting per publisher: the pure counters, the warning logic, and the GID taker against rclpy.

The recorder and the analyzer with two real publishers are in ``test_recorder.py`` and
``test_analyzer_node.py``.
"""

import time
import types

from gyro_noise_ros.link.sequence import PublisherCounts, SequenceGapCounter
from gyro_noise_ros.nodes._publishers import PublisherWatch
import numpy as np
import pytest

A, B = b'\x01' * 16, b'\x02' * 16


def test_two_interleaved_publishers_are_counted_apart():
    rng = np.random.default_rng(3)
    # Two publishers numbering 1..500 each, 7 messages of B lost, merged at random but each in
    # its own order (DDS delivers a writer's messages in order).
    a = [(A, s) for s in range(1, 501)]
    b = [(B, s) for s in range(1, 501) if s not in (100, 101, 102, 300, 301, 302, 303)]
    from_a = np.zeros(len(a) + len(b), bool)
    from_a[rng.choice(from_a.size, len(a), replace=False)] = True
    ia, ib = iter(a), iter(b)
    stream = [next(ia) if f else next(ib) for f in from_a]
    counts = PublisherCounts()
    for start in range(0, len(stream), 37):  # batches as the drain takes them
        part = stream[start:start + 37]
        counts.update([g for g, _ in part], [s for _, s in part])
    assert {g: (n, d) for g, n, d in counts.table()} == {A: (500, 0), B: (493, 7)}
    assert counts.publishers() == [stream[0][0], B if stream[0][0] == A else A]
    assert counts.messages == 993 and counts.missing == 7
    # One counter for both streams (what the nodes did before): the interleaved numbers look like
    # gaps that are not there.
    mixed = SequenceGapCounter()
    mixed.update([s for _, s in stream])
    assert mixed.missing != 7


def test_unknown_writer_and_single_publisher_fast_path():
    counts = PublisherCounts()
    assert counts.update(None, [1, 2, 4]) == [None]
    assert counts.update([A, A], [10, 11]) == [A]
    assert counts.update(np.array([B, A], dtype='V16'), [1, 12]) == [B, A]
    assert counts.table() == [(None, 3, 1), (A, 3, 0), (B, 1, 0)]
    assert counts.update([], []) == []


class _Graph:
    """Stand-in for a node: get_publishers_info_by_topic with fixed answers."""

    def __init__(self, **names):
        self.infos = [types.SimpleNamespace(node_namespace=ns, node_name=n, endpoint_gid=list(g))
                      for g, (ns, n) in names.items()]

    def get_publishers_info_by_topic(self, topic):
        return self.infos


def test_a_second_publisher_warns_a_replacement_informs():
    graph = _Graph()
    graph.infos = [types.SimpleNamespace(node_namespace='/', node_name='driver',
                                         endpoint_gid=list(A)),
                   types.SimpleNamespace(node_namespace='/robot2', node_name='driver',
                                         endpoint_gid=list(B))]
    watch = PublisherWatch('/imu/data_raw', 'mixed', overlap_s=2.0)
    watch.update([A, A], [1, 2], now_s=10.0)
    assert watch.check(graph) == [('info', 'receiving /imu/data_raw from /driver')]
    watch.update([A], [3], now_s=11.0)
    assert watch.check(graph) == []
    # B starts while A delivered 0.5 s ago: a second publisher.
    watch.update([B, A], [1, 4], now_s=11.5)
    assert watch.check(graph) == [('warn', 'another publisher on /imu/data_raw: /robot2/driver '
                                   '(besides /driver); mixed')]
    assert sorted(watch.active(11.5)) == [A, B]
    assert watch.active(14.0) == []
    assert watch.summary() == '/driver 4 (0 dropped); /robot2/driver 1 (0 dropped)'
    # A restarted driver: a new writer GID after the old one fell silent: information only.
    C = b'\x03' * 16
    graph.infos.append(types.SimpleNamespace(node_namespace='/', node_name='driver',
                                             endpoint_gid=list(C)))
    watch.update([C], [1], now_s=20.0)
    (severity, line), = watch.check(graph)
    assert severity == 'info' and line.startswith('new publisher on /imu/data_raw: /driver (03')
    # Two writers of one name are told apart by their GIDs.
    assert watch.name(A) == '/driver (010101010101)'


@pytest.mark.ros
@pytest.mark.timeout(60)
def test_gid_taker_equals_rclpy_take_and_names_the_writers(context):
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    from gyro_noise_ros.nodes._publishers import publisher_names, RawTaker

    node = rclpy.create_node('taker_test', context=context)
    other = rclpy.create_node('second', namespace='/robot2', context=context)
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    pubs = [node.create_publisher(String, '/chatter', qos),
            other.create_publisher(String, '/chatter', qos)]
    sub_gid = node.create_subscription(String, '/chatter', lambda m: None, qos, raw=True)
    sub_rclpy = node.create_subscription(String, '/chatter', lambda m: None, qos, raw=True)
    taker = RawTaker(sub_gid, String)
    try:
        assert taker.with_gid
        deadline = time.monotonic() + 20
        while any(p.get_subscription_count() < 2 for p in pubs):
            assert time.monotonic() < deadline
            time.sleep(0.05)
        sent = []
        for i in range(300):
            k = i % 3 == 0  # one in three from the second publisher
            pubs[k].publish(String(data=f'{k}:{i}'))
            sent.append(k)
        time.sleep(0.5)
        # In bounded batches (a backlog), the same messages in the same order as all at once.
        parts = [taker.take(128) for _ in range(3)]
        assert [len(p[0]) for p in parts] == [128, 128, 44] and taker.take(128)[0] == []
        raws, received, sequence = (sum((p[i] for p in parts), []) for i in range(3))
        gids = np.concatenate([p[3] for p in parts])
        expected = []
        with sub_rclpy.handle:
            while (item := sub_rclpy.handle.take_message(String, True)) is not None:
                expected.append(item)
        names = publisher_names(node, '/chatter')
    finally:
        taker.close()
        node.destroy_node()
        other.destroy_node()
    # The same bytes and sequence numbers as rclpy's take_message of a twin subscription, and
    # receive times within a second of the twin's (two readers of one process; a field read at
    # the wrong offset would be a sequence number or a pointer, far from the clock).
    assert raws == [raw for raw, _ in expected] and len(raws) == 300
    assert sequence == [info['publication_sequence_number'] for _, info in expected]
    twin = np.array([info['received_timestamp'] for _, info in expected])
    assert np.abs(np.array(received) - twin).max() < 1_000_000_000
    # And the writer of each: the graph's endpoint GIDs, named.
    assert sorted(set(names.values())) == ['/robot2/second', '/taker_test']
    by_name = {v: k for k, v in names.items()}
    want = [by_name['/robot2/second' if k else '/taker_test'] for k in sent]
    # Per writer in publication order (DDS keeps each writer's order; readers may interleave).
    gids = [bytes(g) for g in gids]
    for gid in by_name.values():
        assert [s for s, g in zip(sequence, gids) if g == gid] == list(
            range(1, 1 + want.count(gid)))
    assert sorted(gids) == sorted(want)
