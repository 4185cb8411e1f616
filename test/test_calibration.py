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
Six-position calibration (paper 001 eqs. 3-4, section 6, Table 6): estimator, detector, gravity.

Oracles: closed forms (noise-free dwell means, WGS-84 published values), the paper's printed
numbers (Table 6 and the section 6 standard deviations), and the slow least-squares twin in
``_sixpos_reference.py``.
"""

from _reliability_common import six_position_record
from _sixpos_reference import lstsq_matrix, paper_bias, paper_scale
from gyro_noise_ros.calibration.emulate import (PAPER_AFTER_BIAS_MG, PAPER_AFTER_SCALE_PCT,
                                                PAPER_BEFORE_BIAS_MG, PAPER_BEFORE_SCALE_PCT,
                                                SensorErrors)
from gyro_noise_ros.calibration.sixpos import (calibrate_six, EARTH_RATE_RAD_S, normal_gravity,
                                               six_position, uniformity)
from gyro_noise_ros.calibration.static import (DetectorSettings, find_dwells, ORIENTATIONS,
                                               select_six, WindowAccumulator)
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.units import MG_TO_M_S2
import numpy as np
import pytest

G = 9.80665


def _dwell_means(a_matrix, bias, g=G):
    return np.array([a_matrix @ (s * g * np.eye(3)[i]) + bias
                     for i in range(3) for s in (1.0, -1.0)])


def _calibrate(t, accel, gyro, rate_hz=100.0, settings=DetectorSettings(), g=G):
    acc = WindowAccumulator(rate_hz, window_s=settings.window_s)
    acc.update(t, accel, gyro)
    chosen = select_six([find_dwells(acc.result(), settings)], settings)
    res, _, _ = calibrate_six(chosen, g)
    return res, [chosen[o] for o in ORIENTATIONS]


def test_normal_gravity_published_values():
    # WGS-84 (TR8350.2 Table 3.4): equatorial 9.7803253359, polar 9.8321849378 m/s^2
    assert normal_gravity(0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert normal_gravity(90.0) == pytest.approx(9.8321849378, abs=1e-9)
    assert normal_gravity(-45.0) == normal_gravity(45.0)
    # free-air gradient near the surface at 45 deg: -3.0861e-6 s^-2 (first-order term)
    grad = (normal_gravity(45.0, 100.0) - normal_gravity(45.0, 0.0)) / 100.0
    assert grad == pytest.approx(-3.0861e-6, rel=2e-3)
    with pytest.raises(ParameterError):
        normal_gravity(91.0)


def test_noise_free_means_give_the_model_back_exactly():
    rng = np.random.default_rng(3)
    mis = rng.normal(0, 2e-3, (3, 3))
    np.fill_diagonal(mis, 0.0)
    scale = rng.normal(0, 1e-3, 3)
    bias = rng.normal(0, 0.05, 3)
    res = six_position(_dwell_means(np.eye(3) + np.diag(scale) + mis, bias), G)
    np.testing.assert_allclose(res.accel_bias_m_s2, bias, atol=1e-13)
    np.testing.assert_allclose(res.accel_scale_factor, scale, atol=1e-14)
    np.testing.assert_allclose(res.accel_misalignment, mis, atol=1e-14)
    # the calibration maps the raw dwell means back to exactly +/- g on one axis
    np.testing.assert_allclose(res.compensate_accel(_dwell_means(res.accel_matrix, bias)),
                               _dwell_means(np.eye(3), np.zeros(3)), atol=1e-12)


def test_estimator_matches_the_least_squares_twin():
    rng = np.random.default_rng(5)
    for _ in range(20):
        means = _dwell_means(np.eye(3) + rng.normal(0, 3e-3, (3, 3)), rng.normal(0, 0.1, 3))
        means += rng.normal(0, 0.01, means.shape)      # noisy, so the model no longer fits exactly
        res = six_position(means, G)
        a, _ = lstsq_matrix(means, G)
        off = ~np.eye(3, dtype=bool)
        np.testing.assert_allclose(res.accel_misalignment[off], a[off], atol=1e-13)
        np.testing.assert_allclose(res.accel_scale_factor, np.diag(a) - 1.0, atol=1e-13)
        np.testing.assert_allclose(res.accel_bias_m_s2, paper_bias(means), atol=1e-15)
        np.testing.assert_allclose(res.accel_scale_factor, paper_scale(means, G), atol=1e-15)


def test_uniformity_reproduces_paper_section_6():
    # paper 001 section 6: 0.252 -> 2.955 (mg) and 0.025 -> 0.087 (%), from Table 6
    assert uniformity(PAPER_BEFORE_BIAS_MG) == pytest.approx(0.252, abs=5e-4)
    assert uniformity(PAPER_AFTER_BIAS_MG) == pytest.approx(2.955, abs=5e-4)
    assert uniformity(PAPER_BEFORE_SCALE_PCT) == pytest.approx(0.025, abs=5e-4)
    assert uniformity(PAPER_AFTER_SCALE_PCT) == pytest.approx(0.087, abs=5e-4)


@pytest.mark.parametrize('stressed', [False, True])
def test_table6_values_are_recovered_from_a_simulated_record(stressed):
    errors = SensorErrors(accel_misalignment=[2e-3, -1e-3, 1.5e-3, 0.5e-3, -2e-3, 1e-3],
                          gyro_bias_rad_s=(0.01, -0.005, 0.003))
    if stressed:
        errors = errors.stressed()
    bias_mg = PAPER_AFTER_BIAS_MG if stressed else PAPER_BEFORE_BIAS_MG
    scale_pct = PAPER_AFTER_SCALE_PCT if stressed else PAPER_BEFORE_SCALE_PCT
    t, accel, gyro = six_position_record(errors=errors, seed=11 + stressed)
    res, dw = _calibrate(t, accel, gyro)
    assert sorted(d.orientation for d in dw) == sorted(ORIENTATIONS)
    # 4 sigma of the reported uncertainty (false failure ~1e-4 per value); the uncertainty itself
    # must match the noise: 0.04 m/s^2 white, 2800 samples per dwell, b the mean of two dwells:
    # 0.04 / sqrt(2800) / sqrt(2) = 5.3e-4 m/s^2 = 0.054 mg (no wander here: the variogram's
    # white term alone); fitted to 6 x 28 window means per axis, pooled over 3 axes, so it is
    # itself uncertain by ~1 / sqrt(2 * 250) = 5 %: accept 0.035..0.08 mg (> 6 sigma)
    sig_b = res.accel_bias_sigma_m_s2 / MG_TO_M_S2
    assert np.all((sig_b > 0.035) & (sig_b < 0.08)), sig_b
    np.testing.assert_array_less(np.abs(res.accel_bias_m_s2 / MG_TO_M_S2 - bias_mg), 4 * sig_b)
    np.testing.assert_array_less(np.abs(res.accel_scale_factor * 100 - scale_pct),
                                 4 * res.accel_scale_factor_sigma * 100)
    off = ~np.eye(3, dtype=bool)
    np.testing.assert_array_less(np.abs(res.accel_misalignment - errors.accel_misalignment)[off],
                                 4 * res.accel_misalignment_sigma[off])
    # paper section 6 spreads: 0.252 / 2.955 mg and 0.025 / 0.087 %, to within what the
    # estimation noise allows (std of 3 values moves by at most ~sigma: 0.05 mg, 0.005 %)
    assert uniformity(res.accel_bias_m_s2) / MG_TO_M_S2 == pytest.approx(uniformity(bias_mg),
                                                                         abs=0.1)
    assert uniformity(res.accel_scale_factor) * 100 == pytest.approx(uniformity(scale_pct),
                                                                     abs=0.01)


def test_earth_rate_cancels_in_the_gyro_bias():
    bias = np.array([0.01, -0.005, 0.003])
    t, accel, gyro = six_position_record(errors=SensorErrors(gyro_bias_rad_s=bias),
                                         gyro_noise=1e-4, seed=2)
    res, dw = _calibrate(t, accel, gyro)
    # the vertical Earth rate at 45 deg is 5.2e-5 rad/s on the axis pointing up: a single dwell
    # carries it, the pair mean must not (noise: 1e-4 / sqrt(2 * 2800) ~ 1.3e-6 rad/s)
    vertical = EARTH_RATE_RAD_S * np.sin(np.radians(45.0))
    up = {d.orientation: d for d in dw}['+z'].gyro_mean_rad_s[2] - bias[2]
    assert up == pytest.approx(vertical, abs=1e-5)
    np.testing.assert_allclose(res.gyro_bias_rad_s, bias, atol=8e-6)


def test_any_order_and_settling_is_trimmed():
    t, accel, gyro = six_position_record(order=('-y', '+x', '-z', '+y', '-x', '+z'), seed=4)
    res, dw = _calibrate(t, accel, gyro)
    np.testing.assert_array_less(
        np.abs(res.accel_bias_m_s2 / MG_TO_M_S2 - PAPER_BEFORE_BIAS_MG), 0.2)
    # 30 s dwells minus one 1 s window at each end
    assert all(27.5 <= d.duration_s <= 29.5 for d in dw[:-1])


def _detect(t, accel, gyro, **kw):
    settings = DetectorSettings(**kw)
    acc = WindowAccumulator(100.0, window_s=settings.window_s, source='rec')
    acc.update(t, accel, gyro)
    return find_dwells(acc.result(), settings), settings


def test_missing_orientation_is_named():
    t, accel, gyro = six_position_record(order=('+x', '-x', '+y', '-y', '+z'), seed=1)
    det, s = _detect(t, accel, gyro)
    with pytest.raises(InputDataError, match=r'orientation\(s\) -z missing'):
        select_six([det], s)


def test_duplicate_orientation_is_named():
    t, accel, gyro = six_position_record(order=('+x', '-x', '+y', '-y', '+z', '-z', '+x'), seed=1)
    det, s = _detect(t, accel, gyro)
    with pytest.raises(InputDataError, match=r'2 dwells claim orientation \+x: \+x at t='):
        select_six([det], s)


def test_short_dwell_is_reported_as_such():
    t, accel, gyro = six_position_record(dwell_s=30.0, seed=1)
    det, s = _detect(t, accel, gyro, min_static_s=40.0)
    assert not det.dwells and len(det.short) == 6
    with pytest.raises(InputDataError, match='no static dwell of at least min_static_s 40 s'):
        select_six([det], s)


def test_tilted_dwell_is_refused():
    t, accel, gyro = six_position_record(seed=1)
    c, s_ = np.cos(np.radians(20)), np.sin(np.radians(20))
    rot = np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]])
    sel = t < 30.0                                 # the first dwell (+z) tilted by 20 deg
    accel[sel] = accel[sel] @ rot.T
    det, s = _detect(t, accel, gyro)
    with pytest.raises(InputDataError, match=r'tilted more than max_tilt_deg 5 deg.*\+z at t=1'):
        select_six([det], s)


def test_never_static_and_zero_accel_and_nan():
    rng = np.random.default_rng(0)
    t = np.arange(6000) / 100.0
    moving = np.column_stack([np.sin(t), np.cos(t), np.ones_like(t)]) * G
    gyro = np.column_stack([np.ones_like(t), np.zeros_like(t), np.zeros_like(t)])
    det, s = _detect(t, moving + rng.normal(0, 0.3, moving.shape), gyro)
    with pytest.raises(InputDataError, match='never stops moving'):
        select_six([det], s)
    with pytest.raises(InputDataError, match='accelerometer reads ~0'):
        _detect(t, np.zeros((t.size, 3)), gyro * 0)
    with pytest.raises(InputDataError, match='no finite samples'):
        _detect(t, np.full((t.size, 3), np.nan), gyro)
    # NaN samples are dropped one by one and counted, in the recording and in their dwell
    t, accel, gyro = six_position_record(seed=6)
    accel[500:510] = np.nan
    det, s = _detect(t, accel, gyro)
    assert det.non_finite_samples == 10
    chosen = select_six([det], s)
    assert chosen['+z'].non_finite_samples == 10 and '10 NaN/Inf samples dropped' in \
        chosen['+z'].describe()
