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
The compiled frame scanner (gyro_noise_ros.link.scan) against the byte-wise Decoder.

The oracle is the Decoder itself (``link/protocol.py``, the reference implementation of
``docs/portenta_link.md``): for the same bytes fed in the same pieces, the ScanDecoder must return
the same results call for call (samples, loss counts, acks, headers and their positions, discarded
regions) and the same counters. Streams carry every irregularity the scanner hands back to the
byte-wise rules: bit flips (CRC errors), junk with sync markers and plausible headers in it,
truncated frames, duplicated frames, non-sample frames, cuts at every piece boundary. The CRC is
checked against a bit-by-bit twin of the CRC-32 definition and the standard check value.
"""

import dataclasses
import os
import zlib

from gyro_noise_ros.app import importer as import_app
from gyro_noise_ros.cli import emulator as emu_cli
from gyro_noise_ros.cli import importer
from gyro_noise_ros.link import protocol as p
from gyro_noise_ros.link.scan import crc32_numba, ScanDecoder
from gyro_noise_ros.link.sdlog import SdLogReader
from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
import pytest

SETTINGS = {'deadline': None, 'max_examples': 200, 'database': None,
            'suppress_health_check': [HealthCheck.too_slow]}


def crc32_bitwise(data):
    """CRC-32/ISO-HDLC bit by bit from its definition (reflected poly 0xEDB88320)."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xEDB88320 if crc & 1 else crc >> 1
    return crc ^ 0xFFFFFFFF


def test_crc_matches_definition_and_zlib():
    assert crc32_numba(b'123456789') == 0xCBF43926
    rng = np.random.default_rng(4)
    for size in list(range(0, 40)) + [393, 3078, 100_000]:
        data = rng.integers(0, 256, size, dtype=np.uint8).tobytes()
        assert crc32_numba(data) == zlib.crc32(data)
        if size < 4000:
            assert crc32_numba(data) == crc32_bitwise(data)


def assert_same_result(a, b):
    assert a.samples.dtype == b.samples.dtype
    assert a.samples.tobytes() == b.samples.tobytes()
    assert np.array_equal(a.lost_before, b.lost_before)
    for name in ('acks', 'ack_positions', 'commands', 'headers', 'header_positions', 'discarded'):
        assert getattr(a, name) == getattr(b, name), name


def run_both(pieces, reset_at=()):
    """Feed the pieces to both decoders (reset_stream before the given indices); compare all."""
    decoders = (p.Decoder(), ScanDecoder())
    for i, piece in enumerate(pieces):
        if i in reset_at:
            results = [d.reset_stream() for d in decoders]
            assert_same_result(*results)
        results = [d.feed(piece) for d in decoders]
        assert_same_result(*results)
        assert decoders[0].stats == decoders[1].stats
        assert decoders[0].buffered == decoders[1].buffered
    results = [d.flush() for d in decoders]
    assert_same_result(*results)
    assert decoders[0].stats == decoders[1].stats
    assert decoders[0].last_seq == decoders[1].last_seq
    return decoders[0].stats


def samples(seq0, n, rng):
    s = np.zeros(n, p.SAMPLE_DTYPE)
    s['seq'] = (seq0 + np.arange(n)) % 2 ** 32
    s['t_us'] = (seq0 * 150 + 150 * np.arange(n)) % 2 ** 32
    s['gyro'] = rng.integers(-32768, 32768, (n, 3))
    s['accel'] = rng.integers(-32768, 32768, (n, 3))
    s['temp'] = rng.integers(-32768, 32768, n)
    s['flags'] = rng.choice([0, 0, 0, 1, 2, 3], n)
    return s


