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
thermal.live against a slow twin.

Per temperature message the rate from the whole history so far, the model evaluated, then np.interp
of the offsets onto the gyro stamps.
"""

import importlib
import sys
import types

from _thermal_linear import LinearThermal
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.live import (check_live_model, LiveDriftEvaluator, load_live_model,
                                         RANGE_MARGIN, RANGE_OK, RANGE_OUTSIDE)
from gyro_noise_ros.thermal.run import temperature_rate_c_s, ThermalMethod
import numpy as np
import pytest

NS = 1_000_000_000


def _slow_twin(model, t_ns, temp, gyro_ns, window_s):
    """
    Return the twin: knot i's rate from samples 0..i only, offsets by np.interp.

    Before the window is filled (t_i < window_s) a knot takes the rate of the first knot
    whose window is, as temperature_rate_c_s(start='backfill') does offline.
    """
    t_s = (t_ns - t_ns[0]) / NS
    rates = [temperature_rate_c_s(t_s[:i + 1], temp[:i + 1], window_s=window_s,
                                  start='partial')[-1] for i in range(t_ns.size)]
    first = int(np.argmax(t_s >= window_s))
    knots = []
    for i in range(t_ns.size):
        rate = rates[i] if t_s[i] >= window_s else rates[first]
        knots.append(model.drift_rad_s(temp[i:i + 1], np.array([rate]))[0])
    knots = np.array(knots)
    x = (gyro_ns - t_ns[0]) / NS
    return np.column_stack([np.interp(x, t_s, knots[:, a]) for a in range(3)])


def _stream(seed, seconds=30.0, temp_hz=52.0, gyro_hz=6660.0):
    rng = np.random.default_rng(seed)
    t_ns = 10 * NS + np.cumsum(rng.integers(int(0.8 * NS / temp_hz), int(1.2 * NS / temp_hz),
                                            int(seconds * temp_hz)))
    t_s = (t_ns - t_ns[0]) / NS
    temp = 24.0 + 0.1 * t_s + 0.5 * np.sin(t_s / 3.0) + rng.normal(0, 0.01, t_s.size)
    gyro_ns = np.arange(t_ns[0], t_ns[-1], int(NS / gyro_hz), dtype=np.int64)
    return t_ns, temp, gyro_ns


def test_batched_evaluation_matches_slow_twin():
    model = LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), offset=(1e-3, 0.0, -1e-3),
                          rate_gain=(0.01, 0.02, -0.03), temperature_range_c=(0.0, 50.0))
    assert isinstance(model, ThermalMethod)
    t_ns, temp, gyro_ns = _stream(1)
    window = 4.0
    expected = _slow_twin(model, t_ns, temp, gyro_ns, window)
    rng = np.random.default_rng(2)
    ev = LiveDriftEvaluator(model, rate_window_s=window)
    # Feed temperatures and gyro in interleaved batches of random sizes, as the node drains them:
    # each gyro batch only after the temperatures stamped up to its last sample have arrived.
    got = []
    i_t = i_g = 0
    while i_g < gyro_ns.size:
        n_t = int(rng.integers(1, 6))
        ev.add_temperature(t_ns[i_t:i_t + n_t], temp[i_t:i_t + n_t])
        i_t += n_t
        last = t_ns[min(i_t, t_ns.size) - 1]
        stop = max(i_g, int(np.searchsorted(gyro_ns, last, side='right')))
        if i_t >= t_ns.size:
            stop = gyro_ns.size
        if stop > i_g:
            out = ev.drift_at(gyro_ns[i_g:stop])
            # no offset before the 4-s rate window has filled: the node holds those samples
            # and asks again with the next batch
            if out is not None:
                got.append(out)
                i_g = stop
            else:
                assert (t_ns[i_t - 1] - t_ns[0]) / NS < window and ev.pending == i_t
    got = np.concatenate(got)
    # Same arithmetic up to the rate's running sums, which start at another sample (trailing
    # buffer vs whole history): differences at rounding level of offsets around 1e-2 rad/s.
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    assert ev.knots == t_ns.size and ev.rejected == 0


def test_hold_after_newest_knot_and_none_before_first():
    model = LinearThermal(sensitivity=(1.0, 0.0, 0.0), temperature_range_c=(0.0, 50.0))
    ev = LiveDriftEvaluator(model, rate_window_s=1.0)
    assert ev.drift_at(np.array([0, 1])) is None
    ev.add_temperature([NS, 2 * NS], [25.0, 27.0])
    out = ev.drift_at(np.array([NS, 3 * NS // 2, 5 * NS]))
    rate = 2.0  # two samples 1 s apart within the 1-s window: the slope is exact
    np.testing.assert_allclose(out[:, 0], [0.0, 1.0, 2.0])
    assert ev.rate_c_s == pytest.approx(rate)


def test_start_up_waits_for_the_rate_window_and_backfills():
    model = LinearThermal(rate_gain=(1.0, 0.0, 0.0), temperature_range_c=(0.0, 50.0))
    ev = LiveDriftEvaluator(model, rate_window_s=2.0, rate_range_c_s=(0.0, 0.5))
    assert ev.start_up_s == 2.0
    # a 0.25 degC/s ramp read every 0.5 s: no offset until 2 s after the first message
    ev.add_temperature(NS // 2 * np.arange(4), 20.0 + 0.125 * np.arange(4))
    assert ev.drift_at(np.array([0])) is None and ev.pending == 4 and ev.knots == 4
    ev.add_temperature(NS // 2 * np.arange(4, 6), 20.0 + 0.125 * np.arange(4, 6))
    assert ev.pending == 0
    # every knot, the waiting ones too, carries the first filled window's rate (exact on a
    # ramp): the offline backfill
    out = ev.drift_at(NS // 2 * np.arange(6))
    temps = 20.0 + 0.125 * np.arange(6)
    np.testing.assert_allclose(out[:, 0] - model.drift_rad_s(temps, np.zeros(6))[:, 0], 0.25,
                               atol=1e-12)
    assert ev.knots_rate_outside == 0
    # a cooling rate is outside the trained (heating) rate range: counted, not clipped
    ev.add_temperature(NS // 2 * np.arange(6, 16), 20.625 - 0.5 * np.arange(1, 11))
    assert ev.knots_rate_outside >= 5 and ev.rate_c_s < 0
    poly = LinearThermal(temperature_range_c=(0.0, 50.0))
    poly.uses_rate = False
    ev = LiveDriftEvaluator(poly, rate_window_s=2.0)
    assert ev.start_up_s == 0.0
    ev.add_temperature([NS], [25.0])
    assert ev.drift_at(np.array([NS])) is not None


def test_stale_and_non_finite_temperatures_are_rejected():
    ev = LiveDriftEvaluator(LinearThermal(temperature_range_c=(0.0, 50.0)))
    assert ev.add_temperature([2 * NS, 3 * NS], [25.0, float('nan')]) == 1
    assert ev.add_temperature([NS, 2 * NS, 4 * NS], [25.0, 25.0, 26.0]) == 1
    assert ev.rejected == 3 and ev.knots == 2


def test_range_status_and_never_extrapolated():
    model = LinearThermal(sensitivity=(1.0, 1.0, 1.0), temperature_range_c=(20.0, 30.0),
                          range_margin_c=2.0)
    lo, hi, margin = check_live_model(model)
    assert (lo, hi, margin) == (20.0, 30.0, 2.0)
    ev = LiveDriftEvaluator(model, rate_window_s=0.5)
    temps = [25.0, 31.0, 33.0, 37.0, 29.0]   # at most 4 degC/s: a die can move so
    stamps = NS * np.arange(1, 6)
    ev.add_temperature(stamps, temps)
    np.testing.assert_array_equal(ev.range_status(temps), [RANGE_OK, RANGE_MARGIN, RANGE_OUTSIDE,
                                                           RANGE_OUTSIDE, RANGE_OK])
    assert ev.knots_by_status == {RANGE_OK: 2, RANGE_MARGIN: 1, RANGE_OUTSIDE: 2}
    # Knot offsets: 33 and 40 degC hold the offset evaluated at 31 degC (within the margin).
    out = ev.drift_at(stamps)[:, 0]
    np.testing.assert_allclose(out, [0.0, 6.0, 6.0, 6.0, 4.0])
    ev_none = LiveDriftEvaluator(model, rate_window_s=0.5, beyond='none')
    ev_none.add_temperature(stamps, temps)
    np.testing.assert_allclose(ev_none.drift_at(stamps)[:, 0], [0.0, 6.0, 0.0, 0.0, 4.0])
    assert ev_none.status == RANGE_OK


@pytest.mark.parametrize('name, words', [('parallel', 'VMD'), ('wtd', 'wavelet'),
                                         ('emd_wtd_sabp', 'EMD')])
def test_non_causal_models_are_refused_naming_the_offline_steps(name, words):
    model = LinearThermal(name=name)
    with pytest.raises(ParameterError) as err:
        LiveDriftEvaluator(model)
    assert name in str(err.value) and words in str(err.value) and 'offline' in str(err.value)
    model = LinearThermal()
    model.causal = False
    with pytest.raises(ParameterError, match='not causal'):
        check_live_model(model)


def test_model_without_range_is_refused():
    model = LinearThermal()
    model.temperature_range_c = None
    with pytest.raises(ParameterError, match='no training temperature range'):
        check_live_model(model)


def test_model_with_wrong_output_shape_is_refused_at_start():
    model = LinearThermal()
    model.drift_rad_s = lambda temperature_c, dtemp_c_s: np.zeros((len(temperature_c), 1))
    with pytest.raises(ParameterError, match=r'finite \(n, 3\) offsets'):
        check_live_model(model)


class _Training:

    temperature_min_c, temperature_max_c = 10.0, 40.0


class _Loaded:
    """The registry's ThermalModel shape: the fitted method and what it was trained on."""

    def __init__(self, method):
        self.method, self.training = method, _Training()


