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
Before/after verdict on the noise at averaging times fixed before the data (issue 28).

Per channel the Allan deviation at :data:`DEFAULT_TAUS_S` (1 s: the white-noise level; 10 and
30 s: the flicker floor, inside paper 001's bias-instability interval; not 100 s, where real
repeat runs of one sensor differ by up to x1.6: docs/reliability.md), each with its Greenhall
EDF. Two independent records give ``AVAR_a / AVAR_b ~ rho F(nu_a, nu_b)``, so the ADEV
ratio ``sqrt(rho)`` has an exact interval and one-sided tests against the band ``1 +/- tolerance``
(default +/-30 %, docs/reliability.md). Per sensor (three axes x the taus) **beyond**: some test
rejects "within the band" under Holm's step-down at family-wise level ``alpha`` (one-sided);
**within**: every test rejects "beyond" at ``alpha`` (intersection-union, no adjustment: each
(1 - 2 alpha) interval inside the band); **undetermined** otherwise, with the record length at
which a change of the band edge would be detected with 80 % probability, from the EDF as a
function of record length for the noise type identified at that tau (not from the estimate).
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.optimize
import scipy.stats

from ..core.allan import AllanResult, edf_greenhall, NOISE_TYPE_NAMES
from ..errors import InputDataError, ParameterError

#: Averaging times of the verdict (s), fixed before the data (docs/reliability.md says why).
DEFAULT_TAUS_S = (1.0, 10.0, 30.0)
#: Half-width of the band of the ADEV ratio (docs/reliability.md: repeat runs agree within it).
DEFAULT_TOLERANCE = 0.30
#: Paper 001 section 6.
PAPER_TOLERANCE = 0.50
#: Family-wise one-sided level of "beyond" per sensor; each "within" test is at this level too.
DEFAULT_ALPHA = 0.05
#: Probability with which the stated record length detects a change at the band edge.
POWER = 0.80
#: Fewest non-overlapping averages a fixed tau needs in a record.
MIN_AVERAGES = 10
VERDICTS = ('beyond', 'within', 'undetermined')


@dataclass(frozen=True)
class FixedTaus:
    """
    The Allan variance of one channel of one record at the fixed averaging times.

    Attributes
    ----------
    tau_s, avar, edf : numpy.ndarray
        Averaging times (s), Allan variance (unit^2) and its EDF.
    noise_alpha : numpy.ndarray
        Noise type at each tau (rate PSD ~ f^alpha, ``core.allan.noise_types``).
    m : numpy.ndarray
        Averaging factors (samples).
    rate_hz : float
        Sample rate (Hz).
    n_samples : int
        Samples analysed.

    """

    tau_s: np.ndarray
    avar: np.ndarray
    edf: np.ndarray
    noise_alpha: np.ndarray
    m: np.ndarray
    rate_hz: float
    n_samples: int

    @property
    def record_s(self) -> float:
        """float: the record's length (s)."""
        return self.n_samples / self.rate_hz


def fixed_factors(taus_s: Sequence[float], rate_hz: float) -> NDArray[np.int64]:
    """
    Return the averaging factors of the fixed taus at a sample rate.

    Parameters
    ----------
    taus_s : sequence of float
        Averaging times (s, > 0, increasing).
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    numpy.ndarray
        ``max(1, round(tau * rate))`` (int64).

    """
    t = np.asarray(taus_s, dtype=np.float64)
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t) & (t > 0)) \
            or np.any(np.diff(t) <= 0):
        raise ParameterError(f'taus must be increasing positive times (s), got {taus_s!r}')
    return np.maximum(1, np.round(t * float(rate_hz))).astype(np.int64)


