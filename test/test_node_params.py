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
Every node's ``config/<node>.yaml`` against the node's parameter table (``PARAMETERS``).

Nodes are discovered, so a node module added later (analyzer, recorder) is covered as soon as it
defines ``NODE_NAME`` and ``PARAMETERS`` (see ``gyro_noise_ros/nodes/_ros_common.py``).
"""

import importlib
from pathlib import Path
import pkgutil
import re

import gyro_noise_ros.nodes as nodes_pkg
from gyro_noise_ros.nodes._ros_common import ParamSpec
import pytest
import rclpy
from rclpy.parameter import Parameter, parameter_dict_from_yaml_file, parameter_value_to_python
import yaml

pytestmark = pytest.mark.ros

CONFIG_DIR = Path(__file__).resolve().parents[1] / 'config'


def _node_modules():
    found = []
    for info in pkgutil.iter_modules(nodes_pkg.__path__):
        if info.name.startswith('_'):
            continue
        module = importlib.import_module(f'{nodes_pkg.__name__}.{info.name}')
        if hasattr(module, 'PARAMETERS'):
            found.append(module)
    return found


NODE_MODULES = _node_modules()


def _ids(modules):
    return [m.NODE_NAME for m in modules]


def test_driver_is_discovered():
    # Guards the discovery itself: an empty list would make every parametrised test vanish.
    assert 'lsm6dso32_driver' in _ids(NODE_MODULES)


def test_every_config_file_belongs_to_a_node():
    names = set(_ids(NODE_MODULES))
    # diagnostics_analyzers.yaml configures diagnostic_aggregator, not a node of this package.
    orphans = [p.name for p in CONFIG_DIR.glob('*.yaml')
               if p.stem not in names and p.stem != 'diagnostics_analyzers']
    assert not orphans, ('config files without a node module defining NODE_NAME/PARAMETERS: '
                         f'{orphans}')


@pytest.mark.parametrize('module', NODE_MODULES, ids=_ids(NODE_MODULES))
def test_table_is_well_formed(module):
    table = module.PARAMETERS
    names = [spec.name for spec in table]
    assert len(names) == len(set(names)), 'duplicate parameter names'
    for spec in table:
        assert isinstance(spec, ParamSpec)
        assert re.fullmatch(r'[a-z][a-z0-9_]*', spec.name), spec.name
        assert spec.description.strip(), f'{spec.name} has no description'
        assert (spec.min_value is None) == (spec.max_value is None), \
            f'{spec.name}: give both bounds'
        spec.check(spec.default)  # the default itself must satisfy its range and choices
        spec.descriptor()  # builds (type known, range of the right kind)


@pytest.mark.parametrize('module', NODE_MODULES, ids=_ids(NODE_MODULES))
def test_yaml_lists_every_parameter_with_its_default(module):
    path = CONFIG_DIR / f'{module.NODE_NAME}.yaml'
    assert path.is_file(), f'missing {path}'
    params = parameter_dict_from_yaml_file(str(path), use_wildcard=True)  # /** or node name
    values = {name: parameter_value_to_python(p.value) for name, p in params.items()}
    table = {spec.name: spec for spec in module.PARAMETERS}
    assert set(values) == set(table), (f'only in YAML: {sorted(set(values) - set(table))}; '
                                       f'only in the table: {sorted(set(table) - set(values))}')
    for name, spec in table.items():
        # Exact type: a YAML "1" for a double parameter would be refused by rclpy at start.
        assert type(values[name]) is type(spec.default), (name, values[name], spec.default)
        assert values[name] == spec.default, (name, values[name], spec.default)


@pytest.mark.parametrize('module', NODE_MODULES, ids=_ids(NODE_MODULES))
def test_yaml_comment_gives_unit_and_read_only(module):
    text = (CONFIG_DIR / f'{module.NODE_NAME}.yaml').read_text()
    for spec in module.PARAMETERS:
        lines = [ln for ln in text.splitlines() if re.match(rf'\s+{spec.name}:', ln)]
        assert len(lines) == 1, f'{spec.name}: expected one line, found {len(lines)}'
        assert '#' in lines[0], f'{spec.name}: no comment'
        comment = lines[0].split('#', 1)[1].strip()
        unit = spec.unit or '-'
        assert comment.startswith(f'[{unit}]'), f'{spec.name}: comment must start with [{unit}]'
        assert ('read_only' in comment) == spec.read_only, \
            f'{spec.name}: read_only marker mismatch'


@pytest.mark.parametrize('module', NODE_MODULES, ids=_ids(NODE_MODULES))
def test_yaml_is_keyed_for_any_namespace(module):
    # Keyed by the bare node name, a file is silently ignored under -r __ns:=/robot1.
    doc = yaml.safe_load((CONFIG_DIR / f'{module.NODE_NAME}.yaml').read_text())
    assert list(doc) == ['/**'], f'top-level keys {list(doc)}: key the file /** so it applies '
    'under any namespace'


# (node class, parameter changed in a copy of the shipped file, value, extra overrides)
_NAMESPACED = {
    'gyro_noise_record': ('queue_depth', 12345),
    'lsm6dso32_driver': ('qos_depth', 1234),
}


@pytest.mark.parametrize('name', sorted(_NAMESPACED))
def test_shipped_file_applies_under_a_namespace(name, tmp_path):
    module = next(m for m in NODE_MODULES if m.NODE_NAME == name)
    param, value = _NAMESPACED[name]
    text = (CONFIG_DIR / f'{name}.yaml').read_text()
    changed = re.sub(rf'(\n\s+{param}: )\S+', rf'\g<1>{value}', text)
    assert changed != text
    path = tmp_path / f'{name}.yaml'
    path.write_text(changed)
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=['prog', '--ros-args', '-r', '__ns:=/robot1',
                                  '--params-file', str(path)])
    node = None
    try:
        overrides = [Parameter('output', value=str(tmp_path / 'bag'))] if name.endswith('record') \
            else [Parameter('autostart', value=False)]
        node_class = next(v for v in vars(module).values()
                          if isinstance(v, type) and v.__module__ == module.__name__
                          and hasattr(v, 'get_parameter'))
        node = node_class(context=ctx, parameter_overrides=overrides)
        assert node.get_namespace() == '/robot1'
        assert node.get_parameter(param).value == value
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=ctx)


def _driver(ctx, args):
    from gyro_noise_ros.nodes.driver import Lsm6dso32Driver

    return Lsm6dso32Driver(context=ctx, parameter_overrides=[Parameter('autostart', value=False)])


@pytest.mark.parametrize('key, extra, refused', [
    ('/**', [], False),                           # a file shared by several nodes: warned
    ('/*/lsm6dso32_driver', [], True),            # a pattern ending in this node's name
    ('/robot1/*', [], False),                     # every node of the namespace: warned
    ('/robot1/lsm6dso32_driver', [], True),       # the node's own section: refused
    ('/**', ['-p', 'queue_depth:=5'], True),      # given on the command line as well: refused
])
def test_an_unknown_name_of_a_shared_file_is_warned_and_one_given_to_the_node_refused(
        key, extra, refused, tmp_path, monkeypatch, ros_graph, caplog):
    # queue_depth is the recorder's, not the driver's: in a '/**' section meant for every node
    # it is another node's parameter; anywhere addressed to the driver it is a mistake
    from gyro_noise_ros.errors import ParameterError
    from gyro_noise_ros.nodes import _params

    path = tmp_path / 'shared.yaml'
    section = {'ros__parameters': {'queue_depth': 5, 'qos_depth': 77}}
    path.write_text(yaml.safe_dump({key: section}))
    argv = ['lsm6dso32_driver', '--ros-args', '-r', '__ns:=/robot1', '--params-file', str(path),
            *extra]
    monkeypatch.setattr('sys.argv', argv)
    monkeypatch.setattr(_params, '_WARNED', set())
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=argv)
    try:
        if refused:
            with pytest.raises(ParameterError, match="unknown parameter 'queue_depth'"):
                _driver(ctx, argv)
            return
        node = _driver(ctx, argv)
        try:
            assert node.get_parameter('qos_depth').value == 77      # the file did apply
        finally:
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


def test_the_sections_of_a_parameter_file_are_read_with_nested_names(tmp_path):
    from gyro_noise_ros.nodes._params import params_file_sections

    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    a: 1\n    grp:\n      b: 2\n'
                    'robot1:\n  noise_analyzer:\n    ros__parameters:\n      c: [1, 2]\n')
    assert params_file_sections(['x', '--params-file', str(path), '--params-file',
                                 str(tmp_path / 'missing.yaml')]) == [
        (str(path), '**', ['a', 'grp.b']), (str(path), 'robot1/noise_analyzer', ['c'])]
