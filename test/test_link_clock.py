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
Device-clock unwrapping and the device-to-host time estimator.

On an emulated clock with drift and jitter.

The emulated link: samples at 6667 Hz of device time, 16 per batch (417 batches/s), the device
clock off by ``ppm`` against the host, each batch received ``latency + Exp(mean 2 ms)`` after its
newest sample. The error of a stamp is ``stamp - (true host time of the sample + latency)`` (the
constant latency is not observable and is documented as such).
"""

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.link.clock import DeviceClock, Unwrapper
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest

ODR = 6667.0
BATCH = 16
LATENCY_NS = 150_000
H0 = 1_763_000_000_000_000_000  # a 2025 UNIX time in ns: the float64 trap is real at this size


def emulate(clock, *, seconds, ppm, rng, t0_us=0, jitter_mean_ns=2e6, start_index=0,
            host_offset_ns=0):
    """Run the clock over an emulated link; return the released (stamps, errors) in ns."""
    nbatch = int(seconds * ODR / BATCH)
    stamps, errors = [], []
    waiting = np.zeros(0)  # true times of samples the clock holds while its epoch settles
    for b in range(nbatch):
        k = start_index + b * BATCH + np.arange(BATCH)
        dev_us = np.floor(k * 1e6 / ODR)           # device microseconds since its t0
        t_us = ((t0_us + dev_us.astype(np.int64)) % 2 ** 32).astype(np.uint32)
        # device clock runs fast by ppm: true host time = device time / (1 + ppm)
        true_ns = H0 + host_offset_ns + dev_us * 1000.0 / (1.0 + ppm * 1e-6)
        recv = int(true_ns[-1] + LATENCY_NS + rng.exponential(jitter_mean_ns))
        st = clock.update(t_us, recv)
        waiting = np.concatenate((waiting, true_ns))
        stamps.append(st)
        errors.append(st - waiting[:st.size] - LATENCY_NS)
        waiting = waiting[st.size:]
    return np.concatenate(stamps), np.concatenate(errors)


def test_unwrapper_across_wrap_and_backward_jump():
    u = Unwrapper()
    out = u.unwrap(np.array([2 ** 32 - 2, 2 ** 32 - 1, 0, 5], dtype=np.uint32))
    assert out.tolist() == [2 ** 32 - 2, 2 ** 32 - 1, 2 ** 32, 2 ** 32 + 5]
    out = u.unwrap(np.array([7, 3], dtype=np.uint32))
    assert out.tolist() == [2 ** 32 + 7, 2 ** 32 + 3]  # backward jump shows as a decrease


def test_unwrapper_hint_selects_whole_wraps():
    u = Unwrapper()
    u.unwrap(np.array([100], dtype=np.uint32))
    # 3 wraps and 50 counts later: without a hint this is indistinguishable from +50
    out = u.unwrap(np.array([150], dtype=np.uint32), hint=3 * 2 ** 32 + 49.7)
    assert out.tolist() == [100 + 3 * 2 ** 32 + 50]


@pytest.mark.parametrize('ppm, t0_us', [(50.0, 2 ** 32 - 20_000_000), (-50.0, 0)])
def test_estimator_error_well_below_jitter(ppm, t0_us):
    rng = np.random.default_rng(11)
    clock = DeviceClock(nominal_rate_hz=ODR)
    stamps, err = emulate(clock, seconds=90, ppm=ppm, rng=rng, t0_us=t0_us)
    assert np.all(np.diff(stamps) > 0)
    settled = err[int(5 * ODR):]  # after 5 s (5 closed blocks)
    # Jitter is Exp(2 ms). Block minima of ~417 draws sit ~5 us above the latency and their least-
    # squares line over 60 blocks has an offset error of a few us; allow 100 us for the worst
    # sample (20x below the 2 ms mean jitter, 1.5 % of a sample period) and 25 us for the mean.
    assert np.max(np.abs(settled)) < 100_000
    assert abs(np.mean(settled)) < 25_000
    # the drift estimate: the device runs fast by ppm, so host/device rate is 1/(1+ppm) - 1 ~ -ppm
    assert clock.state.drift_ppm == pytest.approx(-ppm, abs=1.0)
    # the first second: slope not yet known, stamps late by at most the earliest batch's delay
    # (~ms)
    assert np.max(np.abs(err[:int(ODR)])) < 20e6


def test_stamps_never_after_receive_time():
    rng = np.random.default_rng(2)
    clock = DeviceClock()
    for b in range(2000):
        t = ((np.arange(BATCH) + b * BATCH) * 150).astype(np.uint32)
        recv = H0 + int(t[-1]) * 1000 + int(rng.exponential(1e6))
        st = clock.update(t, recv)
        assert st[-1] <= recv


def test_board_restart_resets_estimator_and_stays_monotonic():
    rng = np.random.default_rng(3)
    clock = DeviceClock(nominal_rate_hz=ODR)
    s1, _ = emulate(clock, seconds=10, ppm=20.0, rng=rng, t0_us=500_000_000)
    # the board restarts 2 s later: device time starts again at 0, host time continues
    s2, e2 = emulate(clock, seconds=20, ppm=20.0, rng=rng, t0_us=0, host_offset_ns=12_000_000_000)
    assert clock.state.resets == 1
    stamps = np.concatenate((s1, s2))
    assert np.all(np.diff(stamps) > 0)
    assert np.max(np.abs(e2[int(5 * ODR):])) < 100_000


def test_long_unplug_across_counter_wraps_is_bridged():
    rng = np.random.default_rng(4)
    clock = DeviceClock(nominal_rate_hz=ODR)
    emulate(clock, seconds=20, ppm=30.0, rng=rng)
    # unplugged for 2.5 hours (more than two wraps of the us counter); the board kept its clock
    gap_samples = int(2.5 * 3600 * ODR) // BATCH * BATCH
    start = int(20 * ODR) // BATCH * BATCH + gap_samples
    _, err = emulate(clock, seconds=5, ppm=30.0, rng=rng, start_index=start)
    assert clock.state.resets == 0
    # A wrong number of wraps would be off by 71.6 min per wrap. What remains is the slope error of
    # a fit over 20 blocks (~5 us noise each: ~0.2 ppm, 1.8 ms over 9000 s at one sigma): allow 10
    # ms just after the gap, and 1 ms once 5 s of new blocks anchor the line on both sides of the
    # gap.
    assert np.max(np.abs(err)) < 10_000_000
    assert np.max(np.abs(err[-int(ODR):])) < 1_000_000


def test_reset_keeps_monotonic_floor_and_bad_parameters_raise():
    clock = DeviceClock()
    a = clock.update(np.array([1000, 2000], dtype=np.uint32), H0)
    clock.reset()
    b = clock.update(np.array([1000, 2000], dtype=np.uint32), H0 - 10_000_000)
    assert b[0] > a[-1]
    for kwargs in ({'nominal_rate_hz': 0}, {'block_s': -1}, {'window_blocks': 1},
                   {'reset_threshold_s': 0}):
        with pytest.raises(ParameterError):
            DeviceClock(**kwargs)


def _loss_read_downstream(stamps):
    """Return the samples lost and clock steps the analyzer reads in the stamps (core.stamps)."""
    from gyro_noise_ros.core.stamps import StampAccountant

    accountant = StampAccountant(None, 1.5, 10000)
    for i in range(0, stamps.size, 700):
        accountant.add(stamps[i:i + 700], ())
    accountant.flush()
    counts = accountant.counts(chunks=0, tail_samples=0, discarded_samples=0,
                               discarded_partials=0)
    return counts.samples_lost, counts.clock_steps


@pytest.mark.parametrize('ppm', [50.0, -50.0])
def test_stamps_never_step_so_no_loss_is_invented(ppm):
    # Issue 29: the estimate's corrections once made the stamps step by fractions of a period,
    # read downstream as lost samples. Held while the offset settles, then slewed: every step is
    # a period within the slew (500 ppm) and the compression of a late batch.
    rng = np.random.default_rng(21)
    clock = DeviceClock(nominal_rate_hz=ODR, settle_s=0.5)
    stamps, err = emulate(clock, seconds=40, ppm=ppm, rng=rng)
    assert stamps.size == int(40 * ODR) // BATCH * BATCH  # nothing held back at the end
    ratio = np.diff(stamps) / (1e9 / ODR)
    # 149/150 us device steps (integer microseconds) are +-0.5 % of a period; the rest is
    # drift, slew and compressions of at most a few tens of microseconds per batch.
    assert 0.97 < ratio.min() and ratio.max() < 1.03
    # settled before the first stamp: within the jitter's block minimum from the start
    assert np.max(np.abs(err)) < 100_000
    assert _loss_read_downstream(stamps) == (0, 0)
    assert clock.state.settled and clock.state.held == 0 and clock.state.steps == 0


def test_dropped_samples_are_counted_exactly_downstream():
    # The board drops samples (its counter and clock run on): the stamps keep the gaps whole.
    rng = np.random.default_rng(22)
    clock = DeviceClock(nominal_rate_hz=ODR, settle_s=0.5)
    keep = np.ones(int(30 * ODR) // BATCH * BATCH, bool)
    dropped = rng.choice(np.arange(int(2 * ODR), keep.size - 100), size=40, replace=False)
    keep[dropped] = False
    stamps = []
    for b in range(keep.size // BATCH):
        k = b * BATCH + np.arange(BATCH)
        k = k[keep[k]]
        if k.size == 0:
            continue
        dev_us = np.floor(k * 1e6 / ODR).astype(np.int64)
        recv = int(H0 + (b + 1) * BATCH * 1e9 / ODR + LATENCY_NS + rng.exponential(2e6))
        stamps.append(clock.update(dev_us.astype(np.uint32), recv))
    stamps = np.concatenate(stamps)
    assert stamps.size == keep.sum()
    assert _loss_read_downstream(stamps) == (40, 0)


def test_settling_holds_the_first_samples_then_releases_them_in_order():
    clock = DeviceClock(nominal_rate_hz=ODR, settle_s=0.1)
    released = []
    for b in range(60):
        t = ((np.arange(BATCH) + b * BATCH) * 150).astype(np.uint32)
        out = clock.update(t, H0 + int(t[-1]) * 1000 + 300_000)
        released.append(out.size)
        if b * BATCH * 150 < 100_000 - BATCH * 150:
            assert out.size == 0 and clock.state.held == (b + 1) * BATCH
    first = next(i for i, n in enumerate(released) if n)
    assert released[first] == (first + 1) * BATCH  # all held samples, then one batch at a time
    assert set(released[first + 1:]) == {BATCH}
    # a reset releases nothing by itself: flush stamps the held ones first
    clock.reset()
    t = np.arange(BATCH, dtype=np.uint32) * 150
    assert clock.update(t, H0 + 10**10).size == 0
    flushed = clock.flush()
    assert flushed.size == BATCH and clock.state.held == 0
    with pytest.raises(ParameterError):
        DeviceClock(settle_s=-1.0)


def test_a_late_read_is_not_a_clock_jump():
    # The host stalls for 0.8 s (a loaded machine): the board's bytes wait in the port and arrive
    # in one read at the end of the stall, 0.8 s after the previous read but only one period
    # later in device time. Device time did not jump: no reset, no step in the stamps.
    rng = np.random.default_rng(23)
    clock = DeviceClock(nominal_rate_hz=ODR, settle_s=0.5)
    before, _ = emulate(clock, seconds=5, ppm=30.0, rng=rng)
    k0 = int(5 * ODR) // BATCH * BATCH
    n = int(0.8 * ODR)
    dev_us = np.floor((k0 + np.arange(n)) * 1e6 / ODR).astype(np.int64)
    true_last = H0 + dev_us[-1] * 1000.0 / (1 + 30e-6)
    late = clock.update(dev_us.astype(np.uint32), int(true_last + LATENCY_NS + 1e5))
    after, err = emulate(clock, seconds=2, ppm=30.0, rng=rng, start_index=k0 + n)
    assert clock.state.resets == 0
    stamps = np.concatenate((before, late, after))
    ratio = np.diff(stamps) / (1e9 / ODR)
    assert 0.97 < ratio.min() and ratio.max() < 1.03
    assert np.max(np.abs(err)) < 100_000


class _GeneralClock(DeviceClock):
    """The clock without its steady-batch path: every batch goes the general way."""

    def _update_steady(self, raw, h):
        return None


def _clock_state(clock):
    return (clock.state, clock._pub, clock._pub_rate, clock._last_stamp, clock._last_d,
            clock._last_h, clock._unwrap.last, clock._cur_min, clock._cur_block,
            list(clock._blocks), clock._a, clock._s, clock._d0, clock._compressed)


_BATCHES = st.lists(st.tuples(
    st.integers(1, 20),
    st.sampled_from(['next'] * 12 + ['gap', 'back', 'restart', 'same', 'shuffle', 'jump']),
    st.sampled_from(['jitter'] * 6 + ['late', 'early', 'stall', 'away'])),
    min_size=40, max_size=150)


@settings(deadline=None, max_examples=60, database=None)
@given(st.integers(0, 2 ** 32 - 1), st.sampled_from([0.0, 0.003]), st.sampled_from([0, 150_000]),
       _BATCHES)
def test_the_steady_path_stamps_and_steers_as_the_general_path(t0, settle_s, latency_ns,
                                                               batches):
    """Random device steps and receive delays: the same stamps and state after every batch."""
    kwargs = {'nominal_rate_hz': ODR, 'settle_s': settle_s, 'block_s': 0.01, 'window_blocks': 4,
              'latency_ns': latency_ns}
    fast, general = DeviceClock(**kwargs), _GeneralClock(**kwargs)
    rng = np.random.default_rng(t0)
    dev, host = t0, H0
    for size, step, delay in batches:
        gap = {'gap': 5000, 'back': -10 ** 6, 'restart': -(t0 % 10 ** 6) - 1, 'same': 0,
               'jump': 2 ** 31 + 7}.get(step, 150)
        times = dev + gap + 150 * np.arange(size)
        if step == 'same':
            times[:] = dev
        if step == 'shuffle':
            times = rng.permutation(times)
        dev = int(times.max())
        host += 150_000 * size + max(0, gap) * 1000 * (step == 'gap')
        recv = host + {'jitter': int(rng.exponential(80_000)), 'late': 30_000_000,
                       'early': -400_000, 'stall': 700_000_000,
                       'away': 2 ** 31 * 1000 + 5}[delay]
        if delay == 'away':
            host += 2 ** 31 * 1000
        words = np.zeros(size, [('seq', '<u4'), ('t_us', '<u4')])  # strided, as the driver's
        words['t_us'] = np.asarray(times, np.int64) % 2 ** 32
        got, want = fast.update(words['t_us'], recv), general.update(words['t_us'], recv)
        assert got.dtype == want.dtype and np.array_equal(got, want)
        assert _clock_state(fast) == _clock_state(general)


def test_the_steady_path_takes_the_usual_batches():
    """On a plain emulated link nearly every batch after the first takes it."""
    clock = DeviceClock(nominal_rate_hz=ODR)
    taken = [0]
    steady = clock._update_steady

    def counted(raw, h):
        out = steady(raw, h)
        taken[0] += out is not None
        return out

    clock._update_steady = counted
    emulate(clock, seconds=2.0, ppm=50.0, rng=np.random.default_rng(1), jitter_mean_ns=1e5)
    batches = int(2.0 * ODR / BATCH)
    assert taken[0] >= 0.95 * batches
