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
Read the recordings of the reliability procedure: IMU batches in SI with stamps in seconds.

Streams :class:`gyro_noise_ros.bag.ImuBagReader` (constant memory). The sample rate comes from the
first batch's stamps by the package's one estimator (``core.timebase``, right on bursty host
stamps too; a record with no two distinct stamps cannot be analysed), or a nominal rate when given.
"""

from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..bag import ImuBagReader, ImuBatch
from ..core.timebase import estimate_rate, RATE_RANGE_HZ
from ..errors import InputDataError, ParameterError
from ..outputs import StrPath

#: ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)``: one batch of a recording (:func:`iter_imu`). The
#: stamps are float64 (integer nanoseconds times 1e-9), which numpy's stubs call floating.
_ImuBatch = tuple[float, NDArray[np.floating[Any]], NDArray[np.float64], NDArray[np.float64]]
#: ``(t_s, temperature_degc)`` of a recording (:func:`read_temperature`).
_Temperature = tuple[NDArray[np.floating[Any]], NDArray[np.float64]]

#: Messages decoded per batch (~0.4 KB each).
BATCH = 65536


def rate_from_stamps(stamp_ns: ArrayLike, source: str = '') -> float:
    """
    Return the sample rate of the stamps by the package's estimator (``core.timebase``).

    Parameters
    ----------
    stamp_ns : array_like
        Stamps (ns).
    source : str
        Recording name for the message.

    Returns
    -------
    float
        Rate (Hz).

    Raises
    ------
    InputDataError
        Fewer than two samples or no positive interval.

    """
    st = np.asarray(stamp_ns, dtype=np.int64)
    if np.count_nonzero(np.diff(st) > 0) == 0:
        raise InputDataError(f'recording {source!r}: fewer than two distinct stamps, so no '
                             f'sample rate')
    # The package's one estimator (core.timebase): a median step reads bursty host stamps
    # (MPU6050: 2 ms steps at a 99.3 Hz mean rate) as a 5x too high rate.
    try:
        est = estimate_rate(st, unit='ns')
    except InputDataError as err:
        raise InputDataError(f'recording {source!r}: {err}') from err
    if not est.usable:
        raise InputDataError(f'recording {source!r}: no usable sample rate from the stamps: '
                             f'{"; ".join(est.warnings)} (give {{rate_hz}})',
                             parameters=('rate_hz',))
    return float(est.rate_hz)


def iter_imu(path: StrPath, *, topic: str | None = None, rate_hz: float | None = None,
             batch: int = BATCH, t0_ns: int | None = None) -> Iterator[_ImuBatch]:
    """
    Yield the recording as ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)`` batches.

    Parameters
    ----------
    path : str or os.PathLike
        Recording (anything :class:`~gyro_noise_ros.bag.ImuBagReader` reads).
    topic : str, optional, keyword-only
        ``sensor_msgs/Imu`` topic; the single one when None.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz); from the stamps when None.
    batch : int, keyword-only
        Messages per batch.
    t0_ns : int, optional, keyword-only
        Stamp (ns) that becomes t = 0; the first sample's when None.

    Yields
    ------
    tuple
        Rate (Hz, fixed by the first batch), stamps (s, relative to ``t0_ns``), (n, 3)
        specific force (m/s^2), (n, 3) angular rate (rad/s).

    """
    if rate_hz is not None and not RATE_RANGE_HZ[0] <= rate_hz <= RATE_RANGE_HZ[1]:
        raise ParameterError(f'{{rate_hz}} must be {RATE_RANGE_HZ[0]:g} to '
                             f'{RATE_RANGE_HZ[1]:g} Hz, got {rate_hz!r}', parameters=('rate_hz',))
    t0 = t0_ns
    rate = rate_hz
    with ImuBagReader(path, topic=topic) as reader:
        for b in reader.iter_batches(batch):
            if t0 is None:
                t0 = int(b.stamp_ns[0])
            if rate is None:
                rate = rate_from_stamps(b.stamp_ns, str(path))
            t = (b.stamp_ns.astype(np.int64) - t0) * 1e-9
            yield float(rate), t, np.asarray(b.accel, np.float64), np.asarray(b.gyro, np.float64)


def first_stamp_ns(path: StrPath, *, topic: str | None = None) -> int | None:
    """
    Return the stamp of a recording's first Imu sample (ns), None when it holds none.

    Parameters
    ----------
    path : str or os.PathLike
        Recording.
    topic : str, optional, keyword-only
        ``sensor_msgs/Imu`` topic.

    Returns
    -------
    int or None

    """
    b = _first_batch(path, topic)
    return None if b is None else int(b.stamp_ns[0])


def _first_batch(path: StrPath, topic: str | None) -> ImuBatch | None:
    """Return the first non-empty batch of Imu samples of a recording, None when none."""
    with ImuBagReader(path, topic=topic) as reader:
        for b in reader.iter_batches(1024):
            if b.stamp_ns.size:
                return b
    return None


def frame_id(path: StrPath, *, topic: str | None = None) -> str:
    """
    Return the ``header.frame_id`` of a recording's first Imu sample ('' when none is set).

    Parameters
    ----------
    path, topic
        As :func:`first_stamp_ns`.

    Returns
    -------
    str

    """
    b = _first_batch(path, topic)
    return '' if b is None else (b.frame_id or '')


def read_imu(path: StrPath, *, topic: str | None = None, rate_hz: float | None = None,
             t0_ns: int | None = None) -> _ImuBatch:
    """
    Read a whole recording into memory (for records of a few million samples).

    Parameters
    ----------
    path : str or os.PathLike
        Recording.
    topic : str, optional, keyword-only
        ``sensor_msgs/Imu`` topic.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz).
    t0_ns : int, optional, keyword-only
        Stamp (ns) that becomes t = 0; the first sample's when None.

    Returns
    -------
    tuple
        ``(rate_hz, t_s, accel_m_s2, gyro_rad_s)`` as in :func:`iter_imu`.

    """
    parts = list(iter_imu(path, topic=topic, rate_hz=rate_hz, t0_ns=t0_ns))
    rate = parts[0][0]
    return (rate, np.concatenate([p[1] for p in parts]), np.concatenate([p[2] for p in parts]),
            np.concatenate([p[3] for p in parts]))


def read_temperature(path: StrPath, *, topic: str | None = None,
                     t0_ns: int | None = None) -> _Temperature | None:
    """
    Read a recording's ``sensor_msgs/Temperature`` samples, stamps relative to ``t0_ns``.

    Parameters
    ----------
    path : str or os.PathLike
        Recording.
    topic : str, optional, keyword-only
        ``sensor_msgs/Imu`` topic (selects the Imu stream; the temperature topic is the bag's
        single one, or the one in the Imu topic's namespace).
    t0_ns : int, optional, keyword-only
        Stamp (ns) that becomes t = 0; the first Imu sample's when None (as :func:`iter_imu`).

    Returns
    -------
    tuple or None
        ``(t_s, temperature_degc)`` float64 arrays, or None when the recording has no (single)
        temperature topic.

    """
    with ImuBagReader(path, topic=topic) as reader:
        got = reader.read_temperature()
    if got is None:
        return None
    if t0_ns is None:
        t0_ns = first_stamp_ns(path, topic=topic)
        if t0_ns is None:
            return None
    stamps, temp = got
    return (stamps.astype(np.int64) - int(t0_ns)) * 1e-9, np.asarray(temp, np.float64)


def temperature_stats(temperature: _Temperature | None, start_s: float = -np.inf,
                      end_s: float = np.inf) -> dict[str, float | int] | None:
    """
    Return mean, min and max temperature over ``[start_s, end_s]`` (degC), None when none.

    Parameters
    ----------
    temperature : tuple or None
        ``(t_s, temperature_degc)`` from :func:`read_temperature`.
    start_s, end_s : float
        Span (s, same origin as ``t_s``).

    Returns
    -------
    dict or None
        ``{'mean_degc', 'min_degc', 'max_degc', 'samples'}``; None without temperature samples
        in the span (non-finite readings are left out).

    """
    if temperature is None:
        return None
    t, temp = temperature
    sel = (t >= start_s) & (t <= end_s) & np.isfinite(temp)
    if not np.any(sel):
        return None
    v = temp[sel]
    return {'mean_degc': float(np.mean(v)), 'min_degc': float(np.min(v)),
            'max_degc': float(np.max(v)), 'samples': int(v.size)}
