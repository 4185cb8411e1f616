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

"""gyro_noise_thermal end to end on tiny bags: fit, apply, compare, simulate, every refusal."""

import json
import sys

from _thermal_toy import FirstOrderLowPass, LinearInT, write_thermal_bag
from gyro_noise_ros.bag import ImuBagReader
from gyro_noise_ros.cli.thermal import main
from gyro_noise_ros.thermal import methods
from gyro_noise_ros.thermal.methods import register_method
from gyro_noise_ros.thermal.metrics import residual_drift_deg_s
import numpy as np
import pytest

RATE = 20.0
N = int(300 * RATE)
SLOPE = np.array([2e-4, -1e-4, 5e-5])  # rad/s per degC
FAST = ['--f-lo-hz', '0.5', '--no-figures', '--quiet']


@pytest.fixture(autouse=True)
def toys():
    register_method('toy_linear', LinearInT)
    register_method('toy_lowpass', FirstOrderLowPass)
    yield
    methods._registered.pop('toy_linear', None)
    methods._registered.pop('toy_lowpass', None)


def _bag(path, seed, *, lo=10.0, hi=40.0, n=N, gyro_nan=False, temp_shift_s=0.0,
         temp_period_s=1.0, glitches=None, kelvin=False, offset_rad_s=0.0, **kw):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    temp_t = np.arange(0.0, t[-1] + temp_period_s, temp_period_s)
    temp = lo + (hi - lo) * 0.5 * (1 - np.cos(2 * np.pi * temp_t / (t[-1] + 1.0)))
    temp_at_gyro = np.interp(t, temp_t, temp)
    gyro = (rng.normal(0.0, 2e-3, (n, 3)) + np.outer(temp_at_gyro - 25.0, SLOPE)
            + np.array([offset_rad_s, 0.0, 0.0]))
    if gyro_nan:
        gyro[n // 2, 0] = np.nan
    written = temp.copy()
    for index, value in (glitches or {}).items():
        written[index] = value
    write_thermal_bag(path, t, gyro, temp_t + temp_shift_s,
                      written + (273.15 if kelvin else 0.0), **kw)
    return str(path), gyro, temp_at_gyro


@pytest.mark.slow  # fit, apply with every figure and the compensated bag (10-16 s)
def test_fit_apply_writes_model_metrics_report_and_compensated_bag(tmp_path):
    train, _, _ = _bag(tmp_path / 'train', 1)
    test, gyro, temp = _bag(tmp_path / 'test', 2, storage='mcap')
    assert main(['fit', train, '--method', 'toy_linear', '--out', str(tmp_path / 'm'),
                 '--quiet']) == 0
    model = json.loads((tmp_path / 'm' / 'model.json').read_text())
    assert model['method'] == 'toy_linear' and model['format_version'] == 3
    assert set(model['training']) == {'temperature_min_c', 'temperature_max_c',
                                      'temperature_rate_min_c_s', 'temperature_rate_max_c_s',
                                      'rate_hz', 'samples', 'duration_s', 'sources',
                                      'rate_window_s'}
    # a linear drift in T is recovered by the linear model (noise 2e-3 rad/s, 6000 samples)
    np.testing.assert_allclose(model['parameters']['coef_rad_s'][1], SLOPE, atol=2e-5)
    training = json.loads((tmp_path / 'm' / 'training.json').read_text())
    assert set(training['in_sample']) == {'x', 'y', 'z'}
    assert (tmp_path / 'm' / 'training.md').read_text().startswith('# Training report')
    # the one fit of this file that draws its figures (the others pass --no-figures)
    for name in ('training_fig10_run.png', 'training_fig18_output.png',
                 'training_fig17_drift.png'):
        assert (tmp_path / 'm' / name).stat().st_size > 1000, name

    out = tmp_path / 'a'
    assert main(['apply', test, '--model', str(tmp_path / 'm' / 'model.json'), '--out',
                 str(out), *FAST]) == 0
    doc = json.loads((out / 'metrics.json').read_text())
    assert doc['method'] == 'toy_linear' and not doc['in_sample']
    for axis in 'xyz':
        ax = doc['axes'][axis]
        assert set(ax) == {'raw', 'processed', 'bandwidth', 'bandwidth_small_signal', 'noise_path',
                           'verdict'}
        assert {'arw_deg_sqrt_h', 'bias_stability_deg_h', 'residual_drift_deg_s'} <= set(ax['raw'])
        # the drift (up to 0.003 rad/s peak) dominates the raw 60-s means, not the processed
        assert ax['processed']['residual_drift_deg_s'] < 0.3 * ax['raw']['residual_drift_deg_s']
        assert ax['bandwidth']['minus_3db_bound'] == 'above'
    with ImuBagReader(out / 'compensated') as r:
        got = next(r.iter_batches(100_000)).gyro
        assert r.read_temperature()[1].size == 301
    coef = np.asarray(model['parameters']['coef_rad_s'])
    np.testing.assert_allclose(got, gyro - coef[0] - np.outer(temp, coef[1]), atol=1e-12)
    assert '| axis |' in (out / 'report.md').read_text()


@pytest.mark.slow  # fit and apply with every figure drawn (8-14 s)
def test_apply_with_figures_and_in_sample_warning(tmp_path):
    train, _, _ = _bag(tmp_path / 'train', 1)
    assert main(['fit', train, '--method', 'toy_lowpass', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    out = tmp_path / 'a'
    assert main(['apply', train, '--model', str(tmp_path / 'm' / 'model.json'), '--out',
                 str(out), '--f-lo-hz', '0.5', '--no-bag', '--quiet']) == 0
    text = (out / 'report.md').read_text()
    assert 'in-sample' in text
    for name in ('fig10_run.png', 'fig18_output.png', 'fig17_drift.png', 'fig19_allan.png',
                 'bandwidth.png', 'steps.png'):
        assert (out / name).stat().st_size > 1000 and f']({name})' in text
    assert not (out / 'compensated').exists()


def test_compare_one_table_and_unavailable_methods_reported(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(methods.BUILTIN_METHODS, 'ghost', ('gyro_noise_ros.thermal.ghost', 'G'))
    train, _, _ = _bag(tmp_path / 'train', 1)
    test, _, _ = _bag(tmp_path / 'test', 2)
    out = tmp_path / 'c'
    assert main(['compare', train, test, '--out', str(out), '--methods',
                 'toy_linear,toy_lowpass,ghost', *FAST]) == 0
    doc = json.loads((out / 'compare.json').read_text())
    assert set(doc['methods']) == {'toy_linear', 'toy_lowpass'}
    assert 'cannot be imported' in doc['errors']['ghost']
    assert doc['best_held_out']['method'] == 'toy_linear'
    rows = (out / 'compare.csv').read_text().splitlines()
    assert len(rows) == 1 + 3 * 3  # header, raw input and two methods, three axes each
    out = tmp_path / 'refused'  # the first run's folder is not empty (--overwrite)
    assert main(['compare', train, train, '--out', str(out)]) == 2
    assert 'same recording' in capsys.readouterr().err
    assert main(['compare', train, test, '--out', str(out), '--methods', 'ghost',
                 *FAST]) == 4


@pytest.mark.parametrize('case, code, message', [
    ('no_temperature', 3, 'no sensor_msgs/msg/Temperature topic'),
    ('constant', 4, 'constant at 20.000 degC'),
    ('narrow', 4, 'spans only 1 degC'),
    ('nan', 4, 'NaN/Inf angular velocity'),
    ('mismatched', 4, 'do not overlap'),
    ('method', 2, "unknown method 'nope'"),
    ('option', 2, ''),
])
def test_fit_refusals(tmp_path, capsys, case, code, message):
    kw = {'no_temperature': {'temperature_topic': None}, 'constant': {'lo': 20.0, 'hi': 20.0},
          'narrow': {'lo': 20.0, 'hi': 21.0}, 'nan': {'gyro_nan': True},
          'mismatched': {'temp_shift_s': 5000.0}}.get(case, {})
    bag, _, _ = _bag(tmp_path / 'b', 0, **kw)
    argv = ['fit', bag, '--out', str(tmp_path / 'o'), '--quiet',
            '--method', 'nope' if case == 'method' else 'toy_linear']
    if case == 'option':
        argv.append('--bogus')
    assert main(argv) == code
    err = capsys.readouterr().err
    assert message in err
    assert 'Traceback' not in err
    if message:
        assert len(err.strip().splitlines()) == 1 and err.startswith('gyro_noise_thermal: error:')


def test_apply_refuses_outside_trained_range(tmp_path, capsys):
    train, _, _ = _bag(tmp_path / 'train', 1, lo=20.0, hi=30.0)
    test, _, _ = _bag(tmp_path / 'test', 2, lo=10.0, hi=30.0)
    assert main(['fit', train, '--method', 'toy_linear', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    model = str(tmp_path / 'm' / 'model.json')
    assert main(['apply', test, '--model', model, '--out', str(tmp_path / 'a'), *FAST]) == 4
    assert 'leaves the model' in capsys.readouterr().err
    assert main(['apply', test, '--model', model, '--out', str(tmp_path / 'a'),
                 '--range-margin-c', '10', '--no-bag', *FAST]) == 0
    assert main(['apply', test, '--model', str(tmp_path / 'nope.json'), '--out',
                 str(tmp_path / 'b'), *FAST]) == 3


def test_fit_on_two_bags_joins_them(tmp_path):
    a, _, _ = _bag(tmp_path / 'a', 1, lo=10.0, hi=25.0)
    b, _, _ = _bag(tmp_path / 'b', 2, lo=25.0, hi=40.0)
    assert main(['fit', a, b, '--method', 'toy_linear', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    t = json.loads((tmp_path / 'm' / 'model.json').read_text())['training']
    assert t['samples'] == 2 * N and t['sources'] == [a, b]
    # the cosine profiles peak between two 1-s temperature samples
    assert t['temperature_min_c'] == 10.0
    assert t['temperature_max_c'] == pytest.approx(40.0, abs=1e-3)


def test_simulate_calls_the_simulator_lazily(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, 'gyro_noise_ros.thermal.simulate', None)
    assert main(['simulate', '--seed', '3', '--out', str(tmp_path)]) == 2
    assert 'simulator is not available' in capsys.readouterr().err
    monkeypatch.undo()
    argv = ['simulate', '--seed', '3', '--out', str(tmp_path / 's'), '--hours', '0.02',
            '--rate-hz', '20']
    assert main(argv) == 0
    assert capsys.readouterr().out.strip() == f'wrote {tmp_path / "s" / "train"}, ' \
        f'{tmp_path / "s" / "test"}'
    assert json.loads((tmp_path / 's' / 'simulation.json').read_text())['seed'] == 3


def test_mode_class_figure_from_method_diagnostics(tmp_path):
    from gyro_noise_ros.thermal.figures import plot_mode_classes

    info = [{'sample_entropy': [0.1, 0.9, 2.0], 'classes': ['drift', 'mixed', 'noise'],
             'center_freqs_hz': [0.001, 0.5, 8.0]}] * 3
    path = plot_mode_classes(tmp_path / 'f.png', info, title='t')
    assert path.stat().st_size > 1000
    assert plot_mode_classes(tmp_path / 'g.png', None, title='t') is None
    assert plot_mode_classes(tmp_path / 'g.png', [{'classes': ['noise']}] * 3, title='t') is None
    assert not (tmp_path / 'g.png').exists()


def _mpu6050_bags(tmp_path):
    """Write the real MPU6050 record's two halves as bags (gyro deg/s -> rad/s)."""
    from _realdata import real_data

    path = real_data('mpu6050_static_sunsided', 'mpu6050_static_10min.csv')
    data = np.loadtxt(path, delimiter=',', skiprows=1)
    half = data.shape[0] // 2
    out = []
    for name, part in (('first', data[:half]), ('second', data[half:])):
        t = part[:, 0] - data[0, 0]
        write_thermal_bag(tmp_path / name, t, np.radians(part[:, 1:4]), t, part[:, 7])
        out.append(str(tmp_path / name))
    return out, data


def test_real_mpu6050_narrow_temperature_is_refused_then_scored_on_halves(tmp_path, capsys):
    (first, second), data = _mpu6050_bags(tmp_path)
    # SOURCE.md: 25.14-25.61 degC over the whole record, far below the 2 degC a fit needs
    assert main(['fit', first, '--method', 'poly3', '--out', str(tmp_path / 'm'), '--quiet']) == 4
    err = capsys.readouterr().err
    assert 'spans only' in err and len(err.strip().splitlines()) == 1
    # poly3 itself refuses spans under 1 degC; a linear model is fitted to score the halves
    assert main(['fit', first, '--method', 'toy_linear', '--min-range-c', '0.1', '--out',
                 str(tmp_path / 'm'), '--quiet', '--no-figures']) == 0
    assert main(['apply', second, '--model', str(tmp_path / 'm' / 'model.json'), '--out',
                 str(tmp_path / 'a'), '--f-lo-hz', '0.5', '--no-bag', '--no-figures',
                 '--quiet']) == 0
    doc = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    # host stamps are bursty (median step 2 ms): the rate is the mean one, ~99.3 Hz (SOURCE.md)
    assert doc['rate_hz'] == pytest.approx(99.3, abs=0.3)
    # the raw ARW read through the bag equals the one of the CSV's own samples
    from gyro_noise_ros.thermal.metrics import noise_metrics

    second_half = np.radians(data[data.shape[0] // 2:, 1])
    expected = noise_metrics(second_half, doc['rate_hz']).arw_deg_sqrt_h
    assert doc['axes']['x']['raw']['arw_deg_sqrt_h'] == pytest.approx(expected, rel=1e-9)


def test_fitted_model_json_loads_in_the_live_compensator(tmp_path):
    from gyro_noise_ros.thermal.live import check_live_model, load_live_model

    train, _, _ = _bag(tmp_path / 'train', 1, lo=15.0, hi=35.0)
    assert main(['fit', train, '--method', 'toy_linear', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    method, range_c, margin = load_live_model(str(tmp_path / 'm' / 'model.json'))
    assert isinstance(method, LinearInT) and margin == methods.DEFAULT_RANGE_MARGIN_C
    assert range_c[0] == 15.0 and range_c[1] == pytest.approx(35.0, abs=1e-3)
    check_live_model(method, range_c=range_c, margin_c=margin)


@pytest.mark.parametrize('value', ['nan', '-5', 'inf'])
def test_min_range_must_be_finite_and_non_negative(tmp_path, capsys, value):
    bag, _, _ = _bag(tmp_path / 'b', 0)
    for argv in (['fit', bag], ['compare', bag, '--split-at', '0.5']):
        assert main([*argv, '--out', str(tmp_path / 'o'), '--quiet',
                     f'--min-range-c={value}']) == 2
        err = capsys.readouterr().err
        assert '--min-range-c must be a finite temperature span' in err
        assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / 'o').exists()


def test_compare_refuses_an_unknown_method_before_any_work(tmp_path, capsys):
    train, _, _ = _bag(tmp_path / 'train', 1)
    test, _, _ = _bag(tmp_path / 'test', 2)
    assert main(['compare', train, test, '--out', str(tmp_path / 'c'), '--methods',
                 'poly3,nosuch', *FAST]) == 2
    err = capsys.readouterr().err
    assert "unknown method(s) 'nosuch' in --methods" in err and len(err.splitlines()) == 1
    assert not (tmp_path / 'c').exists()


def test_training_shorter_than_the_rate_windows_is_refused(tmp_path, capsys):
    # 15 s of training spanning 30 degC: enough span, too short to see dT
    bag, _, _ = _bag(tmp_path / 'b', 0, n=int(15 * RATE))
    assert main(['fit', bag, '--method', 'linear_tdt', '--out', str(tmp_path / 'o'),
                 '--quiet']) == 4
    err = capsys.readouterr().err
    assert 'needs at least 20 s' in err and len(err.strip().splitlines()) == 1
    assert main(['fit', bag, '--method', 'poly3', '--out', str(tmp_path / 'p'),
                 '--quiet', '--no-figures']) == 0


def _fit_poly3(tmp_path, **kw):
    train, _, _ = _bag(tmp_path / 'train', 1, **kw)
    assert main(['fit', train, '--method', 'poly3', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    return tmp_path / 'm' / 'model.json'


def test_other_version_loads_with_a_note_and_empty_parameters_fail(tmp_path, capsys):
    model = _fit_poly3(tmp_path)
    test, _, _ = _bag(tmp_path / 'test', 2)
    doc = json.loads(model.read_text())
    doc['package_version'] = '9.9.9'
    (tmp_path / 'old.json').write_text(json.dumps(doc))
    assert main(['apply', test, '--model', str(tmp_path / 'old.json'), '--out',
                 str(tmp_path / 'a'), '--no-bag', '--f-lo-hz', '0.5', '--no-figures']) == 0
    err = capsys.readouterr().err
    assert 'note: model file' in err and 'gyro_noise_ros 9.9.9' in err
    metrics = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    assert metrics['model']['package_version'] == '9.9.9'
    assert any('9.9.9' in n for n in metrics['notes'])
    doc['parameters'] = {}
    (tmp_path / 'empty.json').write_text(json.dumps(doc))
    assert main(['apply', test, '--model', str(tmp_path / 'empty.json'), '--out',
                 str(tmp_path / 'b'), *FAST]) == 3
    err = capsys.readouterr().err
    assert 'has no fitted parameters' in err and len(err.strip().splitlines()) == 1


def test_test_run_too_short_for_the_injection_is_exit_4(tmp_path, capsys):
    model = _fit_poly3(tmp_path)
    short, _, _ = _bag(tmp_path / 'short', 2, n=int(200 * RATE))
    # the default chirp starts at 0.1 Hz and needs 666.7 s of run
    assert main(['apply', short, '--model', str(model), '--out', str(tmp_path / 'a'),
                 '--quiet']) == 4
    err = capsys.readouterr().err
    assert 'needs 666.7 s (raise --f-lo-hz' in err and len(err.strip().splitlines()) == 1


def test_apply_reports_the_share_outside_the_trained_range(tmp_path):
    model = _fit_poly3(tmp_path, lo=20.0, hi=30.0)
    test, _, _ = _bag(tmp_path / 'test', 2, lo=18.0, hi=30.0)
    assert main(['apply', test, '--model', str(model), '--out', str(tmp_path / 'a'),
                 *FAST]) == 0
    doc = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    rng = doc['range']
    assert rng['temperature_below'] > 0 and rng['temperature_above'] == 0
    assert rng['outside'] >= rng['temperature_below']
    assert rng['fraction_outside'] == pytest.approx(rng['outside'] / rng['samples'])
    assert 'held at its value at the nearest end' in rng['treatment']
    text = (tmp_path / 'a' / 'report.md').read_text()
    assert f'{rng["outside"]} of {rng["samples"]} samples' in text


def test_accelerometer_is_compensated_beside_the_gyro(tmp_path):
    model = _fit_poly3(tmp_path)
    doc = json.loads(model.read_text())
    assert doc['accel']['relative_to_t_ref'] and doc['accel']['parameters']['relative']
    test, _, temp = _bag(tmp_path / 'test', 2)
    assert main(['apply', test, '--model', str(model), '--out', str(tmp_path / 'a'),
                 *FAST]) == 0
    from gyro_noise_ros.thermal.baselines import TemperaturePolynomial

    poly = TemperaturePolynomial.from_dict(doc['accel']['parameters'])
    with ImuBagReader(tmp_path / 'a' / 'compensated') as r:
        batch = next(r.iter_batches(100_000))
    with ImuBagReader(test) as r:
        raw = next(r.iter_batches(100_000)).accel
    np.testing.assert_allclose(batch.accel, raw - poly.drift_rad_s(temp, 0.0), atol=1e-12)
    metrics = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    assert set(metrics['accel']['axes']) == {'x', 'y', 'z'}


def test_export_writes_px4_and_ardupilot_files(tmp_path, capsys):
    model = _fit_poly3(tmp_path)
    out = tmp_path / 'e'
    assert main(['export', '--model', str(model), '--out', str(out), '--px4-gyro-id',
                 '123', '--px4-accel-id', '2359306', '--quiet']) == 0
    params = (out / 'thermal_px4.params').read_text()
    assert '1\t1\tTC_G0_ID\t123\t6' in params and 'TC_A0_X3_2' in params
    assert '1\t1\tTC_G_ENABLE\t1\t6' in params and '1\t1\tTC_A_ENABLE\t1\t6' in params
    parm = (out / 'thermal_ardupilot.parm').read_text()
    assert 'INS_TCAL1_ENABLE 1' in parm and 'INS_TCAL1_GYR3_Z' in parm
    doc = json.loads((out / 'export.json').read_text())
    assert doc['px4']['TC_G0_ID'] == 123 and doc['accelerometer']
    assert doc['px4_devices']['gyro']['bus_type'] == 'UAVCAN'   # 123 = 0x7B: bus type 3
    assert doc['exported'] == {'method': 'poly3', 'form': 'poly3', 'axes': 'x,y,z',
                               'source': 'the model'}
    # the training bag is still there: each firmware's residual on it
    (pred,) = doc['predicted']
    assert pred['role'] == 'training' and set(pred['residual_deg_s']) == {
        'raw', 'model', 'px4', 'ardupilot'}
    # a method with a dT term exports the poly3 fitted beside it, and says so; without a device
    # id the PX4 blocks are written disabled, with a warning each
    train, _, _ = _bag(tmp_path / 'train2', 1)
    assert main(['fit', train, '--method', 'linear_tdt', '--out', str(tmp_path / 'l'),
                 '--quiet', '--no-figures']) == 0
    capsys.readouterr()
    assert main(['export', '--model', str(tmp_path / 'l' / 'model.json'), '--out',
                 str(tmp_path / 'f'), '--axes=-y,x,z', '--predict', train]) == 0
    out_err = capsys.readouterr()
    assert 'exported: the poly3 fitted beside linear_tdt' in out_err.err
    assert 'no --px4-gyro-id: the PX4 gyro block is written with TC_G_ENABLE 0' in out_err.err
    assert 'as PX4 applies it' in out_err.out and '(predict)' in out_err.out
    params = (tmp_path / 'f' / 'thermal_px4.params').read_text()
    assert '1\t1\tTC_G_ENABLE\t0\t6' in params and '1\t1\tTC_G0_ID\t0\t6' in params
    doc = json.loads((tmp_path / 'f' / 'export.json').read_text())
    assert doc['exported']['source'] == 'the poly3 fitted beside it' and len(doc['warnings']) == 2
    # the autopilot's X is the recording's -y (coef_rad_s: per axis, lowest power first)
    coef = json.loads((tmp_path / 'l' / 'model.json').read_text())['autopilot']['parameters'][
        'coef_rad_s']
    assert doc['px4']['TC_G0_X1_0'] == pytest.approx(-coef[1][1], rel=1e-12)
    assert doc['px4']['TC_G0_X1_1'] == pytest.approx(coef[0][1], rel=1e-12)
    # the default on a drift in T alone chooses a polynomial in T (fit says which terms):
    # exported as it is
    capsys.readouterr()
    assert main(['fit', train, '--out', str(tmp_path / 'd'), '--no-figures']) == 0
    terms = json.loads((tmp_path / 'd' / 'model.json').read_text())['parameters']['terms']
    assert 'r' not in terms
    assert f'lsq_cv [terms {" ".join(terms)}, by blocked CV]' in capsys.readouterr().out
    assert main(['export', '--model', str(tmp_path / 'd' / 'model.json'), '--out',
                 str(tmp_path / 'g'), '--px4-gyro-id', '2359306']) == 0
    assert 'exported: lsq_cv itself' in capsys.readouterr().err


@pytest.mark.parametrize('option, value, message', [
    ('--px4-gyro-id', '99999999999', '24 bits'), ('--px4-gyro-id', '-1', '24 bits'),
    ('--px4-instance', '4', 'instance must be 0..3'),
    ('--axes', 'x,x,z', 'error: --axes must name x, y and z')])
def test_export_refuses_bad_ids_and_axes(tmp_path, capsys, option, value, message):
    model = _fit_poly3(tmp_path)
    assert main(['export', '--model', str(model), '--out', str(tmp_path / 'e'), option,
                 value]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / 'e').exists()


def test_export_of_a_format_2_model_of_another_method_is_refused(tmp_path, capsys):
    train, _, _ = _bag(tmp_path / 'train', 1)
    assert main(['fit', train, '--method', 'toy_linear', '--out', str(tmp_path / 'l'),
                 '--quiet', '--no-figures']) == 0
    path = tmp_path / 'l' / 'model.json'
    doc = json.loads(path.read_text())
    doc['format_version'], doc['autopilot'] = 2, None
    path.write_text(json.dumps(doc))
    assert main(['export', '--model', str(path), '--out', str(tmp_path / 'f')]) == 2
    assert 'carries no poly3 for the autopilots' in capsys.readouterr().err


def test_an_interrupted_fit_leaves_no_model(tmp_path, monkeypatch):
    from gyro_noise_ros.thermal import figures

    train, _, _ = _bag(tmp_path / 'train', 1)

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(figures, 'plot_run', stop)
    assert main(['fit', train, '--method', 'poly3', '--out', str(tmp_path / 'm'),
                 '--quiet']) == 130
    assert not (tmp_path / 'm').exists()  # the folder the run made went with it


def test_simulate_shapes_and_compare_against_the_noise_floor(tmp_path, capsys):
    out = tmp_path / 's'
    assert main(['simulate', '--seed', '2', '--out', str(out), '--shape', 'heating',
                 '--test-shape', 'cooling', '--hours', '0.25', '--rate-hz', '10']) == 0
    settings = json.loads((out / 'simulation.json').read_text())
    assert settings['profile']['shape'] == 'heating'
    assert settings['test_profile']['shape'] == 'cooling'
    capsys.readouterr()
    assert main(['compare', str(out / 'train'), str(out / 'test'), '--out',
                 str(tmp_path / 'c'), '--methods', 'poly3,lsq_cv', '--f-lo-hz', '0.5',
                 '--no-figures']) == 0
    printed = capsys.readouterr()
    assert '(oracle: true terms)' in printed.out and 'x noise floor' in printed.out
    doc = json.loads((tmp_path / 'c' / 'compare.json').read_text())
    # bags of simulate: the floor is the test run's own noise, from its truth file
    truth = np.load(out / 'test_truth.npz')
    floor = residual_drift_deg_s(truth['noise_rad_s'], doc['test_rate_hz'])
    assert doc['floor']['kind'] == 'noise'
    np.testing.assert_allclose(doc['floor']['deg_s'], floor, rtol=1e-9)
    poly3 = [v['processed']['residual_drift_deg_s'] for v in doc['methods']['poly3']['axes']
             .values()]
    for name in ('poly3', 'lsq_cv'):
        m = doc['methods'][name]
        drift = np.array([v['processed']['residual_drift_deg_s'] for v in m['axes'].values()])
        np.testing.assert_allclose(m['yardstick']['over_floor'], drift / floor, rtol=1e-9)
        np.testing.assert_allclose(m['yardstick']['over_poly3'], drift / poly3, rtol=1e-9)
        # heating-trained, cooling-tested: nearly every test rate is below the trained range,
        # more than the 5 % that passes without a warning
        assert m['range']['rate_below'] > 0.5 * m['range']['samples'] or name == 'poly3'
    assert any(w.startswith('lsq_cv: ') for w in doc['warnings'])
    assert 'warning: lsq_cv: ' in printed.err
    # the ranking orders the methods by their mean ratio to the floor
    ranks = [r['mean_over_floor'] for r in doc['ranking']]
    assert ranks == sorted(ranks) and {r['method'] for r in doc['ranking']} == {'poly3', 'lsq_cv'}
    assert '## Ranking' in (tmp_path / 'c' / 'compare.md').read_text()


def test_implausible_temperatures_are_dropped_and_said(tmp_path, capsys):
    # the cases in a 10..40 degC run of 301 readings: a 0x7FFF word (153.0 degC) and a
    # 1e6 degC reading are dropped (0.66 %), counted and said; the trained range is the run's
    saturated = 25.0 + 32767.0 / 256.0
    train, _, _ = _bag(tmp_path / 'train', 1, glitches={100: saturated, 200: 1e6})
    assert main(['fit', train, '--method', 'poly3', '--out', str(tmp_path / 'm'),
                 '--no-figures']) == 0
    err = capsys.readouterr().err
    assert '2 of 301 temperature readings (0.664 %) implausible' in err
    assert 'the first at 100.000 s (152.996 degC)' in err
    model = json.loads((tmp_path / 'm' / 'model.json').read_text())
    assert model['training']['temperature_max_c'] < 40.01
    training = json.loads((tmp_path / 'm' / 'training.json').read_text())
    assert training['bags'][0]['temperature_dropped'] == 2
    assert any('implausible' in n for n in training['notes'])
    # four of them (1.3 %): refused, naming the first
    bad, _, _ = _bag(tmp_path / 'bad', 1, glitches=dict.fromkeys((50, 100, 150, 200), 100.0))
    assert main(['fit', bad, '--out', str(tmp_path / 'n'), '--quiet']) == 4
    err = capsys.readouterr().err
    assert 'the first at 50.000 s (100 degC); more than 1 %' in err
    assert len(err.strip().splitlines()) == 1
    # a stream in kelvin: converted, with a note
    kelvin, _, _ = _bag(tmp_path / 'kelvin', 1, kelvin=True)
    assert main(['fit', kelvin, '--method', 'poly3', '--out', str(tmp_path / 'k'),
                 '--no-figures']) == 0
    assert 'warning: temperature topic' in capsys.readouterr().err   # kelvin, not degC
    model = json.loads((tmp_path / 'k' / 'model.json').read_text())
    assert 9.99 < model['training']['temperature_min_c'] < 10.01


def test_apply_warns_above_the_share_outside_and_refuses_under_strict(tmp_path, capsys):
    # a test run twice as fast: the same temperatures, dT beyond the trained range most of the
    # time, more than the 5 % applied without a warning, for a model using dT (linear_tdt keeps
    # its dT term on this run); poly3 evaluates T alone, which stays inside: no warning
    train, _, _ = _bag(tmp_path / 'train', 1)
    test, _, _ = _bag(tmp_path / 'test', 2, n=N // 2)
    assert main(['fit', train, '--method', 'poly3', '--out', str(tmp_path / 'p'), '--quiet',
                 '--no-figures']) == 0
    assert main(['apply', test, '--model', str(tmp_path / 'p' / 'model.json'), '--out',
                 str(tmp_path / 'p3'), '--strict', '--no-bag', *FAST]) == 0
    doc = json.loads((tmp_path / 'p3' / 'metrics.json').read_text())
    assert doc['range']['rate_below'] + doc['range']['rate_above'] == 0 and not doc['warnings']
    assert main(['fit', train, '--method', 'linear_tdt', '--out', str(tmp_path / 'm'),
                 '--quiet', '--no-figures']) == 0
    model = str(tmp_path / 'm' / 'model.json')
    assert main(['apply', test, '--model', model, '--out', str(tmp_path / 'a'), '--no-bag',
                 '--f-lo-hz', '0.5', '--no-figures', '--no-html']) == 0
    err = capsys.readouterr().err
    assert 'warning: ' in err and 'of the run lies outside the trained range of T or dT' in err
    doc = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    assert doc['range']['fraction_outside'] > 0.05 and len(doc['warnings']) == 1
    assert 'Warning:' in (tmp_path / 'a' / 'report.md').read_text()
    assert main(['apply', test, '--model', model, '--out', str(tmp_path / 's'), '--strict',
                 *FAST]) == 4
    err = capsys.readouterr().err
    assert err.startswith('gyro_noise_thermal: error: --strict: ')
    assert not (tmp_path / 's').exists()


def test_apply_refuses_a_model_of_another_sensor_and_a_sparse_temperature(tmp_path, capsys):
    train, _, _ = _bag(tmp_path / 'train', 1)
    assert main(['fit', train, '--out', str(tmp_path / 'm'), '--quiet', '--no-figures']) == 0
    model = str(tmp_path / 'm' / 'model.json')
    # another part: its zero-rate level 0.5 deg/s off on x
    other, _, _ = _bag(tmp_path / 'other', 2, offset_rad_s=np.radians(0.5))
    assert main(['apply', other, '--model', model, '--out', str(tmp_path / 'a'), *FAST]) == 4
    err = capsys.readouterr().err
    assert 'x +0.5' in err and 'another sensor' in err and len(err.strip().splitlines()) == 1
    assert '(--max-offset-deg-s inf applies it anyway)' in err
    assert main(['apply', other, '--model', model, '--out', str(tmp_path / 'a'), '--no-bag',
                 '--max-offset-deg-s', 'inf', *FAST]) == 0
    # the temperature read every 5 s: too sparse for the 10-s rate window of a model using dT
    # (lsq_cv dropped dT on this run, whose drift has none: linear_tdt keeps it)
    assert main(['fit', train, '--method', 'linear_tdt', '--out', str(tmp_path / 'l'),
                 '--quiet', '--no-figures']) == 0
    sparse, _, _ = _bag(tmp_path / 'sparse', 2, temp_period_s=5.0)
    assert main(['apply', sparse, '--model', str(tmp_path / 'l' / 'model.json'), '--out',
                 str(tmp_path / 'b'), *FAST]) == 4
    assert 'read every 5 s (0.2 Hz)' in capsys.readouterr().err
    assert main(['fit', sparse, '--out', str(tmp_path / 'f'), '--quiet']) == 4
    assert 'at least 4 readings' in capsys.readouterr().err
