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
Offline characterisation of a recording by bag playback: ``ros2 bag play --clock`` + analyzer.

``ros2 launch gyro_noise_ros gyro_noise_playback.launch.py bag:=my_bag``

The bag is played with ``--clock`` and the analyzer runs with ``use_sim_time:=true``, so its
diagnostics and per-chunk topics are stamped on the recording's time base; it drains on a wall
clock, so a paused or slow playback gives no false sample loss. ``gyro_noise_analyze BAG`` gives
the same numbers without ROS, faster.

Arguments: ``bag`` (required), ``namespace``, ``params_file`` (applied after the shipped
``config/noise_analyzer.yaml``), ``rate`` (playback speed factor, default 1.0).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, GroupAction, OpaqueFunction
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node, PushRosNamespace
from launch_ros.substitutions import FindPackageShare

PACKAGE = 'gyro_noise_ros'


def _nodes(context):
    params_file = LaunchConfiguration('params_file').perform(context)
    config = PathJoinSubstitution([FindPackageShare(PACKAGE), 'config', 'noise_analyzer.yaml'])
    return [GroupAction([
        PushRosNamespace(LaunchConfiguration('namespace')),
        Node(package=PACKAGE, executable='noise_analyzer', name='noise_analyzer',
             parameters=[config, *([params_file] if params_file else []),
                         {'use_sim_time': True}], output='screen'),
    ])]


def generate_launch_description():
    """
    Return the launch description (module doc lists the arguments).

    Returns
    -------
    launch.LaunchDescription

    """
    return LaunchDescription([
        DeclareLaunchArgument('bag', description='The rosbag2 directory to play'),
        DeclareLaunchArgument('namespace', default_value='',
                              description='Namespace of the analyzer (the bag topics must be '
                              'under it, or remap them)'),
        DeclareLaunchArgument('params_file', default_value='', description='Parameter file '
                              'applied after the shipped config/noise_analyzer.yaml'),
        DeclareLaunchArgument('rate', default_value='1.0', description='Playback speed factor'),
        OpaqueFunction(function=_nodes),
        ExecuteProcess(cmd=['ros2', 'bag', 'play', LaunchConfiguration('bag'), '--clock',
                            '--rate', LaunchConfiguration('rate')], output='screen'),
    ])
