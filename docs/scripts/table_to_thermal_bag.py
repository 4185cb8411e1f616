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
Write a CSV (or ULog) IMU record with a temperature column as a rosbag2 for gyro_noise_thermal.

Usage: ``python docs/scripts/table_to_thermal_bag.py RECORD.csv OUT_BAG``. The record is read
by :class:`gyro_noise_ros.bag.tabular.TableImuReader` (the columns ``gyro_noise_analyze``
accepts: ``t_s``, ``gyro_x_dps`` ..., ``acc_x_g`` ..., ``temp_c``; units converted to SI) and
written with :class:`gyro_noise_ros.bag.ImuBagWriter`: ``/imu/data_raw`` (every sample, header
stamp = the record's time) and ``/imu/temperature`` (one message per temperature sample, same
stamps). ``gyro_noise_thermal`` reads bags only; this is the bridge used in ``docs/thermal.md``,
"Real data". Exit 0, or 1 with one line on stderr.
"""

import sys

from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.bag.tabular import TableImuReader
import numpy as np

#: Stamp of t = 0 (ns): 2023-11-14, as the package's simulators use; any fixed value would do.
START_NS = 1_700_000_000 * 1_000_000_000


def convert(record, out_bag, *, storage='sqlite3'):
    """
    Convert one table to a rosbag2 with Imu and Temperature topics.

    Parameters
    ----------
    record : str or os.PathLike
        ``.csv`` or ``.ulg`` file with a temperature.
    out_bag : str or os.PathLike
        Bag directory to create (must not exist).
    storage : {'sqlite3', 'mcap'}, keyword-only
        rosbag2 storage plugin.

    Returns
    -------
    tuple of int
        Imu and Temperature messages written.

    """
    with TableImuReader(record) as reader:
        batches = list(reader.iter_batches())
        temperature = reader.read_temperature()
    if temperature is None:
        raise ValueError(f'{record}: no temperature column (temp_c / temperature_c)')
    stamp = np.concatenate([b.stamp_ns for b in batches])
    t0 = int(stamp[0])
    with ImuBagWriter(out_bag, storage=storage) as writer:
        for b in batches:
            writer.write_imu(START_NS + (b.stamp_ns - t0), b.gyro, b.accel)
        t_stamp, t_c = temperature
        writer.write_temperature(START_NS + (t_stamp - t0), t_c, variance=0.0)
    return int(stamp.size), int(t_c.size)


def main(argv=None):
    """Run the conversion; print what was written."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 2:
        print('usage: table_to_thermal_bag.py RECORD.csv OUT_BAG', file=sys.stderr)
        return 1
    try:
        n_imu, n_temp = convert(argv[0], argv[1])
    except Exception as err:  # noqa: BLE001 - one line for the user, as the package's tools do
        print(f'table_to_thermal_bag.py: error: {err}', file=sys.stderr)
        return 1
    print(f'wrote {argv[1]}: {n_imu} Imu and {n_temp} Temperature messages')
    return 0


if __name__ == '__main__':
    sys.exit(main())