def _fake_registry(monkeypatch, method):
    module = types.ModuleType('gyro_noise_ros.thermal.methods')
    module.DEFAULT_RANGE_MARGIN_C = 3.0
    module.load_model = lambda path: _Loaded(method)
    monkeypatch.setitem(sys.modules, 'gyro_noise_ros.thermal.methods', module)
    # `from . import methods` reads the package attribute once the real module was imported
    monkeypatch.setattr(importlib.import_module('gyro_noise_ros.thermal'), 'methods', module,
                        raising=False)


def test_model_file_range_comes_from_the_training_record(monkeypatch):
    method = LinearThermal(temperature_range_c=None)
    _fake_registry(monkeypatch, method)
    got, range_c, margin = load_live_model('model.json')
    assert got is method and range_c == (10.0, 40.0) and margin == 3.0
    ev = LiveDriftEvaluator(got, range_c=range_c, margin_c=margin)
    assert (ev.range_lo_c, ev.range_hi_c, ev.margin_c) == (10.0, 40.0, 3.0)


def test_implausible_temperatures_are_rejected_live():
    # a 0x7FFF word and an in-range jump of 30 degC in 19 ms: rejected and counted like NaN,
    # the offsets come from the plausible messages only
    model = LinearThermal(sensitivity=(1.0, 1.0, 1.0), temperature_range_c=(10.0, 60.0))
    t_ns = NS * (1.0 + np.arange(200) / 52.0)
    temps = 20.0 + 0.01 * np.arange(200)
    bad = temps.copy()
    bad[[50, 120]] = (25.0 + 32767.0 / 256.0, temps[120] + 30.0)
    ev = LiveDriftEvaluator(model, rate_window_s=0.5)
    clean = LiveDriftEvaluator(model, rate_window_s=0.5)
    ev.add_temperature(t_ns.astype(np.int64), bad)
    keep = np.ones(200, dtype=bool)
    keep[[50, 120]] = False
    clean.add_temperature(t_ns.astype(np.int64)[keep], temps[keep])
    assert ev.rejected == 2 and ev.knots == 198
    gyro_ns = np.linspace(t_ns[0], t_ns[-1], 1000).astype(np.int64)
    np.testing.assert_array_equal(ev.drift_at(gyro_ns), clean.drift_at(gyro_ns))


