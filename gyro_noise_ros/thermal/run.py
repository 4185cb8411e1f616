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
from typing import Protocol, runtime_checkable

import numpy as np


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

    """

    t_s: np.ndarray
    gyro_rad_s: np.ndarray
    temperature_c: np.ndarray
    rate_hz: float
    name: str = ''


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


def temperature_rate_c_s(t_s, temperature_c, *, window_s=DEFAULT_RATE_WINDOW_S):
    """
    Estimate the temperature rate causally: least-squares slope over a trailing window.

    The rate at sample k uses only samples with ``t_s[k] - window_s <= t <= t_s[k]``, so the
    same number is available live (the compensation node keeps that much temperature history)
    and offline. A slope fitted over many samples rather than a first difference keeps the
    temperature sensor's noise and LSB steps out of dT; the price is a delay of about
    ``window_s / 2``. Where the window holds fewer than two distinct stamps the rate is 0.

    Parameters
    ----------
    t_s : array_like
        Sample times (n,), seconds, non-decreasing.
    temperature_c : array_like
        Temperature (n,), degC.
    window_s : float, keyword-only
        Length of the trailing window, seconds (> 0).

    Returns
    -------
    numpy.ndarray
        dT/dt (n,), degC/s.

    """
    t = np.asarray(t_s, dtype=float)
    temp = np.asarray(temperature_c, dtype=float)
    if t.ndim != 1 or temp.shape != t.shape:
        raise ValueError(f't_s and temperature_c must be 1-D of one length, got {t.shape} '
                         f'and {temp.shape}')
    if not window_s > 0:
        raise ValueError(f'window_s must be > 0, got {window_s!r}')
    if t.size == 0:
        return np.zeros(0)
    # Centre the time axis on the run's start so the running sums keep their precision.
    tc = t - t[0]
    zero = np.zeros(1)
    s_t = np.concatenate([zero, np.cumsum(tc)])
    s_tt = np.concatenate([zero, np.cumsum(tc * tc)])
    s_y = np.concatenate([zero, np.cumsum(temp)])
    s_ty = np.concatenate([zero, np.cumsum(tc * temp)])
    end = np.arange(1, t.size + 1)
    start = np.searchsorted(t, t - window_s, side='left')
    n = end - start
    sum_t = s_t[end] - s_t[start]
    sum_tt = s_tt[end] - s_tt[start]
    sum_y = s_y[end] - s_y[start]
    sum_ty = s_ty[end] - s_ty[start]
    denom = n * sum_tt - sum_t * sum_t
    rate = np.zeros(t.size)
    # denom > 0 exactly when the window holds two distinct stamps; a relative floor guards
    # against cancellation when the stamps are nearly equal.
    ok = denom > 1e-12 * np.maximum(n * sum_tt, 1e-300)
    rate[ok] = (n[ok] * sum_ty[ok] - sum_t[ok] * sum_y[ok]) / denom[ok]
    return rate
