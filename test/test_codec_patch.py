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
msgs.patch_imu_spans against rosbags: replacing the two vectors gives rosbags' own bytes.

Messages of both byte orders, several frame_id lengths (every CDR padding case) and a non-ASCII
frame_id (the rosbags fallback) are serialised by rosbags, patched in bulk, and compared byte for
byte with rosbags' serialisation of the same messages with the new vectors.
"""

import copy

from gyro_noise_ros.errors import BagError
from gyro_noise_ros.msgs import join_raws, patch_imu_spans, typestore
import numpy as np
import pytest

IMU = 'sensor_msgs/msg/Imu'
FRAMES = [('imu_link', True), ('a', True), ('', True), ('abcdefgh', True), ('imu_link', False),
          ('x' * 13, False), ('gr\u00f6\u00dfe', True), ('gr\u00f6\u00dfe', False)]


def _message(rng, frame_id):
    ts = typestore()
    t = ts.types
    vec = t['geometry_msgs/msg/Vector3']
    return t[IMU](
        header=t['std_msgs/msg/Header'](
            stamp=t['builtin_interfaces/msg/Time'](sec=int(rng.integers(-2**31, 2**31)),
                                                   nanosec=int(rng.integers(0, 10**9))),
            frame_id=frame_id),
        orientation=t['geometry_msgs/msg/Quaternion'](*rng.normal(size=4)),
        orientation_covariance=rng.normal(size=9),
        angular_velocity=vec(*rng.normal(size=3)), angular_velocity_covariance=rng.normal(size=9),
        linear_acceleration=vec(*rng.normal(size=3)),
        linear_acceleration_covariance=rng.normal(size=9))


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_patched_bytes_equal_rosbags_serialisation(seed):
    rng = np.random.default_rng(seed)
    ts = typestore()
    order = rng.permutation(len(FRAMES) * 3)
    cases = [FRAMES[i % len(FRAMES)] for i in order]
    msgs = [_message(rng, frame) for frame, _ in cases]
    raws = [bytes(ts.serialize_cdr(m, IMU, little_endian=le)) for m, (_, le) in zip(msgs, cases)]
    gyro = rng.normal(size=(len(raws), 3))
    accel = rng.normal(size=(len(raws), 3))
    out = patch_imu_spans(*join_raws(raws), gyro, accel)
    for msg, (_, le), got, g, a in zip(msgs, cases, out, gyro, accel):
        expected = copy.deepcopy(msg)
        expected.angular_velocity.x, expected.angular_velocity.y, expected.angular_velocity.z = g
        la = expected.linear_acceleration
        la.x, la.y, la.z = a
        assert got == bytes(ts.serialize_cdr(expected, IMU, little_endian=le))


def test_empty_and_undecodable():
    assert patch_imu_spans(*join_raws([]), np.zeros((0, 3)), np.zeros((0, 3))) == []
    with pytest.raises(BagError):
        patch_imu_spans(*join_raws([b'\x00\x01\x00\x00garbage']), np.zeros((1, 3)),
                        np.zeros((1, 3)))
