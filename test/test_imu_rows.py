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

"""The row fast path of live Imu batches against the span codec it stands in for."""

from gyro_noise_ros.bag import decode_temperature
from gyro_noise_ros.calibration.apply import SensorCalibration
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.msgs import (decode_imu_spans, decode_spans, encode_imu_cdr, encode_imu_rows,
                                 encode_temperature_cdr, IMU_FIELDS, IMU_TAIL_F8, join_raws,
                                 patch_imu_spans, TEMPERATURE_TAIL_F8)
from gyro_noise_ros.msgs.imu_rows import (imu_rows, patch_rows, row_messages, RowCorrector,
                                          RowEncoder, RowLayout, rows_stamps, rows_tail,
                                          rows_vectors)
import numpy as np
import pytest


def _batch(n, frame_id='imu_link', seed=0):
    rng = np.random.default_rng(seed)
    stamps = 1_763_000_000_000_000_000 + np.cumsum(rng.integers(1, 10**6, n))
    gyro, accel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    raws = encode_imu_cdr(stamps, gyro, accel, frame_id=frame_id,
                          angular_velocity_covariance=np.diag(rng.random(3)),
                          linear_acceleration_covariance=np.diag(rng.random(3)))
    return stamps, gyro, accel, raws


@pytest.mark.parametrize('n, frame_id', [(1, 'imu_link'), (16, 'imu_link'), (133, 'a'),
                                         (5, 'x' * 8), (7, 'frame/with_a_longer_name')])
def test_rows_decode_and_patch_like_the_span_codec(n, frame_id):
    stamps, gyro, accel, raws = _batch(n, frame_id)
    buf, starts, lengths = join_raws(raws)
    rows = imu_rows(buf, starts, lengths)
    assert rows is not None and rows.shape == (n, len(raws[0]))
    keep, stamp_ns, g, a = decode_imu_spans(buf, starts, lengths, False, True)
    assert keep is None
    np.testing.assert_array_equal(rows_stamps(rows), stamp_ns)
    np.testing.assert_array_equal(rows_stamps(rows), stamps)
    rg, ra = rows_vectors(rows)
    np.testing.assert_array_equal(rg, g)
    np.testing.assert_array_equal(ra, a)
    new_g, new_a = g * 2.0 - 1.0, a + 0.5
    assert patch_rows(rows, new_g, new_a) == patch_imu_spans(buf, starts, lengths, new_g, new_a)
    assert bytes(buf) == b''.join(raws)  # the input is left alone


def test_anything_else_is_left_to_the_span_codec():
    _, _, _, raws = _batch(4)
    assert imu_rows(*join_raws([])) is None
    # two lengths (another frame_id in the batch)
    assert imu_rows(*join_raws(raws[:2] + _batch(2, 'other_frame')[3])) is None
    # same length, another frame_id: header bytes differ from row 0
    assert imu_rows(*join_raws(raws[:2] + _batch(2, 'imu_lin2')[3])) is None
    # big-endian CDR
    big = [bytes([0, 0]) + r[2:] for r in raws]
    assert imu_rows(*join_raws(big)) is None
    # no NUL where the frame_id length says, in row 0 and in a later row
    for i in (0, 2):
        bad = list(raws)
        bad[i] = bad[i][:24] + b'Z' + bad[i][25:]  # 'imu_link' + NUL: length 9, NUL at 16 + 8
        assert imu_rows(*join_raws(bad)) is None
        ok = decode_spans(*join_raws(bad), IMU_TAIL_F8, IMU_FIELDS, False)[0]
        assert not ok[i] and ok.sum() == 3  # the bulk decoder refuses that message too
    # non-ASCII frame_id: the span codec leaves it to rosbags, and so do the rows
    assert imu_rows(*join_raws(_batch(3, 'imu_\u00e9')[3])) is None
    # spans not back to back
    buf, starts, lengths = join_raws(raws)
    assert imu_rows(buf, starts[::-1].copy(), lengths) is None


def _same_answer(layout, raws):
    got, want = layout.rows(raws), imu_rows(*join_raws(raws))
    assert (got is None) == (want is None)
    if want is not None:
        np.testing.assert_array_equal(got, want)
    return got is not None


