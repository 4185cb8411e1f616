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
Property-based fuzzing of the link decoder (hypothesis): whatever the bytes, feed() never raises.

Every valid frame is recovered; counters are exact against what was injected.

The expected counters come from a plain-Python twin of the counter rules (gap = (seq - prev) mod
2**32
- 1, backward jumps and duplicates excluded), not from the decoder.
"""

from gyro_noise_ros.link import protocol as p, scan
from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np

SETTINGS = {'deadline': None, 'max_examples': 150, 'database': None,
            'suppress_health_check': [HealthCheck.too_slow]}


def expected_counts(seqs, flags):
    """Twin of the decoder's counter rules over the delivered sample sequence."""
    lost = flagged = 0
    prev = None
    for seq, flag in zip(seqs, flags):
        if prev is not None:
            gap = (seq - prev) % 2 ** 32
            if 0 < gap < 2 ** 31:
                lost += gap - 1
                if flag & p.FLAG_SAMPLE_LOST:
                    flagged += gap - 1
        prev = seq
    return lost, flagged


@st.composite
def frame_streams(draw, max_frames=8):
    """
    Draw a list of (frame bytes, samples) with increasing seq (random gaps).

    The seq starts anywhere and may wrap.
    """
    start = draw(st.one_of(st.integers(0, 2 ** 32 - 1), st.integers(2 ** 32 - 300, 2 ** 32 - 1)))
    nframes = draw(st.integers(1, max_frames))
    frames = []
    seq = start
    for _ in range(nframes):
        if draw(st.integers(0, 5)) == 0:
            ack = p.Ack(command_id=draw(st.integers(0, 2 ** 32 - 1)), ok=draw(st.booleans()),
                        odr_hz=6667.0, gyro_fs_dps=2000, accel_fs_g=4,
                        message=draw(st.text('abc xyz', max_size=10)),
                        status=draw(st.integers(0, 255)))
            frames.append((p.encode_ack(ack), None))
            continue
        n = draw(st.integers(1, 6))
        s = np.zeros(n, p.SAMPLE_DTYPE)
        seqs = []
        for _ in range(n):
            seqs.append(seq % 2 ** 32)
            seq += 1 + draw(st.sampled_from([0, 0, 0, 1, 7]))
        s['seq'] = seqs
        s['t_us'] = draw(st.integers(0, 2 ** 32 - 1))
        # payload bytes from hypothesis: may contain A5 5A and other header look-alikes
        s['gyro'] = np.array(draw(st.lists(st.integers(-32768, 32767), min_size=3 * n, max_size=3
                                           * n))).reshape(n, 3)
        s['flags'] = draw(st.lists(st.sampled_from([0, 0, p.FLAG_SAMPLE_LOST, p.FLAG_FIFO_OVERRUN,
                                                    3]), min_size=n, max_size=n))
        frames.append((p.encode_samples(s), s))
    return frames


def decode_all(chunks):
    dec = p.Decoder()
    results = [dec.feed(c) for c in chunks]
    results.append(dec.flush())
    samples = np.concatenate([r.samples for r in results])
    acks = [a for r in results for a in r.acks]
    return dec, samples, acks


def all_samples(frames):
    parts = [s for _, s in frames if s is not None]
    return np.concatenate(parts) if parts else np.zeros(0, p.SAMPLE_DTYPE)


@settings(**SETTINGS)
@given(st.binary(max_size=3000))
def test_random_bytes_never_raise_and_bytes_add_up(data):
    dec = p.Decoder()
    res = dec.feed(data)
    fin = dec.flush()
    stats = dec.stats
    assert stats.bytes_total == len(data)
    # every byte is either in a valid frame or discarded; random bytes make no valid frame
    assert stats.frames_ok == 0 and stats.bytes_discarded == len(data)
    assert res.samples.size == fin.samples.size == 0
    assert stats.resyncs == (1 if data else 0)


@settings(**SETTINGS)
@given(frame_streams(), st.data())
def test_split_into_random_pieces_recovers_everything(frames, data):
    stream = b''.join(f for f, _ in frames)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=12)))
    pieces = [stream[a:b] for a, b in zip([0] + cuts, cuts + [len(stream)])]
    dec, samples, acks = decode_all(pieces)
    expected = all_samples(frames)
    assert np.array_equal(samples, expected)
    assert len(acks) == sum(1 for _, s in frames if s is None)
    st_ = dec.stats
    lost, flagged = expected_counts(expected['seq'].tolist(), expected['flags'].tolist())
    assert (st_.samples_lost, st_.samples_flagged_lost) == (lost, flagged)
    assert (
        st_.frames_ok, st_.crc_errors, st_.bytes_discarded, st_.resyncs) == (len(frames), 0, 0, 0)


