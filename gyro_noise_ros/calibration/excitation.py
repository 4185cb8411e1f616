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
Excitation signal checks of paper 001 section 5.3: sine dwell and sine sweep.

**Sine dwell**: frequency (Hz) and amplitude (the samples' unit) by the IEEE Std 1057
four-parameter sine fit from the FFT peak nearest the nominal frequency; the per-cycle amplitude
(three-parameter fit over each whole cycle) and its spread, the paper's "amplitude stability";
``THD = sqrt(sum_{k=2..H} A_k^2) / A_1`` from a least-squares fit of the harmonics below Nyquist.
Only the excited span is analysed (cycles reaching half the 90th percentile of the amplitudes).

**Sine sweep**: band-pass (zero-phase Butterworth), analytic signal (Hilbert) for the
instantaneous amplitude and frequency, amplitudes averaged in frequency bins, rising and falling
apart; with a reference channel, the deviation ``amplitude / reference - 1`` per bin.

**The record must be what was asked for**: a dwell's fitted frequency within ``frequency_tol``
(relative) of the request, a sweep covering >= 80 % of the requested band; otherwise a
:class:`~gyro_noise_ros.errors.InputDataError` (exit 4).

**Verdicts**, each a test against the record's own noise at false-alarm ``alpha`` *and* a defect
larger than ``tolerance`` (relative, :data:`DEFAULT_TOLERANCE`): *steady* / *unsteady*
(``(n - 1) s^2 / sigma_c^2`` against chi-square(n - 1)); *clean* / *distorted*
(``sum A_k^2 N / (2 sigma^2)`` against chi-square(2 (H - 1))); against a reference, *matches* /
*gain differs* (Student's t) and *flat* / *frequency-dependent* (F). Derivations and the measured
rates: docs/reliability.md section 3 (``docs/scripts/excitation_verdicts.py``).
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import butter, hilbert, sosfiltfilt
from scipy.stats import chi2, f as f_dist, t as t_dist

from ..errors import InputDataError, ParameterError

DEFAULT_HARMONICS = 5
#: Largest relative difference between the requested and the fitted dwell frequency.
DEFAULT_FREQUENCY_TOL = 0.02
#: Least fraction of the requested sweep band the record's frequency must cover.
MIN_SWEEP_COVERAGE = 0.8
#: False-alarm probability of each verdict.
DEFAULT_ALPHA = 1e-3
#: Practical tolerance of each verdict, relative to the amplitude (amplitude stability, THD,
#: gain deviation, spread of the deviation over frequency): 1 %, the uncertainty of a
#: back-to-back comparison against a reference transducer at these frequencies (ISO 16063-21),
#: below which a difference cannot be laid at the sensor's door.
DEFAULT_TOLERANCE = 0.01


def _check(x: ArrayLike, rate_hz: float, name: str = 'samples') -> NDArray[np.float64]:
    arr = np.asarray(x, dtype=np.float64).reshape(-1)
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ParameterError(f'rate_hz must be finite and > 0, got {rate_hz!r}')
    bad = int(np.count_nonzero(~np.isfinite(arr)))
    if bad:
        raise InputDataError(f'{name}: {bad} NaN/Inf samples (first at sample '
                             f'{int(np.argmin(np.isfinite(arr)))}); excitation checks need a '
                             f'gap-free record')
    return arr


def _design(t: NDArray[np.float64], freqs: Sequence[float]) -> NDArray[np.float64]:
    cols = [np.ones_like(t)]
    for f in freqs:
        w = 2.0 * np.pi * f * t
        cols += [np.cos(w), np.sin(w)]
    return np.column_stack(cols)


def sine_fit4(x: ArrayLike, rate_hz: float, frequency_hz: float, *,
              iterations: int = 30) -> tuple[float, float, float, float]:
    """
    Fit ``x = C + A cos(2 pi f t) + B sin(2 pi f t)`` with f free (IEEE Std 1057 4-parameter fit).

    Parameters
    ----------
    x : array_like
        Samples.
    rate_hz : float
        Sample rate (Hz).
    frequency_hz : float
        Starting frequency (Hz); a local method, so within about 1 / (4 T) of the truth for a
        record of T seconds (:func:`sine_dwell` starts from the interpolated FFT peak).
    iterations : int, keyword-only
        Largest number of Gauss-Newton steps.

    Returns
    -------
    (float, float, float, float)
        Frequency (Hz), amplitude, phase (rad, of a sine at t = 0), offset.

    """
    x = np.asarray(x, dtype=np.float64)
    t = np.arange(x.size) / rate_hz
    f = float(frequency_hz)
    for _ in range(iterations):
        w = 2.0 * np.pi * f * t
        c, s = np.cos(w), np.sin(w)
        base = np.column_stack([np.ones_like(t), c, s])
        coef, *_ = np.linalg.lstsq(base, x, rcond=None)
        _, a, b = coef
        deriv = 2.0 * np.pi * t * (-a * s + b * c)
        full = np.column_stack([base, deriv])
        sol, *_ = np.linalg.lstsq(full, x, rcond=None)
        step = sol[3]
        f += step
        if abs(step) < 1e-12 * max(1.0, f):
            break
    coef, *_ = np.linalg.lstsq(_design(t, [f]), x, rcond=None)
    offset, a, b = coef
    return f, float(math.hypot(a, b)), float(math.atan2(a, b)), float(offset)


def _fft_peak(x: NDArray[np.float64], rate_hz: float, near_hz: float) -> float:
    n = x.size
    spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(n)))
    freqs = np.fft.rfftfreq(n, 1.0 / rate_hz)
    band = (freqs > near_hz / 1.5) & (freqs < near_hz * 1.5)
    if not np.any(band):
        return near_hz
    idx = np.flatnonzero(band)
    k = int(idx[np.argmax(spec[band])])
    if 0 < k < spec.size - 1:
        a, b, c = np.log(spec[k - 1:k + 2] + 1e-300)
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
        return float((k + shift) * rate_hz / n)
    return float(freqs[k])


