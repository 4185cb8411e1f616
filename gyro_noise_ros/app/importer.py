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
The import workflow: SD-card log files of one Portenta sequence in, one rosbag2 out.

Shared by ``gyro_noise_import``, bench and tests. :func:`import_logs` reads the files in
(sequence, file index) order from their headers, streams them through the link decoder in
constant memory, scales to SI with the configuration in force (file headers and ACK frames, or
``gyro_fs_dps``/``accel_fs_g`` which override both), and writes ``sensor_msgs/Imu`` (every
sample) and ``sensor_msgs/Temperature`` (decimated to ``temperature_rate_hz``). Corrupt regions
are skipped and reported in the :class:`ImportReport`, never fatal. Time stamps come from the
device clock (the 32-bit microsecond counter, unwrapped), anchored by ``start_time`` (``auto``,
``rtc``, ``zero`` or UNIX seconds: ``docs/portenta_link.md``). The bag is built under a hidden
name beside ``out`` and renamed when it is complete.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import os
import queue
import threading
from typing import Any

import numpy as np

from ..bag import ImuBagWriter
from ..bag.bulk import BulkImuBagWriter
from ..cluster import usable_cpus
from ..errors import BagError, InputDataError, ParameterError
from ..link import lsm6dso32 as lsm
from ..link.clock import Unwrapper
from ..link.sdlog import SdLogReader
from ..outputs import check_new_dir, staged_new_dir

#: LSM6DSO32 temperature sensor output data rate (datasheet: 52 Hz).
TEMPERATURE_ODR_HZ = 52.0
#: The latest first-sample time ``--start-time`` accepts (UNIX s): a ROS stamp is int64
#: nanoseconds (up to 2262-04-11, 9.22e9 s); a day is left for the record itself.
MAX_START_TIME_S = (2**63 - 1) / 1e9 - 86400.0


@dataclass(frozen=True)
class ImportReport:
    """
    Outcome of :func:`import_logs`.

    Attributes
    ----------
    bag : str
    storage : str
    files : tuple of sdlog.LogFileInfo
    samples_written : int
        Imu messages.
    temperature_written : int
        Temperature messages.
    samples_lost : int
        Counter gaps (including across files).
    samples_flagged_lost : int
        Part of the losses the board flagged.
    crc_errors, resyncs, bytes_discarded, frames_truncated : int
        Decoder counters.
    corrupt_regions : tuple of sdlog.CorruptRegion
    corrupt_region_count : int
    missing_file_indices : tuple of int
    sequence_id : int or None
    first_stamp_ns, last_stamp_ns : int or None
    time_jumps : int
        Places where device time did not increase (stamps kept as the device said).
    configurations : tuple of (int, int, float)
        Distinct (gyro_fs_dps, accel_fs_g, odr_hz) used for scaling, in order of appearance.
    epoch : str
        How stamps were anchored.

    """

    bag: str
    storage: str
    files: tuple
    samples_written: int
    temperature_written: int
    samples_lost: int
    samples_flagged_lost: int
    crc_errors: int
    resyncs: int
    bytes_discarded: int
    frames_truncated: int
    corrupt_regions: tuple
    corrupt_region_count: int
    missing_file_indices: tuple
    sequence_id: int | None
    first_stamp_ns: int | None
    last_stamp_ns: int | None
    time_jumps: int
    configurations: tuple
    epoch: str


def _topic(name: str) -> str:
    name = str(name)
    if not name or any(c.isspace() for c in name):
        raise ParameterError(f'topic must be a non-empty name without spaces, got {name!r}')
    return name if name.startswith('/') else '/' + name


