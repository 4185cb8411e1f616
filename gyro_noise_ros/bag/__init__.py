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
Rosbag reading and writing for gyro_noise_ros, ROS-free (rosbags library only).

Reads rosbag2 recordings (a directory with ``metadata.yaml``, or a bare ``.db3``/``.mcap`` file;
sqlite3 or MCAP storage) and ROS 1 ``.bag`` files; writes rosbag2 (sqlite3 or MCAP).
``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` are decoded and encoded in bulk with numpy
(:mod:`gyro_noise_ros.msgs`), and the rosbag2 message streams are read in blocks
(:mod:`.storage`), so a 12 h 6.66 kHz recording streams in constant memory at millions of
messages per second. See ``docs/bags.md``.

This face only hands names on; each lives in one module:

- :mod:`.batch`: :class:`ImuBatch`, :func:`decode_imu`, :func:`decode_temperature`.
- :mod:`.topics`: :class:`TopicInfo`, :func:`list_topics`, :func:`find_imu_topic`.
- :mod:`.reader`: :class:`ImuBagReader`.
- :mod:`.writer`: :class:`ImuBagWriter`, :func:`write_raw`.
- :mod:`gyro_noise_ros.msgs`: the message types, encoders and :func:`count_stamp_regressions`.

Beside them, not handed on: :mod:`.storage` (block reading), :mod:`.bulk` (block writing),
:mod:`.tabular` (CSV and ULog read like bags), :mod:`.inputs` (the one input layer: a path of
any of these kinds opened by the right reader), :mod:`.mcap_records` (the MCAP record layout
and walks), :mod:`.recover` and :mod:`.repair` (unfinished recordings).
"""

from .batch import decode_imu, decode_temperature, ImuBatch
from .reader import ImuBagReader
from .topics import find_imu_topic, list_topics, TopicInfo
from .writer import ImuBagWriter, write_raw
from ..msgs import (
    count_stamp_regressions,
    encode_imu_cdr,
    encode_temperature_cdr,
    IMU_MSGTYPE,
    TEMPERATURE_MSGTYPE,
)

__all__ = [
    'IMU_MSGTYPE',
    'TEMPERATURE_MSGTYPE',
    'TopicInfo',
    'ImuBatch',
    'ImuBagReader',
    'ImuBagWriter',
    'list_topics',
    'find_imu_topic',
    'decode_imu',
    'decode_temperature',
    'encode_imu_cdr',
    'encode_temperature_cdr',
    'count_stamp_regressions',
    'write_raw',
]
