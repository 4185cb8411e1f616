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
Tests of gyro_noise_ros.bag and .msgs: round trips, the bulk codec against rosbags, errors.

Reference bags are built with the rosbags writers and rosbags' per-message serialisers, so the
bulk decoder is checked against an independent implementation on every field it returns.
"""

import math

from _realdata import real_data
from gyro_noise_ros.bag import (
    decode_imu,
    decode_temperature,
    find_imu_topic,
    ImuBagReader,
    ImuBagWriter,
    list_topics,
    mcap_records,
    storage,
    TopicInfo,
)
from gyro_noise_ros.errors import BagError, OutputError, ParameterError
from gyro_noise_ros.msgs import (
    count_stamp_regressions,
    decode_spans,
    encode_imu_cdr,
    encode_temperature_cdr,
    IMU_FIELDS,
    IMU_MSGTYPE,
    IMU_TAIL_F8,
    join_raws,
    TEMPERATURE_MSGTYPE,
)
from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

ROS2 = get_typestore(Stores.ROS2_JAZZY)
ROS1 = get_typestore(Stores.ROS1_NOETIC)
PLUGINS = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}


def imu_msg(store, stamp_ns, gyro, accel, frame_id='imu_link', *, seq=0, av_cov=None, la_cov=None,
            orientation=(0.0, 0.0, 0.0, 1.0), o_cov0=-1.0):
    """One rosbags Imu object built field by field (the slow, obviously-correct twin)."""
    t = store.types
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    stamp = t['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec)
    if 'seq' in t['std_msgs/msg/Header'].__dataclass_fields__:
        header = t['std_msgs/msg/Header'](seq=seq, stamp=stamp, frame_id=frame_id)
    else:
        header = t['std_msgs/msg/Header'](stamp=stamp, frame_id=frame_id)
    vec = t['geometry_msgs/msg/Vector3']
    o_cov = np.zeros(9)
    o_cov[0] = o_cov0
    return t[
        IMU_MSGTYPE](header=header, orientation=t['geometry_msgs/msg/Quaternion'](*orientation),
                     orientation_covariance=o_cov, angular_velocity=vec(*map(float, gyro)),
                     angular_velocity_covariance=np.zeros(9) if av_cov is None
                     else np.asarray(av_cov, float), linear_acceleration=vec(*map(float, accel)),
                     linear_acceleration_covariance=np.zeros(9) if la_cov is None
                     else np.asarray(la_cov, float),)


def temperature_msg(store, stamp_ns, temp, variance=0.0, frame_id='imu_link'):
    t = store.types
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    header = t[
        'std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec),
                               frame_id=frame_id)
    return t[TEMPERATURE_MSGTYPE](header=header, temperature=float(temp), variance=float(variance))


def sample_data(rng, n, *, with_nan=True):
    stamps = 1_700_000_000_000_000_000 + np.arange(
        n, dtype=np.int64) * 150_150 + rng.integers(0, 1000, n)
    gyro = rng.normal(0.0, 0.01, (n, 3))
    accel = rng.normal(0.0, 0.1, (n, 3)) + (0.0, 0.0, 9.81)
    if with_nan and n > 5:
        gyro[3, 1] = np.nan
        accel[4, 2] = np.inf
    return stamps, gyro, accel


def write_ros2_reference(path, storage, msgs, *, topic='/imu/data_raw', little_endian=True,
                         extra=()):
    """Write (log_ns, msg) pairs with rosbags' own writer and serialiser."""
    with Writer(path, version=9, storage_plugin=PLUGINS[storage]) as writer:
        conn = writer.add_connection(topic, IMU_MSGTYPE, typestore=ROS2)
        for log_ns, msg in msgs:
            writer.write(
                conn, log_ns, ROS2.serialize_cdr(msg, IMU_MSGTYPE, little_endian=little_endian))
        for etopic, etype, emsgs in extra:
            econn = writer.add_connection(etopic, etype, typestore=ROS2)
            for log_ns, msg in emsgs:
                writer.write(econn, log_ns, ROS2.serialize_cdr(msg, etype))


def concat(batches):
    return (np.concatenate([b.stamp_ns for b in batches]),
            np.concatenate([b.log_ns for b in batches]), np.concatenate([b.gyro for b in batches]),
            np.concatenate([b.accel for b in batches]))


def assert_same_floats(actual, expected):
    # Bit-level equality, NaN included: decoding must not change a single value.
    np.testing.assert_array_equal(np.asarray(actual).view(np.int64),
                                  np.asarray(expected).view(np.int64))


# -------------------------------------------------------------------------------------------------
# Encoder: byte-exact against rosbags


@pytest.mark.parametrize('frame_id', ['', 'a', 'imu', 'imu_lin', 'imu_link', 'imu_link_',
                                      'imu_link_0123456'])
def test_encode_imu_is_byte_exact_against_rosbags(frame_id):
    rng = np.random.default_rng(1)
    stamps, gyro, accel = sample_data(rng, 20)
    stamps[0] = -1_500_000_000  # negative time: sec = -2, nanosec = 5e8 in ROS 2
    stamps[1] = 0
    av_cov = rng.normal(size=(20, 9))
    la_cov = np.arange(9.0)
    blobs = encode_imu_cdr(stamps, gyro, accel, frame_id=frame_id,
                           angular_velocity_covariance=av_cov,
                           linear_acceleration_covariance=la_cov)
    assert len(blobs) == 20
    for i in range(20):
        ref = ROS2.serialize_cdr(imu_msg(ROS2, stamps[i], gyro[i], accel[i], frame_id,
                                         av_cov=av_cov[i], la_cov=la_cov), IMU_MSGTYPE)
        assert blobs[i] == bytes(ref), i