def _anchor(start_time: str, reader: SdLogReader) -> tuple[str, Any]:
    """Return (epoch description, function(first_t_us_unwrapped, headers) -> offset) pieces."""
    heads = [f.header for f in reader.files if f.header is not None]
    rtc_head = next((h for h in heads if h.rtc_unix_s), None)
    mode = start_time
    if mode == 'auto':
        mode = 'rtc' if rtc_head is not None else 'zero'
    if mode == 'rtc':
        if rtc_head is None:
            raise ParameterError(
                '--start-time rtc: no log header carries an RTC time (rtc_unix_s = 0)')
        return 'rtc', rtc_head
    if mode == 'zero':
        return 'zero', None
    try:
        value = float(mode)
    except ValueError as err:
        raise ParameterError(
            f'--start-time must be auto, rtc, zero or UNIX seconds, got {start_time!r}') from err
    if not np.isfinite(value) or value < 0:
        raise ParameterError(f'--start-time must be >= 0 UNIX seconds, got {start_time!r}')
    if value > MAX_START_TIME_S:
        raise ParameterError(f'--start-time {start_time} s is beyond the latest ROS time stamp '
                             f'(int64 ns: {MAX_START_TIME_S:.4g} s, the year 2262)')
    return f'unix:{value!r}', value


def _first_acked_config(paths: Sequence[str], chunk_bytes: int,
                        scan: bool) -> tuple[Any, int, int] | None:
    """Return (odr_hz, gyro_fs_dps, accel_fs_g) of the first block that knows them, or None."""
    for block in SdLogReader(paths, chunk_bytes=chunk_bytes, scan=scan):
        if block.gyro_fs_dps and block.accel_fs_g:
            return block.odr_hz, block.gyro_fs_dps, block.accel_fs_g
    return None


