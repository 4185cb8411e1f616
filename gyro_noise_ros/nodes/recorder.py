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
ROS 2 node ``gyro_noise_record``: record ``imu/data_raw`` and ``imu/temperature`` into a rosbag2.

``ros2 bag`` is not installable from PyPI, so this small recorder writes rosbag2 (sqlite3 or MCAP)
through :class:`gyro_noise_ros.bag.ImuBagWriter` (the rosbags library); with a full ROS install
``ros2 bag record /imu/data_raw /imu/temperature`` does the same job, its bags interchangeable.

Loss-free at 6.66 kHz: the subscriptions are ``raw=True`` (serialised CDR) in a callback group
the executor never runs (:class:`PolledGroup`); a 50 ms timer drains them with ``take_message``
and writes each batch in bulk (a batch of one verified layout byte for byte, as received; anything
else decoded and re-encoded). The QoS history (``queue_depth`` messages) holds far more than
50 ms of data, so nothing is overwritten between drains.

Messages received and written are counted per publisher (:mod:`._publishers`); gaps in each
publisher's DDS publication sequence numbers are counted as ``dropped``; a second publisher on a
recorded topic is warned about once, naming the publishers. On SIGINT or SIGTERM the queues are
drained once more, the bag is closed (its ``metadata.yaml`` written) and one summary line is
printed.

