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


"""PX4 and ArduPilot export, checked with each autopilot's documented formula written here."""

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.baselines import LinearTdT, TemperaturePolynomial
from gyro_noise_ros.thermal.export import (ardupilot_applied_offset, ardupilot_notes,
                                           ardupilot_parameters, calibration_of,
                                           firmware_residuals, px4_applied_offset, px4_device_id,
                                           px4_parameters, remap_axes, write_ardupilot_parm,
                                           write_px4_params)
from gyro_noise_ros.thermal.methods import fit_accel
from gyro_noise_ros.thermal.metrics import residual_drift_deg_s
from gyro_noise_ros.thermal.run import ThermalRun
import numpy as np
import pytest


@pytest.fixture(scope='module')
def fitted():
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 3000.0, 0.5)
    temp = 5.0 + 50.0 * t / t[-1] + rng.normal(0, 0.02, t.size)
    d = temp - 25.0
    gyro = np.column_stack([0.003 + 2e-4 * d - 3e-6 * d ** 2 + 4e-8 * d ** 3,
                            -0.002 + 1e-4 * d + 5e-6 * d ** 2, 0.001 - 3e-4 * d + 2e-8 * d ** 3])
    accel = np.column_stack([0.05 + 1e-3 * d, -0.02 - 8e-4 * d + 1e-5 * d ** 2,
                             9.80665 + 1.2e-3 * d - 1e-7 * d ** 3])
    run = ThermalRun(t_s=t, gyro_rad_s=gyro + rng.normal(0, 1e-4, gyro.shape),
                     temperature_c=temp, rate_hz=2.0, accel_m_s2=accel)
    poly = TemperaturePolynomial()
    poly.fit(run, rng=rng)
    return poly, fit_accel(run), temp


def _read_px4(text):
    """Parse a QGroundControl parameter file: name -> value (ints for type 6)."""
    out = {}
    for line in text.splitlines():
        if line.startswith('#') or not line.strip():
            continue
        vehicle, component, name, value, kind = line.split('\t')
        assert (vehicle, component) == ('1', '1') and kind in ('6', '9')
        out[name] = int(value) if kind == '6' else float(value)
    return out


def _px4_offset(p, sensor, temperature, dtype=float):
    """PX4's documented compensation: delta = clip(T) - TREF, offset = sum Xn delta^n."""
    f = np.dtype(dtype).type
    out = np.zeros((temperature.size, 3), dtype=dtype)
    tmin, tmax, tref = (f(p[f'TC_{sensor}0_{k}']) for k in ('TMIN', 'TMAX', 'TREF'))
    delta = np.clip(temperature.astype(dtype), tmin, tmax) - tref
    for axis in range(3):
        for n in range(4):
            out[:, axis] += f(p[f'TC_{sensor}0_X{n}_{axis}']) * delta ** n
    return out


def _read_parm(text):
    out = {}
    for line in text.splitlines():
        if line.startswith('#') or not line.strip():
            continue
        name, value = line.split()
        out[name] = float(value)
    return out


def _ardupilot_correction(p, stype, temperature, cal_temp):
    """Return ArduPilot TCal correct_sensor: -P(clip(T) - 35) + P(clip(CALTEMP) - 35)."""
    tmin, tmax = p['INS_TCAL1_TMIN'], p['INS_TCAL1_TMAX']

    def poly(u, axis):
        c = [p[f'INS_TCAL1_{stype}{k}_{"XYZ"[axis]}'] * 1e-6 for k in (1, 2, 3)]
        return (c[0] + (c[1] + c[2] * u) * u) * u

    t = np.clip(temperature, tmin, tmax)
    tc = np.clip(cal_temp, tmin, tmax)
    return np.column_stack([-poly(t - 35.0, a) + poly(tc - 35.0, a) for a in range(3)])


