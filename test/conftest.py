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
Shared fixtures of the test suite.

``ros_graph`` (the private ROS graph every ROS-starting test runs in) leases a ``ROS_DOMAIN_ID``
checked free on this host and held for the test
(:func:`gyro_noise_ros.rosgraph.lease_domain`: port tables plus a file lock, domains 1..101, never
0) and puts the private graph's environment into ``os.environ`` for the test's duration
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, no static peers, no discovery server, no DDS XML
profile): rclpy contexts created in the test and every subprocess started with the default or a
copied environment join that graph and no other.

Every test marked ``ros`` gets the fixture without asking. Outside it, ``ROS_DOMAIN_ID`` holds a
value rcl refuses ("not an integral number"), so a test that starts ROS without the marker or the
fixture fails at ``rclpy.init`` instead of joining domain 0, the one a robot uses.

``make_record``: the one factory of tiny recordings (rosbag2 sqlite3 or MCAP, ROS 1 bag, CSV)
with given stamps, gyro, accel and temperature. Tests call it instead of writing bags by hand;
the bag code itself (``test_bag.py``, ``test_ros1_stream.py``, ``test_import_bulk.py``) keeps
its own reference writers, built on rosbags' per-message serialisers, because they are the
oracle the package's writer is checked against.
"""

import os
from pathlib import Path

from gyro_noise_ros import rosgraph
import numpy as np
import pytest

#: ``ROS_DOMAIN_ID`` outside the fixture: rcl refuses it, so nothing joins a real graph by mistake.
NO_GRAPH = 'none-use-the-ros_graph-fixture'


class RosGraph:
    """
    The private graph of one test.

    Attributes
    ----------
    domain_id : int
        Its ``ROS_DOMAIN_ID`` (held until the test ends).

    """

    def __init__(self, lease):
        self._lease = lease
        self.domain_id = lease.domain_id

    def env(self, **extra):
        """Return the environment of a subprocess in this graph (``os.environ`` plus ``extra``)."""
        return {**self._lease.env(), **{k: str(v) for k, v in extra.items()}}

    def __repr__(self):
        return f'RosGraph(domain_id={self.domain_id})'


def pytest_collection_modifyitems(config, items):
    # A ``usefixtures`` mark added here would come too late for the fixture closure; the names
    # list is what pytest sets up, first entry first.
    for item in items:
        if item.get_closest_marker('ros') is not None and 'ros_graph' not in item.fixturenames:
            item.fixturenames.insert(0, 'ros_graph')


_saved_domain = []


def pytest_configure(config):
    # Set before any fixture or test module runs: outside ``ros_graph``, ``rclpy.init`` fails
    # rather than join domain 0.
    _saved_domain.append(os.environ.get('ROS_DOMAIN_ID'))
    os.environ['ROS_DOMAIN_ID'] = NO_GRAPH


def pytest_unconfigure(config):
    if _saved_domain:
        saved = _saved_domain.pop()
        if saved is None:
            os.environ.pop('ROS_DOMAIN_ID', None)
        else:
            os.environ['ROS_DOMAIN_ID'] = saved


@pytest.fixture
def ros_graph(monkeypatch):
    """Lease a free domain and put its localhost-only environment into ``os.environ``."""
    with rosgraph.lease_domain() as lease:
        for name in rosgraph.UNSET_VARIABLES:
            monkeypatch.delenv(name, raising=False)
        for name, value in lease.env().items():
            if os.environ.get(name) != value:
                monkeypatch.setenv(name, value)
        yield RosGraph(lease)


@pytest.fixture
def context(ros_graph):
    """Yield an initialised rclpy context in the test's private graph (shut down afterwards)."""
    import rclpy

    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        yield ctx
    finally:
        rclpy.try_shutdown(context=ctx)


T0_NS = 1_700_000_000 * 10**9
"""Default first stamp (ns since the epoch) of a record given in seconds (``t_s``)."""

STORAGES = ('sqlite3', 'mcap', 'ros1', 'csv')


