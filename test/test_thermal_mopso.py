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

"""MOPSO (paper 002 section 3.2): known Pareto front, archive rules, determinism, pickling."""

import pickle

from gyro_noise_ros.thermal.entropy import fuzzy_entropy, permutation_entropy
from gyro_noise_ros.thermal.mopso import (_truncate, dominates, evaluated_points, mopso,
                                          pareto_ranks, pick_compromise, refine, VmdFitness)
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
import pytest


def _schaffer(key):
    """Two objectives whose Pareto set is K in [6, 9] (any alpha with alpha = 4000)."""
    k, alpha = key
    a = (alpha - 4000.0) / 1000.0
    return (k - 6.0) ** 2 + a * a, (k - 9.0) ** 2 + a * a


def test_finds_known_front():
    r = mopso(_schaffer, rng=np.random.default_rng(0), bounds=((4, 12), (1000, 10000)),
              iterations=20)
    # Every archived point is mutually non-dominated.
    f = r.archive_fitness
    assert not any(dominates(f[i], f[j]) for i in range(len(f)) for j in range(len(f)))
    # The true front is K in {6, 7, 8, 9} at alpha = 4000; 40 particles x 20 iterations land
    # within 150 of alpha = 4000 (f rises by 0.02 there, below the 1.0 gap between K steps).
    assert set(r.archive_params[:, 0]) <= {6.0, 7.0, 8.0, 9.0}
    assert np.all(np.abs(r.archive_params[:, 1] - 4000) < 150)
    # The compromise (nearest the normalised ideal point) is a middle K.
    assert r.k in (7, 8)
    assert r.requested == 40 * 20 and r.evaluations <= r.requested


def test_deterministic_and_picklable():
    a = mopso(_schaffer, rng=np.random.default_rng(5), iterations=4)
    b = mopso(_schaffer, rng=np.random.default_rng(5), iterations=4)
    assert (a.k, a.alpha) == (b.k, b.alpha)
    assert np.array_equal(a.archive_params, b.archive_params)
    fit = VmdFitness(np.sin(np.arange(200) * 0.3) + 0.1 * np.cos(np.arange(200) * 2.0))
    again = pickle.loads(pickle.dumps(fit))
    assert again((4, 2000.0)) == fit((4, 2000.0))


def test_map_fn_is_used_in_order():
    calls = []

    def recording_map(fn, keys):
        calls.append(list(keys))
        return map(fn, calls[-1])

    a = mopso(_schaffer, rng=np.random.default_rng(2), iterations=3, map_fn=recording_map)
    b = mopso(_schaffer, rng=np.random.default_rng(2), iterations=3)
    assert (a.k, a.alpha) == (b.k, b.alpha)
    # Each iteration asks only for keys it has not seen.
    seen = [k for c in calls for k in c]
    assert len(seen) == len(set(seen)) == a.evaluations


def test_truncation_eq23():
    gen = np.random.default_rng(0)
    # 6 points crowd one cell, 4 points are alone in theirs: |A| = 10, NR = 8.
    fit = np.array([[0.0, 1.0]] * 6 + [[0.3, 0.7], [0.5, 0.5], [0.7, 0.3], [1.0, 0.0]])
    fit[:6, 0] += np.linspace(0, 0.01, 6)
    params = np.arange(20.0).reshape(10, 2)
    p, f = _truncate(params, fit, 8, 7, gen)
    # ND = Int((10 - 8) / 10 * 6 + 0.5) = 1 from the crowded cell, then the most crowded
    # cell loses one more; the singletons stay.
    assert len(f) == 8
    assert {tuple(x) for x in fit[6:]} <= {tuple(x) for x in f}


def test_pick_rule():
    params = np.array([[4, 1000], [6, 3000], [12, 9000], [5, 3000]], dtype=float)
    fit = np.array([[0.0, 1.0], [0.4, 0.4], [1.0, 0.0], [0.4, 0.4]])
    # Two points tie nearest the ideal point; the smaller K wins.
    assert pick_compromise(params, fit) == 3


def test_vmd_fitness_is_mean_over_modes():
    t = np.arange(400)
    rng = np.random.default_rng(1)
    x = np.sin(2 * np.pi * 0.03 * t) + 0.3 * rng.standard_normal(t.size)
    modes = vmd(x, k=5, alpha=3000.0).modes
    fe, pe = VmdFitness(x)((5, 3000.0))
    assert fe == pytest.approx(np.mean([fuzzy_entropy(m) for m in modes]), rel=1e-12)
    assert pe == pytest.approx(np.mean([permutation_entropy(m, order=4) for m in modes]),
                               rel=1e-12)


def test_bad_bounds():
    with pytest.raises(ValueError):
        mopso(_schaffer, rng=np.random.default_rng(0), bounds=((4, 2), (1, 2)))


def _slow_ranks(fit):
    """Twin of pareto_ranks: peel the non-dominated points, one front at a time."""
    ranks = [None] * len(fit)
    left = set(range(len(fit)))
    r = 0
    while left:
        front = {i for i in left if not any(dominates(fit[j], fit[i]) for j in left)}
        for i in front:
            ranks[i] = r
        left -= front
        r += 1
    return ranks


def test_pareto_ranks_match_peeling():
    rng = np.random.default_rng(4)
    # Rounded to a coarse grid so that ties and duplicates occur.
    fit = np.round(rng.random((60, 2)) * 5) / 5
    assert pareto_ranks(fit).tolist() == _slow_ranks(fit)
    assert pareto_ranks(np.array([[1.0, 2.0], [0.0, 3.0], [2.0, 2.0]])).tolist() == [0, 0, 1]


def _mirrored(key):
    """Return a misleading search fitness: _schaffer with K mirrored (front K in [10, 12])."""
    k, alpha = key
    return _schaffer((19 - k, alpha))


def test_refine_recovers_the_reference_front():
    res = mopso(_mirrored, rng=np.random.default_rng(1), bounds=((4, 12), (1000, 10000)),
                n_particles=20, iterations=5)
    ref = refine(res, _schaffer, points=10, polish=12, bounds=((4, 12), (1000, 10000)))
    assert ref.search_pick == (res.k, res.alpha)
    assert ref.reference_evaluations <= 22
    # Screening puts each evaluated K's best point first, so the reference's K = 6..9 are seen;
    # the polish halves its alpha step from 2250 down to 140 or less within 12 evaluations
    # and moves towards alpha = 4000 whenever a probe dominates the pick.
    assert 6 <= ref.k <= 9
    assert abs(ref.alpha - 4000) < 300
    # The archive is the non-dominated set of the reference evaluations; the pick is in it.
    f = ref.archive_fitness
    assert not any(dominates(f[i], f[j]) for i in range(len(f)) for j in range(len(f)))
    assert tuple(f[pick_compromise(ref.archive_params, f)]) == ref.fitness
    assert ref.fitness == _schaffer((ref.k, ref.alpha))
    # Deterministic, and the map_fn receives only distinct keys.
    calls = []

    def recording_map(fn, keys):
        calls.extend(keys)
        return map(fn, keys)

    again = refine(res, _schaffer, points=10, polish=12, bounds=((4, 12), (1000, 10000)),
                   map_fn=recording_map)
    assert (again.k, again.alpha) == (ref.k, ref.alpha)
    assert len(calls) == len(set(calls)) == ref.reference_evaluations
    keys, _ = evaluated_points(res)
    assert len(keys) == res.evaluations
