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
The noise numbers datasheets quote, read off an Allan deviation, beside the IEEE 952 fit.

* **Bias stability** (in-run bias stability): the Allan deviation at its *first* minimum, where the
  curve stops falling and turns up (the flicker floor), with its tau and confidence interval. The
  first minimum, not the global one: past it the ADEV rests on few terms (ADIS16405 run 1, x: the
  first minimum is 0.00706 deg/s at 82 s, the datasheet's 0.007 deg/s; a dip to 0.0052 at 1311 s
  rests on 9 degrees of freedom). When the curve never turns up, the last tau is taken and flagged
  (an upper bound).
* **Angle random walk**: the -1/2 line through the taus whose local log-log slope lies within
  -0.5 +/- 0.15, read at tau = 1 s (N = ADEV(1 s) * sqrt(1 s)); its interval is the relative
  interval of the point of that region nearest to 1 s.
* **Band-limited short taus**: a sensor or driver that averages or low-passes (PX4
  ``sensor_combined``: 4 ms integration; ADIS16405: its Bartlett filter) flattens the shortest taus
  (local slope above -0.35, where white noise gives -0.5). They are left out of the IEEE 952 fit
  and the first tau kept is reported.
* **Fit quality**: 'poor' when the fitted model misses the curve by more than 25 % at a fitted tau
  or by 20 % RMS (PX4 static segment: the model is 0.66x the curve), else 'good'.
