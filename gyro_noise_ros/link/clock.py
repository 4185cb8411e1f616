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
Device time to host time.

Unwrapping of the 32-bit microsecond counter and an offset-and-drift estimator.

Model. The board stamps every sample with its own clock ``d`` (microseconds, uint32, wraps every
2**32 us = 71.6 min). A batch whose newest sample has device time ``d_k`` is received by the host
at ``h_k = a + b d_k + L + e_k`` (host ns), where ``a`` is the clock offset, ``b = 1 + drift`` the
rate ratio (a 50 ppm crystal gives b - 1 = 5e-5), ``L`` the smallest transport latency and ``e_k >=
0`` the USB/OS receive jitter (typically exponential-like, milliseconds).

Estimator (minimum-delay line fit). Jitter only ever *adds* delay, so the informative receive times
are the earliest ones. Device time is cut into blocks of ``block_s`` (1 s); per block the host
keeps the single point with the smallest ``h - d``; a least-squares line through the minima of the
last ``window_blocks`` closed blocks (60) gives ``a`` and ``b`` (extrapolated over the open block).
With F frames per block the block minimum exceeds ``L`` by about mean(e)/F (about 5 us for 2 ms
mean jitter and 417 frames/s), so the line lies within a few microseconds of ``a + b d + L``,
whatever the jitter. Each sample is stamped ``a + b d - latency_ns``; ``latency_ns`` (default 0) is
the constant ``L``, which no receive-only method can observe. Stamps are then clamped to be at most
the receive time (a sample cannot be received before it exists) and forced strictly increasing (1
ns apart at least), so a correction of the line never moves time backwards.

Until the first block closes the slope is taken as 1 and the offset as the smallest ``h - d`` seen
so far: stamps of the first second can be late by up to the jitter of the earliest batches.

Resets. A backward jump of device time (board restart), or a device-time gap that disagrees with
the host-time gap by more than ``reset_threshold_s`` (long unplug across a wrap, a board reset to
another time) restarts the estimator; the monotonic clamp still holds across the restart. A host
gap longer than half a wrap period is used to pick the number of counter wraps.