def fixed_taus(values: AllanResult, curve: AllanResult) -> FixedTaus:
    """
    Return the fixed-tau Allan variances with the EDF of the noise type read on the dense curve.

    Parameters
    ----------
    values : AllanResult
        The estimator at the fixed factors (``AllanAccumulator(taus=fixed_factors(...))``).
    curve : AllanResult
        The dense curve of the same samples: its noise type (:func:`core.allan.noise_types`,
        many taus) at the nearest tau in log is the one the EDF uses (a sparse set of taus
        has no local slope).

    Returns
    -------
    FixedTaus

    Raises
    ------
    InputDataError
        A fixed tau with fewer than :data:`MIN_AVERAGES` averages (the record is too short).

    """
    m = np.asarray(values.m, dtype=np.int64)
    need = int(m.max()) * MIN_AVERAGES
    if values.n_samples < need:
        raise InputDataError(
            f'record too short for the noise verdict: {values.n_samples / values.rate_hz:.0f} s, '
            f'the longest fixed tau ({m.max() / values.rate_hz:g} s) needs '
            f'{need / values.rate_hz:.0f} s ({MIN_AVERAGES} averages)')
    ctau = np.log(np.asarray(curve.tau_s, dtype=np.float64))
    alpha = np.array([int(curve.noise_alpha[int(np.argmin(np.abs(ctau - math.log(t))))])
                      for t in np.asarray(values.tau_s)], dtype=np.int64)
    edf = np.array([edf_greenhall(int(min(2, max(-2, a))), int(mm), values.n_samples + 1,
                                  stride=int(s))
                    for a, mm, s in zip(alpha, m, np.asarray(values.stride))])
    return FixedTaus(np.asarray(values.tau_s, dtype=np.float64).copy(),
                     np.asarray(values.avar, dtype=np.float64).copy(), edf, alpha, m.copy(),
                     float(values.rate_hz), int(values.n_samples))


@dataclass(frozen=True)
class TauChange:
    """
    The change of one channel's Allan deviation at one fixed tau.

    Attributes
    ----------
    channel : str
        e.g. ``gyro_x``.
    tau_s : float
        Averaging time (s).
    adev_before, adev_after : float
        Allan deviations (unit of the channel).
    edf_before, edf_after : float
        Their EDFs.
    alpha_before, alpha_after : int
        The noise types behind the EDFs (rate PSD ~ f^alpha).
    rate_hz : float
        Sample rate of the records (Hz).
    ratio : float
        ``adev_after / adev_before``.
    ci : tuple of float
        Two-sided ``1 - 2 alpha`` interval of the true ratio (F law of the two variances).
    p_above, p_below : float
        One-sided p-values of "the ratio is at most 1 + tolerance" and "at least 1 - tolerance".
    verdict : str
        ``'beyond'``, ``'within'`` or ``'undetermined'`` (after the sensor's Holm step).
    decide_record_s : float or None
        Record length (s, each record) that detects a change at the band edge with 80 %
        probability at this tau (None when decided).

    """

    channel: str
    tau_s: float
    adev_before: float
    adev_after: float
    edf_before: float
    edf_after: float
    alpha_before: int
    alpha_after: int
    rate_hz: float
    ratio: float
    ci: tuple[float, float]
    p_above: float
    p_below: float
    verdict: str = 'undetermined'
    decide_record_s: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """
        Return the JSON entry (SI; keys documented in docs/reliability.md).

        Returns
        -------
        dict

        """
        return {'channel': self.channel, 'tau_s': self.tau_s, 'adev_before': self.adev_before,
                'adev_after': self.adev_after, 'edf_before': self.edf_before,
                'edf_after': self.edf_after, 'noise_before': _name(self.alpha_before),
                'noise_after': _name(self.alpha_after), 'ratio': self.ratio,
                'ci': list(self.ci), 'p_above': self.p_above, 'p_below': self.p_below,
                'verdict': self.verdict, 'decide_record_s': self.decide_record_s}


