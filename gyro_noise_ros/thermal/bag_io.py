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
Bags in and out of the thermal tools: a recording as a :class:`ThermalRun`, a compensated copy.

:func:`read_thermal_run` reads the ``sensor_msgs/Imu`` topic and the ``sensor_msgs/Temperature``
topic of one bag (any format :mod:`gyro_noise_ros.bag` reads), orders the Imu samples by header
stamp and interpolates the temperature linearly onto them. It refuses, with one sentence each:
no or ambiguous temperature topic (:class:`BagError`, exit 3); NaN/Inf gyro or temperature
samples, repeated Imu stamps, temperature stamps that do not cover the Imu stamps (beyond
:data:`MAX_EDGE_S` plus two temperature periods at either end), or a hole in the temperature
longer than ``max_gap_s`` (:class:`InputDataError`, exit 4). Implausible temperature readings
(:func:`gyro_noise_ros.core.plausible.screen_temperature`: outside the sensor's operating range,
saturated register words, jumps faster than a die moves) are dropped and counted, or the bag is
refused when more than :data:`~gyro_noise_ros.core.plausible.MAX_IMPLAUSIBLE_SHARE` of them are,
naming the first; a stream in kelvin is converted to degC with a warning.

:func:`write_compensated` writes a rosbag2 copy of the bag in which only the Imu
``angular_velocity`` (and, with an accelerometer model, ``linear_acceleration``) is replaced
(patched in the serialised bytes, so orientation, covariances, frame ids and stamps are kept bit
for bit) and every other topic, the temperature included, is copied unchanged (ROS 1 input is
converted to ROS 2 CDR).
"""

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .run import ThermalRun
from ..bag import ImuBagReader, ImuBagWriter
from ..bag.storage import BagSource, describe
from ..core.plausible import (KELVIN_OFFSET_C, looks_like_kelvin, MAX_IMPLAUSIBLE_SHARE,
                              screen_temperature)
from ..core.timebase import estimate_rate
from ..errors import BagError, InputDataError, ParameterError
from ..msgs import join_raws, TEMPERATURE_MSGTYPE, typestore
from ..outputs import StrPath

__all__ = ['DEFAULT_MAX_GAP_S', 'MAX_EDGE_S', 'ThermalBag', 'join_runs', 'read_thermal_run',
           'write_compensated']

#: Longest hole (s) in the temperature stream accepted inside the Imu span.
DEFAULT_MAX_GAP_S = 10.0
#: Slack (s), besides two temperature periods, between the ends of the Imu and temperature spans.
MAX_EDGE_S = 1.0

# sensor_msgs/Imu ends with 37 float64 (orientation 4, its covariance 9, angular velocity 3, ...);
# angular_velocity x starts 37 - 13 = 24 float64 before the end, in CDR and ROS 1 alike; then
# its covariance (9), then linear_acceleration x, 12 float64 before the end.
_AV_FROM_END = 8 * 24
_LA_FROM_END = 8 * 12


@dataclass(frozen=True)
class ThermalBag:
    """
    Where a :class:`ThermalRun` came from, enough to write its compensated copy.

    Attributes
    ----------
    path : pathlib.Path
        The bag.
    topic : str
        Imu topic as stored.
    temperature_topic : str
        Temperature topic as stored.
    storage : str
        'sqlite3', 'mcap' or 'ros1'.
    stamp_ns : numpy.ndarray
        Imu header stamps (int64, sorted), the stamps of the run's samples.
    order : numpy.ndarray
        Bag-order index of each sorted sample (int64): sample k is message ``order[k]``.
    temperature_samples : int
        Temperature messages read.
    temperature_dropped : int
        Implausible temperature readings dropped (:func:`screen_temperature`).
    temperature_period_s : float
        Median interval of the temperature readings kept (s; 0 with a single reading).
    notes : tuple of str
        What reading the temperature noticed (implausible readings dropped).
    warnings : tuple of str
        What was changed in the data and calls for a look (a stream in kelvin, converted).

    """

    path: Path
    topic: str
    temperature_topic: str
    storage: str
    stamp_ns: np.ndarray
    order: np.ndarray
    temperature_samples: int
    temperature_dropped: int = 0
    temperature_period_s: float = 0.0
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


def _label(path: StrPath) -> str:
    p = Path(path)
    return p.stem if p.suffix in ('.bag', '.mcap', '.db3') else p.name


def _pick_temperature_topic(reader: ImuBagReader, requested: str | None) -> str:
    if reader.temperature_topic is not None:  # always so when one was requested
        return reader.temperature_topic
    src = reader._open_source()
    names = sorted(n for n, (kind, _) in src.topics().items() if kind == TEMPERATURE_MSGTYPE)
    if not names:
        raise BagError(f'bag {str(reader.path)!r} has no {TEMPERATURE_MSGTYPE} topic: the thermal '
                       'methods need the die temperature')
    raise BagError(f'bag {str(reader.path)!r} has {len(names)} {TEMPERATURE_MSGTYPE} topics '
                   f'({", ".join(names)}); choose one with {{temperature_topic}}',
                   parameters=('temperature_topic',))


def read_thermal_run(path: StrPath, *, topic: str | None = None,
                     temperature_topic: str | None = None, max_gap_s: float = DEFAULT_MAX_GAP_S,
                     name: str | None = None) -> tuple[ThermalRun, ThermalBag]:
    """
    Read one bag's Imu and Temperature topics into a :class:`ThermalRun`.

    Parameters
    ----------
    path : str or os.PathLike
        Bag (rosbag2 directory, ``.db3``, ``.mcap`` or ROS 1 ``.bag``).
    topic : str, optional
        Imu topic; the bag's single Imu topic if None.
    temperature_topic : str, optional
        Temperature topic; if None the bag's single one, or the one in the Imu topic's namespace.
    max_gap_s : float, keyword-only
        Longest accepted hole in the temperature stream inside the Imu span (s).
    name : str, optional
        Run label (default: the bag's file name without suffix).

    Returns
    -------
    run : ThermalRun
        ``t_s`` counts from the first Imu stamp; ``rate_hz`` is the mean rate,
        (n - 1) / (last stamp - first stamp); ``accel_m_s2`` the linear acceleration (None
        when some of it is not finite: the gyro methods do not need it).
    bag : ThermalBag

    Raises
    ------
    BagError
        Unreadable bag, no/ambiguous Imu or temperature topic.
    InputDataError
        Fewer than 3 Imu samples, NaN/Inf samples, repeated Imu stamps, temperature that does not
        cover the Imu stamps or has a hole longer than ``max_gap_s``.

    """
    if not max_gap_s > 0:
        raise ParameterError(f'max_gap_s must be > 0 s, got {max_gap_s!r}')
    with ImuBagReader(path, topic=topic, temperature_topic=temperature_topic) as reader:
        temp_topic = _pick_temperature_topic(reader, temperature_topic)
        stamps, gyros, accels = [], [], []
        for batch in reader.iter_batches():
            stamps.append(batch.stamp_ns)
            gyros.append(batch.gyro)
            accels.append(batch.accel)
        temperatures = reader.read_temperature()
        assert temperatures is not None  # the reader has the topic picked above
        temp_stamp, temp = temperatures
        storage, imu_topic = reader.storage, reader.topic
    where = f'bag {str(path)!r}'
    stamp = np.concatenate(stamps)
    gyro = np.concatenate(gyros)
    accel: NDArray[Any] | None
    accel = np.concatenate(accels)
    if stamp.size < 3:
        raise InputDataError(f'{where}: {stamp.size} Imu message(s) on {imu_topic!r}; at least 3 '
                             'are needed')
    bad = ~np.isfinite(gyro).all(axis=1)
    if bad.any():
        raise InputDataError(f'{where}: {int(bad.sum())} Imu message(s) on {imu_topic!r} have '
                             f'NaN/Inf angular velocity (first: message {int(np.argmax(bad))}); '
                             'the thermal methods need every sample')
    if temp.size == 0:
        raise InputDataError(f'{where}: temperature topic {temp_topic!r} has no messages')
    bad = ~np.isfinite(temp)
    if bad.any():
        raise InputDataError(f'{where}: {int(bad.sum())} NaN/Inf temperature value(s) on '
                             f'{temp_topic!r} (first: message {int(np.argmax(bad))})')
    order = np.argsort(stamp, kind='stable')
    stamp = stamp[order]
    gyro = gyro[order]
    accel = accel[order] if np.isfinite(accel).all() else None
    if (np.diff(stamp) == 0).any():
        k = int(np.argmax(np.diff(stamp) == 0))
        raise InputDataError(f'{where}: Imu stamp {int(stamp[k])} ns repeats on {imu_topic!r}; '
                             'each sample needs its own time')
    t_order = np.argsort(temp_stamp, kind='stable')
    read = int(temp.size)
    temp_stamp, temp, notes, warnings = _plausible_temperature(
        where, temp_topic, temp_stamp[t_order], temp[t_order], int(stamp[0]))
    _check_coverage(where, stamp, temp_stamp, temp_topic, imu_topic, max_gap_s)
    t0 = int(stamp[0])
    t_s = (stamp - t0) / 1e9
    t_temp = (temp_stamp - t0) / 1e9
    if t_temp.size == 1:
        temperature = np.full(t_s.size, float(temp[0]))
    else:
        temperature = np.interp(t_s, t_temp, temp)
    # The package's one estimator (core.timebase): right on bursty host stamps (median step
    # 2 ms at a 100 Hz mean rate), where a median step would mislead, and not lowered by loss.
    est = estimate_rate(stamp, unit='ns')
    rate_hz = float(est.rate_hz) if est.usable else float((t_s.size - 1) / t_s[-1])
    period = float(np.median(np.diff(t_temp))) if t_temp.size > 1 else 0.0
    run = ThermalRun(t_s=t_s, gyro_rad_s=gyro, temperature_c=temperature, rate_hz=rate_hz,
                     name=name or _label(path), accel_m_s2=accel, temperature_period_s=period)
    info = ThermalBag(path=Path(path), topic=imu_topic, temperature_topic=temp_topic,
                      storage=storage, stamp_ns=stamp, order=order.astype(np.int64),
                      temperature_samples=read, temperature_dropped=read - int(temp.size),
                      temperature_period_s=period, notes=notes, warnings=warnings)
    return run, info


def _plausible_temperature(where: str, topic: str, stamp_ns: NDArray[np.int64],
                           temp: NDArray[np.float64],
                           t0_ns: int) -> tuple[NDArray[np.int64], NDArray[np.float64],
                                                tuple[str, ...], tuple[str, ...]]:
    """Convert a kelvin stream, drop implausible readings, refuse a stream with too many."""
    notes, warnings = [], []
    if looks_like_kelvin(temp):
        warnings.append(f'temperature topic {topic!r} reads {np.min(temp):.2f}..'
                        f'{np.max(temp):.2f}: kelvin, not degC (sensor_msgs/Temperature is '
                        f'degC); converted by subtracting {KELVIN_OFFSET_C}')
        temp = temp - KELVIN_OFFSET_C
    t_s = (stamp_ns - t0_ns) / 1e9   # from the first Imu stamp, as the run's times
    screen = screen_temperature(t_s, temp)
    if screen.dropped > MAX_IMPLAUSIBLE_SHARE * temp.size:
        raise InputDataError(f'{where}, {topic!r}: {screen.text(t_s, temp)}; more than '
                             f'{100 * MAX_IMPLAUSIBLE_SHARE:g} % of the stream is implausible: '
                             'refused')
    if screen.dropped:
        notes.append(f'{topic!r}: {screen.text(t_s, temp)}; dropped, the temperature '
                     'interpolated over them')
    return stamp_ns[screen.keep], temp[screen.keep], tuple(notes), tuple(warnings)


def _check_coverage(where: str, stamp: NDArray[np.int64], temp_stamp: NDArray[np.int64],
                    temp_topic: str, imu_topic: str, max_gap_s: float) -> None:
    """Refuse temperature stamps that do not cover the Imu stamps."""
    i0, i1 = int(stamp[0]), int(stamp[-1])
    t0, t1 = int(temp_stamp[0]), int(temp_stamp[-1])
    span = (f'Imu {imu_topic!r} {i0 / 1e9:.3f}..{i1 / 1e9:.3f} s, temperature {temp_topic!r} '
            f'{t0 / 1e9:.3f}..{t1 / 1e9:.3f} s')
    if t1 < i0 or t0 > i1:
        raise InputDataError(f'{where}: Imu and temperature stamps do not overlap ({span}); '
                             'were they stamped by different clocks?')
    period = float(np.median(np.diff(temp_stamp))) / 1e9 if temp_stamp.size > 1 else 0.0
    slack = MAX_EDGE_S + 2.0 * period
    if (t0 - i0) / 1e9 > slack or (i1 - t1) / 1e9 > slack:
        raise InputDataError(f'{where}: temperature does not cover the Imu samples ({span}; more '
                             f'than {slack:.3g} s uncovered at an end)')
    inside = temp_stamp[(temp_stamp >= i0) & (temp_stamp <= i1)]
    edges = np.concatenate([[i0], inside, [i1]])
    gaps = np.diff(edges) / 1e9
    if gaps.size and gaps.max() > max_gap_s:
        k = int(np.argmax(gaps))
        raise InputDataError(f'{where}: no temperature for {gaps[k]:.3g} s from '
                             f'{edges[k] / 1e9:.3f} s on {temp_topic!r} (longest accepted hole: '
                             f'{max_gap_s:g} s)')


def join_runs(runs: Iterable[ThermalRun], *, gap_s: float) -> ThermalRun:
    """
    Join runs end to end into one training run.

    Each run's time axis continues ``gap_s`` after the previous run's last sample, so a trailing
    temperature-rate window no longer than ``gap_s`` never straddles two recordings.

    Parameters
    ----------
    runs : sequence of ThermalRun
        At least one, all at nearly the same rate (within 1 %).
    gap_s : float
        Time inserted between runs (s).

    Returns
    -------
    ThermalRun
        Named after the runs joined with '+'; ``rate_hz`` of the first run.

    """
    runs = list(runs)
    if not runs:
        raise ParameterError('join_runs needs at least one run')
    if len(runs) == 1:
        return runs[0]
    rate = runs[0].rate_hz
    for r in runs[1:]:
        if abs(r.rate_hz - rate) > 0.01 * rate:
            raise InputDataError(f'runs {runs[0].name!r} and {r.name!r} have different sample '
                                 f'rates ({rate:.6g} Hz and {r.rate_hz:.6g} Hz); resample first')
    ts, offset = [], 0.0
    for r in runs:
        ts.append(r.t_s - r.t_s[0] + offset)
        offset = ts[-1][-1] + gap_s
    accel = None
    if all(r.accel_m_s2 is not None for r in runs):
        accel = np.concatenate([r.accel_m_s2 for r in runs])
    periods = [r.temperature_period_s for r in runs if r.temperature_period_s is not None]
    return ThermalRun(t_s=np.concatenate(ts),
                      gyro_rad_s=np.concatenate([r.gyro_rad_s for r in runs]),
                      temperature_c=np.concatenate([r.temperature_c for r in runs]),
                      rate_hz=rate, name='+'.join(r.name for r in runs), accel_m_s2=accel,
                      temperature_period_s=max(periods) if periods else None)


def write_compensated(bag: ThermalBag, processed_rad_s: ArrayLike, out_dir: StrPath, *,
                      storage: str | None = None,
                      accel_m_s2: ArrayLike | None = None) -> dict[str, int]:
    """
    Write a rosbag2 copy of ``bag.path`` with the Imu angular velocity (and acceleration) replaced.

    Parameters
    ----------
    bag : ThermalBag
        From :func:`read_thermal_run`.
    processed_rad_s : array_like
        Processed angular rate (n, 3), rad/s, in the run's (stamp-sorted) sample order.
    out_dir : str or os.PathLike
        Bag directory to create (must not exist).
    storage : {'sqlite3', 'mcap'}, optional
        Output storage; default the input's (sqlite3 for ROS 1 input).
    accel_m_s2 : array_like, optional, keyword-only
        Processed linear acceleration (n, 3), m/s^2, same order; None keeps the input's.

    Returns
    -------
    dict
        ``{topic: messages written}``.

    Raises
    ------
    BagError
        The input cannot be re-read or the output cannot be written.
    ParameterError
        ``processed_rad_s`` does not match the bag's sample count.

    """
    proc = np.asarray(processed_rad_s, dtype=np.float64)
    n = bag.stamp_ns.size
    if proc.shape != (n, 3):
        raise ParameterError(f'processed_rad_s has shape {proc.shape}, the bag has {n} samples')
    in_bag_order = np.empty_like(proc)
    in_bag_order[bag.order] = proc
    accel_in_bag_order = None
    if accel_m_s2 is not None:
        acc = np.asarray(accel_m_s2, dtype=np.float64)
        if acc.shape != (n, 3):
            raise ParameterError(f'accel_m_s2 has shape {acc.shape}, the bag has {n} samples')
        accel_in_bag_order = np.empty_like(acc)
        accel_in_bag_order[bag.order] = acc
    if storage is None:
        storage = bag.storage if bag.storage in ('sqlite3', 'mcap') else 'sqlite3'
    source = BagSource(bag.path)
    store = typestore()
    counts = {}
    try:
        # ImuBagWriter brings the Imu connection and the bulk sqlite3 insert; the other topics'
        # connections are added to its rosbags writer.
        with ImuBagWriter(out_dir, storage=storage, imu_topic=bag.topic,
                          temperature_topic=None) as writer:
            for topic, (msgtype, _) in sorted(source.topics().items()):
                if topic == bag.topic:
                    conn = writer._imu_conn
                else:
                    conn = _add_connection(writer._writer, source, topic, msgtype, store)
                imu = topic == bag.topic
                counts[topic] = _copy_topic(source, writer, conn, topic, msgtype, store,
                                            in_bag_order if imu else None,
                                            accel_in_bag_order if imu else None)
    finally:
        source.close()
    if counts.get(bag.topic) != n:
        raise BagError(f'bag {str(bag.path)!r} changed while being copied: '
                       f'{counts.get(bag.topic)} Imu messages, {n} expected')
    return counts


def _add_connection(writer: Any, source: BagSource, topic: str, msgtype: str | None,
                    store: Any) -> Any:
    if msgtype is None:
        raise BagError(f'bag {str(source.path)!r}: topic {topic!r} mixes message types')
    conn = next(c for c in source.connections if c.topic == topic)
    try:
        if source.ros1 or msgtype in store.types:
            return writer.add_connection(topic, msgtype, typestore=store)
        ext = conn.ext
        return writer.add_connection(
            topic, msgtype, msgdef=conn.msgdef.data, rihs01=conn.digest,
            serialization_format=getattr(ext, 'serialization_format', 'cdr'),
            offered_qos_profiles=getattr(ext, 'offered_qos_profiles', ()))
    except Exception as err:  # noqa: BLE001 - rosbags WriterError on odd connections
        raise BagError(f'cannot copy topic {topic!r} ({msgtype}): {describe(err)}') from err


def _copy_topic(source: BagSource, writer: ImuBagWriter, conn: Any, topic: str,
                msgtype: str | None, store: Any, gyro: NDArray[np.float64] | None,
                accel: NDArray[np.float64] | None = None) -> int:
    """Copy one topic; patch angular_velocity / linear_acceleration (bag order) if given."""
    done = 0
    for buf, starts, lengths, log_ns in source.blocks(topic):
        k = starts.shape[0]
        if source.ros1:
            if msgtype not in store.types:
                raise BagError(f'bag {str(source.path)!r}: ROS 1 type {msgtype} of {topic!r} is '
                               'unknown to the ROS 2 Jazzy type store; cannot convert it')
            raws = [bytes(store.ros1_to_cdr(bytes(buf[s:s + m]), msgtype))
                    for s, m in zip(starts.tolist(), lengths.tolist())]
            buf, starts, lengths = join_raws(raws)
        if gyro is not None:
            buf = _patch_angular_velocity(buf, starts, lengths, gyro[done:done + k])
        if accel is not None:
            buf = _patch_angular_velocity(buf, starts, lengths, accel[done:done + k],
                                          from_end=_LA_FROM_END)
        blob = buf.tobytes()
        raws = [blob[s:s + m] for s, m in zip(starts.tolist(), lengths.tolist())]
        writer._write(conn, log_ns, raws)
        done += k
    return done


def _patch_angular_velocity(buf: NDArray[np.uint8], starts: NDArray[np.int64],
                            lengths: NDArray[np.int64], xyz: NDArray[np.float64], *,
                            from_end: int = _AV_FROM_END) -> NDArray[np.uint8]:
    """Return a copy of ``buf`` with each CDR Imu message's vector ``from_end`` set to ``xyz``."""
    out = np.array(buf, dtype=np.uint8, copy=True)
    at = (starts + lengths - from_end)[:, None] + np.arange(24)
    little = out[starts + 1] == 1
    for mask, order in ((little, '<'), (~little, '>')):
        if mask.any():
            out[at[mask]] = np.ascontiguousarray(xyz[mask], dtype=order + 'f8').view(np.uint8)
    return out
