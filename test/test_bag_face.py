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
The faces of gyro_noise_ros.bag and gyro_noise_ros.msgs hand names on and hold no logic.

Every public name of a face is the very object its home module defines; the bag face defines no
function or class itself; no module of bag/ imports a name back from its own face (only
submodules, so the modules stay importable in any order).
"""

import ast
import importlib
from pathlib import Path

import gyro_noise_ros.bag as bag
import gyro_noise_ros.msgs as msgs
import pytest

_BAG_DIR = Path(bag.__file__).parent

#: Where each public name of a face lives (a move must keep this map true).
_HOMES = {
    'gyro_noise_ros.bag': {
        'ImuBatch': 'gyro_noise_ros.bag.batch',
        'decode_imu': 'gyro_noise_ros.bag.batch',
        'decode_temperature': 'gyro_noise_ros.bag.batch',
        'TopicInfo': 'gyro_noise_ros.bag.topics',
        'list_topics': 'gyro_noise_ros.bag.topics',
        'find_imu_topic': 'gyro_noise_ros.bag.topics',
        'ImuBagReader': 'gyro_noise_ros.bag.reader',
        'ImuBagWriter': 'gyro_noise_ros.bag.writer',
        'write_raw': 'gyro_noise_ros.bag.writer',
        'IMU_MSGTYPE': 'gyro_noise_ros.msgs.imu',
        'TEMPERATURE_MSGTYPE': 'gyro_noise_ros.msgs.temperature',
        'encode_imu_cdr': 'gyro_noise_ros.msgs.imu',
        'encode_temperature_cdr': 'gyro_noise_ros.msgs.temperature',
        'count_stamp_regressions': 'gyro_noise_ros.msgs.stamps',
    },
}


@pytest.mark.parametrize('face', [bag, msgs], ids=['bag', 'msgs'])
def test_face_names_are_the_home_objects(face):
    # Each listed name resolves, and to the object of the module that defines it (functions and
    # classes by __module__, constants by identity with a submodule's attribute).
    assert sorted(face.__all__) == sorted(set(face.__all__)), 'duplicate in __all__'
    homes = _HOMES.get(face.__name__, {})
    for name in face.__all__:
        obj = getattr(face, name)
        home = getattr(obj, '__module__', None) or homes.get(name)
        if home is None:  # a constant of msgs: find the one submodule that defines it
            owners = [m for m in ('cdr', 'imu', 'stamps', 'temperature')
                      if name in vars(importlib.import_module(f'{face.__name__}.{m}'))]
            assert owners, name
            home = f'{face.__name__}.{owners[0]}'
        assert home != face.__name__, f'{name} is defined in the face {face.__name__}'
        if name in homes:
            assert home == homes[name], (name, home)
        assert getattr(importlib.import_module(home), name) is obj, name


def test_bag_face_keeps_its_public_names():
    # Tools and users import these from gyro_noise_ros.bag; the split must not drop any.
    assert set(_HOMES['gyro_noise_ros.bag']) <= set(bag.__all__)


def test_bag_face_defines_no_function_or_class():
    tree = ast.parse((_BAG_DIR / '__init__.py').read_text())
    defined = [node.name for node in tree.body
               if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))]
    assert defined == []


def test_bag_modules_never_import_from_their_face():
    submodules = {path.stem for path in _BAG_DIR.glob('*.py')}
    offenders = []
    for path in sorted(_BAG_DIR.glob('*.py')):
        if path.name == '__init__.py':
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module is None:
                offenders += [f'{path.name}: from . import {alias.name}'
                              for alias in node.names if alias.name not in submodules]
    assert offenders == []
