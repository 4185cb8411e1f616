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
Device time to host time: unwrapping of the 32-bit microsecond counter, offset-and-drift fit.

Model. The board stamps every sample with its own clock ``d`` (microseconds, uint32, wraps every
2**32 us = 71.6 min). A batch whose newest sample has device time ``d_k`` is received by the host
at ``h_k = a + b d_k + L + e_k`` (host ns): clock offset ``a``, rate ratio ``b = 1 + drift`` (a
50 ppm crystal gives b - 1 = 5e-5), the smallest transport latency ``L`` and the receive jitter
``e_k >= 0`` (USB/OS, milliseconds).

Estimator (minimum-delay line fit). Jitter only ever *adds* delay, so per block of ``block_s``
(1 s) of device time the host keeps the point with the smallest ``h - d``; a least-squares line
through the minima of the last ``window_blocks`` (60) closed blocks gives ``a`` and ``b``; before
two blocks have closed the slope is 1 and the offset the smallest ``h - d`` so far.
``latency_ns`` (default 0) is the constant ``L``, which no receive-only method can observe.

Stamps never step (a step of a fraction of a period reads as a lost sample downstream): the first
``settle_s`` of an epoch are held back while the offset converges; then the stamps follow a line
of their own, continuous across batches, at the estimate's rate corrected by the offset to it
over :data:`SLEW_TIME_S` (at most :data:`MAX_SLEW_PPM`); a batch whose last stamp would lie
after its receive time is compressed onto it. Resets (a backward jump of device time, or a device
gap longer than the host gap by more than ``reset_threshold_s``; a longer host gap is a late
read) restart the estimator and the settling; stamps stay strictly increasing. The measured
stamp error: docs/portenta_link.md section 6 (``test/test_link_clock.py``).
"""

from collections import deque
from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from ..core.jit import JIT_OPTIONS
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

    def first_of(self, value: int, *, hint: float | None = None) -> int:
        """Return the unwrapped value of a batch's first raw ``value`` (changes nothing)."""
        if self.last is None:
            return value
        step0 = (value - self.last) % WRAP_US
        if step0 >= _HALF_WRAP:
            step0 -= WRAP_US
        if hint is not None:
            step0 += WRAP_US * int(round((float(hint) - step0) / WRAP_US))
        return self.last + step0

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
        first = self.first_of(int(raw[0]), hint=hint)
        rel = raw.astype(np.int64)
        rel -= rel[0]
        if raw.size > 1 and not (rel[-1] < _HALF_WRAP and np.all(rel[1:] >= rel[:-1])):
            # A wrap or a backward jump inside the batch: signed 32-bit steps.
            steps = np.empty(raw.size, dtype=np.int64)
            steps[1:] = np.diff(raw).astype(np.uint32).view(np.int32)
            steps[0] = 0
            rel = np.cumsum(steps)
        out = first + rel
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
    settled : bool
        The epoch's first ``settle_s`` are over: batches are stamped as they come.
    held : int
        Samples held while the epoch settles.
    offset_error_ns : float
        The stamps' line minus the estimate at the newest sample (ns): what the slew is removing.
    compressed : int
        Batches compressed onto their receive time (their stamps would have lain after it).
    steps : int
        Offsets beyond :data:`MAX_SLEW_OFFSET_S` removed by a step instead of a slew (a host clock
        set by hand or NTP).

    """

    offset_ns: float
    drift_ppm: float
    blocks: int
    resets: int
    samples: int
    settled: bool = False
    held: int = 0
    offset_error_ns: float = 0.0
    compressed: int = 0
    steps: int = 0


#: Time constant of the slew that brings the stamps' line onto the estimate (s).
SLEW_TIME_S = 2.0
#: Largest rate correction of the slew (ppm): 0.05 % of a sample period per sample.
MAX_SLEW_PPM = 500.0
#: An offset to the estimate beyond this is removed at once, and counted (s).
MAX_SLEW_OFFSET_S = 0.1
#: A block minimum this far above the fitted line is left out of the fit (ns): its whole block was
#: read late (a host stall longer than the block), while block minima scatter by microseconds.
_LATE_BLOCK_NS = 1_000_000


@numba.njit(**JIT_OPTIONS)
def _steady_stamps(  # pragma: no cover - compiled; tested through DeviceClock.update
        raw: NDArray[np.uint32], first_rel: int, rel0: int, stamp0: int, rate: float,
        limit_ns: int, floor: int, out: NDArray[np.int64]) -> tuple[bool, int]:
    """
    Stamp a batch as :meth:`DeviceClock.update` does when nothing is unusual.

    ``raw``'s device times unwrapped from ``first_rel`` (relative to the epoch's reference) onto
    the stamps' line through ``(rel0, stamp0)`` at ``rate``, then strictly increasing above
    ``floor`` (the general path's numpy steps, one sample at a time). Returns (False, 0), with
    ``out`` meaningless, when the batch goes back in device time or spans half a wrap (the
    general unwrap), or its newest stamp lies after ``limit_ns`` (the general compression);
    else (True, the newest device time relative to the reference).
    """
    n = raw.shape[0]
    r0 = np.int64(raw[0])
    prev = np.int64(0)
    for i in range(n):
        step = np.int64(raw[i]) - r0
        if step < prev:
            return False, 0
        prev = step
        out[i] = stamp0 + np.int64(np.rint(np.float64(first_rel + step - rel0) * rate))
    if prev >= _HALF_WRAP or out[n - 1] - limit_ns > 0:
        return False, 0
    high = np.int64(floor)
    for i in range(n):
        high = max(high, out[i] - i)
        out[i] = high + i
    return True, first_rel + prev  # type: ignore[return-value]  # numba boxes it as int


class DeviceClock:
    """
    Map device sample times to host (node clock) time, free of receive jitter, without steps.

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
        How much longer the device gap between two batches may be than the host gap before the
        estimator restarts (s).
    max_drift_ppm : float, keyword-only
        Bound on the fitted drift (ppm); a fit beyond it falls back to slope 1 (bad data, not a
        clock).
    settle_s : float, keyword-only
        Device time held back at the start of an epoch while the offset converges (s); 0: stamp
        the first batch at once (later corrections are then slewed or compressed).

    """

    def __init__(self, *, nominal_rate_hz: float | None = None, block_s: float = 1.0,
                 window_blocks: int = 60, latency_ns: int = 0, reset_threshold_s: float = 0.5,
                 max_drift_ppm: float = 2000.0, settle_s: float = 0.0) -> None:
        if nominal_rate_hz is not None and not (np.isfinite(nominal_rate_hz) and nominal_rate_hz
                                                > 0):
            raise ParameterError(f'nominal_rate_hz must be > 0, got {nominal_rate_hz}')
        if not (np.isfinite(block_s) and block_s > 0):
            raise ParameterError(f'block_s must be > 0, got {block_s}')
        if int(window_blocks) < 2:
            raise ParameterError(f'window_blocks must be >= 2, got {window_blocks}')
        if not (np.isfinite(reset_threshold_s) and reset_threshold_s > 0):
            raise ParameterError(f'reset_threshold_s must be > 0, got {reset_threshold_s}')
        if not (np.isfinite(settle_s) and settle_s >= 0):
            raise ParameterError(f'settle_s must be >= 0, got {settle_s}')
        self.nominal_rate_hz = None if nominal_rate_hz is None else float(nominal_rate_hz)
        block_us = float(block_s) * 1e6
        if self.nominal_rate_hz is not None:
            block_us = max(block_us, 100e6 / self.nominal_rate_hz)
        self._block_us = block_us
        self._window = int(window_blocks)
        self.latency_ns = int(latency_ns)
        self._reset_ns = float(reset_threshold_s) * 1e9
        self._max_drift = float(max_drift_ppm) * 1e-6
        self._settle_us = float(settle_s) * 1e6
        self._last_stamp: int | None = None
        self._resets = 0
        self._samples = 0
        self._compressed = 0
        self._steps = 0
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
        # The stamps' own line: its newest point (device us relative to _d_ref, ns) and rate
        # (ns per device us); None until the epoch has settled.
        self._pub: tuple[int, int] | None = None
        self._pub_rate = 1000.0
        self._held: list[NDArray[np.int64]] = []  # device us relative to _d_ref, while settling
        self._epoch_first_d: int | None = None
        self._offset_error = 0.0

    def reset(self) -> None:
        """
        Forget all but the monotonic floor (stamps never go back, even after a reset).

        Samples held while the epoch settled are dropped: :meth:`flush` them first.
        """
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
                          resets=self._resets, samples=self._samples,
                          settled=self._pub is not None, held=sum(h.size for h in self._held),
                          offset_error_ns=self._offset_error, compressed=self._compressed,
                          steps=self._steps)

    @property
    def measured_rate_hz(self) -> float | None:
        """Return the sample rate seen in host time, or None without a nominal rate."""
        if self.nominal_rate_hz is None:
            return None
        return self.nominal_rate_hz / (1.0 + self._s / 1000.0)

    def update(self, t_us: npt.ArrayLike, host_receive_ns: int) -> NDArray[np.int64]:
        """
        Take one received batch; stamp what can be stamped.

        Parameters
        ----------
        t_us : numpy.ndarray
            uint32 device times of the batch's samples (microseconds, wrapping), oldest first.
        host_receive_ns : int
            Host time when the batch was received (ns, the node clock).

        Returns
        -------
        numpy.ndarray
            int64 host-time stamps (ns), strictly increasing across all calls, of the samples
            released by this batch, oldest first: none while the epoch settles, then the held
            samples and this batch's; when this batch starts a new epoch (a reset), the previous
            epoch's held samples (this batch is then held).

        """
        raw = np.asarray(t_us)
        if raw.size == 0:
            return np.zeros(0, dtype=np.int64)
        h = int(host_receive_ns)
        if self._pub is not None and raw.dtype == np.uint32 and raw.ndim == 1:
            stamps = self._update_steady(raw, h)
            if stamps is not None:
                return stamps
        d = self._unwrap.unwrap(raw, hint=self._hint(h))
        flushed = np.zeros(0, dtype=np.int64)
        if self._last_d is not None:
            if self._is_reset(int(d[0]), h):
                flushed = self.flush()
                self.reset()
                d = self._unwrap.unwrap(raw)
        d_last = int(d[-1])
        if self._h_ref is None:
            self._h_ref, self._d_ref, self._epoch_first_d = h, d_last, int(d[0])
        assert self._d_ref is not None and self._epoch_first_d is not None  # set with _h_ref
        self._observe(d_last - self._d_ref, h - self._h_ref)
        self._last_d, self._last_h = d_last, h
        rel = d - self._d_ref
        if self._pub is None:
            self._held.append(rel)
            if d_last - self._epoch_first_d < self._settle_us:
                return flushed
            rel = np.concatenate(self._held)
            self._held = []
        stamps = self._stamp(rel, h - self.latency_ns)
        return np.concatenate((flushed, stamps)) if flushed.size else stamps

    def _hint(self, h: int) -> float | None:
        """Return the host gap (us) to unwrap with, when it is longer than half a wrap."""
        if self._last_h is not None and h - self._last_h > _HALF_WRAP * 1000:
            return (h - self._last_h) / 1000.0
        return None

    def _is_reset(self, first_d: int, h: int) -> bool:
        """
        Return whether a batch starting at device time ``first_d``, received at ``h``, is a reset.

        Device time that went back, or ran ahead of host time: a board restarted or set to
        another time. Host time ahead of device time is a late read (the host stalled and the
        bytes waited in the port), not a jump: the minimum-delay line ignores it.
        """
        assert self._last_d is not None and self._last_h is not None  # a batch came before
        dd = first_d - self._last_d
        dh = h - self._last_h
        return dd < 0 or (dd * 1000.0 * (1.0 + self._s / 1000.0) - dh
                          > self._reset_ns + 2e-3 * abs(dh))

    def _update_steady(self, raw: NDArray[np.uint32], h: int) -> NDArray[np.int64] | None:
        """
        :meth:`update` of the usual batch of a settled epoch, or None for the general path.

        The usual batch: device times that do not go back, no reset, no long host gap, a newest
        stamp not after the receive time (nothing to compress). Its stamps come from one compiled
        pass; the state changes as :meth:`update` changes it (tested on random streams against
        the clock without this path). Nothing changes before it is known to apply.
        """
        if (self._unwrap.last is None or self._last_d is None or self._last_stamp is None
                or self._hint(h) is not None):
            return None  # nothing to continue, or a host gap the general unwrap bridges
        first = self._unwrap.first_of(int(raw[0]))
        if self._is_reset(first, h):
            return None
        assert self._d_ref is not None and self._h_ref is not None and self._pub is not None
        rel0, stamp0 = self._pub
        stamps = np.empty(raw.shape[0], np.int64)
        ok, rel_last = _steady_stamps(raw, first - self._d_ref, rel0, stamp0, self._pub_rate,
                                      h - self.latency_ns, self._last_stamp + 1, stamps)
        if not ok:
            return None
        d_last = self._d_ref + rel_last
        self._unwrap.last = d_last
        self._observe(rel_last, h - self._h_ref)
        self._last_d, self._last_h = d_last, h
        self._last_stamp = int(stamps[-1])
        self._samples += stamps.shape[0]
        self._steer(rel_last, self._last_stamp)
        return stamps

    def flush(self) -> NDArray[np.int64]:
        """
        Stamp the samples held while the epoch settles with the estimate so far.

        Returns
        -------
        numpy.ndarray
            int64 stamps of the held samples, oldest first (empty when none are held).

        """
        if not self._held:
            return np.zeros(0, dtype=np.int64)
        rel = np.concatenate(self._held)
        self._held = []
        assert self._h_ref is not None and self._last_h is not None  # set with the held batches
        return self._stamp(rel, self._last_h - self.latency_ns)

    def _line(self, rel: NDArray[np.int64]) -> NDArray[np.int64]:
        """Return the estimate's host times (ns) of device times relative to ``_d_ref`` (us)."""
        assert self._a is not None and self._h_ref is not None  # _observe fitted the line
        # exact integer part plus a small float correction: float64 cannot hold ns since 1970
        # exactly
        correction = np.rint(self._a + self._s * (rel.astype(np.float64)
                                                  - self._d0)).astype(np.int64)
        return self._h_ref + 1000 * rel + correction - self.latency_ns

    def _stamp(self, rel: NDArray[np.int64], limit_ns: int) -> NDArray[np.int64]:
        """Stamp device times on the stamps' own line (continuous), causal, strictly increasing."""
        if self._pub is None:
            stamps = self._line(rel)  # the epoch has settled: start on the estimate
        else:
            rel0, stamp0 = self._pub
            stamps = stamp0 + np.rint((rel - rel0) * self._pub_rate).astype(np.int64)
        excess = int(stamps[-1]) - limit_ns
        if excess > 0:
            # The newest sample cannot have been received before it existed: the line is late.
            # Compress the batch onto the receive time (a shorter period within one batch, never
            # a step), or shift a first batch.
            self._compressed += 1
            if self._pub is None or limit_ns <= self._pub[1] or rel[-1] <= self._pub[0]:
                stamps -= excess
            else:
                rel0, stamp0 = self._pub
                rate = (limit_ns - stamp0) / float(rel[-1] - rel0)
                stamps = stamp0 + np.rint((rel - rel0) * rate).astype(np.int64)
        n = stamps.size
        idx = np.arange(n, dtype=np.int64)
        floor = -np.iinfo(np.int64).max if self._last_stamp is None else self._last_stamp + 1
        stamps = np.maximum.accumulate(np.maximum(stamps - idx, floor)) + idx
        self._last_stamp = int(stamps[-1])
        self._samples += n
        self._steer(int(rel[-1]), self._last_stamp)
        return stamps

    def _steer(self, rel_last: int, stamp_last: int) -> None:
        """Set the stamps' rate for the next batch: the estimate's, slewing the offset away."""
        assert self._a is not None and self._h_ref is not None  # _observe fitted the line
        line = (self._h_ref + 1000 * rel_last + round(self._a + self._s * (rel_last - self._d0))
                - self.latency_ns)
        error = float(stamp_last - line)
        self._offset_error = error
        if abs(error) > MAX_SLEW_OFFSET_S * 1e9:
            # Too far to slew (a host clock set by hand): step onto the estimate, and count it.
            self._steps += 1
            stamp_last -= int(error)
            error = 0.0
        limit = MAX_SLEW_PPM * 1e-6
        correction = min(max(error / (SLEW_TIME_S * 1e9), -limit), limit)
        self._pub = (rel_last, stamp_last)
        self._pub_rate = (1000.0 + self._s) * (1.0 - correction)

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
        keep = np.ones(dx.size, dtype=bool)
        for _ in range(3):
            d0 = float(dx[keep].mean())
            x = dx[keep] - d0
            sxx = float(x @ x)
            slope = float(x @ (y[keep] - y[keep].mean())) / sxx if sxx > 0 else 0.0
            a = float(y[keep].mean())
            # A block whose fastest batch still lies far above the line was read late as a whole
            # (the host stalled for longer than a block): it says nothing about the clocks.
            late = y - (a + slope * (dx - d0)) > _LATE_BLOCK_NS
            if not (late & keep).any() or np.count_nonzero(keep & ~late) < 2:
                break
            keep &= ~late
        if abs(slope / 1000.0) > self._max_drift:
            # not a clock: slope 0 (b = 1) through the lowest block, as before two blocks close
            slope, d0, a = 0.0, 0.0, float(y.min())
        self._s = slope
        self._d0 = d0
        self._a = a