def test_px4_parameters_reproduce_the_model(fitted, tmp_path):
    poly, accel_poly, temp = fitted
    gyro, accel = calibration_of(poly), calibration_of(accel_poly, unit='m/s^2')
    text = write_px4_params(tmp_path / 'tc.params',
                            px4_parameters(gyro, accel, gyro_device_id=2359306,
                                           accel_device_id=2359562),
                            comment='from test')
    assert (tmp_path / 'tc.params').read_text() == text
    p = _read_px4(text)
    assert p['TC_G_ENABLE'] == 1 and p['TC_A_ENABLE'] == 1 and p['TC_G0_ID'] == 2359306
    # the model's own range and midpoint reference, as PX4's process_sensor_caldata.py sets them
    assert p['TC_G0_TMIN'] == temp.min() and p['TC_G0_TMAX'] == temp.max()
    assert p['TC_G0_TREF'] == pytest.approx((temp.min() + temp.max()) / 2, abs=1e-12)
    probe = np.linspace(-20.0, 80.0, 1001)   # inside and beyond the range (held there)
    want = poly.drift_rad_s(probe, np.zeros_like(probe))
    span = np.ptp(want, axis=0).max()
    np.testing.assert_allclose(_px4_offset(p, 'G', probe), want, rtol=0, atol=1e-6 * span)
    # as the firmware evaluates it, in float32: still ~1e-6 of the offset's span
    np.testing.assert_allclose(_px4_offset(p, 'G', probe, np.float32), want, rtol=0,
                               atol=1e-6 * span)
    want_a = accel_poly.drift_rad_s(probe, np.zeros_like(probe))
    np.testing.assert_allclose(_px4_offset(p, 'A', probe), want_a, rtol=0,
                               atol=1e-6 * np.ptp(want_a, axis=0).max())
    # the accelerometer's polynomial is relative: X0 = 0, the change from TREF
    assert all(p[f'TC_A0_X0_{a}'] == 0.0 for a in range(3))


def test_ardupilot_parameters_reproduce_the_model(fitted, tmp_path):
    poly, accel_poly, temp = fitted
    gyro, accel = calibration_of(poly), calibration_of(accel_poly, unit='m/s^2')
    text = write_ardupilot_parm(tmp_path / 'tcal.parm', ardupilot_parameters(gyro, accel))
    p = _read_parm(text)
    assert p['INS_TCAL1_ENABLE'] == 1.0 and 'INS_TCAL1_ENABLE 1' in text
    assert p['INS_TCAL1_TMIN'] == temp.min() and p['INS_TCAL1_TMAX'] == temp.max()
    probe = np.linspace(-20.0, 80.0, 1001)
    want = poly.drift_rad_s(probe, np.zeros_like(probe))
    span = np.ptp(want, axis=0).max()
    # gyro: raw - OFFS + correction; with the exported offsets at CALTEMP it is raw - model
    offs = np.array([p[f'INS_GYROFFS_{a}'] for a in 'XYZ'])
    removed = offs - _ardupilot_correction(p, 'GYR', probe, p['INS_GYR1_CALTEMP'])
    np.testing.assert_allclose(removed, want, rtol=0, atol=1e-6 * span)
    # whatever offset ArduPilot measures at boot, the temperature-dependent part is the model's
    # change from that temperature
    boot = 31.7
    change = -_ardupilot_correction(p, 'GYR', probe, boot)
    np.testing.assert_allclose(change, want - poly.drift_rad_s([boot], [0.0]), rtol=0,
                               atol=1e-6 * span)
    # accelerometer: the change from the calibration temperature, to 1e-6 of its span
    want_a = accel_poly.drift_rad_s(probe, np.zeros_like(probe))
    change_a = -_ardupilot_correction(p, 'ACC', probe, 25.0)
    np.testing.assert_allclose(change_a, want_a - accel_poly.drift_rad_s([25.0], [0.0]),
                               rtol=0, atol=1e-6 * np.ptp(want_a, axis=0).max())
    only = _read_parm(write_ardupilot_parm(tmp_path / 'g.parm',
                                           ardupilot_parameters(gyro, gyro_offsets=False)))
    assert 'INS_GYROFFS_X' not in only and 'INS_TCAL1_ACC1_X' not in only