def _check(tolerance: float, alpha: float) -> tuple[float, float]:
    tol, a = float(tolerance), float(alpha)
    if not (math.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError(f'tolerance must be in (0, 1), got {tolerance!r}')
    if not (math.isfinite(a) and 0.0 < a < 0.5):
        raise ParameterError(f'alpha must be in (0, 0.5), got {alpha!r}')
    return tol, a


def ratio_test(avar_before: ArrayLike, edf_before: ArrayLike, avar_after: ArrayLike,
               edf_after: ArrayLike, *, tolerance: float = DEFAULT_TOLERANCE,
               alpha: float = DEFAULT_ALPHA) -> tuple[Any, tuple[Any, Any], Any, Any]:
    """
    Test the ADEV ratio after/before of two independent records against the band.

    ``r = AVAR_after / AVAR_before`` over its truth ``rho`` is ``F(nu_a, nu_b)`` (two
    independent chi-squared variances over their EDFs, NIST SP 1065 eq. 45 for each).

    Parameters
    ----------
    avar_before, edf_before, avar_after, edf_after : float or array_like
        The two Allan variances (> 0) and EDFs (> 0); arrays broadcast.
    tolerance : float, keyword-only
        Band half-width of the ADEV ratio: ``1 - tolerance .. 1 + tolerance``.
    alpha : float, keyword-only
        One-sided level of the interval's ends.

    Returns
    -------
    (ratio, (low, high), p_above, p_below)
        ADEV ratio, its two-sided ``1 - 2 alpha`` interval, ``p_above`` (H0: ratio <= 1 + tol)
        and ``p_below`` (H0: ratio >= 1 - tol); floats for scalar input.

    """
    tol, a = _check(tolerance, alpha)
    r = np.asarray(avar_after, dtype=np.float64) / np.asarray(avar_before, dtype=np.float64)
    nu_a = np.asarray(edf_after, dtype=np.float64)
    nu_b = np.asarray(edf_before, dtype=np.float64)
    f = scipy.stats.f
    out = (np.sqrt(r), (np.sqrt(r / f.ppf(1.0 - a, nu_a, nu_b)),
                        np.sqrt(r / f.ppf(a, nu_a, nu_b))),
           f.sf(r / (1.0 + tol) ** 2, nu_a, nu_b), f.cdf(r / (1.0 - tol) ** 2, nu_a, nu_b))
    if r.ndim == 0:
        return (float(out[0]), (float(out[1][0]), float(out[1][1])), float(out[2]),
                float(out[3]))
    return out


def _power(record_s: float, tau_s: float, rate_hz: float, alphas: tuple[int, int],
           edge2: float, level: float) -> float:
    """P(a within test at ``level`` rejects the edge | true ratio 1) for records of record_s."""
    n = int(record_s * rate_hz)
    m = max(1, int(round(tau_s * rate_hz)))
    if n < 2 * m:
        return 0.0
    nu = [edf_greenhall(int(min(2, max(-2, a))), m, n + 1) for a in alphas]
    f = scipy.stats.f(nu[1], nu[0])
    return float(f.cdf(edge2 * f.ppf(level)))


def decide_length_s(tau_s: float, rate_hz: float, alphas: tuple[int, int], *,
                    tolerance: float = DEFAULT_TOLERANCE, level: float = DEFAULT_ALPHA,
                    power: float = POWER) -> float:
    """
    Return the record length that detects a change of the band edge with probability ``power``.

    The power of one one-sided test at ``level`` to tell a ratio of 1 from the band edge (by
    symmetry of the log-F law, the same as telling the edge from 1), with both records of the
    length L, their EDFs from Greenhall's algorithm for the given noise types at ``tau_s`` (the
    noise model, not the present estimate); L by bisection in log.

    Parameters
    ----------
    tau_s : float
        Averaging time (s).
    rate_hz : float
        Sample rate (Hz).
    alphas : (int, int)
        Noise types before and after at ``tau_s``.
    tolerance : float, keyword-only
        Band half-width.
    level : float, keyword-only
        Level of the one-sided test (the Holm / Bonferroni level of the sensor).
    power : float, keyword-only
        Required probability.

    Returns
    -------
    float
        Record length (s).

    """
    tol, _ = _check(tolerance, 0.25)
    edge2 = min((1.0 + tol) ** 2, 1.0 / (1.0 - tol) ** 2)
    lo = 2.0 * max(tau_s, 1.0 / rate_hz) * MIN_AVERAGES / 2.0
    hi = lo
    while _power(hi, tau_s, rate_hz, alphas, edge2, level) < power:
        hi *= 2.0
        if hi > 1e10:
            return math.inf
    if hi == lo:
        return lo
    return float(math.exp(scipy.optimize.brentq(
        lambda x: _power(math.exp(x), tau_s, rate_hz, alphas, edge2, level) - power,
        math.log(hi / 2.0), math.log(hi), xtol=1e-3)))


@dataclass(frozen=True)
class SensorChange:
    """
    The noise verdict of one sensor (its three axes x the fixed taus).

    Attributes
    ----------
    sensor : str
        ``'accel'`` or ``'gyro'``.
    verdict : str
        ``'beyond'``, ``'within'`` or ``'undetermined'``.
    tests : tuple of TauChange
        Every (channel, tau), with the verdict each took.
    decisive : TauChange or None
        The test the sentence quotes: the most significant beyond, else the least decided.
    decide_record_s : float or None
        Undetermined: the record length (each record) that would decide every test.
    reason : str
        Why a channel gave no tests ('' when all did).

    """

    sensor: str
    verdict: str
    tests: tuple[TauChange, ...] = ()
    decisive: TauChange | None = None
    decide_record_s: float | None = None
    reason: str = ''


def _holm(p: Sequence[float], alpha: float) -> list[bool]:
    order = np.argsort(p)
    out = [False] * len(p)
    for k, j in enumerate(order):
        if p[j] > alpha / (len(p) - k):
            break
        out[int(j)] = True
    return out


def compare_sensor(sensor: str, before: Mapping[str, FixedTaus | str],
                   after: Mapping[str, FixedTaus | str], *,
                   tolerance: float = DEFAULT_TOLERANCE,
                   alpha: float = DEFAULT_ALPHA) -> SensorChange:
    """
    Return one sensor's verdict from its channels' fixed-tau Allan variances.

    Parameters
    ----------
    sensor : str
        ``'accel'`` or ``'gyro'``.
    before, after : dict
        ``{channel: FixedTaus or the reason it is missing}`` for the sensor's channels.
    tolerance, alpha : float, keyword-only
        Band half-width and family-wise one-sided level (module doc).

    Returns
    -------
    SensorChange

    """
    tol, a = _check(tolerance, alpha)
    tests: list[TauChange] = []
    reasons = []
    for ch in before:
        b, af = before[ch], after.get(ch, 'not given')
        if isinstance(b, str) or isinstance(af, str):
            reasons.append(f'{ch}: {b if isinstance(b, str) else af}')
            continue
        tests += _channel_tests(ch, b, af, tol, a)
    if not tests:
        return SensorChange(sensor, 'undetermined', reason='; '.join(reasons))
    beyond = _holm([min(t.p_above, t.p_below) for t in tests], a)
    level = a / len(tests)
    done = []
    for t, is_beyond in zip(tests, beyond):
        if is_beyond:
            done.append(replace(t, verdict='beyond'))
        elif _within(t, tol):
            done.append(replace(t, verdict='within'))
        else:
            done.append(replace(t, decide_record_s=decide_length_s(
                t.tau_s, t.rate_hz, (t.alpha_before, t.alpha_after), tolerance=tol,
                level=level)))
    return _sensor_result(sensor, done, reasons)


def _sensor_result(sensor: str, tests: list[TauChange], reasons: list[str]) -> SensorChange:
    beyond = [t for t in tests if t.verdict == 'beyond']
    open_ = [t for t in tests if t.verdict == 'undetermined']
    if beyond:
        top = min(beyond, key=lambda t: min(t.p_above, t.p_below))
        return SensorChange(sensor, 'beyond', tuple(tests), top, None, '; '.join(reasons))
    if open_ or reasons:
        least = max(open_, key=lambda t: t.decide_record_s or 0.0) if open_ else None
        longest = max((t.decide_record_s for t in open_ if t.decide_record_s is not None),
                      default=None)
        return SensorChange(sensor, 'undetermined', tuple(tests), least, longest,
                            '; '.join(reasons))
    top = max(tests, key=lambda t: abs(math.log(t.ratio)))
    return SensorChange(sensor, 'within', tuple(tests), top)


def _within(t: TauChange, tol: float) -> bool:
    # each end of the (1 - 2 alpha) interval inside the band: both one-sided "beyond" rejected
    return t.ci[0] > 1.0 - tol and t.ci[1] < 1.0 + tol


def _channel_tests(ch: str, b: FixedTaus, af: FixedTaus, tol: float,
                   a: float) -> list[TauChange]:
    if b.tau_s.shape != af.tau_s.shape or not np.allclose(b.tau_s, af.tau_s, rtol=0.02):
        raise InputDataError(f'{ch}: the before and after records do not share the fixed taus '
                             f'({b.tau_s.tolist()} s against {af.tau_s.tolist()} s)')
    out = []
    for j in range(b.tau_s.size):
        ratio, ci, p_up, p_down = ratio_test(b.avar[j], b.edf[j], af.avar[j], af.edf[j],
                                             tolerance=tol, alpha=a)
        out.append(TauChange(ch, float(b.tau_s[j]), math.sqrt(b.avar[j]), math.sqrt(af.avar[j]),
                             float(b.edf[j]), float(af.edf[j]), int(b.noise_alpha[j]),
                             int(af.noise_alpha[j]), b.rate_hz, ratio, ci, p_up, p_down))
    return out


def _name(alpha: int) -> str:
    return NOISE_TYPE_NAMES[max(-3, min(2, int(alpha)))]


NAMES = {'accel': 'accelerometer', 'gyro': 'gyroscope'}


def _taus(tests: Sequence[TauChange]) -> str:
    taus = sorted({t.tau_s for t in tests})
    words = [f'{t:g}' for t in taus]
    return (', '.join(words[:-1]) + ' and ' + words[-1]) if len(words) > 1 else words[0]


def sentence(change: SensorChange, *, tolerance: float = DEFAULT_TOLERANCE,
             alpha: float = DEFAULT_ALPHA) -> str:
    """
    Return the verdict in words a lab can sign, with the number it rests on.

    Parameters
    ----------
    change : SensorChange
        The sensor's verdict.
    tolerance, alpha : float, keyword-only
        As given to :func:`compare_sensor`.

    Returns
    -------
    str
        e.g. "The gyroscope noise at 30 s rose x1.55 (90 % interval 1.48-1.62) on gyro_z:
        beyond +/-30 %."

    """
    name = NAMES.get(change.sensor, change.sensor)
    band = f'+/-{100 * tolerance:.0f} %'
    conf = f'{100 * (1 - 2 * alpha):.0f} %'
    t = change.decisive
    if t is None:
        return f'The {name} noise cannot be compared: {change.reason}.'
    how = 'rose' if t.ratio >= 1.0 else 'fell'
    quote = (f'at {t.tau_s:g} s {how} x{t.ratio:.2f} ({conf} interval {t.ci[0]:.2f}-'
             f'{t.ci[1]:.2f}) on {t.channel}')
    n = len(change.tests)
    if change.verdict == 'beyond':
        return (f'The {name} noise {quote}: beyond {band} (Holm over {n} tests, family-wise '
                f'one-sided {100 * alpha:g} %).')
    if change.verdict == 'within':
        return (f'The {name} noise stayed within {band} at {_taus(change.tests)} s on every '
                f'axis ({conf} intervals); the largest change: {quote}.')
    longer = ''
    if change.decide_record_s is not None and math.isfinite(change.decide_record_s):
        longer = (f'; records of about {change.decide_record_s / 3600:.3g} h each would detect '
                  f'a change of x{1 + tolerance:g} with {100 * POWER:.0f} % probability')
    missing = f' ({change.reason})' if change.reason else ''
    return (f'These records cannot tell whether the {name} noise changed beyond {band}: the '
            f'least decided, {quote}{longer}{missing}.')
