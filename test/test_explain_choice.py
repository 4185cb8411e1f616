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
The choice of the next effect never rejects what its own rule accepts (issue 30 item 1).

A property test of :func:`gyro_noise_ros.explain.workflow.choose` over random candidate gaps,
scores and parameter counts; the case of the issue with its numbers; and the MPU6050 record (axis
y, seed 46) on which the old rule chose a tied candidate that failed the acceptance rule and
ended UNEXPLAINED while rate_random_walk passed.
"""

from _realdata import real_data
from gyro_noise_ros.explain import workflow
from gyro_noise_ros.explain.inputs import load_input, select
from gyro_noise_ros.explain.workflow import accepts, choose, criterion, INSIDE_GAP
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

_CANDIDATE = st.tuples(st.floats(0.0, 12.0), st.floats(-60.0, 60.0), st.integers(1, 3))


@settings(max_examples=400, deadline=None)
@given(st.lists(_CANDIDATE, max_size=10), st.floats(0.0, 12.0))
def test_choose_never_rejects_a_passing_candidate(candidates, gap):
    gaps = [c[0] for c in candidates]
    scores = [c[1] for c in candidates]
    counts = [c[2] for c in candidates]
    pick = choose(gaps, scores, counts, gap)
    passing = [i for i, g in enumerate(gaps) if g <= gap - INSIDE_GAP]
    if not passing:
        assert pick is None
        return
    # one passes: a choice is made, and it passes too
    assert pick is not None and accepts(gaps[pick], gap)
    # no passing candidate has a smaller criterion (the documented ranking)
    assert all(criterion(scores[pick], counts[pick]) <= criterion(scores[i], counts[i])
               for i in passing)


@settings(max_examples=200, deadline=None)
@given(st.lists(_CANDIDATE, min_size=1, max_size=8, unique_by=lambda c: c[1]),
       st.floats(0.0, 12.0), st.randoms(use_true_random=False))
def test_the_choice_does_not_depend_on_the_order_of_the_candidates(candidates, gap, rnd):
    # distinct scores: the criterion ranks without ties, so the order cannot matter
    shuffled = list(candidates)
    rnd.shuffle(shuffled)

    def chosen(cands):
        pick = choose([c[0] for c in cands], [c[1] for c in cands], [c[2] for c in cands], gap)
        return None if pick is None else cands[pick]

    first, second = chosen(candidates), chosen(shuffled)
    if first is None or second is None:
        assert first is second
    else:
        # the same candidate unless two have the same criterion by their parameter counts
        assert criterion(first[1], first[2]) == criterion(second[1], second[2])


def test_the_case_of_the_issue():
    # MPU-6050 axis y, last round (issue 30): gap 0.113; bias_instability brings it to 0.0047,
    # bias_transient to within 0.05 of that but not 0.1 below 0.113, with a criterion 0.003
    # smaller. The old rule took bias_transient, which failed the rule, and ended UNEXPLAINED.
    gap = 0.113
    gaps = [0.0047, 0.05]
    counts = [1, 3]
    scores = [-20.964 - 0.25 * 1, -20.967 - 0.25 * 3]  # criteria -20.964 and -20.967
    assert criterion(scores[1], counts[1]) < criterion(scores[0], counts[0])
    assert choose(gaps, scores, counts, gap) == 0
    # with both passing, the criterion decides, not the smaller gap
    assert choose([0.0047, 0.01], scores, counts, gap) == 1


@pytest.mark.slow  # explain on 65,067 real samples, 16 members, three rounds (~15 s)
def test_mpu6050_y_names_the_candidate_that_passes():
    path = real_data('mpu6050_static_sunsided', 'mpu6050_static_10min.csv')
    meas, _ = select(load_input(path, axis='y'))
    result = workflow.explain(meas, seed=46, ensemble=16, bootstrap=0)
    # seed 46 is where the old rule failed on this record (found by a scan of seeds 1-50): in
    # the third round rate_random_walk brought the gap from 0.283 to 0.181 (0.103 less), the
    # rule took bias_drift (0.209, tied within 0.05 by a better criterion) and stopped
    assert result.named[:2] == ['stamp_jitter', 'quantization']
    assert 'rate_random_walk' in result.named
    # and whatever the loop ends with, no rejected candidate of its last round passes
    assert not any(accepts(g, result.gap_final) for g in result.tried_last.values())
    assert not result.stopped_at_limit
