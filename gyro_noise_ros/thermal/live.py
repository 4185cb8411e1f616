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
Live evaluation of a causal thermal drift model: what the ``imu_compensator`` node subtracts.

A causal thermal model (``model.json`` of ``gyro_noise_thermal fit``, or any
:class:`~gyro_noise_ros.thermal.run.ThermalMethod` with ``causal = True``) gives the gyro offset
``drift_rad_s(T, dT)`` (rad/s) of the die temperature T (degC) and its rate dT (degC/s);
:class:`LiveDriftEvaluator` evaluates it per temperature message, interpolated onto gyro stamps:

- dT is :func:`~gyro_noise_ros.thermal.run.temperature_rate_c_s` on a trailing buffer of the last
  ``rate_window_s`` of temperatures, as offline; the messages of the first window wait and get
  the rate of the first message whose window is filled (the offline backfill; :attr:`start_up_s`,
  none for a model with ``uses_rate = False`` such as ``poly3``).
- Each temperature message is a knot (stamp, offset); gyro stamps between two knots get the
  linear interpolation, those after the newest knot its offset, those before the first the first.
- Range: the model is trusted over its training range widened by ``range_margin_c`` (its own or
  :data:`DEFAULT_RANGE_MARGIN_C`). Within the margin a knot is evaluated and flagged
  :data:`RANGE_MARGIN`; beyond it, never extrapolated, flagged :data:`RANGE_OUTSIDE`, holding the
  last offset evaluated inside (``beyond='hold'``) or none (``beyond='none'``). Rates outside the
  trained ``rate_range_c_s`` are counted (:attr:`knots_rate_outside`) and left to the model.

