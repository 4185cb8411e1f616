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

"""Signatures, band/gap, effect templates and the baseline fit of the discrepancy workflow."""

from gyro_noise_ros.core.allan import allan_deviation, allan_deviation_values
from gyro_noise_ros.core.fractional import gl_coefficients
from gyro_noise_ros.core.simulate import (
    check_stability,
    gauss_markov_avar,
    simulate_fractional_noise,
)
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.explain import signatures as sig
from gyro_noise_ros.explain.baseline import fit_baseline, model_gain, simulation_memory, stable
from gyro_noise_ros.explain.effects import (
    allan_template_from_psd,
    flicker_noise,
    null_exceeded,
)
import numpy as np
import pytest
import scipy.signal


def test_welch_equals_scipy():
    x = np.random.default_rng(1).standard_normal(20001) + 5.0
    f1, p1 = sig.welch(x, 250.0, 1024)
    f2, p2 = scipy.signal.welch(x - x.mean(), fs=250.0, window='hann', nperseg=1024, detrend=False)
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_allclose(p1, p2, rtol=1e-12)


def test_allan_signature_is_the_core_estimator_bit_for_bit():
    # One Allan estimator: the signature at the layout's half-octave factors is core.allan's
    # fully overlapping deviation, the same bits as allan_deviation(...).adev
    x = np.random.default_rng(2).standard_normal(50000) * 1e-3 + 0.01
    layout = sig.make_layout(x, 100.0)
    ours = sig.compute(layout, x, None)['allan']
    np.testing.assert_array_equal(ours, allan_deviation(x, 100.0, taus=layout.m).adev)
    np.testing.assert_array_equal(ours, allan_deviation_values(x, 100.0, taus=layout.m))
    assert layout.m[0] == 1 and layout.m[-1] <= x.size // 10


def test_allan_values_refuse_what_allan_deviation_refuses():
    with pytest.raises(ParameterError):
        allan_deviation_values(np.ones(100), 0.0, taus=[1])
    with pytest.raises(InputDataError, match='NaN'):
        allan_deviation_values(np.array([1.0, np.nan, 2.0, 3.0, 4.0]), 1.0)


def test_find_lattice_exact_and_round_off():
    rng = np.random.default_rng(4)
    x = rng.standard_normal(30000) * 1e-3
    step, offset = 2.7e-4, 1.1e-4
    q = offset + step * np.round((x - offset) / step)
    found = sig.find_lattice(q)
    assert found is not None
    assert found[0] == pytest.approx(step, rel=1e-6)
    assert np.mod(found[1] - offset + step / 2, step) - step / 2 == pytest.approx(0.0, abs=1e-9)
    # 9 significant digits in a text file (the MPU6050 CSV) must not hide the lattice
    assert sig.find_lattice(np.array([float(f'{v:.9g}') for v in q])) is not None
    assert sig.find_lattice(x) is None


def test_compare_leave_one_out_and_gap():
    rng = np.random.default_rng(5)
    members = rng.standard_normal((12, 30)) + 10.0
    comp = sig.compare('chunk_bias', members.mean(axis=0), members)
    assert comp.g == 0.0 and comp.gap == 0.0
    # the closed-form leave-one-out threshold equals an explicit loop
    d = []
    for j in range(12):
        others = np.delete(members, j, axis=0)
        d.append(np.max(np.abs(members[j] - others.mean(0)) / others.std(0, ddof=1)))
    d = np.array(d)
    expect = max(sig.MIN_THRESHOLD, d.max(), np.exp(np.log(d).mean() + sig.BAND_K
                                                    * np.log(d).std(ddof=1)))
    assert comp.threshold == pytest.approx(expect, rel=1e-9)
    far = members.mean(axis=0).copy()
    far[7] += 50 * members[:, 7].std(ddof=1)
    comp = sig.compare('chunk_bias', far, members)
    assert comp.g > 1 and comp.outside[7] and comp.outside.sum() == 1
    assert sig.total_gap({'chunk_bias': comp}) == pytest.approx(np.log(comp.g))


def test_gm_closed_form_matches_psd_integral():
    # two-sided Lorentzian of a first-order Markov process, sd 1, correlation time 2 s (IEEE 952)
    tc = 2.0
    tau = np.geomspace(0.05, 50, 12)
    integral = allan_template_from_psd(lambda f: 2 * tc / (1 + (2 * np.pi * f * tc) ** 2), tau,
                                       1e4, 1e5)
    # the integral is truncated at fs/2 and 1/T; the bounds are far outside the Lorentzian's corner
    np.testing.assert_allclose(gauss_markov_avar(tau, 1.0, tc), integral, rtol=0.02)


