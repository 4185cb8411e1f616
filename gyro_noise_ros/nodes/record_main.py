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
``gyro_noise_record``: the recorder node, or ``repair`` (no ROS) when it is the first argument.

``gyro_noise_record --ros-args ...`` runs :mod:`gyro_noise_ros.nodes.recorder`;
``gyro_noise_record repair BAG [--out FIXED]`` runs :mod:`gyro_noise_ros.cli.record`, which
imports no ROS (rclpy is imported only for the node).
"""

from collections.abc import Sequence
import sys


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run the recorder node, or ``repair`` when it is the first argument.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; None: ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit code of :func:`gyro_noise_ros.cli.record.main` (repair) or of
        :func:`gyro_noise_ros.nodes.recorder.main` (the node).

    """
    args = sys.argv[1:] if argv is None else list(argv)
    if args[:1] == ['repair']:
        from ..cli.record import main as repair_main

        return repair_main(args)
    from .recorder import main as node_main

    return node_main(None if argv is None else [sys.argv[0], *args])


if __name__ == '__main__':
    sys.exit(main())