def _stamps(n, stamps_ns, t_s, rate_hz, t0_ns):
    given = [x is not None for x in (stamps_ns, t_s, rate_hz)]
    if sum(given) > 1:
        raise ValueError('give one of stamps_ns, t_s and rate_hz')
    if stamps_ns is not None:
        stamps = np.asarray(stamps_ns, dtype=np.int64)
    else:
        if t_s is None:
            t_s = np.arange(n) / (100.0 if rate_hz is None else rate_hz)
        stamps = t0_ns + np.round(np.asarray(t_s, dtype=np.float64) * 1e9).astype(np.int64)
    if stamps.shape != (n,):
        raise ValueError(f'{stamps.shape[0]} stamps for {n} gyro samples')
    return stamps


def _write_ros1(path, stamps, gyro, accel, temp_stamps, temperature_c, *, imu_topic,
                temperature_topic, frame_id):
    """ROS 1 bag through rosbags' writer and per-message serialiser (log time = stamp)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import get_typestore, Stores

    store = get_typestore(Stores.ROS1_NOETIC)
    ty = store.types
    imu_type, temp_type = 'sensor_msgs/msg/Imu', 'sensor_msgs/msg/Temperature'

    def header(seq, stamp):
        t = ty['builtin_interfaces/msg/Time'](sec=int(stamp) // 10**9,
                                              nanosec=int(stamp) % 10**9)
        return ty['std_msgs/msg/Header'](seq=seq, stamp=t, frame_id=frame_id)

    v3 = ty['geometry_msgs/msg/Vector3']
    with Writer(path) as writer:
        imu = writer.add_connection(imu_topic, imu_type, typestore=store)
        if temperature_c is not None:
            tc = writer.add_connection(temperature_topic, temp_type, typestore=store)
            for k, stamp in enumerate(temp_stamps.tolist()):
                msg = ty[temp_type](header=header(k, stamp), temperature=float(temperature_c[k]),
                                    variance=0.0)
                writer.write(tc, stamp, store.serialize_ros1(msg, temp_type))
        for k, stamp in enumerate(stamps.tolist()):
            msg = ty[imu_type](
                header=header(k, stamp),
                orientation=ty['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=np.zeros(9), angular_velocity=v3(*map(float, gyro[k])),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=v3(*map(float, accel[k])),
                linear_acceleration_covariance=np.zeros(9))
            writer.write(imu, stamp, store.serialize_ros1(msg, imu_type))


def _write_csv(path, stamps, gyro, accel, temperature_c, *, t0_ns, with_accel, time_column,
               gyro_unit):
    """CSV with the documented columns: [time_s (from t0_ns)], gyro, [accel], [temperature]."""
    if gyro_unit not in ('rad_s', 'dps'):
        raise ValueError(f"csv_gyro_unit must be 'rad_s' or 'dps', got {gyro_unit!r}")
    names = [f'gyro_{a}_{gyro_unit}' for a in 'xyz']
    cols = [gyro if gyro_unit == 'rad_s' else np.rad2deg(gyro)]
    if time_column:
        names.insert(0, 'time_s')
        cols.insert(0, (stamps - t0_ns) / 1e9)
    if with_accel:
        names += ['accel_x_m_s2', 'accel_y_m_s2', 'accel_z_m_s2']
        cols.append(accel)
    if temperature_c is not None:
        names.append('temperature_c')
        cols.append(np.asarray(temperature_c, dtype=np.float64)[:, None])
    np.savetxt(path, np.column_stack(cols), delimiter=',', header=','.join(names), comments='',
               fmt='%.17g')


def write_record(path, gyro_rad_s, *, stamps_ns=None, t_s=None, rate_hz=None, accel_m_s2=None,
                 temperature_c=None, temperature_stamps_ns=None, temperature_t_s=None,
                 temperature_variance=0.0, storage='sqlite3', imu_topic='/imu/data_raw',
                 temperature_topic='/imu/temperature', frame_id='imu_link', log_ns=None,
                 extra_imu=None, t0_ns=T0_NS, csv_time=True, csv_gyro_unit='rad_s'):
    """
    Write one tiny recording and return its path.

    Parameters
    ----------
    path : pathlib.Path
        Bag folder (rosbag2), ``.bag`` file (ROS 1) or ``.csv`` file to create.
    gyro_rad_s : array_like, shape (n, 3)
        Angular rate samples; n = 0 gives a bag with its Imu topic and no message.
    stamps_ns, t_s, rate_hz : keyword-only
        The Imu header stamps: given in ns, or in seconds from ``t0_ns``, or evenly at
        ``rate_hz`` from ``t0_ns`` (at most one of the three; default 100 Hz).
    accel_m_s2 : array_like, shape (n, 3), keyword-only
        Acceleration; default (0, 0, 9.81) in every sample.
    temperature_c : array_like, keyword-only
        Temperature messages (bags) or the ``temperature_c`` column (CSV, one per sample).
    temperature_stamps_ns, temperature_t_s : array_like, keyword-only
        Stamps of the temperature messages (default: the Imu stamps).
    temperature_variance : float, keyword-only
        Variance field of the temperature messages (rosbag2).
    storage : {'sqlite3', 'mcap', 'ros1', 'csv'}, keyword-only
        rosbag2 through the package's ImuBagWriter; ROS 1 through rosbags; CSV (no topics).
    imu_topic, temperature_topic, frame_id : str, keyword-only
        Topic names and header frame id.
    log_ns : array_like, keyword-only
        Receive (log) times of the Imu messages in rosbag2 (default: the stamps).
    extra_imu : dict, keyword-only
        rosbag2 only: ``{topic: (gyro, accel)}`` further Imu topics on the same stamps and
        receive times.
    t0_ns : int, keyword-only
        Origin of ``t_s`` and ``rate_hz`` stamps and of the CSV time column.
    csv_time : bool, keyword-only
        CSV only: write the ``time_s`` column (False: none, a reader then needs the rate).
    csv_gyro_unit : {'rad_s', 'dps'}, keyword-only
        CSV only: unit of the gyro columns (``gyro_x_dps``: the samples converted to deg/s).

    Returns
    -------
    pathlib.Path

    """
    if storage not in STORAGES:
        raise ValueError(f'storage must be one of {STORAGES}, got {storage!r}')
    path = Path(path)
    gyro = np.asarray(gyro_rad_s, dtype=np.float64)
    n = gyro.shape[0]
    stamps = _stamps(n, stamps_ns, t_s, rate_hz, t0_ns)
    with_accel = accel_m_s2 is not None
    accel = (np.tile([0.0, 0.0, 9.81], (n, 1)) if accel_m_s2 is None
             else np.asarray(accel_m_s2, dtype=np.float64))
    temp_stamps = None
    if temperature_c is not None:
        temperature_c = np.asarray(temperature_c, dtype=np.float64)
        if temperature_stamps_ns is not None or temperature_t_s is not None:
            temp_stamps = _stamps(temperature_c.size, temperature_stamps_ns, temperature_t_s,
                                  None, t0_ns)
        else:
            temp_stamps = stamps
    if storage == 'csv':
        if temp_stamps is not None and temp_stamps is not stamps:
            raise ValueError('a CSV holds one temperature per gyro sample')
        _write_csv(path, stamps, gyro, accel, temperature_c, t0_ns=t0_ns, with_accel=with_accel,
                   time_column=csv_time, gyro_unit=csv_gyro_unit)
        return path
    if storage == 'ros1':
        _write_ros1(path, stamps, gyro, accel, temp_stamps, temperature_c, imu_topic=imu_topic,
                    temperature_topic=temperature_topic, frame_id=frame_id)
        return path
    from gyro_noise_ros.bag import ImuBagWriter

    with ImuBagWriter(path, storage=storage, imu_topic=imu_topic,
                      temperature_topic=temperature_topic, frame_id=frame_id) as writer:
        if n:
            writer.write_imu(stamps, gyro, accel, log_ns=log_ns)
        for topic, (g, a) in (extra_imu or {}).items():
            writer.write_imu(stamps, g, a, topic=topic, log_ns=log_ns)
        if temperature_c is not None:
            writer.write_temperature(temp_stamps, temperature_c, variance=temperature_variance)
    return path


@pytest.fixture(scope='session')
def make_record(tmp_path_factory):
    """
    Return :func:`write_record`; a bare name (no folder) is placed in a fresh temporary folder.

    Session-scoped so module-scoped fixtures can build their inputs once; tests pass
    ``tmp_path / name`` to keep a record beside their other files.
    """
    def make(path, gyro_rad_s, **kw):
        path = Path(path)
        if not path.is_absolute():
            path = tmp_path_factory.mktemp('record') / path
        return write_record(path, gyro_rad_s, **kw)

    return make
