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

"""The plausible die temperature: range, saturated words, jumps, kelvin; offline and live."""

from gyro_noise_ros.core import plausible
from gyro_noise_ros.core.plausible import (LiveTemperatureScreen, looks_like_kelvin,
                                           screen_temperature, TemperatureLimits)
from gyro_noise_ros.link import lsm6dso32
import numpy as np
import pytest

RATE = 52.0


def _stream(seconds=120.0, slope=0.3, seed=0):
    """Return an LSM6DSO32-like stream: a ramp, 0.02 degC noise, rounded to 1/256 degC."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / RATE)
    temp = 15.0 + slope * t + rng.normal(0.0, 0.02, t.size)
    return t, np.round(temp * 256.0) / 256.0


def test_sensor_numbers_are_the_link_layer_ones():
    assert plausible.TEMPERATURE_LSB_PER_C == lsm6dso32.TEMPERATURE_LSB_PER_C
    assert plausible.TEMPERATURE_OFFSET_C == lsm6dso32.TEMPERATURE_OFFSET_C
    high, low = TemperatureLimits().saturated_c()
    assert high == pytest.approx(float(lsm6dso32.temperature_c(0x7FFF)))
    assert low == pytest.approx(float(lsm6dso32.temperature_c(-0x8000)))


def test_a_plausible_stream_keeps_every_reading():
    # a ramp at 0.3 degC/s with noise and LSB steps: nothing is a jump
    t, temp = _stream()
    screen = screen_temperature(t, temp)
    assert screen.keep.all() and screen.first_index is None and screen.dropped == 0


def test_each_kind_of_implausible_reading_is_counted():
    t, temp = _stream()
    temp[100] = TemperatureLimits().saturated_c()[0]     # 0x7FFF
    temp[200] = 1e6
    temp[300] = -60.0
    temp[400] = temp[400] + 30.0                          # in range, 30 degC in 19 ms
    temp[500:502] = 70.0                                  # two glitches in a row
    screen = screen_temperature(t, temp)
    assert (screen.saturated, screen.out_of_range, screen.jumps) == (1, 2, 3)
    assert screen.first_index == 100
    assert np.flatnonzero(~screen.keep).tolist() == [100, 200, 300, 400, 500, 501]
    text = screen.text(t, temp)
    assert '6 of 6240' in text and 'the first at 1.923 s (152.996 degC)' in text


def test_a_fast_but_possible_change_is_not_a_jump():
    # 4 degC/s (below the 5 degC/s limit) for 10 s, then a hold: every reading kept
    t = np.arange(0.0, 30.0, 1.0 / RATE)
    temp = 20.0 + 4.0 * np.clip(t - 10.0, 0.0, 10.0)
    assert screen_temperature(t, temp).keep.all()
    # a sparse stream (one reading every 5 s) moving 20 degC between readings is kept too:
    # the allowance grows with the time to the neighbours
    t = np.arange(0.0, 60.0, 5.0)
    assert screen_temperature(t, 20.0 + 4.0 * t / 5.0 * 5.0 / 5.0).keep.all()


def test_kelvin_is_recognised_and_degc_is_not():
    _, temp = _stream()
    assert looks_like_kelvin(temp + 273.15)
    assert not looks_like_kelvin(temp)
    # a kelvin stream with one glitch is still recognised (the glitch is screened afterwards)
    glitched = temp + 273.15
    glitched[7] = 1e6
    assert looks_like_kelvin(glitched)
    # a hot degC stream just above the range is not kelvin (its readings are not 233..358)
    assert not looks_like_kelvin(np.full(100, 90.0))


def test_live_screen_rejects_what_the_offline_screen_drops():
    t, temp = _stream()
    temp[[100, 200, 400]] = (153.0, 1e6, temp[400] + 30.0)
    live = LiveTemperatureScreen()
    keep = np.concatenate([live.accept(t[i:i + 37], temp[i:i + 37])
                           for i in range(0, t.size, 37)])
    assert np.flatnonzero(~keep).tolist() == [100, 200, 400]
    assert live.rejected == 3


def test_live_screen_accepts_a_level_that_persists():
    # a stream restarted at another level after a gap: rejected at first, accepted once it
    # persisted for reset_after readings
    t = np.arange(0.0, 10.0, 1.0 / RATE)
    temp = np.where(t < 5.0, 20.0, 40.0)
    live = LiveTemperatureScreen(reset_after=10)
    keep = live.accept(t, temp)
    first = int(np.argmax(t >= 5.0))
    assert not keep[first:first + 10].any() and keep[first + 10:].all() and keep[:first].all()


def test_the_live_screens_median_is_numpys():
    # The live screen takes the median of its last one to three readings per message in plain
    # Python; it must be np.median's number, bit for bit (ties, two values, any scale).
    from gyro_noise_ros.core.plausible import _median_of_few
    rng = np.random.default_rng(3)
    for _ in range(20000):
        values = list(rng.normal(30.0, 10.0, int(rng.integers(1, 4))) * rng.choice([1e-3, 1, 1e3]))
        if rng.random() < 0.2:
            values[-1] = values[0]
        assert _median_of_few(values) == float(np.median(values))
