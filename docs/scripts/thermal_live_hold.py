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
What the compensator's low-latency default costs: the newest offset, held, against interpolation.

Usage::

    python docs/scripts/thermal_live_hold.py [--seeds 1 2 3] [--rate-hz 520] [--compress 1 60]

``imu_compensator`` (``temperature_sync: latest``) gives each gyro sample the thermal offset of
the newest temperature message (52 Hz) as the sample arrives: a zero-order hold, up to one
temperature period (19 ms) old. ``temperature_sync: interpolate`` waits for the next temperature
and interpolates. Both run through the same model and the same
:class:`gyro_noise_ros.thermal.live.LiveDriftEvaluator`. Per seed, a board is calibrated on a
warm-up (``heating``) and held out on runs of other shapes (``cooling`` at a 0.5 degC/s
set-point ramp, ``cycle``, ``soak``, ``staircase_down``; :mod:`gyro_noise_ros.thermal.simulate`),
in natural time and compressed (``--compress``: the rates, and so the cost, scale with it). Each
causal model (``poly3``, ``linear_tdt``, ``bp``) is fitted on the warm-up; on the held-out run
the thermal residual is the true drift minus the offset (``drift_rad_s`` of the truth, the
turn-on bias included, so its mean is that bias: the RMS is taken about the mean), with the
offset interpolated and held. Printed per compression, model and shape, over seeds and axes: the
RMS residual of each, the RMS of their difference and its largest value, in deg/h.
"""

import argparse

from gyro_noise_ros.thermal.baselines import BPNetwork, LinearTdT, TemperaturePolynomial
from gyro_noise_ros.thermal.live import LiveDriftEvaluator
from gyro_noise_ros.thermal.simulate import make_profile, simulate_pair
from gyro_noise_ros.units import RAD_TO_DEG
import numpy as np

SHAPES = {'cooling': {'rate_c_s': 0.5}, 'cycle': {}, 'soak': {}, 'staircase_down': {}}
DEG_H = RAD_TO_DEG * 3600.0


def offsets(method, run, truth):
    """Return the offsets at every sample, (interpolated, held), rad/s, (n, 3) each."""
    ev = LiveDriftEvaluator(method, margin_c=100.0)
    stamps = np.round(run.t_s * 1e9).astype(np.int64)
    t_stamps = stamps[truth.temperature_index]
    ev.add_temperature(t_stamps, truth.temperature_reading_c)
    knots = ev.drift_at(t_stamps)  # the offset evaluated at each temperature message
    interpolated = ev.drift_at(stamps)
    # Zero-order hold: the newest message at or before each sample (the first one before it).
    newest = np.maximum(np.searchsorted(t_stamps, stamps, side='right') - 1, 0)
    return interpolated, knots[newest]


def rms(x):
    """Return the RMS about the mean, over samples and axes."""
    return float(np.sqrt(np.mean((x - x.mean(axis=0)) ** 2)))


def main():
    """Fit, compensate both ways, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--seeds', type=int, nargs='+', default=[1, 2, 3])
    parser.add_argument('--rate-hz', type=float, default=520.0,
                        help='gyro rate (10 samples per 52-Hz temperature period)')
    parser.add_argument('--compress', type=float, nargs='+', default=[1.0, 60.0])
    args = parser.parse_args()
    print('| compression | model | held-out shape | residual, interpolated (deg/h RMS) | '
          'residual, held (deg/h RMS) | held - interpolated (deg/h RMS) | largest |')
    print('|---:|---|---|---:|---:|---:|---:|')
    for compress in args.compress:
        rows = {}
        for seed in args.seeds:
            for shape, options in SHAPES.items():
                (_, train, _), (_, test, truth) = simulate_pair(
                    seed=seed, rate_hz=args.rate_hz, compress=compress,
                    profile=make_profile('heating'),
                    test_profile=make_profile(shape, **options))
                for method in (TemperaturePolynomial(), LinearTdT(), BPNetwork()):
                    method.fit(train, rng=np.random.default_rng(seed))
                    interp, held = offsets(method, test, truth)
                    # the node holds the first rate window back (a model using dT)
                    start = int(round(10.0 * test.rate_hz))
                    drift = truth.drift_rad_s[start:]
                    rows.setdefault((method.name, shape), []).append(
                        (drift - interp[start:], drift - held[start:],
                         held[start:] - interp[start:]))
        for (name, shape), runs in rows.items():
            r_i = np.mean([rms(a) for a, _, _ in runs]) * DEG_H
            r_h = np.mean([rms(b) for _, b, _ in runs]) * DEG_H
            d = np.sqrt(np.mean([np.mean(c ** 2) for _, _, c in runs])) * DEG_H
            worst = max(float(np.abs(c).max()) for _, _, c in runs) * DEG_H
            print(f'| {compress:g} | {name} | {shape} | {r_i:.3f} | {r_h:.3f} | {d:.2g} | '
                  f'{worst:.2g} |')


if __name__ == '__main__':
    main()