@settings(**SETTINGS)
@given(frame_streams(), st.data())
def test_garbage_between_frames_is_discarded_exactly(frames, data):
    pieces, garbage_total, segments = [], 0, 0
    for frame, _ in frames:
        junk = data.draw(st.binary(max_size=60))
        pieces += [junk, frame]
        garbage_total += len(junk)
        segments += bool(junk)
    tail = data.draw(st.binary(max_size=60))
    pieces.append(tail)
    garbage_total += len(tail)
    segments += bool(tail)
    dec, samples, _ = decode_all([b''.join(pieces)])
    assert np.array_equal(samples, all_samples(frames))
    assert dec.stats.bytes_discarded == garbage_total
    assert dec.stats.resyncs == segments
    assert dec.stats.frames_ok == len(frames)


@settings(**SETTINGS)
@given(frame_streams(), st.data())
def test_garbage_without_sync_byte_gives_no_crc_error(frames, data):
    no_sync = st.binary(max_size=40).map(lambda b: b.replace(b'\xa5', b'\x00'))
    stream = b''.join(data.draw(no_sync) + f for f, _ in frames)
    dec, samples, _ = decode_all([stream])
    assert np.array_equal(samples, all_samples(frames))
    assert dec.stats.crc_errors == 0


@settings(deadline=None, max_examples=40, database=None)
@given(frame_streams(max_frames=4))
def test_truncation_at_every_byte(frames):
    stream = b''.join(f for f, _ in frames)
    ends = np.cumsum([len(f) for f, _ in frames])
    for cut in range(len(stream) + 1):
        complete = int(np.searchsorted(ends, cut, side='right'))
        dec, samples, _ = decode_all([stream[:cut]])
        assert np.array_equal(samples, all_samples(frames[:complete]))
        kept = int(ends[complete - 1]) if complete else 0
        assert dec.stats.bytes_discarded == cut - kept
        # a cut frame of two bytes or more starts with a valid sync and header prefix: counted as
        # truncated
        if cut - kept >= 2:
            assert dec.stats.frames_truncated >= 1
        else:
            assert dec.stats.frames_truncated == 0


