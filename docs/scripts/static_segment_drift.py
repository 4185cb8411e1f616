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
False cuts of the static-segment rule on records whose bias wanders (docs/offline_tool.md).

Usage: python docs/scripts/static_segment_drift.py [--seeds 100:130]
The i28 static model of test/test_reliability_cli.py (10 Hz, 12,000 s, rate random walk K = N/5,
flicker plateau N/2, and that flicker x2) per seed through ``core.segments.static_part`` on the
gyro: prints per model how many records are static throughout, and the motion cut in the others.
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', '..', 'test'))


def main() -> None:
    """Print the counts."""
    from _reliability_common import static_record, T0_NS
    from gyro_noise_ros.core.segments import static_part
    from test_reliability_cli import ERRORS

    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--seeds', default='100:130', help='first:stop (default 100:130)')
    a, b = (int(v) for v in p.parse_args().seeds.split(':'))
    for name, errors in (('random walk', ERRORS),
                         ('flicker x2', ERRORS.stressed(instability_factor=2.0))):
        whole, cut = 0, []
        for seed in range(a, b):
            t, _, gyro = static_record(errors=errors, rate_hz=10.0, duration_s=12000.0, seed=seed)
            part = static_part(T0_NS + np.rint(t * 1e9).astype(np.int64), gyro)
            if part.cuts:
                moving = [(c.start_s, c.end_s) for c in part.cuts if c.reason == 'motion']
                cut.append((seed, moving, round(part.kept_samples / t.size, 3)))
            else:
                whole += 1
        print(f'{name}: {whole} of {b - a} static throughout; cut: {cut}')


if __name__ == '__main__':
    main()