@pytest.mark.parametrize('frame_id', ['', 'imu_link', 'x' * 13])
def test_encode_temperature_is_byte_exact_against_rosbags(frame_id):
    stamps = np.array([0, 1, 1_999_999_999, 1_700_000_000_123_456_789])
    temps = np.array([25.0, -40.5, np.nan, 85.125])
    blobs = encode_temperature_cdr(stamps, temps, frame_id=frame_id, variance=0.25)
    for s, t, blob in zip(stamps, temps, blobs):
        ref = ROS2.serialize_cdr(temperature_msg(ROS2, s, t, 0.25, frame_id), TEMPERATURE_MSGTYPE)
        assert blob == bytes(ref)


def test_encode_rejects_bad_input():
    with pytest.raises(ParameterError, match='gyro_rad_s'):
        encode_imu_cdr([1, 2], np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ParameterError, match='stamp_ns'):
        encode_imu_cdr([1.5], np.zeros(3), np.zeros(3))
    with pytest.raises(ParameterError, match='builtin_interfaces'):
        encode_imu_cdr([2**31 * 1_000_000_000], np.zeros(3), np.zeros(3))
    with pytest.raises(ParameterError, match='NUL'):
        encode_imu_cdr([1], np.zeros(3), np.zeros(3), frame_id='a\x00b')
    with pytest.raises(ParameterError, match='angular_velocity_covariance'):
        encode_imu_cdr([1], np.zeros(3), np.zeros(3), angular_velocity_covariance=np.zeros(4))


# -------------------------------------------------------------------------------------------------
# Bulk decoder against rosbags' per-message deserialiser


def bulk_ok(raws, ros1):
    """Which messages the bulk path accepts (the rest go to rosbags)."""
    return decode_spans(*join_raws(raws), IMU_TAIL_F8, IMU_FIELDS, ros1)[0]


def slow_reference(raws, ros1=False):
    store = ROS1 if ros1 else ROS2
    msgs = [store.deserialize_ros1(r, IMU_MSGTYPE) if ros1
            else store.deserialize_cdr(r, IMU_MSGTYPE) for r in raws]
    stamps = np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in msgs],
                      np.int64)
    gyro = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                     for m in msgs])
    accel = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                      for m in msgs])
    return stamps, gyro, accel, msgs[0].header.frame_id


def mixed_raws(rng, n, *, ros1=False):
    """Messages of many frame_id lengths (several byte lengths per batch), both endiannesses."""
    stamps, gyro, accel = sample_data(rng, n)
    store = ROS1 if ros1 else ROS2
    raws = []
    for i in range(n):
        frame = 'f' * int(rng.integers(0, 20))
        msg = imu_msg(store, stamps[i], gyro[i], accel[i], frame, seq=i * 7 + 3)
        if ros1:
            raws.append(bytes(store.serialize_ros1(msg, IMU_MSGTYPE)))
        else:
            raws.append(bytes(store.serialize_cdr(msg, IMU_MSGTYPE,
                                                  little_endian=bool(rng.integers(0, 2)))))
    return raws


@pytest.mark.parametrize('ros1', [False, True])
def test_bulk_decode_equals_rosbags_on_mixed_lengths_and_endianness(ros1):
    raws = mixed_raws(np.random.default_rng(2), 300, ros1=ros1)
    assert len({len(r) for r in raws}) > 2  # several groups really exercised
    ok = bulk_ok(raws, ros1)
    assert ok.all()  # every well-formed message takes the bulk path, none the fallback
    batch = decode_imu(raws, ros1=ros1)
    stamps, gyro, accel, frame = slow_reference(raws, ros1)
    np.testing.assert_array_equal(batch.stamp_ns, stamps)
    assert_same_floats(batch.gyro, gyro)
    assert_same_floats(batch.accel, accel)
    assert batch.frame_id == frame
    np.testing.assert_array_equal(batch.log_ns, stamps)


def corruptions():
    good = bytes(ROS2.serialize_cdr(imu_msg(ROS2, 5, (1, 2, 3), (4, 5, 6), 'abcdefg'),
                                    IMU_MSGTYPE))
    out = {}
    no_nul = bytearray(good)
    no_nul[16 + 7] = ord('h')
    out['NUL overwritten'] = no_nul
    lying = bytearray(good)
    lying[12] = 20  # claims a 20-byte frame_id: the float block would start beyond its place
    out['length field lies'] = lying
    enc = bytearray(good)
    enc[1] = 7
    out['unknown encapsulation'] = enc
    out['trailing bytes'] = good + bytes(8)
    out['truncated'] = good[:-8]
    return good, {k: bytes(v) for k, v in out.items()}


def test_bulk_decoder_refuses_what_rosbags_refuses():
    good, bad = corruptions()
    for name, raw in bad.items():
        ok = bulk_ok([good, raw, good], False)
        assert ok.tolist() == [True, False, True], name
        with pytest.raises(Exception):  # noqa: B017, PT011 - rosbags' own verdict, any error type
            ROS2.deserialize_cdr(raw, IMU_MSGTYPE)
        with pytest.raises(BagError, match='cannot be decoded'):
            decode_imu([good, raw])


def test_bulk_decoder_agrees_with_rosbags_on_odd_but_valid_messages():
    rng = np.random.default_rng(3)
    raws = mixed_raws(rng, 40)
    odd = bytearray(raws[5])
    if len(odd) > 20 and odd[12] > 3:
        odd[17] = 0  # a NUL inside frame_id: legal bytes for both decoders
    raws[5] = bytes(odd)
    batch = decode_imu(raws)
    stamps, gyro, accel, _ = slow_reference(raws)
    np.testing.assert_array_equal(batch.stamp_ns, stamps)
    assert_same_floats(batch.gyro, gyro)
    assert_same_floats(batch.accel, accel)