def corrupted_stream(seed, frames=400):
    """Return a log-like stream (bytes) with every kind of damage."""
    rng = np.random.default_rng(seed)
    parts = [p.encode_log_header(p.LogHeader(sequence_id=3, file_index=0, odr_hz=6667.0,
                                             gyro_fs_dps=500, accel_fs_g=8, first_seq=0, t_us=0,
                                             rtc_unix_s=0))]
    seq = 2 ** 32 - 500  # wraps inside the stream
    for i in range(frames):
        k = int(rng.choice([16, 16, 16, 1, 128, 7]))
        frame = p.encode_samples(samples(seq, k, rng))
        seq += k + int(rng.choice([0, 0, 0, 0, 3]))  # some gaps
        kind = rng.integers(0, 40)
        if kind == 0:  # bit flip: CRC error
            b = bytearray(frame)
            b[int(rng.integers(len(b)))] ^= 1 << int(rng.integers(8))
            frame = bytes(b)
        elif kind == 1:  # duplicated frame (duplicates dropped, counted)
            frame = frame + frame
        elif kind == 2:  # truncated frame followed by a good one
            frame = frame[:int(rng.integers(1, len(frame)))] + frame
        elif kind == 3:  # junk with sync markers and a plausible SAMPLES header inside
            frame = b'\xa5\x5a\x01\x01\x18\x00' + bytes(rng.integers(0, 256, 40, np.uint8)) \
                + b'\xa5' + frame
        elif kind == 4:  # a configuration change
            frame = p.encode_ack(p.Ack(command_id=i, ok=bool(rng.integers(2)), odr_hz=1667.0,
                                       gyro_fs_dps=250, accel_fs_g=8, message='', status=0)) \
                + frame
        elif kind == 5:  # a backward jump (board restart)
            seq = int(rng.integers(0, 1000))
        elif kind == 6:
            frame = frame + p.encode_configure(command_id=i, odr_hz=6667.0, gyro_fs_dps=500,
                                               accel_fs_g=8)
        parts.append(frame)
    parts.append(p.encode_samples(samples(seq, 16, rng))[:-5])  # power loss mid-frame
    return b''.join(parts)


