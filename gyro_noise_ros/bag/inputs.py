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
The one input layer: recognise an IMU recording by its path and open it.

Every offline tool that reads a recording (``gyro_noise_analyze``, ``gyro_noise_explain``) opens
it here, so each reads what the other reads, with the same refusals and exit codes (3: missing,
unreadable, wrong format or headers, no or ambiguous topic; 4: readable with nothing to analyse).

=====================================  ===========================================================
path                                   read by
=====================================  ===========================================================
rosbag2 folder, ``metadata.yaml``,     :class:`~gyro_noise_ros.bag.ImuBagReader` (``sensor_msgs/
``.db3`` or ``.mcap`` file; ROS 1      Imu``, optional ``sensor_msgs/Temperature``; the storage
``.bag`` file                          kind is read from the content, see ``docs/bags.md``)
``.csv`` table; PX4 ULog ``.ulg``      :class:`~gyro_noise_ros.bag.tabular.TableImuReader` (the
                                       column spellings and units of :mod:`.tabular`; ULogs
                                       with ``pyulog``)
=====================================  ===========================================================

:func:`input_kind` names the kind of a path; :func:`open_imu` returns the reader (a context
manager with ``iter_batches`` and ``read_temperature``); :func:`read_imu` reads a whole record
into an :class:`ImuRecord` (stamps, the three gyro axes in rad/s and the temperature on the Imu
stamps) for the tools that need it in memory; :func:`recorded_axes` lists the gyro axes a record
holds.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .reader import ImuBagReader
from .tabular import csv_gyro_axes, is_table, TableImuReader
from ..errors import BagError, InputDataError
from ..outputs import StrPath

__all__ = ['AXES', 'ImuRecord', 'input_kind', 'is_table', 'open_imu', 'read_imu', 'recorded_axes']

#: Gyro axes, in column order.
AXES = ('x', 'y', 'z')


def input_kind(path: StrPath) -> str:
    """
    Tell what kind of recording a path names (by its name; the bag reader checks the content).

    Parameters
    ----------
    path : str or os.PathLike
        The recording.

    Returns
    -------
    str
        ``'csv'``, ``'ulog'``, ``'ros1'`` (a ``.bag`` file) or ``'rosbag2'`` (anything else: a
        folder, ``metadata.yaml``, ``.db3`` or ``.mcap``; a file that is none of these is refused
        when opened).

    """
    suffix = Path(path).suffix.lower()
    if suffix == '.csv':
        return 'csv'
    if suffix == '.ulg':
        return 'ulog'
    if suffix == '.bag':
        return 'ros1'
    return 'rosbag2'


def _check_exists(path: StrPath) -> Path:
    path = Path(path)
    if not path.exists():
        raise BagError(f'cannot read {str(path)!r}: no such file or folder')
    return path


def open_imu(path: StrPath, *, topic: str | None = None, temperature_topic: str | None = None,
             rate_hz: float | None = None,
             gyro_axes: Iterable[str] = AXES) -> ImuBagReader | TableImuReader:
    """
    Open a recording as a stream of :class:`~gyro_noise_ros.bag.ImuBatch` es (module doc).

    Parameters
    ----------
    path : str or os.PathLike
        The recording.
    topic : str, optional, keyword-only
        ``sensor_msgs/Imu`` topic of a bag, or ULog topic (default: the only one / the first
        ULog topic found).
    temperature_topic : str, optional, keyword-only
        ``sensor_msgs/Temperature`` topic (naming it makes a temperature required).
    rate_hz : float, optional, keyword-only
        Rate (Hz) of a CSV without a time column (required there).
    gyro_axes : tuple of str, keyword-only
        Gyro axes a CSV must hold (default all three; a missing other axis reads as NaN).

    Returns
    -------
    ImuBagReader or TableImuReader
        A context manager with ``topic``, ``storage``, ``message_count``, ``iter_batches`` and
        ``read_temperature``.

    Raises
    ------
    BagError
        Missing path, not a recording, unreadable, wrong headers, no or ambiguous topic (exit 3).
    InputDataError
        A CSV header without rows (exit 4).
    ParameterError
        A CSV without a time column and no ``rate_hz`` (exit 2).

    """
    path = _check_exists(path)
    if is_table(path):
        return TableImuReader(path, topic=topic, temperature_topic=temperature_topic,
                              rate_hz=rate_hz, gyro_axes=tuple(gyro_axes))
    return ImuBagReader(path, topic=topic, temperature_topic=temperature_topic)