def test_undecodable_message_raises_or_is_skipped():
    raws = mixed_raws(np.random.default_rng(4), 10)
    raws[3] = raws[3][:50]  # truncated: neither decoder can read it
    with pytest.raises(BagError, match='cannot be decoded'):
        decode_imu(raws)
    batch = decode_imu(raws, skip_undecodable=True)
    assert len(batch) == 9
    stamps, gyro, _, _ = slow_reference(raws[:3] + raws[4:])
    np.testing.assert_array_equal(batch.stamp_ns, stamps)
    assert_same_floats(batch.gyro, gyro)


def test_decode_temperature_equals_rosbags():
    stamps = np.array([3, 2_000_000_001, 5_000_000_000])
    raws = [bytes(ROS2.serialize_cdr(temperature_msg(ROS2, s, 20.0 + s * 1e-9, 0.1, 'x' * i),
                                     TEMPERATURE_MSGTYPE)) for i, s in enumerate(stamps)]
    s, t = decode_temperature(raws)
    np.testing.assert_array_equal(s, stamps)
    np.testing.assert_array_equal(t, 20.0 + stamps * 1e-9)


def test_count_stamp_regressions():
    assert count_stamp_regressions([1, 2, 2, 1, 5, 3]) == 2
    assert count_stamp_regressions([4, 5], previous_ns=6) == 1
    assert count_stamp_regressions([]) == 0


# -------------------------------------------------------------------------------------------------
# Readers on real bags of all three formats


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_reader_on_rosbags_written_bag(tmp_path, storage):
    rng = np.random.default_rng(5)
    stamps, gyro, accel = sample_data(rng, 500)
    stamps[100], stamps[101] = stamps[101], stamps[100]  # out of order: delivered as recorded
    log = np.arange(500, dtype=np.int64) * 150_000 + 10**18
    msgs = [(int(log[i]), imu_msg(ROS2, stamps[i], gyro[i], accel[i])) for i in range(500)]
    temps = [(int(log[i]), temperature_msg(ROS2, stamps[i], 30.0 + i)) for i in range(0, 500, 50)]
    path = tmp_path / 'bag'
    write_ros2_reference(path, storage, msgs, topic='/imu/data_raw',
                         extra=[('/imu/temperature', TEMPERATURE_MSGTYPE, temps)])
    assert list_topics(path) == [TopicInfo('/imu/data_raw', IMU_MSGTYPE, 500),
                                 TopicInfo('/imu/temperature', TEMPERATURE_MSGTYPE, 10)]
    with ImuBagReader(path) as reader:
        assert (
            reader.topic, reader.storage, reader.message_count) == ('/imu/data_raw', storage, 500)
        assert reader.temperature_topic == '/imu/temperature'
        assert reader.duration_s == pytest.approx(499 * 150e-6, abs=1e-9)
        batches = list(reader.iter_batches(batch_size=64))
        assert [len(b) for b in batches] == [64] * 7 + [52]
        s, lg, g, a = concat(batches)
        ts, tc = reader.read_temperature()
    np.testing.assert_array_equal(s, stamps)
    np.testing.assert_array_equal(lg, log)
    assert_same_floats(g, gyro)
    assert_same_floats(a, accel)
    assert batches[0].frame_id == 'imu_link'
    assert count_stamp_regressions(s) == 1
    np.testing.assert_array_equal(ts, stamps[::50])
    np.testing.assert_array_equal(tc, 30.0 + np.arange(0, 500, 50))


def test_reader_on_big_endian_and_bare_storage_file(tmp_path):
    rng = np.random.default_rng(6)
    stamps, gyro, accel = sample_data(rng, 50)
    msgs = [(int(stamps[i]), imu_msg(ROS2, stamps[i], gyro[i], accel[i], 'be_frame'))
            for i in range(50)]
    write_ros2_reference(tmp_path / 'bag', 'mcap', msgs, little_endian=False)
    (mcap,) = (tmp_path / 'bag').glob('*.mcap')
    for path in (mcap, tmp_path / 'bag' / 'metadata.yaml'):
        with ImuBagReader(path, topic='imu/data_raw') as reader:
            assert reader.duration_s == pytest.approx((stamps[-1] - stamps[0]) / 1e9, abs=1e-9)
            s, _, g, a = concat(list(reader.iter_batches()))
            assert reader.read_temperature() is None
        np.testing.assert_array_equal(s, stamps)
        assert_same_floats(g, gyro)
        assert_same_floats(a, accel)