"""

from dataclasses import dataclass
import math

import numpy as np

from .allan import fit_noise_terms
from ..errors import InputDataError, ParameterError

#: Local slope above which the shortest taus are band-limited.
BAND_LIMITED_SLOPE = -0.35
#: Half-width of the slope window of the -1/2 (white noise) region.
ARW_SLOPE_TOLERANCE = 0.15
#: Fit-quality limits (relative ADEV error).
POOR_MAX_ERROR = 0.25
POOR_RMS = 0.20

_DEG = 180.0 / math.pi


@dataclass(frozen=True)
class DatasheetTerms:
    """
    Datasheet noise numbers of one Allan deviation (SI; customary units from :meth:`as_dict`).

    Attributes
    ----------
    bias_stability_rad_s, bias_stability_ci_low_rad_s, bias_stability_ci_high_rad_s : float
        ADEV at its first minimum and its interval (rad/s).
    bias_stability_tau_s : float
        Tau of that minimum (s).
    bias_stability_at_longest_tau : bool
        The curve never turned up: the value is an upper bound.
    arw_rad_per_sqrt_s, arw_ci_low_rad_per_sqrt_s, arw_ci_high_rad_per_sqrt_s : float
        Angle random walk read at tau = 1 s on the -1/2 line (rad/sqrt(s)); NaN without a -1/2
        region.
    arw_tau_range_s : tuple of float
        Taus of the -1/2 region used (s).
    confidence : float
        Two-sided confidence of the intervals.
    band_limited_below_s : float
        Taus below this were left out of the fit as band-limited (0.0: none).
    fit_quality : str
        'good' or 'poor' (module doc).
    fit_max_relative_error : float
        Largest |model ADEV / ADEV - 1| over the fitted taus.

    """

    bias_stability_rad_s: float
    bias_stability_ci_low_rad_s: float
    bias_stability_ci_high_rad_s: float
    bias_stability_tau_s: float
    bias_stability_at_longest_tau: bool
    arw_rad_per_sqrt_s: float
    arw_ci_low_rad_per_sqrt_s: float
    arw_ci_high_rad_per_sqrt_s: float
    arw_tau_range_s: tuple
    confidence: float
    band_limited_below_s: float
    fit_quality: str
    fit_max_relative_error: float

    def as_dict(self):
        """
        Return SI and customary values with units in the keys (NaN as None).

        Returns
        -------
        dict

        """
        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        out = {k: (num(getattr(self, k)) if isinstance(getattr(self, k), float)
                   else getattr(self, k)) for k in self.__dataclass_fields__}
        out['arw_tau_range_s'] = [num(v) for v in self.arw_tau_range_s]
        for key in ('bias_stability', 'bias_stability_ci_low', 'bias_stability_ci_high'):
            v = getattr(self, f'{key}_rad_s')
            out[f'{key}_deg_s'] = num(v * _DEG)
            out[f'{key}_deg_h'] = num(v * _DEG * 3600.0)
        for key in ('arw', 'arw_ci_low', 'arw_ci_high'):
            value = getattr(self, f'{key}_rad_per_sqrt_s')
            out[f'{key}_deg_per_sqrt_h'] = num(value * _DEG * 60.0)
        return out


def _slopes(result):
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.diff(np.log(adev)) / np.diff(np.log(tau))


def band_limited_below(result):
    """
    Return the first tau not flattened by band limiting (module doc); 0.0 when none is.

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data.

    Returns
    -------
    float
        Taus below the returned one (s) are band-limited.

    """
    slopes = _slopes(result)
    k = 0
    # keep at least 3 taus for the fit
    while k < slopes.size and k < result.tau_s.size - 3 and slopes[k] > BAND_LIMITED_SLOPE:
        k += 1
    return float(result.tau_s[k]) if k else 0.0


def fit_noise_terms_band_limited(result, **kwargs):
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


def datasheet_terms(result, terms=None):
    """
    Read bias stability and angle random walk off an Allan deviation, and judge a fit (module doc).

    Parameters
    ----------
    result : allan.AllanResult
        Allan deviation of rate data (rad/s).
    terms : allan.NoiseTerms, optional
        IEEE 952 fit to judge; by default :func:`fit_noise_terms_band_limited` of ``result``.

    Returns
    -------
    DatasheetTerms

    """
    tau = np.asarray(result.tau_s, dtype=np.float64)
    adev = np.asarray(result.adev, dtype=np.float64)
    lo = np.asarray(result.ci_low, dtype=np.float64)
    hi = np.asarray(result.ci_high, dtype=np.float64)
    if tau.size < 2:
        raise InputDataError(f'{tau.size} tau(s): too few for datasheet numbers')
    if terms is None:
        terms = fit_noise_terms_band_limited(result)
    j = 0
    while j + 1 < adev.size and not adev[j + 1] > adev[j]:
        j += 1
    slopes = _slopes(result)
    local = np.full(tau.size, np.nan)
    local[1:-1] = 0.5 * (slopes[:-1] + slopes[1:])
    local[0], local[-1] = slopes[0], slopes[-1]
    region = np.flatnonzero(np.abs(local + 0.5) <= ARW_SLOPE_TOLERANCE)
    if region.size:
        arw = float(np.exp(np.mean(np.log(adev[region]) + 0.5 * np.log(tau[region]))))
        near = region[np.argmin(np.abs(np.log(tau[region])))]
        arw_lo, arw_hi = arw * lo[near] / adev[near], arw * hi[near] / adev[near]
        span = (float(tau[region[0]]), float(tau[region[-1]]))
    else:
        arw = arw_lo = arw_hi = math.nan
        span = (math.nan, math.nan)
    cut = band_limited_below(result)
    fitted = (tau >= terms.tau_min_s) & (tau <= terms.tau_max_s)
    if not np.any(fitted):
        raise ParameterError('the noise terms were fitted on none of the taus of the result')
    rel = terms.model_adev(tau[fitted]) / adev[fitted] - 1.0
    max_err = float(np.max(np.abs(rel)))
    poor = max_err > POOR_MAX_ERROR or terms.rms_relative_residual > POOR_RMS
    return DatasheetTerms(
        bias_stability_rad_s=float(adev[j]), bias_stability_ci_low_rad_s=float(lo[j]),
        bias_stability_ci_high_rad_s=float(hi[j]), bias_stability_tau_s=float(tau[j]),
        bias_stability_at_longest_tau=bool(j == adev.size - 1), arw_rad_per_sqrt_s=arw,
        arw_ci_low_rad_per_sqrt_s=float(arw_lo), arw_ci_high_rad_per_sqrt_s=float(arw_hi),
        arw_tau_range_s=span, confidence=float(result.confidence), band_limited_below_s=cut,
        fit_quality='poor' if poor else 'good', fit_max_relative_error=max_err)


def random_walk_bound(result):
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
