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
The compensator's reliable-input hold (``thermal.live.TemperatureGate``), without ROS.

The rules on small cases, then the property the node needs: with the temperature stream stalled
at random (in-order delivery, as a reliable subscription repairs a lost message), the offsets the
gate and the live evaluator give every sample equal those of an evaluator that knew every
temperature from the start (the twin), while without the gate they are stale.
"""

from _thermal_linear import LinearThermal
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.live import LiveDriftEvaluator, TemperatureGate
import numpy as np
import pytest


def test_before_the_first_temperature_samples_wait_then_are_dropped():
    gate = TemperatureGate(max_wait_s=1.0, first_wait_s=2.0)
    gate.push('a', [10, 11, 12], now_s=0.0)
    assert gate.release(None, 1.9) == [] and gate.waiting == 3
    gate.push('b', [13], now_s=1.0)
    assert gate.release(None, 2.5) == [] and gate.dropped == 3 and gate.waiting == 1
    # The first temperature (stamp 13) covers b's sample: published, interpolated (not late).
    assert gate.release(13, 2.6) == [('b', 0, 1, False)]
    assert gate.waiting == 0 and gate.late == 0


def test_newer_samples_wait_for_a_newer_temperature_then_go_late():
    gate = TemperatureGate(max_wait_s=1.0, first_wait_s=2.0)
    gate.push('a', [8, 9, 10, 11, 12], now_s=0.0)
    gate.push('b', [13, 14], now_s=0.1)
    # Knots up to stamp 10: a's first three go; the rest, and b behind them, wait.
    assert gate.release(10, 0.2) == [('a', 0, 3, False)]
    assert gate.waiting == 4
    assert gate.release(11, 0.5) == [('a', 3, 4, False)]
    # a's last sample has waited 1 s with no newer temperature: the newest offset, counted late.
    # b arrived 0.1 s later and still waits.
    assert gate.release(11, 1.0) == [('a', 4, 5, True)]
    assert gate.late == 1 and gate.waiting == 2
    assert gate.release(20, 1.05) == [('b', 0, 2, False)]
    assert gate.longest_wait_s == pytest.approx(0.95)


def test_zero_wait_releases_at_once_and_bad_waits_are_refused():
    gate = TemperatureGate(max_wait_s=0.0, first_wait_s=0.0)
    gate.push('a', [1, 2, 3], now_s=0.0)
    assert gate.release(1, 0.0) == [('a', 0, 1, False), ('a', 1, 3, True)]
    with pytest.raises(ParameterError):
        TemperatureGate(max_wait_s=-1.0, first_wait_s=0.0)


RATE_HZ = 6660.0
NS = 1_000_000_000


def _stalled_stream(rng, seconds, stall_prob, stall_s):
    """
    Gyro stamps at 6.66 kHz and a 52-Hz temperature ramp; arrival times of each message.

    Gyro messages arrive 1 ms after their stamp. A temperature message is delayed by a stall of
    ``stall_s`` with probability ``stall_prob`` (a lost message resent), and delivery is in order:
    nothing newer arrives before it.
    """
    n = int(seconds * RATE_HZ)
    gyro_ns = np.rint(np.arange(n) * NS / RATE_HZ).astype(np.int64)
    gyro_arrive = gyro_ns / NS + 1e-3
    # Every 128th sample's stamp, and one past the end so the last samples have a later knot.
    temp_ns = np.rint(np.arange(0, n + 128, 128) * NS / RATE_HZ).astype(np.int64)
    temp_c = 25.0 + 2.0 * temp_ns / NS  # 2 degC/s: the e2e test's ramp
    delay = 1e-3 + np.where(rng.random(temp_ns.size) < stall_prob, stall_s, 0.0)
    temp_arrive = np.maximum.accumulate(temp_ns / NS + delay)  # in order
    return gyro_ns, gyro_arrive, temp_ns, temp_c, temp_arrive


def _run_node_logic(model, stream, max_wait_s, drain_s=0.02):
    """Run the node's logic: each drain adds the temperatures arrived, then releases samples."""
    gyro_ns, gyro_arrive, temp_ns, temp_c, temp_arrive = stream
    ev = LiveDriftEvaluator(model, rate_window_s=1.0)
    gate = TemperatureGate(max_wait_s=max_wait_s, first_wait_s=2.0)
    offsets = np.full((gyro_ns.size, 3), np.nan)
    g = t = 0
    now = 0.0
    while g < gyro_ns.size or gate.waiting:
        now += drain_s
        t1 = np.searchsorted(temp_arrive, now, side='right')
        if t1 > t:
            ev.add_temperature(temp_ns[t:t1], temp_c[t:t1])
            t = t1
        g1 = np.searchsorted(gyro_arrive, now, side='right')
        if g1 > g:
            gate.push(np.arange(g, g1), gyro_ns[g:g1], now)
            g = g1
        for idx, i, j, _ in gate.release(ev.offset_stamp_ns, now):
            offsets[idx[i:j]] = ev.drift_at(gyro_ns[idx[i:j]])
        assert now < 100, 'the stream never drained'
    return offsets, gate


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_stalled_temperatures_never_give_a_stale_offset(seed):
    rng = np.random.default_rng(seed)
    model = LinearThermal(sensitivity=(3.5e-4, -3.5e-4, 1.7e-4), temperature_range_c=(0.0, 60.0))
    # 5 s of data; one temperature message in 20 stalls 0.3 s (shorter than the 1 s bound).
    stream = _stalled_stream(rng, 5.0, 0.05, 0.3)
    gyro_ns, _, temp_ns, temp_c, _ = stream
    twin = LiveDriftEvaluator(model, rate_window_s=1.0)
    twin.add_temperature(temp_ns, temp_c)
    expected = twin.drift_at(gyro_ns)
    got, gate = _run_node_logic(model, stream, max_wait_s=1.0)
    assert gate.late == 0 and not np.isnan(got).any()
    # Same knots and the same interpolation: equal to rounding (the trailing-rate sums start
    # elsewhere when the temperatures come in other batches).
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    # Without the gate (no wait) the stalls leave held offsets: wrong by up to the drift rate
    # (0.0007 rad/s per s on x) times the stall, far above rounding.
    held, gate0 = _run_node_logic(model, stream, max_wait_s=0.0)
    assert np.abs(held - expected).max() > 1e-4 and gate0.late > 0


def test_a_stall_beyond_the_bound_goes_late_and_is_counted():
    rng = np.random.default_rng(7)
    model = LinearThermal(sensitivity=(3.5e-4, 0.0, 0.0), temperature_range_c=(0.0, 60.0))
    stream = _stalled_stream(rng, 3.0, 0.02, 1.5)  # stalls of 1.5 s against a 0.5 s bound
    got, gate = _run_node_logic(model, stream, max_wait_s=0.5)
    assert gate.late > 0 and not np.isnan(got).any()  # every sample published, some late
    assert gate.dropped == 0
