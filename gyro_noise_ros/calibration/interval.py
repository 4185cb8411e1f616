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
Bias-instability interval of paper 001 section 6 and the before/after verdict.

Paper 001 section 6: take the Allan deviation curve, its minimum sigma_min, and the level
``c * sigma_min`` (c = 2 in the paper); the **bias-instability interval** is the range of cluster
times between the two crossings of the curve with that level around the minimum. The paper reads
420 s before and 945 s after the vibration (+125 %) and calls +/-50 % physiological.

sigma_min is the bias stability of the one Allan readout (:func:`..core.readout.adev_floor`):
where the usable curve stops falling, a later dip resting on few degrees of freedom does not move
it (the rule and its F test are in :mod:`..core.readout`). Without degrees of freedom it is the
smallest usable value (the paper's plain reading).

Here the crossings are searched outwards from the minimum: the lower one is the last tau below
the minimum where the curve is at or above the level, the upper one the first above it. Between
the two bracketing points the crossing is interpolated linearly in log(tau)-log(sigma) (Allan
curves are piecewise straight there). A side where the curve never reaches the level inside the
record is **open**: its end is reported as None, never extrapolated, and the width is undefined.
"""

from dataclasses import dataclass
import math

import numpy as np

from ..core.readout import adev_floor
from ..errors import ParameterError

#: Paper 001 section 6.
DEFAULT_C = 2.0
DEFAULT_TOLERANCE = 0.5
#: Fewer taus than this cannot show a minimum with two flanks.
MIN_TAUS = 5
#: sigma_min is taken among taus whose Allan variance has at least this many equivalent degrees
#: of freedom (68 % interval of ADEV about +/-23 %), on top of the readout's own F test: the last
#: taus of a record (EDF ~ 1-3) can dip far below the true floor and would move the whole
#: interval.
DEFAULT_MIN_EDF = 10.0


@dataclass(frozen=True)
class Interval:
    """
    The bias-instability interval of one Allan deviation curve.

    Attributes
    ----------
    lo_s, hi_s : float or None
        Crossing times (s); None for an open end (or when undetermined).
    tau_min_s : float
        Tau of the minimum (s); NaN when undetermined.
    sigma_min : float
        Minimum Allan deviation (unit of the rate); NaN when undetermined.
    level : float
        ``c * sigma_min``.
    c : float
        The factor.
    reason : str
        Empty when both ends are closed, otherwise why the width is undefined.

    """

    lo_s: object
    hi_s: object
    tau_min_s: float
    sigma_min: float
    level: float
    c: float
    reason: str = ''

    @property
    def closed(self):
        """Both ends found."""
        return self.lo_s is not None and self.hi_s is not None

    @property
    def width_s(self):
        """Width ``hi_s - lo_s`` (s) when closed, else None."""
        return self.hi_s - self.lo_s if self.closed else None


def _cross(t0, s0, t1, s1, level):
    # linear in log-log between (t0, s0) and (t1, s1)
    l0, l1 = math.log(s0), math.log(s1)
    if l1 == l0:
        return t0
    frac = (math.log(level) - l0) / (l1 - l0)
    return math.exp(math.log(t0) + frac * (math.log(t1) - math.log(t0)))


def bias_instability_interval(tau_s, adev, *, c=DEFAULT_C, edf=None, min_edf=DEFAULT_MIN_EDF,
                              max_tau_s=math.inf):
    """
    Return the tau interval where the Allan deviation stays below ``c * sigma_min``.

    Parameters
    ----------
    tau_s : array_like
        Averaging times (s), increasing; a dense grid (``taus='dense'``) makes the crossings
        precise.
    adev : array_like
        Allan deviation at those taus; non-finite and non-positive values are ignored.
    c : float, keyword-only
        Level factor (> 1; paper 001: 2).
    edf : array_like, optional, keyword-only
        Equivalent degrees of freedom of each tau (``AllanResult.edf``); with it, sigma_min is
        the readout's floor over the taus with ``edf >= min_edf`` (the crossings are still
        searched over all taus). Without it, the smallest usable value (the paper's plain
        reading).
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min.
    max_tau_s : float, keyword-only
        Longest tau that may hold sigma_min (s): pass a tenth of the record
        (``core.readout.MAX_TAU_FRACTION``) to read the analyzer's bias stability.

    Returns
    -------
    Interval

    """
    c = float(c)
    if not (math.isfinite(c) and c > 1.0):
        raise ParameterError(f'c must be finite and > 1, got {c!r}')
    tau = np.asarray(tau_s, dtype=np.float64)
    sig = np.asarray(adev, dtype=np.float64)
    if tau.shape != sig.shape or tau.ndim != 1:
        raise ParameterError(f'tau_s and adev must be 1-D of one length, got {tau.shape}, '
                             f'{sig.shape}')
    keep = np.isfinite(tau) & np.isfinite(sig) & (sig > 0) & (tau > 0)
    if edf is not None:
        edf = np.asarray(edf, dtype=np.float64)
        if edf.shape != tau.shape:
            raise ParameterError(f'edf must match tau_s, got {edf.shape} and {tau.shape}')
        edf = edf[keep]
    tau, sig = tau[keep], sig[keep]
    nan = float('nan')
    if tau.size < MIN_TAUS:
        return Interval(None, None, nan, nan, nan, c,
                        f'record too short: {tau.size} usable taus (need {MIN_TAUS})')
    if np.any(np.diff(tau) <= 0):
        raise ParameterError('tau_s must be strictly increasing')
    floor = adev_floor(tau, sig, edf=edf, min_edf=min_edf if edf is not None else 0.0,
                       max_tau_s=max_tau_s)
    if floor.index < 0:
        return Interval(None, None, nan, nan, nan, c, f'record too short: {floor.reason}')
    i = floor.index
    smin = float(sig[i])
    level = c * smin
    lo = hi = None
    above = np.flatnonzero(sig[:i] >= level)
    if above.size:
        j = int(above[-1])
        lo = _cross(tau[j], sig[j], tau[j + 1], sig[j + 1], level)
    above = np.flatnonzero(sig[i + 1:] >= level)
    if above.size:
        k = i + 1 + int(above[0])
        hi = _cross(tau[k - 1], sig[k - 1], tau[k], sig[k], level)
    reasons = []
    if lo is None:
        reasons.append(f'lower end open: the curve stays below {c:g} sigma_min down to the '
                       f'shortest tau {tau[0]:.3g} s')
    if hi is None:
        reasons.append(f'upper end open: the curve does not come back above {c:g} sigma_min '
                       f'up to the longest tau {tau[-1]:.3g} s')
    return Interval(lo, hi, float(tau[i]), smin, level, c, '; '.join(reasons))


def undetermined(reason, c=DEFAULT_C):
    """
    Return an interval that could not be computed at all.

    Parameters
    ----------
    reason : str
        Why.
    c : float
        The factor.

    Returns
    -------
    Interval

    """
    nan = float('nan')
    return Interval(None, None, nan, nan, nan, float(c), reason)


@dataclass(frozen=True)
class Verdict:
    """
    Before/after comparison of one axis.

    Attributes
    ----------
    change : float or None
        ``width_after / width_before - 1``; None when undetermined.
    verdict : str
        ``'physiological'`` (|change| <= tolerance), ``'beyond'`` or ``'undetermined'``.
    reason : str
        Why undetermined (empty otherwise).

    """

    change: object
    verdict: str
    reason: str = ''


def compare(before, after, *, tolerance=DEFAULT_TOLERANCE):
    """
    Compare two bias-instability intervals (paper 001 section 6: +/-50 % is physiological).

    Parameters
    ----------
    before, after : Interval or None
        None when that record was not given.
    tolerance : float, keyword-only
        Largest relative change still physiological (paper: 0.5).

    Returns
    -------
    Verdict

    """
    tol = float(tolerance)
    if not (math.isfinite(tol) and tol >= 0):
        raise ParameterError(f'tolerance must be finite and >= 0, got {tolerance!r}')
    reasons = []
    for name, iv in (('before', before), ('after', after)):
        if iv is None:
            reasons.append(f'no {name} record')
        elif not iv.closed:
            reasons.append(f'{name}: {iv.reason}')
    if reasons:
        return Verdict(None, 'undetermined', '; '.join(reasons))
    if before.width_s <= 0:
        return Verdict(None, 'undetermined', 'before: zero-width interval')
    change = after.width_s / before.width_s - 1.0
    return Verdict(change, 'physiological' if abs(change) <= tol else 'beyond')
