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


def test_min_range_must_be_a_finite_non_negative_span():
    run = _run(np.linspace(25.0, 30.0, 100))
    for bad in (float('nan'), -5.0, float('inf')):
        with pytest.raises(ParameterError, match='min_range_c'):
            check_trainable(run, min_range_c=bad)
    check_trainable(run, min_range_c=0.0)


def test_trainable_needs_two_rate_windows_for_a_rate_method():
    # 15 s of a fast ramp: enough span, too short for a method that uses dT
    run = _run(np.linspace(20.0, 30.0, 150))
    check_trainable(run, method='poly3')
    with pytest.raises(InputDataError, match='needs at least 20 s'):
        check_trainable(run, method='linear_tdt')
    with pytest.raises(MethodUnavailableError):
        check_trainable(run, method='nosuch')


def test_range_report_counts_t_and_dt():
    run = _run(np.linspace(10.0, 40.0, 3000))
    info = training_info(run)
    # the training rate is one value (a ramp): 0.1 degC/s with 0.1-s samples
    assert info.temperature_rate_min_c_s == pytest.approx(30.0 / 299.9, rel=1e-9)
    temp = np.array([5.0, 20.0, 30.0, 45.0, 25.0])
    rate = np.array([0.0, 30.0 / 299.9, -0.1, 30.0 / 299.9, 30.0 / 299.9])
    rep = methods.range_report(info, temp, rate, treatment='held')
    assert (rep.temperature_below, rep.temperature_above) == (1, 1)
    # 0 and -0.1 are below the trained rate, which is one value
    assert (rep.rate_below, rep.rate_above) == (2, 0)
    assert rep.outside == 3 and rep.fraction_outside == pytest.approx(0.6)
    # counts are named as counts, next to the ranges they refer to
    text = rep.text()
    assert text.startswith('3 of 5 samples (60 %) lie outside the trained range (T 10.00..40.00 '
                           'degC, dT 0.1..0.1 degC/s; this run T 5.00..45.00 degC, dT -0.1..0.1 '
                           'degC/s): 1 with T below it, 1 above, 2 with dT below it, 0 above.')
    assert text.endswith('There the method: held')
    assert '60 % of the run lies outside' in rep.warning()
    # up to MAX_OUTSIDE_SHARE (5 %) there is no warning
    trained = info.temperature_rate_min_c_s
    inside = methods.range_report(info, np.full(100, 20.0), np.r_[np.full(95, trained), [0.0] * 5])
    assert inside.fraction_outside == methods.MAX_OUTSIDE_SHARE and inside.warning() is None
    assert rep.as_dict()['fraction_outside'] == pytest.approx(0.6)
    # a run shorter than the rate window has no rate range: dT is not checked
    short = training_info(_run(np.linspace(10.0, 40.0, 50)))
    assert short.temperature_rate_min_c_s is None
    assert methods.range_report(short, temp, rate).rate_below == 0
    # only the inputs a method evaluates count: T alone for poly3, nothing for raw
    t_only = methods.range_report(info, temp, rate, uses_rate=False)
    assert (t_only.temperature_below, t_only.rate_below, t_only.outside) == (1, 0, 2)
    assert methods.range_report(info, temp, rate, uses_temperature=False).outside == 0
    for name in ('poly3', 'raw', 'wtd'):
        assert not getattr(methods.method_class(name), 'uses_rate')
    assert not methods.method_class('raw').uses_temperature


def _saved(tmp_path):
    run = _run(np.linspace(10.0, 40.0, 3000))
    method = get_method('toy_linear')
    method.fit(run, rng=np.random.default_rng(0))
    save_model(method, tmp_path / 'model.json', training=training_info(run))
    return json.loads((tmp_path / 'model.json').read_text())


def test_model_from_another_version_loads_with_a_note(tmp_path):
    doc = _saved(tmp_path)
    assert not load_model(tmp_path / 'model.json').notes
    doc['package_version'] = '9.9.9'
    (tmp_path / 'old.json').write_text(json.dumps(doc))
    model = load_model(tmp_path / 'old.json')
    assert model.package_version == '9.9.9'
    assert len(model.notes) == 1 and 'written by gyro_noise_ros 9.9.9' in model.notes[0]
    # format version 1 (no accel, no rate window) is still read
    doc['format_version'] = 1
    del doc['accel'], doc['training']['rate_window_s']
    (tmp_path / 'v1.json').write_text(json.dumps(doc))
    assert load_model(tmp_path / 'v1.json').training.rate_window_s == 10.0


