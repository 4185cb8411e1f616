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

"""TFPF (paper 002 eqs. 24-27) and the sample-entropy classification of modes (Figure 13)."""

from math import erf, log

from _thermal_reference import tfpf_peak_loop
from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.classify import classify_modes, coarse_grain
from gyro_noise_ros.thermal.entropy import sample_entropy
from gyro_noise_ros.thermal.tfpf import tfpf
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
import pytest


def _snr_db(clean, est):
    return 10 * np.log10(np.sum(clean ** 2) / np.sum((est - clean) ** 2))


@pytest.mark.parametrize('window,min_gain_db', [(11, 5.0), (31, 8.0)])
def test_tfpf_snr_gain(window, min_gain_db):
    rng = np.random.default_rng(0)
    t = np.arange(4000)
    clean = np.sin(2 * np.pi * t / 400)
    noisy = clean + 0.3 * rng.standard_normal(t.size)
    gain = _snr_db(clean, tfpf(noisy, window=window)) - _snr_db(clean, noisy)
    # A Hamming-weighted smoother over L samples keeps about 1 / (0.55 L) of white noise
    # power, 10 log10(0.55 L) = 7.8 dB (L = 11) and 12.3 dB (L = 31) at most; the bounds leave
    # about 3-4 dB for the peak-picking noise and the sine's curvature over the window.
    assert gain > min_gain_db


def test_tfpf_unbiased_for_linear_signal():
    ramp = 0.01 * np.arange(2000.0)
    out = tfpf(ramp, window=31)
    # PWVD peaks exactly at a linear instantaneous frequency; what is left is the parabolic
    # refinement between FFT bins (< 1/2 bin = 1/256 cycles/sample, reduced ~10x by the
    # parabola) scaled back: 1e-3 of the 20-unit range.
    assert np.max(np.abs(out - ramp)[20:-20]) < 1e-3 * 20


def test_tfpf_matches_direct_sum():
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.standard_normal(300)) * 0.1 + rng.standard_normal(300) * 0.2
    out = tfpf(x, window=15, nfft=64)
    span = x.max() - x.min()
    for n in (40, 150, 260):
        # Fine-grid argmax vs FFT + parabola: both within half a coarse bin of the true
        # peak, 1 / (4 * 64) cycles/sample, i.e. span / 0.4 / 256 in signal units.
        assert out[n] == pytest.approx(tfpf_peak_loop(x, n, 15, grid=4096),
                                       abs=span / 0.4 / 256)


def test_tfpf_options():
    with pytest.raises(ParameterError):
        tfpf(np.ones(10), window=4)
    with pytest.raises(ParameterError):
        tfpf(np.arange(10.0), band=(0.3, 0.2))
    assert np.array_equal(tfpf(np.full(20, 3.0)), np.full(20, 3.0))


def test_classification_rule():
    rng = np.random.default_rng(2)
    n = 6000
    t = np.arange(n)
    drift = np.tanh((t - n / 2) / (n / 6))
    noise = rng.standard_normal(n)
    # A slow oscillation three times the noise: coarse-grained (q = 3) the noise std drops to
    # 0.58 against a tolerance of 0.2 x 2.3, so the entropy sits between the thresholds.
    mixed = 3 * np.sin(2 * np.pi * t / 2000) + rng.standard_normal(n)
    res = classify_modes([noise, drift, mixed], [0.3, 0.0, 0.1], max_samples=2000)
    assert res.classes == ('noise', 'drift', 'mixed')
    assert res.scale == 3
    # Entropies are those of the coarse-grained modes.
    assert res.sample_entropy[0] == sample_entropy(coarse_grain(noise, 3))
    # White noise coarse-grained stays white: -ln erf(0.1) = 2.197 within the sampling
    # spread of 2000 samples (about 0.1).
    assert res.sample_entropy[0] == pytest.approx(-log(erf(0.1)), abs=0.15)
    assert list(res.mask('drift')) == [False, True, False]


def test_lowest_mode_is_always_drift():
    rng = np.random.default_rng(3)
    res = classify_modes(rng.standard_normal((2, 500)), [0.01, 0.2])
    assert res.classes == ('drift', 'noise')
    with pytest.raises(ParameterError):
        classify_modes(np.ones((2, 50)), [0.0, 0.1], drift_max=2.0, noise_min=1.0)


def _mixed_band_case(seed, amplitude=0.6, n=24000):
    """Drift + a tone at 0.01 cycles/sample + unit white noise; VMD into 3 modes around them."""
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    drift = 3 * np.tanh((t - n / 2) / (n / 8))
    tone = amplitude * np.sin(2 * np.pi * 0.01 * t + 0.3)
    dec = vmd(drift + tone + rng.standard_normal(n), k=3, alpha=10000, solver='exact',
              max_iter=50, center_freqs=[0.0, 0.01, 0.25])
    # with the centre frequencies fixed, one exact sweep is a linear filter bank: the tone's
    # own share of each mode, the clean part of the mixed band
    clean = vmd(tone, k=3, alpha=10000, solver='exact', max_iter=1,
                center_freqs=dec.center_freqs).modes
    return dec, clean


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_a_known_mixed_band_is_classed_mixed_and_tfpf_cleans_it(seed):
    dec, clean = _mixed_band_case(seed)
    res = classify_modes(dec.modes, dec.center_freqs, scale=16)
    # the middle mode holds the tone (0.6 of the noise's std) and the noise of its band;
    # coarse-grained by 16 (6 points per period) the tone stays and the noise averages down:
    # entropy 0.90-0.99 measured on seeds 0-5, between drift_max and noise_min (0.5, 1.5);
    # the top mode is white (2.06-2.17)
    assert res.classes == ('drift', 'mixed', 'noise')
    mixed = dec.modes[1]
    err_before = np.sqrt(np.mean((mixed - clean[1]) ** 2))
    filtered = tfpf(mixed, window=31)
    err_after = np.sqrt(np.mean((filtered - clean[1]) ** 2))
    # TFPF changes the mode (by 6.6-6.9 % of its rms on seeds 0-5) and brings it closer to the
    # tone: the error to the clean part falls from 0.145-0.152 to 0.131-0.138 (0.7-0.9 dB, a
    # ratio of 0.90-0.93); the bounds sit outside that spread
    assert np.sqrt(np.mean((filtered - mixed) ** 2)) > 0.05 * np.std(mixed)
    assert err_after < 0.95 * err_before


def test_without_the_tone_the_band_is_noise():
    dec, _ = _mixed_band_case(0, amplitude=0.0)
    res = classify_modes(dec.modes, dec.center_freqs, scale=16)
    assert res.classes == ('drift', 'noise', 'noise')


def test_fixed_scale_pools_windows():
    rng = np.random.default_rng(7)
    x = rng.standard_normal(9000)
    whole = classify_modes(x[None, :], [0.2], scale=3, max_samples=3000)
    pooled = classify_modes(x[None, :], [0.2], scale=3, max_samples=1000)
    # 3000 coarse samples in one window or three: white noise reads -ln erf(0.1) either way
    # (the pooled estimate drops the cross-window pairs only; both within ~0.1 of 2.197)
    assert whole.sample_entropy[0] == pytest.approx(-log(erf(0.1)), abs=0.12)
    assert pooled.sample_entropy[0] == pytest.approx(-log(erf(0.1)), abs=0.12)
    assert whole.scale == pooled.scale == 3
    with pytest.raises(ParameterError):
        classify_modes(x[None, :20], [0.2], scale=10)
