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

"""The hidden-effect sweep's command line (cli/explain_synthetic.py), on a tiny sweep."""

import subprocess
import sys

from gyro_noise_ros.cli.explain_synthetic import main

# 8,192 samples and 4 ensemble members: the smallest the workflow accepts, ~1 s per record.
TINY = ['--seeds', '1', '--samples', '8192', '--ensemble', '4']


def test_sweep_prints_one_row_per_case(capsys):
    assert main(['--effects', 'none,sinusoid', *TINY]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].split() == ['case', 'runs', 'first', 'ok', 'all', 'found', 'inside',
                                'explained', 'extra']
    rows = {line.split()[0]: [int(v) for v in line.split()[1:]] for line in lines[1:]}
    assert set(rows) == {'none', 'sinusoid'}
    # one record per case: every count is 0 or 1 of that one run
    assert all(r[0] == 1 and all(v in (0, 1) for v in r[1:]) for r in rows.values())


def test_bad_value_is_one_line_and_exit_2(capsys):
    assert main(['--effects', 'none', '--seeds', '1', '--ensemble', '2']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'error: ensemble must be >= 4' in err[0]


def test_documented_command_runs():
    # README and docs/discrepancy.md give `python -m gyro_noise_ros.cli.explain_synthetic`
    proc = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.explain_synthetic',
                           '--help'], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and '--coverage' in proc.stdout, proc.stderr
