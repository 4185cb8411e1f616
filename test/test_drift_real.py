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

"""Offset-drift significance on the six real ADIS16405 runs (correlated chunk biases)."""

import itertools

from _realdata import real_data
from gyro_noise_ros.core.chunks import summarise_sequence
from gyro_noise_ros.core.engine import StreamCounts
from gyro_noise_ros.core.health import evaluate_health, ReferenceStats
from gyro_noise_ros.core.results import AxisSummary
import numpy as np
import pytest

CHUNK = 10_000


@pytest.fixture(scope='module')
def runs():
    out = {}
    for k in range(1, 7):
        path = real_data('adis16405_static', f'adis_16405_imu{k}.npz')
        g = np.deg2rad(np.load(path)['gyro_dps'])
        t = (np.arange(100) * CHUNK + (CHUNK - 1) / 2) / 100.0  # 100 Hz, no stamps (SOURCE.md)
        for ax in range(3):
            c = g[:, ax].reshape(100, CHUNK)
            out[(k, ax)] = summarise_sequence(t, c.mean(1), c.var(1, ddof=1), np.full(100, 0.5),
                                              np.full(100, 0.5))
    return out


def _summary(seq):
    stream = StreamCounts(samples=10 ** 6, samples_lost=0, gaps=0, out_of_order=0, chunks=100,
                          tail_samples=0, discarded_samples=0, discarded_partials=0, rate_hz=100.0,
                          duration_s=1e4)
    return AxisSummary('x', seq, stream, 0, 100, 0, 0, 0, 0, float('nan'))


def _drift_level(seq, ref):
    rs = ReferenceStats(ref.drift.slope, ref.mean_variance, 0.5, 0.5, chunks=ref.chunks,
                        offset_drift_stderr_rad_s2=ref.drift.stderr)
    items = evaluate_health(_summary(seq), reference=rs).items
    return next(level for key, _, level in items if key == 'Offset drift deviation (sigma)')


def test_drift_stderr_follows_the_spread_across_runs(runs):
    for ax in range(3):
        slopes = np.array([runs[(k, ax)].drift.slope for k in range(1, 7)])
        se = np.array([runs[(k, ax)].drift.stderr for k in range(1, 7)])
        ols = np.array([runs[(k, ax)].drift.stderr_ols for k in range(1, 7)])
        spread = slopes.std(ddof=1)
        # The issue measured the spread at 4.6-7.1x the OLS error (neighbouring chunk biases
        # correlate at 0.5-0.9). The correlated-residual error must close most of that gap; with
        # six runs the spread itself is known to about +/-30 %, so a factor 3.5 is allowed.
        assert spread > 4 * ols.mean()
        assert se.mean() > 1.8 * ols.mean()
        assert spread < 3.5 * se.mean()


def test_imu2_against_imu1_is_not_an_error(runs):
    for ax in range(3):
        assert _drift_level(runs[(2, ax)], runs[(1, ax)]) != 'ERROR'


def test_false_alarms_over_all_pairs_of_real_runs(runs):
    # None of the six static runs drifts; the difference of two slopes is judged against both
    # standard errors at the verdict's thresholds (5 sigma, Student-t equivalent); the errors are
    # still 1-2.5x below the real spread of slopes (above), so allow 2 of the 90 (run,
    # reference, axis) cases to alarm (docs/verdicts.md measures 0).
    levels = [_drift_level(runs[(a, ax)], runs[(r, ax)])
              for a, r in itertools.permutations(range(1, 7), 2) for ax in range(3)]
    assert sum(lvl != 'OK' for lvl in levels) <= 2