def import_logs(paths: Sequence[str], out: 'os.PathLike[str] | str', *, storage: str = 'mcap',
                topic: str = 'imu/data_raw', temperature_topic: str = 'imu/temperature',
                frame_id: str = 'imu_link', gyro_fs_dps: int | None = None,
                accel_fs_g: int | None = None, start_time: str = 'auto',
                temperature_rate_hz: float = TEMPERATURE_ODR_HZ,
                angular_velocity_variance: float = 0.0,
                linear_acceleration_variance: float = 0.0, temperature_variance: float = 0.0,
                chunk_bytes: int = 1 << 20, bulk: bool = True, scan: bool | None = None,
                threads: int | None = None, overwrite: bool = False) -> ImportReport:
    """
    Convert SD log files of one sequence to a rosbag2.

    Parameters
    ----------
    paths : sequence of str
        Log files (any order).
    out : str
        Bag directory to create (must not exist).
    storage : {'mcap', 'sqlite3'}, keyword-only
        MCAP by default: the faster of the two here, the rosbag2 default since Iron (see
        ``docs/scale.md``).
    topic, temperature_topic : str, keyword-only
        Topic names (a leading '/' is added).
    frame_id : str, keyword-only
        Frame id of the Imu and Temperature messages.
    gyro_fs_dps, accel_fs_g : int, optional, keyword-only
        Force the scaling (deg/s, g), ignoring headers and acks.
    start_time : str, keyword-only
        'auto', 'rtc', 'zero' or UNIX seconds of the first sample (see the module docstring).
    temperature_rate_hz : float, keyword-only
        Temperature messages per second of data (Hz); 0 writes none.
    angular_velocity_variance : float, keyword-only
        Diagonal of the Imu angular velocity covariance ((rad/s)^2; 0 = unknown).
    linear_acceleration_variance : float, keyword-only
        Diagonal of the linear acceleration covariance ((m/s^2)^2; 0 = unknown).
    temperature_variance : float, keyword-only
        Temperature variance (degC^2; 0 = unknown).
    chunk_bytes : int, keyword-only
        Read size (bytes).
    bulk : bool, keyword-only
        Write with :class:`gyro_noise_ros.bag.bulk.BulkImuBagWriter` (same bag, byte for byte, many
        times faster); False keeps the per-message :class:`gyro_noise_ros.bag.ImuBagWriter` path
        (the baseline of ``bench/bench_import.py``).
    scan : bool, optional, keyword-only
        Decode the logs with the compiled frame scanner (:class:`SdLogReader` ``scan=True``; same
        blocks and report); None (default) follows ``bulk``, so ``bulk=False`` is the whole old
        path.
    threads : {1, 2}, optional, keyword-only
        2: the bag is written by a second thread, in order, while this one reads, decodes and
        scales the next blocks (at most :data:`WRITE_QUEUE_BLOCKS` blocks wait between them, so
        memory stays constant); 1: one thread does both. None (default): 2 when this process
        may run on two or more CPUs and ``bulk`` is on, else 1. Same bag, byte for byte.
    overwrite : bool, keyword-only
        An existing bag at ``out`` is replaced when the new one is complete (``--overwrite``);
        never a file or a folder that is not a bag.

    Returns
    -------
    ImportReport

    """
    if gyro_fs_dps is not None:
        gyro_fs_dps = lsm.check_gyro_fs(gyro_fs_dps)
    if accel_fs_g is not None:
        accel_fs_g = lsm.check_accel_fs(accel_fs_g)
    for name, value in (('angular_velocity_variance', angular_velocity_variance),
                        ('linear_acceleration_variance', linear_acceleration_variance),
                        ('temperature_variance', temperature_variance),
                        ('temperature_rate_hz', temperature_rate_hz)):
        if not (np.isfinite(value) and value >= 0):
            raise ParameterError(f'{name} must be finite and >= 0, got {value}')
    if threads is None:
        threads = 2 if bulk and usable_cpus() >= 2 else 1
    if threads not in (1, 2):
        raise ParameterError(f'threads must be 1 or 2, got {threads!r}')
    imu_topic = _topic(topic)
    temp_topic = _topic(temperature_topic) if temperature_rate_hz > 0 else None
    if temp_topic == imu_topic:
        raise ParameterError(f'--topic and --temperature-topic are both {imu_topic!r}: Imu and '
                             'Temperature messages need topics of their own')
    out = os.fspath(out)
    check_new_dir(out, parameter='out', overwrite=overwrite)
    missing = [str(p_) for p_ in paths if not os.path.isfile(p_)]
    if missing:
        raise BagError(f'log file {missing[0]!r} does not exist' + (
            f' (and {len(missing) - 1} more)' if len(missing) > 1 else ''))
    scan = bulk if scan is None else bool(scan)
    reader = SdLogReader(paths, chunk_bytes=chunk_bytes, scan=scan)
    heads = [f.header for f in reader.files if f.header is not None]
    # until a header or an ack says otherwise, the first readable header's configuration holds (the
    # device cannot change it without writing an ACK frame)
    # (odr_hz, gyro_fs_dps, accel_fs_g), None where unknown
    assumed: tuple[Any, int | None, int | None] = (
        (heads[0].odr_hz, heads[0].gyro_fs_dps, heads[0].accel_fs_g) if heads
        else (None, None, None))
    if not heads and (gyro_fs_dps is None or accel_fs_g is None):
        # Corruption is never fatal (docs/portenta_link.md): an unreadable header is replaced by
        # the configuration the first ACK frame carries.
        acked = _first_acked_config(paths, chunk_bytes, scan)
        if acked is None:
            raise InputDataError(
                'no readable log header and no ACK frame with the scales in the files: '
                'give --gyro-fs-dps and --accel-fs-g')
        assumed = acked
        reader = SdLogReader(paths, chunk_bytes=chunk_bytes, scan=scan)
    epoch, anchor = _anchor(start_time, reader)
    av_cov = np.diag([angular_velocity_variance] * 3).reshape(9)
    la_cov = np.diag([linear_acceleration_variance] * 3).reshape(9)
    writer_class = BulkImuBagWriter if bulk else ImuBagWriter

    # The bag is built under a hidden name and renamed when finished: an interrupted or failed
    # import leaves nothing that looks like a bag, and a retry with the same --out works.
    with staged_new_dir(out, parameter='out', overwrite=overwrite) as stage:
        with _BagWrites(lambda: writer_class(stage, storage=storage, imu_topic=imu_topic,
                                             temperature_topic=temp_topic, frame_id=frame_id),
                        threaded=threads == 2) as writes:
            first, last, written, temp_written, jumps, configs = _convert(
                reader, writes, assumed=assumed, gyro_fs_dps=gyro_fs_dps, accel_fs_g=accel_fs_g,
                epoch=epoch, anchor=anchor, temp_topic=temp_topic,
                temperature_rate_hz=temperature_rate_hz, temperature_variance=temperature_variance,
                av_cov=av_cov, la_cov=la_cov)
        rep = reader.report
        assert rep is not None  # the iteration ran to its end
        if written == 0:
            raise InputDataError(f'no valid samples in {len(reader.files)} log file(s) '
                                 f'({rep.stats.bytes_discarded} bytes discarded)')
    st = rep.stats
    return ImportReport(bag=out, storage=storage, files=rep.files, samples_written=written,
                        temperature_written=temp_written, samples_lost=st.samples_lost,
                        samples_flagged_lost=st.samples_flagged_lost, crc_errors=st.crc_errors,
                        resyncs=st.resyncs, bytes_discarded=st.bytes_discarded,
                        frames_truncated=st.frames_truncated, corrupt_regions=rep.corrupt_regions,
                        corrupt_region_count=rep.corrupt_region_count,
                        missing_file_indices=rep.missing_file_indices, sequence_id=rep.sequence_id,
                        first_stamp_ns=first, last_stamp_ns=last, time_jumps=jumps,
                        configurations=tuple(configs), epoch=epoch)