def test_flicker_template_floor_and_simulation():
    tau = np.array([1.0, 10.0])
    floor = np.sqrt(allan_template_from_psd(lambda f: 1 / (2 * np.pi * f), tau, 100.0, 6000.0))
    # IEEE 952: sigma = sqrt(2 ln 2 / pi) B = 0.664 B on the flat part
    np.testing.assert_allclose(floor, 0.664, rtol=0.02)
    rng = np.random.default_rng(6)
    m = np.array([100, 1000])
    adev = np.mean([allan_deviation_values(flicker_noise(200000, 100.0, 1.0, rng), 100.0, taus=m)
                    for _ in range(8)], axis=0)
    # 8 records of 2000 s: the ADEV at 10 s has ~200 independent averages per record, so the mean
    # over 8 records is within ~5 %; 10 % allows for the low-frequency cut of the finite record
    np.testing.assert_allclose(adev, 0.664, rtol=0.10)


def test_null_exceeded():
    null = np.array([0.0, 0.1, 0.3, 0.2, 0.0, 0.5, 0.1, 0.2])
    assert not null_exceeded(0.5, null)
    assert null_exceeded(10.0, null)


def test_simulation_memory_keeps_psd_within_one_percent():
    for alpha, f in ((1.04, -0.87), (0.8, -0.7), (1.2, -0.9)):
        memory = simulation_memory(alpha, f, 1000.0)
        assert memory <= 1000
        freq = np.geomspace(0.1, 500.0, 200)
        ratio = model_gain(
            alpha, f, memory, freq, 1000.0) / model_gain(alpha, f, 1000, freq, 1000.0)
        assert np.max(np.abs(ratio - 1)) <= 0.0101


def test_model_gain_and_stability_shortcut_equal_their_slow_twins():
    # model_gain keeps the FFT of the GL coefficients per (alpha, L) and adds -f e^{-iw}; the
    # slow twin takes one FFT of the full polynomial per call. stable() decides by a
    # coefficient-sum bound where it can, else asks core; it must agree with core everywhere,
    # unstable and marginal pairs included (f beyond S_L(alpha), alpha far from 1)
    rng = np.random.default_rng(11)
    freq = np.geomspace(0.01, 50.0, 300)
    grid = np.arange(65537) * (100.0 / 131072)
    decided = []
    for _ in range(60):
        alpha, f = round(rng.uniform(-0.2, 1.9), 2), round(rng.uniform(-2.5, 1.0), 6)
        memory = int(rng.choice([25, 100, 1000]))
        a = gl_coefficients(alpha, memory)
        a[1] -= f
        slow = 1.0 / np.interp(freq, grid, np.abs(np.fft.rfft(a, 131072)) ** 2)
        # rounding only: the two sums differ in the last bits, near a pole relatively more
        np.testing.assert_allclose(model_gain(alpha, f, memory, freq, 100.0), slow, rtol=1e-9)
        decided.append(stable(alpha, f, memory))
        assert decided[-1] == check_stability(alpha, f, memory).stable, (alpha, f, memory)
    assert 0 < sum(decided) < len(decided)  # both answers were exercised


def test_fit_baseline_recovers_simulated_model():
    rng = np.random.default_rng(7)
    x = simulate_fractional_noise(80000, 1.0, -0.8, 1e-3, rng=rng, sigma_nu=3e-4, bias=0.02)
    model = fit_baseline(x, 1000.0)
    assert model.bias_rad_s == pytest.approx(0.02, abs=2e-5)
    # the identification grid is 0.01; chunk estimates of 8000 samples scatter by a few 0.01
    assert model.alpha == pytest.approx(1.0, abs=0.08)
    # the fit is judged above fs / 100 (baseline.py): there the model PSD must match the record's
    # Welch PSD; averaged over 8 decade-wide bands of ~100 bins x 38 segments each, the estimate
    # scatters by ~0.5 %, so 5 % leaves room for the 0.01-grid order and the errors-in-variables
    # bias of f (paper 000 eq. 12)
    freq, pxx = sig.welch(x, 1000.0, 2048)
    gain = model_gain(model.alpha, model.f, model.memory_sim, freq, 1000.0)
    model_psd = 2.0 / 1000.0 * (model.sigma_w_rad_s ** 2 * gain + model.sigma_nu_rad_s ** 2)
    edges = np.geomspace(10.0, 500.0, 9)
    for lo, hi in zip(edges[:-1], edges[1:]):
        band = (freq >= lo) & (freq < hi)
        assert pxx[band].mean() == pytest.approx(model_psd[band].mean(), rel=0.05)
    # the total variance, dominated by the same band, follows within 8 % (below fs / 100 the model
    # is extrapolated by its (alpha, f))
    sim = model.generator(np.random.default_rng(8)).generate(80000)
    assert np.var(sim) == pytest.approx(np.var(x), rel=0.08)


def test_uniform_counts_equal_numpy_histogram():
    x = np.random.default_rng(9).standard_normal(100001)
    x[:3] = [-4.0, 4.0, 0.5]  # the range ends and an inner edge exactly
    ours = sig._uniform_counts(x, -4.0, 4.0, 32)
    ref = np.histogram(x, bins=32, range=(-4.0, 4.0))[0]
    np.testing.assert_array_equal(ours, ref)