@settings(**SETTINGS)
@given(frame_streams(max_frames=6), st.data())
def test_single_bit_flip_loses_exactly_that_frame(frames, data):
    victim = data.draw(st.integers(0, len(frames) - 1))
    frame = bytearray(frames[victim][0])
    bit = data.draw(st.integers(0, 8 * len(frame) - 1))
    frame[bit // 8] ^= 1 << (bit % 8)
    stream = b''.join(bytes(frame) if i == victim else f for i, (f, _) in enumerate(frames))
    dec, samples, _ = decode_all([stream[i:i + 37] for i in range(0, len(stream), 37)])
    survivors = [(f, s) for i, (f, s) in enumerate(frames) if i != victim]
    expected = all_samples(survivors)
    assert np.array_equal(samples, expected)
    stats = dec.stats
    assert stats.bytes_discarded == len(frame)
    assert stats.resyncs == 1
    assert stats.frames_ok == len(frames) - 1
    lost, flagged = expected_counts(expected['seq'].tolist(), expected['flags'].tolist())
    assert (stats.samples_lost, stats.samples_flagged_lost) == (lost, flagged)


@settings(**SETTINGS)
@given(
    st.integers(2 ** 32 - 2000, 2 ** 32 - 1), st.lists(st.booleans(), min_size=50, max_size=400),
    st.lists(st.booleans(), min_size=50, max_size=400))
def test_counter_wrap_with_injected_drops_is_counted_exactly(start, keep_mask, flag_mask):
    n = len(keep_mask)
    seqs = (start + np.arange(n, dtype=np.uint64)) % 2 ** 32
    keep = np.array(keep_mask)
    keep[0] = keep[-1] = True  # losses are visible only between two delivered samples
    s = np.zeros(n, p.SAMPLE_DTYPE)
    s['seq'] = seqs
    flags = np.zeros(n, np.uint8)
    fm = np.resize(np.array(flag_mask), n)
    flags[fm] = p.FLAG_SAMPLE_LOST
    s['flags'] = flags
    sent = s[keep]
    dec, samples, _ = decode_all([p.encode_samples(sent[i:i + 16])
                                  for i in range(0, sent.size, 16)])
    assert np.array_equal(samples, sent)
    assert dec.stats.samples_lost == int(n - keep.sum())
    lost, flagged = expected_counts(sent['seq'].tolist(), sent['flags'].tolist())
    assert dec.stats.samples_flagged_lost == flagged
    assert lost == dec.stats.samples_lost


@settings(**SETTINGS)
@given(st.integers(1, 40), st.integers(4, 30), st.data())
def test_runs_of_equal_frames_with_one_flip_and_an_ack(per_frame, nframes, data):
    """Long runs of same-size frames (the decoder's bulk path) broken by a bit flip and an ACK."""
    start = data.draw(st.integers(0, 2 ** 32 - 1))
    s = np.zeros(per_frame * nframes, p.SAMPLE_DTYPE)
    s['seq'] = (start + np.arange(s.size, dtype=np.uint64)) % 2 ** 32
    s['gyro'] = data.draw(st.integers(-32768, 32767))
    frames = [(p.encode_samples(s[i:i + per_frame]), s[i:i + per_frame])
              for i in range(0, s.size, per_frame)]
    ack_at = data.draw(st.integers(0, nframes))
    frames.insert(ack_at, (p.encode_ack(p.Ack(1, True, 6667.0, 2000, 4)), None))
    victim = data.draw(st.integers(0, len(frames) - 1))
    frame = bytearray(frames[victim][0])
    bit = data.draw(st.integers(0, 8 * len(frame) - 1))
    frame[bit // 8] ^= 1 << (bit % 8)
    stream = b''.join(bytes(frame) if i == victim else f for i, (f, _) in enumerate(frames))
    piece = data.draw(st.sampled_from([7, 100, 4096, len(stream)]))
    dec, samples, acks = decode_all([stream[i:i + piece] for i in range(0, len(stream), piece)])
    survivors = [(f, x) for i, (f, x) in enumerate(frames) if i != victim]
    assert np.array_equal(samples, all_samples(survivors))
    assert len(acks) == (0 if frames[victim][1] is None else 1)
    assert dec.stats.bytes_discarded == len(frame) and dec.stats.resyncs == 1
    assert dec.stats.frames_ok == len(frames) - 1


@settings(**SETTINGS)
@given(st.integers(0, 2 ** 32 - 1),
       st.lists(st.tuples(st.integers(1, 20), st.sampled_from([1, 1, 1, 1, 0, 2, 3, -5, -10 ** 6]),
                          st.sampled_from([0, 0, 0, p.FLAG_SAMPLE_LOST, p.FLAG_FIFO_OVERRUN])),
                min_size=1, max_size=30))
def test_the_in_order_fast_path_accounts_as_the_general_path(start, batches):
    """Batches of in-order, repeated, skipped and restarted counters, flagged or not."""
    fast, general = p.Decoder(), p.Decoder()
    seq = start
    for size, step, flag in batches:
        s = np.zeros(size, p.SAMPLE_DTYPE)
        s['seq'] = (seq + step + np.arange(size, dtype=np.int64)) % 2 ** 32
        s['flags'][size // 2:size // 2 + 1] = flag
        seq = (seq + step + size - 1) % 2 ** 32
        got = fast._account_samples(s.copy(), (0, size), ())
        want = general._account_general(s.copy(), (0, size), ())
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
        assert got[1].dtype == want[1].dtype and got[2:] == want[2:]
        assert fast.counters() == general.counters() and fast.last_seq == general.last_seq


class _GeneralOnly(p.Decoder):
    """The decoder without its one-frame path: every read goes through ``_run``."""

    def _one_frame(self, data):
        return None


def _same_result(got, want):
    for name in ('samples', 'lost_before'):
        a, b = getattr(got, name), getattr(want, name)
        assert a.dtype == b.dtype and np.array_equal(a, b)
    for name in ('acks', 'ack_positions', 'commands', 'headers', 'header_positions', 'discarded'):
        assert getattr(got, name) == getattr(want, name)


@settings(**SETTINGS)
@given(frame_streams(), st.data())
def test_the_one_frame_path_decodes_as_the_general_path(frames, data):
    """Reads of whole frames (the path's case), pieces, garbage and flipped bits, in any mix."""
    stream = []
    for frame, _ in frames:
        how = data.draw(st.sampled_from(['whole', 'whole', 'whole', 'split', 'flip', 'junk']))
        if how == 'split':
            cut = data.draw(st.integers(1, len(frame) - 1))
            stream += [frame[:cut], frame[cut:]]
        elif how == 'flip':
            i = data.draw(st.integers(0, len(frame) - 1))
            stream.append(frame[:i] + bytes([frame[i] ^ 0x10]) + frame[i + 1:])
        elif how == 'junk':
            stream += [data.draw(st.binary(min_size=1, max_size=12)), frame]
        else:
            stream.append(frame)
    for cls in (p.Decoder, scan.ScanDecoder):
        fast, general = cls(), type('General', (_GeneralOnly, cls), {})()
        for chunk in stream + [bytearray(frames[0][0]), memoryview(frames[0][0])]:
            _same_result(fast.feed(chunk), general.feed(chunk))
            assert fast.counters() == general.counters() and fast.buffered == general.buffered
        _same_result(fast.flush(), general.flush())
        assert fast.counters() == general.counters()


def test_the_one_frame_path_takes_a_whole_frame_and_nothing_else():
    """It decodes a lone valid frame; a frame after buffered bytes goes the general way."""
    s = np.zeros(3, p.SAMPLE_DTYPE)
    s['seq'] = [5, 6, 7]
    frame = p.encode_samples(s)
    dec = p.Decoder()
    assert dec._one_frame(frame) is not None
    assert dec._one_frame(frame[:-1]) is None and dec._one_frame(frame + b'\0') is None
    assert dec._one_frame(frame[:-1] + bytes([frame[-1] ^ 1])) is None
    ack = p.Ack(command_id=1, ok=True, odr_hz=6667.0, gyro_fs_dps=2000, accel_fs_g=4,
                message='', status=0)
    assert dec._one_frame(p.encode_ack(ack)) is None