def _convert(reader: SdLogReader, writes: '_BagWrites', *,
             assumed: tuple[Any, int | None, int | None], gyro_fs_dps: int | None,
             accel_fs_g: int | None, epoch: str, anchor: Any, temp_topic: str | None,
             temperature_rate_hz: float, temperature_variance: float, av_cov: np.ndarray,
             la_cov: np.ndarray) -> tuple[int | None, int | None, int, int, int, list]:
    """
    Stream the log blocks through the scaling into the bag writes.

    Returns (first stamp, last stamp, Imu written, Temperature written, time jumps,
    configurations).
    """
    unwrap = Unwrapper()
    offset_ns = None
    first = last = None
    jumps = 0
    prev_t = None
    temp_acc = 0.0
    configs = []
    written = temp_written = 0
    for block in reader:
        if block.samples.size == 0:
            continue
        odr = block.odr_hz if block.odr_hz is not None else assumed[0]
        gfs = gyro_fs_dps if gyro_fs_dps is not None else (block.gyro_fs_dps or assumed[1])
        afs = accel_fs_g if accel_fs_g is not None else (block.accel_fs_g or assumed[2])
        if (gfs, afs, odr) not in configs:
            configs.append((gfs, afs, odr))
        t = unwrap.unwrap(block.samples['t_us'])
        if offset_ns is None:
            if epoch == 'rtc':
                # rtc_unix_s is the host time of the header's t_us; unwrap that t_us next to
                # ours
                d = (int(anchor.t_us) - int(block.samples['t_us'][0])) % (1 << 32)
                if d >= 1 << 31:
                    d -= 1 << 32
                offset_ns = anchor.rtc_unix_s * 1_000_000_000 - (int(t[0]) + d) * 1000
            elif epoch == 'zero':
                offset_ns = -int(t[0]) * 1000
            else:
                offset_ns = int(round(anchor * 1e9)) - int(t[0]) * 1000
        stamps = t * 1000 + offset_ns
        steps = np.diff(t, prepend=t[0] if prev_t is None else prev_t)
        if prev_t is None:
            steps[0] = 1
        jumps += int(np.count_nonzero(steps <= 0))
        prev_t = int(t[-1])
        assert gfs is not None and afs is not None  # from the options, a header or an ACK
        si = lsm.to_si(block.samples, gyro_fs_dps=gfs, accel_fs_g=afs)
        writes.call('write_imu', stamps, si.gyro_rad_s, si.accel_m_s2,
                    angular_velocity_covariance=av_cov, linear_acceleration_covariance=la_cov)
        written += block.samples.size
        if temp_topic is not None and odr:
            # a running phase keeps the decimation even across blocks and ODR changes
            phase = temp_acc + np.arange(
                1, block.samples.size + 1) * (temperature_rate_hz / odr)
            pick = np.flatnonzero(
                np.floor(phase) > np.floor(np.concatenate(([temp_acc], phase[:-1]))))
            temp_acc = float(phase[-1]) % 1.0
            if pick.size:
                writes.call('write_temperature', stamps[pick], si.temperature_c[pick],
                            variance=temperature_variance)
                temp_written += pick.size
        if first is None:
            first = int(stamps[0])
        last = int(stamps[-1])
    return first, last, written, temp_written, jumps, configs


