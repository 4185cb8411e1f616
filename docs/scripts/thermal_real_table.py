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
Regenerate docs/thermal.md's real-data table: ``compare --split-at 0.5`` on the MPU6050 record.

Usage::

    python docs/scripts/thermal_real_table.py [--data DIR] [--work DIR]
        [--write docs/thermal.md]

``--data`` defaults to ``$GYRO_NOISE_REAL_DATA``, else ``../shared/data/real`` (as the tests).

Runs exactly the commands docs/thermal.md shows ("Real data"): the CSV converted to a bag by
``table_to_thermal_bag.py``, then ``gyro_noise_thermal compare BAG --split-at 0.5 --f-lo-hz
0.25 --min-range-c 0.1``, and prints the table the tool wrote into ``compare.md`` and the
methods not scored (``compare.json``). With
``--write`` the table between the markers ``<!-- real-table:begin -->`` and
``<!-- real-table:end -->`` of that file is replaced, so the page holds what the tool printed.
Exit 1 with one line when the record is missing.
"""

import argparse
import json
import os
from pathlib import Path
import sys
import tempfile
import time

from gyro_noise_ros.cli.thermal import main as thermal_main

RECORD = 'mpu6050_static_sunsided/mpu6050_static_10min.csv'
BEGIN, END = '<!-- real-table:begin -->', '<!-- real-table:end -->'


def main():
    """Run the documented commands and print (or write) the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--data', default=os.environ.get('GYRO_NOISE_REAL_DATA',
                                                         '../shared/data/real'))
    parser.add_argument('--work', default=None, help='keep the bag and compare/ here')
    parser.add_argument('--write', default=None, help='Markdown file to update in place')
    parser.add_argument('--reuse', action='store_true',
                        help='format WORK/mpu_cmp/compare.json of an earlier run, no compare')
    args = parser.parse_args()
    record = Path(args.data) / RECORD
    if not record.is_file():
        print(f'thermal_real_table: {record} not found (see shared/data/real/README.md)',
              file=sys.stderr)
        return 1
    sys.path.insert(0, str(Path(__file__).parent))
    from doc_block import write_block
    from table_to_thermal_bag import convert

    work = Path(args.work or tempfile.mkdtemp(prefix='thermal_real_'))
    bag, out = work / 'mpu_bag', work / 'mpu_cmp'
    if not bag.exists():
        convert(str(record), str(bag))
    took = None
    if not (args.reuse and (out / 'compare.json').is_file()):
        start = time.perf_counter()
        code = thermal_main(['compare', str(bag), '--split-at', '0.5', '--f-lo-hz', '0.25',
                             '--min-range-c', '0.1', '--out', str(out), '--quiet'])
        took = time.perf_counter() - start
        if code != 0:
            print(f'thermal_real_table: compare exited {code}', file=sys.stderr)
            return 1
    summary = json.loads((out / 'compare.json').read_text())
    # the table exactly as the tool wrote it into compare.md (its first Markdown table)
    lines = (out / 'compare.md').read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith('|'))
    stop = next((i for i in range(first, len(lines)) if not lines[i].startswith('|')),
                len(lines))
    table = '\n'.join(lines[first:stop]) + '\n'
    errors = ''.join(f'- `{k}`: not scored: "{v}"\n' for k, v in summary['errors'].items())
    when = ('' if took is None else f'; compare took {took:.0f} s on a 2-core machine shared '
            'with other jobs')
    block = (f'{BEGIN}\n{table}\nNot scored:\n\n{errors}\n'
             f'(`docs/scripts/thermal_real_table.py`{when}.)\n{END}')
    print(block)
    if args.write:
        return write_block(args.write, BEGIN, END, block, 'thermal_real_table')
    return 0


if __name__ == '__main__':
    sys.exit(main())
