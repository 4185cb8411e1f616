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
ROS-free tests of the pure pieces the nodes call: counters, link verdict, items, monitor lines.

These live outside the node modules so they run without ROS; the node tests still run them end
to end.
"""

from dataclasses import fields
import time
from types import SimpleNamespace

from gyro_noise_ros.app.live import LiveAnalysis, parse_axes, TemperatureTrack
from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.engine import EngineConfig
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.core.health import HealthThresholds
from gyro_noise_ros.core.items import allan_items, ALLAN_KEYS, fmt
from gyro_noise_ros.core.readout import read_allan
from gyro_noise_ros.errors import LinkError, ParameterError
from gyro_noise_ros.link import protocol as P
from gyro_noise_ros.link.health import judge_link, LinkTask, LinkThresholds, LinkWindow
from gyro_noise_ros.link.port import hardware_id_for, validate_port
from gyro_noise_ros.link.sequence import SequenceGapCounter, SequenceTracker
from gyro_noise_ros.link.session import handshake, LinkConfig, ODR_TOLERANCE_RATIO
from gyro_noise_ros.monitor_lines import format_array, format_status, parse_axis_parts
from gyro_noise_ros.msgs import imu_covariances, temperature_variances
import numpy as np
import pytest


def test_tracker_counts_gaps_across_wrap():
    t = SequenceTracker(restart_window=100)
    d = t.accept(np.array([2**32 - 3, 2**32 - 2], np.uint32))
    assert d.keep.all() and d.lost == 0 and d.stop == 2
    # ... 2**32-1 and 0 missing, then 1, 2, gap of 3..4, then 5
    d = t.accept(np.array([1, 2, 5], np.uint32))
    assert d.keep.all() and d.lost == 2 + 2 and t.last == 5


def test_tracker_consecutive_batch_across_wrap():
    t = SequenceTracker(restart_window=100)
    t.accept(np.array([2**32 - 5], np.uint32))
    d = t.accept(np.array([2**32 - 2, 2**32 - 1, 0, 1], np.uint32))
    assert d.keep.all() and d.lost == 2 and t.last == 1


def _reference_tracker(batches, window):
    """Per-sample twin of SequenceTracker: (label per sample, total lost)."""
    last, labels, lost = None, [], 0
    for s in (int(v) for batch in batches for v in batch):
        if last is None:
            labels.append('keep')
            last = s
            continue
        d = (s - last) % 2**32
        d = d - 2**32 if d >= 2**31 else d
        if d > 0:
            labels.append('keep')
            lost += d - 1
            last = s
        elif d > -window:
            labels.append('dup')
        else:
            labels.append('restart')
            last = s
    return labels, lost


def test_tracker_matches_its_per_sample_twin():
    rng = np.random.default_rng(7)
    wholes = 0
    for _ in range(300):
        # Runs of consecutive counters near the wrap, joined by a step of +1, a gap, a re-send
        # (back by 0..39, or 99: within the window of 100) or a restart (back by 100 or 200..4999).
        seq, s = [], int(rng.integers(2**32 - 300, 2**32))
        for _ in range(int(rng.integers(1, 8))):
            step = [1, int(rng.integers(2, 50)), -int(rng.integers(0, 40)), -99, -100,
                    -int(rng.integers(200, 5000))]
            s = (s + step[int(rng.integers(len(step)))]) % 2**32
            run = int(rng.integers(1, 30))
            seq += [(s + k) % 2**32 for k in range(run)]
            s = (s + run - 1) % 2**32
        cuts = np.sort(rng.choice(np.arange(1, len(seq)), size=min(3, len(seq) - 1),
                                  replace=False))
        batches = np.split(np.array(seq, np.uint32), cuts)

        tracker, labels, lost, restart_next = SequenceTracker(restart_window=100), [], 0, False
        for batch in batches:
            while len(batch):
                d = tracker.accept(batch)
                # whole: the driver publishes the batch as it is (no indexing)
                assert not d.whole or (d.stop == len(batch) and d.keep.all())
                wholes += d.whole
                part = ['keep' if k else 'dup' for k in d.keep]
                if restart_next and part:
                    part[0], restart_next = 'restart', False
                labels += part
                lost += d.lost
                batch = batch[d.stop:]
                if len(batch):  # what the driver does at a restart
                    tracker.reset()
                    restart_next = True
        assert (labels, lost) == _reference_tracker(batches, 100), seq
    assert wholes > 100  # the usual batches are decided whole


def test_tracker_drops_resent_samples_and_splits_at_restart():
    t = SequenceTracker(restart_window=100)
    t.accept(np.arange(1000, 1010, dtype=np.uint32))
    d = t.accept(np.array([1005, 1006, 1009, 1010, 1012, 1011], np.uint32))
    assert d.keep.tolist() == [False, False, False, True, True, False]
    assert d.duplicates == 4 and d.lost == 1 and d.stop == 6
    # A fall-back of 100 or more is a board restart: decide the prefix, stop at the restart.
    d = t.accept(np.array([1013, 3, 4], np.uint32))
    assert d.stop == 1 and d.keep.tolist() == [True] and d.lost == 0


# --------------------------------------------------------------------------- message content


def test_sequence_gap_counter():
    c = SequenceGapCounter()
    assert c.update([1, 2, 3]) == 0
    assert c.update([5, 6]) == 1          # 4 missing
    assert c.update([0, 0]) == 0          # no sequence numbers from the RMW: ignored
    assert c.update([10, 11, 15]) == 6    # 7, 8, 9 and 12, 13, 14
    assert c.update([1, 2]) == 0          # restarted publisher: a new run
    assert c.missing == 7


def test_sequence_gap_counter_short_lists_count_as_arrays():
    # Short lists take a plain loop, arrays the vectorised path: the same counts, batch by batch.
    rng = np.random.default_rng(5)
    seq = np.cumsum(rng.choice([1, 1, 1, 2, 5, -40], size=3000)) + 50
    seq[rng.random(seq.size) < 0.02] = 0
    loop, vector = SequenceGapCounter(), SequenceGapCounter()
    start = 0
    while start < seq.size:
        stop = start + int(rng.integers(1, 40))
        assert loop.update(seq[start:stop].tolist()) == vector.update(seq[start:stop])
        start = stop
    assert loop.missing == vector.missing > 0 and loop.last == vector.last


def test_imu_covariances_read_back_what_was_encoded():
    from gyro_noise_ros.msgs import encode_imu_cdr

    rng = np.random.default_rng(0)
    av = rng.random((4, 9))
    la = rng.random((4, 9))
    raws = encode_imu_cdr(np.arange(4), rng.random((4, 3)), rng.random((4, 3)), frame_id='f',
                          angular_velocity_covariance=av, linear_acceleration_covariance=la)
    got_av, got_la = imu_covariances(raws)
    np.testing.assert_array_equal(got_av, av)
    np.testing.assert_array_equal(got_la, la)
    # Mixed lengths (two frame_ids) take the per-message path.
    raws2 = raws[:2] + encode_imu_cdr(np.arange(2), rng.random((2, 3)), rng.random((2, 3)),
                                      frame_id='longer_frame', angular_velocity_covariance=av[2:],
                                      linear_acceleration_covariance=la[2:])
    got_av, got_la = imu_covariances(raws2)
    np.testing.assert_array_equal(got_av, av)
    np.testing.assert_array_equal(got_la, la)


def test_temperature_variances_read_back_what_was_encoded():
    from gyro_noise_ros.msgs import encode_temperature_cdr

    raws = encode_temperature_cdr(np.arange(3), [20.0, 21.0, 22.0], frame_id='imu',
                                  variance=[0.5, 0.25, 0.0])
    np.testing.assert_array_equal(temperature_variances(raws), [0.5, 0.25, 0.0])


def test_tracker_counts_a_one_sample_batch_seen_twice():
    t = SequenceTracker(restart_window=100)
    seq = np.array([7], np.uint32)
    assert t.accept(seq).keep.tolist() == [True]
    again = t.accept(seq)
    assert again.keep.tolist() == [False] and again.duplicates == 1 and again.lost == 0


def test_parse_axes():
    assert parse_axes('x,y,z') == ('x', 'y', 'z')
    assert parse_axes('z') == ('z',)
    assert parse_axes('xz') == ('x', 'z')
    for bad in ('', 'x,x', 'q', 'x;y'):
        with pytest.raises(ParameterError):
            parse_axes(bad)


def test_allan_items_keep_their_keys():
    items = allan_items(None)
    assert tuple(k for k, _ in items) == ALLAN_KEYS and all('(' in k for k in ALLAN_KEYS)
    assert {v for _, v in items} == {'n/a'}


def test_allan_items_are_the_readout():
    # White rate noise for 400 s at 100 Hz: the items show the one readout's numbers, the bias
    # stability marked as an upper bound at the last tau it reads (a tenth of the record: white
    # noise keeps falling to the longest tau).
    rate = 100.0
    result = allan_deviation(np.random.default_rng(4).normal(0.0, 0.01, 40_000), rate)
    r = read_allan(result)
    items = dict(allan_items(SimpleNamespace(readout=r)))
    assert items['ADEV at 1 s (deg/s)'] == fmt(r.adev_1s_rad_s * 180.0 / np.pi)
    assert r.bias_stability_upper_bound
    assert items['Bias stability (deg/s)'] == '<=' + fmt(r.bias_stability_rad_s * 180.0 / np.pi)
    assert items['Bias stability tau (s)'] == fmt(result.tau_s[result.tau_s <= 40.0][-1])
    assert items['Angle random walk (deg/sqrt(h))'] == fmt(
        r.arw_rad_per_sqrt_s * 180.0 / np.pi * 60.0)
    assert dict(allan_items(SimpleNamespace(readout=None))) == dict(allan_items(None))


def test_fmt():
    assert fmt(None) == 'nan' and fmt(float('inf')) == 'nan' and fmt(3) == '3'
    assert fmt(1.23456, 3) == '1.23'


def test_every_threshold_has_one_documented_source():
    for cls in (HealthThresholds, LinkThresholds):
        for f in fields(cls):
            assert f.metadata.get('description', '').strip(), f'{cls.__name__}.{f.name}'


def _window(**kw):
    base = {'state': 'streaming', 'window_s': 1.0, 'published': 1000, 'odr_hz': 1000.0,
            'frames_ok': 100, 'samples_ok': 1000, 'silence_limit_s': 1.0}
    base.update(kw)
    return LinkWindow(**base)


def test_link_verdict_levels():
    assert judge_link(_window()).level == 'OK'
    down = judge_link(_window(state='disconnected', last_error='cannot open'))
    assert (down.level, down.message) == ('ERROR', 'Link down: cannot open.')
    # 1 lost in 1000: above loss_warn_ratio 0, below loss_error_ratio 0.01.
    assert judge_link(_window(published=999, lost=1)).level == 'WARN'
    assert judge_link(_window(published=900, lost=100)).level == 'ERROR'
    assert judge_link(_window(crc_errors=1)).level == 'WARN'
    # 5 % fewer samples than the ODR: outside 2 % + two 10-sample frames.
    slow = judge_link(_window(published=950))
    assert slow.level == 'WARN' and 'Sample rate' in slow.message
    # 1.5 % off stays inside the tolerance.
    assert judge_link(_window(published=985)).level == 'OK'
    assert judge_link(_window(seconds_since_sample=2.0)).level == 'ERROR'
    both = judge_link(_window(published=900, lost=100, crc_errors=3))
    assert [lvl for lvl, _ in both.checks] == ['ERROR', 'WARN'] and both.level == 'ERROR'


def test_link_thresholds_are_checked():
    with pytest.raises(ParameterError, match='loss_warn_ratio'):
        LinkThresholds(loss_warn_ratio=0.5, loss_error_ratio=0.1)


def _snapshot(published, lost, **kw):
    base = {'state': 'streaming', 'last_error': 'none', 'config': None, 'connections': 1,
            'streaming_since': 0.0, 'last_sample_monotonic': None, 'lifecycle': 'active',
            'activated_at': 0.0, 'published': published, 'lost': lost, 'restarts': 0,
            'duplicates': 0, 'discarded': 0, 'temperatures': 0, 'link': {'crc_errors': 0}}
    base.update(kw)
    return base


def test_link_task_judges_the_difference_since_the_previous_run():
    task = LinkTask(LinkThresholds(), port='tcp://x', period_s=1.0, now=0.0,
                    snapshot=_snapshot(0, 0))
    status = task.run(_snapshot(1000, 20), 1.0, drift_ppm=0.0)
    assert status.level == 'ERROR' and '20 samples lost in the last 1.0 s' in status.message
    values = dict(status.values)
    assert values['Samples lost'] == '20' and values['Sample rate (Hz)'] == '1000.0'
    # the next window has no new loss: the cumulative 20 no longer count
    status = task.run(_snapshot(2000, 20), 2.0, drift_ppm=0.0)
    assert (status.level, status.message) == ('OK', 'Streaming at 1000 Hz, no loss.')
    task.thresholds = LinkThresholds(loss_error_ratio=0.05)  # a runtime parameter change
    assert task.run(_snapshot(3000, 40), 3.0, drift_ppm=0.0).level == 'WARN'
    idle = _snapshot(3000, 40, lifecycle='unconfigured')
    status = task.run(idle, 4.0, drift_ppm=0.0)
    assert status.level == 'OK' and status.message.startswith('Unconfigured (lifecycle)')
    assert dict(status.values)['Connection'] == 'unconfigured' and idle['state'] == 'streaming'


def _status(name, level, message, **values):
    kvs = [SimpleNamespace(key=k, value=v) for k, v in values.items()]
    return SimpleNamespace(name=name, level=bytes([level]), message=message, values=kvs)


def test_format_status():
    status = _status('noise_analyzer: axis z', 1, 'Drift.',
                     **{'Bias (deg/s)': '0.5', 'Chunks analysed': '7'})
    assert format_status(status) == 'WARN  noise_analyzer: axis z: bias=0.5 chunks=7 | Drift.'


def test_format_array_reads_back_with_the_demo_parser():
    def axis(a, level, drift):
        return _status(f'noise_analyzer: axis {a}', level, f'{a} message',
                       **{'Last chunk': '12 (ok)', 'Bias (deg/s)': '0.1',
                          'Offset drift ((deg/s)/h)': drift, 'Samples lost': '0 (0)'})
    line = format_array([axis('x', 0, '0.01'), axis('y', 1, '6.5'), axis('z', 0, 'nan')])
    assert line.startswith('WARN  chunk   12 |') and line.endswith('-- axis y: y message')
    parts = parse_axis_parts(line)
    assert [(a, lvl) for a, lvl, _ in parts] == [('x', 'OK'), ('y', 'WARN'), ('z', 'OK')]
    assert parts[1][2] == 6.5 and np.isnan(parts[2][2])


def test_temperature_track_interpolates_and_holds():
    track = TemperatureTrack()
    assert track.at(np.array([0])) is None
    track.add(np.array([100]), np.array([20.0]))
    assert track.at(np.array([0, 500])) == 20.0
    track.add(np.array([300]), np.array([22.0]))
    np.testing.assert_allclose(track.at(np.array([100, 200, 300, 400])), [20.0, 21.0, 22.0, 22.0])


class _Port:
    """A serial port stand-in: records writes, returns scripted reads."""

    def __init__(self, reads):
        self.reads, self.written = list(reads), b''

    def write(self, data):
        self.written += data

    def read(self, size):
        return self.reads.pop(0) if self.reads else b''


def _ack_for(odr_hz, gyro=2000, accel=32, ok=True, command_id=1):
    return P.encode_ack(P.Ack(command_id, ok, odr_hz, gyro, accel, '', 0 if ok else P.NAK_BAD_ODR))


def _handshake(reads, odr_hz=6667.0, timeout=0.2):
    return handshake(_Port(reads), P.Decoder(), command_id=1, odr_hz=odr_hz, gyro_fs_dps=2000,
                     accel_fs_g=32, ack_timeout_s=timeout)


def test_handshake_sends_configure_and_takes_the_samples_after_the_ack():
    samples = np.zeros(3, P.SAMPLE_DTYPE)
    samples['seq'] = [7, 8, 9]
    before = np.zeros(2, P.SAMPLE_DTYPE)
    port = _Port([P.encode_samples(before) + _ack_for(6667.0) + P.encode_samples(samples)])
    config, after, _ = handshake(port, P.Decoder(), command_id=1, odr_hz=6667.0,
                                 gyro_fs_dps=2000, accel_fs_g=32, ack_timeout_s=1.0)
    assert config == LinkConfig(6667.0, 2000, 32)
    assert after['seq'].tolist() == [7, 8, 9]
    assert P.Decoder().feed(port.written).commands[0].odr_hz == 6667.0


def test_handshake_accepts_the_odr_within_the_tolerance_and_refuses_beyond():
    # The board accepts requests within 0.5 % of a datasheet rate and reports its own in the ACK.
    assert _handshake([_ack_for(6667.0 * (1 + 0.9 * ODR_TOLERANCE_RATIO))])[0].odr_hz > 6667.0
    with pytest.raises(LinkError, match='acknowledged odr'):
        _handshake([_ack_for(6667.0 * (1 + 1.1 * ODR_TOLERANCE_RATIO))])
    with pytest.raises(LinkError, match='acknowledged'):
        _handshake([_ack_for(6667.0, gyro=250)])


def test_handshake_nak_and_silence_are_link_errors():
    with pytest.raises(LinkError, match='refused'):
        _handshake([_ack_for(6667.0, ok=False)])
    with pytest.raises(LinkError, match='no acknowledgement'):
        _handshake([], timeout=0.05)


@pytest.mark.parametrize('port', ['', '  ', 'socket://127.0.0.1', 'socket://:5760',
                                  'socket://localhost:notaport', 'nosuchscheme://x'])
def test_unusable_ports_are_refused(port):
    with pytest.raises(ParameterError, match="'port'"):
        validate_port(port)


def test_usable_ports_pass():
    assert validate_port(' socket://127.0.0.1:5760 ') == 'socket://127.0.0.1:5760'
    assert validate_port('/dev/ttyACM0') == '/dev/ttyACM0'


def test_hardware_id_is_not_the_port_path():
    # No USB device behind a URL: the frame id names the sensor, the same for any port.
    ids = {hardware_id_for(p, 'imu_link') for p in ('socket://127.0.0.1:1', 'socket://h:2')}
    assert ids == {'lsm6dso32/portenta_h7/imu_link'}


def test_live_analysis_worker_finishes_chunks_and_skips_when_full():
    config = EngineConfig(chunk_size=200, axes=('x', 'z'), alphas=make_grid(0.0, 2.0, 0.5),
                          memory=20, rate_hz=100.0, allan=False)
    live = LiveAnalysis(config, queue_chunks=1)
    try:
        rng = np.random.default_rng(1)
        # 6 chunks of both axes; more than the engine's 1,025-sample timebase hold, which
        # releases nothing before it is full even with the rate configured.
        n = 1200
        stamps = np.arange(n, dtype=np.int64) * 10_000_000
        assert live.ingest(stamps, rng.standard_normal((n, 3))) == ''
        # A queue of one chunk (2 jobs) cannot take 12 jobs at once: the rest are skipped.
        results, chunks = [], []
        deadline = time.monotonic() + 30.0
        while len(results) < 12 and time.monotonic() < deadline:
            r, c = live.collect()
            results += r
            chunks += c
            time.sleep(0.01)
        assert len(results) == 12 and len(chunks) == 6
        statuses = [r.status for r in results]
        assert statuses.count('ok') >= 2 and statuses.count('ok') < 12
        assert all(set(c) == {'x', 'z'} for c in chunks)
        # A batch the engine refuses (gyro of the wrong shape) is reported, not raised.
        assert 'shape' in live.ingest(stamps[:10], np.zeros((10, 2)))
        assert live.rejected_batches == 1 and live.last_batch_rejected
    finally:
        live.stop()
