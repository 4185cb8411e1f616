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
Bias-instability interval of paper 001 section 6, its uncertainty, and the before/after verdicts.

**Interval** (paper 001 section 6): from the Allan deviation's minimum ``sigma_min`` (the bias
stability of the one readout, :func:`..core.readout.adev_floor`) and the level ``c * sigma_min``
(paper c = 2), the cluster times (s) where the curve crosses the level on either side of the
minimum, interpolated in log(tau)-log(sigma); a side that never reaches the level is **open**
(None, never extrapolated). An upward crossing the curve falls back under is flagged ambiguous,
with whether the fall-back is significant (``fallback_s``).

**Width uncertainty** (:func:`bias_instability_interval` with ``edf``), from the Greenhall-Riley
EDF nu: ``sd(log ADEV) = e(nu) = sqrt(trigamma(nu / 2)) / 2`` and, with ``s`` the log-log slope
of the fitted IEEE 952 model at each crossing::

    var(W) = e_min^2 (tau_hi / |s_hi| + tau_lo / |s_lo|)^2 + (tau_hi e_hi / s_hi)^2
             + (tau_lo e_lo / s_lo)^2

**Verdicts** (:func:`compare`): ``log(W_after / W_before)`` with ``sd = hypot(sd_b, sd_a)`` against
the band ``1 +/- tolerance`` at the one-sided level ``alpha``: ``beyond`` (a one-sided bound
outside the band), ``physiological`` (two one-sided tests: the 90 % interval inside it) or
``undetermined`` with the record length that would decide (the sd falls as 1/sqrt(length)).
:func:`overall` gives one verdict per sensor from its three axes. Derivation, why not a
bootstrap, and the measured coverage and power: docs/reliability.md section 2
(``docs/scripts/reliability_verdicts.py``).
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.special
import scipy.stats

from ..core.readout import adev_floor
from ..errors import ParameterError

#: Paper 001 section 6.
DEFAULT_C = 2.0
DEFAULT_TOLERANCE = 0.5
#: One-sided level of each test of a verdict (a 95 % one-sided bound).
DEFAULT_ALPHA = 0.05
#: Fewer taus than this cannot show a minimum with two flanks.
MIN_TAUS = 5
#: sigma_min only among taus with at least this many EDF, on top of the readout's rule (0: the
#: readout's rule alone, so the interval's sigma_min is the analyzer's bias stability).
DEFAULT_MIN_EDF = 0.0
#: A crossing where the curve's log-log slope is flatter than this has no usable uncertainty
#: (a flat curve crosses a level anywhere within its noise).
MIN_CROSSING_SLOPE = 0.05
#: Taus on each side for the least-squares slope when no model is given.
SLOPE_HALF_WIDTH = 3

