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

    .venv/bin/python tools/explain_real_data.py [--data ../shared/data/real]
        [--out /tmp/explain_real] [--figures docs/figures/discrepancy]
        [--only adis|mpu|px4|emulator]
        [--ensemble 16] [--seed 0] [--bootstrap 20]

* ADIS16405 (``adis16405_static/adis_16405_imu1.npz``): 1,000,000 samples per axis at 100 Hz, no
  stamps (the nominal rate is used), values in deg/s on a 0.05 deg/s lattice (SOURCE.md); an
  ``.npz`` is not a recording format, so its measurements are built here and handed to the
  application layer;
* MPU6050 (``mpu6050_static_sunsided/mpu6050_static_10min.csv``): 65,067 samples, bursty host
  stamps (mean rate 99.3 Hz), temperature in degC; read by the tool's own input layer
  (:mod:`gyro_noise_ros.bag.inputs`: columns ``t_s``, ``gyro_*_dps``, ``temp_c``);
* PX4 (``px4_ulog_sample_static/sample.ulg``): ``sensor_combined`` at 248.6 Hz, motion then
  ~61 s at rest: the longest static segment is analysed (``--static auto``);
* the emulator's own record (``--only emulator``, not among the third-party data): 240 s at
  417 Hz written by ``portenta_emulator --write-bag`` with a helium-like bias rise of 0.1 deg/s
  at 60 s (time constant 60 s) and the 2000 dps lattice (70 mdps).

Every case runs through :mod:`gyro_noise_ros.app.explain` (the workflow of
``gyro_noise_explain``) and writes OUT/<name>/explain.json, report.md and figures (one folder per
axis); with ``--figures`` the overview and step figures are copied (renamed
``<name>_<axis>_*.png``) into that directory. A summary table and every named effect's
parameters (value ± stderr, or the bound of an unresolved time scale) are printed.
"""

import argparse
from pathlib import Path
import shutil
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _prepared(data, only, args):
    from gyro_noise_ros.app.explain import ExplainInput, ExplainParams, prepare_explain
    from gyro_noise_ros.explain.inputs import make_measurement

    common = {'seed': args.seed, 'ensemble': args.ensemble, 'bootstrap': args.bootstrap}
    if only in (None, 'adis'):
        path = data / 'adis16405_static' / 'adis_16405_imu1.npz'
        gyro_dps = np.load(path)['gyro_dps']
        meas = tuple(make_measurement(np.deg2rad(gyro_dps[:, i]), rate_hz=100.0, axis=axis,
                                      source=f'{path.name} (100 Hz nominal)')
                     for i, axis in enumerate('xyz'))
        none = {'before_start': 0, 'after_end': 0, 'motion': 0}
        yield 'adis16405_imu1', ExplainInput(params=ExplainParams(path=path, **common),
                                             measurements=meas, left_out=(none,) * 3,
                                             warnings=())
    if only in (None, 'mpu'):
        path = data / 'mpu6050_static_sunsided' / 'mpu6050_static_10min.csv'
        yield 'mpu6050', prepare_explain(ExplainParams(path=path, **common))
    if only in (None, 'px4'):
        path = data / 'px4_ulog_sample_static' / 'sample.ulg'
        yield 'px4', prepare_explain(ExplainParams(path=path, **common))
    if only in (None, 'emulator'):
        from gyro_noise_ros.cli import emulator

        path = Path(args.out) / 'emulator_bag'
        shutil.rmtree(path, ignore_errors=True)
        emulator.main(['--write-bag', str(path), '--duration-s', '240', '--odr-hz', '417',
                       '--helium-amplitude-dps', '0.1', '--helium-delay-s', '60',
                       '--helium-tau-s', '60'])
        yield 'emulator', prepare_explain(ExplainParams(path=path, **common))


def main(argv=None):
    """Run every case and print the summary."""
    from gyro_noise_ros.app.explain import run_explain, write_explain

    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--data', default=str(ROOT.parent / 'shared' / 'data' / 'real'))
    p.add_argument('--out', default='/tmp/explain_real')
    p.add_argument('--figures', help='copy the figures here (e.g. docs/figures/discrepancy)')
    p.add_argument('--only', choices=('adis', 'mpu', 'px4', 'emulator'))
    p.add_argument('--ensemble', type=int, default=16)
    p.add_argument('--seed', type=int, default=0)
    p.add_argument('--bootstrap', type=int, default=20)
    args = p.parse_args(argv)
    data = Path(args.data)
    rows = []
    for name, prepared in _prepared(data, args.only, args):
        for text in prepared.warnings:
            print(f'{name}: warning: {text}', flush=True)
        start = time.perf_counter()
        run = run_explain(prepared)
        seconds = time.perf_counter() - start
        out = Path(args.out) / name
        write_explain(run, out)
        for axis in run.axes:
            case = f'{name}_{axis.axis}'
            result, meas = axis.result, axis.result.measurement
            if args.figures:
                dest = Path(args.figures)
                dest.mkdir(parents=True, exist_ok=True)
                for png in sorted((out / axis.folder).glob('*.png')):
                    shutil.copy(png, dest / f'{case}_{png.name}')
            b = result.baseline
            rows.append((case, meas.n, meas.rate_hz, b.alpha, b.f, b.sigma_w_rad_s,
                         b.sigma_nu_rad_s, result.gap_initial, result.gap_final, result.named,
                         result.unexplained, result.seconds['total'], bool(result.quieter)))
            print(f'{case}: {axis.verdict}', flush=True)
            for line in axis.parameter_lines:
                print(f'    {line}', flush=True)
        print(f'{name}: {seconds:.0f} s', flush=True)
    print()
    print('| case | samples | rate Hz | alpha | f | sigma_w rad/s | sigma_nu rad/s | gap initial '
          '| gap final | named | unexplained | baseline over-estimates | s |')
    print('|---|---|---|---|---|---|---|---|---|---|---|---|---|')
    for r in rows:
        print(f'| {r[0]} | {r[1]} | {r[2]:.2f} | {r[3]:.2f} | {r[4]:.3f} | {r[5]:.3g} | '
              f'{r[6]:.3g} | {r[7]:.2f} | {r[8]:.2f} | {", ".join(r[9]) or "-"} | '
              f'{"yes" if r[10] else "no"} | {"yes" if r[12] else "no"} | {r[11]:.0f} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
