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
Live characterisation: ``lsm6dso32_driver`` + ``noise_analyzer``, optionally more.

``ros2 launch gyro_noise_ros gyro_noise.launch.py port:=/dev/ttyACM0``

Arguments (``ros2 launch gyro_noise_ros gyro_noise.launch.py --show-args``):

- ``namespace`` (default empty): every node and topic under it, e.g. ``robot1``;
- ``port``: the board's serial device or pyserial URL (with ``emulator:=true`` the default is
  the emulator's ``socket://127.0.0.1:5760``);
- ``params_file`` (default empty): a parameter file applied after the shipped
  ``config/<node>.yaml`` of every node; key it ``/**:`` for all nodes or by node name;
- ``use_sim_time`` (default false);
- ``record`` (default false): also ``gyro_noise_record`` into ``bag_output`` (empty: a dated
  directory in the working directory);
- ``emulator`` (default false): also ``portenta_emulator`` on 127.0.0.1:5760 instead of a board;
- ``compensate`` (default false): also ``imu_compensator`` (``config/imu_compensator.yaml``);
- ``in_process`` (default false): with ``compensate``, the driver and the compensator in one
  process (``imu_chain``): the driver hands each read to the compensator, no second trip through
  DDS (a third less CPU, the compensator's added latency p99 about 1 ms; docs/scale.md);
- ``realtime_priority`` (default 0): ``SCHED_FIFO`` priority of the driver and the compensator,
  the stabilisation loop's path (their ``realtime_priority`` parameter; 0: the parameter files'
  value, normal scheduling by default; docs/scale.md).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, GroupAction, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node, PushRosNamespace
from launch_ros.substitutions import FindPackagePrefix, FindPackageShare

PACKAGE = 'gyro_noise_ros'
EMULATOR_URL = 'socket://127.0.0.1:5760'


def _config(name):
    return PathJoinSubstitution([FindPackageShare(PACKAGE), 'config', name + '.yaml'])


def _nodes(context):
    value = LaunchConfiguration
    params_file = value('params_file').perform(context)
    port = value('port').perform(context) or (
        EMULATOR_URL if value('emulator').perform(context).lower() == 'true' else '/dev/ttyACM0')
    common = {'use_sim_time': value('use_sim_time').perform(context).lower() == 'true'}

    def params(name, **extra):
        return [_config(name), *([params_file] if params_file else []), {**common, **extra}]

    record_output = value('bag_output').perform(context)
    priority = int(value('realtime_priority').perform(context) or 0)
    realtime = {'realtime_priority': priority} if priority else {}
    compensate = value('compensate').perform(context).lower() == 'true'
    in_process = compensate and value('in_process').perform(context).lower() == 'true'
    if in_process:  # both nodes in one process, their own names: no name= remapping (it would
        # give both one name); each node takes its names from the files' /** sections
        driver = [Node(package=PACKAGE, executable='imu_chain', parameters=[
            _config('lsm6dso32_driver'), _config('imu_compensator'),
            *params('lsm6dso32_driver', port=port, **realtime)[1:]], output='screen')]
    else:
        driver = [Node(package=PACKAGE, executable='lsm6dso32_driver', name='lsm6dso32_driver',
                       parameters=params('lsm6dso32_driver', port=port, **realtime),
                       output='screen')]
        if compensate:
            driver.append(Node(package=PACKAGE, executable='imu_compensator',
                               name='imu_compensator',
                               parameters=params('imu_compensator', **realtime),
                               output='screen'))
    return [GroupAction([
        PushRosNamespace(value('namespace')),
        *driver,
        Node(package=PACKAGE, executable='noise_analyzer', name='noise_analyzer',
             parameters=params('noise_analyzer'), output='screen'),
        Node(package=PACKAGE, executable='gyro_noise_record', name='gyro_noise_record',
             parameters=params('gyro_noise_record', **({'output': record_output}
                                                       if record_output else {})),
             output='screen', condition=IfCondition(value('record'))),
    ])]


def generate_launch_description():
    """
    Return the launch description (module doc lists the arguments).

    Returns
    -------
    launch.LaunchDescription

    """
    args = [
        DeclareLaunchArgument('namespace', default_value='', description='Namespace of the nodes'),
        DeclareLaunchArgument('port', default_value='', description='Serial device or pyserial '
                              'URL of the board (empty: /dev/ttyACM0, or the emulator)'),
        DeclareLaunchArgument('params_file', default_value='', description='Parameter file '
                              'applied after the shipped config/<node>.yaml (keyed /** or by '
                              'node name)'),
        DeclareLaunchArgument('use_sim_time', default_value='false',
                              description='Use /clock (bag playback)'),
        DeclareLaunchArgument('record', default_value='false',
                              description='Also record imu/data_raw and imu/temperature'),
        DeclareLaunchArgument('bag_output', default_value='',
                              description='Bag directory of the recorder (empty: dated name)'),
        DeclareLaunchArgument('emulator', default_value='false',
                              description='Also run portenta_emulator on 127.0.0.1:5760'),
        DeclareLaunchArgument('compensate', default_value='false',
                              description='Also run the compensation node imu_compensator'),
        DeclareLaunchArgument('in_process', default_value='false',
                              description='With compensate: the driver and the compensator in '
                              'one process (imu_chain), no second DDS trip'),
        DeclareLaunchArgument('realtime_priority', default_value='0',
                              description='SCHED_FIFO priority (1-99) of the driver and the '
                              'compensator; 0: as their parameter files say'),
    ]
    # The emulator is a plain program (no ROS arguments), started outside the namespace group.
    emulator = ExecuteProcess(
        cmd=[PathJoinSubstitution([FindPackagePrefix(PACKAGE), 'lib', PACKAGE,
                                   'portenta_emulator']), '--tcp', '127.0.0.1:5760'],
        output='screen', condition=IfCondition(LaunchConfiguration('emulator')))
    return LaunchDescription([*args, emulator, OpaqueFunction(function=_nodes)])
