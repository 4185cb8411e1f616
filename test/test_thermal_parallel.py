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

"""The parallel model (paper 002 Figure 7) as a ThermalMethod on synthetic thermal runs."""

import json

from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.thermal.mopso import dominates, VmdFitness
from gyro_noise_ros.thermal.parallel import ParallelModel
from gyro_noise_ros.thermal.run import ThermalMethod, ThermalRun
import numpy as np
import pytest
from scipy.signal import lfilter

#: A small MOPSO and refinement budget keeps each fit to seconds; the algorithm is the same.
SMALL = {'n_particles': 8, 'iterations': 3, 'fitness_samples': 128, 'elman_epochs': 3,
         'elman_samples': 500, 'refine_points': 4, 'refine_polish': 4, 'refine_samples': 512,
         'elman_refine': 100}
#: Smaller still, for the tests that compare two fits (determinism, process pool): the
#: reference fitness on 4 windows of 128 samples instead of the whole 2000-sample run (16x
#: fewer entropy pairs), one BAS epoch, a short refinement.
TINY = {**SMALL, 'iterations': 2, 'refine_samples': 128, 'refine_points': 2, 'refine_polish': 2,
        'elman_epochs': 1, 'elman_iterations': 30, 'elman_refine': 20}


def thermal_run(seed, n=40000, rate_hz=5.0, noise_rad_s=0.01):
    """
    Oven-like static run: room, up to 60 degC, steps down to -20 degC, die lagging the oven.

    Gyro bias is a nonlinear function of the die temperature and its rate (different per
    axis) plus white noise; the temperature sensor has 0.05 degC of noise. Returns the run and
    the true bias (n, 3), rad/s.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    frac = t / t[-1]
    oven = np.interp(frac, [0, .1, .15, .3, .35, .5, .55, .7, .75, 1.0],
                     [25, 25, 60, 60, 40, 40, 10, 10, -20, -20])
    a = np.exp(-1 / (rate_hz * 0.02 * t[-1]))
    die = lfilter([1 - a], [1, -a], oven, zi=[a * oven[0]])[0]
    rate = np.gradient(die, t)
    bias = np.stack([g * (0.002 * (die - 25) + 2e-5 * (die - 25) ** 2) + 0.3 * g * rate
                     for g in (1.0, -0.7, 0.5)], axis=1)
    gyro = bias + noise_rad_s * rng.standard_normal((n, 3))
    temp = die + 0.05 * rng.standard_normal(n)
    return ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=rate_hz,
                      name=f'seed{seed}'), bias


@pytest.fixture(scope='module')
def fitted():
    train, _ = thermal_run(1)
    model = ParallelModel(**SMALL)
    model.fit(train, rng=np.random.default_rng(0))
    return model


def test_protocol(fitted):
    assert isinstance(fitted, ThermalMethod)
    assert fitted.name == 'parallel' and fitted.causal is False


def test_removes_drift_and_noise_on_held_out_run(fitted):
    test, bias = thermal_run(2)
    out = fitted.apply(test)
    assert out.shape == (test.t_s.size, 3)
    raw = np.sqrt(np.mean(test.gyro_rad_s ** 2, axis=0))
    resid = np.sqrt(np.mean(out ** 2, axis=0))
    # A static run's true rate is 0. The drift (rms 0.05-0.09 rad/s) is a smooth law of T and
    # dT the network can learn on the training run; the held-out run shares the law but not
    # the noise: the output keeps less than a third of the raw rms on every axis.
    assert np.all(resid < raw / 3)
    info = fitted.last_info
    assert len(info) == 3
    for axis, ax in zip(info, fitted.axes):
        assert len(axis['classes']) == ax['k'] == len(axis['sample_entropy'])
        # The slowest mode carries the drift. Coarse-grained by 20 (40000 samples, entropy on
        # 2000) the narrow-band noise modes look white: at least one is classified noise.
        assert axis['classes'][0] == 'drift'
        assert 'noise' in axis['classes']
        assert axis['center_freqs_hz'] == sorted(axis['center_freqs_hz'])


def test_json_round_trip(fitted):
    test, _ = thermal_run(3, n=3000)
    d = json.loads(json.dumps(fitted.to_dict()))
    assert d['method'] == 'parallel'
    for ax in d['axes']:
        assert 4 <= ax['k'] <= 12 and 1000 <= ax['alpha'] <= 10000
        assert set(ax['classes']) <= {'drift', 'mixed', 'noise'}
        assert {'base', 't_ref_c', 'coef', 'range_lo', 'range_hi'} <= set(ax['elman'])
        assert {'theta', 'theta_bas', 'x_lo', 'x_hi', 'y_lo', 'y_hi', 'dt_s'} <= set(
            ax['elman']['network'])
    again = ParallelModel.from_dict(d)
    assert np.array_equal(again.apply(test), fitted.apply(test))


def test_deterministic():
    train, _ = thermal_run(4, n=2000)
    a, b = ParallelModel(**TINY), ParallelModel(**TINY)
    a.fit(train, rng=np.random.default_rng(9))
    b.fit(train, rng=np.random.default_rng(9))
    assert a.to_dict() == b.to_dict()


@pytest.mark.slow
def test_process_pool_gives_the_serial_result():
    # Distributing the particle evaluations (workers=2) must not change anything: the
    # fitness is pure and the pool's map keeps the order.
    train, _ = thermal_run(8, n=2000)
    serial, pooled = ParallelModel(**TINY), ParallelModel(**TINY, workers=2)
    serial.fit(train, rng=np.random.default_rng(3))
    pooled.fit(train, rng=np.random.default_rng(3))
    a, b = serial.to_dict(), pooled.to_dict()
    a['options'].pop('workers')
    b['options'].pop('workers')
    assert a == b


@pytest.mark.slow
def test_fast_pick_is_not_dominated_by_the_naive_pick():
    # The fast fit must not lose to the naive one, on a small case where the naive path is
    # affordable: MOPSO on the whole-run fitness (fitness_samples=None) against the fast path (4
    # windows of 128 samples, then refine: 10 points re-evaluated on the whole run, 16 polish
    # steps), same budget and seed. Under the whole-run fitness the fast pick must not be
    # Pareto-dominated by the naive pick on any axis. Without refinement (refine_points=0) this
    # case fails on axes 1 and 2: the windowed pick has K = 8 or more where the whole-run front has
    # K = 4 or 5. The bench (bench/bench_thermal_fit.py) measures the same over several seeds.
    train, _ = thermal_run(21, n=768, rate_hz=1.0)
    budget = {'n_particles': 10, 'iterations': 4, 'elman_epochs': 1, 'elman_iterations': 10,
              'elman_refine': 10}
    naive = ParallelModel(**budget, fitness_samples=None)
    fast = ParallelModel(**budget, fitness_samples=128)
    naive.fit(train, rng=np.random.default_rng(5))
    fast.fit(train, rng=np.random.default_rng(5))
    for ax in range(3):
        whole = VmdFitness(train.gyro_rad_s[:, ax])
        f_naive = whole((naive.axes[ax]['k'], naive.axes[ax]['alpha']))
        f_fast = whole((fast.axes[ax]['k'], fast.axes[ax]['alpha']))
        # 768 samples <= 4 x 1024: the reference fitness is the whole-run one, so the model
        # stores the pick's whole-run fitness (same computation, bit for bit).
        stored = fast.axes[ax]['fitness']
        assert (stored['fuzzy_entropy'], stored['permutation_entropy']) == f_fast
        assert not dominates(f_naive, f_fast), (ax, f_naive, f_fast)
        info = fast.fit_info[ax]['mopso']
        assert info['reference_shape'] == [1, 768]
        # 10 screened points and at most 16 polish steps.
        assert 0 < info['reference_evaluations'] <= 26


def test_bad_input(fitted):
    run, _ = thermal_run(5, n=500)
    gyro = run.gyro_rad_s.copy()
    gyro[10, 1] = np.nan
    bad = ThermalRun(t_s=run.t_s, gyro_rad_s=gyro, temperature_c=run.temperature_c,
                     rate_hz=run.rate_hz)
    with pytest.raises(InputDataError):
        fitted.apply(bad)
    with pytest.raises(ParameterError):
        ParallelModel(nonsense=1)
    with pytest.raises(ParameterError):
        ParallelModel().apply(run)
    with pytest.raises(ParameterError):
        ParallelModel.from_dict({'method': 'poly3'})


def test_a_mixed_band_goes_through_tfpf_in_apply(fitted):
    # A run with a band holding signal and noise (a 0.01-Hz oscillation of 0.6 noise std at
    # 1 Hz, 12000 samples) decomposed around drift, oscillation and noise: apply must class
    # that mode mixed and filter it by TFPF (the mixed branch of the paper's Figure 7).
    n, noise = 12000, 1e-3
    rng = np.random.default_rng(6)
    t = np.arange(n, dtype=float)
    temp = 20.0 + 20.0 * t / t[-1]
    tone = 0.6 * noise * np.sin(2 * np.pi * 0.01 * t)
    run = ThermalRun(t_s=t, gyro_rad_s=tone[:, None] + noise * rng.standard_normal((n, 3)),
                     temperature_c=temp, rate_hz=1.0)
    d = fitted.to_dict()
    d['options'] = dict(d['options'], entropy_scale=16)
    d['axes'] = [dict(ax, k=3, alpha=10000.0, center_freqs_hz=[0.0, 0.01, 0.25])
                 for ax in d['axes']]
    model = ParallelModel.from_dict(d)
    model.apply(run)
    parts = model._report_parts[1]
    for info, part in zip(model.last_info, parts):
        assert info['classes'] == ['drift', 'mixed', 'noise']
        before, after = np.asarray(part['zoom_mixed_in']), np.asarray(part['zoom_mixed_out'])
        # the mixed part is the middle mode, and TFPF changed it (by ~7 % of its rms on the
        # known-band cases of test_thermal_tfpf_classify; here over a 620-sample zoom)
        assert np.std(before) > 0
        assert np.sqrt(np.mean((after - before) ** 2)) > 0.03 * np.std(before)
