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
Seeded thermal test data: oven profiles of several shapes, a lagging die, the drift it drives.

**Profiles.** The oven air temperature ``u(t)`` (degC) is piecewise linear in natural time.
:class:`OvenProfile` is the experiment of paper 002 (section 4.1): an hour at room temperature,
a fast heat to 60 degC, an hour there, then down in 10 degC steps to -40 degC, an hour at each.
:class:`ShapeProfile` gives held-out runs shaped unlike a training run (:data:`SHAPES`:
``heating``, ``cooling``, ``staircase``, ``staircase_down``, ``cycle``, ``cool_reheat``, ``soak``,
``sine``); :func:`make_profile` builds one by name.

**Die.** One first-order lag ``tau dT/dt = u(t) + dT_self - T``, solved exactly between samples
for piecewise-linear ``u`` (first-order hold), so the die rate is exact too.

**Gyro drift** of axis i (deg/s), ``d = T - T_ref``::

    b_i = b0 + c1 d + c2 d^2 + c3 d^3 + k tanh((T - T_k) / w_k) + g dT/dt_nat + h (z - T)

a cubic, a smooth knee, a thermal-gradient term in the die rate and a hysteresis (``z``: the play
operator of half-width r on T, a loop of height 2 h r); the seven terms are
:meth:`ThermalModel.bias_terms`, the oracle's basis (:mod:`.oracle`). Accelerometer drift (mg): a
cubic in d. The temperature sensor reads ``T + N(0, s^2)`` rounded to 1/256 degC; the gyro adds
white noise and :class:`~gyro_noise_ros.core.simulate.GaussMarkov` bias instability. Time
compression ``X`` runs the thermal experiment X times faster (noise not compressed). Every
constant: :class:`ThermalModel` and docs/thermal_data.md.
"""

from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
import json
import math
from pathlib import Path
from typing import Any

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .run import ThermalRun
from ..core.jit import JIT_OPTIONS
from ..core.simulate import gauss_markov_avar, GaussMarkov
from ..errors import ParameterError
from ..outputs import StrPath
from ..units import DEG_TO_RAD, MG_TO_M_S2, STANDARD_GRAVITY_M_S2

#: LSM6DSO32 temperature output sensitivity, 256 LSB/degC (datasheet), i.e. one LSB in degC.
TEMPERATURE_LSB_C = 1.0 / 256.0
#: Output rate of the LSM6DSO32 temperature sensor (datasheet: 52 Hz); the driver publishes
#: ``imu/temperature`` at about this rate.
TEMPERATURE_RATE_HZ = 52.0
#: Header stamp of the first sample written to a bag (2023-11-14, any fixed value would do).
DEFAULT_START_NS = 1_700_000_000 * 1_000_000_000
#: Every profile name :func:`make_profile` knows: the paper's oven, then the shapes.
SHAPES = ('oven', 'heating', 'cooling', 'staircase', 'staircase_down', 'cycle', 'cool_reheat',
          'soak', 'sine')
#: Breakpoints per period of the ``sine`` shape (the oven between them is linear; the die's lag
#: smooths the corners: at 64 per period the set-point departs from a sine by < 0.12 % of its
#: amplitude, 1 - cos(pi / 64)).
SINE_POINTS_PER_PERIOD = 64
#: The ``soak`` shape jumps the oven this many times faster than ``rate_c_s``.
SOAK_SPEED_UP = 20.0


# The corners (times_s, temperatures_c) of a piecewise-linear oven profile.
_Corners = tuple[NDArray[np.floating[Any]], NDArray[np.floating[Any]]]


class _PiecewiseProfile:
    """What every oven profile offers on top of its ``breakpoints()``."""

    def breakpoints(self) -> _Corners:
        """Return the corners ``(times_s, temperatures_c)``; every profile class defines them."""
        raise NotImplementedError

    @property
    def duration_s(self) -> float:
        """float: length of the whole profile (s); 50250 s (13.96 h) for the paper's oven."""
        return float(self.breakpoints()[0][-1])

    def temperature_c(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """
        Oven temperature (degC) at times ``t_s`` (s); held at the ends outside the profile.

        Parameters
        ----------
        t_s : array_like
            Times (s) in uncompressed profile time.

        Returns
        -------
        numpy.ndarray
            Same shape as ``t_s``.

        """
        times, temps = self.breakpoints()
        return np.interp(np.asarray(t_s, dtype=float), times, temps)


@dataclass(frozen=True)
class OvenProfile(_PiecewiseProfile):
    """
    The oven set-point of paper 002 section 4.1, piecewise linear in time.

    Room hold, heat to ``peak_c``, hold, then steps of ``step_c`` down to ``low_c``, each held
    ``hold_s``; the last hold ends the profile. The paper says "quickly heated" and gives no
    ramp rates: 2 degC/min heating and 1 degC/min cooling are typical of a lab chamber.

    Attributes
    ----------
    room_c : float
        Room temperature at the start (degC).
    peak_c : float
        Highest set-point (degC).
    low_c : float
        Last set-point (degC).
    step_c : float
        Downward step (degC, > 0).
    hold_s : float
        Duration of every hold, the room hold included (s).
    heat_rate_c_s : float
        Ramp rate from room to peak (degC/s, > 0).
    cool_rate_c_s : float
        Ramp rate of every downward step (degC/s, > 0).

    """

    room_c: float = 25.0
    peak_c: float = 60.0
    low_c: float = -40.0
    step_c: float = 10.0
    hold_s: float = 3600.0
    heat_rate_c_s: float = 2.0 / 60.0
    cool_rate_c_s: float = 1.0 / 60.0

    @property
    def shape(self) -> str:
        """str: ``'oven'``."""
        return 'oven'

    def breakpoints(self) -> _Corners:
        """
        Return the corners of the profile.

        Returns
        -------
        times_s : numpy.ndarray
            Increasing times (s) from 0.
        temperatures_c : numpy.ndarray
            Oven temperature at those times (degC).

        """
        if not (self.step_c > 0 and self.hold_s > 0 and self.heat_rate_c_s > 0
                and self.cool_rate_c_s > 0 and self.low_c < self.peak_c):
            raise ParameterError(f'oven profile needs step, hold and rates > 0 and low < peak, '
                                 f'got {self}')
        times = [0.0, self.hold_s]
        temps = [self.room_c, self.room_c]
        levels = [self.peak_c]
        level = self.peak_c
        while level - self.step_c > self.low_c + 1e-9:
            level -= self.step_c
            levels.append(level)
        levels.append(self.low_c)
        for i, level in enumerate(levels):
            rate = self.heat_rate_c_s if i == 0 else self.cool_rate_c_s
            times.append(times[-1] + abs(level - temps[-1]) / rate)
            temps.append(level)
            times.append(times[-1] + self.hold_s)
            temps.append(level)
        return np.asarray(times), np.asarray(temps)

    def shifted(self, delta_c: float) -> 'OvenProfile':
        """Return the profile of a run whose room is ``delta_c`` (degC) warmer; set-points stay."""
        return replace(self, room_c=self.room_c + float(delta_c))

    def starting_at(self, start_c: float) -> 'OvenProfile':
        """Return the profile with the room (its first temperature) at ``start_c`` (degC)."""
        return replace(self, room_c=float(start_c))


@dataclass(frozen=True)
class ShapeProfile(_PiecewiseProfile):
    """
    An oven set-point of one of the shapes a held-out test needs, piecewise linear in time.

    All in natural (uncompressed) time, between ``low_c`` and ``high_c`` (``span`` apart), ramps
    at ``rate_c_s``, holds of ``hold_s``; ``offset_c`` shifts every set-point (the run-to-run
    room spread). Breakpoints per shape (``h`` = ``hold_s``, ``r`` = ``span / rate_c_s``):

    ============== ===========================================================================
    shape          set-point
    ============== ===========================================================================
    heating        low for h, ramp to high (r), high for h
    cooling        high for h, ramp to low (r), low for h
    staircase      low for h, then ``steps`` equal steps up, each ramped (r / steps), held h
    staircase_down the same from high, down
    cycle          low for h, then ``cycles`` x (ramp up, high for h, ramp down, low for h)
    cool_reheat    high for h, then ``cycles`` x (ramp down, low for h, ramp up, high for h)
    soak           low for 60 s, a jump to high ``SOAK_SPEED_UP`` x faster than r, high for 3 h
    sine           mid + span/2 sin(2 pi t / ``period_s``), ``2 cycles`` periods from mid up
    ============== ===========================================================================

    Attributes
    ----------
    shape : str
        One of :data:`SHAPES` except ``'oven'`` (that is :class:`OvenProfile`).
    low_c, high_c : float
        Lowest and highest set-point (degC), low < high.
    rate_c_s : float
        Ramp rate (degC/s, > 0); 1 degC/min by default (a lab chamber).
    hold_s : float
        Every hold (s, > 0).
    steps : int
        Steps of the staircases (>= 1).
    cycles : int
        Repeats of ``cycle`` and ``cool_reheat``, periods of ``sine`` (>= 1; ``sine`` runs
        ``2 cycles``).
    period_s : float
        Period of ``sine`` (s, > 0; 5400 s: two periods last about as long as a cycle).
    offset_c : float
        Added to every set-point (degC).

    """

    shape: str = 'heating'
    low_c: float = 10.0
    high_c: float = 50.0
    rate_c_s: float = 1.0 / 60.0
    hold_s: float = 1800.0
    steps: int = 4
    cycles: int = 1
    period_s: float = 5400.0
    offset_c: float = 0.0

    def _check(self) -> None:
        if self.shape not in SHAPES or self.shape == 'oven':
            raise ParameterError(f'shape must be one of {", ".join(SHAPES[1:])}, got '
                                 f'{self.shape!r}')
        for name in ('low_c', 'high_c', 'rate_c_s', 'hold_s', 'period_s', 'offset_c'):
            if not math.isfinite(getattr(self, name)):
                raise ParameterError(f'{name} must be finite, got {getattr(self, name)!r}')
        if not (self.low_c < self.high_c and self.rate_c_s > 0 and self.hold_s > 0
                and self.period_s > 0):
            raise ParameterError(f'profile needs low_c < high_c and rate, hold, period > 0, got '
                                 f'{self}')
        for name in ('steps', 'cycles'):
            value = getattr(self, name)
            if not (isinstance(value, (int, np.integer)) and value >= 1):
                raise ParameterError(f'{name} must be an integer >= 1, got {value!r}')

    def breakpoints(self) -> _Corners:
        """
        Return the corners of the profile.

        Returns
        -------
        times_s : numpy.ndarray
            Increasing times (s) from 0.
        temperatures_c : numpy.ndarray
            Oven temperature at those times (degC).

        """
        self._check()
        lo, hi, h = float(self.low_c), float(self.high_c), float(self.hold_s)
        span = hi - lo
        ramp = span / self.rate_c_s
        times, temps = [0.0], []

        def go(level: float, duration: float) -> None:
            times.append(times[-1] + duration)
            temps.append(level)

        if self.shape == 'sine':
            mid, amp = 0.5 * (lo + hi), 0.5 * span
            k = np.arange(SINE_POINTS_PER_PERIOD * 2 * int(self.cycles) + 1)
            t = k * (self.period_s / SINE_POINTS_PER_PERIOD)
            u = mid + amp * np.sin(2.0 * np.pi * k / SINE_POINTS_PER_PERIOD)
            return t, u + self.offset_c
        start = {'heating': lo, 'staircase': lo, 'cycle': lo, 'soak': lo}.get(self.shape, hi)
        temps.append(start)
        if self.shape == 'soak':
            go(lo, 60.0)
            go(hi, ramp / SOAK_SPEED_UP)
            go(hi, 3.0 * h)
        else:
            go(start, h)
        if self.shape in ('heating', 'cooling'):
            go(hi if self.shape == 'heating' else lo, ramp)
            go(temps[-1], h)
        elif self.shape in ('staircase', 'staircase_down'):
            sign = 1.0 if self.shape == 'staircase' else -1.0
            for i in range(1, int(self.steps) + 1):
                go(start + sign * span * i / self.steps, ramp / self.steps)
                go(temps[-1], h)
        elif self.shape in ('cycle', 'cool_reheat'):
            other = hi if self.shape == 'cycle' else lo
            for _ in range(int(self.cycles)):
                go(other, ramp)
                go(other, h)
                go(start, ramp)
                go(start, h)
        return np.asarray(times), np.asarray(temps) + self.offset_c

    def shifted(self, delta_c: float) -> 'ShapeProfile':
        """Return the profile with every set-point ``delta_c`` (degC) warmer."""
        return replace(self, offset_c=self.offset_c + float(delta_c))

    def starting_at(self, start_c: float) -> 'ShapeProfile':
        """Return the profile shifted so that it starts at ``start_c`` (degC)."""
        return self.shifted(float(start_c) - float(self.breakpoints()[1][0]))


def make_profile(shape: str, **options: Any) -> OvenProfile | ShapeProfile:
    """
    Build a profile by name: ``'oven'`` (:class:`OvenProfile`) or a :class:`ShapeProfile` shape.

    Parameters
    ----------
    shape : str
        One of :data:`SHAPES`.
    **options
        Fields of the profile class (e.g. ``low_c``, ``high_c``, ``hold_s``).

    Returns
    -------
    OvenProfile or ShapeProfile

    Raises
    ------
    ParameterError
        Unknown shape, an option the class does not have, or bad values.

    """
    if shape not in SHAPES:
        raise ParameterError(f'unknown thermal profile {shape!r} (known: {", ".join(SHAPES)})')
    cls = OvenProfile if shape == 'oven' else ShapeProfile
    if shape != 'oven':
        options = dict(options, shape=shape)
    unknown = set(options) - set(cls.__dataclass_fields__)
    if unknown:
        raise ParameterError(f'profile {shape!r} has no option(s) {", ".join(sorted(unknown))}')
    profile = cls(**options)
    profile.breakpoints()  # validates
    return profile


@dataclass(frozen=True)
class ThermalModel:
    """
    Constants of the simulated device: die lag, drift laws, temperature sensor, noise.

    Per-axis values are 3-tuples (x, y, z) or one number for all axes. Magnitudes follow the
    LSM6DSO32 datasheet where it gives one (zero-rate level change about 0.01 deg/s/degC, rate
    noise density 3.8 mdps/sqrt(Hz), zero-g level change about 0.1 mg/degC, temperature sensor
    256 LSB/degC); the rest are plausible orders of magnitude, stated as such.

    Attributes
    ----------
    tau_die_s : float
        Thermal time constant of the die in oven air (s). 600 s: a small PCB in a chamber.
    self_heating_c : float
        Die temperature above the oven air at equilibrium (degC).
    t_ref_c : float
        Reference temperature of the bias polynomials (degC).
    bias_dps : float or 3-tuple
        Bias at ``t_ref_c`` at rest (deg/s).
    lin_dps_per_c, quad_dps_per_c2, cubic_dps_per_c3 : float or 3-tuple
        Polynomial coefficients c1, c2, c3 in (T - t_ref_c): about +-1 deg/s over -40..60 degC.
    knee_dps : float or 3-tuple
        Amplitude k of the tanh knee (deg/s).
    knee_c, knee_width_c : float
        Centre T_k and width w_k of the knee (degC).
    gradient_dps_per_c_s : float or 3-tuple
        g: bias per unit die rate in uncompressed time (deg/s per degC/s); 3 gives 0.05 deg/s
        while the die cools at 1 degC/min.
    hysteresis_half_width_c : float
        r of the play operator (degC); 0 switches hysteresis off.
    hysteresis_dps_per_c : float or 3-tuple
        h: bias per degC of (z - T) (deg/s/degC); the loop is 2 h r high.
    accel_bias_mg : float or 3-tuple
        Accelerometer zero-g offset at ``t_ref_c`` (mg).
    accel_lin_mg_per_c, accel_quad_mg_per_c2, accel_cubic_mg_per_c3 : float or 3-tuple
        Accelerometer offset polynomial in (T - t_ref_c) (mg per degC^i); the datasheet's
        zero-g level change is about 0.1 mg/degC.
    accel_noise_ug_rthz : float
        Accelerometer white noise density (ug/sqrt(Hz)); 70 as the emulator's LSM6DSO32.
    temp_noise_c : float
        Standard deviation of the temperature sensor's noise (degC).
    temp_lsb_c : float
        Temperature sensor resolution (degC); 0 = no rounding.
    arw_dps_rthz : float
        White rate noise, the Allan coefficient N (deg/s/sqrt(Hz)): sigma^2(tau) = N^2 / tau.
    bias_instability_dps : float
        Target flicker floor B (deg/s): the Gauss-Markov sum's Allan deviation peaks at 0.664 B.
    bi_corr_times_s : tuple of float
        Correlation times of the equal-variance Gauss-Markov processes making the floor (s).
    turn_on_bias_dps : float
        Run-to-run (turn-on) bias repeatability, standard deviation (deg/s).
    room_spread_c : float
        Run-to-run temperature spread, uniform +- (degC): the room of :class:`OvenProfile`, every
        set-point of a :class:`ShapeProfile`.

    """

    tau_die_s: float = 600.0
    self_heating_c: float = 2.0
    t_ref_c: float = 25.0
    bias_dps: object = (0.20, -0.15, 0.10)
    lin_dps_per_c: object = (0.010, -0.008, 0.006)
    quad_dps_per_c2: object = (1.0e-4, 6.0e-5, -8.0e-5)
    cubic_dps_per_c3: object = (-2.0e-6, 1.5e-6, 1.0e-6)
    knee_dps: object = (0.03, -0.02, 0.025)
    knee_c: float = 5.0
    knee_width_c: float = 8.0
    gradient_dps_per_c_s: object = (3.0, -2.0, 2.5)
    hysteresis_half_width_c: float = 1.0
    hysteresis_dps_per_c: object = (0.004, -0.003, 0.003)
    accel_bias_mg: object = (5.0, -3.0, 8.0)
    accel_lin_mg_per_c: object = (0.10, -0.08, 0.12)
    accel_quad_mg_per_c2: object = (1.0e-3, -8.0e-4, 5.0e-4)
    accel_cubic_mg_per_c3: object = (-1.0e-5, 1.0e-5, 5.0e-6)
    accel_noise_ug_rthz: float = 70.0
    temp_noise_c: float = 0.02
    temp_lsb_c: float = TEMPERATURE_LSB_C
    arw_dps_rthz: float = 3.8e-3
    bias_instability_dps: float = 4.0 / 3600.0
    bi_corr_times_s: tuple = (10.0, 100.0, 1000.0)
    turn_on_bias_dps: float = 0.005
    room_spread_c: float = 1.0

    #: Names of the columns of :meth:`bias_terms`.
    TERMS = ('1', 'd', 'd^2', 'd^3', 'knee', 'dT/dt_nat', 'z - T')

    def vec(self, name: str) -> NDArray[np.float64]:
        """Return per-axis attribute ``name`` as a float array (3,)."""
        arr = np.broadcast_to(np.asarray(getattr(self, name), dtype=float), (3,)).copy()
        if not np.all(np.isfinite(arr)):
            raise ParameterError(f'{name} must be finite, got {getattr(self, name)!r}')
        return arr

    def check(self) -> None:
        """Raise ParameterError naming the first bad constant."""
        for name in ('tau_die_s', 'knee_width_c'):
            if not getattr(self, name) > 0:
                raise ParameterError(f'{name} must be > 0, got {getattr(self, name)!r}')
        for name in ('hysteresis_half_width_c', 'temp_noise_c', 'temp_lsb_c', 'arw_dps_rthz',
                     'bias_instability_dps', 'turn_on_bias_dps', 'room_spread_c',
                     'accel_noise_ug_rthz'):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f'{name} must be finite and >= 0, got {value!r}')
        if not all(tc > 0 for tc in self.bi_corr_times_s):
            raise ParameterError(f'bi_corr_times_s must be > 0, got {self.bi_corr_times_s!r}')

    def bias_coefficients_dps(self) -> NDArray[np.float64]:
        """
        Return the gyro drift law's coefficient of every term of :meth:`bias_terms`.

        Returns
        -------
        numpy.ndarray
            (7, 3), deg/s per unit of each term, rows in the order of :attr:`TERMS`.

        """
        return np.stack([self.vec(k) for k in (
            'bias_dps', 'lin_dps_per_c', 'quad_dps_per_c2', 'cubic_dps_per_c3', 'knee_dps',
            'gradient_dps_per_c_s', 'hysteresis_dps_per_c')])

    def bias_terms(self, die_c: ArrayLike, die_rate_nat_c_s: ArrayLike,
                   played_c: ArrayLike) -> NDArray[np.float64]:
        """
        Return the seven terms of the gyro drift law, one column each (:attr:`TERMS`).

        ``[1, d, d^2, d^3, tanh((T - T_k) / w_k), dT/dt_nat, z - T]`` with ``d = T - t_ref_c``:
        the drift is these times :meth:`bias_coefficients_dps`, and they are the basis of the
        least-squares oracle.

        Parameters
        ----------
        die_c : array_like
            Die temperature T (n,), degC.
        die_rate_nat_c_s : array_like
            Die rate in uncompressed time (n,), degC/s.
        played_c : array_like
            Play-operator output z (n,), degC (equal to ``die_c`` without hysteresis).

        Returns
        -------
        numpy.ndarray
            (n, 7).

        """
        temp = np.asarray(die_c, dtype=float).reshape(-1)
        d = temp - self.t_ref_c
        return np.column_stack([
            np.ones_like(d), d, d * d, d * d * d,
            np.tanh((temp - self.knee_c) / self.knee_width_c),
            np.asarray(die_rate_nat_c_s, dtype=float).reshape(-1),
            np.asarray(played_c, dtype=float).reshape(-1) - temp])

    def bias_rad_s(self, die_c: ArrayLike, die_rate_nat_c_s: ArrayLike,
                   played_c: ArrayLike) -> NDArray[np.float64]:
        """
        Evaluate the gyro drift law of the module docstring.

        Parameters
        ----------
        die_c : array_like
            Die temperature T (n,), degC.
        die_rate_nat_c_s : array_like
            Die rate in uncompressed time (n,), degC/s.
        played_c : array_like
            Play-operator output z (n,), degC (equal to ``die_c`` without hysteresis).

        Returns
        -------
        numpy.ndarray
            Bias (n, 3), rad/s.

        """
        terms = self.bias_terms(die_c, die_rate_nat_c_s, played_c)
        return (terms @ self.bias_coefficients_dps()) * DEG_TO_RAD

    def accel_bias_m_s2(self, die_c: ArrayLike) -> NDArray[np.float64]:
        """
        Evaluate the accelerometer offset law: a cubic in ``d = T - t_ref_c``.

        Parameters
        ----------
        die_c : array_like
            Die temperature T (n,), degC.

        Returns
        -------
        numpy.ndarray
            Offset (n, 3), m/s^2 (added to the specific force).

        """
        d = np.asarray(die_c, dtype=float).reshape(-1)[:, None] - self.t_ref_c
        mg = (self.vec('accel_bias_mg') + d * (self.vec('accel_lin_mg_per_c') + d * (
            self.vec('accel_quad_mg_per_c2') + d * self.vec('accel_cubic_mg_per_c3'))))
        return mg * MG_TO_M_S2

    def gauss_markov_std_dps(self) -> float:
        """
        Return the standard deviation q of each Gauss-Markov process (deg/s).

        Chosen so that the closed-form Allan deviation of their sum
        (:func:`gyro_noise_ros.core.simulate.gauss_markov_avar`) peaks at 0.664 B over
        0.1 s .. 1e5 s.

        Returns
        -------
        float

        """
        if self.bias_instability_dps == 0 or not self.bi_corr_times_s:
            return 0.0
        taus = np.logspace(-1, 5, 600)
        unit = sum(gauss_markov_avar(taus, 1.0, tc) for tc in self.bi_corr_times_s)
        assert isinstance(unit, np.ndarray)  # a sum of at least one array
        return float(0.664 * self.bias_instability_dps / np.sqrt(unit.max()))


