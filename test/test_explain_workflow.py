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
Hidden-effect proof of the discrepancy workflow: one sweep, several checks.

Records come from :mod:`gyro_noise_ros.explain.synthetic`: the baseline and the effect parameters
are drawn at random from the ranges documented there. Every record is explained at most once, on
first use, into one module-scoped table (:func:`sweep`), and the tests below read the same results:
each hidden effect (and four pairs) named first on its first record with every step shrinking the
gap and the final model inside the band; nothing named on the first effect-free records; the
fitted line close to the hidden one; a rerun giving the same result. The two rates, detection over
all the sweep's records and false alarms over all the effect-free ones, need the other 22 records
(about half the sweep's time) and are marked slow (``make test-slow``); ``make test`` explains
the 16 records the other checks read.
Records of 20,000 samples at 100 Hz (150,000 for bias_instability), 8 members, no bootstrap (the
uncertainties are tested in test_explain_uncertainty.py). The rates over 10 seeds per case and the
false-alarm rate over 40 records, with their commands, are in docs/discrepancy.md. (Before, the
same checks ran as 17 separate records plus a slow sweep of 86 more: ~200 s on a quiet machine;
now 39 records, each explained once.)
"""

from gyro_noise_ros.explain.synthetic import EFFECTS, make_record
from gyro_noise_ros.explain.workflow import explain, INSIDE_GAP
import numpy as np
import pytest

N = 20000
ENSEMBLE = 8
#: Record length per effect. Flicker (bias_instability) needs two decades of tau above its crossing
#: with the white noise to be told from one Gauss-Markov process (flicker is a superposition of
#: them): with 20,000 samples it is mistaken for another effect in 4 of 10 seeds, with 150,000 in
#: none of 10 (docs/discrepancy.md). The other effects are named at 20,000 samples.
LENGTH = {'bias_instability': 150000}
#: Seeds of each hidden case: the first is checked record by record, every one counts in the
#: detection rate. Seed 0 for the single effects; 3 for the two pairs checked so far (seed 0 of
#: sinusoid + rate_random_walk draws a random walk too weak to be seen in 20,000 samples); 100
#: for the other two pairs (explained on 10 of 10 seeds 100-109).
SEEDS = {**{(e,): (0, 100) for e in EFFECTS},
         ('quantization', 'bias_drift'): (3, 100), ('sinusoid', 'rate_random_walk'): (3, 100),
         ('quantization', 'sinusoid'): (100, 101), ('sample_loss', 'bias_transient'): (100, 101)}
#: Effect-free records: 0-2 must name nothing (as the seed-0 records above), 100-108 count in the
#: false-alarm rate.
NULL_SEEDS = (0, 1, 2) + tuple(range(100, 109))


def _run(hidden, seed, *, n=N, ensemble=ENSEMBLE):
    meas, truth = make_record(hidden, np.random.default_rng([seed, 7]), n=n)
    return meas, truth, explain(meas, seed=seed, ensemble=ensemble, bootstrap=0)


def _explained(result, hidden):
    """Return '' when the record is explained as it should be, else why not."""
    if not result.named or result.named[0] not in hidden:
        return f'first named {result.named} for hidden {hidden}'
    if not set(hidden) <= set(result.named):
        return f'named {result.named}, hidden {hidden}'
    if result.gap_initial <= INSIDE_GAP:
        return f'the baseline alone was inside the band (gap {result.gap_initial:.3f})'
    if any(step.gap_after >= step.gap_before for step in result.steps):
        return 'a step did not shrink the gap'
    if result.unexplained or result.gap_final > INSIDE_GAP:
        return f'final gap {result.gap_final:.3f}: {result.where_final}'
    return ''


#: Every record of the sweep: (hidden case, seed); ``()`` is effect-free.
HIDDEN_RECORDS = [(case, seed) for case, seeds in SEEDS.items() for seed in seeds]
NULL_RECORDS = [((), seed) for seed in NULL_SEEDS]


class _Sweep(dict):
    """(case, seed) -> (measurement, truth, result); a record is explained on first use, once."""

    def __missing__(self, key):
        case, seed = key
        n = max((LENGTH.get(e, N) for e in case), default=N)
        self[key] = value = _run(case, seed, n=n)
        return value


@pytest.fixture(scope='module')
def sweep():
    """Return the module's table of explained records (filled as the tests ask)."""
    return _Sweep()


@pytest.mark.parametrize('case', list(SEEDS), ids=['+'.join(c) for c in SEEDS])
def test_hidden_effect_is_named_first_and_explained(sweep, case):
    _, _, result = sweep[case, SEEDS[case][0]]
    assert _explained(result, case) == ''


@pytest.mark.slow
def test_detection_rate_over_the_sweep(sweep):
    misses = {key: why for key in HIDDEN_RECORDS
              for why in [_explained(sweep[key][2], key[0])] if why}
    runs = len(HIDDEN_RECORDS)
    # measured over seeds 100-109 (docs/discrepancy.md): about 91 % of these 13 cases fully
    # explained (first named, all found, inside the band). With a 9 % miss rate P(more than 5
    # misses of 26) is 2.5 % (binomial); at a 30 % miss rate (a workflow materially worse) the
    # check fails with 84 %
    assert len(misses) <= 5, f'{len(misses)} of {runs} records: {misses}'


def test_effect_free_data_names_nothing(sweep):
    named = {seed: sweep[(), seed][2].named for seed in (0, 1, 2)}
    assert not any(named.values()), named
    for seed in (0, 1, 2):
        assert not sweep[(), seed][2].unexplained


@pytest.mark.slow
def test_false_alarm_rate_over_the_effect_free_records(sweep):
    named = {seed: sweep[(), seed][2].named for _, seed in NULL_RECORDS
             if sweep[(), seed][2].named}
    # 0 of 40 named (docs/discrepancy.md; 95 % upper bound 7 %): with a 2 % false-alarm rate
    # P(more than 1 of 12) is 2 %, with 20 % (a broken null) 73 %
    assert len(named) <= 1, named
    for _, seed in NULL_RECORDS:
        assert not sweep[(), seed][2].unexplained


def test_fitted_line_is_close_to_the_hidden_one(sweep):
    _, truth, result = sweep[('sinusoid',), 0]
    params = result.steps[0].params
    hidden = truth['sinusoid']
    # the frequency is refined between periodogram bins (bin width 1/T = 5 mHz here)
    assert params['frequency_hz'] == pytest.approx(hidden['frequency_hz'], abs=3e-3)
    # amplitude >= 0.15 sigma over 20,000 samples: LS standard error ~ sigma * sqrt(2 / n) = 0.01
    # sigma
    assert params['amplitude_rad_s'] == pytest.approx(hidden['amplitude_rad_s'], rel=0.15)


def test_same_seed_same_result(sweep):
    meas, _, first = sweep[('bias_drift',), 0]
    again = explain(meas, seed=0, ensemble=ENSEMBLE, bootstrap=0)
    assert again.to_dict()['steps'] == first.to_dict()['steps']
    assert again.gap_initial == first.gap_initial and again.gap_final == first.gap_final


@pytest.mark.slow  # the emulator writes 240 s at 104 Hz, explain runs on one axis (~10 s)
def test_the_emulators_own_record_is_explained(tmp_path, capsys):
    # issue 30: on the emulator's record the injected transient was found exactly and the run
    # ended "UNEXPLAINED ... below the band": the model was louder than the record, because the
    # baseline fitted to the rounded values kept the rounding noise the lattice adds again
    # (docs/discrepancy.md section 5, Sheppard's correction)
    from gyro_noise_ros.cli import emulator
    from gyro_noise_ros.cli import explain as explain_cli
    from gyro_noise_ros.link.lsm6dso32 import gyro_sensitivity_rad_s_per_lsb
    import json

    bag = tmp_path / 'emu'
    assert emulator.main(['--write-bag', str(bag), '--duration-s', '240', '--odr-hz', '104',
                          '--helium-amplitude-dps', '0.1', '--helium-delay-s', '60',
                          '--helium-tau-s', '60']) == 0
    out = tmp_path / 'out'
    assert explain_cli.main([str(bag), '--axis', 'z', '--out', str(out), '--ensemble', '8',
                             '--bootstrap', '0', '--no-html', '--quiet']) == 0
    capsys.readouterr()
    doc = json.loads((out / 'explain.json').read_text())
    steps = {s['effect']: s['params'] for s in doc['steps']}
    assert set(steps) == {'quantization', 'bias_transient'}
    assert not doc['unexplained'] and not doc['baseline_over_estimates']
    # the emulator's 2000 dps LSB (70 mdps) and its helium rise: 0.1 deg/s, 60 s, 60 s. The
    # transient is fitted on chunk means of noise 0.058 deg/s / sqrt(250): a few % on each
    assert steps['quantization']['step_rad_s'] == pytest.approx(
        gyro_sensitivity_rad_s_per_lsb(2000), rel=1e-6)
    transient = steps['bias_transient']
    assert transient['amplitude_rad_s'] == pytest.approx(np.deg2rad(0.1), rel=0.1)
    assert transient['delay_s'] == pytest.approx(60.0, abs=6.0)
    assert transient['time_constant_s'] == pytest.approx(60.0, rel=0.25)


#: Pairs whose two effects leave different traces (docs/discrepancy.md section 6, "Two effects at
#: once": these pairs named both with no false effect on 80 of 80 records, seeds 300-304), one
#: record each at a seed outside the table's.
PAIRS = (('quantization', 'temperature_sensitivity'), ('sinusoid', 'bias_transient'),
         ('bias_drift', 'sample_loss'), ('rate_random_walk', 'sample_loss'),
         ('gauss_markov', 'sample_loss'), ('sinusoid', 'bias_drift'))


@pytest.mark.slow  # six records explained, ~5 s each on an idle core
def test_two_effects_at_once_are_both_named_and_nothing_else():
    from gyro_noise_ros.explain.synthetic import outcome

    got = [outcome(pair, 400) for pair in PAIRS]
    good = [g['hidden'] for g in got if g['all_found'] and not g['extra']]
    # 80 of 80 in the table: a 95 % lower bound of 96 %; with 96 % P(fewer than 5 of 6) = 2 %
    assert len(good) >= 5, [(g['hidden'], g['named']) for g in got]
