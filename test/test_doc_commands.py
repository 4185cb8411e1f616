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
Every command in README.md and docs/*.md runs as written.

The commands are extracted from the Markdown itself: every line of a code block (``` fences) and
every inline code span that starts with one of the package's programs (its console scripts,
``python -m gyro_noise_ros.cli.X``, a script of the checkout, ``make``, ``ros2 launch``).
``test_every_documented_command_parses`` checks each one without running it: a tool's arguments
against its own argparse parser (an inline fragment or a usage synopsis ``[--opt X]`` only for
the options it names), a node's ``-p name:=value`` against its parameter file in config/, a
``--params-file`` against the files that exist or that a documented command writes, a launch
argument against the launch file's declarations, a script's options against its source, a make
target against the Makefile. ``test_readme_commands_run_as_written`` (slow) runs the README's
commands that need no board and no ROS graph in a folder of small generated inputs named as
the README names them, and docs/reliability.md's and docs/thermal.md's walk-throughs.
"""

import contextlib
from dataclasses import dataclass
import importlib
import io
from pathlib import Path
import re
import shlex
import shutil

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]

#: The package's console scripts and the module whose ``build_parser`` (or, for the nodes, whose
#: parameter file) a command is checked against; from setup.py.
SCRIPTS = dict(re.findall(r"'(\w+) = (gyro_noise_ros\.[\w.]+):main'",
                          (ROOT / 'setup.py').read_text()))
NODES = {'lsm6dso32_driver', 'noise_analyzer', 'imu_compensator', 'gyro_noise_record',
         'gyro_noise_monitor', 'imu_chain'}
#: The nodes a program runs together: their parameter files (one per node otherwise).
TOGETHER = {'imu_chain': ('lsm6dso32_driver', 'imu_compensator')}
#: Files a documented command writes, so another may read them (--params-file).
WRITTEN = {'cal/calibration.yaml': 'gyro_noise_calibrate ... --out cal/'}


@dataclass
class Command:
    """One documented command: where, as written, its words."""

    where: str
    text: str
    argv: list
    fenced: bool

    @property
    def synopsis(self) -> bool:
        """Tell whether this is a usage line, options in brackets or ``x|y``, not a command."""
        return any(w.startswith('[') or w.endswith(']') or ('|' in w and '://' not in w)
                   for w in self.argv[1:]) or '...' in self.argv


def _program(word):
    return (word in SCRIPTS or word in ('make', 'ros2') or word.endswith('/python')
            or word in ('python', 'python3'))


def _split(text):
    try:
        return shlex.split(text, comments=True)
    except ValueError:  # an unclosed quote: a snippet of Python, not a command
        return None


def doc_commands():
    """Return every documented command of README.md and docs/*.md."""
    out = []
    for path in DOCS:
        text = path.read_text()
        name = path.relative_to(ROOT)
        fences = list(re.finditer(r'^```([\w-]*)\n(.*?)^```', text, re.S | re.M))
        for m in fences:
            if m.group(1) in ('python', 'yaml', 'json', 'text'):
                continue
            first = text.count('\n', 0, m.start(2)) + 1
            env = {}
            raw = m.group(2).split('\n')
            k = 0
            while k < len(raw):
                line, lineno = raw[k].strip(), first + k
                while line.endswith('\\') and k + 1 < len(raw):
                    k += 1
                    line = line[:-1] + ' ' + raw[k].strip()
                k += 1
                assign = re.match(r'^(\w+)="([^"]*)"$', line)
                if assign:
                    env[assign.group(1)] = assign.group(2)
                    continue
                for var, value in env.items():
                    line = line.replace('$' + var, value)
                words = _split(line)
                if words and words[-1] == '&':
                    words = words[:-1]
                if not words or not _program(words[0]) or _is_output(words):
                    continue
                out.append(Command(f'{name}:{lineno}', line, words, True))
        prose = re.sub(r'^```.*?^```', lambda m: '\n' * m.group(0).count('\n'), text,
                       flags=re.S | re.M)
        for m in re.finditer(r'`([^`\n]+)`', prose):
            words = _split(m.group(1))
            if words and len(words) > 1 and _program(words[0]) and not _is_output(words):
                lineno = prose.count('\n', 0, m.start()) + 1
                out.append(Command(f'{name}:{lineno}', m.group(1), words, False))
    return out


def _is_output(words):
    """Tell a program's printed line (``tool: error: ...``) or a diagram (``-->``) apart."""
    return (words[0].endswith(':') or (len(words) > 1 and words[1].endswith(':')
                                       and ':=' not in words[1] and '//' not in words[1])
            or any('-->' in w or '--+' in w for w in words))


def _parse(parser, argv):
    """Return argparse's complaint about ``argv`` (None when it parses)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            parser.parse_args(argv)
        except SystemExit as exc:
            return None if exc.code == 0 else err.getvalue().strip().splitlines()[-1]
    return None


def _options(parser):
    """Every option string of a parser and of its subparsers."""
    import argparse

    opts = set(parser._option_string_actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                opts |= _options(sub)
    return opts


def _check_names(parser, argv):
    """For a synopsis or a fragment: every ``--option`` it names exists."""
    known = _options(parser)
    bad = [w.strip('[]').split('=')[0] for w in argv
           if w.strip('[]').startswith('--') and w.strip('[]').split('=')[0] not in known]
    return f'unknown option(s) {bad}' if bad else None


def _tool(cmd):
    """Return the tool's parser and its arguments (console script or ``python -m``)."""
    words = cmd.argv
    if words[0] in SCRIPTS:
        module, args = SCRIPTS[words[0]], words[1:]
    elif len(words) > 2 and words[1] == '-m' and words[2].startswith('gyro_noise_ros.cli.'):
        module, args = words[2], words[3:]
    else:
        return None, None
    if words[0] == 'gyro_noise_record' and args[:1] == ['repair']:
        # the console script runs the node, or repair (gyro_noise_ros.cli.record) before it
        return importlib.import_module('gyro_noise_ros.cli.record').build_parser(), args[1:]
    mod = importlib.import_module(module)
    return (mod.build_parser() if hasattr(mod, 'build_parser') else None), args


def _ros_args(cmd, node):
    """Check a node's ``--ros-args``: every ``-p`` a parameter of its file, every file there."""
    words = cmd.argv
    # every ROS 2 node also has the parameter use_sim_time
    params = {'use_sim_time'}
    for name in TOGETHER.get(node, (node,)):
        yaml_file = ROOT / 'config' / f'{name}.yaml'
        if yaml_file.exists():
            params |= set(yaml.safe_load(yaml_file.read_text())['/**']['ros__parameters'])
    own = words[1:words.index('--ros-args')] if '--ros-args' in words else words[1:]
    problems = []
    if node == 'gyro_noise_monitor':
        from gyro_noise_ros.nodes.monitor import build_parser

        problems.append(_check_names(build_parser(), own) if cmd.synopsis
                        else _parse(build_parser(), own))
    elif own and own not in (['--help'], ['-h']) and not (
            node == 'gyro_noise_record' and own[0] == 'repair'):
        problems.append(f'{node} takes no own arguments, got {own}')
    rest = words[words.index('--ros-args') + 1:] if '--ros-args' in words else []
    for flag, value in zip(rest, rest[1:]):
        if flag == '-p' and value.split(':=')[0] not in params:
            problems.append(f'{value.split(":=")[0]!r} is not a parameter of {node} '
                            f'(config/{node}.yaml)')
        if flag == '--params-file' and not (ROOT / value).exists() and value not in WRITTEN:
            problems.append(f'--params-file {value}: no such file, and no command writes it')
    return '; '.join(p for p in problems if p) or None


def _script(cmd):
    """``python path.py --opt``: the file exists, each option is in its source."""
    words = cmd.argv
    if len(words) < 2 or words[1] in ('-c', '-m') or words[1].startswith('-'):
        return None
    path = ROOT / words[1]
    if not path.is_file():
        return f'{words[1]}: no such file'
    source = path.read_text()
    bad = [w for w in words[2:] if w.startswith('--') and f"'{w.split('=')[0]}'" not in source]
    return f'{words[1]} has no option(s) {bad}' if bad else None


def check(cmd):
    """Return what is wrong with a documented command (None: nothing)."""
    words = cmd.argv
    if words[0] == 'make':
        targets = set(re.findall(r'^([\w-]+):', (ROOT / 'Makefile').read_text(), re.M))
        return None if words[1] in targets else f'no make target {words[1]!r}'
    if words[0] == 'ros2':
        if words[1:2] != ['launch'] or len(words) < 4:
            return None  # ros2 run/bag of other packages, or the words 'ros2 launch' in prose
        launch = ROOT / 'launch' / words[3]
        if not launch.exists():
            return f'no launch file {words[3]}'
        declared = set(re.findall(r"DeclareLaunchArgument\('(\w+)'", launch.read_text()))
        bad = [w.split(':=')[0] for w in words[4:] if ':=' in w
               and w.split(':=')[0] not in declared]
        return f'{words[3]} declares no {bad}' if bad else None
    node = words[0] if words[0] in NODES else None
    if node and (node != 'gyro_noise_record' or words[1:2] != ['repair']):
        return _ros_args(cmd, node)
    parser, args = _tool(cmd)
    if parser is None:
        return _script(cmd)
    if cmd.synopsis or not cmd.fenced:
        return _check_names(parser, args)
    return _parse(parser, args)


def test_the_extraction_finds_the_commands():
    """The extractor sees the README's commands (a broken extractor would check nothing)."""
    cmds = doc_commands()
    texts = [c.text for c in cmds]
    assert len(cmds) >= 100, len(cmds)
    assert any('--label ref --label H1 --label H2' in t for t in texts)
    assert any(c.argv[0] == 'portenta_emulator' and '--write-bag' in c.argv for c in cmds)
    assert not any(c.argv[0] == 'gyro_noise_calibrate:' for c in cmds)  # printed errors
    # a wrong option is caught, in a command and in a synopsis
    assert check(Command('x', '', ['gyro_noise_analyze', 'b', '--lable', 'a', '--out', 'o'],
                         True)) is not None
    assert check(Command('x', '', ['gyro_noise_analyze', 'BAG', '[--lable', 'A]'], True))
    assert check(Command('x', '', ['noise_analyzer', '--ros-args', '-p', 'chunksize:=1'],
                         True))
    # a program of two nodes takes either node's parameters, not a third's
    assert check(Command('x', '', ['imu_chain', '--ros-args', '-p', 'port:=p', '-p',
                                   'temperature_sync:=latest'], True)) is None
    assert check(Command('x', '', ['imu_chain', '--ros-args', '-p', 'chunk_size:=1'], True))


def test_every_documented_command_parses():
    bad = [f'{c.where}: {c.text}\n    -> {why}' for c in doc_commands()
           for why in [check(c)] if why]
    assert not bad, 'documented commands that do not run as written:\n' + '\n'.join(bad)


# --- the commands that need no board and no ROS graph, run -------------------------------------

#: Too long for a test and run elsewhere: the 4 h static records of the reliability walk-through
#: (docs/scripts/reliability_demo.sh runs them, 5 min) and the commands that read them;
#: compare's default of every method (minutes). They are parsed above.
_NOT_RUN = ('--duration-s 14400', 'gyro_noise_reliability', 'gyro_noise_thermal compare')


def _bare_storage_file(path, storage, seed, n, rate_hz=200.0):
    """Write a bag of white gyro noise as the bare file ``path`` (storage None: a bag folder)."""
    from gyro_noise_ros.bag import ImuBagWriter

    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    gyro = rng.normal(0.0, 1e-3, (n, 3))
    accel = np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0.0, 0.01, (n, 3))
    folder = path.with_name(path.name + '.folder')
    with ImuBagWriter(folder, storage=storage or 'sqlite3', temperature_topic=None) as w:
        w.write_imu(1_700_000_000 * 10**9 + np.round(t * 1e9).astype(np.int64), gyro, accel)
    if storage is None:
        shutil.move(str(folder), str(path))
        return
    (inner,) = [p for p in folder.iterdir() if p.suffix in ('.mcap', '.db3')]
    shutil.move(str(inner), str(path))
    shutil.rmtree(folder)


def _run(cmd, capsys):
    """Run one documented command in this process (the tool's ``main``); return its exit code."""
    words = cmd.argv
    module = SCRIPTS[words[0]]
    rc = importlib.import_module(module).main(words[1:])
    out = capsys.readouterr()
    assert rc == 0, f'{cmd.where}: {cmd.text}\nexit {rc}: {out.err.strip()}'
    return out


def _commands(doc, first_words):
    return [c for c in doc_commands() if c.fenced and c.where.startswith(doc + ':')
            and c.argv[0] in first_words and not c.synopsis
            and not any(skip in c.text for skip in _NOT_RUN)]


# slow: the README's and the walk-throughs' commands on generated inputs: analyses with the
# default 10,000-sample chunks, calibrations, excitation checks, a thermal fit (60-90 s)
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_readme_commands_run_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    # the README's recordings, named as it names them: three chunks of 10,000 samples each
    for name, storage, seed in (('ref.mcap', 'mcap', 1), ('h1.mcap', 'mcap', 2),
                                ('h2.mcap', 'mcap', 3), ('new.db3', 'sqlite3', 4)):
        _bare_storage_file(tmp_path / name, storage, seed, 30_000)
    for name, seed in (('ref', 5), ('H1', 6), ('H2', 7), ('H3', 8)):   # docs/offline_tool.md
        _bare_storage_file(tmp_path / name, None, seed, 30_000)
    ran = []
    # the emulator writes the procedure's recordings (docs/reliability.md's walk-through), and
    # the README's six-position and multi-pose bags under the README's names
    for cmd in _commands('docs/reliability.md', ('portenta_emulator',)):
        _run(cmd, capsys)
        ran.append(cmd.where)
    for name, scenario in (('sixpos.mcap', 'six-position'), ('poses.mcap', 'multi-pose')):
        _run(Command('setup', '', ['portenta_emulator', '--odr-hz', '104', '--seed', '21',
                                   '--scenario', scenario, '--write-bag', name,
                                   '--bag-storage', 'mcap'], True), capsys)
    tools = ('gyro_noise_analyze', 'gyro_noise_calibrate', 'gyro_noise_excitation',
             'gyro_noise_thermal')
    for doc in ('README.md', 'docs/offline_tool.md', 'docs/reliability.md', 'docs/thermal.md'):
        for cmd in _commands(doc, tools):
            if cmd.argv[0] == 'gyro_noise_thermal' and doc == 'README.md':
                continue  # train.mcap, test.mcap: the user's oven runs; docs/thermal.md's run
            if '--scheduler' in cmd.argv:
                continue  # a Dask cluster: parsed above
            _run(cmd, capsys)
            ran.append(cmd.where)
    # what the README promises, now true: labels one at a time, the bag of a 3-bag reference
    summary = yaml.safe_load((tmp_path / 'report' / 'summary.json').read_text())
    assert [b['label'] for b in summary['bags']] == ['ref', 'H1', 'H2']
    assert (tmp_path / 'check' / 'report.html').is_file()
    assert (tmp_path / 'dwell' / 'report.html').is_file()
    assert len(ran) >= 16, ran
