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
IMU records that are not bags: CSV tables and PX4 ULog files, read like :class:`ImuBagReader`.

Both kinds are loaded whole (minutes to hours of 100-1000 Hz data, tens of MB) and served in
:class:`ImuBatch` es, so ``gyro_noise_analyze`` and ``gyro_noise_explain`` read them as bags.

CSV (one header line, names case-insensitive; comma, semicolon or tab separated, '.' decimals;
a UTF-8 byte-order mark and CRLF line ends are read):

=============================================  ===================================================
``time_s`` / ``t_s`` / ``time (s)``             sample time (s); or ``timestamp_us`` (us); optional
                                                when the caller gives a rate
``gyro_x_rad_s`` ... or ``gyro_x_dps`` ...      angular rate (rad/s or deg/s); x-io's
                                                ``gyroscope x (deg/s)`` is accepted
``acc_x_m_s2`` / ``accel_x_m_s2`` or ``_g``     specific force (m/s^2 or g), optional
``temperature_c`` / ``temp_c``                  sensor temperature (degC), optional
``seq``                                         per-sample counter, optional (exact loss)
=============================================  ===================================================

ULog (PX4, read with ``pyulog``): topic ``sensor_combined`` (``gyro_rad[0..2]``,
``accelerometer_m_s2[0..2]``, default) or ``sensor_gyro`` (``x, y, z``, ``temperature``;
instance 0); stamps are the ``timestamp`` field (us, the autopilot's monotonic clock).
"""

from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, Literal, Self

import numpy as np

from .batch import ImuBatch
from ..errors import BagError, InputDataError, ParameterError
from ..outputs import StrPath
from ..units import DEG_TO_RAD, STANDARD_GRAVITY_M_S2

#: Suffixes read by :class:`TableImuReader`.
TABLE_SUFFIXES = ('.csv', '.ulg')
#: Column separators of a CSV, in the order they are looked for in its header line (a
#: spreadsheet in a locale with decimal commas writes ';').
CSV_DELIMITERS = (',', ';', '\t')
#: Largest time span of a record (s): its stamps are int64 nanoseconds (292 years).
MAX_SPAN_S = (2**63 - 1) / 1e9
#: ULog topics understood, in order of preference.
ULOG_TOPICS = ('sensor_combined', 'sensor_gyro')

_AXES = 'xyz'

#: A loaded record: (stamp_ns, gyro_rad_s, accel_m_s2, temperature_c or None, seq or None,
#: topic).
_Loaded = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None, str]


def is_table(path: StrPath) -> bool:
    """Tell whether ``path`` names a CSV or ULog file (by its suffix)."""
    return Path(path).suffix.lower() in TABLE_SUFFIXES


def read_csv(path: StrPath, *, check_header: Callable[[list[str]], object] | None = None
             ) -> tuple[list[str], np.ndarray]:
    """
    Read a CSV table of numbers with one header line (the reading every tool shares).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    check_header : callable, optional, keyword-only
        Called with the header names before the rows are read (so a wrong format is said before
        a missing row); it raises to refuse them.

    Returns
    -------
    tuple
        ``(names, data)``: the header names, stripped and lower-case, and the rows as a float64
        array of shape (rows, columns).

    Raises
    ------
    BagError
        The file cannot be read, is empty (no header line), or holds a value that is not a
        number or a row of another length (exit code 3: the input is unreadable).
    InputDataError
        A header and no data rows (exit code 4: readable, nothing to analyse).

    """
    import csv
    import warnings

    path = Path(path)
    try:
        # utf-8-sig: Excel's "CSV UTF-8" starts with a byte-order mark
        with path.open(newline='', encoding='utf-8-sig') as fh:
            line = fh.readline()
    except (OSError, UnicodeDecodeError) as err:
        reason = getattr(err, 'strerror', None) or err
        raise BagError(f'cannot read CSV {str(path)!r}: {reason}') from err
    delimiter = next((d for d in CSV_DELIMITERS if d in line), ',')
    try:
        header = next(csv.reader([line], delimiter=delimiter), None)
    except csv.Error as err:
        raise BagError(f'cannot read CSV {str(path)!r}: {err}') from err
    if not header or not any(h.strip() for h in header):
        raise BagError(f'CSV {str(path)!r} is empty (a header line is required)')
    names = [h.strip().lower() for h in header]
    if check_header is not None:
        check_header(names)
    try:
        with warnings.catch_warnings():
            # numpy warns (UserWarning) on a header without rows: said below as one error line
            warnings.simplefilter('ignore', UserWarning)
            data = np.loadtxt(path, delimiter=delimiter, skiprows=1, ndmin=2, dtype=np.float64,
                              encoding='utf-8-sig')
    except (ValueError, UnicodeDecodeError) as err:
        comma = (' (decimal commas are not read: write 0.5, not 0,5)'
                 if delimiter != ',' and ',' in str(err) else '')
        raise BagError(f'CSV {str(path)!r} has a non-numeric value or a short row{comma}: '
                       f'{err}') from err
    except OSError as err:
        raise BagError(f'cannot read CSV {str(path)!r}: {err.strerror or err}') from err
    if data.shape[0] == 0:
        raise InputDataError(f'too short to analyse: CSV {str(path)!r} has no data rows')
    if any(names[data.shape[1]:]):
        # a named column the rows do not reach (an empty name after a trailing comma is fine)
        raise BagError(f'CSV {str(path)!r} has {len(names)} header names but '
                       f'{data.shape[1]} values per row')
    return names, data


def missing_column_error(path: StrPath, wanted: str, names: Sequence[str]) -> BagError:
    """
    Return the BagError (exit code 3) of CSV ``path`` without the column(s) ``wanted``.

    ``wanted`` is said as given; ``names`` are the header names found, listed in the message.
    """
    return BagError(f'CSV {str(path)!r} has no column {wanted}; columns: {", ".join(names)}')


def _col(names: Sequence[str], *choices: str) -> int | None:
    for c in choices:
        if c in names:
            return names.index(c)
    return None


def _gyro_column(names: Sequence[str], axis: str) -> tuple[int, float] | None:
    """Return (column index, factor to rad/s) of one gyro axis, or None when it is missing."""
    rad = _col(names, f'gyro_{axis}_rad_s')
    dps = _col(names, f'gyro_{axis}_dps', f'gyroscope {axis} (deg/s)')
    if rad is not None:
        return rad, 1.0
    if dps is not None:
        return dps, DEG_TO_RAD
    return None


def csv_gyro_axes(names: Sequence[str]) -> tuple[str, ...]:
    """
    Return the gyro axes a CSV header holds, in the order x, y, z.

    ``names`` are the header names, stripped and lower-case (as :func:`read_csv` returns them).
    """
    return tuple(a for a in _AXES if _gyro_column(names, a) is not None)


def _csv_columns(names: Sequence[str], path: StrPath,
                 gyro_axes: Sequence[str] = _AXES) -> dict[str, Any]:
    """Return the column index (or (index, factor to SI)) of each quantity, None if absent."""
    def col(*choices: str) -> int | None:
        return _col(names, *choices)

    cols: dict[str, Any] = {
        't_s': col('time_s', 't_s', 'time (s)'), 't_us': col('timestamp_us'),
        'seq': col('seq', 'sequence'), 'temp': col('temperature_c', 'temp_c')}
    for a in _AXES:
        gyro = _gyro_column(names, a)
        if gyro is None and a in gyro_axes:
            raise missing_column_error(path, f'gyro_{a}_rad_s (or gyro_{a}_dps)', names)
        # an axis the caller does not need may be missing: it reads as NaN
        cols[f'g{a}'] = gyro if gyro is not None else (None, 1.0)
        ms2 = col(f'acc_{a}_m_s2', f'accel_{a}_m_s2')
        g = col(f'acc_{a}_g', f'accel_{a}_g', f'accelerometer {a} (g)')
        cols[f'a{a}'] = ((ms2, 1.0) if ms2 is not None
                         else (g, STANDARD_GRAVITY_M_S2) if g is not None else (None, 1.0))
    return cols


def _stamps_ns(t: np.ndarray, ns_per_unit: float, path: Path, name: str) -> np.ndarray:
    """Return the int64 ns stamps of a time column after its first value; refuse what cannot be."""
    if not np.all(np.isfinite(t)):
        bad = int((~np.isfinite(t)).sum())
        raise InputDataError(f'CSV {str(path)!r}: {bad} time value(s) are NaN/Inf')
    with np.errstate(over='ignore', invalid='ignore'):
        span_s = (t - t[0]) * (ns_per_unit / 1e9)
    worst = float(np.max(np.abs(span_s))) if span_s.size else 0.0
    if not worst < MAX_SPAN_S:
        bad = int(np.argmax(~(np.abs(span_s) < MAX_SPAN_S)))
        raise InputDataError(f'CSV {str(path)!r}: {name} = {t[bad]:g} in data row {bad + 1} is '
                             f'{worst:.3g} s from the first row, beyond any record (a time '
                             f'stamp reaches {MAX_SPAN_S:.3g} s)')
    return np.rint((t - t[0]) * ns_per_unit).astype(np.int64)


def _load_csv(path: Path, rate_hz: float | None, gyro_axes: Sequence[str]) -> _Loaded:
    names, data = read_csv(path, check_header=lambda names: _csv_columns(names, path, gyro_axes))
    cols = _csv_columns(names, path, gyro_axes)
    if cols['t_s'] is None and cols['t_us'] is None and rate_hz is None:
        raise ParameterError(f'CSV {str(path)!r} has no time_s column: give {{rate_hz}}',
                             parameters=('rate_hz',))
    n = data.shape[0]
    if cols['t_s'] is not None:
        stamp = _stamps_ns(data[:, cols['t_s']], 1e9, path, names[cols['t_s']])
    elif cols['t_us'] is not None:
        stamp = _stamps_ns(data[:, cols['t_us']], 1e3, path, names[cols['t_us']])
    else:
        assert rate_hz is not None  # refused above without a time column
        stamp = np.rint(np.arange(n) * (1e9 / float(rate_hz))).astype(np.int64)
    gyro = np.column_stack([data[:, cols[f'g{a}'][0]] * cols[f'g{a}'][1]
                            if cols[f'g{a}'][0] is not None else np.full(n, np.nan)
                            for a in _AXES])
    accel = np.column_stack([data[:, cols[f'a{a}'][0]] * cols[f'a{a}'][1]
                             if cols[f'a{a}'][0] is not None else np.full(n, np.nan)
                             for a in _AXES])
    temp = data[:, cols['temp']] if cols['temp'] is not None else None
    seq = data[:, cols['seq']].astype(np.int64) if cols['seq'] is not None else None
    return stamp, gyro, accel, temp, seq, 'csv'


def _load_ulog(path: Path, topic: str | None) -> _Loaded:
    try:
        from pyulog import ULog
    except ImportError as err:  # pragma: no cover - pyulog is a dependency
        raise BagError(f'reading ULog {str(path)!r} needs pyulog (pip install pyulog)') from err
    wanted = ULOG_TOPICS if topic is None else (topic.lstrip('/'),)
    if any(w not in ULOG_TOPICS for w in wanted):
        raise BagError(f'ULog topic must be one of {ULOG_TOPICS}, got {topic!r}')
    try:
        log = ULog(str(path), message_name_filter_list=list(wanted))
    except FileNotFoundError as err:
        raise BagError(f'cannot read ULog {str(path)!r}: no such file') from err
    except Exception as err:  # noqa: B902 - pyulog raises bare Exceptions on corrupt files
        raise BagError(f'cannot read ULog {str(path)!r}: {err}') from err
    found = {d.name: d for d in log.data_list if d.multi_id == 0}
    name = next((w for w in wanted if w in found), None)
    if name is None:
        raise BagError(f'ULog {str(path)!r} has none of the topics {", ".join(wanted)}')
    d = found[name].data
    stamp = (d['timestamp'].astype(np.int64) - int(d['timestamp'][0])) * 1000
    n = stamp.shape[0]
    if name == 'sensor_combined':
        gyro = np.column_stack([d[f'gyro_rad[{i}]'] for i in range(3)]).astype(np.float64)
        accel = np.column_stack([d.get(f'accelerometer_m_s2[{i}]', np.full(n, np.nan))
                                 for i in range(3)]).astype(np.float64)
        temp = None
    else:
        gyro = np.column_stack([d[k] for k in 'xyz']).astype(np.float64)
        accel = np.full((n, 3), np.nan)
        temp = d['temperature'].astype(np.float64) if 'temperature' in d else None
    return stamp, gyro, accel, temp, None, name


class TableImuReader:
    """
    A CSV or ULog record served like :class:`ImuBagReader` (module doc for the columns).

    Parameters
    ----------
    path : str or os.PathLike
        ``.csv`` or ``.ulg`` file.
    topic : str, optional
        ULog topic (``sensor_combined`` or ``sensor_gyro``); ignored for CSV.
    rate_hz : float, optional
        Rate (Hz) for a CSV without a time column.
    gyro_axes : str or tuple of str, optional
        The gyro axes a CSV must hold (default all three); a missing other axis reads as NaN.

    Attributes
    ----------
    topic, storage : str
        ULog topic or 'csv'; 'csv' or 'ulog'.
    message_count : int
    temperature_topic : str or None
        'temperature_c' when the record has a temperature.
    undecodable_count : int
        Always 0.
    sequence : numpy.ndarray or None
        Per-sample counter of a CSV ``seq`` column.

    """

    def __init__(self, path: StrPath, *, topic: str | None = None,
                 temperature_topic: str | None = None, rate_hz: float | None = None,
                 gyro_axes: Iterable[str] = _AXES) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise BagError(f'cannot read {str(self.path)!r}: no such file')
        if self.path.suffix.lower() == '.ulg':
            loaded = _load_ulog(self.path, topic)
            self.storage = 'ulog'
        else:
            loaded = _load_csv(self.path, rate_hz, tuple(gyro_axes))
            self.storage = 'csv'
        self._stamp, self._gyro, self._accel, self._temp, self.sequence, self.topic = loaded
        self.message_count = int(self._stamp.shape[0])
        self.temperature_topic = 'temperature_c' if self._temp is not None else None
        if temperature_topic is not None and self._temp is None:
            raise BagError(f'{str(self.path)!r} has no temperature')
        self.undecodable_count = 0

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> Literal[False]:
        return False

    def close(self) -> None:
        """Nothing to release (the record is in memory)."""

    def iter_batches(self, batch_size: int = 65536) -> Iterator[ImuBatch]:
        """
        Yield the samples as :class:`ImuBatch` es of ``batch_size``.

        Parameters
        ----------
        batch_size : int
            Samples per batch (>= 1).

        Yields
        ------
        ImuBatch

        """
        size = int(batch_size)
        if size < 1:
            raise ParameterError(f'batch_size must be a positive integer, got {batch_size!r}')
        for i in range(0, self.message_count, size):
            sl = slice(i, i + size)
            stamp_ns = self._stamp[sl]
            yield ImuBatch(stamp_ns=stamp_ns, log_ns=stamp_ns, gyro=self._gyro[sl],
                           accel=self._accel[sl], frame_id='imu_link')

    def read_temperature(self) -> tuple[np.ndarray, np.ndarray] | None:
        """
        Return ``(stamp_ns, temperature_c)`` or None.

        Returns
        -------
        tuple of numpy.ndarray or None

        """
        if self._temp is None:
            return None
        return self._stamp.copy(), self._temp.astype(np.float64)
