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
Speed of the parallel model's fit/apply (issue 9 section 7): fast path against the naive one.

Small case: the naive path (MOPSO fitness on the whole run, fitness_samples=None, reference
ADMM VMD of the whole run) and the fast path (fitness on 4 windows of 128 samples spread over
the run, cached, exact-solver whole-run VMD warm-started) fitted side by side with the same
MOPSO budget and seed; prints both times, the ratio, and each model's residual rms on a
held-out run (true rate 0) so the speed-up is seen not to cost accuracy.

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

from gyro_noise_ros.thermal.parallel import ParallelModel
from gyro_noise_ros.thermal.run import ThermalRun
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
from scipy.signal import lfilter


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


def main():
    p = argparse.ArgumentParser(description='parallel-model fit/apply benchmark')
    p.add_argument('--small-samples', type=int, default=768)
    p.add_argument('--small-particles', type=int, default=10)
    p.add_argument('--small-iterations', type=int, default=4)
    p.add_argument('--full', action='store_true', help='also time the 4-hour 100 Hz case')
    p.add_argument('--workers', type=int, default=2)
    a = p.parse_args()
    print('command:', ' '.join([os.path.basename(sys.executable)] + sys.argv))
    print(f'cores: {os.cpu_count()} on the machine, workers={a.workers} for the MOPSO '
          f'evaluations of the full case, the rest single-threaded; the machine is shared with '
          f'other helpers: load average at start {os.getloadavg()[0]:.1f}')
    n = a.small_samples
    train, test = thermal_run(1, n, 1.0), thermal_run(2, n, 1.0)
    budget = {'n_particles': a.small_particles, 'iterations': a.small_iterations,
              'elman_epochs': 10}
    # Warm-up (JIT cache load) outside the timings.
    ParallelModel(**{**budget, 'iterations': 1, 'n_particles': 2, 'elman_epochs': 1}).fit(
        thermal_run(3, 256, 1.0), rng=np.random.default_rng(0))
    _, t_naive, _, r_naive = _timed_fit({**budget, 'fitness_samples': None}, train, test, 0)
    _, t_fast, _, r_fast = _timed_fit({**budget, 'fitness_samples': 128}, train, test, 0)
    raw = np.sqrt(np.mean(test.gyro_rad_s ** 2, axis=0))
    print(f'small case: {n} samples x 3 axes, MOPSO {a.small_particles} particles x '
          f'{a.small_iterations} iterations')
    print(f'  naive fit {t_naive:.1f} s, fast fit {t_fast:.1f} s, ratio {t_naive / t_fast:.1f}x')
    print(f'  held-out residual rms (rad/s, truth 0): raw {np.round(raw, 5)}, naive '
          f'{np.round(r_naive, 5)}, fast {np.round(r_fast, 5)}')
    if not a.full:
        return 0
    n = 4 * 3600 * 100
    train, test = thermal_run(11, n, 100.0), thermal_run(12, n, 100.0)
    t = time.perf_counter()
    one = vmd(train.gyro_rad_s[:, 0], k=8, alpha=5000.0, max_iter=20, tol=1e-30)
    t_iter = (time.perf_counter() - t) / one.iterations
    model, t_fit, t_apply, resid = _timed_fit({'workers': a.workers}, train, test, 0)
    evals = [i['mopso']['evaluations'] for i in model.fit_info]
    print(f'full case: {n} samples x 3 axes at 100 Hz, MOPSO 40 x 10 (distinct evaluations per '
          f'axis {evals})')
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
