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
Run the discrepancy workflow on the real recordings in ../shared/data/real/.

Results in docs/discrepancy.md.

    .venv/bin/python tools/explain_real_data.py [--data ../shared/data/real] [--out
    /tmp/explain_real]
                                                [--figures docs/figures/discrepancy] [--only
                                                adis|mpu]

* ADIS16405 (``adis16405_static/adis_16405_imu1.npz``): 1,000,000 samples per axis at 100 Hz, no
  stamps (the nominal rate is used), values in deg/s on a 0.05 deg/s lattice (SOURCE.md);
* MPU6050 (``mpu6050_static_sunsided/mpu6050_static_10min.csv``): 65,067 samples, bursty host
  stamps (mean rate 99.3 Hz), temperature in degC; the CSV is read by the tool's own CSV reader
  (its columns ``t_s``, ``gyro_*_dps``, ``temp_c`` are among the documented aliases).

Each run writes OUT/<name>/explain.json, report.md and figures; with ``--figures`` the overview and
step figures are copied (renamed ``<name>_*.png``) into that directory. A summary table is printed.
"""

import argparse
from pathlib import Path
import shutil
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _cases(data, only):
    from gyro_noise_ros.explain.inputs import load_csv, make_measurement

    if only in (None, 'adis'):
        path = data / 'adis16405_static' / 'adis_16405_imu1.npz'
        gyro_dps = np.load(path)['gyro_dps']
        for i, axis in enumerate('xyz'):
            yield f'adis16405_imu1_{axis}', lambda i=i, axis=axis: make_measurement(
                np.deg2rad(gyro_dps[:, i]), rate_hz=100.0, axis=axis,
                source=f'{path.name} (100 Hz nominal)')
    if only in (None, 'mpu'):
        path = data / 'mpu6050_static_sunsided' / 'mpu6050_static_10min.csv'
        for axis in 'xyz':
            yield f'mpu6050_{axis}', lambda axis=axis: load_csv(path, axis=axis)


def main(argv=None):
    """Run every case and print the summary."""
    from gyro_noise_ros.explain.report import verdict, write_outputs
    from gyro_noise_ros.explain.workflow import explain

    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--data', default=str(ROOT.parent / 'shared' / 'data' / 'real'))
    p.add_argument('--out', default='/tmp/explain_real')
    p.add_argument('--figures', help='copy the figures here (e.g. docs/figures/discrepancy)')
    p.add_argument('--only', choices=('adis', 'mpu'))
    p.add_argument('--ensemble', type=int, default=16)
    p.add_argument('--seed', type=int, default=0)
    args = p.parse_args(argv)
    data = Path(args.data)
    rows = []
    for name, load in _cases(data, args.only):
        meas = load()
        start = time.perf_counter()
        result = explain(meas, seed=args.seed, ensemble=args.ensemble)
        seconds = time.perf_counter() - start
        out = write_outputs(result, Path(args.out) / name)
        if args.figures:
            dest = Path(args.figures)
            dest.mkdir(parents=True, exist_ok=True)
            for png in sorted(out.glob('*.png')):
                shutil.copy(png, dest / f'{name}_{png.name}')
        b = result.baseline
        rows.append((name, meas.n, meas.rate_hz, b.alpha, b.f, b.sigma_w_rad_s, b.sigma_nu_rad_s,
                     result.gap_initial, result.gap_final, result.named, result.unexplained,
                     seconds))
        print(f'{name}: {verdict(result)}', flush=True)
        for step in result.steps:
            params = {k: v for k, v in step.params.items() if not k.startswith('_')}
            print(f'    {step.effect}: {params}', flush=True)
        if result.unexplained:
            for where in result.where_final:
                print(f'    still outside: {where}', flush=True)
    print()
    print('| case | samples | rate Hz | alpha | f | sigma_w rad/s | sigma_nu rad/s | gap initial '
          '| gap final | ' 'named | unexplained | s |')
    print('|---|---|---|---|---|---|---|---|---|---|---|---|')
    for r in rows:
        print(f'| {r[0]} | {r[1]} | {r[2]:.2f} | {r[3]:.2f} | {r[4]:.3f} | {r[5]:.3g} | '
              f'{r[6]:.3g} | {r[7]:.2f} | '
              f'{r[8]:.2f} | {", ".join(r[9]) or "-"} | {"yes" if r[10] else "no"} | {r[11]:.0f} '
              '|')
    return 0


if __name__ == '__main__':
    sys.exit(main())
