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
The one Allan readout (core.readout): its rules on closed-form curves, every consumer, imu.yaml.

Oracles: IEEE 952 power-law curves (the floor and the -1/2 line are known exactly), the R avar
package's Allan variance of the ADIS16405 run 1 (an independent computation), seeded white and
random-walk noise with closed-form Allan variances. The acceptance over every real record is in
test_readout_real.py.
"""

import csv
import json
import math
from types import SimpleNamespace

from _realdata import real_data
from gyro_noise_ros.calibration.interval import bias_instability_interval
from gyro_noise_ros.cli import analyze
from gyro_noise_ros.core.allan import allan_deviation, AllanResult, fit_noise_terms
from gyro_noise_ros.core.engine import EngineConfig, NoiseEngine
from gyro_noise_ros.core.items import allan_items, fmt
from gyro_noise_ros.core.readout import (adev_at, adev_floor, B_FACTOR, MAX_TAU_FRACTION,
                                         random_walk_bound, random_walk_region, read_allan,
                                         usable_start)
from gyro_noise_ros.errors import InputDataError
from gyro_noise_ros.thermal.metrics import noise_metrics
import numpy as np
import pytest
import yaml

DEG = 180.0 / math.pi


def _curve(tau, q=0.0, n=0.0, b=0.0, k=0.0, edf=1e6):
    """Return an exact IEEE 952 curve as an AllanResult (rad/s), intervals from an EDF."""
    tau = np.asarray(tau, dtype=np.float64)
    avar = 3 * q ** 2 / tau ** 2 + n ** 2 / tau + B_FACTOR ** 2 * b ** 2 + k ** 2 * tau / 3
    return _result(tau, avar, np.full(tau.shape, float(edf)))


def _result(tau, avar, edf):
    from gyro_noise_ros.core.allan import confidence_bounds

    lo, hi = confidence_bounds(avar, edf, 0.683)
    ones = np.ones(tau.size, dtype=np.int64)
    return AllanResult(tau_s=tau, m=np.round(tau * 100).astype(np.int64), adev=np.sqrt(avar),
                       avar=avar, n_terms=ones, stride=ones, edf=edf, ci_low=np.sqrt(lo),
                       ci_high=np.sqrt(hi), noise_alpha=np.zeros(tau.size, np.int64),
                       noise_type=('',) * tau.size, confidence=0.683, rate_hz=100.0,
                       n_samples=int(4 * tau[-1] * 100))


def _octaves(lo, hi):
    return lo * 2.0 ** np.arange(int(round(math.log2(hi / lo))) + 1)


# ---- bias stability -----------------------------------------------------------------------

def test_floor_of_an_exact_curve_is_its_minimum_and_b_is_it_over_0664():
    # white + flicker + random walk: AVAR minimum near tau* where N^2/tau = K^2 tau/3
    tau = _octaves(0.01, 10485.76)
    n, b, k = 1e-3, 2e-5, 1e-6
    r = read_allan(_curve(tau, n=n, b=b, k=k))
    j = int(np.argmin(_curve(tau, n=n, b=b, k=k).adev))
    assert r.bias_stability_tau_s == tau[j] and not r.bias_stability_upper_bound
    assert r.bias_stability_rad_s == _curve(tau, n=n, b=b, k=k).adev[j]
    # B = bias stability / sqrt(2 ln 2 / pi), exactly (IEEE 952 eq. C.27)
    assert r.bias_instability_rad_s == pytest.approx(r.bias_stability_rad_s / 0.6643, rel=1e-4)
    # a pure flicker floor is 0.6643 B: B comes back
    flat = read_allan(_curve(tau, b=b))
    assert flat.bias_instability_rad_s == pytest.approx(b, rel=1e-12)
    d = r.as_dict()
    assert d['bias_stability_deg_h'] == pytest.approx(r.bias_stability_rad_s * DEG * 3600)
    assert d['bias_instability_deg_h'] == pytest.approx(r.bias_instability_rad_s * DEG * 3600)


def test_white_noise_never_turns_up_an_upper_bound_at_the_last_readable_tau():
    tau = _octaves(0.01, 40.96)
    res = _curve(tau, n=1e-3)
    r = read_allan(res)
    # the record is 4 x the last tau here: a tenth of it ends before the last two octaves
    last = tau[tau <= MAX_TAU_FRACTION * res.n_samples / res.rate_hz][-1]
    assert r.bias_stability_upper_bound and r.bias_stability_tau_s == last
    floor = adev_floor(tau, res.adev)
    assert floor.upper_bound and floor.index == tau.size - 1
    # a noisy up-tick on the last, low-EDF tau is not a turning point either
    avar = 1e-6 / tau
    avar[-1] *= 2.5
    edf = np.where(np.arange(tau.size) < tau.size - 1, 1e4, 3.0)
    f = adev_floor(tau, np.sqrt(avar), edf=edf)
    assert f.upper_bound and f.index == tau.size - 2


def test_a_band_limited_bump_at_the_shortest_taus_is_not_the_floor():
    # ADIS16405 run 2, z (the issue): flat from 0.01 to 0.02 s, slope -1 to 0.04 s, then white
    # noise down to a floor at ~80 s; the "first minimum" rule took 0.01 s.
    tau = _octaves(0.01, 1310.72)
    avar = 4e-6 / tau + 1e-10 + 6.25e-10 * tau    # white and random walk: minimum at 80 s
    avar[0], avar[1] = 4.0 * avar[2], 4.0 * 1.002 * avar[2]
    r = read_allan(_result(tau, avar, np.full(tau.size, 1e3)))
    assert usable_start(tau, np.sqrt(avar)) == 2
    assert r.usable_from_s == tau[2] and r.bias_stability_tau_s > 10.0
    assert not r.bias_stability_upper_bound


def test_the_floor_is_the_minimum_up_to_a_tenth_of_the_record():
    tau = _octaves(0.01, 1310.72)
    sig = np.sqrt(np.maximum(1e-6 / tau, 1e-8) + 1e-12 * tau)   # floor 1e-4 from 100 s
    j = int(np.argmin(sig))
    dipped = sig.copy()
    dipped[-1] = 0.75 * sig[j]              # a dip on the last, low-EDF tau
    edf = np.linspace(1e5, 9.0, tau.size)
    # past a tenth of the record (here 1000 s) a dip cannot hold the floor
    f = adev_floor(tau, dipped, edf=edf, max_tau_s=1000.0)
    assert f.index == j
    # ... but it says the floor may lie lower: an upper bound
    assert f.upper_bound and not adev_floor(tau, sig, edf=edf, max_tau_s=1000.0).upper_bound
    # inside it, the lowest value is the floor, whatever its EDF
    assert adev_floor(tau, dipped, edf=edf).index == tau.size - 1
    # the readout passes a tenth of the record
    res = _result(tau, dipped ** 2, edf)
    assert res.n_samples / res.rate_hz * MAX_TAU_FRACTION < tau[-1]
    assert read_allan(res).bias_stability_tau_s == tau[j]


def test_a_floor_that_barely_rises_is_real_when_the_curve_flattened_into_it():
    # white noise into a flicker floor at 164 s and a random walk that lifts the last tau by only
    # 7 % (EDF falling to 10, as a record's last octaves do): a rise no F test would see, but
    # the curve no longer falls like white noise (-1/2) around the floor: real, not a bound
    tau = _octaves(0.01, 1310.72)
    res = _curve(tau, n=1e-4, b=1e-4, k=1.4e-6)
    res = _result(tau, res.avar, np.geomspace(1e5, 10.0, tau.size))
    r = read_allan(res)
    assert r.bias_stability_tau_s < tau[-1] and not r.bias_stability_upper_bound
    assert r.bias_stability_rad_s == pytest.approx(B_FACTOR * 1e-4, rel=0.05)
    # a floor that is only approached (still falling past the readable taus) is an upper bound
    still = _curve(tau, n=1e-3, b=1e-4)
    last = tau[tau <= MAX_TAU_FRACTION * still.n_samples / still.rate_hz][-1]
    r = read_allan(still)
    assert r.bias_stability_upper_bound and r.bias_stability_tau_s == last


def test_adis16405_run1_x_against_the_r_avar_reference():
    g = np.load(real_data('adis16405_static', 'adis_16405_imu1.npz'))['gyro_dps']
    result = allan_deviation(np.deg2rad(g[:, 0]), 100.0, taus='octave')
    r = read_allan(result)
    d = r.as_dict()
    path = real_data('adis16405_static', 'reference_avar_moav_imu1.csv')
    with open(path, newline='') as fh:
        rows = [row for row in csv.DictReader(fh) if row['channel'] == 'Gyro. X']
    tau_ref = np.array([float(row['tau_s']) for row in rows])
    adev_ref = np.array([float(row['adev']) for row in rows])
    # Independent (R avar, octave taus): the minimum over taus up to a tenth of the record
    # (1000 s) is at 655 s; the curve dips further at 1311 s on 9 degrees of freedom.
    short = tau_ref <= 0.1 * g.shape[0] / 100.0
    j = int(np.argmin(np.where(short, adev_ref, np.inf)))
    assert tau_ref[j] == pytest.approx(655.36)
    assert adev_ref.argmin() > j
    assert r.bias_stability_tau_s == pytest.approx(tau_ref[j])
    assert d['bias_stability_deg_s'] == pytest.approx(adev_ref[j], rel=1e-4)
    assert d['bias_stability_ci_low_deg_s'] < d['bias_stability_deg_s'] < d[
        'bias_stability_ci_high_deg_s']
    # the curve dips lower at 1311 s: the floor may lie lower, an upper bound
    assert r.bias_stability_upper_bound
    # ARW on the -1/2 region against the reference ADEV at 1.28 s scaled along -1/2 (the curve
    # is on the -1/2 slope there: local slope -0.48 to -0.50); 3 % covers the slope.
    k = int(np.argmin(np.abs(tau_ref - 1.28)))
    arw_ref = adev_ref[k] * np.sqrt(tau_ref[k]) * 60.0
    assert d['arw_deg_per_sqrt_h'] == pytest.approx(arw_ref, rel=0.03)
    assert d['arw_ci_low_deg_per_sqrt_h'] < arw_ref < d['arw_ci_high_deg_per_sqrt_h']
    assert r.fit_quality == 'good'


# ---- angle random walk, K, Q --------------------------------------------------------------

def test_arw_comes_from_one_contiguous_region():
    # -1/2 from 0.01 to 5 s, a flicker shoulder, then a stretch of slope ~-1/2 again at 20-40 s
    # (MPU6050 x in the issue): only the first, longest region is used.
    tau = _octaves(0.01, 81.92)
    sig = 1e-3 / np.sqrt(tau)
    sig[tau > 5.12] = sig[tau <= 5.12][-1] * np.array([1.0, 0.99, 0.7, 0.49])[:np.sum(tau > 5.12)]
    r = read_allan(_result(tau, sig ** 2, np.full(tau.size, 1e4)))
    assert r.arw_from_region and r.arw_tau_range_s == (0.01, 5.12)
    assert r.arw_rad_per_sqrt_s == pytest.approx(1e-3, rel=1e-12)
    assert r.arw_ci_low_rad_per_sqrt_s < 1e-3 < r.arw_ci_high_rad_per_sqrt_s


def test_arw_without_a_white_region_is_adev_at_one_second_flagged():
    tau = _octaves(0.0625, 16.0)
    res = _curve(tau, b=1e-4, k=1e-5)   # flicker + random walk: no -1/2 segment
    r = read_allan(res)
    assert not r.arw_from_region and r.arw_tau_range_s == (1.0, 1.0)
    assert r.arw_rad_per_sqrt_s == pytest.approx(adev_at(res, 1.0), rel=1e-12)
    # log-log interpolation is exact on a power law
    white = _curve(np.array([0.5, 2.0]), n=1e-3)
    assert adev_at(white, 1.0) == pytest.approx(1e-3, rel=1e-12)
    assert math.isnan(adev_at(white, 4.0))


def test_rate_random_walk_resolved_and_its_bound():
    tau = _octaves(0.01, 20971.52)
    n, k = 1e-3, 1e-5
    res = _curve(tau, n=n, k=k)
    r = read_allan(res)
    assert r.rate_random_walk_resolved
    assert r.rate_random_walk_rad_per_s_sqrt_s == pytest.approx(k, rel=1e-6)
    # the bound is the +1/2 line through the upper ADEV bound at the longest tau: above K
    bound = res.ci_high[-1] * math.sqrt(3.0 / tau[-1])
    assert r.rate_random_walk_bound_rad_per_s_sqrt_s == pytest.approx(bound, rel=1e-12)
    assert random_walk_bound(res) == pytest.approx(bound, rel=1e-12) and bound > k
    kal = r.kalibr()
    assert kal['random_walk'] == bound and kal['random_walk_is_bound'] and not kal['too_short']
    # white noise alone: nothing resolved, the bound is all there is
    w = read_allan(_curve(tau[:8], n=n))
    assert not w.rate_random_walk_resolved and w.kalibr()['too_short']


def _walk_records(kind, count, n=30_000, rate=10.0):
    """Yield ``count`` seeded records: white noise plus flicker ('flicker') or a random walk."""
    from gyro_noise_ros.explain.effects import flicker_noise

    duration, white = n / rate, 1e-3   # N = 1e-3 rad/sqrt(s)
    for seed in range(count):
        rng = np.random.default_rng([23, seed, len(kind)])
        x = rng.normal(0.0, white * math.sqrt(rate), n)
        if kind == 'flicker':   # a floor met at T/100, no random walk
            x += flicker_noise(n, rate, white / (B_FACTOR * math.sqrt(duration / 100)), rng)
        else:                   # K crossing the white noise at T/300: 4 octaves of +1/2 rise
            k = math.sqrt(3.0) * white / (duration / 300)
            x += np.cumsum(rng.normal(0.0, k / math.sqrt(rate), n))
        yield allan_deviation(x, rate, taus='dense')


def test_random_walk_resolved_only_where_a_plus_half_region_shows_it():
    # docs/readout.md (200 records each, 3000 s at 10 Hz): resolved on 0 of 400 records without
    # a random walk (white; white into a flicker floor), on 80 % with K crossing the white noise
    # at T/300. Here 40 of each: with a 2 % false rate P(more than 2 of 40) = 4.6 %; with the
    # measured 80 % detection P(fewer than 26 of 40) = 1 % (binomial)
    false = sum(read_allan(r).rate_random_walk_resolved for r in _walk_records('flicker', 40))
    found = [read_allan(r) for r in _walk_records('walk', 40)]
    assert false <= 2
    assert sum(r.rate_random_walk_resolved for r in found) >= 26
    for r in found:
        if r.rate_random_walk_resolved:
            lo, hi = r.rate_random_walk_tau_range_s
            assert hi >= 4.0 * lo and lo >= r.bias_stability_tau_s
        else:
            assert all(math.isnan(v) for v in r.rate_random_walk_tau_range_s)


def test_a_curve_rising_by_a_log_slope_of_0_28_is_no_random_walk():
    # the case of issue 30: a 781 s record whose curve rises 29 % after its minimum with a log
    # slope of 0.28 was marked resolved (the K term dominated the fit at the longest tau)
    tau = _octaves(0.01, 163.84)
    floor = np.argmin(np.abs(tau - 10.24))
    adev = 1e-3 / np.sqrt(tau / tau[0])
    adev[floor:] = adev[floor] * (tau[floor:] / tau[floor]) ** 0.28
    r = read_allan(_result(tau, adev ** 2, np.full(tau.size, 1e4)))
    assert not r.rate_random_walk_resolved
    assert random_walk_region(_result(tau, adev ** 2, np.full(tau.size, 1e4)), floor) is None
    # with +1/2 instead the region is there: the taus after the floor, to the end
    adev[floor:] = adev[floor] * (tau[floor:] / tau[floor]) ** 0.5
    res = _result(tau, adev ** 2, np.full(tau.size, 1e4))
    assert random_walk_region(res, floor) == (floor, tau.size - 1)
    # ... unless the curve is too uncertain to exclude a flat one: over 4 octaves the AVAR
    # rises x16, and with 2 degrees of freedom at each end a ratio of 39 is needed (F(2, 2),
    # 97.5 %); with 3 a ratio of 15.4 (it passes)
    assert random_walk_region(_result(tau, adev ** 2, np.full(tau.size, 2.0)), floor) is None
    assert random_walk_region(_result(tau, adev ** 2, np.full(tau.size, 3.0)), floor) is not None


def test_quantization_only_where_a_minus_one_region_shows_it():
    tau = _octaves(0.01, 163.84)
    r = read_allan(_curve(tau, q=1e-3, n=1e-5))
    assert r.quantization_rad == pytest.approx(1e-3, rel=0.02)
    assert math.isnan(read_allan(_curve(tau, n=1e-5)).quantization_rad)


def test_bad_curves_say_so():
    tau = _octaves(0.01, 0.02)
    with pytest.raises(InputDataError):
        read_allan(_curve(tau[:1], n=1e-3))
    zero = _result(tau, np.zeros(tau.size), np.ones(tau.size))
    with pytest.raises(InputDataError):
        read_allan(zero)
    assert adev_floor(tau, np.zeros(tau.size)).index == -1


def test_px4_band_limited_short_taus_are_cut_and_a_bad_fit_is_flagged():
    path = real_data('px4_ulog_sample_static', 'sensor_combined.csv')
    d = np.genfromtxt(path, delimiter=',', names=True)
    # SOURCE.md: static rows 1700-16945; the samples are 4 ms integrals (band-limited).
    result = allan_deviation(d['gyro_z_rad_s'][1700:16945], 248.56, taus='octave')
    r = read_allan(result)
    assert r.band_limited_below_s > result.tau_s[0]
    assert r.fit_quality == 'good'
    assert r.arw_tau_range_s[0] >= r.band_limited_below_s
    # The fit over all taus (what the tool did before) misses the curve: flagged.
    assert read_allan(result, fit_noise_terms(result)).fit_quality == 'poor'


# ---- one curve, every consumer ------------------------------------------------------------

def _white_plus_walk(n, rate, seed):
    # AVAR = N^2 / tau + K^2 tau / 3: minimum at tau = sqrt(3) N / K = 17 s, well inside 250 s
    rng = np.random.default_rng(seed)
    n_arw, k_rrw = 1e-3, 1e-4
    x = rng.normal(0.0, n_arw * math.sqrt(rate), (n, 3))
    return x + np.cumsum(rng.normal(0.0, k_rrw / math.sqrt(rate), (n, 3)), axis=0)


def test_one_curve_gives_one_number_in_every_tool(tmp_path, capsys, make_record):
    rate, n = 100.0, 100_000
    gyro = _white_plus_walk(n, rate, 11)
    stamps = 10 ** 18 + np.arange(n, dtype=np.int64) * 10_000_000
    make_record(tmp_path / 'w.mcap', gyro, stamps_ns=stamps, storage='mcap')
    # the readout of the one estimator's curve, on the analyzer's taus
    truth = read_allan(allan_deviation(gyro[:, 0], rate, taus='dense'))
    assert not truth.bias_stability_upper_bound

    # offline analyzer: summary.json, summary.md, the printed line
    rc = analyze.main([str(tmp_path / 'w.mcap'), '--out', str(tmp_path / 'o'), '--chunk-size',
                       '20000', '--memory', '50', '--order-grid', '0:2:0.1', '--jobs', '1',
                       '--no-figures', '--allan-taus', 'dense', '--axis', 'x'])
    assert rc == 0
    sheet = json.loads((tmp_path / 'o' / 'summary.json').read_text())['bags'][0]['axes']['x'][
        'allan_datasheet']
    # same estimator and taus; the accumulator's offset is the first batch's mean, not the
    # record's: the curves agree to rounding (~1e-12)
    assert sheet['bias_stability_rad_s'] == pytest.approx(truth.bias_stability_rad_s, rel=1e-9)
    assert sheet['bias_stability_tau_s'] == pytest.approx(truth.bias_stability_tau_s, rel=1e-9)
    assert sheet['arw_rad_per_sqrt_s'] == pytest.approx(truth.arw_rad_per_sqrt_s, rel=1e-9)
    bs_deg_h = truth.bias_stability_rad_s * DEG * 3600
    assert f'bias stability {bs_deg_h:.3g} deg/h' in (tmp_path / 'o' / 'summary.md').read_text()
    assert f'bias stability {bs_deg_h:.3g} deg/h' in capsys.readouterr().out

    # live analyzer: the engine's summary and its diagnostic items
    engine = NoiseEngine(EngineConfig(chunk_size=20000, axes=('x',), memory=50, rate_hz=rate,
                                      alphas=np.linspace(0, 2, 21), allan_taus='dense'))
    for i in range(0, n, 7000):
        engine.ingest(stamps[i:i + 7000], gyro[i:i + 7000])
    live = engine.summary()['x'].readout
    assert live.bias_stability_rad_s == pytest.approx(truth.bias_stability_rad_s, rel=1e-9)
    assert live.arw_rad_per_sqrt_s == pytest.approx(truth.arw_rad_per_sqrt_s, rel=1e-9)
    items = dict(allan_items(SimpleNamespace(readout=live)))
    assert items['Bias stability (deg/s)'] == fmt(truth.bias_stability_rad_s * DEG)

    # thermal metrics (its own ADEV of the same samples, the same taus)
    m = noise_metrics(gyro[:, 0], rate)
    assert m.bias_stability_deg_h == pytest.approx(bs_deg_h, rel=1e-9)
    assert m.arw_deg_sqrt_h == pytest.approx(truth.arw_rad_per_sqrt_s * DEG * 60, rel=1e-9)

    # bias-instability interval of the reliability procedure: its sigma_min
    res = allan_deviation(gyro[:, 0], rate, taus='dense')
    iv = bias_instability_interval(res.tau_s, res.adev, edf=res.edf)
    assert iv.sigma_min == truth.bias_stability_rad_s


# ---- imu.yaml -----------------------------------------------------------------------------

def _analyze(path, out, *extra):
    rc = analyze.main([str(path), '--out', str(out), '--chunk-size', '2000', '--memory', '50',
                       '--order-grid', '0:2:0.1', '--jobs', '1', '--no-figures', '--quiet',
                       *extra])
    assert rc == 0
    text = (out / 'imu.yaml').read_text()
    return text, yaml.safe_load(text)


def test_imu_yaml_random_walk_is_the_larger_of_fit_and_bound(tmp_path, make_record):
    # Pure white noise over 40 s: the fitted random walk is 0 and the curve never turns up;
    # Kalibr needs a positive number, and the file says the record is too short for one.
    rng = np.random.default_rng(3)
    n = 40_000
    stamps = 10 ** 18 + np.arange(n, dtype=np.int64) * 1_000_000
    make_record(tmp_path / 'w.mcap', rng.normal(0, 1e-3, (n, 3)), stamps_ns=stamps,
                accel_m_s2=rng.normal(0, 1e-2, (n, 3)), storage='mcap')
    text, doc = _analyze(tmp_path / 'w.mcap', tmp_path / 'o')
    summary = json.loads((tmp_path / 'o' / 'summary.json').read_text())['bags'][0]
    bounds = [summary['axes'][a]['allan_datasheet']['rate_random_walk_bound_rad_per_s_sqrt_s']
              for a in 'xyz']
    assert doc['gyroscope_random_walk'] == max(bounds) > 0
    assert doc['accelerometer_random_walk'] > 0
    assert 'record too short (40 s) for a random walk' in text
    densities = [summary['axes'][a]['allan_datasheet']['arw_rad_per_sqrt_s'] for a in 'xyz']
    assert doc['gyroscope_noise_density'] == max(densities) > 0
    # N = sigma sqrt(tau0) for white noise: 1e-3 * sqrt(1 ms), within 3 % (40 s at 1 kHz)
    assert doc['gyroscope_noise_density'] == pytest.approx(1e-3 * math.sqrt(1e-3), rel=0.03)
    assert doc['rostopic'] == '/imu/data_raw' and '# rostopic' not in text


def test_imu_yaml_of_a_csv_names_the_usual_topic_and_says_why(tmp_path):
    rate, n = 100.0, 20_000
    gyro = _white_plus_walk(n, rate, 5)
    path = tmp_path / 'rec.csv'
    with path.open('w') as fh:
        fh.write('t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s\n')
        for i in range(n):
            fh.write(f'{i / rate:.17g},' + ','.join(f'{v:.17g}' for v in gyro[i]) + '\n')
    text, doc = _analyze(path, tmp_path / 'o')
    assert doc['rostopic'] == '/imu/data_raw'
    assert '# rostopic: the input was a csv file' in text
    assert doc['gyroscope_noise_density'] > 0 and doc['gyroscope_random_walk'] > 0


def test_kalibr_never_writes_a_missing_or_zero_density(tmp_path):
    from gyro_noise_ros.analysis.imu_yaml import kalibr_noise, write_imu_yaml

    tau = _octaves(0.0625, 0.5)     # taus stop before 1 s, and the curve has no -1/2 region
    res = _curve(tau, b=1e-4, k=1e-3)
    r = read_allan(res)
    assert math.isnan(r.arw_rad_per_sqrt_s)
    noise = kalibr_noise({'x': r, 'y': None})
    assert noise['noise_density'] is None and 'not measured' in noise['noise_density_note']
    write_imu_yaml(tmp_path / 'imu.yaml', rostopic='/imu', update_rate_hz=100.0,
                   gyroscope=noise)
    text = (tmp_path / 'imu.yaml').read_text()
    assert yaml.safe_load(text)['gyroscope_noise_density'] is None
    assert '# gyroscope_noise_density: not measured' in text
