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
Magnitudes no inertial sensor reports: corrupt records, not measurements.

A finite value such as 1e300 rad/s is not a noise sample but a broken record (a mis-decoded
field, a wrong unit, a sentinel): kept, its square overflows every moment and Allan sum to
``inf`` (numpy warnings, NaN results, a static-segment search that finds nothing). The limits sit
far above every sensor and far below overflow:

* angular rate: 1e6 rad/s (5.7e7 deg/s). The widest MEMS gyro ranges are about +-5e4 deg/s
  (873 rad/s), so the limit is over 1000 times any full scale; a sum of squares of 1e10 such
  samples is 1e22, far from the float64 limit of 1.8e308.
* specific force: 1e8 m/s^2 (about 1e7 g), 50 times the +-2e5 g of shock accelerometers.

The tools treat a sample beyond its limit as unusable, like NaN: ``gyro_noise_analyze`` counts it
and leaves its chunk out, ``gyro_noise_explain`` refuses the record (exit code 4) as it does NaN.

The die temperature has its own rule (:func:`screen_temperature`, :class:`TemperatureLimits`,
defaults the LSM6DSO32's): a reading outside the operating range (-40..85 degC), a saturated
register word (0x7FFF reads 153.0 degC), or an isolated jump faster than a die can move is not a
temperature. The thermal tools drop and count such readings (refusing a stream where more than
:data:`MAX_IMPLAUSIBLE_SHARE` are), recognise a stream in kelvin (:func:`looks_like_kelvin`), and
the live compensator applies the same rule causally (:class:`LiveTemperatureScreen`).
"""

from dataclasses import dataclass
import math
from typing import Any
import warnings

import numpy as np
from numpy.typing import ArrayLike

#: Largest angular rate magnitude (rad/s) taken as a measurement.
MAX_RATE_RAD_S = 1e6
#: Largest specific force magnitude (m/s^2) taken as a measurement.
MAX_SPECIFIC_FORCE_M_S2 = 1e8


def non_physical(values: ArrayLike, limit: float) -> np.ndarray:
    """
    Mark finite values whose magnitude exceeds ``limit``.

    Parameters
    ----------
    values : array_like
        Samples (NaN and Inf are not marked: they are counted as such elsewhere).
    limit : float
        Largest plausible magnitude, in the unit of ``values``.

    Returns
    -------
    numpy.ndarray of bool
        Same shape as ``values``.

    """
    v = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid='ignore'):
        return np.isfinite(v) & (np.abs(v) > limit)


def mask_non_physical(values: ArrayLike, limit: float) -> tuple[np.ndarray, int]:
    """
    Replace values beyond ``limit`` by NaN (so they count as unusable samples).

    Parameters
    ----------
    values : array_like
        Samples.
    limit : float
        Largest plausible magnitude, in the unit of ``values``.

    Returns
    -------
    tuple
        ``(values, count)``: the input itself when nothing is beyond the limit, else a copy with
        NaN in place of each value beyond it; ``count`` is how many were replaced.

    """
    v = np.asarray(values, dtype=np.float64)
    bad = non_physical(v, limit)
    count = int(np.count_nonzero(bad))
    if not count:
        return v, 0
    v = v.copy()
    v[bad] = np.nan
    return v, count


# ---------------------------------------------------------------------------------------------
# die temperature

#: LSM6DSO32 operating temperature range (degC, datasheet "Operating temperature range"): a
#: reading outside it is not this sensor working, it is a broken record or a wrong unit.
TEMPERATURE_MIN_C = -40.0
TEMPERATURE_MAX_C = 85.0
#: LSM6DSO32 OUT_TEMP: a signed 16-bit word, 256 LSB/degC, 0 LSB = 25 degC (the numbers
#: ``link/lsm6dso32.py`` converts with; ``test/test_plausible_temperature.py`` checks they agree).
TEMPERATURE_LSB_PER_C = 256.0
TEMPERATURE_OFFSET_C = 25.0
#: Fastest change a die can make (degC/s). A board's die follows its air with a time constant of
#: seconds at the very least; 5 degC/s is a 100-degC oven step with a 20-s constant, 75 times the
#: fastest rate of the simulator's soak (0.067 degC/s).
MAX_DIE_RATE_C_S = 5.0
#: Allowance for reading noise and resolution in the jump rule (degC): far above the LSM6DSO32's
#: 1/256 degC LSB and ~0.02 degC noise, and the 0.094-degC steps of an MPU6050.
TEMPERATURE_JUMP_C = 1.0
#: Kelvin: a stream whose readings lie within the operating range shifted by this, and whose
#: median is above the range, is in kelvin (:func:`looks_like_kelvin`).
KELVIN_OFFSET_C = 273.15
#: Neighbours on each side the jump rule compares a reading with: up to two glitches in a row
#: leave their neighbours' median on the good readings.
JUMP_NEIGHBOURS = 3
#: Largest share of a stream's readings that may be dropped as implausible (the rest are kept and
#: the dropped ones interpolated over); above it the stream is refused.
MAX_IMPLAUSIBLE_SHARE = 0.01


@dataclass(frozen=True)
class TemperatureLimits:
    """
    What a plausible die temperature reading is (defaults: the LSM6DSO32).

    Attributes
    ----------
    min_c, max_c : float
        Operating range (degC).
    max_rate_c_s : float
        Fastest plausible die change (degC/s).
    jump_c : float
        Noise allowance of the jump rule (degC).
    lsb_per_c, offset_c : float
        The register's scale and zero: the saturated words 0x7FFF and 0x8000 read
        ``offset_c + 32767 / lsb_per_c`` and ``offset_c - 32768 / lsb_per_c`` (153.0 and
        -103.0 degC for the LSM6DSO32).

    """

    min_c: float = TEMPERATURE_MIN_C
    max_c: float = TEMPERATURE_MAX_C
    max_rate_c_s: float = MAX_DIE_RATE_C_S
    jump_c: float = TEMPERATURE_JUMP_C
    lsb_per_c: float = TEMPERATURE_LSB_PER_C
    offset_c: float = TEMPERATURE_OFFSET_C

    def saturated_c(self) -> tuple[float, float]:
        """Return the readings of the saturated words 0x7FFF and 0x8000 (degC)."""
        return (self.offset_c + 32767.0 / self.lsb_per_c,
                self.offset_c - 32768.0 / self.lsb_per_c)


@dataclass(frozen=True)
class TemperatureScreen:
    """
    Which readings of a temperature stream are plausible (:func:`screen_temperature`).

    Attributes
    ----------
    keep : numpy.ndarray of bool
        (n,) True for a plausible reading.
    out_of_range : int
        Readings outside the operating range (saturated words excluded).
    saturated : int
        Readings equal to a saturated register word (within half an LSB).
    jumps : int
        In-range readings departing from their neighbours faster than the die can move.
    first_index : int or None
        Index of the first implausible reading.

    """

    keep: np.ndarray
    out_of_range: int
    saturated: int
    jumps: int
    first_index: int | None

    @property
    def dropped(self) -> int:
        """int: implausible readings."""
        return self.out_of_range + self.saturated + self.jumps

    def text(self, t_s: ArrayLike, temperature_c: ArrayLike) -> str:
        """
        Say in one clause how many readings are implausible and where the first one is.

        Parameters
        ----------
        t_s, temperature_c : array_like
            The stream's times (s) and readings (degC, after any kelvin conversion).

        Returns
        -------
        str

        """
        n = int(self.keep.size)
        if self.first_index is None:
            return f'all {n} temperature readings plausible'
        k = self.first_index
        return (f'{self.dropped} of {n} temperature readings ({100.0 * self.dropped / n:.3g} %) '
                f'implausible ({self.out_of_range} outside the operating range, '
                f'{self.saturated} saturated register words, {self.jumps} jumps faster than '
                f'the die can move); the first at {float(np.asarray(t_s)[k]):.3f} s '
                f'({float(np.asarray(temperature_c)[k]):.6g} degC)')


def looks_like_kelvin(temperature_c: ArrayLike,
                      limits: TemperatureLimits = TemperatureLimits()) -> bool:
    """
    Tell a stream in kelvin.

    Its median lies above the operating range, and all its finite readings but
    :data:`MAX_IMPLAUSIBLE_SHARE` (glitches, screened after the conversion) within the operating
    range + 273.15.

    Parameters
    ----------
    temperature_c : array_like
        Readings as given (n,).
    limits : TemperatureLimits, optional
        The sensor's limits.

    Returns
    -------
    bool

    """
    v = np.asarray(temperature_c, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return False
    lo, hi = limits.min_c + KELVIN_OFFSET_C, limits.max_c + KELVIN_OFFSET_C
    inside = float(np.mean((v >= lo) & (v <= hi)))
    return bool(inside >= 1.0 - MAX_IMPLAUSIBLE_SHARE and np.median(v) > limits.max_c)


def screen_temperature(t_s: ArrayLike, temperature_c: ArrayLike,
                       limits: TemperatureLimits = TemperatureLimits()) -> TemperatureScreen:
    """
    Mark the implausible readings of a die-temperature stream.

    A reading is implausible when it lies outside the operating range, equals a saturated
    register word (0x7FFF, 0x8000), or departs from the median of its :data:`JUMP_NEIGHBOURS`
    neighbours on each side by more than ``jump_c + max_rate_c_s * dt`` (dt the longest time to
    those neighbours): an isolated jump (up to two readings in a row) faster than the die can
    move. NaN/Inf are not marked (counted elsewhere).

    Parameters
    ----------
    t_s : array_like
        Reading times (n,), s, non-decreasing.
    temperature_c : array_like
        Readings (n,), degC.
    limits : TemperatureLimits, optional
        The sensor's limits.

    Returns
    -------
    TemperatureScreen

    """
    t = np.asarray(t_s, dtype=np.float64).reshape(-1)
    v = np.asarray(temperature_c, dtype=np.float64).reshape(-1)
    outside, saturated = _range_marks(v, limits)
    jumps = _jumps(t, np.where(outside | saturated, np.nan, v), limits) & ~(outside | saturated)
    bad = outside | saturated | jumps
    first = int(np.argmax(bad)) if bad.any() else None
    return TemperatureScreen(keep=~bad, out_of_range=int(outside.sum()),
                             saturated=int(saturated.sum()), jumps=int(jumps.sum()),
                             first_index=first)


def _range_marks(v: Any, limits: TemperatureLimits) -> tuple[Any, Any]:
    """
    Return (outside the operating range, a saturated register word) of finite readings.

    ``v`` is an array (boolean arrays back) or one float (booleans back): the one rule of both.
    """
    half = 0.5 / limits.lsb_per_c
    high, low = limits.saturated_c()
    saturated = (abs(v - high) <= half) | (abs(v - low) <= half)
    outside = (np.logical_not(saturated) & np.isfinite(v)
               & ((v < limits.min_c) | (v > limits.max_c)))
    return outside, saturated


def _jumps(t: np.ndarray, v: np.ndarray, limits: TemperatureLimits) -> np.ndarray:
    """Mark readings departing from the median of up to three finite neighbours on each side."""
    n, m = v.size, JUMP_NEIGHBOURS
    if n < 3:
        return np.zeros(n, dtype=bool)
    pad_v = np.concatenate([np.full(m, np.nan), v, np.full(m, np.nan)])
    pad_t = np.concatenate([np.full(m, np.nan), t, np.full(m, np.nan)])
    offsets = [o for o in range(-m, m + 1) if o]
    near = np.stack([pad_v[m + o:m + o + n] for o in offsets])
    dt = np.stack([np.abs(pad_t[m + o:m + o + n] - t) for o in offsets])
    dt = np.where(np.isfinite(near), dt, np.nan)
    with np.errstate(invalid='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)  # all-NaN neighbourhoods
        ref = np.nanmedian(near, axis=0)
        span = np.nanmax(dt, axis=0)
        allowed = limits.jump_c + limits.max_rate_c_s * span
        return np.isfinite(v) & np.isfinite(ref) & (np.abs(v - ref) > allowed)


def _median_of_few(values: list[float]) -> float:
    """Return ``np.median`` of up to three floats, bit for bit, without numpy's per-call cost."""
    ordered = sorted(values)
    mid = len(ordered) // 2
    return ordered[mid] if len(ordered) % 2 else (ordered[mid - 1] + ordered[mid]) / 2


class LiveTemperatureScreen:
    """
    The same rule on a live stream, causally: each reading against the ones accepted before it.

    Out of range and saturated words as :func:`screen_temperature`; a jump is a departure from
    the median of the last three accepted readings by more than ``jump_c + max_rate_c_s * dt``
    (dt to the newest of them). A level that persists for ``reset_after`` rejected readings is
    accepted from then on (a die cannot jump, but a stream restarted after a gap can).

    Parameters
    ----------
    limits : TemperatureLimits, optional
        The sensor's limits.
    reset_after : int, keyword-only
        Consecutive jump rejections after which the new level is accepted.

    """

    def __init__(self, limits: TemperatureLimits = TemperatureLimits(), *,
                 reset_after: int = 25) -> None:
        self.limits = limits
        self.reset_after = int(reset_after)
        self._recent: list[tuple[float, float]] = []
        self._rejected_run = 0
        self.rejected = 0

    def accept(self, t_s: ArrayLike, temperature_c: ArrayLike) -> np.ndarray:
        """
        Screen readings in time order; return which are plausible.

        Parameters
        ----------
        t_s : array_like
            Times (k,), s, increasing.
        temperature_c : array_like
            Readings (k,), degC.

        Returns
        -------
        numpy.ndarray of bool
            (k,).

        """
        t = np.asarray(t_s, dtype=np.float64).reshape(-1)
        v = np.asarray(temperature_c, dtype=np.float64).reshape(-1)
        outside, saturated = _range_marks(v, self.limits)
        keep = np.isfinite(v) & ~outside & ~saturated
        for k in np.flatnonzero(keep):
            keep[k] = self._level(float(t[k]), float(v[k]))
        self.rejected += int(np.count_nonzero(~keep))
        return keep

    def accept_one(self, t_s: float, temperature_c: float) -> bool:
        """
        Screen one reading newer than the last: :meth:`accept` of one, without numpy's cost.

        Parameters
        ----------
        t_s : float
            Time, s.
        temperature_c : float
            Reading, degC.

        Returns
        -------
        bool
            Plausible; the state (and :attr:`rejected`) as :meth:`accept` leaves it.

        """
        outside, saturated = _range_marks(temperature_c, self.limits)
        keep = (math.isfinite(temperature_c) and not (outside or saturated)
                and self._level(t_s, temperature_c))
        if not keep:
            self.rejected += 1
        return keep

    def _level(self, t_s: float, temperature_c: float) -> bool:
        """Judge one finite in-range reading against the accepted level; update the state."""
        if self._rejected_run >= self.reset_after:
            self._recent = []   # the new level persisted: anchor on it
        if self._recent:
            ref = _median_of_few([x for _, x in self._recent])
            allowed = self.limits.jump_c + self.limits.max_rate_c_s * (t_s - self._recent[-1][0])
            if abs(temperature_c - ref) > allowed:
                self._rejected_run += 1
                return False
        self._rejected_run = 0
        self._recent = (self._recent + [(t_s, temperature_c)])[-3:]
        return True
