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
The exit-code table of the README, tool by tool: each cause gives one line and its code.

Every tool has a table of rows ``Row(cause, args, code, text)``: ``args`` are the command-line
arguments with ``{name}`` standing for a file of the ``inputs`` fixture (or ``{out}`` for a fresh
output folder), ``code`` the README's exit code and ``text`` a piece of the error line. A tool
joins by adding its table to ``TABLES`` (``PROGS`` names its ``main``); the tests run every row,
check that stderr holds exactly one line (the error, no traceback, no numpy warning) and that a
cause shared by several tools gives every one of them the same code.

Interrupts are checked apart: a writer that raises ``KeyboardInterrupt`` and a real SIGINT to a
subprocess end with 130 and leave nothing under the final names, and a retry works.
"""

import errno
import importlib
import json
import os
from pathlib import Path
import signal
import subprocess
import sys
from typing import NamedTuple

from gyro_noise_ros.explain.inputs import MIN_SAMPLES
import numpy as np
import pytest

PERIOD_S = 0.005           # 200 Hz
N = MIN_SAMPLES + 808      # 9000 samples: the explain floor and 15 analyze chunks of 600
COLUMNS = 'time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s'
# Small analyze settings (the numbers do not matter here, only the path to the exit code).
FAST = ['--chunk-size', '600', '--memory', '50', '--order-grid', '0:2:0.1', '--quiet',
        '--jobs', '1', '--no-figures']


class Row(NamedTuple):
    """One cause in a tool's table."""

    cause: str
    args: list
    code: int
    text: str
    warnings: bool = False  # True: '<prog>: warning:' lines may precede the error


def _gyro(n, seed):
    return np.random.default_rng(seed).standard_normal((n, 3)) * 1e-3


@pytest.fixture(scope='module')
def inputs(tmp_path_factory, make_record):
    d = tmp_path_factory.mktemp('inputs')

    def _write_csv(path, gyro):
        make_record(path, gyro, rate_hz=1 / PERIOD_S, storage='csv')

    def _write_bag(path, gyro):
        make_record(path, gyro, rate_hz=1 / PERIOD_S)

    _write_csv(d / 'ok.csv', _gyro(N, 1))
    _write_bag(d / 'bag', _gyro(N, 1))
    (d / 'empty.csv').write_text('')
    (d / 'header.csv').write_text(COLUMNS + '\n')
    (d / 'wrong.csv').write_text('a,b,c\n1,2,3\n')
    (d / 'nonnumeric.csv').write_text(COLUMNS + '\n0,1,2,3\n0.005,1,x,3\n')
    (d / 'binary.csv').write_bytes(bytes(range(256)) * 4)
    huge = _gyro(N, 2)
    huge[:] = 1e300 * np.sign(huge)
    _write_csv(d / 'huge.csv', huge)
    _write_bag(d / 'hugebag', huge)
    _write_csv(d / 'nan.csv', np.full((N, 3), np.nan))
    (d / 'afile').write_text('a file, not a folder\n')
    (d / 'notademo').mkdir()
    (d / 'notademo' / 'precious.txt').write_text('keep me\n')
    return d


PROGS = {
    'gyro_noise_analyze': 'gyro_noise_ros.cli.analyze',
    'gyro_noise_explain': 'gyro_noise_ros.cli.explain',
    'gyro_noise_demo': 'gyro_noise_ros.cli.demo',
    'portenta_emulator': 'gyro_noise_ros.cli.emulator',
}