def test_export_refusals(fitted):
    poly, _, temp = fitted
    with pytest.raises(ParameterError, match="'linear_tdt' cannot be exported"):
        calibration_of(LinearTdT())
    with pytest.raises(ParameterError, match='order 3'):
        wide = TemperaturePolynomial(order=5)
        wide.coef, wide.t_ref_c, wide.t_min_c, wide.t_max_c = np.zeros((3, 6)), 20.0, 0.0, 40.0
        calibration_of(wide)
    with pytest.raises(ParameterError, match='instance must be 0..3'):
        px4_parameters(calibration_of(poly), instance=4)
    with pytest.raises(ParameterError, match='IMU number'):
        ardupilot_parameters(calibration_of(poly), imu=4)
    with pytest.raises(ParameterError, match='nothing to export'):
        px4_parameters(None)
    for bad in (99999999999, -1, 2 ** 24, 7, 1.5):
        with pytest.raises(ParameterError, match='px4_gyro_id'):
            px4_parameters(calibration_of(poly), gyro_device_id=bad)


def test_ardupilot_range_is_a_note_not_a_refusal():
    # the documented -70..80 degC of TMIN/TMAX is not enforced by the firmware: a calibration up
    # to 82 degC is written, with a note; one inside the range has none
    hot = TemperaturePolynomial()
    hot.coef, hot.t_ref_c, hot.t_min_c, hot.t_max_c = np.zeros((3, 4)), 50.0, 18.0, 82.0
    p = dict(ardupilot_parameters(calibration_of(hot)))
    assert p['INS_TCAL1_TMAX'] == 82.0
    (note,) = ardupilot_notes(calibration_of(hot))
    assert '18.00..82.00 degC leave the documented -70..80' in note
    hot.t_max_c = 80.0
    assert ardupilot_notes(calibration_of(hot)) == ()


def test_px4_device_ids_and_instances():
    # 2359306 = 0x24000A: bus type 2 (SPI), bus 1, address 0, device type 0x24
    assert px4_device_id(2359306) == {'id': 2359306, 'bus_type': 'SPI', 'bus': 1, 'address': 0,
                                      'devtype': 0x24}
    cal = TemperaturePolynomial()
    cal.coef, cal.t_ref_c, cal.t_min_c, cal.t_max_c = np.ones((3, 4)), 30.0, 10.0, 50.0
    p = {n: v for n, v, _ in px4_parameters(calibration_of(cal), calibration_of(cal),
                                            instance=3, gyro_device_id=2359306)}
    # the gyro enabled and matched; the accelerometer without an id written disabled
    assert (p['TC_G_ENABLE'], p['TC_G3_ID'], p['TC_A_ENABLE'], p['TC_A3_ID']) == (1, 2359306, 0, 0)
    assert p['TC_G3_X1_2'] == 1.0


def _px4_twin(cal, t, temp):
    """Run the module's loop one tick at a time: each second, publish if T moved > 1 degC."""
    out = np.zeros((t.size, 3))
    last, current, tick = -100.0, None, t[0]
    for k in range(t.size):
        while tick <= t[k] + 1e-12:
            reading = np.float32(temp[np.searchsorted(t, tick, side='right') - 1])
            if abs(reading - np.float32(last)) > 1.0:
                last = float(reading)
                current = cal.offset([last])[0]
            tick += 1.0
        out[k] = 0.0 if current is None else current
    return out