def test_hysteresis_state_is_carried_from_message_to_message():
    # an lsq_cv model with a hysteresis term, fed the temperature in batches, gives the offsets
    # of its offline apply on the whole history (the play operator's state carried over)
    from gyro_noise_ros.thermal.hysteresis import play_operator
    from gyro_noise_ros.thermal.lsq import LeastSquaresCV
    from gyro_noise_ros.thermal.run import ThermalRun

    rate_hz = 5.0
    t = np.arange(30000) / rate_hz
    temp = 30.0 - 10.0 * np.cos(2.0 * np.pi * t / 4000.0)
    drift = 1e-4 * (temp - 30.0) + 0.004 * (play_operator(temp, 1.0) - temp)
    gyro = np.outer(drift, [1.0, -1.0, 0.5])
    model = LeastSquaresCV()
    model.fit(ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=rate_hz),
              rng=np.random.default_rng(0))
    assert model.hysteresis_c == 1.0
    ev = LiveDriftEvaluator(model)
    t_ns = (NS * (1.0 + t)).astype(np.int64)
    for lo in range(0, t.size, 777):
        ev.add_temperature(t_ns[lo:lo + 777], temp[lo:lo + 777])
    offline = model.drift_rad_s(temp, temperature_rate_c_s(t, temp))
    np.testing.assert_allclose(ev.drift_at(t_ns), offline, atol=1e-15)