# Causes shared by tools carry the same name in every table that has them.
TABLES = {
    'gyro_noise_analyze': [
        Row('missing input', ['{missing.csv}', *FAST], 3, 'no such file'),
        Row('empty CSV', ['{empty.csv}', *FAST], 3, 'is empty'),
        Row('wrong CSV headers', ['{wrong.csv}', *FAST], 3, 'has no column gyro_x_rad_s'),
        Row('non-numeric CSV value', ['{nonnumeric.csv}', *FAST], 3, 'non-numeric'),
        Row('binary file named .csv', ['{binary.csv}', *FAST], 3, 'cannot read CSV'),
        Row('CSV header without rows', ['{header.csv}', *FAST], 4, 'no data rows'),
        Row('--out an existing file', ['{bag}', *FAST, '--out', '{afile}'], 6,
            'is an existing file, not a folder'),
        Row('--out under a file', ['{bag}', *FAST, '--out', '{afile}/sub'], 6,
            'cannot be created'),
        Row('--chunk-size beyond any integer', ['{bag}', *FAST, '--chunk-size',
                                                '99999999999999999999999'], 2, 'GiB'),
        Row('--chunk-size beyond memory', ['{bag}', *FAST, '--chunk-size', '1000000000000'],
            2, 'more than half of this machine'),
        Row('--start past the end', ['{bag}', *FAST, '--start', '1000'], 4,
            'nothing left to analyse: --start 1000 s is past the record end 44.995 s'),
        Row('--start past the end of a CSV', ['{ok.csv}', *FAST, '--start', '1000'], 4,
            'nothing left to analyse: --start 1000 s is past the record end 44.995 s'),
        Row('gyro values near 1e300', ['{hugebag}', *FAST], 4,
            'no chunk could be analysed (x: 15 chunk(s) with NaN/Inf or non-physical', True),
        Row('gyro values near 1e300 in a CSV', ['{huge.csv}', *FAST], 4,
            'no chunk could be analysed', True),
        Row('all NaN', ['{nan.csv}', *FAST], 4, 'no chunk could be analysed'),
        # three samples: no chunk, and too few for an Allan deviation to read (a window shorter
        # than one chunk but long enough gets the Allan deviation alone, exit 0)
        Row('window with too few samples', ['{bag}', *FAST, '--end', '0.01'], 4,
            'too few for an Allan deviation to read', True),
        Row('bad option value', ['{bag}', *FAST, '--jobs', '0'], 2, '--jobs'),
    ],
    'gyro_noise_explain': [
        Row('missing input', ['{missing.csv}'], 3, 'no such file'),
        Row('empty CSV', ['{empty.csv}'], 3, 'is empty'),
        Row('wrong CSV headers', ['{wrong.csv}'], 3, 'has no column gyro_x_rad_s'),
        Row('non-numeric CSV value', ['{nonnumeric.csv}'], 3, 'non-numeric'),
        Row('binary file named .csv', ['{binary.csv}'], 3, 'cannot read CSV'),
        Row('CSV header without rows', ['{header.csv}'], 4, 'no data rows'),
        Row('--out an existing file', ['{ok.csv}', '--out', '{afile}'], 6,
            'is an existing file, not a folder'),
        Row('--out under a file', ['{ok.csv}', '--out', '{afile}/sub'], 6,
            'cannot be created'),
        Row('--start past the end', ['{bag}', '--start', '1000'], 4,
            'nothing left to analyse: --start 1000 s is past the record end 44.995 s'),
        Row('--start past the end of a CSV', ['{ok.csv}', '--start', '1000'], 4,
            'nothing left to analyse: --start 1000 s is past the record end 44.995 s'),
        Row('gyro values near 1e300', ['{hugebag}'], 4, 'beyond 1e+06 rad/s'),
        Row('gyro values near 1e300 in a CSV', ['{huge.csv}'], 4, 'beyond 1e+06 rad/s'),
        Row('all NaN', ['{nan.csv}'], 4, 'NaN/Inf sample(s)'),
        Row('--ensemble beyond any integer', ['{ok.csv}', '--ensemble',
                                              '99999999999999999999999'], 2, '--ensemble'),
        Row('--rate-hz that underflows', ['{ok.csv}', '--rate-hz', '1e-300'], 2, '--rate-hz'),
        Row('bad option value', ['{ok.csv}', '--ensemble', '2'], 2, '--ensemble'),
    ],
    'gyro_noise_demo': [
        Row('--out an existing file', ['--out', '{afile}'], 6,
            'is an existing file, not a folder'),
        Row('--out under a file', ['--out', '{afile}/sub'], 6, 'cannot be created'),
        Row('--out not a demo output', ['--out', '{notademo}'], 6,
            'is not a previous demo output'),
        Row('bad option value', ['--speed', '0'], 2, '--speed'),
        Row('--domain-id outside ROS', ['--domain-id', '1000'], 2, '--domain-id'),
    ],
    'portenta_emulator': [
        Row('--write-sd under a file', ['--write-sd', '{afile}/sd', '--samples', '10'], 6,
            'cannot be created'),
        Row('--write-bag in the way', ['--write-bag', '{notademo}', '--samples', '10'], 6,
            'already exists: give --overwrite'),
        # (--write-sd: were the refusal missing, the run would end instead of serving a pty)
        Row('--truth-out a folder', ['--truth-out', '{notademo}', '--write-sd', '{out}',
                                     '--samples', '10'], 6, 'is a folder'),
        Row('--stats-out in a missing folder', ['--stats-out', '{missing}/s.json',
                                                '--write-sd', '{out}', '--samples', '10'], 6,
            'its folder does not exist'),
        Row('bad option value', ['--speed', '0'], 2, '--speed'),
    ],
}