#: Blocks (``chunk_bytes`` of log each, about 2.4 MB of arrays per MB of log) that may wait for the
#: writer thread.
WRITE_QUEUE_BLOCKS = 4


class _BagWrites:
    """
    The bag writer and its writes, in a second thread (``threaded``) or in the caller's.

    ``open_writer()`` creates the writer; in the threaded mode it is created, used and closed in
    the writer thread only (rosbags' sqlite3 connection may only be used by the thread that made
    it), and :meth:`call` queues the writes in order. The first exception of the writer thread
    (creating the bag, a write, finishing it) is raised again in the caller: at its next
    :meth:`call` or when the ``with`` block ends; the writes queued after a failed one are
    dropped, as the single thread would never have made them. Leaving the block waits for every
    queued write and finishes the bag, also when the caller failed (the bag then holds what was
    written, as in the single-threaded path).
    """

    def __init__(self, open_writer: Callable[[], Any], threaded: bool) -> None:
        self._open = open_writer
        # (method name, args, kwargs) of the writer calls, None: the end
        self._queue: queue.Queue[tuple[str, tuple, dict] | None] | None = (
            queue.Queue(WRITE_QUEUE_BLOCKS) if threaded else None)
        self._writer: Any = None  # the bag writer (unthreaded)
        self._error: BaseException | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()

    def __enter__(self) -> '_BagWrites':
        if self._queue is None:
            self._writer = self._open()
            return self
        self._thread = threading.Thread(target=self._work, name='gyro_noise_import writer',
                                        daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._error is not None:  # the bag could not be created
            self._thread.join()
            raise self._error
        return self

    def _work(self) -> None:
        try:
            writer = self._open()
        except BaseException as err:  # noqa: B036 - raised in the caller
            self._error = err
            return
        finally:
            self._ready.set()
        assert self._queue is not None  # the thread runs only when threaded
        try:
            while (item := self._queue.get()) is not None:
                if self._error is None:
                    try:
                        getattr(writer, item[0])(*item[1], **item[2])
                    except BaseException as err:  # noqa: B036 - raised in the caller
                        self._error = err
        finally:
            try:
                writer.close()
            except BaseException as err:  # noqa: B036 - raised in the caller
                if self._error is None:
                    self._error = err

    def call(self, method: str, *args: Any, **kwargs: Any) -> None:
        """Call the writer's ``method(*args, **kwargs)`` now, or queue it for the writer thread."""
        if self._queue is None:
            getattr(self._writer, method)(*args, **kwargs)
            return
        if self._error is not None:
            raise self._error
        self._queue.put((method, args, kwargs))

    def __exit__(self, exc_type: Any, exc: BaseException | None, tb: Any) -> Any:
        if self._queue is None:
            return self._writer.__exit__(exc_type, exc, tb)
        self._queue.put(None)  # the thread drains the queue, also after an error
        assert self._thread is not None  # started by __enter__ when threaded
        self._thread.join()
        if self._error is not None and exc is None:
            raise self._error
        return False
