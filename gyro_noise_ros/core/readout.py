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
The one datasheet readout of an Allan deviation: bias stability, B, ARW, K and its bound, Q.

Every tool that prints one of these numbers (the offline analyzer, the live analyzer's
diagnostics, the thermal metrics, the reliability procedure's bias-instability interval) calls
:func:`read_allan` (or, on bare arrays, :func:`adev_floor`), so one curve gives one number
whatever the tool. SI inside; :meth:`AllanReadout.as_dict` adds customary units, the unit in
each key. The curve is read through the log-log slopes of its segments (IEEE Std 952-1997 annex C,
paper 001 eqs. 5-8: -1 quantization, -1/2 angle random walk, 0 flicker floor, +1/2 rate random
walk):

* the usable part (:func:`usable_start`) leaves out leading band-limited or quantization-like taus;
* bias stability (:func:`adev_floor`): the lowest usable ADEV at taus up to a tenth of the record,
  an upper bound unless an F test with the EDFs shows the curve turned there; B = it / 0.6643;
* ARW N: the -1/2 line through one contiguous region, read at 1 s, with its interval;
* rate random walk K: the IEEE 952 fit's K, *resolved* only over a +1/2 region of two octaves or
  more whose rise excludes a flat curve (:func:`random_walk_region`); beside it the bound
  :func:`random_walk_bound` at the longest tau;
* Q only from a -1 region at the shortest taus; the fit quality of the IEEE 952 fit.

Every rule, its reason and its constants: docs/allan.md ("The one datasheet readout"); their
acceptance on every real record and on seeded simulations: docs/readout.md
(``docs/scripts/readout_table.py``).
"""

from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
import scipy.stats

from .allan import AllanResult, fit_noise_terms, NoiseTerms
from ..errors import InputDataError, ParameterError
from ..formatting import finite_or_none as _num
from ..units import RAD_TO_DEG, S_PER_H

__all__ = ['AdevFloor', 'AllanReadout', 'B_FACTOR', 'BAND_LIMITED_SLOPE', 'MAX_TAU_FRACTION',
           'QUANTIZATION_SLOPE', 'SIGNIFICANCE', 'WHITE_SLOPE_TOLERANCE', 'adev_at', 'adev_floor',
           'band_limited_below', 'fit_noise_terms_band_limited', 'random_walk_bound',
           'read_allan', 'usable_start']

#: Segment slope above which the shortest taus are band-limited (flattened by a filter).
BAND_LIMITED_SLOPE = -0.35
#: Segment slope below which the shortest taus are quantization-like (nearer -1 than -1/2).
QUANTIZATION_SLOPE = -0.75
#: Half-width of the slope window of the -1/2 (angle random walk) region.
WHITE_SLOPE_TOLERANCE = 0.15
#: Half-width of the slope window of the -1 (quantization) region.
QUANTIZATION_SLOPE_TOLERANCE = 0.15
#: One-sided level of the F tests of the bias-stability rule (the upper end of a 95 % interval).
SIGNIFICANCE = 0.025
#: The bias stability is read over taus no longer than this fraction of the record.
MAX_TAU_FRACTION = 0.1
#: Flicker floor of the ADEV per unit B, sqrt(2 ln 2 / pi) = 0.6643 (IEEE 952 eq. C.27).
B_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Fit-quality limits (relative ADEV error).
POOR_MAX_ERROR = 0.25
POOR_RMS = 0.20
#: Half-width of the slope window of the +1/2 (rate random walk) region.
RANDOM_WALK_SLOPE_TOLERANCE = 0.15
#: Shortest +1/2 region that resolves K: two octaves of tau.
RANDOM_WALK_MIN_SPAN = 4.0
#: One-sided level at which the region's rise must exclude a flat curve (a 95 % interval).
RANDOM_WALK_SIGNIFICANCE = 0.025


@dataclass(frozen=True)
class AllanReadout:
    """
    Datasheet numbers of one Allan deviation (SI; customary units from :meth:`as_dict`).

    The module docstring states every rule.

    Attributes
    ----------
    bias_stability_rad_s : float
        ADEV where the usable curve stops falling (rad/s); NaN when undetermined.
    bias_stability_ci_low_rad_s, bias_stability_ci_high_rad_s : float
        Its confidence interval (rad/s), at ``confidence``.
    bias_stability_tau_s : float
        Its averaging time (s).
    bias_stability_edf : float
        Equivalent degrees of freedom of that Allan variance.
    bias_stability_upper_bound : bool
        The curve was not seen to turn up within the record: the value is an upper bound of the
        floor (the lowest usable ADEV where the curve may still be falling).
    bias_instability_rad_s : float
        B = bias stability / 0.6643 (rad/s), the IEEE 952 coefficient.
    arw_rad_per_sqrt_s, arw_ci_low_rad_per_sqrt_s, arw_ci_high_rad_per_sqrt_s : float
        Angle random walk N (rad/sqrt(s) = rad/s/sqrt(Hz)) and its interval; NaN when neither a
        -1/2 region nor tau = 1 s is on the curve.
    arw_tau_range_s : tuple of float
        First and last tau of the -1/2 region (s); (1.0, 1.0) for the ADEV(1 s) reading; NaNs
        when none.
    arw_from_region : bool
        N comes from a -1/2 region (False: from ADEV(1 s), the curve has no such region).
    adev_1s_rad_s : float
        ADEV at tau = 1 s, log-log interpolated (rad/s); NaN when 1 s is outside the taus.
    rate_random_walk_rad_per_s_sqrt_s : float
        K of the IEEE 952 fit (rad/s/sqrt(s) = rad/s^2/sqrt(Hz)); 0.0 when the fit has none,
        NaN when there is no fit (too few taus).
    rate_random_walk_resolved : bool
        The curve shows K: a +1/2 region of at least two octaves after the bias-stability tau
        whose rise excludes a flat curve (:func:`random_walk_region`), and the K term dominates
        the fitted model at the longest fitted tau.
    rate_random_walk_tau_range_s : tuple of float
        First and last tau of that +1/2 region (s); NaNs when there is none.
    rate_random_walk_bound_rad_per_s_sqrt_s : float
        :func:`random_walk_bound` (rad/s^2/sqrt(Hz)).
    rate_random_walk_bound_tau_s : float
        The tau the bound is read at, the longest of the curve (s).
    quantization_rad : float
        Q from a -1 region at the shortest taus (rad); NaN when not resolved.
    confidence : float
        Two-sided confidence of the intervals.
    usable_from_s : float
        First tau of the usable part (s).
    band_limited_below_s : float
        Taus below this are flattened by band limiting and left out of the fit (0.0: none).
    fit_quality : str
        'good' or 'poor' (module doc); 'not fitted' when the curve has too few taus for the five
        terms.
    fit_max_relative_error : float
        Largest |model ADEV / ADEV - 1| over the fitted taus (NaN: not fitted).
    record_s : float
        Length of the analysed record (s): number of samples / rate.

    """

    bias_stability_rad_s: float
    bias_stability_ci_low_rad_s: float
    bias_stability_ci_high_rad_s: float
    bias_stability_tau_s: float
    bias_stability_edf: float
    bias_stability_upper_bound: bool
    bias_instability_rad_s: float
    arw_rad_per_sqrt_s: float
    arw_ci_low_rad_per_sqrt_s: float
    arw_ci_high_rad_per_sqrt_s: float
    arw_tau_range_s: tuple
    arw_from_region: bool
    adev_1s_rad_s: float
    rate_random_walk_rad_per_s_sqrt_s: float
    rate_random_walk_resolved: bool
    rate_random_walk_tau_range_s: tuple
    rate_random_walk_bound_rad_per_s_sqrt_s: float
    rate_random_walk_bound_tau_s: float
    quantization_rad: float
    confidence: float
    usable_from_s: float
    band_limited_below_s: float
    fit_quality: str
    fit_max_relative_error: float
    record_s: float

    def as_dict(self) -> dict[str, Any]:
        """
        Return SI and customary values with units in the keys (NaN as None).

        Returns
        -------
        dict
            Every attribute, plus ``bias_stability_deg_s``/``_deg_h`` (and their ``ci_low``,
            ``ci_high``), ``bias_instability_deg_h``, ``arw_deg_per_sqrt_h`` (and interval),
            ``adev_1s_deg_s``, ``rate_random_walk_deg_per_h_sqrt_h``,
            ``rate_random_walk_bound_deg_per_h_sqrt_h`` and ``quantization_deg``.

        """
        out = {}
        for k in self.__dataclass_fields__:
            v = getattr(self, k)
            out[k] = _num(v) if isinstance(v, float) else v
        out['arw_tau_range_s'] = [_num(v) for v in self.arw_tau_range_s]
        out['rate_random_walk_tau_range_s'] = [_num(v) for v in self.rate_random_walk_tau_range_s]
        for key in ('bias_stability', 'bias_stability_ci_low', 'bias_stability_ci_high'):
            v = getattr(self, f'{key}_rad_s')
            out[f'{key}_deg_s'] = _num(v * RAD_TO_DEG)
            out[f'{key}_deg_h'] = _num(v * RAD_TO_DEG * S_PER_H)
        out['bias_instability_deg_h'] = _num(self.bias_instability_rad_s * RAD_TO_DEG * S_PER_H)
        for key in ('arw', 'arw_ci_low', 'arw_ci_high'):
            # rad/sqrt(s) -> deg/sqrt(h): sqrt(3600 s) = 60 sqrt(s) per sqrt(h)
            out[f'{key}_deg_per_sqrt_h'] = _num(getattr(self, f'{key}_rad_per_sqrt_s')
                                                * RAD_TO_DEG * 60.0)
        out['adev_1s_deg_s'] = _num(self.adev_1s_rad_s * RAD_TO_DEG)
        for key in ('rate_random_walk', 'rate_random_walk_bound'):
            # rad/s/sqrt(s) -> deg/h/sqrt(h): 3600 per (s -> h) and 60 per sqrt(s) -> sqrt(h)
            out[f'{key}_deg_per_h_sqrt_h'] = _num(getattr(self, f'{key}_rad_per_s_sqrt_s')
                                                  * RAD_TO_DEG * S_PER_H * 60.0)
        out['quantization_deg'] = _num(self.quantization_rad * RAD_TO_DEG)
        return out

    def kalibr(self) -> dict[str, float | bool]:
        """
        Return the Kalibr / OpenVINS noise parameters of this axis (continuous time, SI).

        Returns
        -------
        dict
            ``noise_density`` = N (NaN when not measured), ``random_walk`` = the larger of the
            fitted K and its bound, ``random_walk_is_bound`` (the bound is the larger: the record
            does not resolve K) and ``too_short`` (the curve never turned up: the record does not
            reach the random-walk part of the curve at all).

        """
        k_fit = self.rate_random_walk_rad_per_s_sqrt_s
        bound = self.rate_random_walk_bound_rad_per_s_sqrt_s
        k_fit = k_fit if math.isfinite(k_fit) else 0.0
        is_bound = bool(math.isfinite(bound) and bound > k_fit)
        return {'noise_density': self.arw_rad_per_sqrt_s,
                'random_walk': bound if is_bound else k_fit,
                'random_walk_is_bound': is_bound,
                'too_short': bool(self.bias_stability_upper_bound)}


@dataclass(frozen=True)
class AdevFloor:
    """
    Where an Allan deviation curve stops falling (:func:`adev_floor`).

    Attributes
    ----------
    index : int
        Index of the floor in the given arrays; -1 when undetermined.
    tau_s, adev : float
        Its averaging time (s) and deviation (unit of the curve); NaN when undetermined.
    upper_bound : bool
        The curve was not seen to turn up: ``adev`` is the lowest usable value, an upper bound.
    usable_from : int
        Index of the first usable tau (:func:`usable_start`).
    reason : str
        Empty when found; why not otherwise.

    """

    index: int
    tau_s: float
    adev: float
    upper_bound: bool
    usable_from: int
    reason: str = ''


def _slopes(tau: np.ndarray, adev: np.ndarray) -> np.ndarray:
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.diff(np.log(adev)) / np.diff(np.log(tau))


def usable_start(tau_s: ArrayLike, adev: ArrayLike) -> int:
    """
    Return the index of the first usable tau: after leading band-limited or quantization taus.

    The leading run of segments whose slope is above :data:`BAND_LIMITED_SLOPE` or below
    :data:`QUANTIZATION_SLOPE` is skipped when a segment with a slope between the two (white
    noise, -1/2) follows it; when none follows, nothing is skipped (a curve that only rises, or
    only falls steeply into a floor, has no such part to leave out).

    Parameters
    ----------
    tau_s, adev : array_like
        Averaging times (s, increasing) and Allan deviation (positive).

    Returns
    -------
    int

    """
    slopes = _slopes(np.asarray(tau_s, dtype=np.float64), np.asarray(adev, dtype=np.float64))
    white = np.flatnonzero((slopes >= QUANTIZATION_SLOPE) & (slopes <= BAND_LIMITED_SLOPE))
    return int(white[0]) if white.size else 0


def band_limited_below(result: AllanResult) -> float:
    """
    Return the first tau not flattened by band limiting (module doc); 0.0 when none is.

    The leading segments with slope above :data:`BAND_LIMITED_SLOPE` are band-limited when a
    falling segment (slope at most that) follows them; at least 3 taus are kept for the fit.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data.

    Returns
    -------
    float
        Taus below the returned one (s) are band-limited.

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    slopes = _slopes(tau, np.asarray(result.adev, dtype=np.float64))
    falling = np.flatnonzero(slopes <= BAND_LIMITED_SLOPE)
    if not falling.size:
        return 0.0
    k = min(int(falling[0]), max(tau.size - 3, 0))
    return float(tau[k]) if k else 0.0


def fit_noise_terms_band_limited(result: AllanResult, **kwargs: Any) -> NoiseTerms:
    """
    Fit the IEEE 952 terms (:func:`allan.fit_noise_terms`) without the band-limited short taus.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data.
    **kwargs
        Passed to :func:`allan.fit_noise_terms` (``tau_range_s`` is combined with the cut).

    Returns
    -------
    allan.NoiseTerms

    """
    lo = band_limited_below(result)
    rng = kwargs.pop('tau_range_s', None)
    hi = math.inf if rng is None else float(rng[1])
    lo = max(lo, 0.0 if rng is None else float(rng[0]))
    return fit_noise_terms(result, tau_range_s=(lo, hi), **kwargs)


def _f_upper(edf_num: float, edf_den: float, level: float = SIGNIFICANCE) -> float:
    """Critical ratio of two variance estimates at one-sided ``level`` (inf EDF: 1)."""
    if not (math.isfinite(edf_num) or math.isfinite(edf_den)):
        return 1.0
    if not math.isfinite(edf_den):
        return float(scipy.stats.chi2.ppf(1.0 - level, edf_num) / edf_num)
    if not math.isfinite(edf_num):
        return float(edf_den / scipy.stats.chi2.ppf(level, edf_den))
    return float(scipy.stats.f.ppf(1.0 - level, edf_num, edf_den))


def adev_floor(tau_s: ArrayLike, adev: ArrayLike, *, edf: ArrayLike | None = None,
               min_edf: float = 0.0, max_tau_s: float = math.inf) -> 'AdevFloor':
    """
    Find where an Allan deviation stops falling: the bias-stability rule of the module doc.

    Parameters
    ----------
    tau_s : array_like
        Averaging times (s), strictly increasing.
    adev : array_like
        Allan deviation at those taus (any unit); non-finite and non-positive values are ignored.
    edf : array_like, optional, keyword-only
        Equivalent degrees of freedom of each Allan variance (``AllanResult.edf``), for the
        upper-bound test. Without it every difference counts as significant.
    min_edf : float, keyword-only
        Taus with fewer degrees of freedom may not hold the floor (default 0).
    max_tau_s : float, keyword-only
        Longest tau that may hold the floor (s; :func:`read_allan` passes a tenth of the record,
        :data:`MAX_TAU_FRACTION`); longer taus still count in the upper-bound test. When no
        usable tau is that short, the shortest usable tau is taken (flagged by the test).

    Returns
    -------
    AdevFloor

    Raises
    ------
    ParameterError
        Arrays of different shapes, or taus not strictly increasing.

    """
    tau = np.asarray(tau_s, dtype=np.float64)
    sig = np.asarray(adev, dtype=np.float64)
    if tau.ndim != 1 or tau.shape != sig.shape:
        raise ParameterError(f'tau_s and adev must be 1-D of one length, got {tau.shape}, '
                             f'{sig.shape}')
    if edf is None:
        dof = np.full(tau.shape, np.inf)
    else:
        dof = np.asarray(edf, dtype=np.float64)
        if dof.shape != tau.shape:
            raise ParameterError(f'edf must match tau_s, got {dof.shape} and {tau.shape}')
        dof = np.nan_to_num(dof, nan=0.0)
    ok = np.isfinite(tau) & np.isfinite(sig) & (sig > 0) & (tau > 0)
    if np.any(np.diff(tau[ok]) <= 0):
        raise ParameterError('tau_s must be strictly increasing')
    nan = math.nan
    if not np.any(ok):
        return AdevFloor(-1, nan, nan, False, 0, 'no positive Allan deviation')
    start = int(np.flatnonzero(ok)[usable_start(tau[ok], sig[ok])])
    idx = np.flatnonzero(ok & (dof >= float(min_edf)) & (np.arange(tau.size) >= start))
    if not idx.size:
        return AdevFloor(-1, nan, nan, False, start,
                         f'no tau with at least {float(min_edf):g} degrees of freedom')
    avar = sig * sig
    short = idx[tau[idx] <= float(max_tau_s)]
    cand = short if short.size else idx[:1]
    j = int(cand[np.argmin(sig[cand])])
    p = int(np.searchsorted(idx, j))
    # A real floor: the curve has left the -1/2 line of white noise there. Some earlier tau lies
    # significantly below the -1/2 line through it (the curve flattened into it), or some later
    # tau significantly above (it stopped falling). On that line AVAR * tau is constant.
    level = avar * tau
    real = p + 1 < idx.size and (
        any(level[j] > level[i] * _f_upper(dof[j], dof[i]) for i in idx[:p])
        or any(level[i] > level[j] * _f_upper(dof[i], dof[j]) for i in idx[p + 1:]))
    # a longer tau (past the readable tenth) lower still: the floor may lie lower
    deeper = bool(np.any(sig[idx[p + 1:]] < sig[j]))
    return AdevFloor(int(j), float(tau[j]), float(sig[j]), not real or deeper, start)


def adev_at(result: AllanResult, tau_s: float) -> float:
    """
    Return the Allan deviation at ``tau_s``, interpolated in log-log between neighbouring taus.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation.
    tau_s : float
        Averaging time (s).

    Returns
    -------
    float
        NaN when ``tau_s`` is outside the taus (no extrapolation).

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    good = np.isfinite(adev) & (adev > 0)
    tau, adev = tau[good], adev[good]
    t = float(tau_s)
    if tau.size == 0 or not tau[0] <= t <= tau[-1]:
        return math.nan
    # ADEV is a power law between neighbouring taus: interpolate in log-log
    return float(np.exp(np.interp(math.log(t), np.log(tau), np.log(adev))))


def _arw(tau: np.ndarray, adev: np.ndarray, lo: np.ndarray, hi: np.ndarray, start: int,
         stop: int, result: AllanResult) -> tuple[Any, ...]:
    """Return (N, low, high, (tau_a, tau_b), from_region) (module doc)."""
    slopes = _slopes(tau, adev)
    white = np.abs(slopes + 0.5) <= WHITE_SLOPE_TOLERANCE
    best = None
    s = start
    while s < stop:
        if not white[s]:
            s += 1
            continue
        e = s
        while e + 1 < stop and white[e + 1]:
            e += 1
        if best is None or e - s > best[1] - best[0]:
            best = (s, e)
        s = e + 1
    if best is not None:
        pts = np.arange(best[0], best[1] + 2)   # the taus at both ends of the segments
        level = adev[pts] * np.sqrt(tau[pts])
        arw = float(np.exp(np.mean(np.log(level))))
        low = float(np.min(level * lo[pts] / adev[pts]))
        high = float(np.max(level * hi[pts] / adev[pts]))
        return arw, low, high, (float(tau[pts[0]]), float(tau[pts[-1]])), True
    a1 = adev_at(result, 1.0)
    if not math.isfinite(a1):
        return math.nan, math.nan, math.nan, (math.nan, math.nan), False
    # the interval of the tau nearest 1 s, scaled to the interpolated value
    near = int(np.argmin(np.abs(np.log(tau))))
    return a1, a1 * lo[near] / adev[near], a1 * hi[near] / adev[near], (1.0, 1.0), False


def _quantization(tau: np.ndarray, adev: np.ndarray) -> float:
    slopes = _slopes(tau, adev)
    e = 0
    while e < slopes.size and abs(slopes[e] + 1.0) <= QUANTIZATION_SLOPE_TOLERANCE:
        e += 1
    if e < 2:
        return math.nan
    pts = np.arange(0, e + 1)
    return float(np.exp(np.mean(np.log(adev[pts] * tau[pts] / math.sqrt(3.0)))))


def read_allan(result: AllanResult, terms: NoiseTerms | None = None) -> 'AllanReadout':
    """
    Read bias stability, B, ARW, K (and its bound) and Q off an Allan deviation (module doc).

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data (rad/s; m/s^2 for an accelerometer, then ARW is the velocity
        random walk and K the acceleration random walk).
    terms : allan.NoiseTerms, optional
        IEEE 952 fit to judge and to take K from; by default
        :func:`fit_noise_terms_band_limited` of ``result`` (none when it has too few taus).

    Returns
    -------
    AllanReadout

    Raises
    ------
    InputDataError
        Fewer than 2 taus, or no positive Allan deviation.
    ParameterError
        ``terms`` fitted on none of the taus of ``result``.

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    lo = np.asarray(result.ci_low, dtype=np.float64)
    hi = np.asarray(result.ci_high, dtype=np.float64)
    edf = np.asarray(result.edf, dtype=np.float64)
    if tau.size < 2:
        raise InputDataError(f'{tau.size} tau(s): too few for datasheet numbers')
    if not np.all(np.isfinite(adev) & (adev > 0)):
        raise InputDataError('the Allan deviation is zero or not finite at some tau (constant '
                             'or broken data): no datasheet numbers')
    if terms is None:
        try:
            terms = fit_noise_terms_band_limited(result)
        except InputDataError:
            terms = None    # too few taus for the five terms: no fit to judge, no fitted K
    floor = adev_floor(tau, adev, edf=edf, max_tau_s=MAX_TAU_FRACTION * float(result.n_samples)
                       / float(result.rate_hz))
    j = floor.index
    arw, arw_lo, arw_hi, span, from_region = _arw(tau, adev, lo, hi, floor.usable_from,
                                                  max(j, floor.usable_from + 1), result)
    quality, max_err, k_fit, resolved = 'not fitted', math.nan, math.nan, False
    if terms is not None:
        fitted = (tau >= terms.tau_min_s) & (tau <= terms.tau_max_s)
        if not np.any(fitted):
            raise ParameterError('the noise terms were fitted on none of the taus of the result')
        rel = terms.model_adev(tau[fitted]) / adev[fitted] - 1.0
        max_err = float(np.max(np.abs(rel)))
        poor = max_err > POOR_MAX_ERROR or terms.rms_relative_residual > POOR_RMS
        quality = 'poor' if poor else 'good'
        k_fit = terms.rate_random_walk_rad_per_s_sqrt_s
        k_fit = float(k_fit) if math.isfinite(k_fit) else 0.0
        t_end = terms.tau_max_s
        # resolved: the K term is the larger part of the fitted model at the longest fitted tau
        k_var = k_fit ** 2 * t_end / 3.0
        resolved = bool(k_fit > 0.0 and k_var > 0.5 * float(terms.avar_model([t_end])[0]))
    # and only where the curve shows it: a +1/2 region after the floor (module doc)
    region = random_walk_region(result, max(j, floor.usable_from)) if resolved else None
    walk_span = ((float(tau[region[0]]), float(tau[region[1]])) if region is not None
                 else (math.nan, math.nan))
    return AllanReadout(
        bias_stability_rad_s=float(adev[j]), bias_stability_ci_low_rad_s=float(lo[j]),
        bias_stability_ci_high_rad_s=float(hi[j]), bias_stability_tau_s=float(tau[j]),
        bias_stability_edf=float(edf[j]), bias_stability_upper_bound=bool(floor.upper_bound),
        bias_instability_rad_s=float(adev[j]) / B_FACTOR, arw_rad_per_sqrt_s=float(arw),
        arw_ci_low_rad_per_sqrt_s=float(arw_lo), arw_ci_high_rad_per_sqrt_s=float(arw_hi),
        arw_tau_range_s=span, arw_from_region=bool(from_region),
        adev_1s_rad_s=adev_at(result, 1.0), rate_random_walk_rad_per_s_sqrt_s=k_fit,
        rate_random_walk_resolved=region is not None, rate_random_walk_tau_range_s=walk_span,
        rate_random_walk_bound_rad_per_s_sqrt_s=random_walk_bound(result),
        rate_random_walk_bound_tau_s=float(tau[-1]),
        quantization_rad=_quantization(tau, adev),
        confidence=float(result.confidence), usable_from_s=float(tau[floor.usable_from]),
        band_limited_below_s=band_limited_below(result), fit_quality=quality,
        fit_max_relative_error=max_err,
        record_s=float(result.n_samples) / float(result.rate_hz))


def random_walk_region(result: AllanResult, start: int = 0) -> tuple[int, int] | None:
    """
    Find the +1/2 region that resolves a rate random walk (module doc), or None.

    A region is a run of taus ``i..j`` (``start <= i < j``) spanning at least
    :data:`RANDOM_WALK_MIN_SPAN` (two octaves) whose log-log least-squares slope lies within
    :data:`RANDOM_WALK_SLOPE_TOLERANCE` of +1/2, and over which the curve's rise is beyond doubt:
    the 95 % interval of the ratio ``AVAR_j / AVAR_i`` (F distribution with the two EDFs of
    :class:`.allan.AllanResult`; the two estimates overlap in data and are positively
    correlated, so treating them as independent widens the interval) lies above 1, i.e. the
    interval of the region's slope excludes a flat curve. The longest such region (in octaves)
    is returned.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data.
    start : int
        First tau index the region may begin at (the bias-stability tau: the rise follows it).

    Returns
    -------
    tuple of int or None
        ``(i, j)``, indices of the region's first and last tau.

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    avar = np.asarray(result.avar, dtype=np.float64)
    edf = np.nan_to_num(np.asarray(result.edf, dtype=np.float64), nan=0.0)
    with np.errstate(invalid='ignore', divide='ignore'):
        x, y = np.log(tau), 0.5 * np.log(avar)
    # prefix sums: the LS slope of every run i..j in O(1)
    c = [np.concatenate(([0.0], np.cumsum(v))) for v in (np.ones_like(x), x, y, x * x, x * y)]
    best = None
    for i in range(max(int(start), 0), tau.size):
        j = np.arange(i + 1, tau.size)
        j = j[tau[j] >= RANDOM_WALK_MIN_SPAN * tau[i]]
        if not j.size:
            break
        n, sx, sy, sxx, sxy = (v[j + 1] - v[i] for v in c)
        with np.errstate(invalid='ignore', divide='ignore'):
            slope = (n * sxy - sx * sy) / (n * sxx - sx * sx)
        rises = np.array([edf[i] > 0 and edf[k] > 0 and avar[k] > avar[i] * _f_upper(
            edf[k], edf[i], RANDOM_WALK_SIGNIFICANCE) for k in j], dtype=bool)
        ok = j[(np.abs(slope - 0.5) <= RANDOM_WALK_SLOPE_TOLERANCE) & rises]
        if ok.size and (best is None or x[ok[-1]] - x[i] > x[best[1]] - x[best[0]]):
            best = (i, int(ok[-1]))
    return best


def random_walk_bound(result: AllanResult) -> float:
    """
    Return a conservative upper bound of the rate random walk K a record cannot resolve.

    A rate random walk adds ``K sqrt(tau / 3)`` to the ADEV (IEEE 952 C.3). Any K larger than
    ``ADEV_high(tau_max) * sqrt(3 / tau_max)``, with ADEV_high the upper confidence bound at the
    longest tau, would lift the curve above what was measured there; so this K bounds the random
    walk from above. Kalibr cannot use a random walk of 0; this is the number to give it.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data (rad/s, or m/s^2 for an accelerometer).

    Returns
    -------
    float
        K bound (rad/s^2/sqrt(Hz); m/s^3/sqrt(Hz) for an accelerometer); NaN without taus.

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    if tau.size == 0:
        return math.nan
    high = float(np.asarray(result.ci_high, dtype=np.float64)[-1])
    if not math.isfinite(high):
        high = float(np.asarray(result.adev, dtype=np.float64)[-1])
    return high * math.sqrt(3.0 / float(tau[-1]))
