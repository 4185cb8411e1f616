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

"""lsq_cv: terms by blocked cross-validation, the fit, the choice rule, dT and hysteresis."""

from gyro_noise_ros.thermal import lsq
from gyro_noise_ros.thermal.baselines import BPNetwork, LinearTdT
from gyro_noise_ros.thermal.hysteresis import play_operator
from gyro_noise_ros.thermal.lsq import LeastSquaresCV, select_terms
from gyro_noise_ros.thermal.methods import DEFAULT_METHOD, get_method
from gyro_noise_ros.thermal.run import temperature_rate_c_s, ThermalRun
import numpy as np
import pytest

RATE = 5.0


def _run(temp, gyro, name='synthetic'):
    t = np.arange(temp.size) / RATE
    return ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=RATE, name=name)


def _cycle(seconds=6000.0):
    """Return a slow heat-and-cool (both signs of dT), 20..40 degC."""
    t = np.arange(int(seconds * RATE)) / RATE   # the stamps _run gives
    return t, 30.0 - 10.0 * np.cos(2.0 * np.pi * t / (seconds / 1.5))


def _law(temp, t):
    """Return a cubic in T plus a gradient term: exactly what the basis can represent."""
    d = temp - 30.0
    r = temperature_rate_c_s(t, temp)
    base = 1e-3 + 2e-4 * d + 3e-6 * d * d - 1e-7 * d ** 3 + 0.05 * r
    return np.outer(base, [1.0, -0.5, 0.8])


def test_is_the_default_method():
    assert DEFAULT_METHOD == 'lsq_cv'
    assert isinstance(get_method('lsq_cv'), LeastSquaresCV)


def test_recovers_a_drift_it_can_represent_and_picks_the_simplest_exact_basis():
    t, temp = _cycle()
    noise = np.random.default_rng(1).normal(0.0, 1e-5, (t.size, 3))
    m = LeastSquaresCV()
    m.fit(_run(temp, _law(temp, t) + noise), rng=np.random.default_rng(0))
    # the supersets of the law fit the noise a little better in-sample, no better held out:
    # the rule picks the smallest exact basis
    assert m.terms == ('1', 'x1', 'x2', 'x3', 'r')
    t2, temp2 = t, 31.0 + 8.0 * np.sin(2.0 * np.pi * t / 1700.0)   # another history
    # 1e-5 rad/s of white noise over 30000 samples: each coefficient to ~6e-8 rad/s; 1e-6
    # rad/s is about 15 of those, leaving room for the extrapolation to the other history
    np.testing.assert_allclose(m.drift_rad_s(temp2, temperature_rate_c_s(t2, temp2)),
                               _law(temp2, t2), atol=1e-6)


def test_cross_validation_equals_direct_fits_on_the_other_folds():
    rng = np.random.default_rng(3)
    t, temp = _cycle(3000.0)
    gyro = _law(temp, t) + rng.normal(0.0, 1e-3, (t.size, 3))
    m = LeastSquaresCV(folds=4)
    m.fit(_run(temp, gyro), rng=rng)
    rate = temperature_rate_c_s(t, temp)
    edges = np.linspace(0, t.size, 5).astype(int)
    played = {w: play_operator(temp, w) for w in lsq.HYSTERESIS_WIDTHS_C}
    for row in m.cv:
        cols = m._columns(row['terms'], temp, rate, played)
        direct = []
        for a, b in zip(edges[:-1], edges[1:]):
            train = np.ones(t.size, dtype=bool)
            train[a:b] = False
            coef = np.linalg.lstsq(cols[train], gyro[train], rcond=None)[0]
            direct.append(np.mean((gyro[a:b] - cols[a:b] @ coef) ** 2))
        # the same least squares by another route: rounding only
        np.testing.assert_allclose(row['fold_mse_rad2_s2'], direct, rtol=1e-9)


def test_choice_rule_never_rejects_what_it_accepts():
    # the chosen candidate is within one standard error of the best and no candidate within it
    # is simpler (seeded random CV tables, including exact ties)
    rng = np.random.default_rng(7)
    names = lsq.candidate_terms(3)
    for _ in range(200):
        base = rng.uniform(1.0, 2.0, 5)
        rows = [{'terms': list(n), 'fold_mse_rad2_s2':
                 (base + rng.normal(0.0, 0.02, 5) * rng.integers(0, 2)
                  + rng.exponential(0.02) * rng.integers(0, 2)).tolist()} for n in names]
        chosen = select_terms(rows)
        mse = [np.asarray(r['fold_mse_rad2_s2']) for r in rows]
        best = mse[int(np.argmin([m.mean() for m in mse]))]

        def ok(m):
            d = m - best
            return d.mean() <= d.std(ddof=1) / np.sqrt(d.size)

        def key(r):
            t_terms = [n for n in r['terms'] if n == '1' or (n[0] == 'x' and n[1:].isdigit())]
            return (len(r['terms']), len(r['terms']) - len(t_terms))

        assert ok(np.asarray(chosen['fold_mse_rad2_s2']))
        assert not any(ok(m) and key(r) < key(chosen) for r, m in zip(rows, mse))


