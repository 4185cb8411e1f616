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

Sine dwell (paper: 0.3/0.6 g at 6/8 Hz and 0.02 g at 1.5/2 Hz, 30 s): the frequency and amplitude
by the IEEE Std 1057 four-parameter sine fit (start from the windowed FFT peak nearest the
nominal frequency, Gauss-Newton on offset, in-phase, quadrature and frequency), then the
per-cycle amplitude (a three-parameter fit at the estimated frequency over each whole cycle) and
its statistics, the paper's "amplitude stability", and the total harmonic distortion
``THD = sqrt(sum_{k=2..H} A_k^2) / A_1`` from a least-squares fit of the harmonics below Nyquist.
Only the excited span is analysed: the cycles whose amplitude reaches half the 90th percentile
of all cycle amplitudes, from the first to the last.

Sine sweep (paper: 5 -> 10 -> 5 Hz at 0.5 Hz/s): the signal is band-passed (zero-phase 4th-order
Butterworth, an octave around the sweep band), its analytic signal (Hilbert transform) gives the
instantaneous amplitude and frequency, and the amplitude is averaged in frequency bins, separately
for rising and falling frequency. With a reference channel (the paper's piezoelectric feedback
accelerometer) the same is done on it, and the deviation ``amplitude / reference - 1`` is given
per bin.
"""

from dataclasses import dataclass
import math

import numpy as np
from scipy.signal import butter, hilbert, sosfiltfilt

from ..errors import InputDataError, ParameterError

DEFAULT_HARMONICS = 5


def _check(x, rate_hz, name='samples'):
    arr = np.asarray(x, dtype=np.float64).reshape(-1)
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ParameterError(f'rate_hz must be finite and > 0, got {rate_hz!r}')
    bad = int(np.count_nonzero(~np.isfinite(arr)))
    if bad:
        raise InputDataError(f'{name}: {bad} NaN/Inf samples (first at sample '
                             f'{int(np.argmin(np.isfinite(arr)))}); excitation checks need a '
                             f'gap-free record')
    return arr


def _design(t, freqs):
    cols = [np.ones_like(t)]
    for f in freqs:
        w = 2.0 * np.pi * f * t
        cols += [np.cos(w), np.sin(w)]
    return np.column_stack(cols)


def sine_fit4(x, rate_hz, frequency_hz, *, iterations=30):
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


def _fft_peak(x, rate_hz, near_hz):
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


def _cycle_amplitudes(x, rate_hz, f):
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


def sine_dwell(x, rate_hz, frequency_hz, *, harmonics=DEFAULT_HARMONICS):
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

    Returns
    -------
    DwellResult

    Raises
    ------
    ParameterError
        Frequency at or above Nyquist.
    InputDataError
        NaN/Inf, fewer than 3 cycles, or no sine at that frequency above the noise.

    """
    x = _check(x, rate_hz)
    f0 = float(frequency_hz)
    if not (math.isfinite(f0) and 0 < f0 < rate_hz / 2.0):
        raise ParameterError(f'--dwell frequency must be in (0, {rate_hz / 2:g}) Hz (Nyquist), '
                             f'got {frequency_hz!r}')
    if x.size < 3 * rate_hz / f0:
        raise InputDataError(f'record of {x.size} samples holds fewer than 3 cycles at {f0:g} Hz')
    amps, starts, per = _cycle_amplitudes(x, rate_hz, _fft_peak(x, rate_hz, f0))
    ref = np.percentile(amps, 90)
    on = np.flatnonzero(amps >= 0.5 * ref)
    lo, hi = int(starts[on[0]]), int(starts[on[-1]] + round(per))
    seg = x[lo:hi]
    f, amp, _, offset = sine_fit4(seg, rate_hz, _fft_peak(seg, rate_hz, f0))
    if abs(f - f0) > 0.2 * f0:
        raise InputDataError(f'no sine near {f0:g} Hz: the fit went to {f:.4g} Hz')
    cyc, _, _ = _cycle_amplitudes(seg, rate_hz, f)
    t = np.arange(seg.size) / rate_hz
    ks = [k for k in range(1, int(harmonics) + 1) if k * f < rate_hz / 2.0]
    coef, *_ = np.linalg.lstsq(_design(t, [k * f for k in ks]), seg, rcond=None)
    h = np.hypot(coef[1::2], coef[2::2])
    resid = seg - _design(t, [k * f for k in ks]) @ coef
    rms = float(np.sqrt(np.mean(resid ** 2)))
    # a sine must stand clear of the noise: its rms (A / sqrt 2) above 3 x the residual rms per
    # ~sqrt(samples) would be a weak criterion; require A > 3 residual rms / sqrt(cycle samples)
    if h[0] < 3.0 * rms / math.sqrt(max(per, 1.0)):
        raise InputDataError(f'no sine at {f0:g} Hz above the noise (amplitude {h[0]:.3g}, '
                             f'noise rms {rms:.3g})')
    mean = float(cyc.mean())
    std = float(cyc.std(ddof=1)) if cyc.size > 1 else float('nan')
    return DwellResult(
        frequency_hz=float(f), amplitude=float(h[0]), offset=float(coef[0]), cycle_amplitude=cyc,
        cycle_amplitude_mean=mean, cycle_amplitude_std=std,
        cycle_amplitude_min=float(cyc.min()), cycle_amplitude_max=float(cyc.max()),
        amplitude_stability=std / mean if mean > 0 else float('nan'), harmonics=h,
        thd=float(np.sqrt(np.sum(h[1:] ** 2)) / h[0]), residual_rms=rms,
        start_s=lo / rate_hz, duration_s=seg.size / rate_hz, cycles=int(cyc.size))


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

    """

    bin_hz: np.ndarray
    amplitude_up: np.ndarray
    amplitude_down: np.ndarray
    reference_up: object
    reference_down: object
    deviation_up: object
    deviation_down: object
    t_s: np.ndarray
    inst_frequency_hz: np.ndarray
    inst_amplitude: np.ndarray


def _instantaneous(x, rate_hz, f_lo, f_hi):
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


def _smooth(v, n):
    if n <= 1:
        return v
    k = np.ones(n) / n
    return np.convolve(v, k, mode='same')


def sine_sweep(x, rate_hz, f0_hz, f1_hz, sweep_rate_hz_s, *, reference=None, bins=None):
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

    Returns
    -------
    SweepResult

    """
    x = _check(x, rate_hz)
    lo, hi = sorted((float(f0_hz), float(f1_hz)))
    if not (lo > 0 and hi < rate_hz / 2.0 and hi > lo):
        raise ParameterError(f'--sweep band must lie in (0, {rate_hz / 2:g}) Hz with F0 != F1, '
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
    direction = np.sign(np.gradient(_smooth(fs, max(1, int(rate_hz * 0.2 / sweep_rate_hz_s)))))
    edge = int(2 * rate_hz / lo)          # Hilbert / filter edge effects
    valid = np.zeros(x.size, dtype=bool)
    valid[edge:x.size - edge] = True
    valid &= (fs >= lo) & (fs <= hi)

    def binned(a, sel):
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
    ref_up = ref_down = dev_up = dev_down = None
    if reference is not None:
        r = _check(reference, rate_hz, 'reference')
        if r.size != x.size:
            raise ParameterError(f'reference has {r.size} samples, the record {x.size}')
        ramp, _ = _instantaneous(r, rate_hz, lo, hi)
        ref_up, ref_down = binned(ramp, up), binned(ramp, down)
        with np.errstate(invalid='ignore', divide='ignore'):
            dev_up = res['amplitude_up'] / ref_up - 1.0
            dev_down = res['amplitude_down'] / ref_down - 1.0
    step = max(1, x.size // 4000)
    return SweepResult(centres, res['amplitude_up'], res['amplitude_down'], ref_up, ref_down,
                       dev_up, dev_down, np.arange(0, x.size, step) / rate_hz, fs[::step],
                       amp[::step])