Implausible temperatures (``core.plausible``) are rejected like non-finite ones; a hysteresis
term (``lsq_cv``) gets its state carried over. Non-causal methods (VMD, TFPF, EMD, wavelet
thresholding of the whole record) are refused, naming those offline-only steps. No ROS here;
the node and its diagnostics: docs/compensation.md.
"""

from collections.abc import Sequence
from dataclasses import dataclass, field
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .run import DEFAULT_RATE_WINDOW_S, temperature_rate_c_s, temperature_rate_newest_c_s
from ..core.plausible import LiveTemperatureScreen
from ..errors import ParameterError
from ..outputs import StrPath

#: Methods that need the whole record, with the offline-only steps they rely on.
NON_CAUSAL_METHODS = {
    'parallel': 'VMD decomposition (MOPSO-chosen K, alpha) and TFPF filtering of the mixed modes',
    'wtd': 'wavelet-threshold denoising of the whole record',
    'emd_wtd_sabp': 'EMD decomposition and wavelet-threshold denoising of the modes',
}

#: Margin beyond the training temperature range when the model does not give its own (degC).
DEFAULT_RANGE_MARGIN_C = 5.0

#: Range status of a knot: inside the training range, within the margin, beyond the margin.
RANGE_OK, RANGE_MARGIN, RANGE_OUTSIDE = 0, 1, 2
RANGE_NAMES = {RANGE_OK: 'inside', RANGE_MARGIN: 'within margin', RANGE_OUTSIDE: 'outside'}

BEYOND_ACTIONS = ('hold', 'none')

#: How a gyro sample gets its offset: the newest at once, or interpolated once a temperature at
#: or after its stamp is known (:class:`TemperatureGate`).
TEMPERATURE_SYNCS = ('latest', 'interpolate')

_NS = 1_000_000_000


def _model_value(method: Any, key: str) -> Any:
    value = getattr(method, key, None)
    if value is None and hasattr(method, 'to_dict'):
        try:
            value = method.to_dict().get(key)
        except Exception:  # noqa: BLE001 - a model that cannot describe itself gives no value
            value = None
    return value


def check_live_model(method: Any, *, range_c: Sequence[float] | None = None,
                     margin_c: float | None = None) -> tuple[float, float, float]:
    """
    Check that a thermal model can run live and return its trusted temperature span.

    Parameters
    ----------
    method : ThermalMethod
        The model; needs ``name``, ``causal``, ``drift_rad_s`` and a training range.
    range_c : (float, float) or None, keyword-only
        Training temperature range (degC); None: the method's ``temperature_range_c`` attribute
        or ``to_dict()`` key.
    margin_c : float or None, keyword-only
        Margin (degC) beyond the range; None: the model's ``range_margin_c`` or
        :data:`DEFAULT_RANGE_MARGIN_C`.

    Returns
    -------
    (float, float, float)
        Training range low and high (degC) and the margin (degC).

    Raises
    ------
    ParameterError
        Non-causal model (naming its offline-only steps), no ``drift_rad_s``, or no valid range.

    """
    name = str(getattr(method, 'name', type(method).__name__))
    if name in NON_CAUSAL_METHODS or not getattr(method, 'causal', False):
        steps = NON_CAUSAL_METHODS.get(name, 'steps that use future samples')
        raise ParameterError(
            f"thermal model '{name}' is not causal: it needs {steps}, which run offline only "
            f'(gyro_noise_thermal apply on a recording); fit a causal method (e.g. poly3) '
            f'for live compensation')
    if not callable(getattr(method, 'drift_rad_s', None)):
        raise ParameterError(f"thermal model '{name}' has no drift_rad_s(T, dT): it cannot run "
                             'live')
    span = _model_value(method, 'temperature_range_c') if range_c is None else range_c
    try:
        lo, hi = (float(v) for v in span)
    except (TypeError, ValueError):
        raise ParameterError(f"thermal model '{name}' gives no training temperature range "
                             f'(temperature_range_c = {span!r}): it cannot be checked '
                             'live') from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise ParameterError(f"thermal model '{name}': bad temperature_range_c {span!r}")
    if margin_c is None:
        margin_c = _model_value(method, 'range_margin_c')
        margin_c = DEFAULT_RANGE_MARGIN_C if margin_c is None else margin_c
    margin_c = float(margin_c)
    # One evaluation at the middle of the range: the wrong shape or a NaN fails at start-up, not
    # in the middle of a stream.
    probe = np.asarray(method.drift_rad_s(np.array([(lo + hi) / 2]), np.zeros(1)))
    if probe.shape != (1, 3) or not np.isfinite(probe).all():
        raise ParameterError(f"thermal model '{name}': drift_rad_s(T, dT) must return finite "
                             f'(n, 3) offsets, got {probe.shape} {probe.tolist()}')
    if not (math.isfinite(margin_c) and margin_c >= 0):
        raise ParameterError(f"thermal model '{name}': range margin must be >= 0 degC, got "
                             f'{margin_c!r}')
    return lo, hi, margin_c


def load_live_model(path: StrPath) -> tuple[Any, tuple[float, float] | None, float | None]:
    """
    Load a ``model.json`` with the thermal registry (``thermal.methods.load_model``).

    The registry returns the fitted method with what it was trained on (``training``:
    ``temperature_min_c``, ``temperature_max_c``) and the package's range margin
    (``methods.DEFAULT_RANGE_MARGIN_C``); a bare method carrying its own range is accepted too.

    Parameters
    ----------
    path : str or os.PathLike
        ``model.json`` written by ``gyro_noise_thermal fit``.

    Returns
    -------
    method : ThermalMethod
    range_c : (float, float) or None
        Training temperature range (degC); None when the method carries its own.
    margin_c : float or None
        The registry's default margin (degC); None: :data:`DEFAULT_RANGE_MARGIN_C`.

    Raises
    ------
    GyroNoiseError
        The registry's errors (unreadable file, unknown method), or ParameterError when this
        build has no registry. Causality is checked by :func:`check_live_model`.

    """
    live = load_live(path)
    return live.method, live.range_c, live.margin_c


@dataclass(frozen=True)
class LiveModel:
    """
    What the live node needs from a model.json.

    Attributes
    ----------
    method : ThermalMethod
        The fitted gyro model.
    range_c : (float, float) or None
        Training temperature range (degC); None: the method's own.
    margin_c : float or None
        The registry's range margin (degC).
    rate_range_c_s : (float, float) or None
        Training temperature-rate range (degC/s), filled windows only; None: unknown.
    accel : object or None
        The accelerometer's relative polynomial (``drift_rad_s(T, dT)`` in m/s^2), if fitted.
    notes : tuple of str
        What loading noticed (e.g. another package version).

    """

    method: Any  # a ThermalMethod; the node also calls members outside that protocol
    range_c: tuple | None = None
    margin_c: float | None = None
    rate_range_c_s: tuple | None = None
    accel: Any = None  # a TemperaturePolynomial or None
    notes: tuple = field(default_factory=tuple)


def load_live(path: StrPath) -> LiveModel:
    """
    Load a ``model.json`` with everything the live node uses (:class:`LiveModel`).

    Parameters
    ----------
    path : str or os.PathLike
        ``model.json`` written by ``gyro_noise_thermal fit``.

    Returns
    -------
    LiveModel

    """
    try:
        from . import methods
    except ImportError as err:
        raise ParameterError(f'thermal model {path}: this build has no thermal model registry '
                             f'(gyro_noise_ros.thermal.methods: {err})') from err
    loaded = methods.load_model(path)
    training = getattr(loaded, 'training', None)
    method = getattr(loaded, 'method', loaded)
    range_c = None
    if training is not None:
        range_c = (training.temperature_min_c, training.temperature_max_c)
    margin = getattr(methods, 'DEFAULT_RANGE_MARGIN_C', None)
    rate = None
    if training is not None and getattr(training, 'temperature_rate_min_c_s', None) is not None:
        rate = (training.temperature_rate_min_c_s, training.temperature_rate_max_c_s)
    return LiveModel(method=method, range_c=range_c, margin_c=margin, rate_range_c_s=rate,
                     accel=getattr(loaded, 'accel', None),
                     notes=tuple(getattr(loaded, 'notes', ())))


class LiveDriftEvaluator:
    """
    Evaluate a causal thermal model on a live temperature stream, interpolate onto gyro stamps.

    Parameters
    ----------
    method : ThermalMethod
        Causal model (checked with :func:`check_live_model`).
    range_c : (float, float) or None, keyword-only
        Training temperature range (degC); None: the method's own.
    rate_window_s : float or None, keyword-only
        Trailing window of :func:`temperature_rate_c_s` (s); None: the model's own
        ``rate_window_s`` (the window it was fitted with), else
        :data:`~gyro_noise_ros.thermal.run.DEFAULT_RATE_WINDOW_S`.
    margin_c : float or None, keyword-only
        Range margin (degC); None: the model's.
    beyond : str, keyword-only
        What a knot beyond the margin carries: ``'hold'`` the last trusted offset, ``'none'`` zero.
    rate_range_c_s : (float, float) or None, keyword-only
        The model's trained rate range (degC/s): knots outside it are counted.

    """

    def __init__(self, method: Any, *, range_c: Sequence[float] | None = None,
                 rate_window_s: float | None = None, margin_c: float | None = None,
                 beyond: str = 'hold', rate_range_c_s: Sequence[float] | None = None) -> None:
        lo, hi, margin = check_live_model(method, range_c=range_c, margin_c=margin_c)
        self.range_lo_c, self.range_hi_c, self.margin_c = lo, hi, margin
        if beyond not in BEYOND_ACTIONS:
            raise ParameterError(f'beyond must be one of {BEYOND_ACTIONS}, got {beyond!r}')
        if rate_window_s is None:
            rate_window_s = _model_value(method, 'rate_window_s') or DEFAULT_RATE_WINDOW_S
        if not rate_window_s > 0:
            raise ParameterError(f'rate_window_s must be > 0, got {rate_window_s!r}')
        self.method = method
        self.name = str(getattr(method, 'name', type(method).__name__))
        self.rate_window_s = float(rate_window_s)
        self.beyond = beyond
        # a model that does not declare it is assumed to use dT (and to wait for its window)
        self.uses_rate = bool(getattr(method, 'uses_rate', True))
        self.rate_range_c_s: tuple[float, ...] | None = None if rate_range_c_s is None else tuple(
            float(v) for v in rate_range_c_s)
        self._pending_t = np.zeros(0)   # messages waiting for the first filled rate window
        self._pending_temp = np.zeros(0)
        self._t0_ns: int | None = None
        self._buf_t = np.zeros(0)  # trailing temperature history, s since _t0_ns
        self._buf_temp = np.zeros(0)
        self._knot_t = np.zeros(0)  # knots: s since _t0_ns, offsets (k, 3)
        self._knot_drift = np.zeros((0, 3))
        # last offset evaluated inside range + margin
        self._trusted: NDArray[np.float64] | None = None
        self.temperature_c = math.nan  # newest temperature, its rate and range status
        self.rate_c_s = math.nan
        self.status: int | None = None
        self.stamp_ns: int | None = None
        self.knots = 0
        self.knots_by_status = {RANGE_OK: 0, RANGE_MARGIN: 0, RANGE_OUTSIDE: 0}
        self.knots_rate_outside = 0  # knots whose rate is outside the trained rate range
        self.knots_outside = 0  # knots outside the trained range of T or of dT
        self.rejected = 0  # non-finite, implausible or not newer than the previous message
        self._screen = LiveTemperatureScreen()
        self._played: float | None = None  # hysteresis state (lsq_cv's play operator) carried on
        # the rate's numba kernels load (or compile) now, not at a live stream's first messages
        temperature_rate_c_s(np.zeros(2), np.zeros(2), window_s=1.0, start='partial')
        temperature_rate_newest_c_s(np.zeros(2), np.zeros(2), window_s=1.0)

    @property
    def start_up_s(self) -> float:
        """float: how long after the first temperature the first offset exists (s)."""
        return self.rate_window_s if self.uses_rate else 0.0

    @property
    def offset_stamp_ns(self) -> int | None:
        """Stamp of the newest knot (ns, int); None before the first offset exists."""
        # Knots are added in stamp order and, once the rate window has filled, every accepted
        # message becomes one at once: the newest knot is the newest message.
        if self._knot_t.size == 0 or self._pending_t.size:
            return None
        return self.stamp_ns

    @property
    def pending(self) -> int:
        """int: temperature messages waiting for the rate window to fill."""
        return int(self._pending_t.size)

    def range_status(self, temperature_c: ArrayLike) -> NDArray[np.int8]:
        """Return the range status (RANGE_*) of each temperature, as an int array."""
        return np.asarray(self._status(np.asarray(temperature_c, dtype=np.float64)), np.int8)

    def _status(self, temp: Any) -> Any:
        """Range status of an array of temperatures or of one float (the one rule of both)."""
        lo, hi, m = self.range_lo_c, self.range_hi_c, self.margin_c
        # margin >= 0 (check_live_model): inside the range is inside the margin too, so
        # OUTSIDE (2) minus one for each of the two spans a temperature lies in (NaN: none)
        return (RANGE_OUTSIDE - ((temp >= lo - m) & (temp <= hi + m))
                - ((temp >= lo) & (temp <= hi)))

    def add_temperature(self, stamp_ns: ArrayLike, temperature_c: ArrayLike) -> int:
        """
        Add temperature messages: each one newer than the last becomes a knot.

        Parameters
        ----------
        stamp_ns : array_like of int
            (k,) header stamps, ns.
        temperature_c : array_like of float
            (k,) temperatures, degC.

        Returns
        -------
        int
            Knots added (non-finite or stale messages are counted in ``rejected``).

        """
        added = self._add_one(stamp_ns, temperature_c)
        if added is not None:
            return added
        stamps = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
        temp = np.asarray(temperature_c, dtype=np.float64).reshape(-1)
        if stamps.size > 1:
            order = np.argsort(stamps, kind='stable')
            stamps, temp = stamps[order], temp[order]
        keep = np.isfinite(temp)
        if self.stamp_ns is not None:
            keep &= stamps > self.stamp_ns
        if keep.size > 1:
            keep[1:] &= stamps[1:] > stamps[:-1]
        # core.plausible: out of range, saturated words, jumps a die cannot make
        keep[keep] = self._screen.accept(stamps[keep] / _NS, temp[keep])
        self.rejected += int(keep.size - np.count_nonzero(keep))
        stamps, temp = stamps[keep], temp[keep]
        k = stamps.size
        if k == 0:
            return 0
        if self._t0_ns is None:
            self._t0_ns = int(stamps[0])
        t = (stamps - self._t0_ns) / _NS
        self._buf_t = np.concatenate((self._buf_t, t))
        self._buf_temp = np.concatenate((self._buf_temp, temp))
        # the buffer holds the whole trailing window, so its partial-window slope is the full
        # window's once the window is filled (rate_window_filled counts from the first message)
        rate = temperature_rate_c_s(self._buf_t, self._buf_temp, window_s=self.rate_window_s,
                                    start='partial')[-k:]
        self._buf_t, self._buf_temp = self._trailing(self._buf_t, self._buf_temp, t[-1])
        self.temperature_c, self.stamp_ns = float(temp[-1]), int(stamps[-1])
        self.status = int(self.range_status(temp[-1:])[0])
        self.knots += k
        if self.uses_rate and (self._pending_t.size or t[0] < self.rate_window_s * (1.0 - 1e-9)):
            # the rate window is still filling (or has just filled): hold, or backfill the held
            filled = t >= self.rate_window_s * (1.0 - 1e-9)
            t = np.concatenate((self._pending_t, t))
            temp = np.concatenate((self._pending_temp, temp))
            rate = np.concatenate((np.full(self._pending_t.size, np.nan), rate))
            filled = np.concatenate((np.zeros(self._pending_t.size, dtype=bool), filled))
            if not filled.any():
                self._pending_t, self._pending_temp = t, temp
                return k
            first = int(np.argmax(filled))
            rate[:first] = rate[first]   # the offline backfill (run.temperature_rate_c_s)
            self._pending_t, self._pending_temp = np.zeros(0), np.zeros(0)
        self._add_knots(t, temp, rate)
        return k

    def _add_one(self, stamp_ns: ArrayLike, temperature_c: ArrayLike) -> int | None:
        """
        :meth:`add_temperature` for the usual live call, in scalar Python; None: not that call.

        The usual call is one message (int64 stamp, float64 temperature) newer than the last,
        finite, with the rate window already filled; it leaves the state the general path
        leaves, bit for bit. Any other call returns None before changing anything.
        """
        stamps, temps = np.asarray(stamp_ns), np.asarray(temperature_c)
        if (self.stamp_ns is None or self._pending_t.size or stamps.size != 1
                or temps.size != 1 or stamps.dtype != np.int64 or temps.dtype != np.float64):
            return None
        stamp, temp = int(stamps.item()), float(temps.item())
        if not (stamp > self.stamp_ns and math.isfinite(temp)):
            return None
        assert self._t0_ns is not None  # set with stamp_ns
        # float(int) rounds as numpy's int64 -> float64 does, and the division is the same; no
        # message pending: the rate window filled at an older message (or is not waited for)
        t = float(stamp - self._t0_ns) / _NS
        if not self._screen.accept_one(float(stamp) / _NS, temp):
            self.rejected += 1
            return 0
        buf_t = np.concatenate((self._buf_t, (t,)))
        buf_temp = np.concatenate((self._buf_temp, (temp,)))
        rate = temperature_rate_newest_c_s(buf_t, buf_temp, window_s=self.rate_window_s)
        self._buf_t, self._buf_temp = self._trailing(buf_t, buf_temp, t)
        self.temperature_c, self.stamp_ns = temp, stamp
        self.status = status = int(self._status(temp))
        self.knots += 1
        drift = self._evaluate(np.array([temp]), np.array([rate]))
        if status == RANGE_OUTSIDE:  # never extrapolated: the last trusted offset, or none
            fill = np.zeros(3) if self._trusted is None or self.beyond == 'none' else self._trusted
            drift = fill.reshape(1, 3).copy()
        else:
            self._trusted = drift[0].copy()
        self._knot_t = np.concatenate((self._knot_t, (t,)))
        self._knot_drift = np.concatenate((self._knot_drift, drift))
        self.rate_c_s = rate
        self.knots_by_status[status] += 1
        rate_out = False
        if self.uses_rate and self.rate_range_c_s is not None:
            lo, hi = self.rate_range_c_s
            rate_out = rate < lo or rate > hi
            self.knots_rate_outside += int(rate_out)
        self.knots_outside += int(rate_out or status != RANGE_OK)
        return 1

    def _evaluate(self, temp: NDArray[np.float64],
                  rate: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the model's offsets (k, 3) at the knots' T and dT (hysteresis state carried)."""
        if getattr(self.method, 'hysteresis_c', 0.0):
            played = self.method.play(temp, start=self._played)
            self._played = float(played[-1])
            drift = self.method.drift_rad_s(temp, rate, played_c=played)
        else:
            drift = self.method.drift_rad_s(temp, rate)
        return np.asarray(drift, dtype=np.float64).reshape(temp.size, 3)

    def _add_knots(self, t: NDArray[np.float64], temp: NDArray[np.float64],
                   rate: NDArray[np.float64]) -> None:
        k = t.size
        status = self.range_status(temp)
        drift = self._evaluate(temp, rate)
        outside = status == RANGE_OUTSIDE
        if outside.any():
            # Never extrapolate: a knot beyond the margin holds the last trusted offset (forward
            # fill over the batch, seeded by earlier batches) or carries none.
            fill = np.zeros(3) if self._trusted is None or self.beyond == 'none' else self._trusted
            if self.beyond == 'hold':
                idx = np.where(~outside, np.arange(k), -1)
                np.maximum.accumulate(idx, out=idx)
                drift = np.where((idx >= 0)[:, None], drift[np.maximum(idx, 0)], fill)
            else:
                drift[outside] = fill
        if not outside.all():
            self._trusted = drift[np.flatnonzero(~outside)[-1]].copy()
        self._knot_t = np.concatenate((self._knot_t, t))
        self._knot_drift = np.concatenate((self._knot_drift, drift))
        self.rate_c_s = float(rate[-1])
        for code in self.knots_by_status:
            self.knots_by_status[code] += int(np.count_nonzero(status == code))
        rate_out = np.zeros(k, dtype=bool)
        if self.uses_rate and self.rate_range_c_s is not None:
            lo, hi = self.rate_range_c_s
            rate_out = (rate < lo) | (rate > hi)
            self.knots_rate_outside += int(np.count_nonzero(rate_out))
        self.knots_outside += int(np.count_nonzero(rate_out | (status != RANGE_OK)))

    def _trailing(self, t: NDArray[np.float64], values: NDArray[np.float64],
                  t_last: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        first = np.searchsorted(t, t_last - self.rate_window_s, side='left')
        return t[first:], values[first:]

    def drift_at(self, stamp_ns: ArrayLike) -> NDArray[np.float64] | None:
        """
        Offset to subtract at each gyro stamp, linear in time between temperature knots.

        Parameters
        ----------
        stamp_ns : array_like of int
            (n,) gyro stamps, ns (non-decreasing within a batch).

        Returns
        -------
        numpy.ndarray or None
            (n, 3) offsets in rad/s; None before the first temperature message.

        """
        if self._knot_t.size == 0:
            return None
        assert self._t0_ns is not None  # set with the first knot
        stamps = np.asarray(stamp_ns, dtype=np.int64)
        # (min - t0) / 1e9 is the min of x below (the map is non-decreasing, the rounding the same)
        if stamps.size and (int(stamps.min()) - self._t0_ns) / _NS >= self._knot_t[-1]:
            # Every stamp at or after the newest knot (live, the usual batch): its offset, held,
            # as np.interp gives it; the older knots are no longer needed.
            if self._knot_t.size > 1:
                self._knot_t, self._knot_drift = self._knot_t[-1:], self._knot_drift[-1:]
            return np.repeat(self._knot_drift, stamps.size, axis=0)
        x = (stamps - self._t0_ns) / _NS
        out = np.empty((x.size, 3))
        for axis in range(3):
            out[:, axis] = np.interp(x, self._knot_t, self._knot_drift[:, axis])
        if x.size:
            # Knots before the one at or before the oldest stamp asked for are no longer needed
            # (gyro stamps only advance); keep that one so the interval stays interpolated.
            first = max(int(np.searchsorted(self._knot_t, x.min(), side='right')) - 1, 0)
            if first:
                self._knot_t = self._knot_t[first:]
                self._knot_drift = self._knot_drift[first:]
        return out


class TemperatureGate:
    """
    Hold gyro samples until a temperature at or after their stamp is known, for a bounded time.

    The offset of a sample between two temperature knots is interpolated; one newer than the
    newest knot could only get the newest offset, held. Over a reliable subscription a lost
    temperature message stalls every newer one until it is resent (in-order delivery), and the
    held offset of a ramp is then wrong by the drift rate times the stall. So samples newer than
    the newest temperature wait for the next one, in arrival order; a sample that has waited
    ``max_wait_s`` is released with the newest offset anyway and counted in :attr:`late`.
    Before the first temperature there is no offset at all: samples that waited ``first_wait_s``
    are dropped and counted in :attr:`dropped`.

    With ``wait_for_newer=False`` (the node's default, ``temperature_sync: latest``) only the
    wait for the first temperature remains: once an offset exists every sample is released at
    once and gets the newest one (temperature moves over seconds; docs/compensation.md measures
    what that costs), and :attr:`late` stays 0.

    Batches are opaque to the gate (the node keeps the message bytes in them); it returns index
    ranges of each batch to publish.

    Parameters
    ----------
    max_wait_s : float
        Longest wait for a newer temperature once one is known (s); 0: never wait.
    first_wait_s : float
        Longest wait for the first temperature (s).
    wait_for_newer : bool, keyword-only
        Hold samples newer than the newest temperature (False: only until the first one).

    """

    def __init__(self, max_wait_s: float, first_wait_s: float, *,
                 wait_for_newer: bool = True) -> None:
        if not (max_wait_s >= 0 and first_wait_s >= 0):
            raise ParameterError(f'waits must be >= 0 s, got {max_wait_s!r}, {first_wait_s!r}')
        self.max_wait_s, self.first_wait_s = float(max_wait_s), float(first_wait_s)
        self.wait_for_newer = bool(wait_for_newer)
        # [batch, stamp_ns (int64 array), next index, arrival time (s)]
        self._queue: list[list[Any]] = []
        self._held = 0     # samples in _queue not yet released (kept with it: read per batch)
        self.late = 0      # samples released after max_wait_s with the newest offset
        self.dropped = 0   # samples dropped waiting for the first temperature
        self.longest_wait_s = 0.0  # of a sample released on time (interpolated)

    @property
    def waiting(self) -> int:
        """int: Samples held now."""
        return self._held

    def push(self, batch: Any, stamp_ns: ArrayLike, now_s: float) -> None:
        """
        Queue a batch of samples.

        Parameters
        ----------
        batch : object
            Returned with each released range.
        stamp_ns : array_like of int
            (n,) gyro stamps of the batch, ns.
        now_s : float
            Monotonic arrival time (s).

        """
        stamps = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
        if stamps.size:
            self._queue.append([batch, stamps, 0, float(now_s)])
            self._held += stamps.size

    def release(self, newest_temperature_ns: int | None,
                now_s: float) -> list[tuple[Any, int, int, bool]]:
        """
        Return what may be published now, in arrival order.

        Parameters
        ----------
        newest_temperature_ns : int or None
            Stamp of the newest temperature knot (ns); None before the first one.
        now_s : float
            Monotonic time (s).

        Returns
        -------
        list of (batch, int, int, bool)
            ``(batch, start, stop, late)``: publish samples ``start:stop`` of ``batch``; ``late``
            when they waited ``max_wait_s`` for a newer temperature and get the newest offset.

        """
        out = []
        while self._queue:
            entry = self._queue[0]
            batch, stamps, start, arrived = entry
            waited = now_s - arrived
            if newest_temperature_ns is None:
                if waited <= self.first_wait_s:
                    break
                self.dropped += len(stamps) - start
                self._held -= len(stamps) - start
                self._queue.pop(0)
                continue
            if self.wait_for_newer:
                beyond = np.flatnonzero(stamps[start:] > newest_temperature_ns)
                stop = len(stamps) if beyond.size == 0 else start + int(beyond[0])
            else:
                stop = len(stamps)
            if stop > start:
                out.append((batch, start, stop, False))
                self.longest_wait_s = max(self.longest_wait_s, waited)
                self._held -= stop - start
                entry[2] = start = stop
            if start == len(stamps):
                self._queue.pop(0)
                continue
            if waited < self.max_wait_s:
                break  # later batches are newer still: they wait behind this one
            out.append((batch, start, len(stamps), True))
            self.late += len(stamps) - start
            self._held -= len(stamps) - start
            self._queue.pop(0)
        return out
