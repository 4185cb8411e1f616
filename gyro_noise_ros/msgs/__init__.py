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
Bulk numpy codec of ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` (ROS 2 CDR and ROS 1).

ROS-free (numpy, and rosbags' typestore for the messages the bulk path refuses); used by the bag
reader and writers (:mod:`gyro_noise_ros.bag`) and by the nodes on raw subscriptions and
serialised publishers. One module per idea:

- :mod:`.stamps`: integer-ns stamps to and from ``builtin_interfaces/Time``, stamp order.
- :mod:`.cdr`: the shared wire layer (header + float64 tail): column decoder over byte spans,
  encoder, rosbags' typestore and per-message fallback, ``frame_id``.
- :mod:`.imu`: ``sensor_msgs/Imu`` decode, encode, covariances, in-place patching.
- :mod:`.imu_rows`: a live batch of Imu messages of one layout as a byte matrix (the nodes' fast
  path for small batches).
- :mod:`.temperature`: ``sensor_msgs/Temperature`` decode, encode, variances.

See ``docs/bags.md``.
"""

from .cdr import decode_spans, frame_id_of, join_raws, slow_decode, typestore
from .imu import (
    decode_imu_spans,
    encode_imu_cdr,
    encode_imu_rows,
    imu_covariances,
    IMU_FIELDS,
    IMU_MSGTYPE,
    IMU_TAIL_F8,
    patch_imu_spans,
)
from .stamps import count_stamp_regressions, NS_PER_S, split_stamps
from .temperature import (
    decode_temperature_spans,
    encode_temperature_cdr,
    encode_temperature_rows,
    TEMPERATURE_FIELDS,
    TEMPERATURE_MSGTYPE,
    TEMPERATURE_TAIL_F8,
    temperature_variances,
)

__all__ = [
    'count_stamp_regressions',
    'decode_imu_spans',
    'decode_spans',
    'decode_temperature_spans',
    'encode_imu_cdr',
    'encode_imu_rows',
    'encode_temperature_cdr',
    'encode_temperature_rows',
    'frame_id_of',
    'IMU_FIELDS',
    'IMU_MSGTYPE',
    'IMU_TAIL_F8',
    'imu_covariances',
    'join_raws',
    'NS_PER_S',
    'patch_imu_spans',
    'slow_decode',
    'split_stamps',
    'TEMPERATURE_FIELDS',
    'TEMPERATURE_MSGTYPE',
    'TEMPERATURE_TAIL_F8',
    'temperature_variances',
    'typestore',
]