def _expand(args, inputs, out):
    def one(arg):
        text = arg.replace('{out}', str(out))
        for name in ('missing.csv', 'missing', 'ok.csv', 'bag', 'empty.csv', 'header.csv',
                     'wrong.csv', 'nonnumeric.csv', 'binary.csv', 'huge.csv', 'hugebag',
                     'nan.csv', 'afile', 'notademo'):
            text = text.replace('{' + name + '}', str(inputs / name))
        return text

    return [one(a) for a in args]


def _main(prog):
    return importlib.import_module(PROGS[prog]).main


def check_error_lines(prog, err, text, *, warnings=False):
    """
    Check stderr of a refused run: one error line naming ``text``, nothing else.

    Parameters
    ----------
    prog : str
        The tool.
    err : str
        Its stderr.
    text : str
        A piece of the error line.
    warnings : bool
        Whether '<prog>: warning:' lines may precede the error.

    """
    assert 'Traceback' not in err and 'Warning:' not in err, err
    lines = err.strip().splitlines()
    assert lines and lines[-1].startswith(f'{prog}: error: '), err
    assert text in lines[-1], err
    others = lines[:-1]
    if warnings:
        assert all(line.startswith(f'{prog}: warning: ') for line in others), err
    else:
        assert not others, err


def run_row(prog, row, inputs, tmp_path, capsys):
    """Run one row in-process and check its code and its stderr."""
    out = tmp_path / 'out'
    argv = _expand(row.args, inputs, out)
    if prog in ('gyro_noise_analyze', 'gyro_noise_explain') and '--out' not in argv:
        argv += ['--out', str(out)]
    if prog == 'gyro_noise_demo' and '--out' not in argv:
        argv += ['--out', str(out)]
    code = _main(prog)(argv)
    err = capsys.readouterr().err
    assert code == row.code, f'{row.cause}: exit {code}, expected {row.code}\n{err}'
    check_error_lines(prog, err, row.text, warnings=row.warnings)
    # a refused run publishes nothing
    if out.is_dir():
        assert not [p for p in out.rglob('*') if p.is_file()], row.cause


def _rows(prog):
    return [pytest.param(row, id=row.cause) for row in TABLES[prog]]


@pytest.mark.parametrize('row', _rows('gyro_noise_analyze'))
def test_analyze_exit_codes(row, inputs, tmp_path, capsys):
    run_row('gyro_noise_analyze', row, inputs, tmp_path, capsys)


@pytest.mark.parametrize('row', _rows('gyro_noise_explain'))
def test_explain_exit_codes(row, inputs, tmp_path, capsys):
    run_row('gyro_noise_explain', row, inputs, tmp_path, capsys)


