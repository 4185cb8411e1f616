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
Cost of the parallel model's report figures (paper Figs. 11, 12, 14-17) against its apply.

A small-budget model is fitted on a short run; a long run (default 4 h at 100 Hz, 1.44 M
samples x 3 axes) is then processed side by side: ``apply`` without keeping the plot parts (the
baseline, as before the report hook), ``apply`` keeping them, and ``report_figures`` right
after (drawn from the kept parts, no second VMD). Prints each time and its ratio to the
baseline apply, and the cores available.
"""

import argparse
import os
from pathlib import Path
import sys
import tempfile
import time

from bench_thermal_fit import thermal_run
from gyro_noise_ros.thermal.parallel import ParallelModel
import numpy as np

SMALL = {'n_particles': 8, 'iterations': 3, 'fitness_samples': 128, 'elman_epochs': 5,
         'elman_samples': 500}


def main(argv=None):
    """Run the benchmark; print times and ratios."""
    p = argparse.ArgumentParser(description='parallel-model report figure cost')
    p.add_argument('--hours', type=float, default=4.0, help='length of the applied run (4)')
    p.add_argument('--rate-hz', type=float, default=100.0, help='sample rate, Hz (100)')
    a = p.parse_args(argv)
    n = int(a.hours * 3600 * a.rate_hz)
    train = thermal_run(1, 40000, a.rate_hz)
    test = thermal_run(2, n, a.rate_hz)
    model = ParallelModel(**SMALL)
    model.fit(train, rng=np.random.default_rng(0))
    model.apply(thermal_run(3, 4000, a.rate_hz))  # JIT warm-up

    bare = ParallelModel.from_dict(model.to_dict())
    bare._plot_parts = lambda *args: None  # the apply of before the report hook
    t = time.perf_counter()
    bare.apply(test)
    t_bare = time.perf_counter() - t
    t = time.perf_counter()
    model.apply(test)
    t_kept = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as out:
        t = time.perf_counter()
        figs = model.report_figures(test, Path(out))
        t_figs = time.perf_counter() - t
    cores = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count()
    print(f'run: {n} samples x 3 axes at {a.rate_hz:g} Hz; {cores} cores available '
          '(shared with other jobs: absolute times vary, ratios less)')
    print(f'apply without plot parts (baseline): {t_bare:.2f} s')
    print(f'apply keeping plot parts:            {t_kept:.2f} s  ratio {t_kept / t_bare:.3f}')
    print(f'report_figures after apply ({len(figs)} entries): {t_figs:.2f} s  '
          f'ratio {t_figs / t_bare:.3f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
