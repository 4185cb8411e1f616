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
Speed of the parallel model's fit/apply: the fast path against the naive one.

Small case, for each seed: the naive path (MOPSO fitness on the whole run, fitness_samples=None,
reference ADMM VMD of the whole run), the fast path (fitness on 4 windows of 128 samples,
cached, then ``refine``: the best 10 points re-evaluated with the whole-run fitness and the
pick polished with 16 more, exact-solver whole-run VMD warm-started) and the fast path
without refinement (refine_points=0), fitted with the same MOPSO budget and seed. Per axis it
prints each pick's whole-run fitness (fuzzy, permutation entropy), whether the naive pick
dominates the fast pick, whether any point of the naive archive does, and the held-out residual
rms (static run: truth 0); then the counts, the naive/fast time ratio, cores and load.

"Equals or beats" (docs/thermal_model.md, Speed): under the whole-run fitness the fast pick is
not Pareto-dominated by the naive pick.

Full case (--full): a 4-hour run at 100 Hz (1.44 M samples x 3 axes) fitted with the paper's
full budget (40 particles x 10 iterations = 400 VMD evaluations per axis) and applied to another
run, both timed; the naive path is extrapolated from one whole-run VMD (it would also need
fuzzy entropies of 1.44 M-sample modes, O(n^2) each, which the extrapolation leaves out: a
lower bound).
"""

import argparse
import os
import sys
import time

from gyro_noise_ros.thermal.mopso import dominates, VmdFitness
from gyro_noise_ros.thermal.parallel import fitness_windows, ParallelModel
from gyro_noise_ros.thermal.run import ThermalRun
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
from scipy.signal import lfilter


#: Differences below this fraction of a fitness value are not resolved by the data (the
#: whole-run entropies of one (K, alpha) vary by 1.2-13 % between realisations of the run).
MARGIN = 0.01


def thermal_run(seed, n, rate_hz, noise_rad_s=0.01):
    """Oven-like static run (as in test/test_thermal_parallel.py); returns the run."""
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
    return ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=rate_hz)


def _timed_fit(opts, train, test, seed):
    model = ParallelModel(**opts)
    t = time.perf_counter()
    model.fit(train, rng=np.random.default_rng(seed))
    t_fit = time.perf_counter() - t
    t = time.perf_counter()
    out = model.apply(test)
    t_apply = time.perf_counter() - t
    return model, t_fit, t_apply, np.sqrt(np.mean(out ** 2, axis=0))


def _small_case(a):
    n = a.small_samples
    budget = {'n_particles': a.small_particles, 'iterations': a.small_iterations,
              'elman_epochs': 10}
    paths = {'naive': {'fitness_samples': None}, 'fast': {'fitness_samples': 128},
             'unrefined': {'fitness_samples': 128, 'refine_points': 0}}
    times = dict.fromkeys(paths, 0.0)
    counts = {'axes': 0}
    for name in ('fast', 'unrefined'):
        counts.update({f'{name}_dominated': 0, f'{name}_dominated_by_archive': 0,
                       f'{name}_dominated_margin': 0})
    ratios = []
    print(f'small case: {n} samples x 3 axes at 1 Hz, MOPSO {a.small_particles} particles x '
          f'{a.small_iterations} iterations, seeds {a.seeds}; fitness = (fuzzy, permutation '
          f'entropy) of the whole training run; dom = dominated by the naive pick, dom1 = by '
          f'more than {MARGIN:.0%} in one objective, arch = by a point of the naive archive; '
          f'residual = held-out rms summed over axes (rad/s)')
    print('  seed axis | naive K alpha  FE     PE    | fast K alpha  FE     PE    dom dom1 arch '
          '| unrefined K alpha  FE     PE    dom dom1 arch')
    for seed in a.seeds:
        train, test = thermal_run(100 + 2 * seed, n, 1.0), thermal_run(101 + 2 * seed, n, 1.0)
        fits = {}
        for name, opts in paths.items():
            model, t_fit, _, resid = _timed_fit({**budget, **opts}, train, test, seed)
            times[name] += t_fit
            fits[name] = (model, resid)
        for ax in range(3):
            whole = VmdFitness(train.gyro_rad_s[:, ax])
            row = {}
            for name, (model, _) in fits.items():
                k, alpha = model.axes[ax]['k'], model.axes[ax]['alpha']
                row[name] = (k, alpha, whole((k, alpha)))
            naive = row['naive'][2]
            arch = np.c_[fits['naive'][0].fit_info[ax]['mopso']['archive_fuzzy_entropy'],
                         fits['naive'][0].fit_info[ax]['mopso']['archive_permutation_entropy']]
            cells = []
            counts['axes'] += 1
            for name in ('fast', 'unrefined'):
                k, alpha, f = row[name]
                dom = dominates(naive, f)
                dom1 = dominates(naive, f, margin=MARGIN)
                by_arch = any(dominates(g, f) for g in arch)
                counts[f'{name}_dominated'] += dom
                counts[f'{name}_dominated_margin'] += dom1
                counts[f'{name}_dominated_by_archive'] += by_arch
                yes = ('no ', 'yes')
                cells.append(f'{k:2d} {alpha:6.0f} {f[0]:.4f} {f[1]:.4f} {yes[dom]} '
                             f'{yes[dom1]}  {yes[by_arch]}')
            k, alpha, f = row['naive']
            print(f'  {seed:4d} {ax:4d} |  {k:2d} {alpha:6.0f} {f[0]:.4f} {f[1]:.4f} | '
                  f'{cells[0]} |         {cells[1]}')
        r_naive, r_fast = fits['naive'][1].sum(), fits['fast'][1].sum()
        ratios.append(r_fast / r_naive)
        print(f'  {seed:4d}  all | held-out residual naive {r_naive:.5f}, fast {r_fast:.5f} '
              f'(fast/naive {r_fast / r_naive:.2f}), unrefined {fits["unrefined"][1].sum():.5f}')
    m = counts['axes']
    for name in ('fast', 'unrefined'):
        print(f'  {name} pick dominated by the naive pick on {counts[f"{name}_dominated"]} of {m} '
              f'axes ({counts[f"{name}_dominated_margin"]} by more than {MARGIN:.0%}), by a '
              f'point of the naive archive on {counts[f"{name}_dominated_by_archive"]}')
    print(f'  held-out residual fast/naive: {", ".join(f"{r:.2f}" for r in ratios)}')
    print(f'  fit time over the seeds: naive {times["naive"]:.1f} s, fast {times["fast"]:.1f} s '
          f'(ratio {times["naive"] / times["fast"]:.1f}x), unrefined {times["unrefined"]:.1f} s')


def main():
    p = argparse.ArgumentParser(description='parallel-model fit/apply benchmark')
    p.add_argument('--small-samples', type=int, default=768)
    p.add_argument('--small-particles', type=int, default=20)
    p.add_argument('--small-iterations', type=int, default=5)
    p.add_argument('--seeds', type=int, nargs='+', default=[0, 1, 2])
    p.add_argument('--full', action='store_true', help='also time the 4-hour 100 Hz case')
    p.add_argument('--no-small', action='store_true', help='skip the small case')
    p.add_argument('--workers', type=int, default=2)
    a = p.parse_args()
    print('command:', ' '.join([os.path.basename(sys.executable)] + sys.argv))
    print(f'cores: {os.cpu_count()} on the machine, workers={a.workers} for the MOPSO '
          f'evaluations of the full case, the rest single-threaded; the machine is shared with '
          f'other helpers: load average at start {os.getloadavg()[0]:.1f}')
    # Warm-up (JIT cache load) outside the timings.
    ParallelModel(**{'iterations': 1, 'n_particles': 2, 'elman_epochs': 1}).fit(
        thermal_run(3, 256, 1.0), rng=np.random.default_rng(0))
    if not a.no_small:
        _small_case(a)
    if not a.full:
        return 0
    n = 4 * 3600 * 100
    train, test = thermal_run(11, n, 100.0), thermal_run(12, n, 100.0)
    t = time.perf_counter()
    one = vmd(train.gyro_rad_s[:, 0], k=8, alpha=5000.0, max_iter=20, tol=1e-30)
    t_iter = (time.perf_counter() - t) / one.iterations
    x = train.gyro_rad_s[:, 0]
    cost = {}
    for name, (samples, count) in {'search': (256, 4), 'reference': (1024, 4)}.items():
        fitness = VmdFitness(np.ascontiguousarray(fitness_windows(x, samples, count)))
        t = time.perf_counter()
        for key in ((6, 3000.0), (8, 6000.0), (10, 9000.0)):
            fitness(key)
        cost[name] = (time.perf_counter() - t) / 3
    model, t_fit, t_apply, resid = _timed_fit({'workers': a.workers}, train, test, 0)
    evals = [i['mopso']['evaluations'] for i in model.fit_info]
    refs = [i['mopso']['reference_evaluations'] for i in model.fit_info]
    print(f'full case: {n} samples x 3 axes at 100 Hz, MOPSO 40 x 10 (distinct evaluations per '
          f'axis {evals}, reference evaluations {refs})')
    print(f'  one evaluation (mean of K = 6, 8, 10, one process, wall time): search fitness '
          f'4 x 256 {cost["search"]:.3f} s, reference 4 x 1024 {cost["reference"]:.3f} s; '
          f'refinement ~ {sum(refs) * cost["reference"]:.0f} s of one process, search ~ '
          f'{sum(evals) * cost["search"]:.0f} s (both spread over the workers)')
    raw = np.sqrt(np.mean(test.gyro_rad_s ** 2, axis=0))
    print(f'  fit {t_fit:.1f} s ({t_fit / 60:.2f} min), apply {t_apply:.1f} s; residual rms '
          f'{np.round(resid, 5)} rad/s, raw {np.round(raw, 5)}')
    naive = t_iter * 500 * 400 * 3
    print(f'  naive lower bound: one whole-run ADMM iteration (K = 8) {t_iter:.3f} s x 500 '
          f'iterations x 400 evaluations x 3 axes = {naive / 3600:.1f} h (entropies excluded); '
          f'ratio >= {naive / t_fit:.0f}x')
    print(f'  load average at end {os.getloadavg()[0]:.1f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
