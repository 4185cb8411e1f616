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
What a tilt, NaN and bias wander do to a static calibration, and the checks that can fail.

Oracles: the scenario model's known errors (tilts, sensor matrices, the wander it generated),
an explicit covariance matrix as the twin of the variogram algebra, and closed forms.
"""

import dataclasses

from _reliability_common import six_position_record
from gyro_noise_ros.calibration.dwell_noise import DwellNoise, DwellNoiseFitter
from gyro_noise_ros.calibration.emulate import (BiasVariation, MultiPose, Scenario,
                                                SensorErrors, simulate, SixPosition)
from gyro_noise_ros.calibration.multipose import calibrate_poses, triangular
from gyro_noise_ros.calibration.sixpos import calibrate_six, consistency, residual_projector
from gyro_noise_ros.calibration.static import (DetectorSettings, find_dwells, ORIENTATIONS,
                                               select_poses, select_six, WindowAccumulator)
from gyro_noise_ros.errors import InputDataError
import numpy as np
import pytest

G = 9.80665
RATE = 104.0
#: The emulator's accelerometer: 70 ug/sqrt(Hz) white, flicker plateau at half the white ADEV at
#: 1 s, random walk white / 11.5 (cli/_scenario.py defaults).
N_ACC = 70e-6 * G / np.sqrt(2.0)
WHITE = 70e-6 * G * np.sqrt(RATE / 2.0)
WANDER = {'accel_bias_instability_m_s2': N_ACC / 2.0 / 0.664,
          'accel_random_walk_m_s2_sqrt_s': N_ACC / 11.5}
MIS = np.array([0.10, -0.05, 0.08, 0.03, -0.10, 0.05]) / 100.0


def _record(motion, errors, seed, *, gyro_noise=1e-3):
    n = int(round((motion.duration_s + 5.0) * RATE))
    sc = Scenario(motion, errors, RATE, np.random.default_rng([seed, 2]))
    return simulate(sc, n, RATE, rng=np.random.default_rng(seed), accel_noise_m_s2=WHITE,
                    gyro_noise_rad_s=gyro_noise)


def _detect(t, accel, gyro, settings=DetectorSettings(), rate=RATE):
    acc = WindowAccumulator(rate, window_s=settings.window_s, source='rec')
    acc.update(t, accel, gyro)
    return find_dwells(acc.result(), settings)


# -- the variogram algebra against an explicit covariance matrix ---------------------------------

def test_dwell_covariance_equals_the_explicit_covariance_twin():
    # A random walk of K per sqrt(s) plus white noise, in window means of w = 1 s: their
    # covariance is known exactly. With B(0) = 0, the mean of B over a window centred at t_i
    # has variance K^2 (t_i - w / 6) and covariance K^2 min(t_i, t_k) with a later window; white
    # noise adds s2 on the diagonal. Its variogram is exactly a + c lag / w with
    # a = s2 - K^2 w / 6, c = K^2 w / 2 (lag >= w), so the variogram algebra must give any
    # contrast of dwell means to rounding.
    k2, s2, w = 4e-6, 3e-5, 1.0
    times = [np.arange(20) + 0.5, np.arange(40, 70) + 0.5, np.arange(100, 112) + 0.5]
    counts = [np.full(t.size, 50.0) for t in times]
    fitter = DwellNoiseFitter(times, counts, [np.zeros((t.size, 3)) for t in times])
    model = DwellNoise(w, np.array([s2 - k2 * w / 6.0, 0.0, k2 * w / 2.0]), fitter.basis,
                       fitter.weights, fitter.white_factor)
    t_all = np.concatenate(times)
    cov = k2 * np.minimum.outer(t_all, t_all)
    cov[np.diag_indices_from(cov)] += s2 - k2 * w / 6.0
    avg = np.zeros((3, t_all.size))
    start = 0
    for d, t in enumerate(times):
        avg[d, start:start + t.size] = 1.0 / t.size
        start += t.size
    for c in (np.array([1.0, -0.3, -0.7]), np.array([0.5, 0.5, -1.0])):
        explicit = float(c @ avg @ cov @ avg.T @ c)
        assert model.variance(c) == pytest.approx(explicit, rel=1e-9)


def test_white_noise_alone_gives_sigma_over_sqrt_n_against_the_calibration_bias():
    # white noise is measurement noise, no part of the bias during the calibration: a mean of
    # two dwells keeps its full variance sigma^2 / N. Six dwells of 60 window means, tied by the
    # residuals of the six-position equations as the calibration ties them (without that tie
    # the non-negative fit leans the long-lag terms upwards: conservative, module docstring)
    rng = np.random.default_rng(1)
    times = [np.arange(60) + 0.5 + 65 * d for d in range(6)]
    counts = [np.full(60, 100.0) for _ in times]
    values = [rng.normal(0, 0.01, (60, 3)) for _ in times]      # window means of 100 samples
    p = residual_projector()
    means = np.array([v.mean(axis=0) for v in values])
    loading = np.zeros((18, 6, 3))
    for j in range(3):
        loading[6 * j:6 * j + 6, :, j] = p
    fitter = DwellNoiseFitter(times, counts, values)
    noise = fitter.fit(residual_loading=loading, residuals=(p @ means).T.reshape(-1))
    c = np.zeros(6)
    c[:2] = 0.5
    # 1e-4 / 60 / 2: the fit has 6 x 60 x 3 window means and 6 residual degrees of freedom
    assert noise.variance(c) == pytest.approx(1e-4 / 120.0, rel=0.25)


# -- NaN and the detector -----------------------------------------------------------------------

def test_three_nan_samples_are_counted_in_their_dwell_not_two_dwells():
    t, accel, gyro = six_position_record(dwell_s=30.0, seed=5)
    sel = np.flatnonzero((t > 110.0) & (t < 120.0))[:3]      # inside -x (102-132 s)
    accel[sel, 1] = np.nan
    clean = select_six([_detect(*six_position_record(dwell_s=30.0, seed=5), rate=100.0)])
    chosen = select_six([_detect(t, accel, gyro, rate=100.0)])
    d = chosen['-x']
    assert d.non_finite_samples == 3 and '3 NaN/Inf samples dropped' in d.describe()
    # one NaN costs its samples, not the dwell's length (no split, no extra trimming)
    assert d.duration_s == pytest.approx(clean['-x'].duration_s)
    assert d.samples == clean['-x'].samples - 3


def test_an_all_nan_dwell_is_said_as_nan():
    t, accel, gyro = six_position_record(dwell_s=30.0, seed=5)
    sel = (t > 169.0) & (t < 200.0)                               # the whole -y dwell
    accel[sel] = np.nan
    det = _detect(t, accel, gyro, rate=100.0)
    with pytest.raises(InputDataError, match=r'no finite dwell for orientation\(s\) -y: the '
                                             r'recording holds 3\d\.\d s of NaN/Inf samples at '
                                             r't=16\d'):
        select_six([det])


def test_a_window_longer_than_the_record_says_so():
    t, accel, gyro = six_position_record(dwell_s=30.0, seed=5)
    with pytest.raises(InputDataError, match=r'shorter than one detector window \(window_s '
                                             r'1000 s\)'):
        _detect(t, accel, gyro, DetectorSettings(window_s=1000.0), rate=100.0)


# -- six-position: a tilt is named and refused; the checks can fail ----------------------------

@pytest.mark.parametrize('dwell,deg', [('+x', 3.0), ('-z', 4.5), ('+y', 4.0)])
def test_a_tilted_dwell_is_named(dwell, deg):
    errors = SensorErrors(accel_misalignment=MIS, **WANDER)
    motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0, tilts=((dwell, deg),))
    chosen = select_six([_detect(*_record(motion, errors, seed=3))])
    pairs, loo = consistency(chosen, G)
    bad = [p for p in pairs if not p.consistent]
    # exactly the tilted pair fails, and its tilted dwell is named with its tilt (+/- the
    # 0.1 % cross-axis terms, 0.06 deg)
    assert [p.axis for p in bad] == [dwell[1]]
    assert bad[0].suspect == dwell
    assert bad[0].suspect_tilt_deg == pytest.approx(deg, abs=0.15)


def test_an_untilted_calibration_passes_both_checks():
    errors = SensorErrors(accel_misalignment=MIS, **WANDER)
    motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0)
    for seed in (11, 12, 13):
        chosen = select_six([_detect(*_record(motion, errors, seed=seed))])
        pairs, loo = consistency(chosen, G)
        assert all(p.consistent for p in pairs) and all(c.consistent for c in loo)


def test_the_gravity_check_fails_on_a_scale_asymmetry():
    # the +x direction reads 0.1 % more than the -x one (a calibration that the model of
    # eqs. 3-4 cannot represent): the held-out +/-x dwells miss g by ~10 mg / 2, far beyond
    # their ~0.1 mg sigma; the other dwells pass
    errors = SensorErrors(accel_misalignment=MIS, **WANDER)
    motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0)
    t, accel, gyro = _record(motion, errors, seed=4)
    accel[:, 0] = np.where(accel[:, 0] > 0, accel[:, 0] * 1.001, accel[:, 0])
    chosen = select_six([_detect(t, accel, gyro)])
    _, loo = consistency(chosen, G)
    verdict = {c.label: c.consistent for c in loo}
    assert not verdict['+x'] and not verdict['-x']
    assert verdict['+y'] and verdict['-y'] and verdict['+z'] and verdict['-z']


# -- honest uncertainties with bias wander ----------------------------------------------------

def test_six_position_errors_stay_within_the_stated_sigma_with_wander():
    # 8 calibrations x 3 axes at the emulator's default wander, 60 s dwells: against the bias
    # during the calibration (constant + mean wander over the samples used). The coverage over
    # 100 calibrations is in docs/reliability.md (65 %); here: no error beyond 4 sigma and a 1
    # sigma fraction that a correct sigma gives with probability > 99.9 % (binomial, n = 24)
    errors = SensorErrors(accel_misalignment=MIS, **WANDER)
    motion = SixPosition(dwell_s=60.0, move_s=5.0, lead_s=5.0)
    z = []
    for seed in range(8):
        t, accel, gyro = _record(motion, errors, seed=100 + seed)
        chosen = select_six([_detect(t, accel, gyro)])
        res, _, _ = calibrate_six(chosen, G)
        u = _wander(t, seed=100 + seed)
        used = np.zeros(t.size, bool)
        for d in chosen.values():
            used |= (t >= d.t_start_s - 1e-9) & (t < d.t_end_s - 1e-9)
        z += list((res.accel_bias_m_s2 - errors.accel_bias_m_s2 - u[used].mean(axis=0))
                  / res.accel_bias_sigma_m_s2)
        z += list((res.accel_scale_factor - errors.accel_scale_factor)
                  / res.accel_scale_factor_sigma)
    z = np.abs(np.array(z))
    assert np.all(z < 4.0)
    assert 0.4 < np.mean(z < 1.0) < 0.92


def _wander(t, *, seed):
    # the scenario's own accelerometer wander stream, regenerated (Scenario spawns accel first)
    acc_rng, _ = np.random.default_rng([seed, 2]).spawn(2)
    return BiasVariation(WANDER['accel_bias_instability_m_s2'],
                         WANDER['accel_random_walk_m_s2_sqrt_s'], RATE, acc_rng).generate(t.size)


# -- multi-pose: |a| = g, no aligned dwell needed -------------------------------------------------

@pytest.mark.parametrize('wander', [False, True])
def test_multi_pose_recovers_bias_within_0p2_mg_and_scale_within_0p01_percent(wander):
    # 18 poses x 30 s at 104 Hz, the emulator's white noise (0.5 mg per sample); with its
    # default bias wander the bias is compared with the bias during the calibration (the
    # constant part is out of reach of any calibration: docs/reliability.md)
    errors = SensorErrors(accel_misalignment=MIS, **(WANDER if wander else {}))
    motion = MultiPose(poses=18, dwell_s=30.0, move_s=5.0, lead_s=5.0)
    t, accel, gyro = _record(motion, errors, seed=7)
    dwells = select_poses([_detect(t, accel, gyro)])
    assert len(dwells) == 18
    res, loo, _ = calibrate_poses(dwells, G)
    lower, _ = triangular(errors.accel_matrix)
    truth_b = errors.accel_bias_m_s2
    if wander:
        used = np.zeros(t.size, bool)
        for d in dwells:
            used |= (t >= d.t_start_s - 1e-9) & (t < d.t_end_s - 1e-9)
        truth_b = truth_b + _wander(t, seed=7)[used].mean(axis=0)
    assert np.all(np.abs(res.bias_m_s2 - truth_b) < 0.2e-3 * G)
    assert np.all(np.abs(res.scale_factor - (np.diag(lower) - 1.0)) < 1e-4)
    # and within 4 of the stated sigma, the lower cross-axis terms included
    assert np.all(np.abs(res.bias_m_s2 - truth_b) < 4 * res.bias_sigma_m_s2)
    assert np.all(np.abs(res.scale_factor - (np.diag(lower) - 1.0))
                  < 4 * res.scale_factor_sigma)
    for j, i in ((1, 0), (2, 0), (2, 1)):
        assert abs(res.misalignment[j, i] - lower[j, i]) < 4 * res.misalignment_sigma[j, i]
    assert all(c.consistent for c in loo)


def test_multi_pose_gravity_check_names_a_bumped_pose():
    # pose 5 reads 3 mg more along gravity (a knock during its dwell): its leave-one-out norm
    # misses g by ~3 mg against a ~0.02 mg sigma; once it is set aside the others pass
    errors = SensorErrors(accel_misalignment=MIS)
    motion = MultiPose(poses=18, dwell_s=30.0, move_s=5.0, lead_s=5.0)
    t, accel, gyro = _record(motion, errors, seed=8)
    o, t0, t1 = motion.schedule()[4]
    sel = (t >= t0) & (t < t1)
    up = accel[sel].mean(axis=0)
    accel[sel] += 3e-3 * G * up / np.linalg.norm(up)
    dwells = select_poses([_detect(t, accel, gyro)])
    res, loo, _ = calibrate_poses(dwells, G)
    bad = [k for k, c in enumerate(loo) if not c.consistent]
    assert bad == [4] and loo[4].residual_m_s2 > 2e-3 * G
    # it is left out of the fit, which then recovers the sensor as without the knock
    lower, _ = triangular(errors.accel_matrix)
    assert res.left_out == (loo[4].label,)
    assert np.all(np.abs(res.bias_m_s2 - errors.accel_bias_m_s2) < 4 * res.bias_sigma_m_s2)
    assert np.all(np.abs(res.scale_factor - (np.diag(lower) - 1.0)) < 4 * res.scale_factor_sigma)


def test_nine_poses_calibrate_without_a_gravity_check_and_ten_check_sanely():
    # 9 poses: 9 equations for 9 numbers, an exact fit. It used to end in a traceback (the
    # leave-one-out refit of 8); now the calibration comes with uncertainties from the windows
    # inside the dwells and no gravity check, which is said. 10 poses: each check refits 9
    # (exact) and predicts the tenth; it used to rest on the rounding residuals of that exact
    # fit (sigma ~1e-14 m/s^2 -> INCONSISTENT). Sane: sigma of the order of the pose means' noise
    # with wander (0.05-1 mg here, measured 0.24 mg median), no false alarm on a clean record,
    # a pose 3 mg off flagged (it is 10-60 sigma off).
    errors = SensorErrors(accel_misalignment=MIS, **WANDER)
    lower, _ = triangular(errors.accel_matrix)
    for poses in (9, 10):
        motion = MultiPose(poses=poses, dwell_s=30.0, move_s=5.0, lead_s=5.0)
        t, accel, gyro = _record(motion, errors, seed=40 + poses)
        dwells = select_poses([_detect(t, accel, gyro)])
        assert len(dwells) == poses
        res, loo, _ = calibrate_poses(dwells, G)
        assert np.all((res.scale_factor_sigma > 1e-7) & (res.bias_sigma_m_s2 > 1e-6))
        assert np.all(np.abs(res.scale_factor - (np.diag(lower) - 1.0))
                      < 4 * res.scale_factor_sigma)
        if poses == 9:
            assert loo == ()
            continue
        sig = np.array([c.sigma_m_s2 for c in loo]) / (1e-3 * G)
        assert len(loo) == 10 and np.all((sig > 0.05) & (sig < 1.0)), sig
        assert all(c.consistent for c in loo)
        up = dwells[3].accel_mean_m_s2 / np.linalg.norm(dwells[3].accel_mean_m_s2)
        dwells[3] = dataclasses.replace(dwells[3], accel_mean_m_s2=dwells[3].accel_mean_m_s2
                                        + 3e-3 * G * up)
        _, loo, _ = calibrate_poses(dwells, G)
        assert not all(c.consistent for c in loo)


def test_multi_pose_needs_nine_poses_and_says_how_many():
    motion = MultiPose(poses=6, dwell_s=30.0, move_s=5.0, lead_s=5.0)
    det = _detect(*_record(motion, SensorErrors(), seed=1))
    with pytest.raises(InputDataError, match='needs at least 9 static poses, found 6'):
        select_poses([det])


def test_orientations_are_the_six_and_triangular_is_an_lq_decomposition():
    assert ORIENTATIONS == ('+x', '-x', '+y', '-y', '+z', '-z')
    a = SensorErrors(accel_misalignment=MIS, accel_scale_factor=(1e-3, -2e-3, 5e-4)).accel_matrix
    lower, rot = triangular(a)
    np.testing.assert_allclose(lower @ rot, a, atol=1e-15)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    assert lower[0, 1] == lower[0, 2] == lower[1, 2] == 0.0
