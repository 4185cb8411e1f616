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
The live analysis (``noise_analyzer``): configuration, temperature, the worker.

The live twin of :mod:`gyro_noise_ros.app.analyze`: both feed the same
:class:`~gyro_noise_ros.core.engine.NoiseEngine`. The node (:mod:`gyro_noise_ros.nodes.analyzer`)
only adapts ROS to these; everything here runs and is tested without ROS. :class:`LiveAnalysis`
is the image_pipeline pattern "pure library, thin node, bounded hand-off": the caller's thread
ingests (cheap) and collects results, one worker thread runs the heavy identification from a
bounded queue, and only the caller's thread mutates the engine.
"""

from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import fields
import queue
import threading
from typing import Any

import numpy as np

from ..core.engine import AXES, ChunkJob, EngineConfig, NoiseEngine
from ..core.fractional import make_grid
from ..core.health import HealthThresholds, ReferenceStats
from ..core.results import ChunkResult
from ..errors import GyroNoiseError, ParameterError

#: Chunk results kept in :attr:`LiveAnalysis.results`, about 0.9 kB each (the last 100 chunks of
#: 3 axes, 2.5 min at 6.66 kHz): full within minutes, so the node's memory levels off early
#: (1,000 took 8.3 min and 10,000 83 min to fill; docs/scale.md, memory).
RECENT_RESULTS = 300

#: Numeric per-chunk topics of the analyzer: name -> (ChunkResult field, unit).
CHUNK_TOPICS = {
    'bias': ('bias_rad_s', 'rad/s'),
    'variance': ('variance_rad2_s2', '(rad/s)^2'),
    'alpha_var': ('alpha_var', '-'),
    'alpha_corr': ('alpha_corr', '-'),
    'f_var': ('f_var', '-'),
    'f_corr': ('f_corr', '-'),
}


def parse_axes(text: str) -> tuple[str, ...]:
    """
    Parse the ``axes`` parameter (``'x,y,z'``, ``'z'``, ``'xyz'``) into a tuple of axis names.

    Parameters
    ----------
    text : str
        The parameter value.

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        Unknown, repeated or no axis.

    """
    raw = str(text).replace(' ', '')
    names = raw.split(',') if ',' in raw else list(raw)
    names = [n for n in names if n]
    if not names or any(n not in AXES for n in names) or len(set(names)) != len(names):
        raise ParameterError(f"parameter 'axes' = {text!r} must name distinct axes among x, y, z "
                             "(e.g. 'x,y,z' or 'z')")
    return tuple(names)


def engine_config_from(params: Mapping[str, Any]) -> EngineConfig:
    """
    Build the :class:`EngineConfig` from the analyzer's parameter values.

    Parameters
    ----------
    params : dict
        Name to value (``chunk_size``, ``axes``, ``order_grid_*``, ``memory``, ``demean``,
        ``max_lag``, ``rate_hz``, ``gap_factor``, ``gap_policy``, ``allan``, ``history_chunks``).

    Returns
    -------
    EngineConfig

    Raises
    ------
    ParameterError
        An inconsistent combination (e.g. chunk_size below memory + 2), naming the parameters.

    """
    alphas = make_grid(params['order_grid_start'], params['order_grid_stop'],
                       params['order_grid_step'])
    try:
        return EngineConfig(
            chunk_size=params['chunk_size'], axes=parse_axes(params['axes']), alphas=alphas,
            memory=params['memory'], demean=params['demean'],
            max_lag=None if params['max_lag'] < 0 else params['max_lag'],
            rate_hz=params['rate_hz'] or None, gap_factor=params['gap_factor'],
            gap_policy=params['gap_policy'], allan=params['allan'],
            history_chunks=params['history_chunks'])
    except ParameterError as err:
        raise ParameterError(f'parameters chunk_size/memory/max_lag/order grid: {err}') from err


def thresholds_from(params: Mapping[str, Any]) -> HealthThresholds:
    """
    Build :class:`HealthThresholds` from the parameter values (same names).

    ``params`` maps names to values, a superset of the threshold names.

    """
    return HealthThresholds(**{f.name: params[f.name] for f in fields(HealthThresholds)})


class TemperatureTrack:
    """
    The latest temperature messages of a live stream, interpolated at sample stamps.

    Linear between messages, held constant after the latest (the offline tool, which sees the
    whole bag, interpolates towards the next one there instead).
    """

    def __init__(self) -> None:
        self.stamp_ns: np.ndarray | None = None
        self.temperature_c: np.ndarray | None = None

    def add(self, stamp_ns: np.ndarray, temperature_c: np.ndarray) -> None:
        """
        Add a batch of temperature messages (any order).

        Parameters
        ----------
        stamp_ns : numpy.ndarray of int64
            Header stamps (ns).
        temperature_c : numpy.ndarray
            Temperatures (degC).

        """
        stamp_ns = np.asarray(stamp_ns, np.int64)
        temperature_c = np.asarray(temperature_c, np.float64)
        if not stamp_ns.size:
            return
        if self.stamp_ns is not None and self.temperature_c is not None:  # both or neither
            # Keep the previous latest message so samples between two batches are interpolated.
            stamp_ns = np.concatenate((self.stamp_ns[-1:], stamp_ns))
            temperature_c = np.concatenate((self.temperature_c[-1:], temperature_c))
        order = np.argsort(stamp_ns, kind='stable')
        self.stamp_ns, self.temperature_c = stamp_ns[order], temperature_c[order]

    def at(self, stamp_ns: np.ndarray) -> np.ndarray | float | None:
        """
        Return the temperature at sample stamps.

        Parameters
        ----------
        stamp_ns : numpy.ndarray of int64
            Sample stamps (ns).

        Returns
        -------
        numpy.ndarray or float or None
            degC per stamp; one float when only one message is known; None before any.

        """
        if self.stamp_ns is None or self.temperature_c is None:  # both or neither
            return None
        if self.stamp_ns.size == 1:
            return float(self.temperature_c[0])
        return np.interp(np.asarray(stamp_ns).astype(np.float64),
                         self.stamp_ns.astype(np.float64), self.temperature_c)


class LiveAnalysis:
    """
    Streaming analysis with a bounded queue of chunk jobs served by one worker thread.

    Parameters
    ----------
    config : EngineConfig
        The analysis configuration.
    reference : str, dict of ReferenceStats or None, keyword-only
        ``summary.json`` of a reference recording, or its statistics per axis (see
        :class:`NoiseEngine`).
    thresholds : HealthThresholds or None, keyword-only
        Health thresholds.
    queue_chunks : int, keyword-only
        Chunks (of all axes) waiting for analysis before new ones are skipped.
    on_worker_start : callable, keyword-only
        Called in the worker thread when it starts (a profiler wants its native id).

    """

    def __init__(self, config: EngineConfig, *,
                 reference: str | dict[str, ReferenceStats] | None = None,
                 thresholds: HealthThresholds | None = None, queue_chunks: int = 4,
                 on_worker_start: Callable[[], None] = lambda: None) -> None:
        self.config = config
        self.engine = NoiseEngine(config, reference=reference, thresholds=thresholds)
        self.temperature = TemperatureTrack()
        # recent ChunkResults in completion order (for embedding code and tests; the node's own
        # statistics are the engine's)
        self.results: deque[ChunkResult] = deque(maxlen=RECENT_RESULTS)
        self.last: dict[str, ChunkResult] = {}  # axis -> latest ChunkResult
        self.rejected_batches = 0
        self.last_rejection = ''
        self.last_batch_rejected = False
        # chunk index -> {axis: ChunkResult} until all axes are in
        self._chunks: dict[int, dict[str, ChunkResult]] = {}
        self._jobs: queue.Queue[ChunkJob] = queue.Queue(
            maxsize=int(queue_chunks) * len(config.axes))
        # (job, result, None) or (job, None, the error the analysis raised)
        self._done: queue.SimpleQueue[
            tuple[ChunkJob, ChunkResult | None, Exception | None]] = queue.SimpleQueue()
        self._finished: list[ChunkResult] = []
        self._stop = threading.Event()
        self._on_worker_start = on_worker_start
        self._worker = threading.Thread(target=self._work, name='noise_analyzer_worker',
                                        daemon=True)
        self._worker.start()

    @property
    def queue_size(self) -> int:
        """int: Chunk jobs waiting for the worker."""
        return self._jobs.qsize()

    def stop(self, timeout_s: float = 5.0) -> None:
        """
        Stop and join the worker thread.

        Parameters
        ----------
        timeout_s : float
            Longest wait (s).

        """
        self._stop.set()
        self._worker.join(timeout=timeout_s)

    def _work(self) -> None:
        self._on_worker_start()
        while not self._stop.is_set():
            try:
                job = self._jobs.get(timeout=0.2)
            except queue.Empty:
                continue
            try:
                self._done.put((job, self.engine.analyze(job), None))
            except Exception as err:  # noqa: BLE001 - reported as a skipped chunk, work goes on
                self._done.put((job, None, err))

    def ingest(self, stamp_ns: np.ndarray, gyro: np.ndarray) -> str:
        """
        Feed samples (caller's thread); complete chunks become jobs, or are skipped when full.

        Parameters
        ----------
        stamp_ns : numpy.ndarray of int64
            Sample stamps (ns).
        gyro : numpy.ndarray, shape (n, 3)
            Angular velocity (rad/s).

        Returns
        -------
        str
            Why the batch was refused (the engine's error), or ``''`` when it was accepted.

        """
        try:
            jobs = self.engine.ingest(stamp_ns, gyro, self.temperature.at(stamp_ns))
        except GyroNoiseError as err:
            self.last_rejection = str(err)
            self.rejected_batches += 1
            self.last_batch_rejected = True
            return self.last_rejection
        self.last_batch_rejected = False
        for job in jobs:
            try:
                self._jobs.put_nowait(job)
            except queue.Full:
                self._finish(self.engine.skip(job, 'analysis fell behind'))
        return ''

    def collect(self) -> tuple[list[ChunkResult], list[dict[str, ChunkResult]]]:
        """
        Record the worker's results (caller's thread) and return what finished.

        Returns
        -------
        results : list of ChunkResult
            Every result finished since the previous call (analysed, failed or skipped).
        chunks : list of dict
            ``{axis: ChunkResult}`` of every chunk whose axes are now all finished.

        """
        while True:
            try:
                job, result, err = self._done.get_nowait()
            except queue.Empty:
                break
            if err is not None:
                result = self.engine.skip(job, f'analysis failed: {err}')
            else:
                assert result is not None  # no error: the worker put a result
                self.engine.record(result)
            self._finish(result)
        finished, self._finished = self._finished, []
        chunks = []
        for result in finished:
            per_chunk = self._chunks.setdefault(result.chunk, {})
            per_chunk[result.axis] = result
            if len(per_chunk) == len(self.config.axes):
                chunks.append(self._chunks.pop(result.chunk))
        return finished, chunks

    def _finish(self, result: ChunkResult) -> None:
        self.results.append(result)
        self.last[result.axis] = result
        self._finished.append(result)