The measured error on an emulated clock (50 ppm drift, exponential receive delays with a 2 ms mean,
417 frames/s) is recorded in ``docs/portenta_link.md`` and checked by ``test/test_link_clock.py``.
"""

from collections import deque
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from ..errors import ParameterError

WRAP_US = 1 << 32
_HALF_WRAP = 1 << 31


class Unwrapper:
    """
    Unwrap a uint32 counter (device microseconds or sample sequence) into int64, across calls.

    A step is read modulo 2**32 as a signed 32-bit number: forward steps below 2**31 are forward,
    larger ones are backward jumps (which show as decreasing output). ``unwrap`` with a ``hint`` of
    the elapsed count (from another clock) picks the number of wraps for long gaps instead.
    """

    def __init__(self) -> None:
        self.last: int | None = None   # last unwrapped value (int)

    def reset(self) -> None:
        """Forget the history: the next value starts a new epoch."""
        self.last = None

    def unwrap(self, values: npt.ArrayLike, *, hint: float | None = None) -> NDArray[np.int64]:
        """
        Unwrap a batch of counter values.

        Parameters
        ----------
        values : array_like of uint32
            Consecutive raw counter values.
        hint : float, optional, keyword-only
            Expected increment from the last value of the previous batch to the first one of this
            batch (counter units); selects the number of whole wraps in between.

        Returns
        -------
        numpy.ndarray
            int64 unwrapped values (the first batch ever starts at its raw value).

        """
        raw = np.asarray(values).astype(np.uint32, copy=False)
        if raw.size == 0:
            return np.zeros(0, dtype=np.int64)
        steps = np.empty(raw.size, dtype=np.int64)
        steps[1:] = np.diff(raw).astype(np.uint32).view(np.int32)
        if self.last is None:
            first = int(raw[0])
        else:
            step0 = (int(raw[0]) - self.last) % WRAP_US
            if step0 >= _HALF_WRAP:
                step0 -= WRAP_US
            if hint is not None:
                step0 += WRAP_US * int(round((float(hint) - step0) / WRAP_US))
            first = self.last + step0
        steps[0] = 0
        out = first + np.cumsum(steps)
        self.last = int(out[-1])
        return out


@dataclass(frozen=True)
class ClockState:
    """
    Snapshot of the device-clock estimator.

    Attributes
    ----------
    offset_ns : float
        Host time (ns) of unwrapped device time 0 of the current epoch according to the line
        (approximate: float64).
    drift_ppm : float
        Host-clock rate relative to the device clock minus one, in parts per million
        (positive: the device clock runs slow).
    blocks : int
        Closed blocks in the fit window.
    resets : int
        Estimator restarts (device clock jumps).
    samples : int
        Samples stamped.

    """

    offset_ns: float
    drift_ppm: float
    blocks: int
    resets: int
    samples: int


class DeviceClock:
    """
    Map device sample times to host (node clock) time, free of receive jitter and monotonic.

    Parameters
    ----------
    nominal_rate_hz : float, optional, keyword-only
        Nominal sample rate (Hz); when given, :attr:`measured_rate_hz` can be compared with it and
        the block length is never shorter than 100 sample periods.
    block_s : float, keyword-only
        Device-time length of a minimum block (s).
    window_blocks : int, keyword-only
        Number of closed blocks in the line fit (the drift is tracked over this window).
    latency_ns : int, keyword-only
        Constant transport latency to subtract (ns); not observable by the estimator.
    reset_threshold_s : float, keyword-only
        Disagreement between device and host gaps between two batches that restarts the estimator
        (s).
    max_drift_ppm : float, keyword-only
        Bound on the fitted drift (ppm); a fit beyond it falls back to slope 1 (bad data, not a
        clock).

    """

    def __init__(self, *, nominal_rate_hz: float | None = None, block_s: float = 1.0,
                 window_blocks: int = 60, latency_ns: int = 0, reset_threshold_s: float = 0.5,
                 max_drift_ppm: float = 2000.0) -> None:
        if nominal_rate_hz is not None and not (np.isfinite(nominal_rate_hz) and nominal_rate_hz
                                                > 0):
            raise ParameterError(f'nominal_rate_hz must be > 0, got {nominal_rate_hz}')
        if not (np.isfinite(block_s) and block_s > 0):
            raise ParameterError(f'block_s must be > 0, got {block_s}')
        if int(window_blocks) < 2:
            raise ParameterError(f'window_blocks must be >= 2, got {window_blocks}')
        if not (np.isfinite(reset_threshold_s) and reset_threshold_s > 0):
            raise ParameterError(f'reset_threshold_s must be > 0, got {reset_threshold_s}')
        self.nominal_rate_hz = None if nominal_rate_hz is None else float(nominal_rate_hz)
        block_us = float(block_s) * 1e6
        if self.nominal_rate_hz is not None:
            block_us = max(block_us, 100e6 / self.nominal_rate_hz)
        self._block_us = block_us
        self._window = int(window_blocks)
        self.latency_ns = int(latency_ns)
        self._reset_ns = float(reset_threshold_s) * 1e9
        self._max_drift = float(max_drift_ppm) * 1e-6
        self._last_stamp: int | None = None
        self._resets = 0
        self._samples = 0
        self._unwrap = Unwrapper()
        self._start_epoch()

    def _start_epoch(self) -> None:
        self._unwrap.reset()
        # (d_us, h_ns - d_us*1000) of closed blocks
        self._blocks: deque[tuple[int, float]] = deque(maxlen=self._window)
        self._cur_block: int | None = None                # block index of the open block
        self._cur_min: tuple[int, float] | None = None    # (d_us, y_ns) of the open block
        self._last_d: int | None = None
        self._last_h: int | None = None
        self._first_d: int | None = None
        self._h_ref: int | None = None
        self._d_ref: int | None = None
        self._a: float | None = None  # y = a + s * (d - d0)  with y = h - 1000 d
        self._s = 0.0
        self._d0 = 0.0

    def reset(self) -> None:
        """Forget all but the monotonic floor (stamps never go back, even after a reset)."""
        self._start_epoch()
        self._resets += 1

    @property
    def state(self) -> ClockState:
        """ClockState: the current estimate."""
        if self._a is None:
            a = float('nan')
        else:
            assert self._h_ref is not None and self._d_ref is not None  # set before the first fit
            a = self._h_ref - 1000.0 * self._d_ref + self._a - self._s * (self._d0 + self._d_ref)
        return ClockState(offset_ns=a, drift_ppm=self._s / 1000.0 * 1e6, blocks=len(self._blocks),
                          resets=self._resets, samples=self._samples)

    @property
    def measured_rate_hz(self) -> float | None:
        """Return the sample rate seen in host time, or None without a nominal rate."""
        if self.nominal_rate_hz is None:
            return None
        return self.nominal_rate_hz / (1.0 + self._s / 1000.0)

    def update(self, t_us: npt.ArrayLike, host_receive_ns: int) -> NDArray[np.int64]:
        """
        Stamp one received batch.

        Parameters
        ----------
        t_us : numpy.ndarray
            uint32 device times of the batch's samples (microseconds, wrapping), oldest first.
        host_receive_ns : int
            Host time when the batch was received (ns, the node clock).

        Returns
        -------
        numpy.ndarray
            int64 host-time stamps (ns), one per sample, strictly increasing across all calls.

        """
        raw = np.asarray(t_us)
        if raw.size == 0:
            return np.zeros(0, dtype=np.int64)
        h = int(host_receive_ns)
        hint = None
        if self._last_h is not None and h - self._last_h > _HALF_WRAP * 1000:
            hint = (h - self._last_h) / 1000.0
        d = self._unwrap.unwrap(raw, hint=hint)
        if self._last_d is not None:
            assert self._last_h is not None  # set with self._last_d
            dd = int(d[0]) - self._last_d
            dh = h - self._last_h
            if dd < 0 or abs(dd * 1000.0 * (1.0 + self._s / 1000.0)
                             - dh) > self._reset_ns + 2e-3 * abs(dh):
                self.reset()
                d = self._unwrap.unwrap(raw)
        d_last = int(d[-1])
        if self._h_ref is None:
            self._h_ref, self._d_ref = h, d_last
        assert self._d_ref is not None  # set with self._h_ref
        self._observe(d_last - self._d_ref, h - self._h_ref)
        assert self._a is not None  # _observe fitted the line
        rel = d - self._d_ref
        # exact integer part plus a small float correction: float64 cannot hold ns since 1970
        # exactly
        correction = np.rint(self._a + self._s * (rel.astype(np.float64)
                                                  - self._d0)).astype(np.int64)
        stamps = self._h_ref + 1000 * rel + correction - self.latency_ns
        # causality: the newest sample existed before it was received
        excess = int(stamps[-1]) - (h - self.latency_ns)
        if excess > 0:
            stamps -= excess
        n = stamps.size
        idx = np.arange(n, dtype=np.int64)
        floor = -np.iinfo(np.int64).max if self._last_stamp is None else self._last_stamp + 1
        u = np.maximum.accumulate(np.maximum(stamps - idx, floor))
        stamps = u + idx
        self._last_stamp = int(stamps[-1])
        self._last_d, self._last_h = d_last, h
        self._samples += n
        return stamps

    def _observe(self, d_us: int, h_ns: int) -> None:
        # both relative to the epoch's first batch, so y stays small and exact in float64
        y = float(h_ns - 1000 * d_us)
        if self._first_d is None:
            self._first_d = d_us
        block = int((d_us - self._first_d) // self._block_us)
        if self._cur_block is None:
            self._cur_block = block
        closed = False
        if block != self._cur_block:
            if self._cur_min is not None:
                self._blocks.append(self._cur_min)
                closed = True
            self._cur_block = block
            self._cur_min = None
        if self._cur_min is None or y < self._cur_min[1]:
            self._cur_min = (d_us, y)
        # the line changes only when a block closes, except while the open block is all there is
        if closed or len(self._blocks) < 2 or self._a is None:
            self._fit()

    def _fit(self) -> None:
        pts = list(self._blocks)
        if len(self._blocks) < 2:
            # the open block's running minimum is used only while there is nothing better: right
            # after a block opens it is a single, possibly very late, point and would pull the line
            # up
            if self._cur_min is not None:
                pts.append(self._cur_min)
            # not enough closed blocks for a slope: slope 0 (b = 1), offset from the lowest point
            self._s = 0.0
            self._d0 = 0.0
            self._a = min(p[1] for p in pts)
            return
        dx = np.array([p[0] for p in pts], dtype=np.float64)
        y = np.array([p[1] for p in pts], dtype=np.float64)
        d0 = dx.mean()
        x = dx - d0
        sxx = float(x @ x)
        slope = float(x @ (y - y.mean())) / sxx if sxx > 0 else 0.0
        if abs(slope / 1000.0) > self._max_drift:
            slope = 0.0
        self._s = slope
        self._d0 = d0
        self._a = float(y.mean())
