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
Errors name the caller's parameters; each adapter spells them (errors.py, cli/_common.py).

The science layer writes a parameter as ``{name}``: a library caller reads the parameter's name,
a tool's user reads the tool's option, and pickling (process pools, Dask) keeps the template.
"""

import pickle

from gyro_noise_ros.cli._common import option_of, run_cli
from gyro_noise_ros.errors import (BagError, GyroNoiseError, InputDataError, nothing_left_error,
                                   ParameterError)


def test_a_parameter_is_its_name_for_a_library_caller_and_an_option_for_a_tool():
    err = nothing_left_error(start_s=1000.0, record_end_s=44.995, label='run1')
    assert str(err) == ('run1: nothing left to analyse: start_s 1000 s is past the record end '
                        '44.995 s')
    assert err.spelled(lambda name: option_of(name, {'start_s': '--start'})) == (
        'run1: nothing left to analyse: --start 1000 s is past the record end 44.995 s')
    window = nothing_left_error(start_s=5.0, end_s=6.0, record_end_s=10.0)
    renamed = {'start_s': '--start', 'end_s': '--end'}
    assert window.spelled(lambda name: option_of(name, renamed)) == (
        'nothing left to analyse: no sample between --start 5 s and --end 6 s (the record '
        'spans 0-10 s)')


def test_only_the_listed_parameters_are_replaced():
    err = ParameterError('{min_range_c} is {bad}; {"json": 1}', parameters=('min_range_c',))
    assert str(err) == 'min_range_c is {bad}; {"json": 1}'
    assert err.spelled(option_of) == '--min-range-c is {bad}; {"json": 1}'
    plain = BagError('no {braces} touched')
    assert str(plain) == plain.spelled(option_of) == 'no {braces} touched'


def test_prefixed_keeps_class_and_parameters_and_pickling_keeps_the_template():
    err = InputDataError('give {rate_hz}', parameters=('rate_hz',)).prefixed('before record: ')
    assert type(err) is InputDataError and err.parameters == ('rate_hz',)
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is InputDataError
    assert back.spelled(option_of) == 'before record: give --rate-hz'
    assert isinstance(back, GyroNoiseError) and back.exit_code == 4


def test_run_cli_prints_the_option_and_the_exit_code(capsys):
    def body(argv):
        raise ParameterError('{tcp} must be HOST:PORT, got {spec}', parameters=('tcp',))

    assert run_cli('tool', body, []) == 2
    assert capsys.readouterr().err == 'tool: error: --tcp must be HOST:PORT, got {spec}\n'