def test_the_remembered_layout_answers_as_imu_rows_does():
    # RowLayout checks later batches of a learnt layout in Python; every batch, good or bad,
    # before or after it learnt one, must get imu_rows' answer.
    rng = np.random.default_rng(7)
    layout = RowLayout()
    assert layout.rows([]) is None
    raws = _batch(40)[3]
    others = {
        'longer frame_id': _batch(3, 'other_frame')[3],
        'same length, other frame_id': _batch(3, 'imu_lin2')[3],
        'big-endian': [bytes([0, 0]) + r[2:] for r in raws[:3]],
        'non-ASCII frame_id': _batch(3, 'imu_\u00e9')[3],
    }
    accepted = refused = 0
    for trial in range(400):
        i = int(rng.integers(0, 30))
        batch = list(raws[i:i + int(rng.integers(1, 11))])
        kind = trial % 4
        if kind == 1:  # one byte of one message changed anywhere before the float block
            j = int(rng.integers(0, len(batch)))
            pos = int(rng.integers(0, len(batch[j]) - 8 * IMU_TAIL_F8))
            raw = bytearray(batch[j])
            raw[pos] ^= int(rng.integers(1, 256))
            batch[j] = bytes(raw)
        elif kind == 2:  # another layout's message in the batch
            batch.insert(int(rng.integers(0, len(batch) + 1)),
                         others[list(others)[trial % len(others)]][0])
        elif kind == 3:  # a truncated or lengthened message
            j = int(rng.integers(0, len(batch)))
            batch[j] = batch[j][:-8] if trial % 8 == 3 else batch[j] + bytes(8)
        if _same_answer(layout, batch):
            accepted += 1
        else:
            refused += 1
    # both answers came up many times (a changed stamp byte is still a good message)
    assert accepted > 100 and refused > 100
    for name, batch in others.items():
        _same_answer(layout, batch)
        _same_answer(layout, raws[:5])


@pytest.mark.parametrize('n, frame_id, av_cov, la_cov', [
    (1, 'imu_link', None, None), (16, 'imu_link', np.arange(9.0), np.eye(3) * 2e-3),
    (7, 'a', None, np.arange(9.0) * -1.5), (33, 'frame/with_a_longer_name', np.eye(3), None)])
def test_the_template_encoder_writes_the_general_encoders_bytes(n, frame_id, av_cov, la_cov):
    rng = np.random.default_rng(n)
    # negative stamps too: ROS 2 keeps nanosec in [0, 1e9)
    stamps = rng.integers(-2**60, 2**60, n)  # within int32 seconds
    gyro, accel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)) * 1e3
    kwargs = {'frame_id': frame_id, 'angular_velocity_covariance': av_cov,
              'linear_acceleration_covariance': la_cov}
    rows = RowEncoder(frame_id, av_cov, la_cov).rows(stamps, gyro, accel)
    np.testing.assert_array_equal(rows, encode_imu_rows(stamps, gyro, accel, **kwargs))
    assert row_messages(rows) == encode_imu_cdr(stamps, gyro, accel, **kwargs)


def test_the_template_encoder_refuses_what_the_general_one_refuses():
    enc = RowEncoder('imu_link')
    with pytest.raises(ParameterError, match='gyro_rad_s must have shape'):
        enc.rows([1, 2], np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ParameterError, match='accel_m_s2 must have shape'):
        enc.rows([1, 2], np.zeros((2, 3)), np.zeros(3))
    with pytest.raises(ParameterError, match='integer nanoseconds'):
        enc.rows([1.5], np.zeros((1, 3)), np.zeros((1, 3)))
    with pytest.raises(ParameterError, match='must be shared'):
        RowEncoder('imu_link', np.zeros((2, 9)))
    assert enc.rows([], np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, enc.template.size)


@pytest.mark.parametrize('n, frame_id, strided', [
    (0, 'imu_link', False), (1, 'a', True), (16, 'imu_link', True), (33, 'frame/x', False)])
def test_scaled_rows_are_the_rows_of_the_scaled_values(n, frame_id, strided):
    """The compiled pass against :meth:`RowEncoder.rows` of ``numpy.multiply``'s values."""
    rng = np.random.default_rng(n)
    stamps = rng.integers(-2**60, 2**60, n)
    words = np.zeros(n, [('seq', '<u4'), ('g', '<i2', (3,)), ('a', '<i2', (3,))])
    words['g'] = rng.integers(-32768, 32768, (n, 3))
    words['a'] = rng.integers(-32768, 32768, (n, 3))
    words['a'][:1] = [-32768, 32767, 0]
    gyro, accel = (words['g'], words['a']) if strided else (words['g'].copy(), words['a'].copy())
    enc = RowEncoder(frame_id, np.arange(9.0))
    for gs, as_ in ((7.635e-4, 9.577e-3), (1.0, -3.3), (np.float32(0.1), 1e-300)):
        want = enc.rows(stamps, np.multiply(gyro, gs, dtype=np.float64),
                        np.multiply(accel, as_, dtype=np.float64))
        np.testing.assert_array_equal(enc.rows_scaled(stamps, gyro, accel, gs, as_), want)
    # other dtypes go the general way, with its answers and refusals
    np.testing.assert_array_equal(enc.rows_scaled(stamps, gyro.astype(float), accel, 2.0, 3.0),
                                  enc.rows(stamps, gyro * 2.0, accel * 3.0))
    with pytest.raises(ParameterError, match='does not fit'):
        enc.rows_scaled(np.array([2**62]), np.zeros((1, 3), np.int16), np.zeros((1, 3), np.int16),
                        1.0, 1.0)
    with pytest.raises(ParameterError, match='gyro_rad_s must have shape'):
        enc.rows_scaled(stamps, np.zeros((n + 1, 3), np.int16), accel, 1.0, 1.0)


