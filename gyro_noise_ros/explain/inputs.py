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
Inputs of the discrepancy workflow: one gyro axis with stamps, optionally the sensor temperature.

Every recording ``gyro_noise_analyze`` reads is read here, through the one input layer
:mod:`gyro_noise_ros.bag.inputs` (rosbag2 folder / ``.db3`` / ``.mcap``, ROS 1 ``.bag``, CSV with
the column spellings and units of :mod:`gyro_noise_ros.bag.tabular`, PX4 ``.ulg``), with the same
refusals and exit codes; a bag's temperature is interpolated linearly onto the Imu stamps. A CSV
needs only the gyro column of the axis analysed.

The result is a :class:`Measurement` (SI units). Stamps: the nominal rate is ``rate_hz`` if given,
else the :mod:`gyro_noise_ros.core.timebase` estimate (the same estimator as
``gyro_noise_analyze``: step mean for device clocks, block median for bursty host stamps); the
estimate, its method and its warnings are kept in ``Measurement.timebase``.
"""

from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..bag.inputs import AXES, ImuRecord, read_imu
from ..core.plausible import MAX_RATE_RAD_S, non_physical
from ..core.timebase import RateEstimate
from ..errors import InputDataError, nothing_left_error, ParameterError
from ..outputs import StrPath

#: Fewest samples the workflow accepts: 16 chunks of 512 samples (the signatures need a few chunks
#: and the order identification needs chunks longer than its memory; the layout scales with the
#: record, so a minute at 250 Hz, 15,000 samples, is enough).
MIN_SAMPLES = 8192


@dataclass(frozen=True)
class Measurement:
    """
    One gyro axis ready for the discrepancy workflow.

    Attributes
    ----------
    rate : numpy.ndarray
        Angular rate, rad/s, shape (n,).
    t_s : numpy.ndarray
        Sample times in s from the first sample, shape (n,).
    rate_hz : float
        Nominal sample rate (Hz).
    temperature_c : numpy.ndarray or None
        Temperature at each sample (degC), or None.
    axis : str
        'x', 'y' or 'z'.
    source : str
        Where the data came from (for the report).
    timebase : core.timebase.RateEstimate or None
        How the rate was obtained from the stamps (None without stamps).

    """

    rate: NDArray[np.float64]
    t_s: NDArray[np.float64]
    rate_hz: float
    temperature_c: NDArray[np.float64] | None = None
    axis: str = 'z'
    source: str = ''
    timebase: RateEstimate | None = None

    @property
    def n(self) -> int:
        """Count the samples."""
        return int(self.rate.shape[0])

    @property
    def duration_s(self) -> float:
        """Nominal duration n / rate_hz (s)."""
        return self.n / self.rate_hz


def _check_axis(axis: str) -> int:
    if axis not in AXES:
        raise ParameterError(f"axis must be 'x', 'y' or 'z', got {axis!r}")
    return AXES.index(axis)


def make_measurement(rate: ArrayLike, *, t_s: ArrayLike | None = None,
                     rate_hz: float | None = None, temperature_c: ArrayLike | None = None,
                     axis: str = 'z', source: str = '',
                     require_temperature: bool = False) -> Measurement:
    """
    Validate arrays and build a :class:`Measurement`.

    Parameters
    ----------
    rate : array_like
        Angular rate of one axis (rad/s).
    t_s : array_like, keyword-only
        Sample times (s); None means uniform at ``rate_hz``.
    rate_hz : float, keyword-only
        Nominal rate (Hz); None means the mean rate of ``t_s``.
    temperature_c : array_like, keyword-only
        Temperature per sample (degC) or None.
    axis, source : str, keyword-only
        Labels.
    require_temperature : bool, keyword-only
        Raise InputDataError when no temperature is given.

    Returns
    -------
    Measurement

    """
    _check_axis(axis)
    rate = np.asarray(rate, dtype=np.float64).ravel()
    n = rate.shape[0]
    bad = ~np.isfinite(rate)
    if bad.any():
        raise InputDataError(
            f'angular rate ({axis} axis) has {int(bad.sum())} NaN/Inf sample(s), first at '
            f'index {int(np.argmax(bad))}; remove or repair them first')
    huge = non_physical(rate, MAX_RATE_RAD_S)
    if huge.any():
        raise InputDataError(
            f'angular rate ({axis} axis) has {int(huge.sum())} sample(s) beyond '
            f'{MAX_RATE_RAD_S:g} rad/s, first at index {int(np.argmax(huge))} '
            f'({rate[np.argmax(huge)]:.3g}): not a measurement (a corrupt record or a wrong '
            'unit); remove or repair them first')
    if n < MIN_SAMPLES:
        raise InputDataError(f'too short to analyse: {n} samples, need at least {MIN_SAMPLES}')
    if np.ptp(rate) == 0.0:
        raise InputDataError(
            f'angular rate ({axis} axis) is constant ({rate[0]!r}): nothing to analyse')
    if t_s is None:
        if rate_hz is None:
            raise ParameterError('rate_hz is required when no sample times are given')
        t = np.arange(n) / float(rate_hz)
    else:
        t = np.asarray(t_s, dtype=np.float64).ravel()
        if t.shape[0] != n:
            raise InputDataError(f'{t.shape[0]} sample times for {n} samples')
        if not np.all(np.isfinite(t)):
            raise InputDataError(
                f'sample times have {int((~np.isfinite(t)).sum())} NaN/Inf value(s)')
        if np.any(np.diff(t) < 0):
            raise InputDataError(
                f'sample times go backwards {int((np.diff(t) < 0).sum())} time(s); '
                'sort the recording or give {rate_hz} and no time column',
                parameters=('rate_hz',))
        t = t - t[0]
        if t[-1] <= 0:
            raise InputDataError('all sample times are equal: give {rate_hz}',
                                 parameters=('rate_hz',))
    timebase = None
    if t_s is not None:
        from ..core.timebase import estimate_rate

        timebase = estimate_rate(t, unit='s', rate_hz=rate_hz)
        rate_hz = timebase.rate_hz
    assert rate_hz is not None  # without stamps rate_hz was required above
    rate_hz = float(rate_hz)
    if not np.isfinite(rate_hz) or rate_hz <= 0:
        raise ParameterError(f'rate_hz must be finite and > 0, got {rate_hz}')
    temp = None
    if temperature_c is not None:
        temp = np.asarray(temperature_c, dtype=np.float64).ravel()
        if temp.shape[0] != n:
            raise InputDataError(f'{temp.shape[0]} temperature values for {n} samples')
        bad = ~np.isfinite(temp)
        if bad.any():
            raise InputDataError(
                f'temperature has {int(bad.sum())} NaN/Inf value(s), first at index '
                f'{int(np.argmax(bad))}')
    if require_temperature and temp is None:
        raise InputDataError(f'temperature was asked for but {source or "the input"} has none')
    return Measurement(rate=rate, t_s=t, rate_hz=rate_hz, temperature_c=temp, axis=axis,
                       source=source, timebase=timebase)


def from_record(record: ImuRecord, *, axis: str = 'z', rate_hz: float | None = None,
                require_temperature: bool = False) -> Measurement:
    """
    Build the :class:`Measurement` of one gyro axis of a recording read in memory.

    Parameters
    ----------
    record : gyro_noise_ros.bag.inputs.ImuRecord
        The recording (:func:`gyro_noise_ros.bag.inputs.read_imu`).
    axis : {'x', 'y', 'z'}, keyword-only
        Gyro axis to analyse.
    rate_hz : float, keyword-only
        Nominal rate (Hz); None means the :mod:`~gyro_noise_ros.core.timebase` estimate.
    require_temperature : bool, keyword-only
        Raise InputDataError if the recording has no temperature.

    Returns
    -------
    Measurement

    """
    index = _check_axis(axis)
    t_s = (record.stamp_ns - record.stamp_ns[0]).astype(np.float64) * 1e-9
    return make_measurement(record.gyro_rad_s[:, index], t_s=t_s, rate_hz=rate_hz,
                            # ImuRecord types it as object: an array or None
                            temperature_c=cast('NDArray[np.float64] | None',
                                               record.temperature_c),
                            axis=axis, source=record.source,
                            require_temperature=require_temperature)


def load_input(path: StrPath, *, topic: str | None = None,
               temperature_topic: str | None = None, axis: str = 'z',
               rate_hz: float | None = None, require_temperature: bool = False) -> Measurement:
    """
    Read one gyro axis (and the temperature) of any recording into a :class:`Measurement`.

    Parameters
    ----------
    path : str or os.PathLike
        Bag, CSV or ULog (:mod:`gyro_noise_ros.bag.inputs`).
    topic, temperature_topic : str, keyword-only
        Imu and Temperature topics (auto-detected when None). Naming a temperature topic means
        temperature is required.
    axis : {'x', 'y', 'z'}, keyword-only
        Gyro axis to analyse.
    rate_hz : float, keyword-only
        Nominal rate (Hz); required for a CSV without a time column, else it overrides the
        estimate from the stamps.
    require_temperature : bool, keyword-only
        Raise InputDataError if there is no temperature.

    Returns
    -------
    Measurement

    """
    _check_axis(axis)
    require_temperature = require_temperature or temperature_topic is not None
    record = read_imu(path, topic=topic, temperature_topic=temperature_topic, rate_hz=rate_hz,
                      gyro_axes=(axis,))
    return from_record(record, axis=axis, rate_hz=rate_hz,
                       require_temperature=require_temperature)


def cut_record(record: ImuRecord, *, start_s: float | None = None, end_s: float | None = None,
               static: str = 'auto', window_names: tuple[str, str] = ('the start', 'the end'),
               ) -> tuple[ImuRecord, dict[str, Any], str]:
    """
    Keep the part of a recording to analyse, for all axes alike: a time window, then the segment.

    The static segment is the one rule of :func:`gyro_noise_ros.core.segments.static_part`,
    judged on every gyro axis the record holds (what ``gyro_noise_analyze`` cuts).

    Parameters
    ----------
    record : gyro_noise_ros.bag.inputs.ImuRecord
        The recording.
    start_s, end_s : float, optional, keyword-only
        Window in seconds after the first sample.
    static : {'auto', 'off'}, keyword-only
        'auto': keep the longest static segment.
    window_names : tuple of str, keyword-only
        How the sentence names the window's two ends (a tool: its options).

    Returns
    -------
    tuple
        ``(record, left_out, sentence)``: the samples kept (all columns), the ``left_out`` entry
        of explain.json (sample counts ``before_start``, ``after_end``, ``motion``; with a cut,
        the times of :meth:`gyro_noise_ros.core.segments.StaticPart.left_out`) and the line
        that says it (:func:`gyro_noise_ros.core.segments.left_out_sentence`; '' when nothing
        was left out).

    Raises
    ------
    InputDataError
        The window selects no sample (exit code 4).

    """
    from ..core.segments import Cut, left_out_sentence, static_part

    t = (record.stamp_ns - record.stamp_ns[0]).astype(np.float64) * 1e-9
    keep = np.ones(record.n, dtype=bool)
    left: dict[str, Any] = {'before_start': 0, 'after_end': 0, 'motion': 0}
    if start_s is not None:
        left['before_start'] = int((t < start_s).sum())
        keep &= t >= start_s
    if end_s is not None:
        left['after_end'] = int((keep & (t > end_s)).sum())
        keep &= t <= end_s
    if not keep.any():
        raise nothing_left_error(start_s=start_s, end_s=end_s, record_end_s=float(t[-1]))
    cuts: tuple[Cut, ...] = ()
    if static == 'auto':
        inside = np.flatnonzero(keep)
        part = static_part(record.stamp_ns[inside], record.gyro_rad_s[inside],
                           origin_ns=int(record.stamp_ns[0]))
        keep[inside[~part.keep]] = False
        left.update(part.left_out())
        cuts = part.cuts
    span = left.get('static_segment_s')
    sentence = left_out_sentence(
        record.n, before_start=left['before_start'], after_end=left['after_end'],
        motion=left['motion'], segment_s=None if span is None else (span[0], span[1]),
        cuts=cuts, window_names=window_names)
    if keep.all():
        return record, left, sentence
    temp = record.temperature_c
    return replace(record, stamp_ns=record.stamp_ns[keep], gyro_rad_s=record.gyro_rad_s[keep],
                   temperature_c=None if temp is None else np.asarray(temp)[keep]), left, sentence


def select(meas: Measurement, *, start_s: float | None = None, end_s: float | None = None,
           static: str = 'auto') -> tuple[Measurement, dict[str, Any]]:
    """
    Keep the part of a lone axis to analyse: a time window, then its static segment.

    The rule of :func:`cut_record` judged on this axis alone: for a recording, cut the record
    (all its axes together) before building the measurements.

    Parameters
    ----------
    meas : Measurement
        The loaded input.
    start_s, end_s : float, optional, keyword-only
        Window in seconds after the first sample.
    static : {'auto', 'off'}, keyword-only
        'auto': keep the longest static segment (:mod:`gyro_noise_ros.core.segments`).

    Returns
    -------
    tuple
        ``(Measurement, left_out)`` (``left_out`` as :func:`cut_record`'s).

    """
    stamps = np.rint(meas.t_s * 1e9).astype(np.int64)
    record = ImuRecord(stamp_ns=stamps, gyro_rad_s=meas.rate[:, None],
                       temperature_c=meas.temperature_c, topic='', storage='', source=meas.source)
    kept, left, _ = cut_record(record, start_s=start_s, end_s=end_s, static=static)
    if kept is record:
        return meas, left
    fixed = meas.timebase is not None and meas.timebase.method == 'configured'
    out = make_measurement(kept.gyro_rad_s[:, 0], t_s=kept.stamp_ns * 1e-9,
                           rate_hz=meas.rate_hz if fixed else None,
                           temperature_c=kept.temperature_c, axis=meas.axis, source=meas.source)
    return out, left
