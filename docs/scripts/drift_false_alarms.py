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
False-alarm rate of the offset-drift verdict over ordered pairs of the six real ADIS16405 runs.

Usage: python docs/scripts/drift_false_alarms.py [--data DIR]
None of the six static runs drifts. Each run (100 chunks of 10,000 samples, 100 Hz) is judged by
``core.health.evaluate_health`` against every other run as reference, per axis (90 cases),
two ways: with the ordinary least-squares standard errors of both slopes, and with the
correlation-robust errors the verdict uses (``chunks.drift_stderr``). Prints the counts of the
levels of the item 'Offset drift deviation (sigma)' (the difference of the slopes in standard
errors of both, default thresholds), and the spread of the slopes across runs beside the mean OLS
and robust standard errors.
"""

import argparse
from dataclasses import replace
import itertools
import os

from gyro_noise_ros.core.chunks import summarise_sequence
from gyro_noise_ros.core.engine import StreamCounts
from gyro_noise_ros.core.health import evaluate_health, ReferenceStats
from gyro_noise_ros.core.results import AxisSummary
import numpy as np

DEFAULT_DATA = os.path.join(os.path.dirname(__file__), '..', '..', '..', 'shared', 'data', 'real',
                            'adis16405_static')
CHUNK = 10_000


def _sequences(data):
    seqs = {}
    for k in range(1, 7):
        g = np.deg2rad(np.load(os.path.join(data, f'adis_16405_imu{k}.npz'))['gyro_dps'])
        t = (np.arange(100) * CHUNK + (CHUNK - 1) / 2) / 100.0
        for ax in range(3):
            c = g[:, ax].reshape(100, CHUNK)
            seqs[(k, ax)] = summarise_sequence(t, c.mean(1), c.var(1, ddof=1), np.full(100, 0.5),
                                               np.full(100, 0.5))
    return seqs


def _level(seq, ref, *, ols):
    stream = StreamCounts(samples=10 ** 6, samples_lost=0, gaps=0, out_of_order=0, chunks=100,
                          tail_samples=0, discarded_samples=0, discarded_partials=0, rate_hz=100.0,
                          duration_s=1e4)
    if ols:
        seq = replace(seq, drift=replace(seq.drift, stderr=seq.drift.stderr_ols))
    rs = ReferenceStats(ref.drift.slope, ref.mean_variance, 0.5, 0.5, chunks=ref.chunks,
                        offset_drift_stderr_rad_s2=ref.drift.stderr_ols if ols
                        else ref.drift.stderr)
    summary = AxisSummary('x', seq, stream, 0, 100, 0, 0, 0, 0, float('nan'))
    items = evaluate_health(summary, reference=rs).items
    return next(level for key, _, level in items if key == 'Offset drift deviation (sigma)')


def main():
    """Print the false-alarm counts and the error-versus-spread table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--data', default=DEFAULT_DATA)
    args = parser.parse_args()
    seqs = _sequences(args.data)
    for name, ols in (('OLS errors of both slopes', True),
                      ('correlation-robust errors of both slopes (the verdict)', False)):
        counts = {'OK': 0, 'WARN': 0, 'ERROR': 0}
        for (a, r) in itertools.permutations(range(1, 7), 2):
            for ax in range(3):
                counts[_level(seqs[(a, ax)], seqs[(r, ax)], ols=ols)] += 1
        print(f'{name}: {counts} of 90')
    print('| axis | spread of slopes ((deg/s)/h) | mean OLS error | mean new error |')
    print('|---|---:|---:|---:|')
    to_dph = np.degrees(1.0) * 3600.0
    for ax in range(3):
        runs = [seqs[(k, ax)].drift for k in range(1, 7)]
        spread = np.std([d.slope for d in runs], ddof=1) * to_dph
        ols = np.mean([d.stderr_ols for d in runs]) * to_dph
        new = np.mean([d.stderr for d in runs]) * to_dph
        print(f'| {"xyz"[ax]} | {spread:.4f} | {ols:.4f} | {new:.4f} |')


if __name__ == '__main__':
    main()
