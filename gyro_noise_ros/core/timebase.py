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
Sample rate, stamp irregularity and sample loss from stamps: one estimator for every tool.

Stamps come as a device clock (regular, a few holes where samples were lost), host-receive times
(bursts), USB packets (samples sharing one stamp) or two clocks drifting apart; the median step is
wrong for all but the first, the mean rate ``(n - 1) / span`` once a sample is lost. So:

* regular stamps (no step shorter than :data:`SHORT_STEP` of the local period): the **step mean**,
  the mean of the steps within 0.5-1.5 times their block's median step (holes left out, uneven
  integration windows averaged);
* bursty stamps (more than :data:`BURSTY_FRACTION` of such steps): the **block rate**, the median
  of ``k / duration`` over blocks of ``k`` samples spanning :data:`BLOCK_SPAN_STEPS` typical
  largest steps, standard error ``1.2533 * 1.4826 MAD / sqrt(blocks)``;
* a per-sample sequence counter: ``(last - first) / span``, loss exact.

**Loss** is the deficit ``span * rate + 1 - n`` (a run or a window), reported only above its
resolution (rate uncertainty times span plus stamp jitter), never read from single steps of bursty
stamps. **Jitter** is the RMS of the stamps about a line through each block of :data:`BASE_BLOCK`
samples (s), blocks with a gap of :data:`GAP_STEPS` typical block maxima left out. Equal stamps
(one packet) are counted, never unusable; decreasing stamps above :data:`UNUSABLE_FRACTION` of the
steps, or stamps that never advance, are. :func:`estimate_rate` gives a :class:`RateEstimate` of a
whole record; :class:`TimebaseTracker` the same while streaming, in memory bounded by
:data:`MAX_BLOCKS` block rows (neighbours merged in pairs). Measurements: docs/offline_tool.md.
"""

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING, TypeVar

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from ..errors import InputDataError, ParameterError

if TYPE_CHECKING:  # not imported at run time: this module does not need the estimator
    from .allan import AllanResult

#: An Allan result, or None (passed through by :func:`rescale_allan`).
_R = TypeVar('_R', 'AllanResult', None)

#: Samples per base block.
#: Nominal sample rates a tool accepts (Hz): every gyro samples inside; outside, a record's times
#: overflow or vanish in floating point (a period of 1e9 / 1e-320 ns is infinite).
RATE_RANGE_HZ = (1e-3, 1e9)
BASE_BLOCK = 64
#: Blocks held before neighbours are merged in pairs.
MAX_BLOCKS = 1 << 14
# The columns of TimebaseTracker's block rows: duration, longest step, median step (ns), sum of
# squared residuals about the block's line (ns^2).
_DUR, _MAX, _MED, _JSS = range(4)
_COLUMNS = 4
#: A step shorter than this fraction of the local period only happens with bursty stamps.
SHORT_STEP = 0.5
#: Fraction of short steps above which stamps are called bursty.
BURSTY_FRACTION = 0.01
#: Relative difference between estimators above which a warning is given.
DISAGREE = 0.01
#: Fraction of decreasing steps (< 0) above which the stamps are not a time base (equal stamps
#: are not counted: module doc).
UNUSABLE_FRACTION = 0.01
#: A block whose largest step exceeds this many median block maxima holds a gap: it is left out
#: of the jitter and of the burst length.
GAP_STEPS = 10.0
#: Fewest blocks for the block rate; below, the mean rate is used.
MIN_BLOCKS = 8
#: A block must span this many typical largest steps.
BLOCK_SPAN_STEPS = 50.0

_NS = 1e9


@dataclass(frozen=True)
class RateEstimate:
    """
    Sample rate of a stamped record and how its stamps behave.

    Attributes
    ----------
    rate_hz : float
        The rate in use (Hz): configured, or from ``method``.
    method : str
        'configured', 'sequence' (per-sample counter), 'step_mean' (regular stamps: the mean of the
        steps within 0.5-1.5 local median steps, so holes do not count), 'block_median' (bursty
        stamps, module doc) or 'mean' ((n - 1) / span, for records too short for blocks).
    stamp_rate_hz : float
        The rate the stamps give (Hz), whatever ``rate_hz`` is.
    stamp_rate_se_hz : float
        Standard error of ``stamp_rate_hz`` (Hz); NaN for 'mean'.
    mean_rate_hz : float
        (n - 1) / span (Hz); lower than the true rate when samples are lost.
    median_step_rate_hz : float
        1 / median step (Hz); wrong for bursty stamps.
    samples : int
        Stamps seen.
    span_s : float
        Last minus first stamp (s).
    block_samples : int
        Samples per block of the block rate.
    bursty : bool
        More than :data:`BURSTY_FRACTION` of the steps are shorter than half the local period.
    short_step_fraction, long_step_fraction : float
        Steps below 0.5 and above 1.5 local periods, as fractions of all steps.
    jitter_s : float
        RMS of the stamps about a line through each block of 64 samples (s), blocks holding a gap
        (see ``burst_step_s``) left out.
    max_step_s : float
        Largest step (s).
    out_of_order : int
        Decreasing steps (< 0): a stamp earlier than its predecessor.
    usable : bool
        False when more than :data:`UNUSABLE_FRACTION` of the steps decrease (shuffled stamps) or
        the stamps never advance (span 0).
    loss_samples : int
        Samples missing against elapsed time (0 when within the resolution).
    loss_resolution_samples : float
        Smallest deficit the record resolves (samples).
    deficit_samples : float
        ``span * rate + 1 - n`` before rounding and thresholding (samples; < 0 is a surplus).
    warnings : tuple of str
        Sentences for the user (estimators disagree, bursts, loss, unusable stamps).
    equal_steps : int
        Steps of exactly zero (samples sharing their predecessor's stamp, e.g. one USB packet):
        a normal time base, counted for information.
    burst_step_s : float
        Largest step that is not a gap (s): the largest step of the blocks whose largest step is
        below :data:`GAP_STEPS` times the median block maximum. The longest burst wait of bursty
        stamps; a gap counts as loss, not as jitter.

    """

    rate_hz: float
    method: str
    stamp_rate_hz: float
    stamp_rate_se_hz: float
    mean_rate_hz: float
    median_step_rate_hz: float
    samples: int
    span_s: float
    block_samples: int
    bursty: bool
    short_step_fraction: float
    long_step_fraction: float
    jitter_s: float
    max_step_s: float
    out_of_order: int
    usable: bool
    loss_samples: int
    loss_resolution_samples: float
    deficit_samples: float
    warnings: tuple[str, ...] = ()
    equal_steps: int = 0
    burst_step_s: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """
        Return the fields as JSON-able values (units in the keys).

        Returns
        -------
        dict

        """
        out = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if isinstance(value, float) and not math.isfinite(value):
                value = None
            out[name] = list(value) if isinstance(value, tuple) else value
        return out


class TimebaseTracker:
    """
    Streaming stamp statistics for :class:`RateEstimate`, in bounded memory (module doc).

    Parameters
    ----------
    base_block : int, keyword-only
        Samples per base block (>= 4).
    max_blocks : int, keyword-only
        Blocks held before merging in pairs (>= 2 * MIN_BLOCKS).

    """

    def __init__(self, *, base_block: int = BASE_BLOCK, max_blocks: int = MAX_BLOCKS) -> None:
        if int(base_block) < 4 or int(max_blocks) < 2 * MIN_BLOCKS:
            raise ParameterError(f'base_block must be >= 4 and max_blocks >= {2 * MIN_BLOCKS}, '
                                 f'got {base_block!r}, {max_blocks!r}')
        self._k = int(base_block)
        self._max_blocks = int(max_blocks)
        self._carry = np.empty(0, dtype=np.int64)
        self._n = 0
        self._first: int | None = None
        self._last: int | None = None
        self._out_of_order = 0
        self._equal = 0
        self._max_step = 0
        self._short = 0
        self._long = 0
        self._steps_in_blocks = 0
        self._reg_n = 0
        self._reg_sum = 0.0
        self._reg_ss = 0.0
        self._samples_per_block = self._k
        # Per block, in rows [0, _nb) of arrays that grow by doubling (a live stream adds a block
        # or two per batch; one small array per batch would be objects without number): the
        # duration, the longest and the median step (ns), the sum of squared residuals about the
        # block's line (ns^2), and the residuals counted (_jn).
        self._blocks = np.empty((0, _COLUMNS))
        self._jn_rows = np.empty(0, dtype=np.int64)
        self._nb = 0
        self._seq_first: int | None = None
        self._seq_last: int | None = None
        self._seq_n = 0

    @property
    def samples(self) -> int:
        """Stamps seen so far."""
        return self._n

    def update(self, stamp_ns: npt.ArrayLike, sequence: npt.ArrayLike | None = None) -> None:
        """
        Add stamps in delivery order.

        Parameters
        ----------
        stamp_ns : array_like of int
            Stamps (ns).
        sequence : array_like of int, optional
            Per-sample counter of the same length (wraps are not handled: give it unwrapped).

        """
        s = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
        if s.size == 0:
            return
        if sequence is not None:
            q = np.asarray(sequence, dtype=np.int64).reshape(-1)
            if q.shape != s.shape:
                raise InputDataError(
                    f'sequence must match the stamps, got {q.shape} and {s.shape}')
            if self._seq_first is None:
                self._seq_first = int(q[0])
            self._seq_last = int(q[-1])
            self._seq_n += q.size
        if self._first is None:
            self._first = int(s[0])
            steps = np.diff(s)
        else:
            assert self._last is not None  # set with self._first
            steps = np.diff(np.concatenate(([np.int64(self._last)], s)))
        self._last = int(s[-1])
        self._n += s.size
        if steps.size:
            self._out_of_order += int(np.count_nonzero(steps < 0))
            self._equal += int(np.count_nonzero(steps == 0))
            self._max_step = max(self._max_step, int(steps.max()))
        self._carry = np.concatenate((self._carry, s))
        k = self._k
        nb = (self._carry.size - 1) // k
        if nb <= 0:
            return
        body = self._carry[:nb * k + 1]
        idx = np.arange(nb)[:, None] * k + np.arange(k + 1)[None, :]
        blk = body[idx].astype(np.float64)
        blk -= blk[:, :1]
        dur = blk[:, -1].copy()  # a view would keep the whole (nb, k + 1) block matrix alive
        st = np.diff(blk, axis=1)
        period = dur / k
        with np.errstate(invalid='ignore', divide='ignore'):
            self._short += int(np.count_nonzero(st < SHORT_STEP * period[:, None]))
            self._long += int(np.count_nonzero(st > (2.0 - SHORT_STEP) * period[:, None]))
        self._steps_in_blocks += st.size
        med = np.median(st, axis=1)
        reg = (st > SHORT_STEP * med[:, None]) & (st < (2.0 - SHORT_STEP) * med[:, None])
        regular = st[reg]
        self._reg_n += regular.size
        self._reg_sum += float(regular.sum())
        self._reg_ss += float(regular @ regular)
        x = np.arange(k + 1, dtype=np.float64)
        xc = x - x.mean()
        slope = (blk @ xc) / (xc @ xc)
        resid = blk - blk.mean(axis=1, keepdims=True) - slope[:, None] * xc[None, :]
        self._add_blocks(dur, st.max(axis=1), med, np.sum(resid ** 2, axis=1), k + 1)
        self._carry = self._carry[nb * k:].copy()
        if self._nb > self._max_blocks:
            self._merge()

    def _add_blocks(self, dur: NDArray[np.float64], maxstep: NDArray[np.float64],
                    medstep: NDArray[np.float64], jss: NDArray[np.float64], jn: int) -> None:
        """Append the rows of new blocks (growing the arrays by doubling)."""
        nb, stop = dur.size, self._nb + dur.size
        if stop > self._blocks.shape[0]:
            cap = max(stop, 2 * self._blocks.shape[0], 64)
            blocks = np.empty((cap, _COLUMNS))
            blocks[:self._nb] = self._blocks[:self._nb]
            jn_rows = np.empty(cap, dtype=np.int64)
            jn_rows[:self._nb] = self._jn_rows[:self._nb]
            self._blocks, self._jn_rows = blocks, jn_rows
        rows = self._blocks[self._nb:stop]
        rows[:, _DUR], rows[:, _MAX], rows[:, _MED], rows[:, _JSS] = dur, maxstep, medstep, jss
        self._jn_rows[self._nb:stop] = jn
        self._nb += nb

    def _merge(self) -> None:
        m = self._nb // 2 * 2
        # An odd last block cannot be merged: it leaves the rows (its samples stay counted in n and
        # span). New blocks are cut at the doubled size from now on.
        b = self._blocks[:m]
        merged = np.empty((m // 2, _COLUMNS))
        merged[:, _DUR] = b[0::2, _DUR] + b[1::2, _DUR]
        merged[:, _MAX] = np.maximum(b[0::2, _MAX], b[1::2, _MAX])
        merged[:, _MED] = 0.5 * (b[0::2, _MED] + b[1::2, _MED])
        merged[:, _JSS] = b[0::2, _JSS] + b[1::2, _JSS]
        jn = self._jn_rows[:m]
        self._blocks[:m // 2] = merged
        self._jn_rows[:m // 2] = jn[0::2] + jn[1::2]
        self._nb = m // 2
        self._k *= 2
        self._samples_per_block = self._k

    def estimate(self, rate_hz: float | None = None) -> RateEstimate:
        """
        Return the rate estimate of everything seen so far.

        Parameters
        ----------
        rate_hz : float, optional
            Configured rate (Hz); the stamp estimate is still computed and compared.

        Returns
        -------
        RateEstimate

        Raises
        ------
        InputDataError
            Fewer than 2 stamps, or a zero span without a configured rate.

        """
        n = self._n
        if n < 2:
            raise InputDataError(f'{n} stamp(s): at least 2 are needed to estimate a sample rate')
        assert self._first is not None and self._last is not None  # set by the first stamp
        span_ns = float(self._last - self._first)
        steps = n - 1
        usable, warnings = self._time_base(span_ns)
        mean_rate = steps / span_ns * _NS if span_ns > 0 else math.nan
        blocks = self._blocks[:self._nb]
        dur, mx, md = blocks[:, _DUR].copy(), blocks[:, _MAX].copy(), blocks[:, _MED].copy()
        med_step = float(np.median(md)) if md.size else (span_ns / steps)
        median_step_rate = _NS / med_step if med_step > 0 else math.nan
        block_rate, block_se, k = _block_rate(dur, mx, self._samples_per_block)
        short = self._short / self._steps_in_blocks if self._steps_in_blocks else 0.0
        long_ = self._long / self._steps_in_blocks if self._steps_in_blocks else 0.0
        bursty = short > BURSTY_FRACTION
        method, stamp_rate, se = self._stamp_rate(span_ns, bursty=bursty, block_rate=block_rate,
                                                  block_se=block_se, mean_rate=mean_rate)
        rate, used_method = _chosen_rate(rate_hz, stamp_rate, method, usable, warnings)
        jitter, burst_step = self._jitter(mx)
        if usable and math.isfinite(median_step_rate) and math.isfinite(stamp_rate) \
                and abs(median_step_rate / stamp_rate - 1.0) > 2 * DISAGREE:
            hint = ' (bursty stamps: host receive times or packets?)' if bursty else ''
            warnings.append(f'the median stamp step gives {median_step_rate:.6g} Hz but the '
                            f'{method} rate is {stamp_rate:.6g} Hz{hint}')
        deficit, resolution = self._deficit(
            method, span_ns, rate=rate, stamp_rate=stamp_rate, se=se, jitter=jitter,
            burst_step=burst_step, bursty=bursty)
        loss = int(round(deficit)) if usable and deficit > resolution else 0
        if loss:
            warnings.append(f'{loss} sample(s) missing against elapsed time '
                            f'({loss / (n + loss):.3g} of expected; resolution {resolution:.3g})')
        elif usable and deficit < -resolution and used_method == 'configured':
            warnings.append(
                f'{-deficit:.0f} more samples than the configured rate allows over the span')
        return RateEstimate(
            rate_hz=float(rate), method=used_method, stamp_rate_hz=float(stamp_rate),
            stamp_rate_se_hz=float(se), mean_rate_hz=float(mean_rate),
            median_step_rate_hz=float(median_step_rate), samples=int(n), span_s=span_ns / _NS,
            block_samples=int(k), bursty=bool(bursty), short_step_fraction=float(short),
            long_step_fraction=float(long_), jitter_s=float(jitter),
            max_step_s=self._max_step / _NS,
            out_of_order=int(self._out_of_order), usable=bool(usable), loss_samples=loss,
            loss_resolution_samples=float(resolution), deficit_samples=float(deficit),
            warnings=tuple(warnings), equal_steps=int(self._equal),
            burst_step_s=float(burst_step))

    def _time_base(self, span_ns: float) -> tuple[bool, list[str]]:
        """Return whether the stamps are a time base, and the warnings that say why not."""
        n = self._n
        steps = n - 1
        warnings = []
        usable = self._out_of_order <= UNUSABLE_FRACTION * steps and span_ns > 0
        if self._out_of_order > UNUSABLE_FRACTION * steps:
            warnings.append(f'{self._out_of_order} of {steps} stamp steps go backwards (a stamp '
                            'earlier than its predecessor): the stamps are not a time base')
        elif span_ns == 0:
            warnings.append(f'all {n} stamps are equal (they never advance): the stamps are not a '
                            'time base')
        elif span_ns < 0:
            warnings.append('the last stamp is earlier than the first: the stamps are not a time '
                            'base')
        return usable, warnings

    def _stamp_rate(self, span_ns: float, *, bursty: bool, block_rate: float, block_se: float,
                    mean_rate: float) -> tuple[str, float, float]:
        """Return the best rate of the stamps: (method, rate in Hz, its standard error in Hz)."""
        if self._seq_n == self._n and self._seq_last is not None and span_ns > 0:
            assert self._seq_first is not None  # set with self._seq_last
            return 'sequence', (self._seq_last - self._seq_first) / span_ns * _NS, math.nan
        if not bursty and self._reg_n >= MIN_BLOCKS * BASE_BLOCK // 2 and self._reg_sum > 0:
            mean_step = self._reg_sum / self._reg_n
            var_step = max(self._reg_ss / self._reg_n - mean_step ** 2, 0.0)
            stamp_rate = _NS / mean_step
            # Steps of a device clock are nearly independent; the jitter of one stamp enters two
            # steps with opposite signs, so this is conservative.
            se = stamp_rate * math.sqrt(var_step / self._reg_n) / mean_step
            return 'step_mean', stamp_rate, se
        if math.isfinite(block_rate):
            return 'block_median', block_rate, block_se
        return 'mean', mean_rate, block_se

    def _jitter(self, mx: NDArray[np.float64]) -> tuple[float, float]:
        """Return the stamp jitter (s) and the longest step of a burst (s) over calm blocks."""
        jitter, burst_step = math.nan, self._max_step / _NS
        if mx.size:
            # A block holding a gap (a step of 10 typical block maxima and more) would make the
            # gap's length look like jitter, and a burst wait like hours: both leave it out.
            calm = mx <= GAP_STEPS * float(np.median(mx))
            jss = self._blocks[:self._nb, _JSS][calm]
            jn = self._jn_rows[:self._nb][calm]
            if jn.sum():
                jitter = math.sqrt(float(jss.sum()) / float(jn.sum())) / _NS
                burst_step = float(mx[calm].max()) / _NS
        return jitter, burst_step

    def _deficit(self, method: str, span_ns: float, *, rate: float, stamp_rate: float,
                 se: float, jitter: float, burst_step: float,
                 bursty: bool) -> tuple[float, float]:
        """Return the samples missing against elapsed time, and the resolution of that count."""
        n = self._n
        if method == 'sequence':
            assert self._seq_first is not None and self._seq_last is not None  # as method says
            return float((self._seq_last - self._seq_first) + 1 - n), 0.5
        deficit = span_ns / _NS * rate + 1.0 - n
        rate_rel = (se / stamp_rate) if math.isfinite(se) and stamp_rate > 0 else 0.0
        jit = jitter if math.isfinite(jitter) else 0.0
        resolution = (n * rate_rel * 3.0 + 3.0 * jit * rate
                      + 2.0 * burst_step * rate * bursty + 1.0)
        return deficit, resolution


def _block_rate(dur: NDArray[np.float64], mx: NDArray[np.float64],
                k: int) -> tuple[float, float, int]:
    """
    Return the median rate of groups of blocks, its standard error (Hz) and samples per group.

    Blocks of ``k`` samples (durations ``dur``, longest steps ``mx``, ns) are grouped in powers of
    two until a group spans many typical longest steps; (NaN, NaN, ``k``) with too few blocks.
    """
    block_rate = se = math.nan
    if dur.size >= MIN_BLOCKS:
        typical_max = float(np.median(mx))
        g = 1
        while (dur.size // (2 * g) >= MIN_BLOCKS
               and float(np.median(_group(dur, g))) < BLOCK_SPAN_STEPS * typical_max):
            g *= 2
        d = _group(dur, g)
        d = d[d > 0]
        if d.size >= MIN_BLOCKS // 2:
            rates = k * g / d * _NS
            block_rate = float(np.median(rates))
            mad = float(np.median(np.abs(rates - block_rate)))
            se = 1.2533 * 1.4826 * mad / math.sqrt(rates.size)
            k = k * g
    return block_rate, se, k


def _chosen_rate(rate_hz: float | None, stamp_rate: float, method: str, usable: bool,
                 warnings: list[str]) -> tuple[float, str]:
    """
    Return the rate the analysis uses and how it was chosen: the configured one, else the stamps'.

    Appends to ``warnings`` when a configured rate disagrees with the stamps.
    """
    if rate_hz is not None:
        rate = float(rate_hz)
        if not (math.isfinite(rate) and rate > 0):
            raise ParameterError(f'rate_hz must be a positive number, got {rate_hz!r}')
        if math.isfinite(stamp_rate) and abs(stamp_rate / rate - 1.0) > DISAGREE and usable:
            off = 100 * (stamp_rate / rate - 1)
            warnings.append(f'the configured rate {rate:.6g} Hz differs from the rate of the '
                            f'stamps, {stamp_rate:.6g} Hz ({method}), by {off:+.2f} %')
        return rate, 'configured'
    if not math.isfinite(stamp_rate):
        raise InputDataError(warnings[0] if not usable else
                             'the stamps do not increase: cannot estimate a sample rate; '
                             'give the rate explicitly')
    return stamp_rate, method


def _group(dur: NDArray[np.float64], g: int) -> NDArray[np.float64]:
    if g == 1:
        return dur
    m = dur.size // g * g
    return dur[:m].reshape(-1, g).sum(axis=1)


def estimate_rate(t: npt.ArrayLike, *, unit: str = 'ns', rate_hz: float | None = None,
                  sequence: npt.ArrayLike | None = None) -> RateEstimate:
    """
    Estimate the sample rate, stamp irregularity and loss of a whole record (module doc).

    Parameters
    ----------
    t : array_like
        Stamps in delivery order: int ns (``unit='ns'``) or float seconds (``unit='s'``).
    unit : {'ns', 's'}, keyword-only
        Unit of ``t``.
    rate_hz : float, optional, keyword-only
        Configured rate (Hz); the stamps are still analysed and compared with it.
    sequence : array_like of int, optional, keyword-only
        Per-sample counter.

    Returns
    -------
    RateEstimate

    """
    if unit == 's':
        arr = np.asarray(t, dtype=np.float64).reshape(-1)
        if not np.all(np.isfinite(arr)):
            raise InputDataError(f'{int((~np.isfinite(arr)).sum())} sample time(s) are NaN/Inf')
        base = arr[0] if arr.size else 0.0
        stamps = np.rint((arr - base) * _NS).astype(np.int64)
    elif unit == 'ns':
        stamps = np.asarray(t).astype(np.int64).reshape(-1)
    else:
        raise ParameterError(f"unit must be 'ns' or 's', got {unit!r}")
    tracker = TimebaseTracker()
    tracker.update(stamps, sequence)
    return tracker.estimate(rate_hz)


def rescale_allan(result: _R, rate_hz: float) -> _R:
    """
    Return an Allan result with its taus recomputed for another sample rate.

    The Allan deviation of rate samples depends only on the averaging factor m; tau = m / rate. A
    streaming analysis that learns the rate better at the end rescales with this.

    Parameters
    ----------
    result : allan.AllanResult or None
        Allan deviation computed at another rate (None is returned as it is).
    rate_hz : float
        The rate (Hz).

    Returns
    -------
    allan.AllanResult or None

    """
    from dataclasses import replace

    rate = float(rate_hz)
    if not (math.isfinite(rate) and rate > 0) or result is None or rate == result.rate_hz:
        return result
    return replace(result, tau_s=np.asarray(result.m, dtype=np.float64) / rate, rate_hz=rate)