def test_model_with_empty_parameters_is_refused(tmp_path):
    doc = _saved(tmp_path)
    for empty in ({}, None, []):
        doc['parameters'] = empty
        (tmp_path / 'e.json').write_text(json.dumps(doc))
        with pytest.raises(ModelFileError, match='no fitted parameters'):
            load_model(tmp_path / 'e.json')


def test_accelerometer_polynomial_is_fitted_and_saved(tmp_path):
    temp = np.linspace(10.0, 40.0, 3000)
    run = _run(temp)
    d = temp - 25.0
    accel = np.column_stack([1e-3 * d, 9.80665 - 2e-4 * d + 1e-5 * d ** 2, 0.5 + 3e-6 * d ** 3])
    run = ThermalRun(t_s=run.t_s, gyro_rad_s=run.gyro_rad_s, temperature_c=temp,
                     rate_hz=run.rate_hz, accel_m_s2=accel)
    model = methods.fit_method('poly3', run, rng=np.random.default_rng(0))
    poly = model.accel
    # T_ref is the middle of the range (25); the change from T_ref is exact, X0 is 0
    assert poly.t_ref_c == 25.0 and poly.relative
    np.testing.assert_allclose(poly.drift_rad_s(temp, 0.0), accel - [0.0, 9.80665, 0.5],
                               atol=1e-12)
    save_model(model.method, tmp_path / 'm.json', training=model.training, accel=poly)
    again = load_model(tmp_path / 'm.json')
    np.testing.assert_array_equal(again.accel.coef, poly.coef)
    assert methods.fit_method('poly3', run, rng=np.random.default_rng(0), accel=False).accel \
        is None


def test_a_method_of_another_form_carries_its_autopilot_poly3(tmp_path):
    # the poly3 fitted on the same run, saved and loaded with the model; a poly3 model is its own
    temp = np.linspace(10.0, 40.0, 3000)
    run = _run(temp)
    model = methods.fit_method('toy_linear', run, rng=np.random.default_rng(0))
    alone = methods.fit_method('poly3', run, rng=np.random.default_rng(0))
    np.testing.assert_array_equal(model.autopilot.coef, alone.method.coef)
    assert model.poly3() is model.autopilot and alone.poly3() is alone.method
    assert alone.autopilot is None
    save_model(model.method, tmp_path / 'm.json', training=model.training,
               autopilot=model.autopilot)
    doc = json.loads((tmp_path / 'm.json').read_text())
    assert doc['format_version'] == 3 and 'PX4 and ArduPilot' in doc['autopilot']['note']
    np.testing.assert_array_equal(load_model(tmp_path / 'm.json').poly3().coef, alone.method.coef)


def test_a_model_of_another_sensor_is_refused():
    # the same sensor, another run: its offset from the model is its turn-on difference (here
    # the noise's median, ~1e-5 deg/s); another part: its zero-rate level differs by 0.5 deg/s
    model = methods.fit_method('lsq_cv', _run(np.linspace(10.0, 40.0, 3000)),
                               rng=np.random.default_rng(0))
    again = _run(np.linspace(40.0, 12.0, 3000), seed=1)
    offsets = methods.check_same_sensor(model, again)
    assert max(abs(v) for v in offsets) < 0.01
    other = ThermalRun(t_s=again.t_s, gyro_rad_s=again.gyro_rad_s + np.radians([0.5, 0.0, -0.3]),
                       temperature_c=again.temperature_c, rate_hz=again.rate_hz, name='other')
    with pytest.raises(methods.SensorMismatchError, match=r'x \+0\.50\d, z -0\.30\d deg/s .*more '
                                                          r'than 0\.25 deg/s.*another sensor'):
        methods.check_same_sensor(model, other)
    assert methods.check_same_sensor(model, other, max_offset_deg_s=float('inf'))[0] == \
        pytest.approx(0.5, abs=0.01)
    with pytest.raises(ParameterError, match='max_offset_deg_s'):
        methods.check_same_sensor(model, other, max_offset_deg_s=float('nan'))