@dataclass(frozen=True)
class DwellResult:
    """
    Sine-dwell analysis of one record.

    Attributes
    ----------
    frequency_hz : float
        Estimated frequency (Hz).
    amplitude : float
        Estimated amplitude (unit of the samples).
    offset : float
        Mean level (unit of the samples; gravity for an accelerometer axis pointing up).
    cycle_amplitude : numpy.ndarray
        Amplitude of each whole cycle of the excited span.
    cycle_amplitude_mean, cycle_amplitude_std, cycle_amplitude_min, cycle_amplitude_max : float
        Its statistics (std with ddof = 1).
    amplitude_stability : float
        ``cycle_amplitude_std / cycle_amplitude_mean`` (relative).
    harmonics : numpy.ndarray
        Amplitudes of harmonics 1..H below Nyquist.
    thd : float
        Total harmonic distortion (ratio, not %).
    residual_rms : float
        RMS of what the harmonic fit leaves (noise).
    start_s, duration_s : float
        Excited span analysed (s from the first sample).
    cycles : int
        Whole cycles in it.
    frequency_sigma_hz, amplitude_sigma : float
        Standard errors of the fitted frequency (Hz) and amplitude (white residual assumed).
    stability_noise : float
        The amplitude stability white noise alone would give (relative).
    stability_p, distortion_p : float
        p-values of the steadiness and distortion tests (module docstring).
    thd_noise : float
        The THD white noise alone would show, on average (ratio).
    alpha : float
        False-alarm probability of the verdicts.
    tolerance : float
        Practical tolerance of the verdicts (relative: amplitude stability, THD).

    """

    frequency_hz: float
    amplitude: float
    offset: float
    cycle_amplitude: np.ndarray
    cycle_amplitude_mean: float
    cycle_amplitude_std: float
    cycle_amplitude_min: float
    cycle_amplitude_max: float
    amplitude_stability: float
    harmonics: np.ndarray
    thd: float
    residual_rms: float
    start_s: float
    duration_s: float
    cycles: int
    frequency_sigma_hz: float = float('nan')
    amplitude_sigma: float = float('nan')
    stability_noise: float = float('nan')
    stability_p: float = float('nan')
    distortion_p: float = float('nan')
    thd_noise: float = float('nan')
    alpha: float = DEFAULT_ALPHA
    tolerance: float = DEFAULT_TOLERANCE

    @property
    def steady(self) -> bool:
        """bool: the cycle amplitudes scatter within noise, or by no more than the tolerance."""
        return not (self.stability_p < self.alpha and self.amplitude_stability > self.tolerance)

    @property
    def clean(self) -> bool:
        """bool: no harmonic stands out of the noise, or the THD is within the tolerance."""
        return not (self.distortion_p < self.alpha and self.thd > self.tolerance)


