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
Allan analysis of a long static record, every accelerometer and gyro axis (paper 001 step 1/3).

:class:`StaticRecord` takes ``(t, accel, gyro)`` batches and keeps, per channel, a streaming
overlapping Allan accumulator on the dense tau grid (:class:`gyro_noise_ros.core.allan.
AllanAccumulator`), and the 1 s window statistics of the static-dwell detector. Its
:meth:`StaticRecord.finish` gives, per channel, the Allan deviation, its one readout
(``core.readout.read_allan``), the paper's bias-instability interval with the uncertainty of its
width (sigma_min is the readout's bias stability, read over taus up to a tenth of the record, so
``gyro_noise_analyze`` prints the same number for the same curve) and the noise terms with their
uncertainties (:func:`noise_terms`), or the reason why not:

* a channel holding NaN/Inf samples stops at the first one: undetermined (the Allan variance of a
  record with holes would be made up);
* an all-zero (or constant) channel: undetermined;
* a record that is not static (fewer than ``STATIC_FRACTION_MIN`` of its windows pass the
  detector, or its static windows do not all share one orientation): every channel undetermined;
* too few samples for five taus: undetermined ("record too short").
"""

from collections.abc import Sequence
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .interval import (bias_instability_interval, DEFAULT_ALPHA, DEFAULT_C, DEFAULT_MIN_EDF,
                       Interval, log_adev_sd, undetermined)
from .noise_change import DEFAULT_TAUS_S, fixed_factors, fixed_taus, FixedTaus
from .static import classify, DetectorSettings, find_dwells, WindowAccumulator
from ..core.allan import AllanAccumulator, AllanResult
from ..core.readout import (AllanReadout, fit_noise_terms_band_limited, MAX_TAU_FRACTION,
                            read_allan)
from ..errors import GyroNoiseError

CHANNELS = ('accel_x', 'accel_y', 'accel_z', 'gyro_x', 'gyro_y', 'gyro_z')
#: Fraction of the 1 s windows that must be static for a "static" record.
STATIC_FRACTION_MIN = 0.9
#: Terms of the model whose slope the crossings' uncertainty uses: white noise, flicker floor,
#: random walk (IEEE 952).
SLOPE_TERMS = ('angle_random_walk', 'bias_instability', 'rate_random_walk')
#: Noise terms reported per channel (from the one readout, ``core.readout.read_allan``).
TERMS = ('white_noise', 'bias_stability', 'random_walk')


def unit_of(channel: str) -> str:
    """Return the unit suffix of a channel of :data:`CHANNELS` (``m_s2`` accel, ``rad_s`` gyro)."""
    return 'm_s2' if channel.startswith('accel') else 'rad_s'


@dataclass(frozen=True)
class Term:
    """
    One noise term with its standard uncertainty (from the record's EDF).

    Attributes
    ----------
    value : float
        The term (SI: white noise per sqrt(Hz), bias stability flat, random walk per sqrt(s)).
    sd_log : float
        Standard deviation of log(value); inf when the record does not resolve the term.
    how : str
        Where ``sd_log`` comes from (one phrase).

    """

    value: float
    sd_log: float
    how: str = ''

    @property
    def bracket(self) -> tuple[float, float]:
        """(float, float): ``value * exp(-+sd_log)``, a 68 % interval that holds the value."""
        if not math.isfinite(self.sd_log):
            return (0.0, math.inf)
        return (self.value * math.exp(-self.sd_log), self.value * math.exp(self.sd_log))


def _white_sd(allan: AllanResult, readout: AllanReadout) -> float:
    """Return the sd of log N: the least-determined tau of the readout's -1/2 region."""
    tau = np.asarray(allan.tau_s, dtype=np.float64)
    edf = np.asarray(allan.edf, dtype=np.float64)
    a, b = readout.arw_tau_range_s
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    if readout.arw_from_region:
        sel = (tau >= a * (1 - 1e-9)) & (tau <= b * (1 + 1e-9))
    else:
        sel = np.arange(tau.size) == int(np.argmin(np.abs(np.log(tau))))
    # the region's level is a mean of strongly correlated points: no better than its worst
    return float(np.max(log_adev_sd(edf[sel]))) if np.any(sel) else math.inf


def _random_walk_sd(allan: AllanResult, k: float) -> float:
    """Return the sd of log K, read at the longest readable tau (a tenth of the record)."""
    if not (math.isfinite(k) and k > 0):
        return math.inf
    tau = np.asarray(allan.tau_s, dtype=np.float64)
    record_s = float(allan.n_samples) / float(allan.rate_hz)
    readable = np.flatnonzero(tau <= MAX_TAU_FRACTION * record_s)
    if not readable.size:
        return math.inf
    j = int(readable[-1])
    avar = float(np.asarray(allan.avar)[j])
    walk = k * k * tau[j] / 3.0
    # d log K = (AVAR / K^2 tau / 3) d log ADEV at that tau: the other terms dilute it
    return float(log_adev_sd(np.asarray(allan.edf)[j])) * max(1.0, avar / walk)


def noise_terms(allan: AllanResult, readout: AllanReadout) -> dict[str, Term]:
    """
    Return the three noise terms of one channel with their uncertainties.

    Parameters
    ----------
    allan : AllanResult
        The channel's Allan deviation.
    readout : AllanReadout
        Its readout (:func:`..core.readout.read_allan`).

    Returns
    -------
    dict
        ``{'white_noise': Term, 'bias_stability': Term, 'random_walk': Term}``, the readout's
        numbers: the angle (velocity) random walk N, with the EDF of the least-determined tau of
        its -1/2 region (the region's points are strongly correlated, so their mean is hardly
        better); the bias stability (sigma_min), with the EDF of its tau; the fitted random walk
        K, with the EDF at the longest readable tau (a tenth of the record, where the readout
        stops trusting the curve) scaled by the share of K in the Allan variance there. Each
        standard deviation is checked against the spread over emulated repeats
        (``docs/reliability.md``).

    """
    k = readout.rate_random_walk_rad_per_s_sqrt_s
    return {
        'white_noise': Term(readout.arw_rad_per_sqrt_s, _white_sd(allan, readout),
                            'EDF of the least-determined tau of the -1/2 region'),
        'bias_stability': Term(readout.bias_stability_rad_s,
                               float(log_adev_sd(readout.bias_stability_edf)),
                               'EDF of its tau (chi-squared)'),
        'random_walk': Term(k, _random_walk_sd(allan, k),
                            'EDF at a tenth of the record, scaled by the share of K there'),
    }


@dataclass(frozen=True)
class ChannelResult:
    """
    Allan analysis of one channel of a static record.

    Attributes
    ----------
    channel : str
        One of :data:`CHANNELS`.
    allan : AllanResult or None
        Allan deviation (None when undetermined before any tau).
    interval : Interval
        Bias-instability interval (paper 001 section 6), with its uncertainty.
    terms : dict or None
        :func:`noise_terms` (None when the curve has no readout).
    readout : AllanReadout or None
        The one datasheet readout of the curve (its bias stability is the interval's
        sigma_min).
    fixed : FixedTaus or str
        The Allan variance at the verdict's fixed taus (:mod:`.noise_change`), or why not.

    """

    channel: str
    allan: AllanResult | None
    interval: Interval
    terms: dict[str, Term] | None = None
    readout: AllanReadout | None = None
    fixed: FixedTaus | str = 'not computed'


class StaticRecord:
    """
    Stream one static record into per-channel Allan accumulators and window statistics.

    Parameters
    ----------
    rate_hz : float
        Sample rate (Hz).
    c : float, keyword-only
        Level factor of the interval.
    settings : DetectorSettings, keyword-only
        Static-window thresholds.
    source : str, keyword-only
        Record name for messages.
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min (0: the readout's rule alone).
    alpha : float, keyword-only
        One-sided level of the test of a fall-back below the level (ambiguous crossing).
    taus_s : sequence of float, keyword-only
        The noise verdict's fixed averaging times (s).

    """

    def __init__(self, rate_hz: float, *, c: float = DEFAULT_C,
                 settings: DetectorSettings = DetectorSettings(), source: str = '',
                 min_edf: float = DEFAULT_MIN_EDF, alpha: float = DEFAULT_ALPHA,
                 taus_s: Sequence[float] = DEFAULT_TAUS_S) -> None:
        self.rate_hz = float(rate_hz)
        self.c = c
        self.min_edf = min_edf
        self.alpha = alpha
        self.settings = settings
        self.source = source
        self._acc = [AllanAccumulator(self.rate_hz, taus='dense') for _ in CHANNELS]
        fixed = fixed_factors(taus_s, self.rate_hz)
        self._fixed = [AllanAccumulator(self.rate_hz, taus=fixed) for _ in CHANNELS]
        self._bad = [''] * len(CHANNELS)
        self._win = WindowAccumulator(self.rate_hz, window_s=settings.window_s, source=source)
        self.samples = 0
        self.duration_s = 0.0

    def update(self, t_s: NDArray[np.floating[Any]] | Sequence[float], accel_m_s2: ArrayLike,
               gyro_rad_s: ArrayLike, *, keep: NDArray[np.bool_] | None = None) -> None:
        """
        Ingest a batch.

        Parameters
        ----------
        t_s : numpy.ndarray or sequence of float
            (n,) stamps (s).
        accel_m_s2, gyro_rad_s : array_like
            (n, 3) specific force (m/s^2) and angular rate (rad/s).
        keep : numpy.ndarray of bool, optional, keyword-only
            (n,) the samples of the static part (``core.segments``: one contiguous run over the
            record); the others count in the static check only, never in the Allan deviation.
            Default: all.

        """
        data = np.hstack([np.asarray(accel_m_s2, np.float64), np.asarray(gyro_rad_s, np.float64)])
        self._win.update(t_s, data[:, :3], data[:, 3:])
        if keep is not None:
            data = data[np.asarray(keep, dtype=bool)]
        for k in range(len(CHANNELS)):
            if self._bad[k]:
                continue
            col = data[:, k]
            finite = np.isfinite(col)
            if not finite.all():
                first = self.samples + int(np.argmin(finite))
                self._bad[k] = (f'NaN/Inf samples in the record (first at sample {first}): the '
                                f'Allan deviation would be made up')
                continue
            self._acc[k].update(col)
            self._fixed[k].update(col)
        self.samples += data.shape[0]
        if len(t_s):
            self.duration_s = float(t_s[-1])

    def static_check(self) -> dict[str, Any]:
        """
        Return why the record is not a static record, or '' when it is.

        Returns
        -------
        dict
            ``{'static_fraction': float, 'orientation': str or None, 'problem': str,
            'accel_problem': str}``.

        """
        win = self._win.result()
        out: dict[str, Any] = {'static_fraction': float('nan'), 'orientation': None,
                               'problem': '', 'accel_problem': ''}
        try:
            det = find_dwells(win, self.settings)
        except GyroNoiseError as err:
            msg = str(err)
            if 'accelerometer reads' in msg:
                # no specific force: accel channels are undetermined, the gyro may be fine
                out['accel_problem'] = msg
                return out
            out['problem'] = msg
            return out
        out['static_fraction'] = det.static_fraction
        if det.static_fraction < STATIC_FRACTION_MIN:
            out['problem'] = (f'record is not static: only {100 * det.static_fraction:.0f} % of '
                              f'its {self.settings.window_s:g} s windows are static '
                              f'(need {100 * STATIC_FRACTION_MIN:.0f} %)')
            return out
        fin = win.usable
        mean = np.nanmean(win.accel_mean_m_s2[fin], axis=0)
        out['orientation'] = classify(mean)[0]
        kinds = {d.orientation for d in det.dwells + det.short}
        if len(kinds) > 1:
            out['problem'] = (f'record is not static: it holds dwells in {len(kinds)} '
                              f'orientations ({", ".join(sorted(kinds))})')
        return out

    def finish(self) -> tuple[dict[str, ChannelResult], dict[str, Any]]:
        """
        Return the per-channel results and the static check.

        Returns
        -------
        (dict, dict)
            ``{channel: ChannelResult}`` and the :meth:`static_check` document.

        """
        check = self.static_check()
        out: dict[str, ChannelResult] = {}
        for k, ch in enumerate(CHANNELS):
            reason = self._bad[k] or check['problem']
            if not reason and ch.startswith('accel'):
                reason = check['accel_problem']
            if reason:
                out[ch] = ChannelResult(ch, None, undetermined(reason, self.c), fixed=reason)
                continue
            try:
                allan = self._acc[k].result()
            except GyroNoiseError as err:
                why = f'record too short: {err}'
                out[ch] = ChannelResult(ch, None, undetermined(why, self.c), fixed=why)
                continue
            if not np.any(np.asarray(allan.adev) > 0):
                why = 'constant signal (all-zero Allan deviation)'
                out[ch] = ChannelResult(ch, allan, undetermined(why, self.c), fixed=why)
                continue
            record_s = float(allan.n_samples) / float(allan.rate_hz)
            readout: AllanReadout | None
            terms: dict[str, Term] | None
            try:
                readout = read_allan(allan)
                terms = noise_terms(allan, readout)
            except GyroNoiseError:
                readout = terms = None
            try:
                model = fit_noise_terms_band_limited(allan, terms=SLOPE_TERMS).model_adev
            except GyroNoiseError:
                model = None
            # sigma_min is the readout's bias stability: taus up to a tenth of the record
            iv = bias_instability_interval(allan.tau_s, allan.adev, c=self.c, edf=allan.edf,
                                           min_edf=self.min_edf,
                                           max_tau_s=MAX_TAU_FRACTION * record_s,
                                           model_adev=model, record_s=record_s,
                                           alpha=self.alpha)
            out[ch] = ChannelResult(ch, allan, iv, terms, readout, self._fixed_of(k, allan))
        return out, check

    def _fixed_of(self, k: int, allan: AllanResult) -> FixedTaus | str:
        try:
            return fixed_taus(self._fixed[k].result(), allan)
        except GyroNoiseError as err:
            return str(err)
