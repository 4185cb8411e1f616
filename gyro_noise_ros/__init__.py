"""
Noise characterisation of MEMS gyroscopes, live (ROS 2 nodes) and from recordings (rosbags).

Everything in this package except :mod:`gyro_noise_ros.nodes` imports and runs without ROS.
"""

__version__ = '0.1.0'