@numba.njit(**JIT_OPTIONS)
def _lag_play(t: NDArray[np.float64], u: NDArray[np.float64], tau: float, r: float,
              t0: float, u0: float, y0: float, z0: float, y_out: NDArray[np.float64],
              z_out: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    """
    First-order lag of a piecewise-linear input (exact), then the play operator of half-width r.

    Between samples the input is linear, u(s) = u_prev + slope (s - t_prev), so
    y(t) = u(t) - slope tau + (y_prev - u_prev + slope tau) exp(-(t - t_prev) / tau).
    z = min(max(z_prev, y - r), y + r).
    """
    tp = t0
    up = u0
    yp = y0
    zp = z0
    for k in range(t.shape[0]):
        h = t[k] - tp
        if h > 0.0:
            slope = (u[k] - up) / h
            a = np.exp(-h / tau)
            yp = a * (yp - up + slope * tau) + u[k] - slope * tau
        zp = min(max(zp, yp - r), yp + r)
        y_out[k] = yp
        z_out[k] = zp
        tp = t[k]
        up = u[k]


@dataclass(frozen=True)
class ThermalSamples:
    """
    What :meth:`ThermalStream.step` returns for a batch of sample times.

    Attributes
    ----------
    oven_c : numpy.ndarray
        Oven air temperature (n,), degC.
    die_c : numpy.ndarray
        True die temperature (n,), degC.
    die_rate_c_s : numpy.ndarray
        True die rate (n,), degC per (compressed, i.e. real) second.
    played_c : numpy.ndarray
        Play-operator output z (n,), degC.
    bias_rad_s : numpy.ndarray
        Thermal gyro bias (n, 3), rad/s.
    accel_bias_m_s2 : numpy.ndarray
        Thermal accelerometer offset (n, 3), m/s^2.

    """

    oven_c: np.ndarray
    die_c: np.ndarray
    die_rate_c_s: np.ndarray
    played_c: np.ndarray
    bias_rad_s: np.ndarray
    accel_bias_m_s2: np.ndarray


class ThermalStream:
    """
    The oven, the die and the thermal drift, evaluated batch by batch with state carried over.

    The same times give the same values whatever the batch sizes (the recursion runs sample by
    sample). Used by :func:`simulate_run` (one batch) and by the Portenta emulator (many).

    Parameters
    ----------
    model : ThermalModel, optional
        Device constants (defaults if None).
    profile : OvenProfile or ShapeProfile, optional
        Oven profile (the paper's :class:`OvenProfile` if None).
    compress : float, keyword-only
        Time compression X (>= 1 speeds up; any value > 0 allowed).
    room_c : float, optional, keyword-only
        The temperature the profile starts at: the room of an :class:`OvenProfile`; a
        :class:`ShapeProfile` is shifted so that it starts there.

    """

    def __init__(self, model: ThermalModel | None = None,
                 profile: OvenProfile | ShapeProfile | None = None, *, compress: float = 1.0,
                 room_c: float | None = None) -> None:
        self.model = ThermalModel() if model is None else model
        self.model.check()
        profile = OvenProfile() if profile is None else profile
        if room_c is not None:
            profile = profile.starting_at(float(room_c))
        self.profile = profile
        self._times, self._temps = profile.breakpoints()
        if not (np.isfinite(compress) and compress > 0):
            raise ParameterError(f'compress must be finite and > 0, got {compress!r}')
        self.compress = float(compress)
        self.tau_s = self.model.tau_die_s / self.compress
        self._state: tuple[float, float, float, float] | None = None

    @property
    def duration_s(self) -> float:
        """float: length of the compressed profile (s)."""
        return float(self._times[-1]) / self.compress

    def oven_c(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Oven temperature (degC) at real times ``t_s`` (s), self-heating not included."""
        return np.interp(np.asarray(t_s, dtype=float) * self.compress, self._times, self._temps)

    def step(self, t_s: ArrayLike) -> ThermalSamples:
        """
        Advance to the times ``t_s`` and return the thermal state there.

        Parameters
        ----------
        t_s : array_like
            Real times (s), non-decreasing and not before the previous batch's last time. The
            die starts in equilibrium with the oven at the first time given.

        Returns
        -------
        ThermalSamples

        """
        t = np.ascontiguousarray(t_s, dtype=float).reshape(-1)
        u = self.oven_c(t) + self.model.self_heating_c
        y = np.empty_like(t)
        z = np.empty_like(t)
        if t.size:
            if self._state is None:
                self._state = (t[0], u[0], u[0], u[0])
            if t[0] < self._state[0] or np.any(np.diff(t) < 0):
                raise ParameterError('ThermalStream.step needs non-decreasing times')
            _lag_play(t, u, self.tau_s, float(self.model.hysteresis_half_width_c), *self._state,
                      y, z)
            self._state = (t[-1], u[-1], y[-1], z[-1])
        rate = (u - y) / self.tau_s
        bias = self.model.bias_rad_s(y, rate / self.compress, z)
        return ThermalSamples(oven_c=u - self.model.self_heating_c, die_c=y, die_rate_c_s=rate,
                              played_c=z, bias_rad_s=bias,
                              accel_bias_m_s2=self.model.accel_bias_m_s2(y))

    def measure_c(self, die_c: ArrayLike, rng: np.random.Generator) -> NDArray[np.float64]:
        """
        Temperature sensor reading: die temperature plus noise, rounded to the LSB.

        Parameters
        ----------
        die_c : array_like
            True die temperature (n,), degC.
        rng : numpy.random.Generator
            Consumed one normal draw per sample.

        Returns
        -------
        numpy.ndarray
            Reading (n,), degC.

        """
        die = np.asarray(die_c, dtype=float)
        reading = die + rng.standard_normal(die.shape) * self.model.temp_noise_c
        lsb = self.model.temp_lsb_c
        return np.round(reading / lsb) * lsb if lsb > 0 else reading


def gyro_noise_rad_s(n: int, rate_hz: float, model: ThermalModel,
                     rng: np.random.Generator) -> NDArray[np.float64]:
    """
    White rate noise plus the Gauss-Markov sum of the bias-instability floor.

    White: per-sample standard deviation ``N sqrt(rate_hz)`` (so sigma^2(tau) = N^2 / tau).
    Gauss-Markov: one :class:`gyro_noise_ros.core.simulate.GaussMarkov` per correlation time
    (exact sampling, started from its stationary distribution), each of standard deviation
    :meth:`ThermalModel.gauss_markov_std_dps`.

    Parameters
    ----------
    n : int
        Samples.
    rate_hz : float
        Sample rate (Hz).
    model : ThermalModel
        Noise constants (``arw_dps_rthz``, ``bias_instability_dps``, ``bi_corr_times_s``).
    rng : numpy.random.Generator
        Random stream (children are spawned from it).

    Returns
    -------
    numpy.ndarray
        Noise (n, 3), rad/s.

    """
    white_rng, gm_rng = rng.spawn(2)
    noise = white_rng.standard_normal((n, 3)) * (model.arw_dps_rthz * np.sqrt(rate_hz))
    q = model.gauss_markov_std_dps()
    if q > 0 and n:
        for corr_time, sub in zip(model.bi_corr_times_s, gm_rng.spawn(len(model.bi_corr_times_s))):
            noise += GaussMarkov(q, corr_time, rate_hz, rng=sub, shape=(3,)).generate(n)
    return noise * DEG_TO_RAD


@dataclass(frozen=True)
class ThermalTruth:
    """
    What a simulated run really contained (the ThermalRun holds only what a sensor reports).

    Attributes
    ----------
    oven_c, die_c, die_rate_c_s : numpy.ndarray
        (n,) oven air (degC), die (degC) and die rate (degC/s, real time) at every sample.
    played_c : numpy.ndarray
        (n,) the hysteresis state z (degC): ``z - die_c`` is the drift law's last term.
    drift_rad_s : numpy.ndarray
        (n, 3) the thermal bias plus the turn-on bias: everything in the gyro output but noise.
    noise_rad_s : numpy.ndarray
        (n, 3) white plus Gauss-Markov noise.
    accel_drift_m_s2 : numpy.ndarray
        (n, 3) the accelerometer's thermal offset (gravity not included).
    accel_noise_m_s2 : numpy.ndarray
        (n, 3) its white noise.
    temperature_index : numpy.ndarray
        Indices of the samples at which the temperature sensor was read (Temperature messages).
    temperature_reading_c : numpy.ndarray
        The readings at those samples (degC).
    room_c : float
        The temperature the profile started at for this run (degC): the room of the paper's
        oven, the first set-point of a shape (both include the run-to-run spread).
    turn_on_bias_rad_s : numpy.ndarray
        (3,) this run's turn-on bias, rad/s (included in ``drift_rad_s``).
    compress : float
        Time compression X.
    shape : str
        The profile's shape (:data:`SHAPES`).

    """

    oven_c: np.ndarray
    die_c: np.ndarray
    die_rate_c_s: np.ndarray
    played_c: np.ndarray
    drift_rad_s: np.ndarray
    noise_rad_s: np.ndarray
    accel_drift_m_s2: np.ndarray
    accel_noise_m_s2: np.ndarray
    temperature_index: np.ndarray
    temperature_reading_c: np.ndarray
    room_c: float
    turn_on_bias_rad_s: np.ndarray
    compress: float
    shape: str = 'oven'


#: A simulated train/test pair: ``[('train', run, truth), ('test', run, truth)]``.
Pair = list[tuple[str, ThermalRun, ThermalTruth]]


def resolve_timing(profile: OvenProfile | ShapeProfile, *, hours: float | None = None,
                   compress: float | None = None) -> tuple[float, float]:
    """
    Turn ``hours`` and ``compress`` into (duration_s, compress).

    Neither: the whole profile in real time. ``hours`` only: the profile compressed to fill it.
    ``compress`` only: the compressed profile's length. Both: ``hours`` long with that
    compression (the oven holds its last set-point past the profile's end, or the run stops
    early).

    Parameters
    ----------
    profile : OvenProfile or ShapeProfile
        The profile whose natural length is compressed.
    hours : float, optional, keyword-only
        Run length (h).
    compress : float, optional, keyword-only
        Time compression X (> 0).

    Returns
    -------
    tuple of float

    """
    natural = profile.duration_s
    if hours is not None and not (np.isfinite(hours) and hours > 0):
        raise ParameterError(f'hours must be > 0, got {hours!r}')
    if compress is not None and not (np.isfinite(compress) and compress > 0):
        raise ParameterError(f'compress must be > 0, got {compress!r}')
    if hours is None and compress is None:
        return natural, 1.0
    if compress is None:
        assert hours is not None
        return hours * 3600.0, natural / (hours * 3600.0)
    if hours is None:
        return natural / compress, float(compress)
    return hours * 3600.0, float(compress)


def simulate_run(*, rng: np.random.Generator, rate_hz: float = 100.0, hours: float | None = None,
                 compress: float | None = None, model: ThermalModel | None = None,
                 profile: OvenProfile | ShapeProfile | None = None,
                 temperature_rate_hz: float = TEMPERATURE_RATE_HZ,
                 name: str = '') -> tuple[ThermalRun, ThermalTruth]:
    """
    Simulate one static run: the ThermalRun a recording would give, and the truth.

    The device lies flat (+1 g on z, REP-103); the gyro reads drift + turn-on bias + noise, the
    accelerometer gravity + its thermal offset + noise.

    Parameters
    ----------
    rng : numpy.random.Generator, keyword-only
        Parent of every random stream (temperature spread, turn-on bias, gyro noise, sensor
        noise, accelerometer noise).
    rate_hz : float, keyword-only
        Gyro sample rate (Hz).
    hours, compress : float, optional, keyword-only
        Run length and time compression (see :func:`resolve_timing`).
    model : ThermalModel, optional, keyword-only
        Device constants (defaults if None).
    profile : OvenProfile or ShapeProfile, optional, keyword-only
        Oven profile (the paper's :class:`OvenProfile` if None); :func:`make_profile` builds one
        by shape name.
    temperature_rate_hz : float, keyword-only
        The temperature is read at every m-th sample, ``m = max(1, round(rate_hz / this))``
        (the driver publishes it the same way); the run's temperature is those readings
        linearly interpolated onto every sample, as a bag reader would do.
    name : str, keyword-only
        Label of the run.

    Returns
    -------
    run : ThermalRun
    truth : ThermalTruth

    """
    if not isinstance(rng, np.random.Generator):
        raise ParameterError(f'rng must be a numpy.random.Generator, got {type(rng).__name__}')
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise ParameterError(f'rate_hz must be > 0, got {rate_hz!r}')
    if not (np.isfinite(temperature_rate_hz) and temperature_rate_hz > 0):
        raise ParameterError(f'temperature_rate_hz must be > 0, got {temperature_rate_hz!r}')
    model = ThermalModel() if model is None else model
    model.check()
    profile = OvenProfile() if profile is None else profile
    duration_s, compress = resolve_timing(profile, hours=hours, compress=compress)
    n = int(np.floor(duration_s * rate_hz))
    if n < 2:
        raise ParameterError(f'run of {duration_s} s at {rate_hz} Hz has fewer than 2 samples')
    run_rng, noise_rng, temp_rng = rng.spawn(3)
    profile = profile.shifted(run_rng.uniform(-1.0, 1.0) * model.room_spread_c)
    turn_on = run_rng.standard_normal(3) * model.turn_on_bias_dps * DEG_TO_RAD
    accel_rng = run_rng.spawn(1)[0]
    t = np.arange(n) / rate_hz
    stream = ThermalStream(model, profile, compress=compress)
    th = stream.step(t)
    drift = th.bias_rad_s + turn_on
    noise = gyro_noise_rad_s(n, rate_hz, model, noise_rng)
    accel_noise = accel_rng.standard_normal((n, 3)) * (
        model.accel_noise_ug_rthz * 1e-6 * STANDARD_GRAVITY_M_S2 * np.sqrt(rate_hz / 2.0))
    m = max(1, int(round(rate_hz / temperature_rate_hz)))
    idx = np.arange(0, n, m)
    reading = stream.measure_c(th.die_c[idx], temp_rng)
    gravity = np.array([0.0, 0.0, STANDARD_GRAVITY_M_S2])
    run = ThermalRun(t_s=t, gyro_rad_s=drift + noise,
                     temperature_c=np.interp(t, t[idx], reading), rate_hz=float(rate_hz),
                     name=name, accel_m_s2=gravity + th.accel_bias_m_s2 + accel_noise)
    truth = ThermalTruth(oven_c=th.oven_c, die_c=th.die_c, die_rate_c_s=th.die_rate_c_s,
                         played_c=th.played_c, drift_rad_s=drift, noise_rad_s=noise,
                         accel_drift_m_s2=th.accel_bias_m_s2, accel_noise_m_s2=accel_noise,
                         temperature_index=idx, temperature_reading_c=reading,
                         room_c=float(th.oven_c[0]), turn_on_bias_rad_s=turn_on,
                         compress=compress, shape=profile.shape)
    return run, truth


def write_run_bag(path: StrPath, run: ThermalRun, truth: ThermalTruth, *, storage: str = 'sqlite3',
                  start_ns: int = DEFAULT_START_NS, imu_topic: str = '/imu/data_raw',
                  temperature_topic: str = '/imu/temperature', frame_id: str = 'imu_link') -> Path:
    """
    Write a simulated run as a rosbag2: ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature``.

    The Imu messages carry the gyro samples and the run's accelerometer samples (a static +1 g
    on z if the run has none); the Temperature messages carry the sensor readings at
    ``truth.temperature_index`` (variance 0, unknown, as the driver publishes by default). Header
    stamps are ``start_ns + t_s``; bag time equals the stamp.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory to create (must not exist).
    run : ThermalRun
        The run (gyro samples and stamps).
    truth : ThermalTruth
        Its truth (the temperature readings and where they were taken).
    storage : {'sqlite3', 'mcap'}, keyword-only
        rosbag2 storage plugin.
    start_ns : int, keyword-only
        Stamp of the first sample (ns).
    imu_topic : str, keyword-only
        Imu topic.
    temperature_topic : str, keyword-only
        Temperature topic.
    frame_id : str, keyword-only
        ``header.frame_id`` of every message.

    Returns
    -------
    pathlib.Path
        The bag directory.

    """
    from ..bag import ImuBagWriter

    stamps = start_ns + np.round(run.t_s * 1e9).astype(np.int64)
    accel = run.accel_m_s2
    if accel is None:
        accel = np.broadcast_to(np.array([0.0, 0.0, STANDARD_GRAVITY_M_S2]), (stamps.size, 3))
    chunk = 200_000
    with ImuBagWriter(path, storage=storage, imu_topic=imu_topic,
                      temperature_topic=temperature_topic, frame_id=frame_id) as writer:
        for lo in range(0, stamps.size, chunk):
            hi = min(lo + chunk, stamps.size)
            writer.write_imu(stamps[lo:hi], run.gyro_rad_s[lo:hi], accel[lo:hi])
        t_stamps = stamps[truth.temperature_index]
        for lo in range(0, t_stamps.size, chunk):
            writer.write_temperature(t_stamps[lo:lo + chunk],
                                     truth.temperature_reading_c[lo:lo + chunk],
                                     variance=0.0)
    return Path(path)


def truth_arrays(run: ThermalRun, truth: ThermalTruth) -> dict[str, Any]:
    """
    Return the arrays of a run's truth as saved in ``<label>_truth.npz`` (name -> array or scalar).

    ``run`` gives the stamps, ``truth`` the rest (keys in docs/thermal_data.md, train and test
    runs).

    """
    return {'t_s': run.t_s, 'oven_c': truth.oven_c, 'die_c': truth.die_c,
            'die_rate_c_s': truth.die_rate_c_s, 'played_c': truth.played_c,
            'drift_rad_s': truth.drift_rad_s, 'noise_rad_s': truth.noise_rad_s,
            'accel_drift_m_s2': truth.accel_drift_m_s2,
            'accel_noise_m_s2': truth.accel_noise_m_s2,
            'temperature_index': truth.temperature_index,
            'temperature_reading_c': truth.temperature_reading_c, 'room_c': truth.room_c,
            'turn_on_bias_rad_s': truth.turn_on_bias_rad_s, 'compress': truth.compress,
            'shape': truth.shape}


def simulate_pair(*, seed: int, rate_hz: float = 100.0, hours: float | None = None,
                  compress: float | None = None, model: ThermalModel | None = None,
                  profile: OvenProfile | ShapeProfile | None = None,
                  test_profile: OvenProfile | ShapeProfile | None = None,
                  temperature_rate_hz: float = TEMPERATURE_RATE_HZ) -> Pair:
    """
    Simulate two runs of one device in one time compression: train and (held-out) test.

    Both runs share the device (``model``) and the compression; they differ in everything a
    second run differs in: noise, temperature spread, turn-on bias (seed streams 0 and 1 of
    ``numpy.random.SeedSequence(seed)``), and in the oven profile when ``test_profile`` is
    given (a held-out run of another shape). The compression comes from the training profile
    and ``hours``/``compress`` (:func:`resolve_timing`); the test run is its whole profile at
    that compression (``hours`` long too when its profile is the training one).

    Parameters
    ----------
    seed : int, keyword-only
        Seed of both runs.
    rate_hz : float, keyword-only
        Gyro sample rate (Hz).
    hours, compress : float, optional, keyword-only
        Training run length and compression.
    model : ThermalModel, optional, keyword-only
        Device constants (defaults if None).
    profile : OvenProfile or ShapeProfile, optional, keyword-only
        Training profile (the paper's oven if None).
    test_profile : OvenProfile or ShapeProfile, optional, keyword-only
        Test profile (None: the training profile, a replicate run).
    temperature_rate_hz : float, keyword-only
        Rate of the temperature readings (see :func:`simulate_run`).

    Returns
    -------
    list of (str, ThermalRun, ThermalTruth)
        ``[('train', run, truth), ('test', run, truth)]``.

    """
    model = ThermalModel() if model is None else model
    profile = OvenProfile() if profile is None else profile
    duration_s, comp = resolve_timing(profile, hours=hours, compress=compress)
    test = profile if test_profile is None else test_profile
    timings = [(duration_s / 3600.0, comp)]
    timings.append(timings[0] if test_profile is None
                   else (resolve_timing(test, compress=comp)[0] / 3600.0, comp))
    out = []
    children = np.random.SeedSequence(seed).spawn(2)
    for label, child, prof, (run_h, run_x) in zip(('train', 'test'), children, (profile, test),
                                                  timings):
        run, truth = simulate_run(rng=np.random.default_rng(child), rate_hz=rate_hz,
                                  hours=run_h, compress=run_x, model=model, profile=prof,
                                  temperature_rate_hz=temperature_rate_hz,
                                  name=f'{label} {prof.shape} (seed {seed})')
        out.append((label, run, truth))
    return out


def pair_settings(pair: Pair, *, seed: int, rate_hz: float, hours: float | None, storage: str,
                  model: ThermalModel, profile: OvenProfile | ShapeProfile,
                  test_profile: OvenProfile | ShapeProfile | None,
                  temperature_rate_hz: float) -> dict[str, Any]:
    """
    Return the settings of a simulated pair as written to ``simulation.json``.

    Parameters
    ----------
    pair : list
        From :func:`simulate_pair`.
    seed, rate_hz, hours, storage, temperature_rate_hz : keyword-only
        As given to :func:`simulate_pair` / :func:`write_train_test`.
    model : ThermalModel, keyword-only
        The device.
    profile, test_profile : OvenProfile or ShapeProfile, keyword-only
        The profiles (``test_profile`` None: the training one).

    Returns
    -------
    dict

    """
    test = profile if test_profile is None else test_profile
    return {'seed': seed, 'rate_hz': rate_hz, 'hours': hours,
            'duration_s': float(pair[0][1].t_s.size / rate_hz),
            'test_duration_s': float(pair[1][1].t_s.size / rate_hz),
            'compress': pair[0][2].compress, 'storage': storage,
            'temperature_rate_hz': temperature_rate_hz, 'model': asdict(model),
            'profile': dict(asdict(profile), shape=profile.shape),
            'test_profile': dict(asdict(test), shape=test.shape)}


def write_pair(out_dir: StrPath, pair: Pair, settings: Mapping[str, Any], *,
               storage: str = 'sqlite3') -> tuple[Path, ...]:
    """
    Write a simulated pair: ``train/``, ``test/`` bags, their truth and ``simulation.json``.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Existing folder (``train/`` and ``test/`` must not exist in it).
    pair : list
        From :func:`simulate_pair`.
    settings : dict
        From :func:`pair_settings`.
    storage : {'sqlite3', 'mcap'}, keyword-only
        rosbag2 storage plugin.

    Returns
    -------
    tuple of pathlib.Path
        ``(train_bag, test_bag)``.

    """
    out = Path(out_dir)
    paths = []
    for label, run, truth in pair:
        paths.append(write_run_bag(out / label, run, truth, storage=storage))
        np.savez_compressed(out / f'{label}_truth.npz', **truth_arrays(run, truth))
    (out / 'simulation.json').write_text(json.dumps(settings, indent=2, default=list) + '\n')
    return tuple(paths)


def load_truth(path: StrPath) -> ThermalTruth:
    """
    Read a ``<label>_truth.npz`` back into a :class:`ThermalTruth`.

    Parameters
    ----------
    path : str or os.PathLike
        The file :func:`write_pair` wrote.

    Returns
    -------
    ThermalTruth

    """
    with np.load(path) as z:
        kw = {k: z[k] for k in z.files if k != 't_s'}
    for key in ('room_c', 'compress'):
        kw[key] = float(kw[key])
    kw['shape'] = str(kw.get('shape', 'oven'))
    return ThermalTruth(**kw)


def model_from_settings(settings: Mapping[str, Any]) -> ThermalModel:
    """
    Rebuild the :class:`ThermalModel` of a ``simulation.json`` document.

    Parameters
    ----------
    settings : dict
        The document.

    Returns
    -------
    ThermalModel

    """
    fields = ThermalModel.__dataclass_fields__
    kw: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v
                          for k, v in settings['model'].items() if k in fields}
    return ThermalModel(**kw)


def write_train_test(out_dir: StrPath, *, seed: int, hours: float | None = None,
                     rate_hz: float = 100.0, compress: float | None = None,
                     storage: str = 'sqlite3', model: ThermalModel | None = None,
                     profile: OvenProfile | ShapeProfile | None = None,
                     test_profile: OvenProfile | ShapeProfile | None = None,
                     temperature_rate_hz: float = TEMPERATURE_RATE_HZ) -> tuple[Path, ...]:
    """
    Simulate a train/test pair (:func:`simulate_pair`) and write them (:func:`write_pair`).

    ``out_dir`` receives ``train/`` and ``test/`` (bags), ``train_truth.npz`` and
    ``test_truth.npz`` (:func:`truth_arrays`) and ``simulation.json`` (every setting, so the
    runs can be reproduced).

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output directory (created; ``train/`` and ``test/`` must not exist).
    seed : int, keyword-only
        Seed of both runs.
    hours, compress : float, optional, keyword-only
        See :func:`resolve_timing` (the training run's).
    rate_hz : float, keyword-only
        Gyro sample rate (Hz).
    storage : {'sqlite3', 'mcap'}, keyword-only
        rosbag2 storage plugin.
    model : ThermalModel, optional, keyword-only
        Device constants (defaults if None).
    profile, test_profile : OvenProfile or ShapeProfile, optional, keyword-only
        Training and test profiles (see :func:`simulate_pair`).
    temperature_rate_hz : float, keyword-only
        Rate of the Temperature messages (see :func:`simulate_run`).

    Returns
    -------
    tuple of pathlib.Path
        ``(train_bag, test_bag)``.

    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    model = ThermalModel() if model is None else model
    profile = OvenProfile() if profile is None else profile
    pair = simulate_pair(seed=seed, rate_hz=rate_hz, hours=hours, compress=compress,
                         model=model, profile=profile, test_profile=test_profile,
                         temperature_rate_hz=temperature_rate_hz)
    settings = pair_settings(pair, seed=seed, rate_hz=rate_hz, hours=hours, storage=storage,
                             model=model, profile=profile, test_profile=test_profile,
                             temperature_rate_hz=temperature_rate_hz)
    return write_pair(out, pair, settings, storage=storage)