def test_px4_update_rule_against_a_step_by_step_twin(fitted):
    poly, _, _ = fitted
    cal = calibration_of(poly)
    t = np.arange(0.0, 600.0, 0.05)
    temp = 30.0 + 20.0 * np.sin(2.0 * np.pi * t / 400.0)
    got = px4_applied_offset(cal, t, temp)
    # float32 evaluation against float64: 1e-6 of the offset's span
    span = np.ptp(cal.offset(temp), axis=0).max()
    np.testing.assert_allclose(got, _px4_twin(cal, t, temp), rtol=0, atol=1e-6 * span)
    # held between publications: the offset only changes where the temperature moved > 1 degC
    changes = np.flatnonzero(np.any(np.diff(got, axis=0) != 0.0, axis=1)) + 1
    published = temp[changes]
    assert (np.abs(np.diff(published)) > 1.0).all()
    # a constant temperature: published once, at the first tick, then held
    still = px4_applied_offset(cal, t, np.full(t.size, 33.3))
    np.testing.assert_allclose(still, np.broadcast_to(cal.offset([33.3]), still.shape),
                               rtol=0, atol=1e-6 * span)


def test_ardupilot_rule_is_the_model_in_float32(fitted):
    poly, _, temp = fitted
    cal = calibration_of(poly)
    probe = np.linspace(-20.0, 80.0, 1001)
    span = np.ptp(cal.offset(probe), axis=0).max()
    np.testing.assert_allclose(ardupilot_applied_offset(cal, probe), cal.offset(probe), rtol=0,
                               atol=1e-6 * span)
    # another CALTEMP: the same offsets (OFFS is the model's offset there)
    np.testing.assert_allclose(ardupilot_applied_offset(cal, probe, cal_temp_c=12.0),
                               cal.offset(probe), rtol=0, atol=1e-6 * span)


def test_reexpansion_is_exact(fitted):
    poly, _, _ = fitted
    cal = calibration_of(poly)
    x = np.linspace(cal.t_min_c, cal.t_max_c, 50)
    for ref in (35.0, -10.0, cal.t_ref_c):
        b = cal.about(ref)
        got = np.column_stack([np.polyval(b[a, ::-1], x - ref) for a in range(3)])
        np.testing.assert_allclose(got, cal.offset(x), rtol=0, atol=1e-14)


def test_axes_are_remapped_to_the_autopilots(fitted):
    poly, _, _ = fitted
    cal = calibration_of(poly)
    probe = np.linspace(0.0, 60.0, 7)
    turned = remap_axes(cal, '-y, x ,+z')   # the chip turned 90 degrees about z on the board
    np.testing.assert_array_equal(turned.offset(probe),
                                  np.column_stack([-cal.offset(probe)[:, 1],
                                                   cal.offset(probe)[:, 0],
                                                   cal.offset(probe)[:, 2]]))
    np.testing.assert_array_equal(remap_axes(cal, 'x,y,z').coef, cal.coef)
    for bad in ('x,x,z', 'x,y', 'x,y,w', '--x,y,z', ''):
        with pytest.raises(ParameterError, match='axes must name'):
            remap_axes(cal, bad)


def test_firmware_residuals_on_a_run(fitted):
    poly, _, _ = fitted
    cal = calibration_of(poly)
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 1800.0, 0.1)
    temp = 30.0 + 10.0 * np.sin(2.0 * np.pi * t / 900.0)
    gyro = cal.offset(temp) + rng.normal(0.0, 1e-3, (t.size, 3))
    got = firmware_residuals(cal, t, gyro, temp)
    np.testing.assert_allclose(got['raw'], residual_drift_deg_s(gyro, 10.0), rtol=1e-6)
    np.testing.assert_allclose(got['model'], residual_drift_deg_s(gyro - cal.offset(temp), 10.0),
                               rtol=1e-6)
    # ArduPilot evaluates the cubic at every sample: the model's residual to float32 rounding;
    # PX4's 1 degC steps leave more on a run sweeping 20 degC every 15 minutes
    np.testing.assert_allclose(got['ardupilot'], got['model'], rtol=1e-3)
    assert all(p > m for p, m in zip(got['px4'], got['model']))
