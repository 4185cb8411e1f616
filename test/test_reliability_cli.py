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
gyro_noise_reliability end to end on simulated bags, and its bad-input paths.

The static records come from the scenario model (white + flicker + random walk, IEEE 952); the
expected interval comes from the closed-form ADEV of the same model. Widths of single axes
scatter (the paper's reason for the +/-50 % band), so the stress test reads the mean over three
axes, as the paper does (420 s -> 945 s "average among the three axes").
"""

import json

from _reliability_common import six_position_record, static_record, write_bag
from gyro_noise_ros.calibration.emulate import BiasVariation, SensorErrors
from gyro_noise_ros.calibration.reliability_report import in_short
from gyro_noise_ros.calibration.static_record import CHANNELS, StaticRecord
from gyro_noise_ros.cli.reliability import main
from gyro_noise_ros.core.allan import allan_deviation
import numpy as np
import pytest

RATE = 10.0
N_ACC = 0.02 / np.sqrt(RATE)          # white noise density of the records (per sqrt(Hz))
N_GYR = 2e-3 / np.sqrt(RATE)
# plateau half the white ADEV at 1 s, random walk a fifth: interval ~0.6 s .. ~125 s (closed form)
ERRORS = SensorErrors(accel_bias_instability_m_s2=N_ACC / 2 / 0.664,
                      accel_random_walk_m_s2_sqrt_s=N_ACC / 5,
                      gyro_bias_instability_rad_s=N_GYR / 2 / 0.664,
                      gyro_random_walk_rad_s_sqrt_s=N_GYR / 5)
#: These records' bias walks (K = N/5 at 10 Hz: ~15 N over 12,000 s) wander more than the
#: static-segment rule's 3 window-noise levels, which cuts such a drift as motion (core/segments;
#: docs/reliability.md, limitations): the tests of the analysis read every sample.
WHOLE = ('--static', 'off')
KEYS = {'before_s', 'after_s', 'width_before_s', 'width_after_s', 'change', 'verdict'}


def test_flicker_generator_gives_the_ieee952_plateau():
    rng = np.random.default_rng(7)
    x = BiasVariation(1.0, 0.0, RATE, rng).generate(int(RATE * 40000))
    plateau = []
    for ax in range(3):
        res = allan_deviation(x[:, ax], RATE, taus='dense')
        sel = (res.tau_s > 1.0) & (res.tau_s < 200.0)
        plateau.append(res.adev[sel].mean())
    # sqrt(2 ln2 / pi) B = 0.664 B; the mean of 3 axes over 1..200 s scatters by a few % (EDF
    # > 100 per tau there), and the Gauss-Markov sum ripples by ~2 %: 8 % is a safe band
    assert np.mean(plateau) == pytest.approx(0.664, rel=0.08)


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    root = tmp_path_factory.mktemp('rel')
    out = {}
    for name, errors, seed in (('before', ERRORS, 1), ('after', ERRORS.stressed(
            instability_factor=2.0), 2), ('same', ERRORS, 3)):
        # the before record carries a 25 -> 26 degC ramp (sensor_msgs/Temperature at 1 Hz)
        temp = (lambda t: 25.0 + t / 12000.0) if name == 'before' else None
        out[name] = str(write_bag(root / f'{name}_static', *static_record(
            errors=errors, rate_hz=RATE, duration_s=12000.0, seed=seed), temperature_degc=temp))
    out['cal_before'] = str(write_bag(root / 'cal_before', *six_position_record(
        dwell_s=20.0, seed=4), temperature_degc=lambda t: 30.0 + 0.01 * t))
    out['cal_after'] = str(write_bag(root / 'cal_after', *six_position_record(
        dwell_s=20.0, seed=5, errors=SensorErrors().stressed())))
    return out


@pytest.mark.slow  # the whole before/after procedure with figures and report.html (5-10 s)
def test_full_procedure(tmp_path, bags, capsys):
    out = tmp_path / 'rep'
    assert main(['--before-calibration', bags['cal_before'], '--before-static', bags['before'],
                 '--after-calibration', bags['cal_after'], '--after-static', bags['after'],
                 '--gravity', '9.80665', *WHOLE, '--out', str(out)]) == 0
    doc = json.loads((out / 'reliability.json').read_text())
    assert doc['c'] == 2.0 and doc['tolerance'] == 0.3 and doc['alpha'] == 0.05
    assert doc['taus_s'] == [1.0, 10.0, 30.0] and doc['interval_tolerance'] == 0.5
    # the verdict: the flicker level x2 moves the ADEV at 10-100 s by x1.6-1.9 (closed form of
    # this model), far beyond +/-30 % at 12,000 s; every test is in the document
    for sensor in ('accel', 'gyro'):
        o = doc['overall'][sensor]
        assert o['verdict'] == 'beyond' and 'beyond +/-30 %' in o['sentence'], o
        assert o['tests'] == 9 and o['decisive']['ratio'] > 1.3
        assert o['decisive']['ci'][0] > 1.3
    for ch in CHANNELS:
        assert [t['tau_s'] for t in doc['noise_change'][ch]] == [1.0, 10.0, 30.0]
    assert set(doc['bias_instability_interval']) == set(CHANNELS)
    for entry in doc['bias_instability_interval'].values():
        assert set(entry) >= KEYS
        # closed form of this model: ~0.6 .. 125 s before (scatter of single records ~+/-30 %)
        lo, hi = entry['before_s']
        assert 0.4 < lo < 1.2 and 60.0 < hi < 250.0
        if entry['change'] is not None:
            # every width and change carries its uncertainty and its 90 % interval
            assert entry['width_sigma_before_s'] > 0 and entry['change_sd'] > 0
            assert entry['ci'][0] < entry['change'] < entry['ci'][1]
            assert entry['verdict'] in ('beyond', 'physiological', 'undetermined')
            if entry['verdict'] == 'undetermined':
                assert len(entry['decide_record_s']) == 2
                assert min(entry['decide_record_s']) > 12000.0
    # stress x2 on the flicker level: closed form +135 %; the three-axis mean must be beyond 50 %
    for sensor in ('accel', 'gyro'):
        assert doc['summary'][sensor]['mean_change'] > 0.5
        o = doc['interval_indicator'][sensor]
        # a widening: never called physiological; beyond or undetermined with its basis
        assert o['verdict'] in ('beyond', 'undetermined') and o['basis']
        assert o['mean_change'] > 0.5 and o['mean_change_sd'] > 0
    # the noise terms: the one readout's numbers, each with a 68 % bracket that holds it
    for ch, e in doc['noise_terms'].items():
        for side in ('before', 'after'):
            for key, value in e[side].items():
                if key.endswith('_ci68'):
                    lo, hi = value
                    v = e[side][key[:-5]]
                    assert lo <= v and (hi is None or v <= hi), (ch, key)
        assert e['ratio_after_before']
    # uniformity: paper 0.252 -> 2.955 mg carried by the simulated calibrations (4 sigma ~0.2 mg)
    ub = doc['uniformity']['before']['accel_bias_std_m_s2'] / 9.80665e-3
    ua = doc['uniformity']['after']['accel_bias_std_m_s2'] / 9.80665e-3
    assert ub == pytest.approx(0.252, abs=0.2) and ua == pytest.approx(2.955, abs=0.2)
    assert doc['calibration']['before']['accel']['misalignment'] is not None
    # Table 6 before/after with the change and its standard uncertainty (mg, %)
    rows = {r['parameter']: r for r in doc['table6']}
    assert set(rows) == {'bx', 'by', 'bz', 'Sx', 'Sy', 'Sz'}
    by = rows['by']
    assert by['unit'] == 'mg' and by['change'] == pytest.approx(by['after'] - by['before'])
    assert by['change_sigma'] == pytest.approx(np.hypot(by['before_sigma'], by['after_sigma']))
    # paper Table 6: by -4.4 -> -8.3 mg; the calibrations recover it within 0.3 mg
    assert by['change'] == pytest.approx(-3.9, abs=0.3)
    g = doc['gyro_calibration']
    assert len(g['before']['bias_rad_s']) == 3 and len(g['bias_change_sigma_rad_s']) == 3
    assert doc['accel_cross_axis']['after']['misalignment_sigma'] is not None
    gc = doc['gravity_check']['after']
    assert gc['consistent'] and {'mean_norm_raw_m_s2', 'loo_mean_norm_m_s2'} <= set(gc)
    # temperatures: the before record's ramp 25 -> 26 degC, the before dwells at 30 degC + ramp
    tb = doc['static_records']['before']['temperature']
    assert tb['mean_degc'] == pytest.approx(25.5, abs=0.01) and tb['max_degc'] < 26.0
    assert doc['static_records']['after']['temperature'] is None      # not recorded
    dwells = doc['dwell_temperatures']['before']
    assert len(dwells) == 6
    for d in dwells:
        mid = d['t_start_s'] + d['duration_s'] / 2
        assert d['temperature']['mean_degc'] == pytest.approx(30.0 + 0.01 * mid, abs=0.01)
    assert all(d['temperature'] is None for d in doc['dwell_temperatures']['after'])
    for f in ('reliability.md', 'fig6_accel.png', 'fig6_gyro.png', 'before/calibration.yaml',
              'after/calibration.json', 'adev_before.csv', 'adev_after.csv'):
        assert (out / f).exists(), f
    # the curves behind Figure 6: tau_s and, per channel, ADEV, its interval and EDF, in SI
    lines = (out / 'adev_before.csv').read_text().splitlines()
    head = lines[0].split(',')
    assert head[0] == 'tau_s' and 'accel_x_adev_m_s2' in head and 'gyro_z_ci_high_rad_s' in head
    assert len(head) == 1 + 6 * 4 and len(lines) > 30
    row = dict(zip(head, map(float, lines[1].split(','))))
    assert row['gyro_x_ci_low_rad_s'] < row['gyro_x_adev_rad_s'] < row['gyro_x_ci_high_rad_s']
    md = (out / 'reliability.md').read_text()
    # the verdict first: the plain-language summary, then the overall verdict, then evidence
    assert md.index('## In short') < md.index('## Verdict: the noise at fixed') < md.index(
        '## Indicator: the bias-instability interval') < md.index('Table 6')
    assert '| gyro_z | 30 |' in md
    assert '| accel_x |' in md or '| accel_x (ambiguous) |' in md
    assert '(m/s^2) |' in md and 'degC' in md and '| by (mg) |' in md
    assert in_short(doc)[0].startswith('The accelerometer noise at')
    assert capsys.readouterr().out.count('accel:') == 1


def test_same_sensor_twice_is_never_beyond(tmp_path, bags):
    out = tmp_path / 'rep'
    assert main(['--before-static', bags['before'], '--after-static', bags['same'],
                 '--no-figures', *WHOLE, '--out', str(out)]) == 0
    doc = json.loads((out / 'reliability.json').read_text())
    for sensor in ('accel', 'gyro'):
        assert doc['overall'][sensor]['verdict'] != 'beyond'
    assert all(t['verdict'] != 'beyond' for tests in doc['noise_change'].values()
               for t in tests)
    assert all(e['verdict'] != 'beyond' for e in doc['bias_instability_interval'].values())
    assert doc['calibration'] == {'before': None, 'after': None} and doc['table6'] is None
    md = (out / 'reliability.md').read_text()
    assert 'Table 6' not in md and not (out / 'fig6_accel.png').exists()


def test_bad_channels_are_undetermined_with_the_reason(tmp_path, bags, capsys):
    # 1200 s: long enough for the verdict's longest tau (100 s x 10 averages)
    t, accel, gyro = static_record(errors=ERRORS, rate_hz=RATE, duration_s=1200.0, seed=9)
    accel_nan = accel.copy()
    accel_nan[100, 1] = np.nan
    nan_bag = write_bag(tmp_path / 'nan', t, accel_nan, gyro)
    zero_bag = write_bag(tmp_path / 'zero', t, np.zeros_like(accel), gyro)
    out = tmp_path / 'rep'
    assert main(['--before-static', str(nan_bag), '--after-static', str(zero_bag),
                 '--no-figures', *WHOLE, '--out', str(out)]) == 0
    doc = json.loads((out / 'reliability.json').read_text())
    iv = doc['bias_instability_interval']
    assert iv['accel_y']['verdict'] == 'undetermined' and 'NaN' in iv['accel_y']['reason']
    assert iv['accel_y']['change'] is None and iv['accel_y']['width_before_s'] is None
    assert 'accelerometer reads ~0' in iv['accel_x']['reason_after']
    # the same gyro samples in both records: no change, but 1200 s cannot decide +/-50 % of
    # the interval; the verdict at fixed taus: ratio 1 everywhere, within where the EDF allows
    g = iv['gyro_x']
    assert g['change'] == 0.0 and g['verdict'] == 'undetermined'
    assert 'open' in g['reason'] or 'times as long would decide' in g['reason']
    assert all(t['ratio'] == 1.0 for t in doc['noise_change']['gyro_x'])
    assert doc['overall']['gyro']['verdict'] in ('within', 'undetermined')
    assert doc['overall']['accel']['verdict'] == 'undetermined'
    assert 'accel_y: NaN/Inf' in doc['overall']['accel']['reason']
    # said on stderr too, one line per channel that cannot be judged
    err = capsys.readouterr().err
    assert 'before static record, accel_y: NaN/Inf samples in the record (first at sample 100)' \
        in err and 'Traceback' not in err


def test_unusable_static_records_are_refused_with_one_line(tmp_path, bags, capsys):
    # a 20 s record, a constant one and a six-position record given as static: not six
    # "undetermined" channels and exit 0, but one line naming the record and exit 4
    t, accel, gyro = static_record(errors=ERRORS, rate_hz=RATE, duration_s=600.0, seed=9)
    short = write_bag(tmp_path / 'short', t[t < 20.0], accel[t < 20.0], gyro[t < 20.0])
    const = write_bag(tmp_path / 'const', t, np.tile([0.0, 0.0, 9.8], (t.size, 1)),
                      np.zeros_like(gyro))
    moving = write_bag(tmp_path / 'moving', *six_position_record(dwell_s=20.0, seed=8))
    for bag, why in ((short, 'record too short'), (const, 'constant'),
                     (moving, 'record is not static')):
        capsys.readouterr()
        out = tmp_path / f'rep_{bag.name}'
        assert main(['--before-static', bags['before'], '--after-static', str(bag),
                     '--no-figures', *WHOLE, '--out', str(out)]) == 4, why
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and why in err and str(bag) in err, err
        assert not (out / 'reliability.json').exists()


def test_records_that_are_not_one_sensor_at_one_rate_are_refused(tmp_path, capsys):
    # before at 10 Hz, after at 20 Hz; then the same rate from another sensor frame: one line,
    # exit 4, nothing written
    rec = static_record(errors=ERRORS, rate_hz=RATE, duration_s=1200.0, seed=21)
    before = write_bag(tmp_path / 'before', *rec)
    fast = write_bag(tmp_path / 'fast', *static_record(errors=ERRORS, rate_hz=2 * RATE,
                                                       duration_s=1200.0, seed=22))
    other = write_bag(tmp_path / 'other', *rec, frame_id='adis_link')
    for bag, why in ((fast, 'differ in sample rate (10 Hz before, 20 Hz after)'),
                     (other, "different sensor frames ('imu_link' before, 'adis_link' after)")):
        out = tmp_path / f'rep_{bag.name}'
        capsys.readouterr()
        assert main(['--before-static', str(before), '--after-static', str(bag),
                     '--no-figures', *WHOLE, '--out', str(out)]) == 4
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and why in err, err
        assert not out.exists() or not any(out.iterdir())     # nothing written


def test_a_record_too_short_for_the_longest_tau_is_refused_naming_its_length(tmp_path, capsys):
    # 200 s at 10 Hz: the verdict's 30 s needs 10 averages, 300 s; taus up to 20 s would do
    t, accel, gyro = static_record(errors=ERRORS, rate_hz=RATE, duration_s=200.0, seed=23)
    bag = write_bag(tmp_path / 'short', t, accel, gyro)
    out = tmp_path / 'rep'
    assert main(['--before-static', str(bag), '--after-static', str(bag), '--no-figures',
                 *WHOLE, '--out', str(out)]) == 4
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'record too short for the noise verdict: 200 s' in err
    assert 'needs 300 s' in err and not (out.exists() and any(out.iterdir()))
    assert main(['--before-static', str(bag), '--after-static', str(bag), '--taus', '1', '10',
                 '20', '--no-figures', *WHOLE, '--out', str(out)]) == 0


def test_a_knock_is_cut_as_analyze_cuts_it_and_said(tmp_path, capsys):
    # white noise only (no drift for the rule to mistake), 1500 s at 10 Hz; after: the same
    # sensor knocked at t = 500-502 s (gyro_x +0.3 rad/s = 17 deg/s, as ADIS16405 run 4 at
    # 4046 s). The rule of gyro_noise_analyze cuts 500-502 s and the shorter run before it; the
    # 998 s left hold the 300 s the 30 s tau needs. Analysed whole, the knock is "noise": x5 at
    # 10 s on gyro_x (0.3 rad/s x 2 s / 10 s against a white ADEV of 2e-3/sqrt(10) rad/s)
    t, accel, gyro = static_record(errors=SensorErrors(), rate_hz=RATE, duration_s=1500.0,
                                   seed=31)
    before = write_bag(tmp_path / 'before', t, accel, gyro)
    _, accel2, gyro2 = static_record(errors=SensorErrors(), rate_hz=RATE, duration_s=1500.0,
                                     seed=32)
    gyro2[(t >= 500.0) & (t < 502.0), 0] += 0.3
    after = write_bag(tmp_path / 'after', t, accel2, gyro2)
    args = ['--before-static', str(before), '--after-static', str(after), '--no-figures']
    assert main([*args, '--out', str(tmp_path / 'cut')]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if 'static record' in line]
    assert len(said) == 1 and said[0].startswith('after static record: 5020 of 15000 samples '
                                                 'left out') and '500.0-502.0 s' in said[0]
    doc = json.loads((tmp_path / 'cut' / 'reliability.json').read_text())
    left = doc['static_records']['after']['left_out']
    assert left['motion'] == 5020 and left['static_segment_s'] == [502.0, pytest.approx(1499.9)]
    assert {'start_s': 500.0, 'end_s': 502.0, 'reason': 'motion'} in left['cut_s']
    assert doc['static_records']['before']['left_out'] == {'motion': 0}
    assert doc['overall']['gyro']['verdict'] != 'beyond'
    assert in_short(doc)[0].startswith('The after static record: 5020 of 15000')
    # --static off: every sample, the knock read as noise
    assert main([*args, '--static', 'off', '--out', str(tmp_path / 'whole')]) == 0
    doc = json.loads((tmp_path / 'whole' / 'reliability.json').read_text())
    assert doc['static_records']['after']['left_out'] == {'motion': 0}
    assert doc['overall']['gyro']['verdict'] == 'beyond'
    assert doc['overall']['gyro']['decisive']['channel'] == 'gyro_x'


@pytest.mark.parametrize('where', ['file', 'under_file'])
def test_out_in_the_way_is_exit_6_before_reading(tmp_path, capsys, where):
    blocker = tmp_path / 'blocker'
    blocker.write_text('x')
    out = blocker if where == 'file' else blocker / 'out'
    assert main(['--before-static', str(tmp_path / 'nope'), '--out', str(out)]) == 6
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err


def test_exit_codes(tmp_path, bags, capsys):
    out = str(tmp_path / 'rep')
    assert main(['--out', out]) == 2
    assert 'nothing to analyse' in capsys.readouterr().err
    assert main(['--before-static', bags['before'], '--c', '0.5', '--out', out]) == 2
    assert main(['--before-static', str(tmp_path / 'missing'), '--out', out]) == 3
    # the only part given fails (a six-position record missing a dwell): nothing analysed -> 4
    t, accel, gyro = six_position_record(dwell_s=20.0, seed=3)
    five = write_bag(tmp_path / 'five', t[t < 110.0], accel[t < 110.0], gyro[t < 110.0])
    capsys.readouterr()
    assert main(['--before-calibration', str(five), '--gravity', '9.81', '--out', out]) == 4
    err = capsys.readouterr().err
    assert 'nothing could be analysed' in err and 'missing' in err


def test_static_record_streams_like_one_batch():
    t, accel, gyro = static_record(errors=ERRORS, rate_hz=RATE, duration_s=3000.0, seed=12)
    one = StaticRecord(RATE)
    one.update(t, accel, gyro)
    many = StaticRecord(RATE)
    for k in range(0, t.size, 7777):
        many.update(t[k:k + 7777], accel[k:k + 7777], gyro[k:k + 7777])
    r1, _ = one.finish()
    r2, _ = many.finish()
    for ch in CHANNELS:
        assert r1[ch].interval.lo_s == pytest.approx(r2[ch].interval.lo_s, rel=1e-9)
