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
The data a thermal method is fitted on and applied to, and the protocol every method follows.

A :class:`ThermalRun` is one static recording: gyro samples with their stamps and the die
temperature interpolated onto the same stamps. Every method (the paper's parallel model and each
baseline) implements :class:`ThermalMethod`: fitted on one run, applied to another (never the same
one when it is scored), serialised to a JSON-able dict for ``model.json``. Causal methods can
also give the gyro offset as a function of temperature and its rate, which is what the live
compensation node evaluates.
"""

from dataclasses import dataclass
import math
from typing import Protocol, runtime_checkable

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.jit import JIT_OPTIONS
from ..errors import InputDataError


@dataclass(frozen=True)
class ThermalRun:
    """
    One recording for thermal fitting or evaluation.

    Attributes
    ----------
    t_s : numpy.ndarray
        Sample times (n,), seconds, strictly increasing.
    gyro_rad_s : numpy.ndarray
        Angular rate (n, 3), rad/s, sensor frame.
    temperature_c : numpy.ndarray
        Die temperature (n,), degC, interpolated onto ``t_s``.
    rate_hz : float
        Sample rate, Hz.
    name : str
        Label for reports (file name or seed).
    accel_m_s2 : numpy.ndarray or None
        Specific force (n, 3), m/s^2, sensor frame, when the recording has it (the
        accelerometer's temperature compensation is fitted on it); None otherwise.
    temperature_period_s : float or None
        Median interval of the temperature readings behind ``temperature_c`` (s): the rate
        window needs several of them (:func:`check_temperature_readings`); None: unknown (the
        readings are taken as dense).

    """

    t_s: np.ndarray
    gyro_rad_s: np.ndarray
    temperature_c: np.ndarray
    rate_hz: float
    name: str = ''
    accel_m_s2: np.ndarray | None = None
    temperature_period_s: float | None = None


@runtime_checkable
class ThermalMethod(Protocol):
    """
    What every thermal compensation or denoising method provides.

    ``name`` is the ``--method`` value; ``causal`` says whether ``apply`` uses only past
    samples (only causal methods may run live). ``fit`` learns from one run; ``apply`` returns
    the processed angular rate (n, 3) in rad/s for another. ``to_dict``/``from_dict`` round-trip
    every fitted parameter through JSON. Causal methods also implement
    ``drift_rad_s(temperature_c, dtemp_c_s) -> (n, 3)``: the gyro offset to subtract, used live.

    Optional (not part of the checked protocol; a method without it contributes no figures of
    its own): ``report_figures(run, out_dir) -> list of (file name or None, caption)``. Called
    by the ``fit`` and ``apply`` reports right after ``apply(run)`` on the same run object, it
    writes PNG files into the existing directory ``out_dir`` (names relative to it) for the
    paper figures only the method can draw (the parallel model: Figures 11, 12 and 14-17).
    Each caption names the paper figure it mirrors as 'Fig. N' or 'Figs. N, M', which is how
    the report's table of Figures 10-19 finds it; an entry whose name is None draws nothing and
    its caption says why that figure is absent. Figures must be cheap: plot-sized data, no
    second fit.
    """

    name: str
    causal: bool

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Learn the method's parameters from one run."""

    def apply(self, run: ThermalRun) -> np.ndarray:
        """Return the processed angular rate (n, 3), rad/s."""

    def to_dict(self) -> dict:
        """Return every fitted parameter as a JSON-serialisable dict."""


#: Default trailing window of the temperature-rate estimate (s).
DEFAULT_RATE_WINDOW_S = 10.0

#: What :func:`temperature_rate_c_s` gives where its trailing window is not yet filled.
RATE_START_MODES = ('backfill', 'nan', 'partial')


class RateWindowError(InputDataError):
    """A record is shorter than the temperature-rate window, so it has no rate (exit code 4)."""


def rate_window_filled(t_s: ArrayLike, window_s: float) -> NDArray[np.bool_]:
    """
    Return which samples have a filled trailing rate window.

    Sample k's window ``[t_k - window_s, t_k]`` is filled when it lies inside the record:
    ``t_k - t_0 >= window_s`` (to 1e-9 relative, so a window that ends exactly on a stamp
    counts).

    Parameters
    ----------
    t_s : array_like
        Sample times (n,), s, non-decreasing.
    window_s : float
        Window length (s, > 0).

    Returns
    -------
    numpy.ndarray of bool
        (n,).

    """
    t = np.asarray(t_s, dtype=float)
    if t.size == 0:
        return np.zeros(0, dtype=bool)
    return (t - t[0]) >= window_s * (1.0 - 1e-9)


def temperature_rate_c_s(t_s: ArrayLike, temperature_c: ArrayLike, *,
                         window_s: float = DEFAULT_RATE_WINDOW_S,
                         start: str = 'backfill') -> NDArray[np.float64]:
    """
    Estimate the temperature rate causally: least-squares slope over a trailing window.

    The rate at sample k uses only samples with ``t_s[k] - window_s <= t <= t_s[k]``, so the
    same number is available live (the compensation node keeps that much temperature history)
    and offline. A slope fitted over many samples rather than a first difference keeps the
    temperature sensor's noise and LSB steps out of dT; the price is a delay of about
    ``window_s / 2``.

    While the window is not yet filled (the first ``window_s`` of a record) it holds few
    samples and their slope is dominated by the sensor's noise and LSB: 0.02 degC of noise
    over 0.1 s of 52-Hz readings gives a slope scatter of ~0.3 degC/s, ten times a chamber's
    ramp. So by default (``start='backfill'``) those samples get the rate of the first sample
    whose window is filled (:func:`rate_window_filled`): unbiased for a steady ramp and never an
    outlier; live, the compensation node holds the first ``window_s`` of data until that rate
    exists. ``start='nan'`` leaves NaN there, ``start='partial'`` fits whatever the window holds
    (0 with fewer than two distinct stamps): the noisy start the training range once included.

    Parameters
    ----------
    t_s : array_like
        Sample times (n,), seconds, non-decreasing.
    temperature_c : array_like
        Temperature (n,), degC.
    window_s : float, keyword-only
        Length of the trailing window, seconds (> 0).
    start : {'backfill', 'nan', 'partial'}, keyword-only
        What the samples before the first filled window get (see above).

    Returns
    -------
    numpy.ndarray
        dT/dt (n,), degC/s.

    Raises
    ------
    RateWindowError
        ``start='backfill'`` and no sample's window is filled (the record is shorter than
        ``window_s``).

    """
    t = np.asarray(t_s, dtype=float)
    temp = np.asarray(temperature_c, dtype=float)
    if t.ndim != 1 or temp.shape != t.shape:
        raise ValueError(f't_s and temperature_c must be 1-D of one length, got {t.shape} '
                         f'and {temp.shape}')
    if not window_s > 0:
        raise ValueError(f'window_s must be > 0, got {window_s!r}')
    if start not in RATE_START_MODES:
        raise ValueError(f'start must be one of {RATE_START_MODES}, got {start!r}')
    if t.size == 0:
        return np.zeros(0)
    first = np.searchsorted(t, t - window_s, side='left')
    rate = _window_slopes(t, temp, first, 0)
    if start == 'partial':
        return rate
    filled = rate_window_filled(t, window_s)
    if not filled.any():
        if start == 'nan':
            return np.full(t.size, np.nan)
        raise RateWindowError(f'the record is {t[-1] - t[0]:.3g} s long, shorter than the '
                              f'{window_s:g}-s window of the temperature rate dT')
    k = int(np.argmax(filled))
    rate[:k] = rate[k] if start == 'backfill' else np.nan
    return rate


def temperature_rate_newest_c_s(t_s: NDArray[np.float64], temperature_c: NDArray[np.float64], *,
                                window_s: float) -> float:
    """
    Return :func:`temperature_rate_c_s`' ``start='partial'`` rate of the last sample alone.

    Bit for bit the array's last value (the same sums in the same order), for the live
    compensator's one message per call. ``t_s`` (s, non-decreasing) and ``temperature_c`` (degC)
    are 1-D float64 of one length >= 1, not checked; the result is in degC/s.
    """
    return float(_newest_slope(t_s, temperature_c, float(window_s)))


@numba.njit(**JIT_OPTIONS)
def _newest_slope(t: NDArray[np.float64], temp: NDArray[np.float64],
                  window_s: float) -> float:  # pragma: no cover - compiled
    """:func:`_window_slopes` of the last sample only, its window found as the array's is."""
    k = t.shape[0] - 1
    first = np.empty(1, np.intp)
    first[0] = np.searchsorted(t, t[k] - window_s, side='left')
    return _window_slopes(t, temp, first, k)[0]


@numba.njit(**JIT_OPTIONS)
def _slope(n: int, sum_t: float, sum_tt: float, sum_y: float,
           sum_ty: float) -> float:  # pragma: no cover - compiled
    """Least-squares slope of n points from their sums; 0 without two distinct stamps."""
    denom = n * sum_tt - sum_t * sum_t
    # denom > 0 exactly when the window holds two distinct stamps; a relative floor guards
    # against cancellation when the stamps are nearly equal (np.maximum: a NaN stays NaN).
    scale = n * sum_tt
    if scale < 1e-300:
        scale = 1e-300
    if denom > 1e-12 * scale:
        return (n * sum_ty - sum_t * sum_y) / denom
    return 0.0


@numba.njit(**JIT_OPTIONS)
def _window_slopes(t: NDArray[np.float64], temp: NDArray[np.float64], first: NDArray[np.intp],
                   start: int) -> NDArray[np.float64]:  # pragma: no cover - compiled
    """
    Slopes of samples ``start..n-1``, sample k's window holding samples ``first[k - start]..k``.

    Running sums from t[0] on, with the time axis centred on t[0] so they keep their precision;
    a window's sums are differences of two running sums (one pass, O(n)).
    """
    n = t.shape[0]
    s_t, s_tt = np.zeros(n + 1), np.zeros(n + 1)
    s_y, s_ty = np.zeros(n + 1), np.zeros(n + 1)
    # -0.0 + x is x for every x (+0.0 + -0.0 is not): the sums are np.cumsum's, bit for bit
    a_t = a_tt = a_y = a_ty = -0.0
    for i in range(n):
        tc = t[i] - t[0]
        a_t += tc
        a_tt += tc * tc
        a_y += temp[i]
        a_ty += tc * temp[i]
        s_t[i + 1], s_tt[i + 1], s_y[i + 1], s_ty[i + 1] = a_t, a_tt, a_y, a_ty
    rate = np.empty(n - start)
    for k in range(start, n):
        f, e = first[k - start], k + 1
        rate[k - start] = _slope(e - f, s_t[e] - s_t[f], s_tt[e] - s_tt[f], s_y[e] - s_y[f],
                                 s_ty[e] - s_ty[f])
    return rate


#: A temperature-rate window needs at least this many temperature readings.
MIN_READINGS_PER_WINDOW = 4
#: A dT term needs the training run's dT to spread (5th to 95th percentile over filled windows)
#: by at least this (degC/s; 0.06 degC/min: slower changes are a drifting room, not a signal) ...
MIN_RATE_SPREAD_C_S = 1e-3
#: ... and by this many times the noise of the rate estimate itself.
MIN_RATE_SPREAD_SNR = 10.0


def check_temperature_readings(run: ThermalRun, window_s: float = DEFAULT_RATE_WINDOW_S) -> None:
    """
    Refuse a run whose temperature readings are too sparse for the rate window.

    Parameters
    ----------
    run : ThermalRun
        Its ``temperature_period_s`` (None: not checked).
    window_s : float
        The rate window (s).

    Raises
    ------
    InputDataError
        Fewer than :data:`MIN_READINGS_PER_WINDOW` readings per window.

    """
    period = run.temperature_period_s
    if period is not None and period > window_s / MIN_READINGS_PER_WINDOW:
        raise InputDataError(
            f'run {run.name!r}: the temperature is read every {period:.3g} s '
            f"({1.0 / period:.3g} Hz) against the gyro's {run.rate_hz:.4g} Hz; the "
            f'{window_s:g}-s window of dT needs at least {MIN_READINGS_PER_WINDOW} readings '
            f'(a reading every {window_s / MIN_READINGS_PER_WINDOW:g} s or faster), or use a '
            'method without dT (poly3)')


@dataclass(frozen=True)
class RateSupport:
    """
    Whether a training run's temperature rate can support a dT term (:func:`rate_support`).

    Attributes
    ----------
    supported : bool
        The spread of dT reaches both floors.
    spread_c_s : float
        5th to 95th percentile of dT over filled windows (degC/s).
    noise_c_s : float
        Standard deviation of the rate estimate's own noise (degC/s), from second differences
        of dT three windows apart.
    needed_c_s : float
        The spread needed: ``max(MIN_RATE_SPREAD_C_S, MIN_RATE_SPREAD_SNR * noise_c_s)``.
    low_c_s, high_c_s : float
        The 5th and 95th percentiles of dT (degC/s).

    """

    supported: bool
    spread_c_s: float
    noise_c_s: float
    needed_c_s: float
    low_c_s: float = 0.0
    high_c_s: float = 0.0

    @property
    def both_signs(self) -> bool:
        """bool: the run both heated and cooled, each by half the needed spread or more."""
        return bool(self.supported and self.low_c_s <= -0.5 * self.needed_c_s
                    and self.high_c_s >= 0.5 * self.needed_c_s)

    def text(self) -> str:
        """Return one clause for notes and reports."""
        verb = 'supports' if self.supported else 'cannot support'
        return (f'the training dT spreads {self.spread_c_s:.3g} degC/s (5th-95th percentile; '
                f"its estimate's noise {self.noise_c_s:.2g} degC/s), which {verb} a dT term "
                f'(needed: {self.needed_c_s:.3g} degC/s)')

    def notes(self, method: str) -> tuple[str, ...]:
        """Return the note of a method fitted without its dT term (none when supported)."""
        return () if self.supported else (f'{method} fitted without a dT term: {self.text()}',)


def rate_support(t_s: ArrayLike, temperature_c: ArrayLike, *,
                 window_s: float = DEFAULT_RATE_WINDOW_S) -> RateSupport:
    """
    Tell whether a run's dT varies enough, beyond its own noise, to fit a dT term.

    A term in dT is fitted on how dT varies, not on its level: a run at one constant rate (a
    ramp without holds, or no change at all) gives dT a spread of only its estimation noise, and
    a coefficient fitted to it is noise, extrapolated wherever dT differs. The spread is the 5th
    to 95th percentile of the causal rate over filled windows; the noise is
    ``MAD(d2) / 0.6745 / sqrt(6)`` of the second differences ``d2`` of the rate at one window's
    lag (three disjoint windows, independent noise, a slowly varying true rate cancelled).

    Parameters
    ----------
    t_s, temperature_c : array_like
        The run (n,), s and degC.
    window_s : float, keyword-only
        The rate window (s).

    Returns
    -------
    RateSupport

    """
    t = np.asarray(t_s, dtype=float)
    rate = temperature_rate_c_s(t, temperature_c, window_s=window_s, start='nan')
    ok = np.isfinite(rate)
    if ok.sum() < 3:
        return RateSupport(False, 0.0, 0.0, MIN_RATE_SPREAD_C_S)
    filled = rate[ok]
    low, high = (float(v) for v in np.percentile(filled, [5, 95]))
    spread = high - low
    lag = int(np.searchsorted(t, t[0] + window_s)) or 1
    noise = 0.0
    if filled.size > 2 * lag:
        d2 = filled[2 * lag:] - 2.0 * filled[lag:-lag] + filled[:-2 * lag]
        noise = float(np.median(np.abs(d2 - np.median(d2))) / 0.6745 / math.sqrt(6.0))
    needed = max(MIN_RATE_SPREAD_C_S, MIN_RATE_SPREAD_SNR * noise)
    return RateSupport(bool(spread >= needed), spread, noise, needed, low, high)
