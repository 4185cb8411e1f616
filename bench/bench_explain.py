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
Benchmark of gyro_noise_explain: wall time of the whole workflow against record length.

    .venv/bin/python bench/bench_explain.py [--hours 1] [--rate-hz 1000] [--ensemble 16] [--quick]

Records are the synthetic baseline (paper model, alpha ~ 1, LSM6DSO32-like level) with a hidden
quantization (LSB 0.3 sigma) and a sinusoid, so the loop does two steps and evaluates every
candidate the fitters propose, the usual case for real data. Each length is timed once (the machine
is shared; read the ratios, not the third digit). Printed side by side: seconds per phase, and the
ratio of the time to the time of the shortest record (the baseline of the comparison) against the
length ratio, which shows how the time grows with the record length (linear growth: equal ratios).
"""

import argparse
import sys
import time

import numpy as np


def run(n, rate_hz, ensemble, seed=0):
    """Time one explain() run on an n-sample synthetic record; returns (seconds dict, result)."""
    from gyro_noise_ros.core.simulate import simulate_fractional_noise
    from gyro_noise_ros.explain.inputs import make_measurement
    from gyro_noise_ros.explain.workflow import explain

    rng = np.random.default_rng(seed)
    x = simulate_fractional_noise(n, 1.02, -0.85, 1.5e-3, rng=rng, sigma_nu=3e-4, bias=0.01)
    sigma = float(x.std())
    t = np.arange(n) / rate_hz
    x = x + 0.25 * sigma * np.sin(2 * np.pi * 0.123 * rate_hz * t)
    step = 0.3 * sigma
    x = step * np.round(x / step)
    meas = make_measurement(x, rate_hz=rate_hz, source='bench')
    start = time.perf_counter()
    result = explain(meas, seed=seed, ensemble=ensemble)
    wall = time.perf_counter() - start
    return wall, result


def main(argv=None):
    """Run the benchmark and print the table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--hours', type=float, default=1.0, help='longest record (h), default 1')
    p.add_argument('--rate-hz', type=float, default=1000.0)
    p.add_argument('--ensemble', type=int, default=16)
    p.add_argument('--quick', action='store_true', help='only the short records (smoke run)')
    args = p.parse_args(argv)
    longest = int(args.hours * 3600 * args.rate_hz)
    lengths = [longest // 64, longest // 16, longest // 4, longest]
    if args.quick:
        lengths = lengths[:2]
    print(f'gyro_noise_explain benchmark: rate {args.rate_hz:g} Hz, ensemble {args.ensemble}, '
          f'command: {" ".join([sys.executable] + sys.argv)}')
    print(f'{"samples":>10} {"record":>9} {"fit s":>7} {"sim s":>7} {"loop s":>7} {"total s":>8} '
          f'{"len ratio":>9} {"time ratio":>10} {"named":<30}')
    base = None
    for n in lengths:
        wall, result = run(n, args.rate_hz, args.ensemble)
        s = result.seconds
        if base is None:
            base = (n, wall)
        print(f'{n:>10} {n / args.rate_hz / 60:>7.1f}mn {s["fit_baseline"]:>7.1f} '
              f'{s["simulate_baseline"]:>7.1f} '
              f'{s["iterate"]:>7.1f} {wall:>8.1f} {n / base[0]:>9.1f} {wall / base[1]:>10.1f} '
              f'{",".join(result.named):<30}', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
