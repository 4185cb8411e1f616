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
thermal.live's one-message fast path against the general path, state for state, bit for bit.

The same random streams (one message per call mostly; batches, NaN, stale stamps, glitches,
saturated words, out-of-range readings, gaps, level shifts) drive the real evaluator and a
twin whose fast path is off; after every call their whole state, return value and offsets agree.
"""

from _thermal_linear import LinearThermal
from gyro_noise_ros.core.plausible import LiveTemperatureScreen
from gyro_noise_ros.thermal.live import LiveDriftEvaluator
from gyro_noise_ros.thermal.lsq import LeastSquaresCV, RATE_SCALE_C_S
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest

NS = 1_000_000_000
PERIOD_NS = NS // 52
SATURATED_C = 25.0 + 32767.0 / 256.0   # the 0x7FFF word of the LSM6DSO32

STATE = ('_buf_t', '_buf_temp', '_knot_t', '_knot_drift', '_trusted', '_pending_t',
         '_pending_temp', '_t0_ns', 'temperature_c', 'rate_c_s', 'status', 'stamp_ns', 'knots',
         'knots_by_status', 'knots_rate_outside', 'knots_outside', 'rejected', '_played')
SCREEN_STATE = ('_recent', '_rejected_run', 'rejected')


class _GeneralOnly(LiveDriftEvaluator):
    """The evaluator with its fast path off: every call takes the general (array) path."""

    def _add_one(self, stamp_ns, temperature_c):
        return None


class _Counting(LiveDriftEvaluator):
    """The real evaluator, counting the calls its fast path took."""

    fast = 0

    def _add_one(self, stamp_ns, temperature_c):
        added = super()._add_one(stamp_ns, temperature_c)
        self.fast += added is not None
        return added


def _bits(value):
    """Return a value's exact identity: arrays by dtype, shape and bytes; scalars by repr."""
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, dict):
        return {k: _bits(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_bits(v) for v in value]
    if isinstance(value, tuple):
        return tuple(_bits(v) for v in value)
    return (type(value).__name__, repr(value))


def _state(ev):
    return ({name: _bits(getattr(ev, name)) for name in STATE},
            {name: _bits(getattr(ev._screen, name)) for name in SCREEN_STATE})


def _hysteresis_model(rate_gain):
    """Return a fitted lsq_cv with a 1-degC hysteresis term (a dT term if rate_gain != 0)."""
    terms = ['1', 'x1', 'h1.0'] + (['r'] if rate_gain else [])
    coef = [[1e-3, 2e-3, 5e-4] + ([rate_gain] if rate_gain else []),
            [-1e-3, 1e-3, 2e-4] + ([-rate_gain] if rate_gain else []),
            [0.0, -2e-3, 1e-4] + ([rate_gain] if rate_gain else [])]
    model = LeastSquaresCV.from_dict({
        'method': 'lsq_cv', 'rate_scale_c_s': RATE_SCALE_C_S, 'max_degree': 3, 'folds': 5,
        'widths_c': [1.0], 'rate_window_s': 1.0, 'terms': terms, 'coef_rad_s': coef,
        't_centre_c': 25.0, 't_scale_c': 5.0, 'input_min': [20.0, -0.1],
        'input_max': [30.0, 0.1]})
    assert model.hysteresis_c == 1.0
    return model


def _model(kind):
    if kind.startswith('hysteresis'):
        return _hysteresis_model(0.02 if kind.endswith('rate') else 0.0)
    # range 20-30 degC, margin 5: the wandering level visits every range status
    return LinearThermal(sensitivity=(1e-3, -2e-3, 5e-4), offset=(1e-3, 0.0, -1e-3),
                         rate_gain=(0.01, 0.02, -0.03) if kind == 'rate' else (0.0, 0.0, 0.0))


# 'one' (a plain message) dominates, as live; each other kind is one unusual call
KINDS = ('one',) * 20 + ('batch', 'shuffled', 'nan', 'older', 'same', 'jump', 'saturated',
                         'range', 'gap', 'level', 'list', 'float32', 'empty')


class _Stream:
    """Temperature messages around a wandering level, one call's worth at a time."""

    def __init__(self, seed, start_c, drift_c=0.0):
        self.rng = np.random.default_rng(seed)
        self.stamp = 5 * NS + int(self.rng.integers(0, NS))
        self.level, self.drift_c = start_c, drift_c

    def _next(self, gap_ns=0):
        self.stamp += gap_ns + int(self.rng.integers(int(0.8 * PERIOD_NS), int(1.2 * PERIOD_NS)))
        self.level += self.drift_c + float(self.rng.normal(0.0, 0.02))
        return self.stamp, self.level + float(self.rng.normal(0.0, 0.01))

    def call(self, kind, size):
        """Return (stamps, temperatures) of one add_temperature call of this kind."""
        if kind in ('batch', 'shuffled'):
            msgs = [self._next() for _ in range(size)]
            if kind == 'shuffled':
                msgs = [msgs[i] for i in self.rng.permutation(size)]
        elif kind == 'empty':
            msgs = []
        elif kind in ('older', 'same'):
            msgs = [(self.stamp - (NS // 100 if kind == 'older' else 0), self.level)]
        else:
            if kind == 'level':
                self.level += 8.0   # a persisting shift: rejected until the screen resets
            stamp, temp = self._next(gap_ns=3 * NS if kind == 'gap' else 0)
            temp = {'nan': np.nan, 'jump': temp + 30.0, 'saturated': SATURATED_C,
                    'range': 95.0}.get(kind, temp)
            msgs = [(stamp, temp)]
        stamps = np.array([m[0] for m in msgs], dtype=np.int64)
        temps = np.array([m[1] for m in msgs], dtype=np.float64)
        if kind == 'list':
            return [int(s) for s in stamps], [float(v) for v in temps]
        if kind == 'float32':
            return stamps, temps.astype(np.float32)
        return stamps, temps


@pytest.mark.parametrize('model', ['rate', 'plain', 'hysteresis', 'hysteresis_rate'])
@settings(max_examples=25, deadline=None, database=None)
@given(seed=st.integers(0, 2 ** 32 - 1), plain=st.integers(0, 80),
       calls=st.lists(st.tuples(st.sampled_from(KINDS), st.integers(2, 5)), min_size=10,
                      max_size=200),
       window_s=st.sampled_from((0.3, 1.0)), beyond=st.sampled_from(('hold', 'none')),
       rate_range=st.sampled_from((None, (-0.2, 0.2))),
       start_c=st.floats(12.0, 38.0), drift_c=st.floats(-0.03, 0.03))
def test_fast_path_leaves_the_general_paths_state_bit_for_bit(
        model, seed, plain, calls, window_s, beyond, rate_range, start_c, drift_c):
    # `plain` one-message calls first (filling the rate window), then the drawn calls; the
    # level drifts by drift_c per message (up to 1.6 degC/s) across the range statuses
    kw = {'rate_window_s': window_s, 'beyond': beyond, 'rate_range_c_s': rate_range}
    fast = _Counting(_model(model), **kw)
    general = _GeneralOnly(_model(model), **kw)
    assert _state(fast) == _state(general)
    stream = _Stream(seed, start_c, drift_c)
    gyro_ns = stream.stamp
    for kind, size in [('one', 1)] * plain + calls:
        stamps, temps = stream.call(kind, size)
        assert fast.add_temperature(stamps, temps) == general.add_temperature(stamps, temps)
        assert _state(fast) == _state(general), kind
        # gyro stamps advance, straddling the newest knot (interpolated and held offsets)
        upto = stream.stamp + int(stream.rng.integers(-PERIOD_NS, PERIOD_NS))
        gyro = np.linspace(gyro_ns, max(upto, gyro_ns), 7).astype(np.int64)
        gyro_ns = int(gyro[-1])
        got, want = fast.drift_at(gyro), general.drift_at(gyro)
        assert _bits(got) == _bits(want)
        assert _state(fast) == _state(general)


def test_a_plain_stream_takes_the_fast_path_once_the_window_is_filled():
    # 52-Hz messages one per call: only the first (no stamp yet) and those of the filling
    # 2-s window take the general path
    stream = _Stream(7, 25.0)
    ev = _Counting(_model('rate'), rate_window_s=2.0)
    n = 600
    for _ in range(n):
        ev.add_temperature(*stream.call('one', 1))
    filling = 2.0 * NS / (0.8 * PERIOD_NS) + 1   # at most this many within the first window
    assert ev.knots == n and ev.rejected == 0
    assert n - filling <= ev.fast < n


def test_screen_accept_one_is_accept_of_one():
    # the scalar and array screens, fed the same readings, agree and end in the same state
    rng = np.random.default_rng(4)
    t = 1.0 + np.arange(400) / 52.0
    temp = 25.0 + np.cumsum(rng.normal(0.0, 0.05, 400))
    temp[rng.choice(400, 40, replace=False)] = rng.choice([np.nan, SATURATED_C, 95.0, -60.0,
                                                           60.0], 40)
    temp[200:240] += 8.0   # a level shift that persists past reset_after
    one, many = LiveTemperatureScreen(reset_after=10), LiveTemperatureScreen(reset_after=10)
    got = [one.accept_one(float(a), float(b)) for a, b in zip(t, temp)]
    want = np.concatenate([many.accept(t[i:i + 1], temp[i:i + 1]) for i in range(400)])
    assert got == want.tolist() and not all(got) and any(got)
    assert [_bits(getattr(one, k)) for k in SCREEN_STATE] == \
        [_bits(getattr(many, k)) for k in SCREEN_STATE]
