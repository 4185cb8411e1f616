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

"""VMD (paper 002 eqs. 1-7): known signal, the reference-code twin, the exact solver."""

from _thermal_reference import vmd_loop
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
import pytest


def _known(n=1200, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    trend = 1e-3 * t
    tone1 = np.sin(2 * np.pi * 0.05 * t)
    tone2 = 0.5 * np.sin(2 * np.pi * 0.2 * t)
    noise = 0.05 * rng.standard_normal(n)
    return trend + tone1 + tone2 + noise, (trend, tone1, tone2)


def test_known_signal_recovered():
    x, (trend, tone1, tone2) = _known()
    r = vmd(x, k=3, alpha=2000, tol=1e-9)
    assert r.converged
    # Centre frequencies: trend near 0, tones at 0.05 and 0.2 cycles/sample. The tones'
    # estimates are power-weighted means over a mode's band: within 2 bins of the 2n-point
    # mirrored spectrum (1 / 2400 each) of the truth.
    assert r.center_freqs[0] < 0.005
    assert r.center_freqs[1:] == pytest.approx([0.05, 0.2], abs=2 / 2400)
    # Away from the ends (mirroring blurs the first and last few periods) each mode matches
    # its component to 10 % of the component's amplitude; the 0.05 noise spread over three
    # bands sets the floor.
    mid = slice(100, -100)
    for mode, truth, amp in zip(r.modes, (trend, tone1, tone2), (1.2, 1.0, 0.5)):
        assert np.max(np.abs(mode[mid] - truth[mid])) < 0.1 * amp
    # Modes sum to the signal up to the noise they leave out (tau = 0: no exact constraint).
    assert np.std(r.modes.sum(axis=0)[mid] - x[mid]) < 0.05


@pytest.mark.parametrize('k,alpha,tau', [(3, 2000, 0.0), (4, 500, 0.0), (3, 2000, 0.1)])
def test_matches_reference_twin(k, alpha, tau):
    x, _ = _known(301, seed=1)  # odd length: mirroring is asymmetric
    r = vmd(x, k=k, alpha=alpha, tau=tau, tol=1e-8, max_iter=300)
    modes, omega = vmd_loop(x, k, alpha, tau=tau, tol=1e-8, max_iter=300)
    # Same arithmetic in a different order (rfft vs shifted fft): rounding only.
    assert r.center_freqs == pytest.approx(omega, abs=1e-10)
    assert np.max(np.abs(r.modes - modes)) < 1e-9


def test_exact_solver_reaches_admm_point():
    x, _ = _known(800, seed=2)
    a = vmd(x, k=3, alpha=2000, tol=1e-12, max_iter=5000)
    e = vmd(x, k=3, alpha=2000, tol=1e-12, max_iter=5000, solver='exact')
    assert a.converged and e.converged
    # Both stop within tol of one stationary point; 1e-6 of the unit tone amplitude.
    assert e.center_freqs == pytest.approx(a.center_freqs, abs=1e-6)
    assert np.max(np.abs(e.modes - a.modes)) < 1e-4


def test_warm_start_and_options():
    x, _ = _known(600, seed=3)
    cold = vmd(x, k=3, alpha=2000, tol=1e-9)
    warm = vmd(x, k=3, alpha=2000, tol=1e-9, center_freqs=cold.center_freqs)
    assert warm.iterations < cold.iterations
    assert warm.center_freqs == pytest.approx(cold.center_freqs, abs=1e-4)
    dc = vmd(x, k=3, alpha=2000, dc=True)
    assert dc.center_freqs[0] == 0.0
    rnd1 = vmd(x, k=3, alpha=2000, init='random', rng=np.random.default_rng(7))
    rnd2 = vmd(x, k=3, alpha=2000, init='random', rng=np.random.default_rng(7))
    assert np.array_equal(rnd1.modes, rnd2.modes)
    capped = vmd(x, k=3, alpha=2000, max_iter=2)
    assert capped.iterations == 2 and not capped.converged


def test_bad_input():
    with pytest.raises(InputDataError):
        vmd([1.0, np.nan, 2.0, 3.0, 4.0], k=2, alpha=100)
    with pytest.raises(ParameterError):
        vmd(np.ones(10), k=0, alpha=100)
    with pytest.raises(ParameterError):
        vmd(np.ones(10), k=2, alpha=100, init='nope')
    with pytest.raises(ParameterError):
        vmd(np.ones(10), k=2, alpha=100, tau=0.1, solver='exact')
