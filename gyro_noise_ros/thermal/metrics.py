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
Honest metrics of a thermal method on a held-out run: noise terms, residual drift, bandwidth cost.

Definitions (docs/thermal.md, "Metrics", states them in full, with the verdict's keys):

* **Angle random walk** N (deg/sqrt(h)) and **bias stability** (deg/h): the one Allan readout
  (:func:`..core.readout.read_allan`) of the overlapping Allan deviation at the ``'dense'`` taus,
  the numbers the offline and live analyzers print: N is the -1/2 line of one contiguous
  white-noise region read at tau = 1 s; bias stability is where the usable curve stops falling
  (*not* divided by 0.664, the IEEE 952 B). Taus flattened by smoothing are left out of both
  (``band_limited_below_s``), so a denoiser cannot show a bias stability read off its smoothing.
* **Residual drift** (deg/s): standard deviation (ddof = 1) of the means of consecutive,
  non-overlapping 60-s windows of the output.
* **Bandwidth cost**: a known rate (a logarithmic chirp over ``f_lo_hz``..``f_hi_hz`` and a train
  of steps) is added to every axis of the held-out run; the method processes the run with and
  without it; the difference is its response. Gain, phase and group delay come from the
  band-averaged cross spectrum ``H = sum(Y conj(X)) / sum(|X|^2)`` over log-spaced bands (20 per
  decade, the bulk delay taken out and put back); the -3 dB bandwidth is the first crossing of
  ``|H| = 1/sqrt(2)`` going up in frequency. The mean normalised step response gives the 50 %
  delay, the 10-90 % rise time, the overshoot, the settled gain and the precursor (> 5 % before
  the step: the method is non-causal).
"""

from collections.abc import Sequence
import dataclasses
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.signal

from .run import ThermalMethod, ThermalRun

from ..core.allan import allan_deviation
from ..core.readout import read_allan
from ..errors import InputDataError, ParameterError
from ..formatting import finite_list as _curve, finite_or_none as _num
from ..units import RAD_TO_DEG

__all__ = ['DEFAULT_AMPLITUDE_RAD_S', 'DEFAULT_F_HI_HZ', 'DEFAULT_F_LO_HZ',
           'DRIFT_WINDOW_S', 'PRECURSOR_LIMIT', 'FrequencyResponse', 'Injection', 'NoiseMetrics',
           'StepResponse', 'evaluate_method', 'frequency_response', 'make_injection',
           'noise_metrics', 'noise_path_gain', 'residual_drift', 'residual_drift_deg_s',
           'step_response',
           'verdict', 'white_floor_deg_s', 'white_noise_sigma', 'yardstick']

#: Window of the residual-drift means (s).
DRIFT_WINDOW_S = 60.0
#: Default amplitude of the injected chirp and steps (rad/s): 1 deg/s.
DEFAULT_AMPLITUDE_RAD_S = math.radians(1.0)
#: Default band of the injected chirp (Hz); the top is capped at 0.45 x the sample rate.
DEFAULT_F_LO_HZ = 0.1
DEFAULT_F_HI_HZ = 50.0
#: Step-response precursor above which a method is called non-causal (fraction of the step).
PRECURSOR_LIMIT = 0.05
#: Bands per decade of the frequency-response estimate.
BANDS_PER_DECADE = 20
#: Seed of the white noise of the noise path (the same noise for every method).
NOISE_PATH_SEED = 20211021

# (tau_s, adev_rad_s) of one axis; (doc, processed, curves) of evaluate_method.
_Adev = tuple[NDArray[np.float64], NDArray[np.float64]]
_Evaluation = tuple[dict[str, Any], NDArray[np.float64], dict[str, dict[str, Any]]]


@dataclass(frozen=True)
class NoiseMetrics:
    """
    Noise read-outs of one axis (definitions in the module docstring).

    Attributes
    ----------
    arw_deg_sqrt_h : float
        Angle random walk (deg/sqrt(h)); NaN when neither a -1/2 region nor tau = 1 s is on the
        curve.
    arw_slope : float
        Free log-log slope of ADEV over the taus N was read from (-0.5 for white rate noise; NaN
        for the ADEV(1 s) reading).
    arw_on_slope : bool
        N comes from a contiguous -1/2 region (False: from ADEV(1 s)).
    bias_stability_deg_h : float
        Bias stability (deg/h), the readout's floor.
    bias_stability_tau_s : float
        Its averaging time (s).
    bias_stability_upper_bound : bool
        The curve was not seen to turn up: an upper bound only.
    band_limited_below_s : float
        Taus below this are flattened by smoothing and left out of the readout (s; 0.0: none).
    residual_drift_deg_s : float
        Std of the 60-s means (deg/s); NaN with fewer than two windows.
    drift_windows : int
        Number of 60-s windows.
    mean_deg_s : float
        Mean of the output (deg/s).

    """

    arw_deg_sqrt_h: float
    arw_slope: float
    arw_on_slope: bool
    bias_stability_deg_h: float
    bias_stability_tau_s: float
    bias_stability_upper_bound: bool
    band_limited_below_s: float
    residual_drift_deg_s: float
    drift_windows: int
    mean_deg_s: float

    def as_dict(self) -> dict[str, Any]:
        """
        Return the JSON form (keys as the attribute names).

        Returns
        -------
        dict

        """
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def noise_metrics(rate_rad_s: ArrayLike, rate_hz: float, *,
                  drift_window_s: float = DRIFT_WINDOW_S) -> NoiseMetrics:
    """
    Compute ARW, bias stability and residual drift of one axis (module docstring).

    ``rate_rad_s`` (n,) is the finite angular rate in rad/s at ``rate_hz``; ``drift_window_s`` the
    window of the residual-drift means (s). Raises InputDataError for fewer than 8 samples or
    non-finite ones.

    """
    return _noise_metrics(rate_rad_s, rate_hz, drift_window_s)[0]


def _noise_metrics(rate_rad_s: ArrayLike, rate_hz: float,
                   drift_window_s: float) -> tuple[NoiseMetrics, _Adev]:
    """Return (NoiseMetrics, (tau_s, adev_rad_s))."""
    x = np.asarray(rate_rad_s, dtype=np.float64)
    if x.ndim != 1 or x.size < 8:
        raise InputDataError(f'noise metrics need at least 8 samples of one axis, got shape '
                             f'{x.shape}')
    res = allan_deviation(x, rate_hz, taus='dense')
    tau, adev = res.tau_s, res.adev
    nan = math.nan
    try:
        r = read_allan(res)
    except InputDataError:
        # a constant output (a method that returns its input's mean) has no Allan curve
        r = None
    slope = nan
    if r is not None and r.arw_from_region:
        sel = (tau >= r.arw_tau_range_s[0]) & (tau <= r.arw_tau_range_s[1])
        slope = float(np.polyfit(np.log(tau[sel]), np.log(adev[sel]), 1)[0])
    drift = float(residual_drift_deg_s(x[:, None], rate_hz, window_s=drift_window_s)[0])
    window = int(round(drift_window_s * rate_hz))
    k = x.size // window if window >= 1 else 0
    return NoiseMetrics(
        # rad/sqrt(s) -> deg/sqrt(h): sqrt(3600 s)
        arw_deg_sqrt_h=r.arw_rad_per_sqrt_s * RAD_TO_DEG * 60.0 if r else nan,
        arw_slope=slope,
        arw_on_slope=bool(r and r.arw_from_region),
        bias_stability_deg_h=r.bias_stability_rad_s * RAD_TO_DEG * 3600.0 if r else nan,
        bias_stability_tau_s=r.bias_stability_tau_s if r else nan,
        bias_stability_upper_bound=bool(r and r.bias_stability_upper_bound),
        band_limited_below_s=r.band_limited_below_s if r else nan,
        residual_drift_deg_s=drift, drift_windows=int(k),
        mean_deg_s=float(np.mean(x) * RAD_TO_DEG)), (tau, adev)


def residual_drift(values: ArrayLike, rate_hz: float, *,
                   window_s: float = DRIFT_WINDOW_S) -> NDArray[np.float64]:
    """
    Return the residual drift of each column: the std (ddof 1) of consecutive window means.

    Parameters
    ----------
    values : array_like
        Samples (n, m), any unit (the result is in it).
    rate_hz : float
        Sample rate (Hz).
    window_s : float, keyword-only
        Window of the means (s).

    Returns
    -------
    numpy.ndarray
        (m,); NaN with fewer than two whole windows.

    """
    x = np.asarray(values, dtype=np.float64)
    window = int(round(window_s * rate_hz))
    k = x.shape[0] // window if window >= 1 else 0
    if k < 2:
        return np.full(x.shape[1], math.nan)
    means = x[:k * window].reshape(k, window, -1).mean(axis=1)
    return np.std(means, axis=0, ddof=1)


def residual_drift_deg_s(rate_rad_s: ArrayLike, rate_hz: float, *,
                         window_s: float = DRIFT_WINDOW_S) -> NDArray[np.float64]:
    """
    Return :func:`residual_drift` of an angular rate (n, m) in rad/s as deg/s per axis (m,).

    ``rate_hz`` and ``window_s`` as in :func:`residual_drift`.

    """
    return residual_drift(rate_rad_s, rate_hz, window_s=window_s) * RAD_TO_DEG


def white_floor_deg_s(arw_deg_sqrt_h: ArrayLike, *,
                      window_s: float = DRIFT_WINDOW_S) -> NDArray[np.float64]:
    """
    Return the noise floor of the residual drift (deg/s per axis) from the run's angle random walk.

    ``N / sqrt(window_s)``: the standard deviation of a ``window_s`` mean of white rate noise whose
    Allan coefficient N is ``arw_deg_sqrt_h`` (deg/sqrt(h); NaN in, NaN out). It leaves out slow
    noise and noise above the readout's taus (docs/thermal.md, the yardstick).

    """
    # deg/sqrt(h) -> deg/sqrt(s): / sqrt(3600 s/h) = / 60
    return np.asarray(arw_deg_sqrt_h, dtype=float) / 60.0 / math.sqrt(window_s)


def yardstick(residual_deg_s: ArrayLike, floor_deg_s: ArrayLike, *,
              poly3_deg_s: ArrayLike | None = None, floor: str = 'white') -> dict[str, Any]:
    """
    Put residual drifts against the noise floor and against poly3's, per axis.

    Parameters
    ----------
    residual_deg_s : array_like
        A method's residual drift per axis (deg/s).
    floor_deg_s : array_like
        The noise floor per axis (deg/s): :func:`white_floor_deg_s` of the run's ARW, or a
        simulated run's own noise through :func:`residual_drift_deg_s`.
    poly3_deg_s : array_like, optional, keyword-only
        poly3's residual drift on the same run per axis (deg/s).
    floor : str, keyword-only
        Which floor: ``'white'`` (white noise of the run, a lower bound) or ``'noise'`` (the
        run's whole noise, known for a simulated run).

    Returns
    -------
    dict
        ``floor`` (the kind), ``floor_deg_s``, ``over_floor`` (residual / floor; the std of k
        window means scatters by about 1 / sqrt(2 (k - 1)) of itself, so a short run's ratio
        can fall below 1), and with
        poly3 ``poly3_deg_s`` and ``over_poly3`` (residual / poly3's: 0.2 is 5 times better),
        lists per axis, None where not finite; ``mean_over_floor``, ``mean_over_poly3``.

    """
    res = np.asarray(residual_deg_s, dtype=float)
    flo = np.asarray(floor_deg_s, dtype=float)
    with np.errstate(divide='ignore', invalid='ignore'):
        over = res / flo
        out: dict[str, Any] = {'floor': floor, 'floor_deg_s': _curve(flo),
                               'over_floor': _curve(over),
                               'mean_over_floor': _num(np.mean(over))}
        if poly3_deg_s is not None:
            p3 = np.asarray(poly3_deg_s, dtype=float)
            out.update(poly3_deg_s=_curve(p3), over_poly3=_curve(res / p3),
                       mean_over_poly3=_num(np.mean(res / p3)))
    return out


@dataclass(frozen=True)
class Injection:
    """
    A known rate signal to add to a run, and where its parts lie.

    Attributes
    ----------
    signal_rad_s : numpy.ndarray
        The injected rate (n,), rad/s.
    chirp : slice
        Samples of the analysis window around the chirp (the chirp plus margins of zeros).
    step_edges : numpy.ndarray
        Sample index of each step edge (int64).
    step_deltas_rad_s : numpy.ndarray
        Rate change at each edge (rad/s).
    step_window : int
        Samples analysed before and after each edge.
    f_lo_hz, f_hi_hz : float
        Band the chirp covers and the response is reported over (Hz).
    amplitude_rad_s : float
        Chirp amplitude and step height (rad/s).

    """

    signal_rad_s: np.ndarray
    chirp: slice
    step_edges: np.ndarray
    step_deltas_rad_s: np.ndarray
    step_window: int
    f_lo_hz: float
    f_hi_hz: float
    amplitude_rad_s: float


def make_injection(n: int, rate_hz: float, *, amplitude_rad_s: float = DEFAULT_AMPLITUDE_RAD_S,
                   f_lo_hz: float = DEFAULT_F_LO_HZ, f_hi_hz: float = DEFAULT_F_HI_HZ,
                   chirp_s: float = 300.0, hold_s: float = 20.0, steps: int = 6) -> Injection:
    """
    Build the injected rate: a logarithmic chirp, then a train of steps 0 -> A -> 0 -> ...

    The chirp starts at 25 % of the run, the steps at 60 %; both shrink to fit a short run
    (chirp at most 30 % of it, the step train at most 30 %). The chirp sweeps from
    0.8 x ``f_lo_hz`` to ``f_hi_hz`` / 0.8 (capped at 0.45 x ``rate_hz``) under a 5 % Tukey
    taper so the reported band is well excited.

    Parameters
    ----------
    n : int
        Samples of the run.
    rate_hz : float
        Sample rate (Hz).
    amplitude_rad_s : float, keyword-only
        Chirp amplitude and step height (rad/s).
    f_lo_hz, f_hi_hz : float, keyword-only
        Reported band (Hz); ``f_hi_hz`` is lowered to 0.45 x ``rate_hz`` / 1.25 if needed.
    chirp_s : float, keyword-only
        Chirp duration on a long run (s).
    hold_s : float, keyword-only
        Hold of each step on a long run (s).
    steps : int, keyword-only
        Number of step edges (even: the train ends at 0).

    Returns
    -------
    Injection

    Raises
    ------
    ParameterError
        Bad band, amplitude or a run too short (under 20 chirp periods of ``f_lo_hz``).

    """
    if not (amplitude_rad_s > 0 and math.isfinite(amplitude_rad_s)):
        raise ParameterError(f'injection amplitude must be > 0 rad/s, got {amplitude_rad_s!r}')
    f_top = 0.45 * rate_hz / 1.25
    f_hi = min(float(f_hi_hz), f_top)
    if not 0 < f_lo_hz < f_hi:
        raise ParameterError(f'injection band must satisfy 0 < f_lo < f_hi <= {f_top:.4g} Hz '
                             f'(0.36 x the {rate_hz:.4g} Hz sample rate), got {f_lo_hz!r}..'
                             f'{f_hi_hz!r} Hz')
    duration = n / rate_hz
    c_s = min(chirp_s, 0.3 * duration)
    if c_s * f_lo_hz < 20:
        raise ParameterError(f'the run ({duration:.4g} s) is too short to measure the response '
                             f'down to {f_lo_hz:g} Hz: the chirp needs at least '
                             f'{20 / f_lo_hz / 0.3:.4g} s of run; raise {{f_lo_hz}}',
                             parameters=('f_lo_hz',))
    sig = np.zeros(n)
    c0 = int(0.25 * n)
    c_n = int(round(c_s * rate_hz))
    t = np.arange(c_n) / rate_hz
    f0, f1 = 0.8 * f_lo_hz, min(f_hi / 0.8, 0.45 * rate_hz)
    sig[c0:c0 + c_n] = (amplitude_rad_s * scipy.signal.windows.tukey(c_n, 0.05)
                        * scipy.signal.chirp(t, f0, t[-1], f1, method='logarithmic', phi=-90))
    margin = int(0.1 * c_n)
    chirp = slice(max(c0 - margin, 0), min(c0 + c_n + margin, n))
    steps = max(2, int(steps) // 2 * 2)
    hold = int(round(min(hold_s, 0.3 * duration / steps) * rate_hz))
    if hold < 4:
        raise ParameterError(f'the run ({duration:.4g} s) is too short for {steps} steps')
    s0 = int(0.6 * n)
    edges = s0 + hold * np.arange(steps, dtype=np.int64)
    deltas = np.where(np.arange(steps) % 2 == 0, 1.0, -1.0) * amplitude_rad_s
    for e, d in zip(edges, deltas):
        sig[e:] += d
    return Injection(signal_rad_s=sig, chirp=chirp, step_edges=edges, step_deltas_rad_s=deltas,
                     step_window=hold // 2, f_lo_hz=float(f_lo_hz), f_hi_hz=float(f_hi),
                     amplitude_rad_s=float(amplitude_rad_s))


@dataclass(frozen=True)
class FrequencyResponse:
    """
    Band-averaged frequency response of a method to injected motion.

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        Band centres (geometric), Hz.
    gain : numpy.ndarray
        ``|H|`` (1 = passed unchanged).
    phase_deg : numpy.ndarray
        ``angle(H)``, unwrapped, degrees (negative = lag).
    group_delay_s : numpy.ndarray
        ``-d phase / d omega`` (s).
    coherence : numpy.ndarray
        Band-averaged magnitude-squared coherence of response and input (1 = linear, noise-free).
    minus_3db_hz : float or None
        First crossing of gain 1/sqrt(2) going up in frequency; None if not inside the band.
    minus_3db_bound : str
        'measured', 'below' (already below -3 dB at the lowest band) or 'above' (never below).

    """

    frequency_hz: np.ndarray
    gain: np.ndarray
    phase_deg: np.ndarray
    group_delay_s: np.ndarray
    coherence: np.ndarray
    minus_3db_hz: object
    minus_3db_bound: str

    def gain_at(self, f_hz: float) -> float:
        """Interpolate the gain at ``f_hz`` (Hz), linearly in log frequency."""
        return float(np.interp(np.log(f_hz), np.log(self.frequency_hz), self.gain))


def frequency_response(injected: ArrayLike, response: ArrayLike, rate_hz: float, *, f_lo_hz: float,
                       f_hi_hz: float,
                       bands_per_decade: int = BANDS_PER_DECADE) -> FrequencyResponse:
    """
    Estimate H(f) = response / injected from one record by band-averaged cross spectra.

    Parameters
    ----------
    injected, response : array_like
        Input and response (n,), same unit.
    rate_hz : float
        Sample rate (Hz).
    f_lo_hz, f_hi_hz : float, keyword-only
        Band reported (Hz).
    bands_per_decade : int, keyword-only
        Log-spaced bands per decade.

    Returns
    -------
    FrequencyResponse

    """
    x = np.asarray(injected, dtype=float)
    y = np.asarray(response, dtype=float)
    xf, yf = np.fft.rfft(x), np.fft.rfft(y)
    f = np.fft.rfftfreq(x.size, 1.0 / rate_hz)
    # Averaging H over a band blurs a steep phase: a delay of d s turns by 2 pi f d across it.
    # Take out the bulk delay (the cross-correlation peak, whole samples) first, put it back after.
    xcorr = np.fft.irfft(yf * np.conj(xf), n=x.size)
    lag = int(np.argmax(np.abs(xcorr)))
    if lag > x.size // 2:
        lag -= x.size
    turn = np.exp(2j * np.pi * f * lag / rate_hz)
    yf = yf * turn
    n_b = max(int(math.ceil(math.log10(f_hi_hz / f_lo_hz) * bands_per_decade)), 1)
    edges = f_lo_hz * (f_hi_hz / f_lo_hz) ** (np.arange(n_b + 1) / n_b)
    centres, hs, coh = [], [], []
    sxy_all = yf * np.conj(xf)
    sxx_all = np.abs(xf) ** 2
    syy_all = np.abs(yf) ** 2
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (f >= lo) & (f < hi)
        if not sel.any():
            continue
        sxx = sxx_all[sel].sum()
        if sxx <= 0:
            continue
        sxy = sxy_all[sel].sum()
        syy = syy_all[sel].sum()
        centres.append(math.sqrt(lo * hi))
        hs.append(sxy / sxx * np.exp(-2j * np.pi * centres[-1] * lag / rate_hz))
        coh.append(float(abs(sxy) ** 2 / (sxx * syy)) if syy > 0 else 0.0)
    freq = np.array(centres)
    h = np.array(hs, dtype=complex)
    gain = np.abs(h)
    phase = np.unwrap(np.angle(h))
    delay = (-np.gradient(phase, 2 * np.pi * freq) if freq.size > 1
             else np.full(freq.size, math.nan))
    limit = 1.0 / math.sqrt(2.0)
    below = np.flatnonzero(gain < limit)
    if below.size == 0:
        f3, bound = None, 'above'
    elif below[0] == 0:
        f3, bound = None, 'below'
    else:
        j = below[0]
        g0, g1 = 20 * np.log10(gain[j - 1]), 20 * np.log10(gain[j])
        target = 20 * math.log10(limit)
        frac = (target - g0) / (g1 - g0)
        f3 = float(np.exp(np.log(freq[j - 1]) + frac * (np.log(freq[j]) - np.log(freq[j - 1]))))
        bound = 'measured'
    return FrequencyResponse(frequency_hz=freq, gain=gain, phase_deg=np.degrees(phase),
                             group_delay_s=delay, coherence=np.array(coh), minus_3db_hz=f3,
                             minus_3db_bound=bound)


@dataclass(frozen=True)
class StepResponse:
    """
    Mean normalised response to the injected steps (0 before, 1 after for a perfect pass).

    Attributes
    ----------
    t_s : numpy.ndarray
        Time from the step (s), which happens half a sample before the edge sample.
    response : numpy.ndarray
        Mean normalised response.
    delay_50_s : float
        First time the response reaches 0.5 (s; negative: before the step). NaN if never.
    rise_time_s : float
        10 % to 90 % rise time (s); NaN if 90 % is never reached.
    overshoot : float
        Peak after the edge minus 1 (fraction of the step, >= 0 reported as measured).
    settled_gain : float
        Mean response over the last half of the window after the edge.
    precursor : float
        Largest change of the response over the last fifth of the window before the edge
        (fraction of the step; 0 for a causal method).
    lead_s : float
        How long before the step the response first moves by more than
        :data:`PRECURSOR_LIMIT` of it from its level at the window's start (s; 0 when it does
        not move before the step): the look-ahead the method uses, i.e. the latency a causal
        version of it would have to add.

    """

    t_s: np.ndarray
    response: np.ndarray
    delay_50_s: float
    rise_time_s: float
    overshoot: float
    settled_gain: float
    precursor: float
    lead_s: float = 0.0


def _first_crossing(t: NDArray[np.floating[Any]], r: NDArray[np.floating[Any]],
                    level: float) -> float:
    idx = np.flatnonzero(r >= level)
    if idx.size == 0:
        return math.nan
    j = int(idx[0])
    if j == 0:
        return float(t[0])
    return float(t[j - 1] + (level - r[j - 1]) / (r[j] - r[j - 1]) * (t[j] - t[j - 1]))


def step_response(response: ArrayLike, rate_hz: float, edges: NDArray[np.int64] | Sequence[int],
                  deltas: NDArray[np.float64] | Sequence[float],
                  window: int) -> StepResponse:
    """
    Average the response around each step edge, normalised by the step.

    Parameters
    ----------
    response : array_like
        Output difference (n,) caused by the injection.
    rate_hz : float
        Sample rate (Hz).
    edges : array_like of int
        Edge sample indices.
    deltas : array_like of float
        Step heights (same unit as ``response``).
    window : int
        Samples analysed before and after each edge (the mean of the first fifth of the window
        is the baseline).

    Returns
    -------
    StepResponse

    """
    y = np.asarray(response, dtype=float)
    tail = max(window // 5, 1)
    segs = []
    for e, d in zip(edges, deltas):
        seg = y[int(e) - window:int(e) + window]
        # Baseline: the response at the start of the window, not the injected level, so a method
        # passing a fraction g of slow motion shows g on every edge.
        segs.append((seg - seg[:tail].mean()) / d)
    r = np.mean(segs, axis=0)
    # The step happens between the last sample before the edge and the edge sample.
    t = (np.arange(2 * window) - window + 0.5) / rate_hz
    after = t >= 0
    # Causal responses still settling from the previous edge drift slowly before this one; a
    # response to this edge before it happens changes quickly right before it. Compare the last
    # fifth of the window before the edge with the sample just before that stretch.
    pre = r[window - tail:window] - r[window - tail - 1] if window > tail else np.zeros(0)
    post_t, post = t[after], r[after]
    t10 = _first_crossing(post_t, post, 0.1)
    t90 = _first_crossing(post_t, post, 0.9)
    d50 = _first_crossing(t, r, 0.5)
    # the look-ahead: after the last sample before the edge still within the limit of the
    # starting level (the baseline is the first fifth of the window)
    quiet = np.flatnonzero(np.abs(r[:window]) <= PRECURSOR_LIMIT)
    if quiet.size == 0:
        lead = float(-t[0])
    elif quiet[-1] == window - 1:
        lead = 0.0
    else:
        lead = float(-t[quiet[-1] + 1])
    # a non-causal filter crosses 50 % before the edge; report that crossing, from the full window
    return StepResponse(t_s=t, response=r, delay_50_s=d50, rise_time_s=t90 - t10,
                        overshoot=float(post.max() - 1.0),
                        settled_gain=float(post[post.size // 2:].mean()),
                        precursor=float(np.abs(pre).max()) if pre.size else 0.0, lead_s=lead)


def _axis_bandwidth(injection: Injection, diff: NDArray[np.float64],
                    rate_hz: float) -> tuple[FrequencyResponse, StepResponse]:
    sl = injection.chirp
    fr = frequency_response(injection.signal_rad_s[sl], diff[sl], rate_hz,
                            f_lo_hz=injection.f_lo_hz, f_hi_hz=injection.f_hi_hz)
    st = step_response(diff, rate_hz, injection.step_edges, injection.step_deltas_rad_s,
                       injection.step_window)
    return fr, st


def _band_text(fr: FrequencyResponse) -> str:
    if fr.frequency_hz.size == 0:
        return 'no band measured'
    if fr.minus_3db_bound == 'measured':
        return f'-3 dB at {fr.minus_3db_hz:.3g} Hz'
    return (f'-3 dB {fr.minus_3db_bound} the measured band {fr.frequency_hz[0]:.3g}..'
            f'{fr.frequency_hz[-1]:.3g} Hz')


def _low_gain(fr: FrequencyResponse) -> float:
    # ADEV at tau = 1 s is most sensitive to motion between ~0.1 and ~1 Hz (its transfer function
    # peaks near 0.37 / tau); attenuation there shows up as lower "ARW".
    band = (fr.frequency_hz >= 0.1) & (fr.frequency_hz <= 1.0)
    return float(fr.gain[band].min()) if band.any() else math.nan


def noise_path_gain(injected_rad_s: ArrayLike, response_rad_s: ArrayLike, rate_hz: float) -> float:
    """
    Return the ARW gain of a method on its noise path: ARW of its response over ARW of the input.

    ``injected_rad_s`` is white noise added to a run, ``response_rad_s`` the method's output
    with it minus its output without it. A drift model subtracts the same drift from both, so
    its response is the injected noise itself and the gain is 1 whatever the drift does to the
    ADEV of the output; a denoiser's response is the part of the noise it keeps.

    Parameters
    ----------
    injected_rad_s, response_rad_s : array_like
        (n,) rad/s.
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    float
        ``ARW(response) / ARW(injected)``, both read as in :func:`noise_metrics`.

    """
    a_in = _noise_metrics(injected_rad_s, rate_hz, DRIFT_WINDOW_S)[0].arw_deg_sqrt_h
    a_out = _noise_metrics(response_rad_s, rate_hz, DRIFT_WINDOW_S)[0].arw_deg_sqrt_h
    return a_out / a_in


def verdict(raw: NoiseMetrics, processed: NoiseMetrics, fr: FrequencyResponse, st: StepResponse, *,
            causal: bool, small: tuple[FrequencyResponse, StepResponse, float] | None = None,
            noise_gain: float | None = None) -> dict[str, Any]:
    """
    Say in plain words what a method did to the noise, to the drift and to motion.

    Parameters
    ----------
    raw, processed : NoiseMetrics
        One axis before and after.
    fr : FrequencyResponse
        Response to the chirp.
    st : StepResponse
        Response to the steps.
    causal : bool
        What the method declares.
    small : tuple of (FrequencyResponse, StepResponse, float), optional
        The same at small amplitude, and that amplitude (rad/s).
    noise_gain : float, optional
        :func:`noise_path_gain` of the axis. When given it is the ``arw_ratio`` (drift leaking
        into the output's ADEV near 1 s is not noise removed); ``output_arw_ratio`` keeps the
        ratio of the output's and the input's ARW read-outs either way.

    Returns
    -------
    dict
        ``arw_ratio``, ``output_arw_ratio``, ``arw_source`` ('noise path' or 'output'),
        ``residual_drift_ratio``, ``low_band_min_gain``,
        ``small_signal_low_band_min_gain``, ``arw_from_bandwidth`` (bool), ``measured_causal``
        (bool), ``live_capable`` (bool) and ``text`` (sentences).

    """
    output_ratio = processed.arw_deg_sqrt_h / raw.arw_deg_sqrt_h
    arw_ratio = output_ratio if noise_gain is None else float(noise_gain)
    source = 'output' if noise_gain is None else 'noise path'
    drift_ratio = processed.residual_drift_deg_s / raw.residual_drift_deg_s
    low_gain = _low_gain(fr)
    cut = [f'motion at 0.1-1 Hz passed with gain down to {low_gain:.3g}'] if low_gain < 0.9 else []
    if st.settled_gain < 0.9:
        cut.append(f'a held step passed with {st.settled_gain:.3g}')
    small_gain = math.nan
    if small is not None:
        s_fr, s_st, s_amp = small
        small_gain = _low_gain(s_fr)
        if small_gain < 0.9 or s_st.settled_gain < 0.9:
            cut.append(f'motion of {s_amp * RAD_TO_DEG:.3g} deg/s (the size of the noise) passed '
                       f'with gain down to {min(small_gain, s_st.settled_gain):.3g} '
                       f'({_band_text(s_fr)}): small motion goes with the noise')
    from_bw = bool(arw_ratio < 0.9 and cut)
    measured_causal = bool(st.precursor <= PRECURSOR_LIMIT)
    text = []
    if from_bw:
        text.append(f'ARW ratio {arw_ratio:.3g} ({source}) comes from removing bandwidth, not '
                    f'noise: {"; ".join(cut)} ({_band_text(fr)}).')
    elif arw_ratio < 0.9:
        text.append(f'ARW ratio {arw_ratio:.3g} ({source}) while motion at 0.1-1 Hz keeps gain '
                    f'>= {low_gain:.3g} ({_band_text(fr)}).')
    elif math.isfinite(arw_ratio):
        text.append(f'ARW unchanged (ratio {arw_ratio:.3g}, {source}): no denoising '
                    f'({_band_text(fr)}).')
    else:
        text.append(f'No ARW can be read off the processed Allan curve ({_band_text(fr)}).')
    if (noise_gain is not None and math.isfinite(output_ratio)
            and abs(output_ratio - arw_ratio) > 0.05):
        text.append(f"(The ARW read-out of the output is {output_ratio:.3g} times the input's: "
                    'the difference is drift in the ADEV of the input near 1 s, not noise.)')
    if not processed.arw_on_slope:
        text.append('The processed Allan curve has no -1/2 region: its ARW is only ADEV(1 s).')
    if processed.band_limited_below_s > max(raw.band_limited_below_s, 0.0):
        text.append(f'Its output is smoothed: the Allan deviation is flattened below '
                    f'{processed.band_limited_below_s:.3g} s, so ARW and bias stability are read '
                    'above that, never off the smoothing.')
    text.append(f"Residual drift {drift_ratio:.3g} times the input's.")
    if not measured_causal:
        text.append(f'Responds {st.precursor:.0%} of a step before it happens: non-causal, '
                    'offline only.')
    elif not causal:
        text.append('Declared non-causal (offline only).')
    return {'arw_ratio': _num(arw_ratio), 'output_arw_ratio': _num(output_ratio),
            'arw_source': source, 'residual_drift_ratio': _num(drift_ratio),
            'low_band_min_gain': _num(low_gain),
            'small_signal_low_band_min_gain': _num(small_gain), 'arw_from_bandwidth': from_bw,
            'measured_causal': measured_causal, 'live_capable': bool(causal and measured_causal),
            'text': ' '.join(text)}


def _run_with(run: ThermalRun, gyro: NDArray[np.float64]) -> ThermalRun:
    return dataclasses.replace(run, gyro_rad_s=gyro)


def evaluate_method(method: ThermalMethod, run: ThermalRun, *,
                    amplitude_rad_s: float = DEFAULT_AMPLITUDE_RAD_S,
                    f_lo_hz: float = DEFAULT_F_LO_HZ, f_hi_hz: float = DEFAULT_F_HI_HZ,
                    processed: NDArray[np.float64] | None = None, small_signal: bool = True,
                    noise_path: bool = True) -> _Evaluation:
    """
    Score a fitted method on a held-out run: noise, drift and bandwidth per axis.

    Parameters
    ----------
    method : ThermalMethod
        Fitted method.
    run : ThermalRun
        Held-out run (never the one it was fitted on).
    amplitude_rad_s : float, keyword-only
        Height of the injected chirp and steps (rad/s). Nonlinear methods (thresholding,
        decompositions) respond differently to different amplitudes: state it with the result.
    f_lo_hz, f_hi_hz : float, keyword-only
        Band of the chirp (Hz).
    processed : numpy.ndarray, optional
        ``method.apply(run)`` if already computed.
    small_signal : bool, keyword-only
        Also inject the same signal scaled to the white-noise sigma of the run
        (:func:`white_noise_sigma`) and report ``bandwidth_small_signal``: a nonlinear method
        that passes a large motion may remove a small one (one more ``apply``).
    noise_path : bool, keyword-only
        Also add white noise of the run's own size (:func:`white_noise_sigma`, a fixed seed)
        and take the ARW gain from the method's response to it (:func:`noise_path_gain`, one
        more ``apply``): the verdict's ``arw_ratio``, free of the drift that leaks into the
        output's ADEV near 1 s. Without it the ratio of the output's read-outs is used.

    Returns
    -------
    doc : dict
        JSON-able: ``method``, ``causal``, ``yardstick`` (the processed residual drift against
        the run's white-noise floor, :func:`yardstick`; the caller may replace the floor and add
        poly3), ``injection`` and ``axes`` -> x/y/z -> ``raw``, ``processed``
        (:class:`NoiseMetrics` keys), ``bandwidth`` and ``verdict``.
    processed : numpy.ndarray
        The processed run (n, 3), rad/s.
    curves : dict
        Per axis: ``frequency`` (:class:`FrequencyResponse`), ``step`` (:class:`StepResponse`),
        ``allan_raw`` and ``allan_processed`` ((tau_s, adev_rad_s) arrays), and with
        ``small_signal`` ``frequency_small`` and ``step_small``, for figures.

    """
    gyro = np.asarray(run.gyro_rad_s, dtype=float)
    n = gyro.shape[0]
    inj = make_injection(n, run.rate_hz, amplitude_rad_s=amplitude_rad_s, f_lo_hz=f_lo_hz,
                         f_hi_hz=f_hi_hz)
    if processed is None:
        processed = np.asarray(method.apply(run), dtype=float)
    _check_output(method, processed, n)
    diff = _response(method, run, gyro, processed, inj.signal_rad_s)
    noise_in = noise_diff = None
    if noise_path:
        # a fixed seed: the same noise for every method scored on this run
        noise_in = (white_noise_sigma(gyro)
                    * np.random.default_rng(NOISE_PATH_SEED).standard_normal(gyro.shape))
        noise_diff = _response(method, run, gyro, processed, noise_in)
    small_amp = small_diff = None
    if small_signal:
        small_amp = white_noise_sigma(gyro)
        small_diff = _response(method, run, gyro, processed,
                               inj.signal_rad_s * (small_amp / inj.amplitude_rad_s))
    axes, curves = {}, {}
    for a, name in enumerate('xyz'):
        raw_m, raw_adev = _noise_metrics(gyro[:, a], run.rate_hz, DRIFT_WINDOW_S)
        proc_m, proc_adev = _noise_metrics(processed[:, a], run.rate_hz, DRIFT_WINDOW_S)
        fr, st = _axis_bandwidth(inj, diff[:, a], run.rate_hz)
        curves[name] = {'frequency': fr, 'step': st, 'allan_raw': raw_adev,
                        'allan_processed': proc_adev}
        small = None
        axes[name] = {'raw': _metrics_dict(raw_m), 'processed': _metrics_dict(proc_m),
                      'bandwidth': _bandwidth_dict(fr, st)}
        if small_signal:
            assert small_diff is not None and small_amp is not None
            # The same injection scaled to the noise's size: nonlinear methods (thresholds,
            # decompositions) pass a large motion and remove a small one.
            s_fr, s_st = _axis_bandwidth(inj, small_diff[:, a] * (inj.amplitude_rad_s
                                                                  / small_amp), run.rate_hz)
            small = (s_fr, s_st, small_amp)
            curves[name].update(frequency_small=s_fr, step_small=s_st)
            axes[name]['bandwidth_small_signal'] = dict(
                _bandwidth_dict(s_fr, s_st), amplitude_deg_s=small_amp * RAD_TO_DEG)
        gain = None
        if noise_path:
            assert noise_in is not None and noise_diff is not None
            gain = noise_path_gain(noise_in[:, a], noise_diff[:, a], run.rate_hz)
            axes[name]['noise_path'] = {'arw_gain': _num(gain),
                                        'amplitude_deg_s': _num(np.std(noise_in[:, a])
                                                                * RAD_TO_DEG)}
        axes[name]['verdict'] = verdict(raw_m, proc_m, fr, st, causal=bool(method.causal),
                                        small=small, noise_gain=gain)
    residual = [axes[a]['processed']['residual_drift_deg_s'] for a in 'xyz']
    arw = [axes[a]['raw']['arw_deg_sqrt_h'] for a in 'xyz']
    doc = {
        'method': method.name, 'causal': bool(method.causal),
        'yardstick': yardstick([math.nan if v is None else v for v in residual],
                               white_floor_deg_s([math.nan if v is None else v for v in arw])),
        'injection': {'amplitude_deg_s': inj.amplitude_rad_s * RAD_TO_DEG,
                      'small_signal_amplitude_deg_s': (small_amp * RAD_TO_DEG
                                                       if small_amp is not None else None),
                      'f_lo_hz': inj.f_lo_hz, 'f_hi_hz': inj.f_hi_hz,
                      'noise_path_seed': NOISE_PATH_SEED if noise_path else None,
                      'chirp_start_s': inj.chirp.start / run.rate_hz,
                      'chirp_stop_s': inj.chirp.stop / run.rate_hz,
                      'step_edges_s': _curve(inj.step_edges / run.rate_hz)},
        'axes': axes,
    }
    return doc, processed, curves


def _response(method: ThermalMethod, run: ThermalRun, gyro: NDArray[np.float64],
              processed: NDArray[np.float64], signal: NDArray[np.float64]) -> NDArray[np.float64]:
    add = signal if signal.ndim == 2 else signal[:, None]
    out = np.asarray(method.apply(_run_with(run, gyro + add)), dtype=float)
    _check_output(method, out, gyro.shape[0])
    return out - processed


def _metrics_dict(m: NoiseMetrics) -> dict[str, Any]:
    return {k: _num(v) if isinstance(v, float) else v for k, v in m.as_dict().items()}


def _delay(v: float) -> float | None:
    # a pass-through's 50 % crossing lands on the step time up to rounding (1e-18 s): snap to ns
    return _num(round(v, 9) + 0.0) if math.isfinite(v) else None  # + 0.0: no '-0'


def _bandwidth_dict(fr: FrequencyResponse, st: StepResponse) -> dict[str, Any]:
    return {
        'minus_3db_hz': fr.minus_3db_hz, 'minus_3db_bound': fr.minus_3db_bound,
        'gain_at_1hz': _num(fr.gain_at(1.0)) if fr.frequency_hz.size else None,
        'low_band_min_gain': _num(_low_gain(fr)),
        'step_delay_50_s': _delay(st.delay_50_s), 'step_rise_time_s': _delay(st.rise_time_s),
        'step_overshoot': _num(st.overshoot), 'step_settled_gain': _num(st.settled_gain),
        'step_precursor': _num(st.precursor), 'step_lead_s': _delay(st.lead_s),
        'frequency_hz': _curve(fr.frequency_hz), 'gain': _curve(fr.gain),
        'phase_deg': _curve(fr.phase_deg), 'group_delay_s': _curve(fr.group_delay_s),
        'coherence': _curve(fr.coherence),
    }


def white_noise_sigma(gyro_rad_s: ArrayLike) -> float:
    """
    Estimate the per-sample white-noise standard deviation, median over axes.

    Uses first differences, std(diff(x)) / sqrt(2), which a slow drift does not inflate.

    Parameters
    ----------
    gyro_rad_s : numpy.ndarray
        Rate (n, 3), rad/s.

    Returns
    -------
    float
        rad/s; at least 1e-9 rad/s so a noise-free input still gets a finite injection.

    """
    d = np.diff(np.asarray(gyro_rad_s, dtype=float), axis=0)
    return max(float(np.median(np.std(d, axis=0))) / math.sqrt(2.0), 1e-9)


def _check_output(method: ThermalMethod, out: NDArray[np.float64], n: int) -> None:
    if out.shape != (n, 3):
        raise InputDataError(f'method {method.name!r} returned shape {out.shape}, expected '
                             f'({n}, 3)')
    if not np.isfinite(out).all():
        raise InputDataError(f'method {method.name!r} returned NaN/Inf samples')
