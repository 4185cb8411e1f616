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
chunks.csv and allan.csv of an analysis: one row per chunk, one row per averaging time.

Units: the engine works in SI (rad/s); every number written here is converted to deg/s at this
edge and its unit is in the column name (``bias_deg_s``, ``variance_deg2_s2``, ``adev_deg_s``);
floats are written losslessly (``repr``). The columns are documented in ``docs/offline_tool.md``.
"""

from collections.abc import Iterable
import csv
import math
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..outputs import StrPath
from ..units import RAD_TO_DEG

if TYPE_CHECKING:  # annotations only: a renderer needs no engine at run time
    from ..core.allan import AllanResult
    from ..core.results import ChunkResult

__all__ = ['ALLAN_COLUMNS', 'CHUNK_COLUMNS', 'ChunkCsvWriter', 'allan_curve', 'write_allan_csv']

_DEG2 = RAD_TO_DEG ** 2

#: Columns of chunks.csv, in order.
CHUNK_COLUMNS = ('bag', 'axis', 'chunk', 'status', 't_start_s', 't_mid_s', 'stamp_start_ns',
                 'samples', 'samples_lost', 'gaps', 'nan_samples', 'bias_deg_s',
                 'variance_deg2_s2', 'alpha_var', 'f_var', 'var_min_deg2_s2', 'alpha_corr',
                 'f_corr', 'j_min_deg2_s2', 'tie_var', 'tie_corr', 'noise_colour_adev_slope',
                 'temperature_c', 'message')

#: Columns of allan.csv, in order.
ALLAN_COLUMNS = ('bag', 'axis', 'tau_s', 'adev_deg_s', 'ci_low_deg_s', 'ci_high_deg_s', 'n')

#: One Allan curve of allan.csv: bag, axis, tau (s), deviation and its interval (rad/s), terms.
AllanEntry = tuple[str, str, NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any]]


def _num(value: float) -> str:
    """Format a float losslessly (repr), NaN as 'nan'."""
    value = float(value)
    return repr(value) if math.isfinite(value) else 'nan'


class ChunkCsvWriter:
    """
    Stream ``chunks.csv``: one row per bag, axis and chunk, written as results arrive.

    Parameters
    ----------
    path : str or os.PathLike
        Output file (overwritten).

    """

    def __init__(self, path: StrPath) -> None:
        self._fh = open(path, 'w', newline='')  # noqa: SIM115 - closed in close()
        self._csv = csv.writer(self._fh)
        self._csv.writerow(CHUNK_COLUMNS)
        self.rows = 0

    def write(self, bag: str, result: 'ChunkResult') -> None:
        """
        Append one :class:`..core.results.ChunkResult` of bag ``bag``.

        Parameters
        ----------
        bag : str
            Bag label.
        result : ChunkResult
            One analysed chunk.

        """
        r = result
        self._csv.writerow((bag, r.axis, r.chunk, r.status, _num(r.t_start_s), _num(r.t_mid_s),
                            r.stamp_start_ns, r.samples, r.samples_lost, r.gaps, r.nan_samples,
                            _num(r.bias_rad_s * RAD_TO_DEG), _num(r.variance_rad2_s2 * _DEG2),
                            _num(r.alpha_var), _num(r.f_var), _num(r.var_min * _DEG2),
                            _num(r.alpha_corr), _num(r.f_corr), _num(r.j_min * _DEG2),
                            int(r.tie_var), int(r.tie_corr), _num(r.noise_colour),
                            _num(r.temperature_c), r.message))
        self.rows += 1

    def close(self) -> None:
        """Close the file."""
        self._fh.close()


def write_allan_csv(path: StrPath, entries: Iterable[AllanEntry]) -> None:
    """
    Write allan.csv.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file to write.
    entries : iterable of (bag, axis, tau_s, adev_rad_s, ci_low_rad_s, ci_high_rad_s, n)
        Arrays per (bag, axis); the deviation and its confidence interval in rad/s.

    """
    with open(path, 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(ALLAN_COLUMNS)
        for bag, axis, tau, adev, lo, hi, n in entries:
            for i in range(len(tau)):
                w.writerow((bag, axis, _num(tau[i]), _num(adev[i] * RAD_TO_DEG),
                            _num(lo[i] * RAD_TO_DEG), _num(hi[i] * RAD_TO_DEG), int(n[i])))


def allan_curve(result: 'AllanResult') -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                NDArray[np.float64], NDArray[np.float64],
                                                NDArray[np.int64]]:
    """
    Return (tau_s, adev, ci_low, ci_high, n) arrays of an Allan result (rad/s), NaN-free rows only.

    The rows of allan.csv, and the points the Allan figures draw.

    Parameters
    ----------
    result : core.allan.AllanResult
        The Allan deviation of one bag and axis.

    Returns
    -------
    tuple of numpy.ndarray

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    lo = np.asarray(getattr(result, 'ci_low', np.full_like(adev, np.nan)), dtype=np.float64)
    hi = np.asarray(getattr(result, 'ci_high', np.full_like(adev, np.nan)), dtype=np.float64)
    n = np.asarray(getattr(result, 'n_terms', np.zeros(adev.shape, np.int64)), dtype=np.int64)
    ok = np.isfinite(adev) & np.isfinite(tau)
    return tau[ok], adev[ok], lo[ok], hi[ok], n[ok]
