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

"""Wire protocol and LSM6DSO32 scaling against the documented layout and the datasheet numbers."""

import struct

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.link import lsm6dso32 as lsm
from gyro_noise_ros.link import protocol as p
import numpy as np
import pytest


def crc32_bitwise(data):
    """Compute CRC-32/IEEE bit by bit (reflected 0xEDB88320, init and xorout 0xFFFFFFFF)."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ (0xEDB88320 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


def hand_frame(frame_type, payload):
    """Frame built from the layout table of docs/portenta_link.md, independently of the encoder."""
    body = bytes([0xA5, 0x5A, 1, frame_type]) + struct.pack('<H', len(payload)) + payload
    return body + struct.pack('<I', crc32_bitwise(body))


def hand_sample(seq, t_us, gyro, accel, temp, flags):
    return struct.pack('<II3h3hhBB', seq, t_us, *gyro, *accel, temp, flags, 0)


# The worked example of docs/portenta_link.md, section "Worked example".
WORKED_EXAMPLE_HEX = ('a5 5a 01 01 18 00 2a 00 00 00 40 e2 01 00 0e 00 f6 ff 03 00 '
                      '1d 00 e8 ff 0c 20 00 02 00 00 4b 37 cf e1')


def test_crc_check_value():
    # the standard check value of CRC-32/ISO-HDLC (the zlib/Ethernet CRC)
    assert crc32_bitwise(b'123456789') == 0xCBF43926
    assert p.crc32(b'123456789') == 0xCBF43926


def test_worked_example_matches_layout_and_doc():
    sample = np.zeros(1, p.SAMPLE_DTYPE)
    sample['seq'] = 42
    sample['t_us'] = 123456
    sample['gyro'] = (14, -10, 3)
    sample['accel'] = (29, -24, 8204)
    sample['temp'] = 512
    encoded = p.encode_samples(sample)
    expected = hand_frame(
        p.FRAME_SAMPLES, hand_sample(42, 123456, (14, -10, 3), (29, -24, 8204), 512, 0))
    assert encoded == expected
    assert encoded.hex(' ') == WORKED_EXAMPLE_HEX
    res = p.Decoder().feed(bytes.fromhex(WORKED_EXAMPLE_HEX))
    assert res.samples['seq'].tolist() == [42]
    si = lsm.to_si(res.samples, gyro_fs_dps=2000, accel_fs_g=4)
    # 14 LSB * 70 mdps/LSB = 0.98 deg/s; 8204 * 0.122 mg = 1.000888 g; 25 + 512/256 = 27 degC
    assert si.gyro_rad_s[0, 0] == pytest.approx(np.radians(0.98), rel=1e-12)
    assert si.accel_m_s2[0, 2] == pytest.approx(1.000888 * 9.80665, rel=1e-12)
    assert si.temperature_c[0] == 27.0


def test_sample_dtype_is_24_packed_little_endian_bytes():
    assert p.SAMPLE_DTYPE.itemsize == 24
    assert [
        p.SAMPLE_DTYPE.fields[n][1] for n in ('seq', 't_us', 'gyro', 'accel', 'temp', 'flags')
    ] == [0, 4, 8, 14, 20, 22]


def test_configure_and_ack_layout():
    cmd = p.encode_configure(command_id=7, odr_hz=12.5, gyro_fs_dps=125, accel_fs_g=32)
    assert cmd == hand_frame(p.FRAME_CONFIGURE, struct.pack('<IIHBB', 7, 12500, 125, 32, 0))
    nak = p.Ack(command_id=7, ok=False, odr_hz=6667.0, gyro_fs_dps=2000, accel_fs_g=4,
                message='bad odr', status=p.NAK_BAD_ODR)
    assert p.encode_ack(nak) == hand_frame(p.FRAME_ACK,
                                           struct.pack('<IBBHI', 7, 1, 4, 2000, 6667000)
                                           + b'bad odr')
    res = p.Decoder().feed(cmd + p.encode_ack(nak))
    assert res.commands == (p.Configure(7, 12.5, 125, 32),)
    assert res.acks == (nak,)


def test_nak_without_status_is_sent_as_unspecified():
    ack = p.Ack(command_id=1, ok=False, odr_hz=6667.0, gyro_fs_dps=2000, accel_fs_g=4)
    back = p.Decoder().feed(p.encode_ack(ack)).acks[0]
    assert not back.ok and back.status == p.NAK_UNSPECIFIED


def test_log_header_round_trip():
    head = p.LogHeader(sequence_id=3, file_index=2, odr_hz=833.0, gyro_fs_dps=500, accel_fs_g=16,
                       first_seq=2 ** 32 - 1, t_us=99, rtc_unix_s=1_700_000_000)
    res = p.Decoder().feed(p.encode_log_header(head))
    assert res.headers == (head,)


def test_batches_split_at_max_samples_per_frame():
    samples = np.zeros(p.MAX_SAMPLES_PER_FRAME + 5, p.SAMPLE_DTYPE)
    samples['seq'] = np.arange(samples.size)
    dec = p.Decoder()
    res = dec.feed(p.encode_samples(samples))
    assert dec.stats.frames_ok == 2
    assert np.array_equal(res.samples, samples)


@pytest.mark.parametrize('length', [0, 23, 25, 24 * (p.MAX_SAMPLES_PER_FRAME + 1)])
def test_length_out_of_bounds_is_rejected_before_crc(length):
    bad = hand_frame(p.FRAME_SAMPLES, bytes(length))
    good = p.encode_samples(np.zeros(1, p.SAMPLE_DTYPE))
    dec = p.Decoder()
    res = dec.feed(bad + good)
    res2 = dec.flush()
    assert res.samples.size + res2.samples.size == 1
    st = dec.stats
    assert (st.crc_errors, st.bytes_discarded, st.resyncs, st.frames_ok) == (0, len(bad), 1, 1)


def test_wrong_version_and_unknown_type_are_rejected():
    for version, ftype in ((2, p.FRAME_SAMPLES), (1, 0x7F)):
        body = bytes([0xA5, 0x5A, version, ftype]) + struct.pack('<H', 24) + bytes(24)
        frame = body + struct.pack('<I', crc32_bitwise(body))
        dec = p.Decoder()
        dec.feed(frame)
        dec.flush()
        assert dec.stats.frames_ok == 0 and dec.stats.bytes_discarded == len(frame)


def _samples(seqs, flags=None):
    s = np.zeros(len(seqs), p.SAMPLE_DTYPE)
    s['seq'] = np.asarray(seqs, dtype=np.uint64) % 2 ** 32
    if flags is not None:
        s['flags'] = flags
    return s


def test_counter_gaps_across_wrap_flags_duplicates_and_resets():
    seqs = [2 ** 32 - 3, 2 ** 32 - 1, 0, 3, 3, 4, 10, 2]
    flags = [0, 0, 0, p.FLAG_SAMPLE_LOST, 0, p.FLAG_FIFO_OVERRUN, p.FLAG_SAMPLE_LOST, 0]
    dec = p.Decoder()
    res = dec.feed(p.encode_samples(_samples(seqs[:3], flags[:3])))
    res2 = dec.feed(p.encode_samples(_samples(seqs[3:], flags[3:])))
    lost = res.lost_before.tolist() + res2.lost_before.tolist()
    # 2**32-3 -> 2**32-1 skips one; -> 0 none; 0 -> 3 skips two; 3 duplicate dropped; 4 none; 10
    # skips 5; 2 is a backward jump (board restart): no loss
    assert lost == [0, 1, 0, 2, 0, 5, 0]
    st = dec.stats
    assert (st.samples_ok, st.samples_lost, st.samples_flagged_lost) == (7, 8, 7)
    assert (st.duplicates, st.sequence_resets, st.loss_flags, st.fifo_overruns) == (1, 1, 2, 1)


def test_ack_positions_locate_configuration_changes():
    ack = p.Ack(command_id=1, ok=True, odr_hz=6667.0, gyro_fs_dps=250, accel_fs_g=8)
    data = p.encode_samples(_samples([0, 1,
                                      2])) + p.encode_ack(ack) + p.encode_samples(_samples([3]))
    res = p.Decoder().feed(data)
    assert res.ack_positions == (3,)
    assert res.samples.size == 4


def test_reset_stream_drops_partial_frame_and_keeps_counters():
    dec = p.Decoder()
    dec.feed(p.encode_samples(_samples([5])) + p.encode_samples(_samples([6]))[:10])
    dec.reset_stream()
    res = dec.feed(p.encode_samples(_samples([8])))
    assert res.lost_before.tolist() == [2]
    assert dec.stats.bytes_discarded == 10 and dec.stats.resyncs == 1


def test_discarded_regions_have_stream_offsets():
    frame = p.encode_samples(_samples([1]))
    junk = b'\x00\x11' * 5
    dec = p.Decoder()
    res = dec.feed(frame + junk + frame)
    assert res.discarded == ((len(frame), len(junk)),)


def test_encoders_refuse_out_of_range_fields():
    with pytest.raises(ParameterError, match='command_id'):
        p.encode_configure(command_id=-1, odr_hz=6667, gyro_fs_dps=2000, accel_fs_g=4)
    with pytest.raises(ParameterError, match='gyro_fs_dps'):
        p.encode_configure(command_id=1, odr_hz=6667, gyro_fs_dps=70000, accel_fs_g=4)
    with pytest.raises(ParameterError, match='1-D'):
        p.encode_samples(np.zeros((2, 2), p.SAMPLE_DTYPE))


# --- LSM6DSO32 scaling: datasheet sensitivities
# ---------------------------------------------------

@pytest.mark.parametrize(
    'fs, mdps', [(125, 4.375), (250, 8.75), (500, 17.5), (1000, 35.0), (2000, 70.0)])
def test_gyro_sensitivity_datasheet(fs, mdps):
    assert lsm.gyro_sensitivity_rad_s_per_lsb(
        fs) == pytest.approx(mdps * 1e-3 * np.pi / 180, rel=1e-15)
    # full scale sits inside the int16 range with the datasheet sensitivity (32767 LSB > FS)
    assert 32767 * mdps * 1e-3 > fs


@pytest.mark.parametrize('fs, mg', [(4, 0.122), (8, 0.244), (16, 0.488), (32, 0.976)])
def test_accel_sensitivity_datasheet(fs, mg):
    assert lsm.accel_sensitivity_m_s2_per_lsb(fs) == pytest.approx(mg * 1e-3 * 9.80665, rel=1e-15)


def test_to_si_values():
    s = np.zeros(3, p.SAMPLE_DTYPE)
    s['gyro'] = [(1000, -1000, 0), (32767, -32768, 1), (0, 0, 0)]
    s['accel'] = [(8197, 0, -8197), (0, 0, 0), (1, 1, 1)]
    s['temp'] = [0, 256, -6400]
    si = lsm.to_si(s, gyro_fs_dps=500, accel_fs_g=4)
    assert si.gyro_rad_s[0].tolist() == pytest.approx(np.radians([17.5, -17.5, 0.0]), rel=1e-12)
    assert si.gyro_rad_s[1, 1] == pytest.approx(np.radians(-32768 * 17.5e-3), rel=1e-12)
    assert si.accel_m_s2[0, 0] == pytest.approx(8197 * 0.122e-3 * 9.80665, rel=1e-12)
    assert si.temperature_c.tolist() == [25.0, 26.0, 0.0]
    assert si.gyro_rad_s.shape == (3, 3) and si.gyro_rad_s.dtype == np.float64


@pytest.mark.parametrize('call', [lambda: lsm.gyro_sensitivity_rad_s_per_lsb(300),
                                  lambda: lsm.accel_sensitivity_m_s2_per_lsb(2),
                                  lambda: lsm.to_si(np.zeros(1, p.SAMPLE_DTYPE), gyro_fs_dps=2000,
                                                    accel_fs_g=3), lambda: lsm.check_odr(100.0),
                                  lambda: lsm.check_odr('fast')])
def test_bad_scales_and_rates_raise_parameter_error(call):
    with pytest.raises(ParameterError):
        call()


def test_odr_matching_accepts_datasheet_labels():
    assert lsm.check_odr(6660) == 6667.0
    assert lsm.check_odr(6664) == 6667.0
    assert lsm.check_odr(416) == 417.0
    assert lsm.check_odr(12.5) == 12.5
    assert lsm.ODRS_HZ[-1] == 6667.0


def test_quantise_rounds_and_saturates():
    assert lsm.quantise([0.49, 0.51, -0.5, 1e9, -1e9], 1.0).tolist() == [0, 1, 0, 32767, -32768]


def test_feed_accepts_any_bytes_like_and_refuses_other_types():
    frame = p.encode_samples(_samples([1]))
    for kind in (bytes, bytearray, memoryview):
        assert p.Decoder().feed(kind(frame)).samples.size == 1
    assert p.Decoder().feed(None).samples.size == 0
    with pytest.raises(ParameterError, match='bytes-like'):
        p.Decoder().feed('A5 5A')