def _cycle_amplitudes(x: NDArray[np.float64], rate_hz: float,
                      f: float) -> tuple[NDArray[np.float64], NDArray[np.int64], float]:
    per = rate_hz / f
    n_cyc = int(x.size // per)
    amps = np.empty(n_cyc)
    starts = np.empty(n_cyc, dtype=np.int64)
    for k in range(n_cyc):
        lo = int(round(k * per))
        hi = int(round((k + 1) * per))
        t = np.arange(lo, hi) / rate_hz
        coef, *_ = np.linalg.lstsq(_design(t, [f]), x[lo:hi], rcond=None)
        amps[k] = math.hypot(coef[1], coef[2])
        starts[k] = lo
    return amps, starts, per


def sine_dwell(x: ArrayLike, rate_hz: float, frequency_hz: float, *,
               harmonics: int = DEFAULT_HARMONICS, frequency_tol: float = DEFAULT_FREQUENCY_TOL,
               alpha: float = DEFAULT_ALPHA, tolerance: float = DEFAULT_TOLERANCE) -> DwellResult:
    """
    Analyse a sine-dwell record (paper 001 section 5.3, Figures 7, 8, 10, 11).

    Parameters
    ----------
    x : array_like
        Samples of the excited axis (m/s^2 or rad/s).
    rate_hz : float
        Sample rate (Hz).
    frequency_hz : float
        Nominal excitation frequency (Hz), below Nyquist.
    harmonics : int, keyword-only
        Harmonics used for the THD (those at or above Nyquist are left out).
    frequency_tol : float, keyword-only
        Largest relative difference between ``frequency_hz`` and the fitted frequency.
    alpha : float, keyword-only
        False-alarm probability of the steadiness and distortion verdicts.
    tolerance : float, keyword-only
        Their practical tolerance (relative amplitude stability, THD).

    Returns
    -------
    DwellResult

    Raises
    ------
    ParameterError
        Frequency at or above Nyquist.
    InputDataError
        NaN/Inf, fewer than 3 cycles, no sine at that frequency above the noise, or a sine at
        another frequency than requested.

    """
    x = _check(x, rate_hz)
    f0 = float(frequency_hz)
    if not (math.isfinite(f0) and 0 < f0 < rate_hz / 2.0):
        raise ParameterError(f'{{frequency_hz}} frequency must be in (0, {rate_hz / 2:g}) Hz '
                             f'(Nyquist), got {frequency_hz!r}', parameters=('frequency_hz',))
    if not (math.isfinite(frequency_tol) and frequency_tol > 0):
        raise ParameterError(f'frequency tolerance must be > 0, got {frequency_tol!r}')
    if x.size < 3 * rate_hz / f0:
        raise InputDataError(f'record of {x.size} samples holds fewer than 3 cycles at {f0:g} Hz')
    amps, starts, per = _cycle_amplitudes(x, rate_hz, _fft_peak(x, rate_hz, f0))
    ref = np.percentile(amps, 90)
    on = np.flatnonzero(amps >= 0.5 * ref)
    lo, hi = int(starts[on[0]]), int(starts[on[-1]] + round(per))
    seg = x[lo:hi]
    f, amp, _, offset = sine_fit4(seg, rate_hz, _fft_peak(seg, rate_hz, f0))
    cyc, _, _ = _cycle_amplitudes(seg, rate_hz, f)
    t = np.arange(seg.size) / rate_hz
    ks = [k for k in range(1, int(harmonics) + 1) if k * f < rate_hz / 2.0]
    coef, *_ = np.linalg.lstsq(_design(t, [k * f for k in ks]), seg, rcond=None)
    h = np.hypot(coef[1::2], coef[2::2])
    resid = seg - _design(t, [k * f for k in ks]) @ coef
    rms = float(np.sqrt(np.mean(resid ** 2)))
    # a sine must stand clear of the noise: its rms (A / sqrt 2) above 3 x the residual rms per
    # ~sqrt(samples) would be a weak criterion; require A > 3 residual rms / sqrt(cycle samples)
    if h[0] < 3.0 * rms / math.sqrt(max(per, 1.0)) or abs(f - f0) > 0.2 * f0:
        raise InputDataError(f'no sine at {f0:g} Hz above the noise (amplitude {h[0]:.3g}, '
                             f'noise rms {rms:.3g})')
    n = seg.size
    # 4-parameter fit: frequency standard error from its Gauss-Newton covariance
    w = 2.0 * np.pi * f * t
    deriv = 2.0 * np.pi * t * (-coef[1] * np.sin(w) + coef[2] * np.cos(w))
    jac = np.column_stack([np.ones(n), np.cos(w), np.sin(w), deriv])
    try:
        f_sig = rms * math.sqrt(float(np.linalg.inv(jac.T @ jac)[3, 3]))
    except np.linalg.LinAlgError:
        f_sig = float('nan')
    if abs(f - f0) > max(frequency_tol * f0, 5.0 * f_sig):
        raise InputDataError(
            f'the record holds a sine at {f:.4g} Hz, not the requested {{frequency_hz}} {f0:g} Hz '
            f'(tolerance {100 * frequency_tol:g} %): another record, or another frequency?',
            parameters=('frequency_hz',))
    mean = float(cyc.mean())
    std = float(cyc.std(ddof=1)) if cyc.size > 1 else float('nan')
    sigma_c = rms * math.sqrt(2.0 / per)          # one cycle's amplitude from white noise
    stab_p = (float(chi2.sf((cyc.size - 1) * std ** 2 / sigma_c ** 2, cyc.size - 1))
              if cyc.size > 1 and sigma_c > 0 else float('nan'))
    dof = 2 * (len(ks) - 1)
    var_coef = 2.0 * rms ** 2 / n                 # each harmonic coefficient, white noise
    dist_p = (float(chi2.sf(float(np.sum(h[1:] ** 2)) / var_coef, dof))
              if dof > 0 and var_coef > 0 else float('nan'))
    return DwellResult(
        frequency_hz=float(f), amplitude=float(h[0]), offset=float(coef[0]), cycle_amplitude=cyc,
        cycle_amplitude_mean=mean, cycle_amplitude_std=std,
        cycle_amplitude_min=float(cyc.min()), cycle_amplitude_max=float(cyc.max()),
        amplitude_stability=std / mean if mean > 0 else float('nan'), harmonics=h,
        thd=float(np.sqrt(np.sum(h[1:] ** 2)) / h[0]), residual_rms=rms,
        start_s=lo / rate_hz, duration_s=seg.size / rate_hz, cycles=int(cyc.size),
        frequency_sigma_hz=f_sig, amplitude_sigma=math.sqrt(var_coef),
        stability_noise=sigma_c / mean if mean > 0 else float('nan'), stability_p=stab_p,
        distortion_p=dist_p, thd_noise=math.sqrt(dof * var_coef) / h[0], alpha=float(alpha),
        tolerance=_tolerance(tolerance))


def _tolerance(value: float) -> float:
    """Return a verdict's practical tolerance, checked (a fraction >= 0)."""
    if not (math.isfinite(value) and value >= 0):
        raise ParameterError(f'{{tolerance}} must be a fraction >= 0, got {value!r}',
                             parameters=('tolerance',))
    return float(value)


@dataclass(frozen=True)
class SweepResult:
    """
    Sine-sweep analysis of one record.

    Attributes
    ----------
    bin_hz : numpy.ndarray
        Centres of the frequency bins (Hz).
    amplitude_up, amplitude_down : numpy.ndarray
        Mean instantaneous amplitude per bin for rising / falling frequency (NaN: no samples).
    reference_up, reference_down : numpy.ndarray or None
        The same for the reference channel.
    deviation_up, deviation_down : numpy.ndarray or None
        ``amplitude / reference - 1`` per bin.
    t_s, inst_frequency_hz, inst_amplitude : numpy.ndarray
        Decimated time series of the instantaneous frequency and amplitude (for figures).
    frequency_range_hz : (float, float)
        5th and 95th percentiles of the instantaneous frequency over the excited span (Hz).
    mean_deviation, mean_deviation_sigma : float
        Mean of the per-bin deviations and its standard error (NaN without a reference or with
        fewer than 3 bins seen both rising and falling).
    bin_deviation_sigma : float
        Noise of one bin's deviation (rising minus falling scatter over sqrt 2).
    gain_p, flatness_p : float
        p-values of "matches the reference" and "flat" (module docstring).
    deviation_spread : float
        RMS of the per-bin deviations about their mean (relative; NaN without a reference).
    alpha : float
        False-alarm probability of the verdicts.
    tolerance : float
        Practical tolerance of the verdicts (relative gain deviation, spread).

    """

    bin_hz: np.ndarray
    amplitude_up: np.ndarray
    amplitude_down: np.ndarray
    reference_up: np.ndarray | None
    reference_down: np.ndarray | None
    deviation_up: np.ndarray | None
    deviation_down: np.ndarray | None
    t_s: np.ndarray
    inst_frequency_hz: np.ndarray
    inst_amplitude: np.ndarray
    frequency_range_hz: tuple[float, float] = (float('nan'), float('nan'))
    mean_deviation: float = float('nan')
    mean_deviation_sigma: float = float('nan')
    bin_deviation_sigma: float = float('nan')
    gain_p: float = float('nan')
    flatness_p: float = float('nan')
    deviation_spread: float = float('nan')
    alpha: float = DEFAULT_ALPHA
    tolerance: float = DEFAULT_TOLERANCE

    @property
    def matches_reference(self) -> bool | None:
        """Whether the mean deviation is within noise or the tolerance (None: no reference)."""
        if math.isnan(self.gain_p):
            return None
        return not (self.gain_p < self.alpha and abs(self.mean_deviation) > self.tolerance)

    @property
    def flat(self) -> bool | None:
        """Whether the deviation stays flat within noise or the tolerance (None: no reference)."""
        if math.isnan(self.flatness_p):
            return None
        return not (self.flatness_p < self.alpha and self.deviation_spread > self.tolerance)


def _instantaneous(x: NDArray[np.float64], rate_hz: float, f_lo: float,
                   f_hi: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    nyq = rate_hz / 2.0
    lo = max(f_lo / 2.0, 1e-3)
    hi = min(f_hi * 2.0, 0.95 * nyq)
    sos = butter(4, [lo / nyq, hi / nyq], btype='bandpass', output='sos')
    y = sosfiltfilt(sos, x - x.mean())
    z = hilbert(y)
    amp = np.abs(z)
    phase = np.unwrap(np.angle(z))
    freq = np.gradient(phase) * rate_hz / (2.0 * np.pi)
    return amp, freq


def _smooth(v: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    if n <= 1:
        return v
    k = np.ones(n) / n
    return np.convolve(v, k, mode='same')


def sine_sweep(x: ArrayLike, rate_hz: float, f0_hz: float, f1_hz: float, sweep_rate_hz_s: float,
               *, reference: ArrayLike | None = None, bins: int | None = None,
               alpha: float = DEFAULT_ALPHA, tolerance: float = DEFAULT_TOLERANCE) -> SweepResult:
    """
    Analyse a sine-sweep record (paper 001 section 5.3, Figures 9 and 12).

    Parameters
    ----------
    x : array_like
        Samples of the excited axis.
    rate_hz : float
        Sample rate (Hz).
    f0_hz, f1_hz : float
        Sweep band (Hz), below Nyquist.
    sweep_rate_hz_s : float
        Sweep rate (Hz/s), used to smooth the instantaneous frequency over 1/rate of a Hz.
    reference : array_like, optional, keyword-only
        Reference channel on the same time base (the shaker's feedback sensor).
    bins : int, optional, keyword-only
        Number of frequency bins across the band (default: one per 0.25 Hz, at least 4).
    alpha : float, keyword-only
        False-alarm probability of the verdicts against the reference.
    tolerance : float, keyword-only
        Their practical tolerance (relative gain deviation, spread over frequency).

    Returns
    -------
    SweepResult

    Raises
    ------
    ParameterError
        A band not below Nyquist, a rate <= 0, a reference of another length.
    InputDataError
        NaN/Inf, fewer than 3 cycles, or a record whose frequency does not sweep the band.

    """
    x = _check(x, rate_hz)
    lo, hi = sorted((float(f0_hz), float(f1_hz)))
    if not (lo > 0 and hi < rate_hz / 2.0 and hi > lo):
        raise ParameterError(f'sweep band must lie in (0, {rate_hz / 2:g}) Hz with F0 != F1, '
                             f'got {f0_hz!r}..{f1_hz!r}')
    if not (math.isfinite(sweep_rate_hz_s) and sweep_rate_hz_s > 0):
        raise ParameterError(f'sweep rate must be > 0 Hz/s, got {sweep_rate_hz_s!r}')
    if x.size < 3 * rate_hz / lo:
        raise InputDataError(f'record of {x.size} samples is shorter than 3 cycles at {lo:g} Hz')
    nb = bins or max(4, int(round((hi - lo) / 0.25)))
    edges = np.linspace(lo, hi, nb + 1)
    centres = (edges[:-1] + edges[1:]) / 2.0
    amp, freq = _instantaneous(x, rate_hz, lo, hi)
    # smooth over one cycle of the lowest frequency, direction over ~0.2 Hz of sweep
    fs = _smooth(freq, max(1, int(rate_hz / lo)))
    edge0 = int(2 * rate_hz / lo)
    inner = slice(edge0, max(edge0 + 1, x.size - edge0))
    excited = amp[inner] >= 0.5 * np.percentile(amp[inner], 90)
    f_lo, f_hi = (float(v) for v in np.percentile(fs[inner][excited], [5, 95]))
    covered = max(0.0, min(f_hi, hi) - max(f_lo, lo))
    if covered < MIN_SWEEP_COVERAGE * (hi - lo):
        hint = (f'a sine dwell? ({{frequency_hz}} {np.median(fs[inner][excited]):.3g})'
                if f_hi - f_lo < 0.1 * (hi - lo) else 'another band?')
        raise InputDataError(f'the record does not sweep {lo:g}-{hi:g} Hz: its frequency stays '
                             f'within {f_lo:.3g}-{f_hi:.3g} Hz, {hint}',
                             parameters=('frequency_hz',))
    direction = np.sign(np.gradient(_smooth(fs, max(1, int(rate_hz * 0.2 / sweep_rate_hz_s)))))
    valid = np.zeros(x.size, dtype=bool)
    valid[inner] = True                   # Hilbert / filter edge effects
    valid &= (fs >= lo) & (fs <= hi)

    def binned(a: NDArray[np.float64], sel: NDArray[np.bool_]) -> NDArray[np.float64]:
        idx = np.digitize(fs[sel], edges) - 1
        out = np.full(nb, np.nan)
        vals = a[sel]
        for k in range(nb):
            m = idx == k
            if np.any(m):
                out[k] = vals[m].mean()
        return out

    up = valid & (direction > 0)
    down = valid & (direction < 0)
    res = {'amplitude_up': binned(amp, up), 'amplitude_down': binned(amp, down)}
    ref_up: NDArray[np.float64] | None = None
    ref_down: NDArray[np.float64] | None = None
    dev_up: NDArray[np.float64] | None = None
    dev_down: NDArray[np.float64] | None = None
    nan = float('nan')
    stats: tuple[float, ...] = (nan,) * 6
    tol = _tolerance(tolerance)
    if reference is not None:
        r = _check(reference, rate_hz, 'reference')
        if r.size != x.size:
            raise ParameterError(f'reference has {r.size} samples, the record {x.size}')
        ramp, _ = _instantaneous(r, rate_hz, lo, hi)
        ref_up, ref_down = binned(ramp, up), binned(ramp, down)
        with np.errstate(invalid='ignore', divide='ignore'):
            dev_up = res['amplitude_up'] / ref_up - 1.0
            dev_down = res['amplitude_down'] / ref_down - 1.0
        stats = _deviation_tests(dev_up, dev_down)
    step = max(1, x.size // 4000)
    mean, se, sigma, gain_p, flat_p, spread = stats
    return SweepResult(centres, res['amplitude_up'], res['amplitude_down'], ref_up, ref_down,
                       dev_up, dev_down, np.arange(0, x.size, step) / rate_hz, fs[::step],
                       amp[::step], (f_lo, f_hi), mean_deviation=mean, mean_deviation_sigma=se,
                       bin_deviation_sigma=sigma, gain_p=gain_p, flatness_p=flat_p,
                       deviation_spread=spread, alpha=float(alpha), tolerance=tol)


def _deviation_tests(dev_up: NDArray[np.float64],
                     dev_down: NDArray[np.float64]) -> tuple[float, ...]:
    """Return the deviation's mean, its std error, one bin's noise, gain p, flatness p, spread."""
    nan = float('nan')
    both = np.isfinite(dev_up) & np.isfinite(dev_down)
    values = np.concatenate([dev_up[np.isfinite(dev_up)], dev_down[np.isfinite(dev_down)]])
    if np.count_nonzero(both) < 3 or values.size < 2:
        return nan, nan, nan, nan, nan, nan
    # a bin seen rising and falling measures the same gain twice: their difference is noise
    sigma = float(np.std(dev_up[both] - dev_down[both], ddof=1) / math.sqrt(2.0))
    mean = float(values.mean())
    se = sigma / math.sqrt(values.size)
    spread = float(np.sum((values - mean) ** 2)) / (values.size - 1)
    if not sigma > 0:
        return mean, se, sigma, nan, nan, math.sqrt(spread)
    # sigma comes from the m bins seen both ways: m - 1 degrees of freedom, hence t and F
    dof = int(np.count_nonzero(both)) - 1
    gain_p = float(2.0 * t_dist.sf(abs(mean) / se, dof))
    flat_p = float(f_dist.sf(spread / sigma ** 2, values.size - 1, dof))
    return mean, se, sigma, gain_p, flat_p, math.sqrt(spread)