@pytest.mark.parametrize('row', _rows('gyro_noise_demo'))
def test_demo_exit_codes(row, inputs, tmp_path, capsys):
    run_row('gyro_noise_demo', row, inputs, tmp_path, capsys)
    assert (inputs / 'notademo' / 'precious.txt').read_text() == 'keep me\n'


@pytest.mark.parametrize('row', _rows('portenta_emulator'))
def test_emulator_exit_codes(row, inputs, tmp_path, capsys):
    run_row('portenta_emulator', row, inputs, tmp_path, capsys)


def test_the_same_cause_has_the_same_code_in_every_tool():
    codes = {}
    for prog, rows in TABLES.items():
        for row in rows:
            codes.setdefault(row.cause, {})[prog] = row.code
    shared = {cause: by for cause, by in codes.items() if len(by) > 1}
    assert {'empty CSV', 'wrong CSV headers', 'CSV header without rows', '--start past the end',
            'gyro values near 1e300', '--out an existing file'} <= set(shared)
    for cause, by in shared.items():
        assert len(set(by.values())) == 1, (cause, by)


def test_codes_are_the_readme_table():
    readme = (Path(__file__).resolve().parents[1] / 'README.md').read_text()
    table = readme.split('## Exit codes of the command-line tools and nodes', 1)[1].split(
        '\n## ', 1)[0]
    documented = {int(line.split('|')[1]) for line in table.splitlines()
                  if line.startswith('| ') and line.split('|')[1].strip().isdigit()}
    used = {row.code for rows in TABLES.values() for row in rows}
    assert used <= documented and {0, 1, 2, 3, 4, 5, 6, 130, 143} == documented


# --- non-physical values: counted, no numpy warning, no time before the record -------------


def test_a_few_non_physical_values_are_counted_and_their_chunks_left_out(tmp_path, capsys,
                                                                         make_record):
    from gyro_noise_ros.cli.analyze import main

    gyro = _gyro(N, 3)
    gyro[1000:1010, 1] = 1e300  # inside chunk 1 of axis y
    make_record(tmp_path / 'bag', gyro, rate_hz=1 / PERIOD_S)
    out = tmp_path / 'out'
    assert main([str(tmp_path / 'bag'), *FAST, '--out', str(out)]) == 0
    err = capsys.readouterr().err
    assert 'Warning' not in err and 'Traceback' not in err, err
    assert err.count('\n') == 1 and '10 angular rate value(s) beyond 1e+06 rad/s' in err
    bag = json.loads((out / 'summary.json').read_text())['bags'][0]
    assert bag['non_physical_values'] == {'gyro': 10, 'accel': 0}
    assert bag['axes']['y']['chunks_nan'] == 1 and bag['axes']['x']['chunks_nan'] == 0
    assert bag['axes']['y']['chunks'] == bag['axes']['x']['chunks'] - 1
    # the static segment was found on the finite samples: no time before the first sample
    assert all(v >= 0 for v in bag['left_out'].get('static_segment_s', [0.0]))


def test_segment_search_on_nothing_is_not_at_1970():
    from gyro_noise_ros.core.segments import WindowStats

    stats = WindowStats()
    stats.update(np.array([], dtype=np.int64), np.empty((0, 3)))  # a window that selected nothing
    assert stats.segment() is None


# --- interrupted and failed runs leave nothing under the final names ---------------------


def _visible(folder):
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob('*'))


def test_analyze_interrupted_while_writing_leaves_nothing_and_a_retry_works(
        inputs, tmp_path, capsys, monkeypatch):
    from gyro_noise_ros.app import analyze as app_analyze
    from gyro_noise_ros.cli.analyze import main

    out = tmp_path / 'out'

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    # chunks.csv and summary.json are written (in the staging folder) before imu.yaml
    monkeypatch.setattr(app_analyze, 'write_imu_yaml', interrupted)
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out)]) == 130
    assert capsys.readouterr().err == 'gyro_noise_analyze: interrupted\n'
    assert _visible(out) == []
    monkeypatch.undo()
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out)]) == 0
    assert {'chunks.csv', 'summary.json', 'summary.md', 'allan.csv', 'imu.yaml'} <= set(
        _visible(out))