Crash safety: every ``flush_period_s`` (0.5 s) the bag is flushed (:meth:`ImuBagWriter.flush`),
so a recorder killed by SIGKILL loses at most that span plus what DDS still queues; the tools
read the killed recording as it is and ``gyro_noise_record repair`` writes a complete bag from it
(docs/bags.md, killed recordings; docs/demo.md, the recorder).
"""

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path
import shutil
import sys
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray
from rclpy.node import Node
from sensor_msgs.msg import Imu, Temperature

from ._publishers import PublisherWatch, RawTaker
from ._ros_common import (declare_parameter_table, ParamSpec, PolledGroup, run_node,
                          sensor_data_qos, unused_callback, wall_timer)
from ..bag import decode_imu, decode_temperature, ImuBagWriter
from ..bag.storage import describe
from ..errors import GyroNoiseError, OutputError
from ..msgs import frame_id_of, imu_covariances, temperature_variances
from ..msgs.imu_rows import RowLayout, rows_stamps
from ..outputs import check_new_dir

NODE_NAME = 'gyro_noise_record'

#: Imu messages written at a time (0.3 s at 6.66 kHz); a larger backlog goes in several batches.
MAX_BATCH = 2000

#: Parameter table (``config/gyro_noise_record.yaml`` lists every row).
PARAMETERS = (
    ParamSpec('output', '', 'Bag directory to create; empty: gyro_noise_<UTC date>_<time> in '
              'the working directory', read_only=True),
    ParamSpec('overwrite', False, 'Replace an existing bag at output (a bag folder only, when '
              'the first message arrives); false: an existing output is refused at start',
              read_only=True),
    ParamSpec('storage', 'sqlite3', 'rosbag2 storage plugin', read_only=True,
              choices=('sqlite3', 'mcap')),
    ParamSpec('record_temperature', True, 'Also record imu/temperature', read_only=True),
    ParamSpec('reliable', False, 'Subscribe reliable (retransmitted; matches only a reliable '
              'publisher such as the driver) instead of sensor-data best effort, so a busy host '
              'drops no message that would count as a lost sample', read_only=True),
    ParamSpec('queue_depth', 20000, 'QoS history depth of the subscriptions', unit='messages',
              read_only=True, min_value=10, max_value=1000000),
    # 50 ms: a batch of ~330 messages per executor wake-up (20 a second instead of 100: each
    # costs rclpy's wait-set set-up and the batch calls); the 3-s history covers it many times.
    ParamSpec('drain_period_s', 0.05,
              'Period of the loop that takes queued messages and writes them',
              unit='s', read_only=True, min_value=0.001, max_value=0.5),
    ParamSpec('flush_period_s', 0.5,
              'Period of the flush (sqlite3 commit, MCAP chunk closed) that bounds what a '
              'killed recorder loses (0: only at close)', unit='s', read_only=True,
              min_value=0.0, max_value=3600.0),
    ParamSpec('report_period_s', 10.0, 'Period of the progress line in the log (0: never)',
              unit='s',
              read_only=True, min_value=0.0, max_value=3600.0),
)


#: How a user of the node gives the parameters an output error names (errors.GyroNoiseError).
SPELLING = {'output': "parameter 'output' =", 'overwrite': '-p overwrite:=true'}


def check_output(output: str, *, overwrite: bool) -> None:
    """
    Refuse the bag folder ``output`` before recording (:func:`..outputs.check_new_dir`).

    Parameters
    ----------
    output : str
        The ``output`` parameter.
    overwrite : bool, keyword-only
        The ``overwrite`` parameter.

    Raises
    ------
    OutputError
        As ``check_new_dir``, its message naming the parameters as ``-p`` gives them.

    """
    try:
        check_new_dir(output, parameter='output', overwrite=overwrite)
    except OutputError as err:
        raise OutputError(err.spelled(lambda name: SPELLING.get(name, name))) from err


def default_bag_name(now: datetime | None = None) -> str:
    """Return ``gyro_noise_<YYYYmmdd>_<HHMMSS>`` for the current UTC time (or ``now``)."""
    now = now or datetime.now(timezone.utc)
    return now.strftime('gyro_noise_%Y%m%d_%H%M%S')


class RecorderNode(Node):
    """
    Record the IMU stream into a rosbag2 (see the module docstring).

    Parameters
    ----------
    **kwargs
        Passed to :class:`rclpy.node.Node` (e.g. ``parameter_overrides`` in tests).

    Raises
    ------
    ParameterError
        A parameter is invalid.
    OutputError
        The bag cannot be created: the output exists (without ``overwrite``, or is not a bag),
        lies under a file or in a folder that cannot be written (a read-only file system),
        checked at start; or writing it failed later (disk full).

    """

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        params = declare_parameter_table(self, PARAMETERS)
        self.output = params['output'] or default_bag_name()
        self.storage = params['storage']
        self.received_imu = 0
        self.received_temperature = 0
        self.written_imu = 0
        self.written_temperature = 0
        self._writer: ImuBagWriter | None = None
        self._layout = RowLayout()
        self._closed = False
        self._overwrite = params['overwrite']
        # before spinning: a refused output fails now, not when the first message arrives
        check_output(self.output, overwrite=self._overwrite)
        group = PolledGroup()
        qos = sensor_data_qos(params['queue_depth'], params['reliable'])
        self._imu_sub = self.create_subscription(Imu, 'imu/data_raw', unused_callback, qos,
                                                 raw=True,
                                                 callback_group=group)
        self._temperature_sub = None
        if params['record_temperature']:
            self._temperature_sub = self.create_subscription(
                Temperature, 'imu/temperature', unused_callback, qos, raw=True,
                callback_group=group)
        self._watch_publishers_setup()
        wall_timer(self, params['drain_period_s'], self.drain)
        if params['flush_period_s'] > 0:
            wall_timer(self, params['flush_period_s'], self._flush)
        if params['report_period_s'] > 0:
            wall_timer(self, params['report_period_s'], self._report)
        self.get_logger().info(f'recording {self._imu_sub.topic_name}'
                               + (f' and {self._temperature_sub.topic_name}'
                                  if self._temperature_sub else '')
                               + f' into {self.output} ({self.storage})')

    @property
    def dropped(self) -> int:
        """int: Messages the transport dropped before this node (per-publisher sequence gaps)."""
        return sum(w.counts.missing for w, _ in self._watches)

    # ---- who publishes (counts per publisher, the second-publisher warning) ----------------

    def _watch_publishers_setup(self) -> None:
        consequence = 'the bag mixes their messages (counts are kept per publisher)'
        self._imu_watch = PublisherWatch(self._imu_sub.topic_name, consequence)
        self._imu_taker = RawTaker(self._imu_sub, Imu, self.get_logger())
        self._watches = [(self._imu_watch, self._imu_taker)]
        if self._temperature_sub is not None:
            self._temperature_watch = PublisherWatch(self._temperature_sub.topic_name,
                                                     consequence)
            self._temperature_taker = RawTaker(self._temperature_sub, Temperature,
                                               self.get_logger())
            self._watches.append((self._temperature_watch, self._temperature_taker))
        wall_timer(self, 1.0, self._check_publishers)

    def _take(self, watch: PublisherWatch, taker: RawTaker,
              limit: int | None = None) -> tuple[list[bytes], list[int]]:
        raws, received, sequence, gids = taker.take(limit)
        if raws:
            watch.update(gids, sequence, time.monotonic())
        return raws, received

    def _check_publishers(self) -> None:
        for watch, _ in self._watches:
            for severity, line in watch.check(self):
                if severity == 'warn':  # rclpy refuses two severities from one call site
                    self.get_logger().warn(line)
                else:
                    self.get_logger().info(line)

    def publisher_summary(self) -> str:
        """Return ``'publishers of <topic>: <name> <count> (<dropped> dropped); ...'``."""
        return '; '.join(f'publishers of {w.topic}: {w.summary()}' for w, _ in self._watches)

    def _open(self, frame_id: str | None) -> None:
        if self._overwrite and Path(self.output).exists():
            check_output(self.output, overwrite=True)
            shutil.rmtree(self.output)  # a bag folder (checked): what overwrite:=true asked
        self._writer = ImuBagWriter(
            self.output, storage=self.storage, imu_topic=self._imu_sub.topic_name,
            temperature_topic=(self._temperature_sub.topic_name if self._temperature_sub
                               else None),
            frame_id=frame_id or 'imu_link')

    @contextmanager
    def _writing(self) -> Iterator[None]:
        """Turn a failed write (disk full, the folder gone) into one OutputError (exit code 6)."""
        try:
            yield
        except GyroNoiseError:
            raise
        except Exception as err:  # noqa: BLE001 - rosbags, sqlite3 and OS errors
            self._closed = True  # nothing more can be written; the summary still says what was
            raise OutputError(f'cannot write the bag {self.output!r}: {describe(err)}') from err

    def drain(self) -> None:
        """Take every queued message and write it (called by the timer and at shutdown)."""
        if self._closed:
            return
        with self._writing():
            self._drain()

    def _drain(self) -> None:
        # A backlog (a commit or the host stalled) goes through in bounded batches: one large
        # batch would grow the heap for good. Temperatures are taken once, after the Imu messages.
        while True:
            raws, received = self._take(self._imu_watch, self._imu_taker, MAX_BATCH)
            more = len(raws) == MAX_BATCH
            self._write_batch(raws, received, [], [])
            if not more:
                break
        t_raws, t_received = ([], []) if self._temperature_sub is None else \
            self._take(self._temperature_watch, self._temperature_taker)
        self._write_batch([], [], t_raws, t_received)

    def _write_batch(self, raws: list[bytes], received: Sequence[int], t_raws: list[bytes],
                     t_received: Sequence[int]) -> None:
        if self._writer is None and (raws or t_raws):
            # The bag is created on the first message so it carries the sensor's frame_id.
            self._open(frame_id_of((raws or t_raws)[0], False))
        if raws:
            assert self._writer is not None  # opened above
            self.received_imu += len(raws)
            self._write_imu(raws, received)
            self.written_imu += len(raws)
        if t_raws:
            assert self._writer is not None  # opened above
            self.received_temperature += len(t_raws)
            stamp_ns, temperature_c = decode_temperature(t_raws)
            self._writer.write_temperature(stamp_ns, temperature_c,
                                           variance=temperature_variances(t_raws),
                                           log_ns=_log_times(t_received, stamp_ns))
            self.written_temperature += len(t_raws)

    def _write_imu(self, raws: list[bytes], received: Sequence[int]) -> None:
        rows = self._layout.rows(raws)
        if rows is not None:
            # One verified layout (one publisher's messages): stored byte for byte, as
            # ros2 bag record stores them, with no decode and re-encode.
            log_ns = _log_times(received, rows_stamps(rows))
            assert self._writer is not None and log_ns is not None  # opened by drain; stamps
            self._writer.write_imu_raw(raws, log_ns)
            return
        batch = decode_imu(raws, log_ns=_log_times(received, None))
        av_cov, la_cov = imu_covariances(raws)
        assert self._writer is not None  # opened by drain
        self._writer.write_imu(batch.stamp_ns, batch.gyro, batch.accel,
                               angular_velocity_covariance=av_cov,
                               linear_acceleration_covariance=la_cov, log_ns=batch.log_ns)

    def _flush(self) -> None:
        if self._writer is not None and not self._closed:
            with self._writing():
                self._writer.flush()

    def _report(self) -> None:
        self.get_logger().info(f'{self.written_imu} Imu, {self.written_temperature} Temperature '
                               f'written; {self.dropped} dropped in transport; '
                               f'{self.publisher_summary()}')

    def close(self) -> str:
        """Drain once more, close the bag and return the summary line (idempotent)."""
        if not self._closed:
            try:
                self.drain()
            finally:
                self._closed = True
                if self._writer is not None:
                    with self._writing():
                        self._writer.close()
        where = (self.output if self._writer is not None
                 else f'{self.output} (not created: nothing received)')
        return (f'{NODE_NAME}: received {self.received_imu} Imu and {self.received_temperature} '
                f'Temperature messages, wrote {self.written_imu} and {self.written_temperature} '
                f'to '
                f'{where}; {self.dropped} dropped in transport; {self.publisher_summary()}')

    def destroy_node(self) -> None:
        try:
            summary = self.close()
            print(summary, file=sys.stderr, flush=True)
        finally:
            for _, taker in getattr(self, '_watches', ()):
                taker.close()
            super().destroy_node()


def _log_times(received: Sequence[int], fallback_ns: np.ndarray | None
               ) -> NDArray[np.int64] | None:
    """Receive times as int64 ns; the header stamps (``fallback_ns``) where the RMW gave none."""
    log = np.asarray(received, dtype=np.int64)
    if fallback_ns is not None and np.any(log == 0):
        log = np.where(log == 0, fallback_ns, log)
    elif fallback_ns is None and np.any(log == 0):
        return None
    return log


def main(args: list[str] | None = None) -> int:
    """
    Run the recorder until Ctrl-C or SIGTERM; ``args`` is the command line (None: ``sys.argv``).

    Returns 0; 130/143 after SIGINT/SIGTERM (the bag closed); 2 for a bad or unknown parameter; 6
    when the bag cannot be created (it exists without ``overwrite``, under a file, a read-only
    folder) or written (disk full).

    """
    return run_node(RecorderNode, args, prog=NODE_NAME, parameters=PARAMETERS,
                    summary=__doc__)


if __name__ == '__main__':
    sys.exit(main())
