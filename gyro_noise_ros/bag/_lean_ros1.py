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
rosbags' ROS 1 reader without the per-message index: the chunk list and counts only.

Apart from the rest so that rosbags is imported when a bag is read, not when the package is
(:class:`.storage.BagSource` imports it on first use, docs/architecture.md).
"""

from typing import Any, NoReturn

from rosbags.rosbag1 import Reader
from rosbags.rosbag1.reader import IndexData

from ..errors import BagError

__all__ = ['LeanRos1Reader']


class LeanRos1Reader(Reader):
    """
    Open a ROS 1 bag reading its connections, chunk infos and chunk headers only.

    The index data records after each chunk (one entry per message) are skipped, so memory does
    not grow with the bag; ``messages()`` is therefore unavailable (empty), and message counts
    come from the chunk infos.
    """

    def read_index_data(self, pos: int, indexes: dict[int, list[IndexData]]) -> None:
        """Skip one index data record (fixed 47-byte header, then 12 bytes per message)."""
        bio = self.bio
        assert bio is not None  # an open reader
        head = bio.read(55)
        if len(head) != 55 or int.from_bytes(head[0:4], 'little') != 47:
            raise BagError(f'ROS 1 index data record after chunk at byte {pos} is malformed')
        bio.seek(int.from_bytes(head[51:55], 'little'), 1)

    def open(self) -> None:  # noqa: A003 - overrides rosbags Reader.open
        """Open the bag; connection message counts from the chunk infos."""
        super().open()
        counts: dict[int, int] = {}
        for info in self.chunk_infos:
            for cid, k in info.connection_counts.items():
                counts[cid] = counts.get(cid, 0) + k
        self.connections = [c._replace(msgcount=counts.get(c.id, 0)) for c in self.connections]
        self.indexes = {}

    def messages(self, *args: Any, **kwargs: Any) -> NoReturn:
        """Refuse: the lean reader has no per-message index."""
        raise BagError('the lean ROS 1 reader streams chunks only (no per-message index)')