def test_analyze_disk_full_is_an_output_error_and_keeps_the_previous_result(
        inputs, tmp_path, capsys, monkeypatch):
    from gyro_noise_ros.app import analyze as app_analyze
    from gyro_noise_ros.cli.analyze import main

    out = tmp_path / 'out'
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out)]) == 0
    before = {name: (out / name).read_bytes() for name in ('summary.json', 'chunks.csv')}

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(out / 'summary.json'))

    monkeypatch.setattr(app_analyze, 'write_json', full)
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out), '--overwrite']) == 6
    check_error_lines('gyro_noise_analyze', capsys.readouterr().err,
                      'cannot write the results: No space left on device')
    assert {name: (out / name).read_bytes() for name in before} == before
    assert not list(out.glob('.partial-*'))


@pytest.mark.parametrize('prog', ['gyro_noise_analyze', 'gyro_noise_explain'])
def test_out_without_write_permission_is_an_output_error(
        prog, inputs, tmp_path, capsys, monkeypatch):
    # Tests run as root, where chmod does not stop writes: the refusal is made to happen where
    # it would (creating the staging folder inside --out), then the real one is tested below.
    out = tmp_path / 'ro'
    out.mkdir()
    real_mkdir = Path.mkdir

    def refused(self, *args, **kwargs):
        if self.parent == out:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))
        return real_mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, 'mkdir', refused)
    src = 'bag' if prog == 'gyro_noise_analyze' else 'ok.csv'
    extra = FAST if prog == 'gyro_noise_analyze' else []
    code = _main(prog)([str(inputs / src), *extra, '--out', str(out)])
    assert code == 6
    check_error_lines(prog, capsys.readouterr().err, 'is not writable: Permission denied')
    assert _visible(out) == []


@pytest.mark.skipif(os.geteuid() == 0, reason='root writes into any folder: chmod cannot refuse '
                    'it (test_out_without_write_permission_is_an_output_error covers root)')
@pytest.mark.parametrize('prog', ['gyro_noise_analyze', 'gyro_noise_explain'])
def test_out_without_write_permission_for_real(prog, inputs, tmp_path):
    out = tmp_path / 'ro'
    out.mkdir()
    out.chmod(0o555)
    try:
        src = 'bag' if prog == 'gyro_noise_analyze' else 'ok.csv'
        extra = FAST if prog == 'gyro_noise_analyze' else []
        done = subprocess.run([sys.executable, '-m', PROGS[prog], str(inputs / src), *extra,
                               '--out', str(out)], capture_output=True, text=True, timeout=300)
    finally:
        out.chmod(0o755)
    assert done.returncode == 6
    check_error_lines(prog, done.stderr, 'not writable')


@pytest.fixture(scope='module')
def explain_result(inputs):
    """Return a real (small) result of the workflow, so explain's writing is tested quickly."""
    from gyro_noise_ros.explain.inputs import load_input
    from gyro_noise_ros.explain.workflow import explain

    return explain(load_input(inputs / 'ok.csv', axis='z'), seed=0, ensemble=4, max_steps=0,
                   bootstrap=0)