def test_hysteresis_term_when_the_run_turned():
    # a play-operator drift of half-width 1 degC on a heat-and-cool run: chosen, recovered
    t, temp = _cycle()
    hyst = 0.004 * (play_operator(temp, 1.0) - temp)
    gyro = _law(temp, t) + np.outer(hyst, [1.0, 1.0, -1.0])
    m = LeastSquaresCV()
    m.fit(_run(temp, gyro), rng=np.random.default_rng(0))
    assert 'h1' in m.terms and m.hysteresis_c == 1.0
    # exact but for the normal equations' rounding (their condition is squared)
    assert np.abs(m.apply(_run(temp, gyro))).max() < 1e-6
    # live: the state carried across two batches gives the whole-run offset
    rate = temperature_rate_c_s(t, temp)
    k = t.size // 3
    z1 = m.play(temp[:k])
    z2 = m.play(temp[k:], start=z1[-1])
    halves = np.vstack([m.drift_rad_s(temp[:k], rate[:k], played_c=z1),
                        m.drift_rad_s(temp[k:], rate[k:], played_c=z2)])
    np.testing.assert_allclose(halves, m.drift_rad_s(temp, rate), atol=1e-15)
    # a run that only heats never shows the other branch: no hysteresis or x r candidate
    heat = np.minimum(20.0 + t / 100.0, 40.0)
    h = LeastSquaresCV()
    h.fit(_run(heat, _law(heat, t)), rng=np.random.default_rng(0))
    offered = {n for row in h.cv for n in row['terms']}
    assert 'r' in offered and not offered & {'xr', 'h0.5', 'h1', 'h2'}


def test_round_trip_through_json():
    rng = np.random.default_rng(5)
    t, temp = _cycle(3000.0)
    gyro = _law(temp, t) + rng.normal(0.0, 1e-3, (t.size, 3))
    m = LeastSquaresCV()
    m.fit(_run(temp, gyro), rng=rng)
    back = LeastSquaresCV.from_dict(m.to_dict())
    np.testing.assert_array_equal(back.apply(_run(temp, gyro)), m.apply(_run(temp, gyro)))
    assert back.terms == m.terms and back.uses_rate == m.uses_rate


@pytest.mark.parametrize('cls', [LeastSquaresCV, LinearTdT, BPNetwork])
def test_a_run_that_cannot_support_dt_gets_no_dt_term(cls):
    # the case: a noise-free constant ramp, dT constant to 1e-9 degC/s; linear_tdt once
    # normalised dT by that range and put out a mean of -4.7e5 deg/s
    t = np.arange(0.0, 2000.0, 1.0 / RATE)
    temp = 15.0 + 0.01 * t
    gyro = np.outer(1e-3 + 2e-4 * (temp - 25.0), [1.0, 1.0, 1.0])
    m = cls(epochs=200) if cls is BPNetwork else cls()
    m.fit(_run(temp, gyro), rng=np.random.default_rng(0))
    (note,) = m.notes
    assert 'fitted without a dT term' in note and 'cannot support' in note
    assert not m.uses_rate
    # and on a cooling run, whose dT is far outside, the offset follows T only
    cool = 35.0 - 0.01 * t
    out = m.apply(_run(cool, np.outer(1e-3 + 2e-4 * (cool - 25.0), [1.0, 1.0, 1.0])))
    assert np.abs(out).max() < 1e-4


def test_a_polynomial_in_t_alone_is_its_own_poly3():
    # a drift in T alone: lsq_cv chooses a polynomial in T, which is the PX4 form exactly inside
    # the trained range; with a dT term there is none
    t, temp = _cycle()
    d = temp - 30.0
    noise = np.random.default_rng(2).normal(0.0, 1e-5, (t.size, 3))
    gyro = np.outer(1e-3 + 2e-4 * d + 3e-6 * d * d - 1e-7 * d ** 3, [1.0, -0.5, 0.8]) + noise
    m = LeastSquaresCV()
    m.fit(_run(temp, gyro), rng=np.random.default_rng(0))
    assert m.terms == ('1', 'x1', 'x2', 'x3') and not m.uses_rate
    poly = m.as_poly3()
    probe = np.linspace(temp.min(), temp.max(), 50)
    np.testing.assert_allclose(poly.drift_rad_s(probe, 0.0), m.drift_rad_s(probe, 0.0),
                               rtol=0, atol=1e-15)
    assert (poly.t_min_c, poly.t_max_c) == (temp.min(), temp.max())
    m.fit(_run(temp, _law(temp, t)), rng=np.random.default_rng(0))
    assert m.as_poly3() is None