def test_reader_on_ros1_bag(tmp_path):
    rng = np.random.default_rng(7)
    stamps, gyro, accel = sample_data(rng, 300)
    path = tmp_path / 'rec.bag'
    with Ros1Writer(path) as writer:
        conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=ROS1)
        tconn = writer.add_connection('/imu/temperature', TEMPERATURE_MSGTYPE, typestore=ROS1)
        for i in range(300):
            writer.write(
                conn,
                int(stamps[i]) + 7,
                ROS1.serialize_ros1(
                    imu_msg(ROS1, stamps[i], gyro[i], accel[i], seq=i), IMU_MSGTYPE
                ),
            )
        t = ROS1.types
        for i in range(0, 300, 100):
            header = t['std_msgs/msg/Header'](seq=i, stamp=t['builtin_interfaces/msg/Time'](
                sec=int(stamps[i]) // 10**9, nanosec=int(stamps[i]) % 10**9), frame_id='imu_link')
            writer.write(
                tconn,
                int(stamps[i]) + 7,
                ROS1.serialize_ros1(
                    t[TEMPERATURE_MSGTYPE](header=header, temperature=21.5 + i, variance=0.0),
                    TEMPERATURE_MSGTYPE,
                ),
            )
    assert find_imu_topic(path) == '/imu/data_raw'
    with ImuBagReader(path) as reader:
        assert reader.storage == 'ros1' and reader.message_count == 300
        assert reader.duration_s == pytest.approx((stamps[-1] - stamps[0]) / 1e9, abs=1e-9)
        s, lg, g, a = concat(list(reader.iter_batches(100)))
        ts, tc = reader.read_temperature()
    np.testing.assert_array_equal(s, stamps)
    np.testing.assert_array_equal(lg, stamps + 7)
    assert_same_floats(g, gyro)
    assert_same_floats(a, accel)
    np.testing.assert_array_equal(ts, stamps[::100])
    np.testing.assert_array_equal(tc, [21.5, 121.5, 221.5])


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_writer_round_trip_and_rosbags_reads_it(tmp_path, storage):
    rng = np.random.default_rng(8)
    stamps, gyro, accel = sample_data(rng, 1000)
    path = tmp_path / 'out'
    av_cov = np.diag([1e-6, 2e-6, 3e-6])
    with ImuBagWriter(path, storage=storage, frame_id='board') as writer:
        writer.write_imu(stamps[:999], gyro[:999], accel[:999], angular_velocity_covariance=av_cov,
                         log_ns=stamps[:999] + 11)
        writer.write_imu(
            int(stamps[999]),
            gyro[999],
            accel[999],
            angular_velocity_covariance=av_cov,
            log_ns=int(stamps[999]) + 11,
        )  # single message, scalar stamp
        writer.write_temperature(stamps[::100], np.linspace(20, 30, 10), variance=0.01)
    assert (writer.imu_count, writer.temperature_count) == (1000, 10)
    assert list_topics(path) == [TopicInfo('/imu/data_raw', IMU_MSGTYPE, 1000),
                                 TopicInfo('/imu/temperature', TEMPERATURE_MSGTYPE, 10)]
    with ImuBagReader(path) as reader:
        s, lg, g, a = concat(list(reader.iter_batches()))
        assert reader.iter_batches().__next__().frame_id == 'board'
        ts, tc = reader.read_temperature()
    np.testing.assert_array_equal(s, stamps)
    np.testing.assert_array_equal(lg, stamps + 11)
    assert_same_floats(g, gyro)
    assert_same_floats(a, accel)
    np.testing.assert_array_equal(tc, np.linspace(20, 30, 10))
    # rosbags' own reader and deserialiser see REP-145 messages with our covariances.
    from rosbags.rosbag2 import Reader
    with Reader(path) as reader:
        conn = next(c for c in reader.connections if c.topic == '/imu/data_raw')
        _, t0, raw = next(reader.messages(connections=[conn]))
    msg = ROS2.deserialize_cdr(raw, IMU_MSGTYPE)
    assert t0 == stamps[0] + 11
    assert msg.orientation_covariance[0] == -1.0 and msg.orientation.w == 1.0
    np.testing.assert_array_equal(msg.angular_velocity_covariance, av_cov.ravel())
    assert msg.header.frame_id == 'board'


def test_real_mpu6050_recording_round_trips(tmp_path):
    # Real MEMS data (65,067 samples, see SOURCE.md) through the writer and reader: every value is
    # recovered bit-exactly and the author's published mean gyro X (4.53532 deg/s) is reproduced.
    data = np.loadtxt(real_data('mpu6050_static_sunsided', 'mpu6050_static_10min.csv'),
                      delimiter=',', skiprows=1)
    stamps = np.round(data[:, 0] * 1e9).astype(np.int64)
    gyro = np.deg2rad(data[:, 1:4])
    accel = data[:, 4:7] * 9.80665
    with ImuBagWriter(tmp_path / 'mpu', storage='mcap') as writer:
        writer.write_imu(stamps, gyro, accel)
        writer.write_temperature(stamps, data[:, 7])
    with ImuBagReader(tmp_path / 'mpu') as reader:
        s, _, g, a = concat(list(reader.iter_batches(20_000)))
        _, tc = reader.read_temperature()
    np.testing.assert_array_equal(s, stamps)
    assert_same_floats(g, gyro)
    assert_same_floats(a, accel)
    np.testing.assert_array_equal(tc, data[:, 7])
    # sensor-stats.csv gives 4.53532; the CSV carries 9 significant digits, so 1e-5 deg/s is ample.
    assert math.isclose(np.rad2deg(g[:, 0]).mean(), 4.53532, abs_tol=1e-5)


# -------------------------------------------------------------------------------------------------
# Topic discovery and errors


def two_imu_bag(path):
    msgs = [(i + 1, imu_msg(ROS2, i + 1, (0, 0, 0), (0, 0, 9.8))) for i in range(3)]
    write_ros2_reference(path, 'sqlite3', msgs, topic='/imu_a/data',
                         extra=[('/imu_b/data', IMU_MSGTYPE, msgs),
                                ('/imu_a/temperature', TEMPERATURE_MSGTYPE,
                                 [(1, temperature_msg(ROS2, 1, 20.0))]),
                                ('/imu_b/temperature', TEMPERATURE_MSGTYPE,
                                 [(1, temperature_msg(ROS2, 1, 30.0))])])


def test_topic_discovery_rules(tmp_path):
    path = tmp_path / 'two'
    two_imu_bag(path)
    with pytest.raises(BagError,
                       match=r'2 sensor_msgs/msg/Imu topics \(/imu_a/data, /imu_b/data\)'):
        find_imu_topic(path)
    assert find_imu_topic(path, 'imu_b/data') == '/imu_b/data'
    assert find_imu_topic(path, '/imu_a/data') == '/imu_a/data'
    with pytest.raises(BagError, match="topic '/nope' is not in bag"):
        find_imu_topic(path, '/nope')
    with pytest.raises(BagError,
                       match='carries sensor_msgs/msg/Temperature, not sensor_msgs/msg/Imu'):
        ImuBagReader(path, topic='/imu_a/temperature')
    # Several temperature topics: the one beside the Imu topic is chosen.
    with ImuBagReader(path, topic='/imu_b/data') as reader:
        assert reader.temperature_topic == '/imu_b/temperature'
        np.testing.assert_array_equal(reader.read_temperature()[1], [30.0])
    with pytest.raises(BagError, match='carries sensor_msgs/msg/Imu'):
        ImuBagReader(path, topic='/imu_b/data', temperature_topic='/imu_a/data')


def test_missing_and_non_bag_paths(tmp_path):
    with pytest.raises(BagError, match='does not exist'):
        ImuBagReader(tmp_path / 'missing')
    text = tmp_path / 'notes.db3'
    text.write_text('hello, not a database\n')
    with pytest.raises(BagError, match='is not a bag'):
        list_topics(text)
    (tmp_path / 'bad_meta').mkdir()
    (tmp_path / 'bad_meta'
     / 'metadata.yaml').write_text('rosbag2_bagfile_information: [unclosed\n')
    with pytest.raises(BagError, match='cannot be opened as rosbag2'):
        list_topics(tmp_path / 'bad_meta')
    (tmp_path / 'empty_dir').mkdir()
    with pytest.raises(BagError, match='is not a rosbag2 bag'):
        ImuBagReader(tmp_path / 'empty_dir')


def test_empty_bags(tmp_path):
    with Writer(tmp_path / 'nothing', version=9) as writer:
        pass
    with pytest.raises(BagError, match='has no sensor_msgs/msg/Imu topic'):
        find_imu_topic(tmp_path / 'nothing')
    with Writer(tmp_path / 'no_msgs', version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=ROS2)
    with ImuBagReader(
            tmp_path / 'no_msgs') as reader, pytest.raises(BagError, match='has no messages'):
        list(reader.iter_batches())


def test_corrupt_and_truncated_bags(tmp_path):
    rng = np.random.default_rng(9)
    stamps, gyro, accel = sample_data(rng, 20_000, with_nan=False)
    for kind in ('sqlite3', 'mcap'):
        with ImuBagWriter(tmp_path / kind, storage=kind) as writer:
            writer.write_imu(stamps, gyro, accel)
    (mcap,) = (tmp_path / 'mcap').glob('*.mcap')
    data = mcap.read_bytes()
    mcap.write_bytes(data[:len(data) // 2])  # summary and footer gone, chunks cut mid-way
    # Read by its whole chunks (test_bag_recover.py checks which messages); never more.
    with ImuBagReader(tmp_path / 'mcap') as reader:
        got = concat(list(reader.iter_batches()))[0]
        assert reader.recovery.startswith('truncated MCAP')
    assert 0 < got.size < stamps.size
    np.testing.assert_array_equal(got, stamps[:got.size])
    (db3,) = (tmp_path / 'sqlite3').glob('*.db3')
    raw = bytearray(db3.read_bytes())
    # header kept, pages garbage
    raw[100:] = rng.integers(0, 256, len(raw) - 100, dtype=np.uint8).tobytes()
    db3.write_bytes(bytes(raw))
    with pytest.raises(BagError, match='sqlite3'):
        with ImuBagReader(tmp_path / 'sqlite3') as reader:
            for _ in reader.iter_batches():
                pass


def test_bag_without_metadata_is_read_from_its_storage_file(tmp_path):
    # A recorder killed before close leaves no metadata.yaml; the storage file alone is still read.
    stamps, gyro, accel = sample_data(np.random.default_rng(10), 30)
    with ImuBagWriter(tmp_path / 'rec', storage='sqlite3') as writer:
        writer.write_imu(stamps, gyro, accel)
    (tmp_path / 'rec' / 'metadata.yaml').unlink()
    with ImuBagReader(tmp_path / 'rec') as reader:
        np.testing.assert_array_equal(concat(list(reader.iter_batches()))[0], stamps)


def test_parameter_errors(tmp_path):
    with pytest.raises(ParameterError, match='storage'):
        ImuBagWriter(tmp_path / 'x', storage='csv')
    with ImuBagWriter(tmp_path / 'y') as writer:
        with pytest.raises(ParameterError, match='log_ns'):
            writer.write_imu([1, 2], np.zeros((2, 3)), np.zeros((2, 3)), log_ns=[1])
        writer.write_imu([1, 2], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(OutputError, match='exists already'):
        ImuBagWriter(tmp_path / 'y')
    with ImuBagReader(tmp_path / 'y') as reader:
        for bad in (0, -3, 2.5, True):
            with pytest.raises(ParameterError, match='batch_size'):
                next(reader.iter_batches(bad))


# -------------------------------------------------------------------------------------------------
# Block readers against rosbags' own message iterator


def reference_mcap_records(chunk):
    """Plain struct walk over an MCAP chunk: the twin of mcap_records.mcap_message_records."""
    import struct

    out, pos = [], 0
    while pos < len(chunk):
        op, length = struct.unpack_from('<BQ', chunk, pos)
        if op == 0x05:
            cid, _, log = struct.unpack_from('<HIQ', chunk, pos + 9)
            out.append((pos + 31, length - 22, cid, log))
        pos += 9 + length
    return [np.array(col, np.int64) for col in zip(*out)]


def mcap_record(cid, log, payload):
    import struct

    body = struct.pack('<HIQQ', cid, 0, log, log) + payload
    return struct.pack('<BQ', 0x05, len(body)) + body


def test_mcap_record_scan_matches_struct_walk():
    uniform = b''.join(mcap_record(1, 10 * i, bytes([i]) * 40) for i in range(50))
    mixed = b''.join(mcap_record(1 + i % 3, 5 * i, bytes(i % 7 + 1)) for i in range(50))
    mixed += b'\x06' + (3).to_bytes(8, 'little') + b'abc'  # a non-message record is stepped over
    for chunk in (uniform, mixed):
        got = mcap_records.mcap_message_records(chunk)
        for a, b in zip(got, reference_mcap_records(chunk)):
            np.testing.assert_array_equal(a, b)
    with pytest.raises(BagError, match='beyond the chunk'):
        mcap_records.mcap_message_records(mixed[:-2])


def ros1_record(fields, data):
    import struct

    head = b''.join(struct.pack('<I', len(f)) + f for f in fields)
    return struct.pack('<I', len(head)) + head + struct.pack('<I', len(data)) + data


def reference_ros1_records(chunk):
    """Plain struct walk over a ROS 1 chunk: the twin of storage.ros1_message_records."""
    import struct

    out, pos = [], 0
    while pos < len(chunk):
        (hlen,) = struct.unpack_from('<I', chunk, pos)
        head = chunk[pos + 4:pos + 4 + hlen]
        fields, p = {}, 0
        while p < hlen:
            (flen,) = struct.unpack_from('<I', head, p)
            name, _, value = head[p + 4:p + 4 + flen].partition(b'=')
            fields[name] = value
            p += 4 + flen
        (dlen,) = struct.unpack_from('<I', chunk, pos + 4 + hlen)
        if fields[b'op'] == b'\x02':
            sec, nsec = struct.unpack('<II', fields[b'time'])
            out.append((pos + 8 + hlen, dlen, struct.unpack('<I', fields[b'conn'])[0], sec * 10**9
                        + nsec))
        pos += 8 + hlen + dlen
    return [np.array(col, np.int64) for col in zip(*out)]


def test_ros1_record_scan_matches_struct_walk():
    import struct

    def msg(conn, t, data, order=('op', 'conn', 'time')):
        parts = {'op': b'op=\x02', 'conn': b'conn=' + struct.pack('<I', conn),
                 'time': b'time=' + struct.pack('<II', t // 10**9, t % 10**9)}
        return ros1_record([parts[k] for k in order], data)

    connection = ros1_record([b'op=\x07', b'conn=' + struct.pack('<I', 0), b'topic=/imu'],
                             b'type=x')
    uniform = connection + b''.join(msg(0, 10**9 * i + 7, bytes([i]) * 30) for i in range(40))
    mixed = b''.join(msg(i % 3, 5 * i, bytes(i % 5 + 1), ('time', 'op', 'conn') if i % 4
                         else ('op', 'conn', 'time')) for i in range(40)) + connection
    for chunk in (uniform, mixed):
        got = storage.ros1_message_records(chunk)
        for a, b in zip(got, reference_ros1_records(chunk)):
            np.testing.assert_array_equal(a, b)
    with pytest.raises(BagError, match='beyond the chunk'):
        storage.ros1_message_records(mixed[:-3])


def source_stream(path, topic, fast):
    src = storage.BagSource(path, fast=fast)
    try:
        logs, raws = [], []
        for buf, starts, lengths, log_ns in src.blocks(topic, block=1000):
            logs.append(log_ns)
            raws += [buf[s:s + n].tobytes() for s, n in zip(starts, lengths)]
        return np.concatenate(logs), raws
    finally:
        src.close()


def assert_block_reader_matches_rosbags(path, log, stamps, gyro):
    """Check the block reader against rosbags' raw stream per topic, ImuBagReader's order."""
    for topic in ('/imu/data_raw', '/imu/temperature'):
        fast_log, fast_raws = source_stream(path, topic, True)
        slow_log, slow_raws = source_stream(path, topic, False)
        np.testing.assert_array_equal(fast_log, slow_log)
        assert fast_raws == slow_raws
    with ImuBagReader(path) as reader:
        s, lg, g, _ = concat(list(reader.iter_batches(4096)))
    order = np.argsort(log, kind='stable')
    np.testing.assert_array_equal(lg, log[order])
    np.testing.assert_array_equal(s, stamps[order])
    assert_same_floats(g, gyro[order])


@pytest.mark.parametrize('storage_kind', ['sqlite3', 'mcap'])
@pytest.mark.parametrize('pattern', ['increasing', 'backwards_chunks', 'interleaved', 'ties'])
def test_block_readers_yield_rosbags_order(tmp_path, storage_kind, pattern):
    # 12,000 Imu messages (several 1 MiB MCAP chunks) interleaved with temperature, with log times
    # increasing, decreasing chunk by chunk, shuffled (chunks overlap in time: rosbags' merge
    # must be used) or tied in groups of 10.
    rng = np.random.default_rng(11)
    n = 12_000
    stamps, gyro, accel = sample_data(rng, n, with_nan=False)
    base = 10**18 + np.arange(n, dtype=np.int64) * 150_000
    log = {'increasing': base,
           'backwards_chunks': base[::-1].copy() // 4000 * 4000 + base % 4000,
           'interleaved': base + rng.integers(0, 10**9, n),
           'ties': base // 10 // 150_000 * 150_000}[pattern]
    path = tmp_path / 'bag'
    with ImuBagWriter(path, storage=storage_kind) as writer:
        for i in range(0, n, 500):
            writer.write_imu(stamps[i:i + 500], gyro[i:i + 500], accel[i:i + 500],
                             log_ns=log[i:i + 500])
            writer.write_temperature(stamps[i], 25.0 + i, log_ns=log[i])
    assert_block_reader_matches_rosbags(path, log, stamps, gyro)


def test_flush_leaves_a_readable_db3_behind(tmp_path):
    import shutil

    stamps, gyro, accel = sample_data(np.random.default_rng(12), 100)
    writer = ImuBagWriter(tmp_path / 'live', storage='sqlite3')
    try:
        writer.write_imu(stamps[:60], gyro[:60], accel[:60])
        writer.flush()
        writer.write_imu(stamps[60:], gyro[60:], accel[60:])  # not flushed: lost in a crash
        (db3,) = (tmp_path / 'live').glob('*.db3')
        shutil.copy(db3, tmp_path / 'crashed.db3')  # what a killed recorder leaves on disk
    finally:
        writer.close()
    with ImuBagReader(tmp_path / 'crashed.db3') as reader:
        np.testing.assert_array_equal(concat(list(reader.iter_batches()))[0], stamps[:60])


# -------------------------------------------------------------------------------------------------
# Fuzzing: on damaged messages the bulk decoder agrees with rosbags message by message


@st.composite
def damaged_messages(draw):
    ros1 = draw(st.booleans())
    store = ROS1 if ros1 else ROS2
    raws = []
    for _ in range(draw(st.integers(1, 12))):
        # \u00e9: non-ASCII goes to rosbags
        frame = draw(st.text(alphabet='abc_/\u00e9', max_size=17))
        values = draw(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=6,
                               max_size=6))
        stamp = draw(st.integers(0, 2**31 * 10**9 - 1))
        msg = imu_msg(store, stamp, values[:3], values[3:], frame,
                      seq=draw(st.integers(0, 2**32 - 1)))
        if ros1:
            raw = bytearray(store.serialize_ros1(msg, IMU_MSGTYPE))
        else:
            raw = bytearray(store.serialize_cdr(msg, IMU_MSGTYPE,
                                                little_endian=draw(st.booleans())))
        damage = draw(st.sampled_from(['none', 'flip', 'cut', 'extend']))
        if damage == 'flip':
            for pos in draw(st.lists(st.integers(0, len(raw) - 1), min_size=1, max_size=3)):
                raw[pos] ^= 1 << draw(st.integers(0, 7))
        elif damage == 'cut':
            raw = raw[:draw(st.integers(0, len(raw) - 1))]
        elif damage == 'extend':
            raw += bytes(draw(st.integers(1, 9)))
        raws.append(bytes(raw))
    return ros1, raws


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(damaged_messages())
def test_fuzz_bulk_decoder_agrees_with_rosbags(case):
    ros1, raws = case
    store = ROS1 if ros1 else ROS2
    expected = []
    for raw in raws:
        try:
            msg = store.deserialize_ros1(
                raw, IMU_MSGTYPE) if ros1 else store.deserialize_cdr(raw, IMU_MSGTYPE)
        except Exception:  # noqa: BLE001 - any refusal by rosbags
            continue
        av, la = msg.angular_velocity, msg.linear_acceleration
        # ROS 1 `time` is uint32 secs (wiki.ros.org/msg); rosbags hands it over as ROS 2's int32
        # builtin_interfaces/Time.sec, so secs >= 2**31 come back negative there: the oracle
        # takes them unsigned, as the ROS 1 wire format means them.
        sec = msg.header.stamp.sec % 2 ** 32 if ros1 else msg.header.stamp.sec
        expected.append((sec * 1_000_000_000 + msg.header.stamp.nanosec,
                         (av.x, av.y, av.z), (la.x, la.y, la.z)))
    batch = decode_imu(raws, ros1=ros1, skip_undecodable=True)
    assert len(batch) == len(expected)
    if expected:
        np.testing.assert_array_equal(batch.stamp_ns, [e[0] for e in expected])
        assert_same_floats(batch.gyro, np.array([e[1] for e in expected], float).reshape(-1, 3))
        assert_same_floats(batch.accel, np.array([e[2] for e in expected], float).reshape(-1, 3))


@pytest.mark.parametrize('storage_kind', ['sqlite3', 'mcap'])
def test_damaged_bag_files_raise_only_bag_error(tmp_path, storage_kind):
    # Random byte damage anywhere in the storage file: reading either works or raises BagError,
    # never another exception (seeded; 25 damaged copies per storage).
    rng = np.random.default_rng(14)
    stamps, gyro, accel = sample_data(rng, 3000, with_nan=False)
    src = tmp_path / 'src'
    with ImuBagWriter(src, storage=storage_kind) as writer:
        writer.write_imu(stamps, gyro, accel)
        writer.write_temperature(stamps[::300], np.full(10, 25.0))
    (storage_file,) = [p for p in src.iterdir() if p.suffix in ('.db3', '.mcap')]
    original = storage_file.read_bytes()
    outcomes = set()
    for k in range(25):
        data = bytearray(original)
        for pos in rng.integers(0, len(data), int(rng.integers(1, 40))):
            data[pos] = int(rng.integers(0, 256))
        damaged = tmp_path / f'd{k}{storage_file.suffix}'
        damaged.write_bytes(bytes(data))
        try:
            with ImuBagReader(damaged, skip_undecodable=bool(k % 2)) as reader:
                for _ in reader.iter_batches(1000):
                    pass
                reader.read_temperature()
            outcomes.add('read')
        except BagError:
            outcomes.add('BagError')
    # The damage must really be exercised: some copies are refused (headers, indexes, CRCs hit).
    assert 'BagError' in outcomes


@pytest.mark.parametrize(('storage_kind', 'mode'),
                         [('sqlite3', 'FILE'), ('sqlite3', 'MESSAGE'), ('mcap', 'FILE'),
                          ('mcap', 'MESSAGE'), ('mcap', 'STORAGE')])
def test_compressed_bags(tmp_path, storage_kind, mode):
    from rosbags.rosbag2 import CompressionFormat, CompressionMode

    rng = np.random.default_rng(15)
    stamps, gyro, accel = sample_data(rng, 4000)
    path = tmp_path / 'z'
    writer = Writer(path, version=9, storage_plugin=PLUGINS[storage_kind])
    writer.set_compression(CompressionMode[mode], CompressionFormat.ZSTD)
    with writer:
        conn = writer.add_connection('/imu', IMU_MSGTYPE, typestore=ROS2)
        for i in range(4000):
            writer.write(
                conn,
                int(stamps[i]),
                ROS2.serialize_cdr(imu_msg(ROS2, stamps[i], gyro[i], accel[i]), IMU_MSGTYPE),
            )
    with ImuBagReader(path) as reader:
        s, _, g, a = concat(list(reader.iter_batches(1500)))
    np.testing.assert_array_equal(s, stamps)
    assert_same_floats(g, gyro)
    assert_same_floats(a, accel)


@pytest.mark.parametrize('pattern', ['increasing', 'backwards_chunks', 'interleaved', 'ties'])
def test_ros1_block_reader_yields_rosbags_order(tmp_path, pattern):
    rng = np.random.default_rng(16)
    n = 6000
    stamps, gyro, accel = sample_data(rng, n, with_nan=False)
    base = 10**18 + np.arange(n, dtype=np.int64) * 150_000
    log = {'increasing': base,
           'backwards_chunks': base[::-1].copy(),
           'interleaved': base + rng.integers(0, 10**9, n),
           'ties': base // 10 // 150_000 * 150_000}[pattern]
    path = tmp_path / 'r.bag'
    t = ROS1.types
    with Ros1Writer(path) as writer:
        writer.chunk_threshold = 256 * 1024  # several chunks
        conn = writer.add_connection('/imu/data_raw', IMU_MSGTYPE, typestore=ROS1)
        tconn = writer.add_connection('/imu/temperature', TEMPERATURE_MSGTYPE, typestore=ROS1)
        for i in range(n):
            writer.write(
                conn,
                int(log[i]),
                ROS1.serialize_ros1(
                    imu_msg(ROS1, stamps[i], gyro[i], accel[i], seq=i), IMU_MSGTYPE
                ),
            )
            if i % 700 == 0:
                header = t['std_msgs/msg/Header'](
                    seq=i, stamp=t['builtin_interfaces/msg/Time'](sec=1, nanosec=i),
                    frame_id='imu_link')
                writer.write(
                    tconn,
                    int(log[i]),
                    ROS1.serialize_ros1(
                        t[TEMPERATURE_MSGTYPE](header=header, temperature=20.0 + i, variance=0.0),
                        TEMPERATURE_MSGTYPE,
                    ),
                )
    assert_block_reader_matches_rosbags(path, log, stamps, gyro)


def test_fsync_switches_sqlite_synchronous(tmp_path):
    # Commits without fsync are what keeps a 6.66 kHz recorder's periodic flush cheap; with
    # fsync=True every commit waits for the disk (sqlite's default, synchronous=FULL=2).
    for fsync, expected in ((False, 0), (True, 2)):
        with ImuBagWriter(tmp_path / f'f{fsync}', fsync=fsync) as writer:
            assert writer._writer.storage.conn.execute(
                'PRAGMA synchronous').fetchone() == (expected,)
            writer.write_imu([1], np.zeros(3), np.zeros(3))


@st.composite
def damaged_temperatures(draw):
    ros1 = draw(st.booleans())
    store = ROS1 if ros1 else ROS2
    t = store.types
    raws = []
    for _ in range(draw(st.integers(1, 8))):
        stamp = draw(st.integers(0, 2**31 - 1))
        fields = {
            'stamp': t['builtin_interfaces/msg/Time'](sec=stamp,
                                                      nanosec=draw(st.integers(0, 10**9 - 1))),
            'frame_id': draw(st.text(alphabet='ab_\u00e9', max_size=12))}
        if ros1:
            fields['seq'] = draw(st.integers(0, 2**32 - 1))
        msg = t[TEMPERATURE_MSGTYPE](header=t['std_msgs/msg/Header'](**fields),
                                     temperature=draw(st.floats()), variance=draw(st.floats()))
        raw = bytearray(store.serialize_ros1(msg, TEMPERATURE_MSGTYPE) if ros1
                        else store.serialize_cdr(msg, TEMPERATURE_MSGTYPE,
                                                 little_endian=draw(st.booleans())))
        damage = draw(st.sampled_from(['none', 'flip', 'cut', 'extend']))
        if damage == 'flip':
            raw[draw(st.integers(0, len(raw) - 1))] ^= 1 << draw(st.integers(0, 7))
        elif damage == 'cut':
            raw = raw[:draw(st.integers(0, len(raw) - 1))]
        elif damage == 'extend':
            raw += bytes(draw(st.integers(1, 9)))
        raws.append(bytes(raw))
    return ros1, raws


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(damaged_temperatures())
def test_fuzz_temperature_decoder_agrees_with_rosbags(case):
    ros1, raws = case
    store = ROS1 if ros1 else ROS2
    expected, refused = [], False
    for raw in raws:
        try:
            msg = (store.deserialize_ros1(raw, TEMPERATURE_MSGTYPE) if ros1 else
                   store.deserialize_cdr(raw, TEMPERATURE_MSGTYPE))
        except Exception:  # noqa: BLE001 - any refusal by rosbags
            refused = True
            continue
        expected.append((msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec,
                         msg.temperature))
    if refused:
        with pytest.raises(BagError, match='cannot be decoded'):
            decode_temperature(raws, ros1=ros1)
        return
    stamps, temps = decode_temperature(raws, ros1=ros1)
    np.testing.assert_array_equal(stamps, [e[0] for e in expected])
    assert_same_floats(temps, np.array([e[1] for e in expected], float))