@pytest.mark.parametrize('piece', [1, 7, 394, 4096, 1 << 20])
def test_scan_equals_decoder_on_a_damaged_stream(piece):
    data = corrupted_stream(seed=piece)
    pieces = [data[i:i + piece] for i in range(0, len(data), piece)]
    if piece == 1:
        pieces = pieces[:3000] + [b''.join(pieces[3000:])]  # keep the byte-by-byte part short
    stats = run_both(pieces, reset_at={len(pieces) // 2})
    # the stream exercised what it was built for
    assert stats.crc_errors and stats.duplicates and stats.resyncs and stats.frames_truncated
    assert stats.acks and stats.sequence_resets and stats.samples_lost and stats.commands


@st.composite
def damaged_streams(draw):
    """Draw valid frames, apply random small corruptions, cut the bytes into pieces."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    seq = draw(st.integers(0, 2 ** 32 - 1))
    frames = []
    for _ in range(draw(st.integers(1, 12))):
        kind = draw(st.integers(0, 9))
        if kind == 0:
            frames.append(p.encode_ack(p.Ack(command_id=1, ok=True, odr_hz=6667.0,
                                             gyro_fs_dps=2000, accel_fs_g=4, message='x',
                                             status=0)))
            continue
        k = draw(st.sampled_from([1, 2, 16, 128]))
        frames.append(p.encode_samples(samples(seq, k, rng)))
        seq += k + draw(st.sampled_from([0, 0, 0, 1, -1, -20]))
    data = bytearray(b''.join(frames))
    for _ in range(draw(st.integers(0, 6))):
        op = draw(st.integers(0, 4))
        pos = draw(st.integers(0, len(data)))
        if op == 0 and pos < len(data):  # bit flip
            data[pos] ^= 1 << draw(st.integers(0, 7))
        elif op == 1:  # junk, often sync-like
            data[pos:pos] = draw(st.sampled_from([b'\xa5', b'\xa5\x5a', b'\xa5\x5a\x01\x01',
                                                  b'\xa5\x5a\x01\x01\x18\x00', b'\x00\xff']))
        elif op == 2:  # delete a few bytes
            del data[pos:pos + draw(st.integers(1, 30))]
        elif op == 3:  # duplicate a stretch
            length = draw(st.integers(1, 500))
            data[pos:pos] = data[pos:pos + length]
        elif op == 4:  # cut
            del data[pos:]
    cuts = sorted(draw(st.lists(st.integers(0, len(data)), max_size=8)))
    return [bytes(data[a:b]) for a, b in zip([0] + cuts, cuts + [len(data)])]


@settings(**SETTINGS)
@given(damaged_streams())
def test_scan_equals_decoder_on_random_damage(pieces):
    run_both(pieces)


@settings(**SETTINGS)
@given(st.binary(max_size=2000), st.integers(1, 64))
def test_scan_equals_decoder_on_random_bytes(data, piece):
    run_both([data[i:i + piece] for i in range(0, len(data), piece)])


@pytest.fixture(scope='module')
def damaged_logs(tmp_path_factory):
    """SD logs of three files with bit flips, junk, truncated and duplicated frames."""
    out = tmp_path_factory.mktemp('sd')
    assert emu_cli.main(['--write-sd', str(out), '--samples', '40000', '--sd-file-bytes', '400000',
                         '--seed', '5', '--drop-flagged-rate', '0.001',
                         '--drop-unflagged-rate', '0.001', '--rtc-unix-s', '1700000000',
                         '--gyro-fs-dps', '500', '--accel-fs-g', '8']) == 0
    files = sorted(str(out / f) for f in os.listdir(out))
    assert len(files) >= 3
    rng = np.random.default_rng(9)
    for i, path in enumerate(files):
        data = bytearray(open(path, 'rb').read())
        for pos in rng.integers(100, len(data), 8):  # bit flips, one in the header of file 0
            data[pos] ^= 1 << int(rng.integers(8))
        frame = 394  # a 16-sample frame; the emulator writes them after the 38-byte header
        start = 38 + frame * 40
        assert data[start:start + 2] == b'\xa5\x5a' == data[start + frame:start + frame + 2]
        data[start:start] = data[start:start + 100]  # a truncated copy of a frame
        start = 38 + frame * 20
        data[start:start] = data[start:start + frame]  # a duplicated frame
        data[3000:3000] = b'\xa5\x5a\x01\x01\x30\x00' + bytes(range(50))  # junk, fake header
        if i == len(files) - 1:
            del data[-50:]  # power loss in the last frame
        with open(path, 'wb') as fh:
            fh.write(bytes(data))
    return files


def test_reader_blocks_and_report_equal_the_decoder_path(damaged_logs):
    out = {}
    for scan in (False, True):
        reader = SdLogReader(damaged_logs, chunk_bytes=5003, scan=scan)
        out[scan] = ([(b.path, b.samples.tobytes(), b.lost_before.tobytes(), b.odr_hz,
                       b.gyro_fs_dps, b.accel_fs_g) for b in reader], reader.report)
    assert out[True][0] == out[False][0]
    assert out[True][1] == out[False][1]
    stats = out[False][1].stats
    # a repeated frame reads as a backward seq jump (a restart), not as sample duplicates
    assert stats.crc_errors and stats.sequence_resets and stats.resyncs and stats.frames_truncated


def test_import_with_scanner_writes_the_same_bag_and_report(damaged_logs, tmp_path):
    reports, files = {}, {}
    for scan in (False, True):
        bag = tmp_path / str(scan) / 'bag'
        bag.parent.mkdir()
        reports[scan] = import_app.import_logs(damaged_logs, bag, scan=scan, chunk_bytes=4099)
        mcap = next(f for f in os.listdir(bag) if f.endswith('.mcap'))
        files[scan] = open(bag / mcap, 'rb').read()
    assert reports[True].corrupt_region_count > 3
    assert dataclasses.replace(reports[True], bag=reports[False].bag) == reports[False]
    assert importer.format_report(reports[True]).splitlines()[1:] \
        == importer.format_report(reports[False]).splitlines()[1:]
    assert files[True] == files[False]
