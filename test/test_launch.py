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
Launch files and packaging checked without ``launch_ros`` (it does not install from PyPI).

What can be checked here: each launch file imports only launch APIs (parsed with ``ast``, not
run), every executable it starts is a console script of ``setup.py``, every parameter file it
names is in ``config/``, ``setup.py`` installs them to ``share/gyro_noise_ros/launch`` and
``package.xml`` declares ``launch_ros``; ``config/diagnostics_analyzers.yaml`` groups match the
status names the nodes publish. With ``launch_ros`` importable (a ROS install), the launch
descriptions are also built.
"""

import ast
import importlib.util
from pathlib import Path
import xml.etree.ElementTree as ET

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
LAUNCH_FILES = sorted((ROOT / 'launch').glob('*.launch.py'))
# The compensation node is written in parallel; its reference may wait for its entry point.
PENDING = {'imu_compensator'}


def _console_scripts():
    tree = ast.parse((ROOT / 'setup.py').read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values):
                if isinstance(key, ast.Constant) and key.value == 'console_scripts':
                    return {ast.literal_eval(e).split('=')[0].strip() for e in value.elts}
    raise AssertionError('no console_scripts in setup.py')


def _calls(tree, name):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func
            called = func.id if isinstance(func, ast.Name) else getattr(func, 'attr', '')
            if called == name:
                yield node


def _executables(tree):
    found = set()
    for call in _calls(tree, 'Node'):
        for kw in call.keywords:
            if kw.arg == 'executable':
                found.add(ast.literal_eval(kw.value))
    for call in _calls(tree, 'PathJoinSubstitution'):
        parts = call.args[0].elts
        consts = [p.value for p in parts if isinstance(p, ast.Constant)]
        if 'lib' in consts:
            found.add(consts[-1])
    return found


def test_launch_files_exist():
    names = {p.name for p in LAUNCH_FILES}
    assert {'gyro_noise.launch.py', 'gyro_noise_playback.launch.py'} <= names


@pytest.mark.parametrize('path', LAUNCH_FILES, ids=[p.name for p in LAUNCH_FILES])
def test_imports_only_launch_apis(path):
    tree = ast.parse(path.read_text())
    modules = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            modules.add(node.module)
    assert modules, 'no imports found'
    others = {m for m in modules if m.split('.')[0] not in ('launch', 'launch_ros')}
    assert not others, f'{path.name} imports {others}: launch files use launch APIs only'
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert 'generate_launch_description' in functions


@pytest.mark.parametrize('path', LAUNCH_FILES, ids=[p.name for p in LAUNCH_FILES])
def test_executables_are_console_scripts(path):
    found = _executables(ast.parse(path.read_text()))
    assert found, 'no executables found in the launch file'
    missing = found - _console_scripts()
    pending = missing & PENDING
    if pending:
        pytest.skip(f'{sorted(pending)} not in setup.py yet (written in parallel)')
    assert not missing, f'{path.name} starts {sorted(missing)}, not console scripts of setup.py'


def test_live_launch_starts_driver_analyzer_and_optional_nodes():
    tree = ast.parse((ROOT / 'launch' / 'gyro_noise.launch.py').read_text())
    assert {'lsm6dso32_driver', 'noise_analyzer', 'gyro_noise_record', 'portenta_emulator',
            'imu_compensator', 'imu_chain'} <= _executables(tree)
    declared = {ast.literal_eval(c.args[0]) for c in _calls(tree, 'DeclareLaunchArgument')}
    assert {'namespace', 'port', 'params_file', 'use_sim_time', 'record', 'emulator',
            'compensate', 'in_process'} <= declared
    defaults = {ast.literal_eval(c.args[0]): ast.literal_eval(kw.value)
                for c in _calls(tree, 'DeclareLaunchArgument') for kw in c.keywords
                if kw.arg == 'default_value'}
    assert defaults['compensate'] == defaults['record'] == defaults['emulator'] == 'false'
    assert defaults['in_process'] == 'false'


@pytest.mark.parametrize('path', LAUNCH_FILES, ids=[p.name for p in LAUNCH_FILES])
def test_parameter_files_exist(path):
    tree = ast.parse(path.read_text())
    named = set()
    for call in _calls(tree, 'PathJoinSubstitution'):
        last = call.args[0].elts[-1]
        if isinstance(last, ast.Constant) and last.value.endswith('.yaml'):
            named.add(last.value)
    for call in _calls(tree, 'params'):  # the live file's helper: params('<node>', ...)
        if call.args and isinstance(call.args[0], ast.Constant):
            named.add(call.args[0].value + '.yaml')
    assert named, 'no parameter files found'
    missing = {n for n in named if not (ROOT / 'config' / n).is_file()}
    pending = {n for n in missing if n.removesuffix('.yaml') in PENDING}
    assert missing == pending, f'missing parameter files {sorted(missing - pending)}'


def test_setup_installs_launch_files_and_package_declares_launch_ros():
    text = (ROOT / 'setup.py').read_text()
    assert "('share/' + PACKAGE + '/launch', glob('launch/*.launch.py'))" in text
    root = ET.parse(ROOT / 'package.xml').getroot()
    exec_depends = {e.text for e in root.findall('exec_depend')}
    assert {'launch', 'launch_ros', 'rcl_interfaces'} <= exec_depends
    assert 'std_msgs' not in exec_depends  # nothing imports it
    maintainer = root.find('maintainer')
    assert not maintainer.get('email').endswith('.invalid')


def test_aggregator_groups_match_the_node_statuses():
    doc = yaml.safe_load((ROOT / 'config' / 'diagnostics_analyzers.yaml').read_text())
    params = doc['/**']['ros__parameters']
    groups = {k: v for k, v in params.items() if isinstance(v, dict)}
    prefixes = {p for g in groups.values() for p in g['startswith']}
    for g in groups.values():
        assert g['type'] == 'diagnostic_aggregator/GenericAnalyzer'
    # Status names published by the nodes: '<node name>: <task>'.
    assert {'lsm6dso32_driver', 'noise_analyzer'} <= prefixes
    assert 'lsm6dso32_driver: link'.startswith('lsm6dso32_driver')


@pytest.mark.skipif(importlib.util.find_spec('launch_ros') is None,
                    reason='launch_ros is not installable from PyPI; runs in a ROS install')
@pytest.mark.parametrize('path', LAUNCH_FILES, ids=[p.name for p in LAUNCH_FILES])
def test_launch_description_builds(path):  # pragma: no cover - needs a ROS install
    spec = importlib.util.spec_from_file_location(path.stem.replace('.', '_'), path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.generate_launch_description().entities
