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

"""Method registry, model.json round trip, trained-range refusal, training-data checks."""

import json

from _thermal_toy import LinearInT
from gyro_noise_ros import __version__
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.thermal import methods
from gyro_noise_ros.thermal.methods import (check_temperature_range, check_trainable,
                                            get_method, load_model, method_class,
                                            MethodUnavailableError, ModelFileError,
                                            register_method, save_model, TemperatureRangeError,
                                            ThermalModel, training_info)
from gyro_noise_ros.thermal.run import ThermalRun
import numpy as np
import pytest


@pytest.fixture(autouse=True)
def toy_registered():
    register_method('toy_linear', LinearInT)
    yield
    methods._registered.pop('toy_linear', None)


def _run(temp, seed=0, rate_hz=10.0):
    rng = np.random.default_rng(seed)
    n = temp.size
    gyro = rng.normal(0.0, 1e-3, (n, 3)) + np.outer(temp - 20.0, [1e-4, -2e-4, 3e-4])
    return ThermalRun(t_s=np.arange(n) / rate_hz, gyro_rad_s=gyro, temperature_c=temp,
                      rate_hz=rate_hz, name=f'run{seed}')


def test_builtin_names_and_unknown_name():
    names = methods.method_names()
    for name in ('raw', 'poly3', 'linear_tdt', 'wtd', 'bp', 'emd_wtd_sabp', 'parallel',
                 'toy_linear'):
        assert name in names
    with pytest.raises(MethodUnavailableError, match="unknown method 'nope'"):
        method_class('nope')
    assert MethodUnavailableError('x').exit_code == 2


def test_missing_module_gives_one_clear_error(monkeypatch):
    monkeypatch.setitem(methods.BUILTIN_METHODS, 'ghost', ('gyro_noise_ros.thermal.ghost', 'G'))
    with pytest.raises(MethodUnavailableError, match='gyro_noise_ros.thermal.ghost cannot be'):
        method_class('ghost')
    monkeypatch.setitem(methods.BUILTIN_METHODS, 'ghost2', ('gyro_noise_ros.thermal.run', 'G'))
    with pytest.raises(MethodUnavailableError, match='has no G'):
        method_class('ghost2')


def test_register_refuses_bad_names_and_classes():
    with pytest.raises(ParameterError):
        register_method('bad name', LinearInT)
    with pytest.raises(ParameterError, match='from_dict'):
        register_method('half', type('Half', (), {'fit': lambda s: 0, 'apply': lambda s: 0,
                                                  'to_dict': lambda s: 0}))


def test_model_json_round_trip(tmp_path):
    temp = np.linspace(10.0, 40.0, 3000)
    run = _run(temp)
    method = get_method('toy_linear')
    method.fit(run, rng=np.random.default_rng(0))
    info = training_info(run, sources=['a.mcap'])
    doc = save_model(method, tmp_path / 'model.json', training=info)
    on_disk = json.loads((tmp_path / 'model.json').read_text())
    assert on_disk == doc
    assert on_disk['method'] == 'toy_linear' and on_disk['causal'] is True
    assert on_disk['package_version'] == __version__
    tr = on_disk['training']
    assert tr['temperature_min_c'] == 10.0 and tr['temperature_max_c'] == 40.0
    assert tr['sources'] == ['a.mcap'] and tr['samples'] == 3000 and tr['rate_hz'] == 10.0
    # the ramp rises 30 degC over 2999 sample periods of 0.1 s: a least-squares slope is exact
    assert tr['temperature_rate_max_c_s'] == pytest.approx(30.0 / 299.9, rel=1e-9)
    model = load_model(tmp_path / 'model.json')
    assert isinstance(model, ThermalModel)
    np.testing.assert_array_equal(model.method.apply(run), method.apply(run))
    assert model.training == info


def test_load_model_refuses_garbage(tmp_path):
    with pytest.raises(ModelFileError, match='cannot be read'):
        load_model(tmp_path / 'missing.json')
    (tmp_path / 'x.json').write_text('{not json')
    with pytest.raises(ModelFileError, match='not JSON'):
        load_model(tmp_path / 'x.json')
    (tmp_path / 'y.json').write_text('{"format": "other"}')
    with pytest.raises(ModelFileError, match='not a gyro_noise_ros thermal model'):
        load_model(tmp_path / 'y.json')
    doc = {'format': methods.MODEL_FORMAT, 'format_version': 1, 'method': 'toy_linear',
           'training': {}, 'parameters': {}}
    (tmp_path / 'z.json').write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match='lacks or garbles'):
        load_model(tmp_path / 'z.json')


def test_range_check_margin():
    run = _run(np.linspace(10.0, 40.0, 500))
    method = get_method('toy_linear')
    method.fit(run, rng=np.random.default_rng(0))
    model = ThermalModel(method=method, training=training_info(run))
    assert check_temperature_range(model, [6.0, 44.9]) == (6.0, 44.9)
    with pytest.raises(TemperatureRangeError, match='10.00..40.00 degC'):
        check_temperature_range(model, [4.9, 20.0])
    with pytest.raises(TemperatureRangeError):
        check_temperature_range(model, [20.0, 41.0], margin_c=0.5)
    check_temperature_range(model, [-100.0, 100.0], margin_c=float('inf'))
    with pytest.raises(ParameterError):
        check_temperature_range(model, [20.0], margin_c=-1.0)
    assert TemperatureRangeError('x').exit_code == 4


def test_trainable_refuses_constant_and_narrow_temperature():
    with pytest.raises(InputDataError, match='constant at 25.000 degC'):
        check_trainable(_run(np.full(100, 25.0)))
    with pytest.raises(InputDataError, match='spans only 1 degC'):
        check_trainable(_run(np.linspace(25.0, 26.0, 100)))
    check_trainable(_run(np.linspace(25.0, 26.0, 100)), min_range_c=0.5)
    bad = _run(np.linspace(0.0, 30.0, 100))
    bad.gyro_rad_s[5, 1] = np.nan
    with pytest.raises(InputDataError, match='NaN'):
        check_trainable(bad)