def test_explain_interrupted_mid_run_leaves_no_axis_behind_and_a_retry_works(
        inputs, explain_result, tmp_path, capsys, monkeypatch):
    from gyro_noise_ros.cli.explain import main
    from gyro_noise_ros.explain import report, workflow

    monkeypatch.setattr(workflow, 'explain', lambda *args, **kwargs: explain_result)
    calls = []
    interrupt_at = [2]  # axis y's first figure: its explain.json is written, not its report

    def plot(path, *args, **kwargs):  # the figures' content is not the point here
        calls.append(path)
        if len(calls) in interrupt_at:
            raise KeyboardInterrupt
        path.write_bytes(b'png')

    monkeypatch.setattr(report, 'plot_signatures', plot)
    out = tmp_path / 'out'
    argv = [str(inputs / 'ok.csv'), '--out', str(out), '--quiet']
    assert main(argv) == 130
    assert capsys.readouterr().err == 'gyro_noise_explain: interrupted\n'
    assert calls[1].parent.name == 'axis_y'  # where it stopped
    assert _visible(out) == []
    interrupt_at.clear()
    assert main(argv) == 0
    files = set(_visible(out))
    assert {'explain.json', 'report.md'} <= files
    for axis in 'xyz':
        assert {f'axis_{axis}/explain.json', f'axis_{axis}/report.md',
                f'axis_{axis}/overview.png'} <= files


def test_explain_disk_full_is_an_output_error(inputs, explain_result, tmp_path, capsys,
                                              monkeypatch):
    from gyro_noise_ros.cli.explain import main
    from gyro_noise_ros.explain import report, workflow

    monkeypatch.setattr(workflow, 'explain', lambda *args, **kwargs: explain_result)

    def full(result):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(report, '_markdown', full)
    monkeypatch.setattr(report, 'plot_signatures', lambda path, *a, **k: path.write_bytes(b''))
    out = tmp_path / 'out'
    assert main([str(inputs / 'ok.csv'), '--axis', 'z', '--out', str(out), '--quiet']) == 6
    check_error_lines('gyro_noise_explain', capsys.readouterr().err,
                      'cannot write the results: No space left on device')
    assert _visible(out) == []


def _sigint_default():
    """Give the child the default SIGINT (a shell's background job starts with it ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt_subprocess(argv, ready, cwd):
    """Start a tool, SIGINT it once stderr shows ``ready``; return (code, stderr)."""
    proc = subprocess.Popen([sys.executable, '-m', *argv], stderr=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, text=True, cwd=cwd,
                            preexec_fn=_sigint_default)
    try:
        seen = []
        for line in proc.stderr:
            seen.append(line)
            if ready in line:
                break
        assert proc.poll() is None, ''.join(seen)
        proc.send_signal(signal.SIGINT)
        rest = proc.stderr.read()
        proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc.returncode, ''.join(seen) + rest


# slow: a subprocess analysing 100,000 samples until its first tenth, then SIGINT (10-20 s)
@pytest.mark.slow
@pytest.mark.timeout(600)
def test_a_real_sigint_to_analyze_leaves_nothing(tmp_path, make_record):
    bag = tmp_path / 'long'
    make_record(bag, _gyro(100_000, 4), rate_hz=1 / PERIOD_S)
    out = tmp_path / 'out'
    # progress goes to stderr once per 10 % (not a terminal): interrupt after the first tenth
    code, err = _interrupt_subprocess(
        [PROGS['gyro_noise_analyze'], str(bag), *FAST[:6], '--jobs', '1', '--batch-size',
         '2000', '--out', str(out)], ready='10%', cwd=tmp_path)
    assert code == 130, err
    assert err.strip().splitlines()[-1] == 'gyro_noise_analyze: interrupted'
    assert 'Traceback' not in err
    assert _visible(out) == []


# slow: a subprocess explaining a record until its first axis, then SIGINT (10 s)
@pytest.mark.slow
@pytest.mark.timeout(600)
def test_a_real_sigint_to_explain_leaves_nothing(inputs, tmp_path):
    out = tmp_path / 'out'
    code, err = _interrupt_subprocess(
        [PROGS['gyro_noise_explain'], str(inputs / 'ok.csv'), '--out', str(out)],
        ready='axis x (1 of 3)', cwd=tmp_path)
    assert code == 130, err
    assert err.strip().splitlines()[-1] == 'gyro_noise_explain: interrupted'
    assert 'Traceback' not in err
    assert _visible(out) == []
