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
Hidden-effect proof of the discrepancy workflow: known effects injected, found again.

Records come from :mod:`gyro_noise_ros.explain.synthetic`: the baseline and the effect parameters
are drawn at random from the ranges documented there; the test asserts that the first named effect
is the hidden one, that every step shrinks the gap and that the final model puts the measurement
inside the band (G <= INSIDE_GAP). The default run uses one seeded record per case (20,000 samples
at 100 Hz, 150,000 for bias_instability, 8 members); the slow sweep runs 6 seeds per case and
requires at least 4 of 6 (the rates over 10 seeds and the false-alarm rate over 40 are in
docs/discrepancy.md, with the commands).
"""

from gyro_noise_ros.explain.synthetic import EFFECTS, make_record
from gyro_noise_ros.explain.workflow import explain, INSIDE_GAP
import numpy as np
import pytest

FAST = {'n': 20000, 'ensemble': 8}
#: Record length per effect in the default run. Flicker (bias_instability) needs two decades of tau
#: above its crossing with the white noise to be told from one Gauss-Markov process (flicker is a
#: superposition of them): with 20,000 samples it is mistaken for gauss_markov in 3 of 4 seeds,
#: with 150,000 in none of 4 (docs/discrepancy.md). The other effects are named at 20,000 samples.
LENGTH = {'bias_instability': 150000}


def _run(hidden, seed, *, n, ensemble):
    meas, truth = make_record(hidden, np.random.default_rng([seed, 7]), n=n)
    return explain(meas, seed=seed, ensemble=ensemble), truth


def _check_explained(result, hidden):
    assert result.named, f'nothing named for hidden {hidden}'
    assert result.named[0] in hidden, f'first named {result.named} for hidden {hidden}'
    assert result.gap_initial > INSIDE_GAP
    for step in result.steps:
        assert step.gap_after < step.gap_before
    assert result.gap_final <= INSIDE_GAP and not result.unexplained, result.where_final


@pytest.mark.parametrize('effect', EFFECTS)
def test_hidden_effect_is_named_first(effect):
    result, _ = _run((effect,), 0, n=LENGTH.get(effect, FAST['n']), ensemble=FAST['ensemble'])
    _check_explained(result, (effect,))


def test_fitted_parameters_are_close_to_the_hidden_ones():
    result, truth = _run(('sinusoid',), 1, **FAST)
    params = result.steps[0].params
    hidden = truth['sinusoid']
    # the frequency is refined between periodogram bins (bin width 1/T = 5 mHz here)
    assert params['frequency_hz'] == pytest.approx(hidden['frequency_hz'], abs=3e-3)
    # amplitude >= 0.15 sigma over 20,000 samples: LS standard error ~ sigma * sqrt(2 / n) = 0.01
    # sigma
    assert params['amplitude_rad_s'] == pytest.approx(hidden['amplitude_rad_s'], rel=0.15)


@pytest.mark.parametrize(
    'pair', [('quantization', 'bias_drift'), ('sinusoid', 'rate_random_walk')])
def test_two_hidden_effects_are_both_found(pair):
    result, _ = _run(pair, 3, **FAST)
    _check_explained(result, pair)
    assert set(pair) <= set(result.named), result.named


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_effect_free_data_names_nothing(seed):
    result, _ = _run((), seed, **FAST)
    assert result.named == []
    assert not result.unexplained


def test_same_seed_same_result():
    meas, _ = make_record(('bias_drift',), np.random.default_rng([4, 7]), n=20000)
    a = explain(meas, seed=5, ensemble=6)
    b = explain(meas, seed=5, ensemble=6)
    assert a.to_dict()['steps'] == b.to_dict()['steps']
    assert a.gap_initial == b.gap_initial


@pytest.mark.slow
@pytest.mark.parametrize('case', [(e,) for e in EFFECTS] + [('quantization', 'sinusoid'),
                                                            ('sample_loss', 'bias_transient')])
def test_sweep_hidden_effects(case):
    n = max(LENGTH.get(e, FAST['n']) for e in case)
    ok = 0
    for seed in range(100, 106):
        result, _ = _run(case, seed, n=n, ensemble=FAST['ensemble'])
        ok += bool(result.named and result.named[0] in case and set(case) <= set(result.named)
                   and not result.unexplained)
    # docs/discrepancy.md gives the measured rates over 10 seeds (70-100 % per effect at these
    # lengths); 4 of 6 is a floor that fails only if the workflow gets materially worse
    assert ok >= 4, f'{case}: {ok} of 6'


@pytest.mark.slow
def test_sweep_false_alarms():
    named = 0
    for seed in range(100, 120):
        result, _ = _run((), seed, **FAST)
        named += bool(result.named)
    # 0 of 40 measured (docs/discrepancy.md); at most 1 of 20 here
    assert named <= 1