def recorded_axes(path: StrPath) -> tuple[str, ...]:
    """
    Return the gyro axes a recording holds (a CSV may carry only some; bags and ULogs hold three).

    Parameters
    ----------
    path : str or os.PathLike
        The recording.

    Returns
    -------
    tuple of str
        The axes found, or all three when the header cannot be read (opening the file then says
        what is wrong with it) or names none.

    """
    import csv

    path = Path(path)
    if input_kind(path) != 'csv' or not path.is_file():
        return AXES
    try:
        with path.open(newline='') as fh:
            header = [h.strip().lower() for h in next(csv.reader(fh), [])]
    except (OSError, UnicodeDecodeError, csv.Error):
        return AXES
    return csv_gyro_axes(header) or AXES


@dataclass(frozen=True)
class ImuRecord:
    """
    A whole recording in memory (SI units).

    Attributes
    ----------
    stamp_ns : numpy.ndarray
        Header stamps (int64 ns), shape (n,).
    gyro_rad_s : numpy.ndarray
        Angular rate (rad/s), shape (n, 3) in x, y, z order; NaN for an axis a CSV lacks.
    temperature_c : numpy.ndarray or None
        Temperature (degC) on the Imu stamps (a bag's Temperature messages interpolated
        linearly), or None.
    topic : str
        Imu topic, ULog topic, or ``'csv'``.
    storage : str
        Storage kind (``'sqlite3'``, ``'mcap'``, ``'ros1'``, ``'csv'``, ``'ulog'``).
    source : str
        The path, with the topic for a bag or a ULog (for reports).

    """

    stamp_ns: np.ndarray
    gyro_rad_s: np.ndarray
    temperature_c: np.ndarray | None
    topic: str
    storage: str
    source: str

    @property
    def n(self) -> int:
        """Count the samples."""
        return int(self.stamp_ns.shape[0])


def read_imu(path: StrPath, *, topic: str | None = None, temperature_topic: str | None = None,
             rate_hz: float | None = None, gyro_axes: Iterable[str] = AXES) -> ImuRecord:
    """
    Read a whole recording into an :class:`ImuRecord` (module doc; arguments as :func:`open_imu`).

    Returns
    -------
    ImuRecord

    Raises
    ------
    BagError, InputDataError, ParameterError
        As :func:`open_imu`; InputDataError also for a recording without Imu samples.

    """
    stamps, gyro = [], []
    with open_imu(path, topic=topic, temperature_topic=temperature_topic, rate_hz=rate_hz,
                  gyro_axes=gyro_axes) as reader:
        for batch in reader.iter_batches():
            stamps.append(batch.stamp_ns)
            gyro.append(batch.gyro)
        temperature = reader.read_temperature()
        imu_topic, storage = reader.topic, reader.storage
    if not stamps:
        raise InputDataError(f'too short to analyse: {str(path)!r} has no Imu samples on '
                             f'{imu_topic}')
    stamp_ns = np.concatenate(stamps)
    temp = None
    if temperature is not None and temperature[0].size:
        t_stamp, t_value = temperature
        if t_stamp.shape == stamp_ns.shape and np.array_equal(t_stamp, stamp_ns):
            # a table's temperature column: one value per sample already
            temp = np.asarray(t_value, dtype=np.float64)
        else:
            ts = (t_stamp - stamp_ns[0]).astype(np.float64) * 1e-9
            order = np.argsort(ts, kind='stable')
            temp = np.interp((stamp_ns - stamp_ns[0]).astype(np.float64) * 1e-9, ts[order],
                             np.asarray(t_value, dtype=np.float64)[order])
    source = str(path) if storage == 'csv' else f'{path} ({imu_topic})'
    return ImuRecord(stamp_ns=stamp_ns, gyro_rad_s=np.concatenate(gyro), temperature_c=temp,
                     topic=imu_topic, storage=storage, source=source)
