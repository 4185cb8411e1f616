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
Run the bad-input sweep (``test/test_bad_input.py``) and write its counts to docs/bad_input.md.

Usage: python docs/scripts/bad_input_table.py [--slow] [--out docs/bad_input.md]

Runs pytest on the sweep (the cases of ``make test``; with ``--slow`` also the real signals to
tool and node processes, whose stop times are collected through ``GYRO_NOISE_STOP_TIMES``), then
counts the parametrised cases per class of bad input and per tool, with how many passed, and
tabulates the measured stop times with the load average beside them. The wall time of the run
and the load at its start and end go into the page.
"""

import argparse
from collections import Counter, defaultdict
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROOT = Path(__file__).resolve().parents[2]
SUITE = 'test/test_bad_input.py'


def run_suite(slow: bool, junit: Path, stops: Path) -> tuple[float, float, float]:
    """
    Run the sweep under pytest; return (wall time s, load average at start, at end).

    Parameters
    ----------
    slow : bool
        Also the tests marked slow.
    junit, stops : pathlib.Path
        Where pytest writes its JUnit XML and the slow tests their stop times.

    Returns
    -------
    tuple of float

    """
    env = dict(os.environ, GYRO_NOISE_STOP_TIMES=str(stops), PYTHONPATH=str(ROOT))
    marks = [] if slow else ['-m', 'not slow']
    load0, t0 = os.getloadavg()[0], time.monotonic()
    subprocess.run([sys.executable, '-m', 'pytest', '-q', '-p', 'no:cacheprovider', *marks,
                    f'--junitxml={junit}', SUITE], cwd=ROOT, env=env, check=False)
    return time.monotonic() - t0, load0, os.getloadavg()[0]


def outcomes(junit: Path) -> list[tuple[str, str, str, bool]]:
    """
    Return (class, tool, test, passed) of every test case in the JUnit XML.

    Parameters
    ----------
    junit : pathlib.Path
        pytest's ``--junitxml`` file.

    Returns
    -------
    list of tuple
        Cases of the table carry ``[tool|class|...]`` in their name; the other tests are
        class ``'(other checks)'`` and are named by their function.

    """
    rows = []
    for case in ET.parse(junit).getroot().iter('testcase'):
        name = case.get('name', '')
        passed = not any(child.tag in ('failure', 'error', 'skipped') for child in case)
        if '[' in name and '|' in name:
            tool, klass = name.split('[', 1)[1].split('|')[:2]
            rows.append((klass, tool, name, passed))
        else:
            rows.append(('(other checks)', name.split('[')[0], name, passed))
    return rows


def markdown(rows: list[tuple[str, str, str, bool]], stops: list[dict], wall_s: float,
             loads: tuple[float, float], slow: bool) -> str:
    """
    Return the page: counts per class, the class x tool matrix, the stop times.

    Parameters
    ----------
    rows : list of tuple
        :func:`outcomes`.
    stops : list of dict
        The slow tests' stop times (what, signal, code, seconds, load).
    wall_s : float
        Wall time of the pytest run (s).
    loads : (float, float)
        Load average (1 min) at its start and end.
    slow : bool
        Whether the slow tests ran.

    Returns
    -------
    str

    """
    per_class: dict[str, Counter] = defaultdict(Counter)
    tools: dict[str, set] = defaultdict(set)
    matrix: dict[tuple[str, str], int] = Counter()
    for klass, tool, _, passed in rows:
        per_class[klass]['cases'] += 1
        per_class[klass]['passed'] += passed
        if klass != '(other checks)':
            tools[klass].add(tool)
            matrix[(tool, klass)] += 1
    total = sum(c['cases'] for c in per_class.values())
    passed = sum(c['passed'] for c in per_class.values())
    lines = [
        '# Bad input: the sweep and its counts', '',
        'Made by `python docs/scripts/bad_input_table.py' + (' --slow' if slow else '')
        + '` from `test/test_bad_input.py` (issue 33). Every case runs a tool or a node with one '
        'bad input and checks the documented exit code, one error line on stderr (no traceback, '
        'no numpy or Python warning), that every file that existed is byte-identical afterwards '
        'and that a refusal, failure or interrupt leaves nothing new (no empty folder, no hidden '
        'stage). The `signal` cases send SIGINT or SIGTERM to the process from inside the '
        'work; with `--slow`, real signals go to real processes and the stop is timed.', '',
        f'{total} tests, {passed} passed, {"with" if slow else "without"} the slow ones, in '
        f'{wall_s:.0f} s of wall time (pytest, one process; load average {loads[0]:.1f} at the '
        f'start, {loads[1]:.1f} at the end, 2 cores shared with other work).', '',
        '| class | cases | passed | tools and nodes |', '|---|---|---|---|']
    for klass in sorted(per_class, key=lambda k: (k == '(other checks)', k)):
        c = per_class[klass]
        names = ', '.join(sorted(tools[klass])) if tools[klass] else 'see below'
        lines.append(f'| {klass} | {c["cases"]} | {c["passed"]} | {names} |')
    classes = sorted(k for k in per_class if k != '(other checks)')
    lines += ['', '## Cases per tool and class', '',
              '| tool | ' + ' | '.join(classes) + ' |',
              '|---|' + '---|' * len(classes)]
    for tool in sorted({t for t, _ in matrix}):
        lines.append(f'| {tool} | ' + ' | '.join(str(matrix.get((tool, k), '')) for k in classes)
                     + ' |')
    others = sorted({test.split('[')[0] for k, _, test, _ in rows if k == '(other checks)'})
    lines += ['', '## The other checks', '', *[f'* `{name}`' for name in others]]
    if stops:
        lines += ['', '## Stop times (a real signal to a real process)', '',
                  'From the signal to the exit, measured by the slow tests (target 2 s).', '',
                  '| process | signal | exit | stop (s) | load average |', '|---|---|---|---|---|']
        for s in sorted(stops, key=lambda s: (s['what'], s['signal'])):
            lines.append(f"| {s['what']} | {s['signal']} | {s['code']} | {s['seconds']:.2f} | "
                         f"{s['load']:.1f} |")
    return '\n'.join(lines) + '\n'


def main(argv: list[str] | None = None) -> int:
    """
    Run the sweep and write the page.

    Parameters
    ----------
    argv : list of str, optional
        ``--slow``, ``--out FILE``.

    Returns
    -------
    int
        0 when every test passed, else 1 (the page is written either way).

    """
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    p.add_argument('--slow', action='store_true', help='also the slow tests (real signals)')
    p.add_argument('--out', default=str(ROOT / 'docs' / 'bad_input.md'))
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        junit, stops_file = Path(tmp) / 'junit.xml', Path(tmp) / 'stops.jsonl'
        wall_s, load0, load1 = run_suite(args.slow, junit, stops_file)
        rows = outcomes(junit)
        stops = ([json.loads(line) for line in stops_file.read_text().splitlines()]
                 if stops_file.exists() else [])
    Path(args.out).write_text(markdown(rows, stops, wall_s, (load0, load1), args.slow))
    return 0 if all(r[3] for r in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
