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

"""The soak's memory and flow checks: a step is not a leak, a stall fails (bench/bench_soak.py)."""

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

_PATH = Path(__file__).resolve().parents[1] / 'bench' / 'bench_soak.py'
_spec = importlib.util.spec_from_file_location('bench_soak', _PATH)
assert _spec is not None and _spec.loader is not None
soak = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(soak)

FAULTS_S = (450.0, 900.0, 1350.0)  # a 30-minute run's faults


def _series(mb_of_t, seed, noise_mb=0.3, minutes=30.0):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0 * minutes + 1.0, 5.0)
    return [(float(a), float(mb_of_t(a) + rng.normal(0.0, noise_mb))) for a in t]


@pytest.mark.parametrize('seed', range(5))
def test_a_step_at_a_fault_is_not_a_leak(seed):
    # The driver in the 30-minute soak: +34 MB when the recorder was killed, flat around it.
    series = _series(lambda t: 78.0 + 34.0 * (t >= 905.0), seed)
    slope, se = soak._slope_mb_h(series, FAULTS_S)
    assert abs(slope) < 3.0 * se + 1.0, (slope, se)
    # The whole-run line (no breaks) reads the step as growth: what the check used to do.
    whole, _ = soak._slope_mb_h(series)
    assert whole > 50.0


@pytest.mark.parametrize('seed', range(5))
@pytest.mark.parametrize('leak_mb_h', [10.0, 25.0])
def test_a_leak_is_measured_between_the_faults_even_with_steps(seed, leak_mb_h):
    series = _series(lambda t: 300.0 + leak_mb_h * t / 3600.0 + 20.0 * (t >= 905.0), seed)
    slope, se = soak._slope_mb_h(series, FAULTS_S)
    assert abs(slope - leak_mb_h) < 4.0 * se, (slope, se)
    assert se < 1.5


def test_a_short_run_still_has_points_and_too_few_gives_nan():
    # --minutes 4: faults at 60, 120, 180 s; half their spacing left out after each.
    series = _series(lambda t: 100.0, 0, minutes=4.0)
    slope, se = soak._slope_mb_h(series, (60.0, 120.0, 180.0), settle_s=30.0)
    assert np.isfinite(slope) and np.isfinite(se)
    slope, _ = soak._slope_mb_h(series, (60.0, 120.0, 180.0), settle_s=60.0)
    assert np.isnan(slope)


def _allan_mb(t):
    # The analyzer's three accumulators at 6.66 kHz ('dense'): the level-0 history and, per level
    # L >= 1 seeded at N = 2**15 * 2**(L-1), the points written (x_k for k a multiple of 2**L, at
    # most 2**16 + 1), 8 bytes each: log2 growth, 9 MB/h at 15 minutes, 0.1 MB/h at 12 h.
    n = int(6660 * t)
    points = (2 ** 16 + 1) * (1 + sum(min(2 ** 16 + 1, (n >> lev) + 1) / (2 ** 16 + 1)
                                      for lev in range(1, 30) if n >= 2 ** 15 * 2 ** (lev - 1)))
    return 3 * 8 * points / 2 ** 20


@pytest.mark.parametrize('seed', range(3))
@pytest.mark.parametrize('leak_mb_h', [0.0, 12.0])
def test_the_analyzer_is_judged_beyond_its_stated_allan_storage(seed, leak_mb_h):
    # RSS = a level + the storage the analyzer states + a leak: the RSS slope alone reads the
    # storage's log2 growth as a leak, the slope beyond it is the leak.
    series = _series(lambda t: 280.0 + _allan_mb(t) + leak_mb_h * t / 3600.0
                     + 4.0 * (t >= 905.0), seed)
    allan = [(t, _allan_mb(t)) for t, _ in series]
    raw, _ = soak._slope_mb_h(series, FAULTS_S)
    assert raw > leak_mb_h + 4.0
    beyond = soak._beyond_allan(series, allan)
    assert len(beyond) == len(series)
    slope, se = soak._slope_mb_h(beyond, FAULTS_S)
    assert abs(slope - leak_mb_h) < 4.0 * se, (slope, se)
    # samples without a stated storage (the analyzer not reporting yet) are left out
    assert len(soak._beyond_allan(series, allan[10:])) == len(series) - 10


def _flow(points):
    report = {'faults': [{'kind': 'unplug', 'at_s': 450.0}], 'compensator_series': points}
    args = SimpleNamespace(settle_s=15.0, unplug_s=2.0, odr_hz=6667.0)
    checks = []
    soak._check_flow(args, report, lambda *c: checks.append(c))
    return checks[0][1], report['flow_worst']


def test_the_flow_check_fails_a_stall_and_leaves_the_unplug_out():
    t = np.arange(0.0, 1800.0, 5.0)
    steady = 6667.0 * t
    # the unplug: nothing for 5 s, then the board's buffer arrives
    unplugged = np.where((t > 450) & (t <= 455), 6667.0 * 450, steady)
    ok, worst = _flow([[a, b, b, 0, 0] for a, b in zip(t, unplugged)])
    assert ok and worst[0] > 0.99
    # session 3's soaks: after the recorder kill the stream crawled for ~30 s, then caught up
    rate = np.where((t > 900) & (t <= 930), 1500.0, 6667.0)
    crawled = np.concatenate(([0.0], np.cumsum(rate[1:] * 5.0)))
    lag = crawled - 6667.0 * t
    caught = np.where(t > 930, np.minimum(0.0, lag + 20000.0 * (t - 930)), lag)
    ok, worst = _flow([[a, b, b, 0, 0] for a, b in zip(t, 6667.0 * t + caught)])
    assert not ok and 900 <= worst[1] <= 925 and worst[0] < 0.3
    # an unknown count (None before the first status) is left out, not a stall
    ok, _ = _flow([[a, None if a < 60 else b, b, 0, 0] for a, b in zip(t, steady)])
    assert ok
