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
Bias-instability interval (paper 001 section 6): closed-form curves, open ends, real data.

Oracles: piecewise power laws (straight in log-log, so the interpolated crossing is exact), the
IEEE 952 white + flicker + random-walk curve (crossings from a quadratic), and on the real
ADIS16405 record an independent per-crossing interpolation twin.
"""

from _realdata import real_data
from gyro_noise_ros.calibration.interval import bias_instability_interval, compare, Interval
from gyro_noise_ros.core.allan import allan_deviation
from gyro_noise_ros.core.readout import MAX_TAU_FRACTION
from gyro_noise_ros.errors import ParameterError
import numpy as np
import pytest


def _grid(per_decade, lo=1e-2, hi=1e4):
    return np.logspace(np.log10(lo), np.log10(hi), int(np.log10(hi / lo) * per_decade) + 1)


def test_piecewise_power_law_crossings_are_exact():
    tau = _grid(10)
    a, b, k = 0.1, 0.01, 1e-3          # white 0.1/sqrt(tau), floor 0.01, rise 1e-3 sqrt(tau)
    sig = np.maximum.reduce([a / np.sqrt(tau), np.full_like(tau, b), k * np.sqrt(tau)])
    iv = bias_instability_interval(tau, sig, c=2.0)
    # the crossing points lie on the straight flanks: a/sqrt(lo) = 2b, k sqrt(hi) = 2b
    assert iv.lo_s == pytest.approx((a / (2 * b)) ** 2, rel=1e-12)
    assert iv.hi_s == pytest.approx((2 * b / k) ** 2, rel=1e-12)
    assert iv.sigma_min == b and iv.level == 2 * b and iv.closed and iv.reason == ''
    iv3 = bias_instability_interval(tau, sig, c=3.0)
    assert iv3.lo_s == pytest.approx((a / (3 * b)) ** 2, rel=1e-12)
    assert iv3.width_s > iv.width_s


def test_ieee952_curve_against_the_quadratic():
    n, bi, k = 2e-3, 1e-4, 2e-6       # N (1/sqrt(s)), plateau B' (flat), K (per sqrt(s))
    tau = _grid(200, hi=1e6)

    def avar(t):
        return n * n / t + bi * bi + k * k * t / 3.0

    sig = np.sqrt(avar(tau))
    iv = bias_instability_interval(tau, sig, c=2.0)
    # minimum of N^2/t + K^2 t/3 at t* = sqrt(3) N / K; crossings: (K^2/3) t^2 + (B'^2 - L^2) t
    # + N^2 = 0 with L = 2 sigma_min (sigma_min taken from the same grid, as the code must)
    level2 = iv.level ** 2
    roots = np.sort(np.roots([k * k / 3.0, bi * bi - level2, n * n]).real)
    # 200 points per decade: log-log chords of this smooth curve are within ~1e-5 relative
    assert iv.lo_s == pytest.approx(roots[0], rel=1e-4)
    assert iv.hi_s == pytest.approx(roots[1], rel=1e-4)
    assert iv.tau_min_s == pytest.approx(np.sqrt(3) * n / k, rel=0.02)


def test_open_ends_are_never_invented():
    tau = _grid(10)
    white = bias_instability_interval(tau, 0.1 / np.sqrt(tau))
    assert white.hi_s is None and white.lo_s is not None and white.width_s is None
    assert 'upper end open' in white.reason
    walk = bias_instability_interval(tau, 1e-3 * np.sqrt(tau))
    assert walk.lo_s is None and walk.hi_s is not None and 'lower end open' in walk.reason
    flat = bias_instability_interval(tau, 1 + 0.1 * np.sin(np.log(tau)))
    assert flat.lo_s is None and flat.hi_s is None and not flat.closed
    short = bias_instability_interval(tau[:4], 0.1 / np.sqrt(tau[:4]))
    assert short.lo_s is None and 'record too short' in short.reason
    # zeros (an all-zero channel) and NaN are not a curve
    assert 'too short' in bias_instability_interval(tau, np.zeros_like(tau)).reason
    with pytest.raises(ParameterError):
        bias_instability_interval(tau, tau, c=1.0)


def test_verdict():
    def iv(lo, hi, sd=0.1):
        return Interval(lo, hi, 1.0, 1.0, 2.0, 2.0, '' if hi else 'upper end open',
                        width_sd_log=sd, record_s=3600.0)
    # paper: 420 s -> 945 s (+125 %); with 10 % per width the one-sided 95 % bound is +87 %
    v = compare(iv(1.0, 421.0), iv(1.0, 946.0))
    assert v.verdict == 'beyond' and v.change == pytest.approx(1.25)
    assert v.log_ratio_sd == pytest.approx(0.1 * np.sqrt(2)) and v.ci[0] > 0.5
    assert v.change_sd == pytest.approx(2.25 * 0.1 * np.sqrt(2))
    # the same +125 % with 40 % per width cannot be told from +50 %: undetermined, and records
    # (1.645 * 0.566 / (log 2.25 - log 1.5))^2 = 5.3 times as long would decide it
    v = compare(iv(1.0, 421.0, 0.4), iv(1.0, 946.0, 0.4))
    assert v.verdict == 'undetermined' and 'straddles' in v.reason
    k = (1.6449 * 0.4 * np.sqrt(2) / np.log(1.5)) ** 2
    assert v.decide_record_s[0] == pytest.approx(k * 3600.0, rel=1e-3)
    assert compare(iv(1.0, 101.0), iv(1.0, 111.0)).verdict == 'physiological'
    assert compare(iv(1.0, 101.0), iv(1.0, 40.0)).verdict == 'beyond'
    v = compare(iv(1.0, 101.0), iv(1.0, None))
    assert v.verdict == 'undetermined' and v.change is None and 'after: upper end open' in v.reason
    assert compare(None, iv(1.0, 5.0)).reason == 'no before record'
    # no uncertainty, no verdict
    v = compare(iv(1.0, 421.0, float('nan')), iv(1.0, 946.0))
    assert v.verdict == 'undetermined' and 'no uncertainty' in v.reason


def _twin_crossing(tau, sig, level, j):
    # independent: interpolate log(tau) as a function of log(sigma) on the segment [j, j + 1]
    xs = np.log([sig[j], sig[j + 1]])
    ys = np.log([tau[j], tau[j + 1]])
    order = np.argsort(xs)
    return float(np.exp(np.interp(np.log(level), xs[order], ys[order])))


@pytest.mark.parametrize('sensor', ['gyro_dps', 'accel_g'])
def test_real_adis16405_record(sensor):
    data = np.load(real_data('adis16405_static', 'adis_16405_imu1.npz'))[sensor]
    for ax in range(3):
        res = allan_deviation(data[:, ax], 100.0, taus='dense')
        iv = bias_instability_interval(res.tau_s, res.adev)
        tau, sig = res.tau_s, res.adev
        i = int(np.argmin(sig))
        assert iv.tau_min_s == tau[i] and iv.level == 2 * sig[i]
        assert iv.lo_s is not None            # 100 Hz white noise always starts far above
        j = int(np.flatnonzero(sig[:i] >= iv.level)[-1])
        assert iv.lo_s == pytest.approx(_twin_crossing(tau, sig, iv.level, j), rel=1e-12)
        assert tau[j] <= iv.lo_s <= tau[j + 1]
        if iv.hi_s is None:
            assert np.all(sig[i:] < iv.level)
            continue
        k = i + int(np.flatnonzero(sig[i:] >= iv.level)[0])
        assert iv.hi_s == pytest.approx(_twin_crossing(tau, sig, iv.level, k - 1), rel=1e-12)
        inside = (tau > iv.lo_s) & (tau < iv.hi_s)
        assert np.all(sig[inside] < iv.level)


def test_real_repeat_runs_are_never_beyond():
    # three 2.78 h runs of one ADIS16405 at rest, same conditions: the Z accelerometer's interval
    # closes in every run; an unchanged sensor must never be called beyond, and the differences
    # between runs are what the stated uncertainty says (within 2.5 sigma)
    ivs = []
    for run in (1, 2, 3):
        z = np.load(real_data('adis16405_static', f'adis_16405_imu{run}.npz'))['accel_g'][:, 2]
        res = allan_deviation(z, 100.0, taus='dense')
        record_s = z.size / 100.0
        ivs.append(bias_instability_interval(res.tau_s, res.adev, edf=res.edf,
                                             max_tau_s=MAX_TAU_FRACTION * record_s,
                                             record_s=record_s))
    assert all(iv.closed and np.isfinite(iv.width_sd_log) for iv in ivs)
    for a, b in ((0, 1), (0, 2), (1, 2)):
        v = compare(ivs[a], ivs[b])
        assert v.verdict != 'beyond', v
        assert abs(v.log_ratio) < 2.5 * v.log_ratio_sd, v


def test_low_edf_tail_cannot_hold_sigma_min():
    tau = _grid(10, hi=1e3)
    sig = np.maximum.reduce([0.1 / np.sqrt(tau), np.full_like(tau, 0.01), 1e-3 * np.sqrt(tau)])
    sig[-1] = 0.004                      # a last tau with 1-2 degrees of freedom dips far down
    edf = np.where(np.arange(tau.size) < tau.size - 1, 50.0, 1.5)
    plain = bias_instability_interval(tau, sig)
    assert plain.sigma_min == 0.004 and plain.tau_min_s == tau[-1]
    robust = bias_instability_interval(tau, sig, edf=edf, min_edf=10.0)
    assert robust.sigma_min == 0.01
    assert robust.lo_s == pytest.approx(25.0, rel=1e-12)     # (0.1 / 0.02)^2, as without the dip
    # with the dip at the end the upper crossing is still found where the curve rises
    assert robust.hi_s == pytest.approx(400.0, rel=1e-12)
    none = bias_instability_interval(tau, sig, edf=np.zeros_like(tau), min_edf=10.0)
    assert 'degrees of freedom' in none.reason
    # the readout's rule alone (the default): taus up to a tenth of the record hold sigma_min
    tenth = bias_instability_interval(tau, sig, edf=edf, max_tau_s=100.0)
    assert tenth.sigma_min == 0.01 and tenth.hi_s == pytest.approx(400.0, rel=1e-12)
