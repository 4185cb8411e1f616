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
Why a heating-only calibration stays above the noise floor: the tables of docs/thermal.md.

Usage: ``python docs/scripts/thermal_why.py [--seeds 1,2,3,4,5] [--write docs/thermal.md]``.
Part 1: the basis lsq_cv chooses on a heating run (a cubic in T and a term in dT) fitted by
least squares on the heating run and scored on a cooling and a sine run (20 Hz, 1-h training,
as the held-out table), as the ratio of each axis's residual drift to the test run's noise floor
(mean over axes and seeds), with T and dT as a method sees them (the measured temperature, its
10-s slope) and as the simulation knows them (the die's temperature and rate), and the
least-squares oracle on the law's own seven terms, on four devices:
the simulator's, without its bias instability (the noise then white), without its hysteresis,
without both. Part 2: the gradient coefficient g (deg/s per degC/s of die rate) that basis
recovers with the true T and dT on the device without either, trained on heating, on a
staircase warm-up and on a heat-and-cool cycle: the relative error per axis, mean over seeds.
With ``--write`` the tables replace the block between ``<!-- heldout-why:begin -->`` and
``<!-- heldout-why:end -->`` of that file.
"""

import argparse
from pathlib import Path
import sys

from gyro_noise_ros.thermal.metrics import residual_drift_deg_s
from gyro_noise_ros.thermal.oracle import oracle_residual
from gyro_noise_ros.thermal.run import temperature_rate_c_s
from gyro_noise_ros.thermal.simulate import make_profile, simulate_pair, ThermalModel
import numpy as np

BEGIN, END = '<!-- heldout-why:begin -->', '<!-- heldout-why:end -->'
DEVICES = (("the simulator's device", {}),
           ('no bias instability (white noise only)', {'bias_instability_dps': 0.0}),
           ('no hysteresis', {'hysteresis_half_width_c': 0.0}),
           ('neither', {'bias_instability_dps': 0.0, 'hysteresis_half_width_c': 0.0}))
TESTS = ('cooling', 'sine')
RATE_HZ, HOURS = 20.0, 1.0


def _columns(temp, rate, centre, scale):
    x = (temp - centre) / scale
    return np.column_stack([np.ones_like(x), x, x * x, x ** 3, rate / 0.01])


def _inputs(run, truth, true_terms):
    if true_terms:
        return truth.die_c, truth.die_rate_c_s
    return run.temperature_c, temperature_rate_c_s(run.t_s, run.temperature_c)


def _score(pair, true_terms):
    """Fit [1, x, x^2, x^3, r] on the training run, return the test residual / floor per axis."""
    (_, train, train_truth), (_, test, test_truth) = pair
    t_a, r_a = _inputs(train, train_truth, true_terms)
    t_b, r_b = _inputs(test, test_truth, true_terms)
    centre, scale = 0.5 * (t_a.min() + t_a.max()), 0.5 * (t_a.max() - t_a.min())
    coef = np.linalg.lstsq(_columns(t_a, r_a, centre, scale), train.gyro_rad_s, rcond=None)[0]
    residual = test.gyro_rad_s - _columns(t_b, r_b, centre, scale) @ coef
    floor = residual_drift_deg_s(test_truth.noise_rad_s, RATE_HZ)
    return residual_drift_deg_s(residual, RATE_HZ) / floor, coef[4], train_truth.compress


def _oracle(pair, model):
    """Return the least-squares oracle's test residual / floor per axis (thermal/oracle.py)."""
    (_, train, train_truth), (_, test, test_truth) = pair
    residual = oracle_residual(train, train_truth, test, test_truth, model)
    return (residual_drift_deg_s(residual, RATE_HZ)
            / residual_drift_deg_s(test_truth.noise_rad_s, RATE_HZ))


def _part1(seeds):
    lines = ['| device | T and dT | ' + ' | '.join(f'heating -> {t} (x noise floor)'
                                                   for t in TESTS) + ' |',
             '|---|---|' + '---|' * len(TESTS)]
    for label, device in DEVICES:
        model = ThermalModel(**device)
        pairs = {t: [simulate_pair(seed=s, rate_hz=RATE_HZ, hours=HOURS, model=model,
                                   profile=make_profile('heating'),
                                   test_profile=make_profile(t)) for s in seeds] for t in TESTS}
        for key, inputs in (('measured', "measured (a method's)"), ('true', "the die's true"),
                            ('oracle', "the law's own seven terms, true (the oracle)")):
            cells = []
            for t in TESTS:
                ratios = np.array([_oracle(p, model) if key == 'oracle'
                                   else _score(p, key == 'true')[0] for p in pairs[t]])
                axes = ', '.join(f'{v:.2f}' for v in ratios.mean(0))
                cells.append(f'{ratios.mean():.2f} (axes {axes})')
            lines.append(f'| {label} | {inputs} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def _part2(seeds):
    device = {'bias_instability_dps': 0.0, 'hysteresis_half_width_c': 0.0}
    model = ThermalModel(**device)
    truth_g = model.vec('gradient_dps_per_c_s')
    lines = ['| training run | g error x, y, z (%, mean over seeds) |', '|---|---|']
    for shape in ('heating', 'staircase', 'cycle'):
        errors = []
        for s in seeds:
            pair = simulate_pair(seed=s, rate_hz=RATE_HZ, hours=HOURS, model=model,
                                 profile=make_profile(shape), test_profile=make_profile('sine'))
            _, g_coef, compress = _score(pair, True)
            # coef is rad/s per (dT / 0.01 degC/s), dT in real time; the law's g is deg/s per
            # degC/s of the uncompressed rate, dT / compress
            g = np.degrees(g_coef) / 0.01 * compress
            errors.append(100.0 * (g - truth_g) / np.abs(truth_g))
        mean = np.mean(errors, axis=0)
        lines.append(f'| {shape} | {", ".join(f"{v:+.1f}" for v in mean)} |')
    return '\n'.join(lines)


def main():
    """Print (or write) the two tables."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--seeds', default='1,2,3,4,5')
    p.add_argument('--write', help='Markdown file to update in place')
    args = p.parse_args()
    seeds = [int(s) for s in args.seeds.split(',')]
    block = '\n'.join([BEGIN, '', _part1(seeds), '', _part2(seeds), '',
                       f'(`python docs/scripts/thermal_why.py --seeds {args.seeds}`.)', END])
    print(block)
    if args.write:
        sys.path.insert(0, str(Path(__file__).parent))
        from doc_block import write_block

        return write_block(args.write, BEGIN, END, block, 'thermal_why')
    return 0


if __name__ == '__main__':
    sys.exit(main())
