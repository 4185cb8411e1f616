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

"""The held-out table: residuals against the simulated run's own noise and against poly3."""

from gyro_noise_ros.thermal import heldout
from gyro_noise_ros.thermal.heldout import HeldoutMethod, score_pair, summarise
import numpy as np
import pytest

FAST = (HeldoutMethod('lsq_cv (default)', 'lsq_cv'), HeldoutMethod('poly3', 'poly3'))


@pytest.fixture(scope='module')
def scores():
    # two seeds of a short heating -> cooling pair at 5 Hz (cheap; the docs use 20 Hz, 1 h)
    return [score_pair('heating', 'cooling', seed, methods=FAST, rate_hz=5.0, hours=0.5)
            for seed in (1, 2)]


def test_rows_and_the_floor(scores):
    rows = {r['method']: r for r in scores[0]['rows']}
    assert list(rows) == ['raw', 'oracle (true drift terms)', 'lsq_cv (default)', 'poly3',
                          'poly3 as PX4 applies it (1 Hz, > 1 degC)',
                          'poly3 as ArduPilot applies it']
    floor = np.array(scores[0]['floor_deg_s'])
    # the floor is the test run's own noise: far below the raw drift, above zero
    assert (floor > 0).all() and (np.array(rows['raw']['residual_deg_s']) > 20 * floor).all()
    # ArduPilot applies the cubic at every sample: poly3's own residual to float32 rounding
    np.testing.assert_allclose(rows['poly3 as ArduPilot applies it']['residual_deg_s'],
                               rows['poly3']['residual_deg_s'], rtol=1e-4)
    # heating-only training: cooling rates are all outside the trained dT range but the holds
    assert 0.3 < scores[0]['rate_outside'] < 1.0
    assert rows['lsq_cv (default)']['terms'][-1] == 'r'


def test_summary_is_the_mean_of_the_seed_ratios(scores):
    rows = {r['method']: r for r in summarise(scores)}
    lsq = rows['lsq_cv (default)']
    per_seed = [np.array(next(r for r in s['rows'] if r['method'] == 'lsq_cv (default)')
                         ['residual_deg_s']) for s in scores]
    floors = [np.array(s['floor_deg_s']) for s in scores]
    poly3 = [np.array(next(r for r in s['rows'] if r['method'] == 'poly3')['residual_deg_s'])
             for s in scores]
    np.testing.assert_allclose(lsq['over_floor'],
                               np.mean([r / f for r, f in zip(per_seed, floors)], axis=0))
    np.testing.assert_allclose(lsq['over_poly3'],
                               np.mean([r / p for r, p in zip(per_seed, poly3)], axis=0))
    assert lsq['worst_over_floor'] == pytest.approx(
        max((r / f).max() for r, f in zip(per_seed, floors)))
    assert lsq['seeds'] == 2 and rows['poly3']['over_poly3'] == [1.0, 1.0, 1.0]


def test_slow_methods_run_on_the_first_seeds_only(monkeypatch):
    calls = []

    def fake(train, test, seed, *, methods, **kw):
        calls.append((seed, [m.label for m in methods]))
        return {}

    monkeypatch.setattr(heldout, 'score_pair', fake)
    slow = HeldoutMethod('slow', 'poly3', slow=True)
    heldout.run_table([('heating', 'cooling')], [1, 2, 3], methods=FAST + (slow,), slow_seeds=2)
    assert [len(m) for _, m in calls] == [3, 3, 2]
