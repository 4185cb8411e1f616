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
Topic discovery: the topics of a bag and the choice of the Imu (or Temperature) topic to read.

With no topic given, the bag's single topic of the message type is used; topic names match with
or without their leading slash. Every failure is a :class:`~gyro_noise_ros.errors.BagError` with
one sentence naming the bag and the problem.
"""

from __future__ import annotations

from dataclasses import dataclass

from .storage import BagSource
from ..errors import BagError
from ..msgs import IMU_MSGTYPE
from ..outputs import StrPath


@dataclass(frozen=True)
class TopicInfo:
    """
    One topic of a bag.

    Attributes
    ----------
    name : str
        Topic name as stored in the bag.
    msgtype : str or None
        ROS 2 style message type (``sensor_msgs/msg/Imu``; rosbags normalises ROS 1 names), None if
        the topic's connections disagree.
    count : int
        Number of messages the bag's index or metadata reports for the topic.

    """

    name: str
    msgtype: str | None
    count: int


def _norm(name: str) -> str:
    return name.lstrip('/')


def _select_topic(topics: dict[str, tuple[str | None, int]], topic: str | None, msgtype: str,
                  path: StrPath) -> str:
    """Pick the topic of ``msgtype`` (the single one if ``topic`` is None); raise BagError."""
    if topic is not None:
        matches = [name for name in topics if _norm(name) == _norm(topic)]
        if not matches:
            known = ', '.join(sorted(topics)) or 'none'
            raise BagError(f'topic {topic!r} is not in bag {str(path)!r} (topics: {known})')
        name = matches[0]
        if topics[name][0] != msgtype:
            raise BagError(
                f'topic {name!r} in bag {str(path)!r} carries {topics[name][0]}, not {msgtype}')
        return name
    candidates = sorted(name for name, (kind, _) in topics.items() if kind == msgtype)
    if not candidates:
        raise BagError(f'bag {str(path)!r} has no {msgtype} topic')
    if len(candidates) > 1:
        raise BagError(
            f'bag {str(path)!r} has {len(candidates)} {msgtype} topics ({", ".join(candidates)}); '
            'choose one with {topic}', parameters=('topic',))
    return candidates[0]


def list_topics(path: StrPath) -> list[TopicInfo]:
    """
    List the topics of a bag.

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory, ``.db3``/``.mcap`` file, or ROS 1 ``.bag`` file.

    Returns
    -------
    list of TopicInfo
        Sorted by name.

    Raises
    ------
    BagError
        The path is missing or not a readable bag.

    """
    source = BagSource(path)
    try:
        return [TopicInfo(name, kind, count) for name,
                (kind, count) in sorted(source.topics().items())]
    finally:
        source.close()


def find_imu_topic(path: StrPath, topic: str | None = None) -> str:
    """
    Name the ``sensor_msgs/Imu`` topic to analyse.

    Parameters
    ----------
    path : str or os.PathLike
        Bag path (see :func:`list_topics`).
    topic : str, optional
        Requested topic, matched with or without the leading slash. If None, the bag's single
        ``sensor_msgs/msg/Imu`` topic.

    Returns
    -------
    str
        The topic name as stored in the bag.

    Raises
    ------
    BagError
        No Imu topic, several Imu topics (the message lists them), unknown topic, or a topic of
        another message type.

    """
    source = BagSource(path)
    try:
        return _select_topic(source.topics(), topic, IMU_MSGTYPE, path)
    finally:
        source.close()