#: ``model_adev(tau_s) -> ADEV`` of a fitted model (``NoiseTerms.model_adev``).
_ModelAdev = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def log_adev_sd(edf: ArrayLike) -> float | NDArray[np.float64]:
    """
    Return the standard deviation of log ADEV of an Allan variance with ``edf`` degrees of freedom.

    ``AVAR_hat = AVAR chi2_nu / nu``, so ``var(log ADEV_hat) = var(log chi2_nu) / 4 =
    trigamma(nu / 2) / 4`` (exact for the chi-squared law; about ``1 / (2 nu)`` for large nu).

    Parameters
    ----------
    edf : float or array_like
        Equivalent degrees of freedom (> 0).

    Returns
    -------
    float or numpy.ndarray
        Standard deviation of the natural log of the ADEV; inf where ``edf`` is not > 0.

    """
    nu = np.asarray(edf, dtype=np.float64)
    with np.errstate(invalid='ignore'):
        good = np.isfinite(nu) & (nu > 0)
    out = np.full(nu.shape, np.inf)
    out[good] = 0.5 * np.sqrt(scipy.special.polygamma(1, nu[good] / 2.0))
    return float(out) if out.ndim == 0 else out


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
    width_sd_log : float
        Standard deviation of log(width) (module doc); NaN without EDF, inf when a crossing is
        on a flat part of the curve.
    lo_sd_log, hi_sd_log : float
        Standard deviations of log(lo_s), log(hi_s).
    slope_lo, slope_hi : float
        Log-log slopes used at the crossings.
    record_s : float
        Length of the record the curve comes from (s); NaN when not given.
    fallback_s : tuple of float or None
        First and last tau (s) after the upper crossing where the curve is back below the
        level: an ambiguous upper crossing; None when it never falls back.
    fallback_significant : bool
        The fall-back is significant (module doc): the width is then undetermined.
    hi_last_s : float or None
        Where the interval would end if the fall-back belonged to it: the last upward crossing,
        None when the curve ends below the level (open).

    """

    lo_s: float | None
    hi_s: float | None
    tau_min_s: float
    sigma_min: float
    level: float
    c: float
    reason: str = ''
    width_sd_log: float = math.nan
    lo_sd_log: float = math.nan
    hi_sd_log: float = math.nan
    slope_lo: float = math.nan
    slope_hi: float = math.nan
    record_s: float = math.nan
    fallback_s: tuple[float, float] | None = None
    fallback_significant: bool = False
    hi_last_s: float | None = None

    @property
    def closed(self) -> bool:
        """Both ends found."""
        return self.lo_s is not None and self.hi_s is not None

    @property
    def width_s(self) -> float | None:
        """Width ``hi_s - lo_s`` (s) when closed, else None."""
        if self.lo_s is None or self.hi_s is None:  # not closed
            return None
        return self.hi_s - self.lo_s

    @property
    def ambiguous(self) -> bool:
        """bool: the curve falls back below the level after the upper crossing."""
        return self.fallback_s is not None

    def fallback_note(self) -> str:
        """
        Return one sentence on an ambiguous upper crossing ('' when there is none).

        Returns
        -------
        str

        """
        if self.fallback_s is None:
            return ''
        a, b = self.fallback_s
        end = ('open (the curve ends below the level)' if self.hi_last_s is None
               else f'{self.hi_last_s:.4g} s')
        kind = ('significantly (beyond the ADEV uncertainty there)' if self.fallback_significant
                else 'within the ADEV uncertainty there')
        return (f'ambiguous upper crossing: the curve falls back under {self.c:g} sigma_min '
                f'for tau {a:.4g}-{b:.4g} s, {kind}; read to the last crossing the interval '
                f'would end at {end}')


def _cross(t0: float, s0: float, t1: float, s1: float, level: float) -> float:
    # linear in log-log between (t0, s0) and (t1, s1)
    l0, l1 = math.log(s0), math.log(s1)
    if l1 == l0:
        return t0
    frac = (math.log(level) - l0) / (l1 - l0)
    return math.exp(math.log(t0) + frac * (math.log(t1) - math.log(t0)))


def _interp_log(tau: NDArray[np.float64], values: NDArray[np.float64], t: float) -> float:
    """Interpolate ``values`` (positive, inf allowed) at ``t`` in log-log."""
    with np.errstate(divide='ignore'):
        lv = np.log(values)
    if not np.all(np.isfinite(lv)):
        # an inf neighbour makes the interpolated value inf too
        j = int(np.clip(np.searchsorted(tau, t), 1, tau.size - 1))
        if not (np.isfinite(lv[j - 1]) and np.isfinite(lv[j])):
            return math.inf
    return float(np.exp(np.interp(math.log(t), np.log(tau), lv)))


def _slope(tau: NDArray[np.float64], sig: NDArray[np.float64], t: float, sign: float,
           model_adev: _ModelAdev | None) -> float:
    """Log-log slope at ``t`` on the side ``sign`` (+1 rising, -1 falling); NaN when unusable."""
    if model_adev is not None:
        h = 0.05
        try:
            a, b = (float(v) for v in model_adev(np.array([t * math.exp(-h), t * math.exp(h)])))
        except (ValueError, FloatingPointError):
            a = b = math.nan
        if a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b):
            s = (math.log(b) - math.log(a)) / (2.0 * h)
            if sign * s >= MIN_CROSSING_SLOPE:
                return s
    j = int(np.searchsorted(tau, t))
    sel = slice(max(0, j - SLOPE_HALF_WIDTH), min(tau.size, j + SLOPE_HALF_WIDTH))
    if sel.stop - sel.start < 2:
        return math.nan
    s = float(np.polyfit(np.log(tau[sel]), np.log(sig[sel]), 1)[0])
    return s if sign * s >= MIN_CROSSING_SLOPE else math.nan


def bias_instability_interval(tau_s: ArrayLike, adev: ArrayLike, *, c: float = DEFAULT_C,
                              edf: ArrayLike | None = None, min_edf: float = DEFAULT_MIN_EDF,
                              max_tau_s: float = math.inf,
                              model_adev: _ModelAdev | None = None, record_s: float = math.nan,
                              alpha: float = DEFAULT_ALPHA) -> Interval:
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
        Equivalent degrees of freedom of each tau (``AllanResult.edf``): the readout's test of
        the floor uses them, and the width gets its uncertainty from them (module doc). Without
        them sigma_min is the smallest usable value (the paper's plain reading) and the width
        has no uncertainty (NaN).
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min (0: the readout's rule alone).
    max_tau_s : float, keyword-only
        Longest tau that may hold sigma_min (s): pass a tenth of the record
        (``core.readout.MAX_TAU_FRACTION``) to read the analyzer's bias stability.
    model_adev : callable, optional, keyword-only
        ``model_adev(tau_s) -> ADEV`` of a fitted model (``NoiseTerms.model_adev``), for the
        slope at the crossings.
    record_s : float, keyword-only
        Length of the record (s), kept for the record-length extrapolation of :func:`compare`.
    alpha : float, keyword-only
        One-sided level of the test that a fall-back below the level is significant.

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
    record_s = float(record_s)
    if tau.size < MIN_TAUS:
        return Interval(None, None, nan, nan, nan, c,
                        f'record too short: {tau.size} usable taus (need {MIN_TAUS})',
                        record_s=record_s)
    if np.any(np.diff(tau) <= 0):
        raise ParameterError('tau_s must be strictly increasing')
    floor = adev_floor(tau, sig, edf=edf, min_edf=min_edf if edf is not None else 0.0,
                       max_tau_s=max_tau_s)
    if floor.index < 0:
        return Interval(None, None, nan, nan, nan, c, f'record too short: {floor.reason}',
                        record_s=record_s)
    i = floor.index
    smin = float(sig[i])
    level = c * smin
    lo: float | None = None
    hi: float | None = None
    k: int | None = None
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
    fallback: tuple[float, float] | None = None
    significant = False
    hi_last: float | None = None
    if k is not None:
        below = k + np.flatnonzero(sig[k:] < level)
        if below.size:
            fallback = (float(tau[below[0]]), float(tau[below[-1]]))
            last = int(below[-1])
            if last + 1 < tau.size:
                hi_last = _cross(tau[last], sig[last], tau[last + 1], sig[last + 1], level)
            if edf is not None:
                nu = edf[below]
                ok = np.isfinite(nu) & (nu > 0)
                # one-sided upper confidence bound of ADEV at each fall-back tau
                upper = sig[below][ok] * np.sqrt(nu[ok] / scipy.stats.chi2.ppf(alpha, nu[ok]))
                significant = bool(np.any(upper < level))
    sd = _uncertainty(tau, sig, edf, i, lo, hi, model_adev)
    return Interval(lo, hi, float(tau[i]), smin, level, c, '; '.join(reasons), *sd,
                    record_s=record_s, fallback_s=fallback, fallback_significant=significant,
                    hi_last_s=hi_last)


def _uncertainty(tau: NDArray[np.float64], sig: NDArray[np.float64],
                 edf: NDArray[np.float64] | None, i: int, lo: float | None, hi: float | None,
                 model_adev: _ModelAdev | None) -> tuple[float, float, float, float, float]:
    """Return (width_sd_log, lo_sd_log, hi_sd_log, slope_lo, slope_hi) (module doc)."""
    nan = math.nan
    if edf is None:
        return nan, nan, nan, nan, nan
    e = log_adev_sd(edf)
    assert isinstance(e, np.ndarray)  # edf is the 1-D array of the taus
    e_min = float(e[i])
    out_lo = out_hi = (nan, nan)
    if lo is not None:
        s = _slope(tau, sig, lo, -1.0, model_adev)
        e_x = _interp_log(tau, e, lo)
        out_lo = (math.hypot(e_min, e_x) / abs(s) if math.isfinite(s) else math.inf, s)
    if hi is not None:
        s = _slope(tau, sig, hi, 1.0, model_adev)
        e_x = _interp_log(tau, e, hi)
        out_hi = (math.hypot(e_min, e_x) / abs(s) if math.isfinite(s) else math.inf, s)
    width_sd = nan
    if lo is not None and hi is not None:
        s_lo, s_hi = abs(out_lo[1]), abs(out_hi[1])
        if not (math.isfinite(s_lo) and math.isfinite(s_hi)):
            width_sd = math.inf
        else:
            e_lo = _interp_log(tau, e, lo)
            e_hi = _interp_log(tau, e, hi)
            var = ((e_min * (hi / s_hi + lo / s_lo)) ** 2 + (hi * e_hi / s_hi) ** 2
                   + (lo * e_lo / s_lo) ** 2)
            width_sd = math.sqrt(var) / (hi - lo)
    return width_sd, out_lo[0], out_hi[0], out_lo[1], out_hi[1]


def undetermined(reason: str, c: float = DEFAULT_C) -> Interval:
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


def _check_tolerance(tolerance: float, alpha: float) -> tuple[float, float, float, float]:
    tol = float(tolerance)
    if not (math.isfinite(tol) and tol >= 0):
        raise ParameterError(f'tolerance must be finite and >= 0, got {tolerance!r}')
    a = float(alpha)
    if not (math.isfinite(a) and 0.0 < a < 0.5):
        raise ParameterError(f'alpha must be in (0, 0.5), got {alpha!r}')
    up = math.log1p(tol)
    down = math.log1p(-tol) if tol < 1.0 else -math.inf
    return tol, a, up, down


@dataclass(frozen=True)
class BandTest:
    """
    A relative change tested against the +/- tolerance band (module doc).

    Attributes
    ----------
    verdict : str
        ``'beyond'``, ``'physiological'`` or ``'undetermined'``.
    log_ratio, log_ratio_sd : float
        log(after / before) and its standard deviation.
    ci : tuple of float
        Two-sided ``1 - 2 alpha`` interval of the relative change (e.g. 90 %: each end is a
        one-sided 95 % bound).
    decide_factor : float or None
        How many times longer both records would have to be for the verdict to be decided at
        the present estimate (1.0 when decided; None when no length would, the estimate sitting
        on a band edge).

    """

    verdict: str
    log_ratio: float
    log_ratio_sd: float
    ci: tuple[float, float]
    decide_factor: float | None


def band_test(log_ratio: float, log_ratio_sd: float, *, tolerance: float = DEFAULT_TOLERANCE,
              alpha: float = DEFAULT_ALPHA) -> BandTest:
    """
    Test a change ``log(after / before)`` with its standard deviation against the band.

    Parameters
    ----------
    log_ratio, log_ratio_sd : float
        The change as a log ratio, and its standard deviation (finite, > 0).
    tolerance : float, keyword-only
        Half-width of the physiological band (0.5: ratios 0.5 .. 1.5).
    alpha : float, keyword-only
        One-sided level of each test.

    Returns
    -------
    BandTest

    """
    _, a, up, down = _check_tolerance(tolerance, alpha)
    lr, s = float(log_ratio), float(log_ratio_sd)
    z = float(scipy.stats.norm.ppf(1.0 - a))
    lo, hi = lr - z * s, lr + z * s
    ci = (math.expm1(lo), math.expm1(hi))
    if lo > up or hi < down:
        return BandTest('beyond', lr, s, ci, 1.0)
    if hi <= up and lo >= down:
        return BandTest('physiological', lr, s, ci, 1.0)
    # outside the band: the edge it crossed; inside: the nearer edge
    if lr > up:
        d = lr - up
    elif lr < down:
        d = down - lr
    else:
        d = min(up - lr, lr - down)
    # the standard deviation falls as 1 / sqrt(record length) (EDF proportional to it)
    factor = (z * s / d) ** 2 if d > 0 else None
    return BandTest('undetermined', lr, s, ci, factor)


@dataclass(frozen=True)
class Verdict:
    """
    Before/after comparison of one axis.

    Attributes
    ----------
    change : float or None
        ``width_after / width_before - 1``; None when undetermined.
    verdict : str
        ``'physiological'``, ``'beyond'`` or ``'undetermined'`` (module doc).
    reason : str
        Why undetermined (empty otherwise).
    change_sd : float or None
        Standard deviation of ``change`` (``(1 + change) * log_ratio_sd``, first order).
    log_ratio, log_ratio_sd : float or None
        log(width_after / width_before) and its standard deviation.
    ci : tuple or None
        Two-sided ``1 - 2 alpha`` interval of ``change``.
    decide_record_s : tuple or None
        Lengths of the before and after records (s) that would decide an undetermined verdict
        at the present estimate (None when decided, or when no length would).
    notes : tuple of str
        Ambiguous crossings that did not change the verdict.

    """

    change: float | None
    verdict: str
    reason: str = ''
    change_sd: float | None = None
    log_ratio: float | None = None
    log_ratio_sd: float | None = None
    ci: tuple[float, float] | None = None
    decide_record_s: tuple[float, float] | None = None
    notes: tuple[str, ...] = ()


def compare(before: Interval | None, after: Interval | None, *,
            tolerance: float = DEFAULT_TOLERANCE, alpha: float = DEFAULT_ALPHA) -> Verdict:
    """
    Compare two bias-instability intervals (paper 001 section 6: +/-50 % is physiological).

    Parameters
    ----------
    before, after : Interval or None
        None when that record was not given.
    tolerance : float, keyword-only
        Largest relative change still physiological (paper: 0.5).
    alpha : float, keyword-only
        One-sided level of each test (module doc).

    Returns
    -------
    Verdict

    """
    _check_tolerance(tolerance, alpha)
    reasons = []
    notes = []
    for name, iv in (('before', before), ('after', after)):
        if iv is None:
            reasons.append(f'no {name} record')
        elif not iv.closed:
            reasons.append(f'{name}: {iv.reason}')
        elif iv.ambiguous:
            if iv.fallback_significant:
                reasons.append(f'{name}: {iv.fallback_note()}')
            else:
                notes.append(f'{name}: {iv.fallback_note()}')
    if reasons:
        return Verdict(None, 'undetermined', '; '.join(reasons), notes=tuple(notes))
    # no reason: both records given and their intervals closed
    assert before is not None and after is not None
    width_before, width_after = before.width_s, after.width_s
    assert width_before is not None and width_after is not None
    if width_before <= 0:
        return Verdict(None, 'undetermined', 'before: zero-width interval')
    change = width_after / width_before - 1.0
    sd = math.hypot(before.width_sd_log, after.width_sd_log)
    if not math.isfinite(sd):
        why = ('a crossing lies on a flat part of the curve' if math.isinf(sd)
               else 'no degrees of freedom for the Allan variance')
        return Verdict(change, 'undetermined', f'the width has no uncertainty: {why}',
                       notes=tuple(notes))
    t = band_test(math.log1p(change), sd, tolerance=tolerance, alpha=alpha)
    decide: tuple[float, float] | None = None
    reason = ''
    if t.verdict == 'undetermined':
        if t.decide_factor is None:
            reason = ('the change sits on the tolerance edge: no record length decides it at '
                      'this estimate')
        else:
            decide = (t.decide_factor * before.record_s, t.decide_factor * after.record_s)
            reason = (f'the {100 * (1 - 2 * alpha):.0f} % interval of the change '
                      f'({100 * t.ci[0]:+.0f} % .. {100 * t.ci[1]:+.0f} %) straddles '
                      f'+/-{100 * tolerance:.0f} %; records {t.decide_factor:.1f} times as long '
                      'would decide it at this estimate')
    return Verdict(change, t.verdict, reason, (1.0 + change) * sd, t.log_ratio, sd, t.ci,
                   decide, tuple(notes))


@dataclass(frozen=True)
class SensorVerdict:
    """
    The verdict of one sensor (accelerometer or gyro) from its three axes (:func:`overall`).

    Attributes
    ----------
    verdict : str
        ``'beyond'``, ``'physiological'`` or ``'undetermined'``.
    basis : str
        How it was reached (one sentence).
    mean_change, mean_change_sd : float or None
        Geometric mean over the axes of the width ratio, minus 1, and its standard deviation.
    ci : tuple or None
        Two-sided ``1 - 2 alpha`` interval of ``mean_change``.
    axes_beyond : tuple of str
        Axes beyond at the Bonferroni level ``alpha / 3``.
    decide_factor : float or None
        How many times longer the records would have to be to decide the three-axis mean.

    """

    verdict: str
    basis: str
    mean_change: float | None = None
    mean_change_sd: float | None = None
    ci: tuple[float, float] | None = None
    axes_beyond: tuple[str, ...] = ()
    decide_factor: float | None = None


def overall(verdicts: Mapping[str, Verdict], *, tolerance: float = DEFAULT_TOLERANCE,
            alpha: float = DEFAULT_ALPHA) -> SensorVerdict:
    """
    Return one sensor's verdict from the verdicts of its axes.

    Rule: **beyond** when some axis is beyond at the Bonferroni level ``alpha / n`` (one
    damaged axis is not averaged away), or when the three-axis mean of log(width ratio) (the
    paper's "average among the three axes") is beyond at ``alpha``; **physiological** when the
    mean is physiological and no axis is beyond; **undetermined** otherwise. The axes are taken
    as independent for the mean's standard deviation ``sqrt(sum sd_i^2) / n``. A sensor whose
    true change sits on a band edge is called beyond with probability at most 2 alpha (union of
    the two tests).

    Parameters
    ----------
    verdicts : dict
        ``{axis name: Verdict}``.
    tolerance : float, keyword-only
        Half-width of the band.
    alpha : float, keyword-only
        One-sided level.

    Returns
    -------
    SensorVerdict

    """
    _check_tolerance(tolerance, alpha)
    n = len(verdicts)
    # {axis: (log_ratio, log_ratio_sd)} of the axes with a width change
    usable = {k: (v.log_ratio, v.log_ratio_sd) for k, v in verdicts.items()
              if v.log_ratio is not None and v.log_ratio_sd is not None
              and math.isfinite(v.log_ratio_sd)}
    beyond = tuple(k for k, (lr, sd) in usable.items() if band_test(
        lr, sd, tolerance=tolerance, alpha=alpha / n).verdict == 'beyond')
    mean = None
    if n and len(usable) == n:
        m = sum(lr for lr, _ in usable.values()) / n
        s = math.sqrt(sum(sd ** 2 for _, sd in usable.values())) / n
        mean = band_test(m, s, tolerance=tolerance, alpha=alpha)
    pct = f'{100 * tolerance:.0f} %'
    conf = f'{100 * (1 - alpha):.0f} %'
    if beyond or (mean is not None and mean.verdict == 'beyond'):
        parts = []
        if beyond:
            parts.append(f'{", ".join(beyond)} beyond +/-{pct} at one-sided '
                         f'{100 * (1 - alpha / n):.1f} % (Bonferroni over {n} axes)')
        if mean is not None and mean.verdict == 'beyond':
            parts.append(f'the three-axis mean beyond +/-{pct} at one-sided {conf}')
        verdict, basis = 'beyond', '; '.join(parts)
    elif mean is not None and mean.verdict == 'physiological':
        verdict = 'physiological'
        basis = (f'the three-axis mean within +/-{pct} at one-sided {conf} on both sides, no '
                 'axis beyond')
    else:
        verdict = 'undetermined'
        if mean is None:
            basis = (f'{n - len(usable)} of {n} axes without a width change, and none beyond')
        else:
            basis = (f'the {100 * (1 - 2 * alpha):.0f} % interval of the three-axis mean '
                     f'straddles +/-{pct}, no axis beyond')
    if mean is None:
        return SensorVerdict(verdict, basis, axes_beyond=beyond)
    return SensorVerdict(verdict, basis, math.expm1(mean.log_ratio),
                         math.exp(mean.log_ratio) * mean.log_ratio_sd, mean.ci, beyond,
                         mean.decide_factor if mean.verdict == 'undetermined' else None)