def _sensor(rng, identity):
    if identity:
        return SensorCalibration(np.zeros(3), np.zeros(3), np.zeros((3, 3)))
    mis = rng.normal(0, 3e-3, (3, 3))
    np.fill_diagonal(mis, 0.0)
    return SensorCalibration(rng.normal(0, 0.05, 3), rng.normal(0, 2e-3, 3), mis)


@pytest.mark.parametrize('n', [0, 1, 2, 16, 33])
def test_corrected_rows_are_the_patched_rows_of_the_calibration_and_offsets(n):
    """The compiled pass against SensorCalibration.apply, the offsets, patch_rows: same bytes."""
    rng = np.random.default_rng(40 + n)
    stamps, gyro, accel, raws = _batch(n, seed=n) if n else (None, None, None, [])
    rows = RowLayout().rows(raws) if n else RowEncoder('imu_link').rows(
        [], np.zeros((0, 3)), np.zeros((0, 3)))
    if n > 2:  # values a correction must carry through as numpy does: signed zeros, non-finite
        tail = rows.copy()
        v = tail[:, tail.shape[1] - 8 * IMU_TAIL_F8:].view('<f8')
        v[0, 4:7] = [-0.0, np.nan, np.inf]
        v[1, 8:11] = [-np.inf, 1e308, -5e-324]
        rows = tail  # writable rows: the kernel's other specialisation
    for case in range(8):
        gyro_cal, accel_cal = _sensor(rng, case & 1), _sensor(rng, case & 2)
        offsets = [rng.normal(0, 1e-3, (n, 3)) if case & 4 else None for _ in range(2)]
        g, a = rows_vectors(rows)
        g, a = gyro_cal.apply(g), accel_cal.apply(a)
        for vec, off in ((g, offsets[0]), (a, offsets[1])):
            if off is not None:
                vec -= off
        want = patch_rows(rows, g, a)
        corrector = RowCorrector(None if gyro_cal.is_identity else gyro_cal.inverse,
                                 gyro_cal.bias, None if accel_cal.is_identity
                                 else accel_cal.inverse, accel_cal.bias)
        before = rows.tobytes()
        assert row_messages(corrector.rows(rows, *offsets)) == want, case
        assert rows.tobytes() == before  # a copy: the input rows are left as they were
    with pytest.raises(ParameterError, match='offsets'):
        corrector.rows(rows, np.zeros((n + 1, 3)))
    with pytest.raises(ParameterError, match='matrix'):
        RowCorrector(np.eye(2), np.zeros(3), None, np.zeros(3))


@pytest.mark.parametrize('frame_id', ['imu_link', 'a', 'x' * 8, 'frame/with_a_longer_name'])
def test_temperature_rows_decode_as_the_temperature_decoder(frame_id):
    rng = np.random.default_rng(len(frame_id))
    stamps = rng.integers(-2**60, 2**60, 12)
    temps = rng.normal(30.0, 20.0, 12)
    raws = encode_temperature_cdr(stamps, temps, frame_id=frame_id, variance=0.01)
    layout = RowLayout(TEMPERATURE_TAIL_F8)
    for batch in (raws[:1], raws[1:5], raws[5:]):  # learnt, then the cached check
        rows = layout.rows(batch)
        assert rows is not None
        want_stamps, want_temps = decode_temperature(batch)
        np.testing.assert_array_equal(rows_stamps(rows), want_stamps)
        np.testing.assert_array_equal(rows_tail(rows, TEMPERATURE_TAIL_F8)[:, 0], want_temps)
    # an Imu message is not a Temperature of this layout, nor the other way round
    assert layout.rows(_batch(2)[3]) is None
    assert RowLayout().rows(raws[:2]) is None
