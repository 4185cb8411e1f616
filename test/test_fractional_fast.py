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
The fast identification algorithms of core/fractional.py.

* 'fast' curves against the per-order numpy.convolve oracle (test/_fractional_reference.py) to
  1e-9 over chunk sizes, memories, grids (from 1 to 201 orders, so low-rank and full-rank
  coefficient matrices), demean and max_lag (correlation sizes that take the half-length cosine
  path, and even and odd sizes that do not), and the low-rank premise itself;
* 'exact' against a twin of the blocked algorithm of every earlier release (below), bit for bit;
* 'auto' (the default) against 'exact', bit for bit, including exact ties, every block position,
  other block sizes, and the fallback when the fast curves are off; the orders whose J it skips
  (sign bounds) are never a minimum, and the bounds are lower bounds of J.
"""

from _fractional_reference import curves_ref
from gyro_noise_ros.core import fractional
from gyro_noise_ros.core.fractional import gl_coefficients, make_grid, OrderIdentifier
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np
import pytest
import scipy.fft

RESULT_FIELDS = ('alpha_var', 'f_var', 'var_min', 'alpha_corr', 'f_corr', 'j_min',
                 'tied_alphas_var', 'tied_alphas_corr', 'bias')


def released_curves(v, alphas, memory, max_lag, block=8):
    """Return the curves of the blocked FFT algorithm as released up to commit 37cfcbf."""
    big_n = v.shape[0]
    n = big_n - 1
    max_lag = n - 1 if max_lag is None else max_lag
    conv = scipy.fft.next_fast_len(big_n + memory, real=True)
    corr = scipy.fft.next_fast_len(n + max_lag + 1, real=True)
    coeff_hat = scipy.fft.rfft(np.stack([gl_coefficients(a, memory) for a in alphas]), conv,
                               axis=1)
    w_reg = v[:-1]
    ww = float(w_reg @ w_reg)
    v_hat = scipy.fft.rfft(v, conv)
    k = len(alphas)
    var_c, j_c, f_c = np.empty(k), np.empty(k), np.empty(k)
    padded = np.zeros((block, corr))
    for start in range(0, k, block):
        stop = min(k, start + block)
        rows = stop - start
        diff = scipy.fft.irfft(coeff_hat[start:stop] * v_hat, conv, axis=1)
        d = diff[:, 1:n + 1]
        f = (d @ w_reg) / ww
        w = padded[:rows, :n]
        np.multiply(f[:, None], w_reg, out=w)
        np.subtract(d, w, out=w)
        var_c[start:stop] = w.var(axis=1)
        spec = scipy.fft.rfft(padded[:rows], axis=1)
        power = np.multiply(spec, spec.conj(), out=spec)
        r = scipy.fft.irfft(power, corr, axis=1)
        j_c[start:stop] = np.abs(r[:, :max_lag + 1]).sum(axis=1) / n
        f_c[start:stop] = f
    return var_c, j_c, f_c


def chunk(kind, size, seed):
    rng = np.random.default_rng(seed)
    if kind == 'white':
        return rng.standard_normal(size) * 1e-3 + 0.01
    if kind == 'walk':
        return np.cumsum(rng.standard_normal(size)) * 1e-4
    if kind == 'tone':
        t = np.arange(size)
        return np.sin(0.01 * t) * 1e-2 + rng.standard_normal(size) * 1e-4
    alpha = float(kind)
    return FractionalNoise(alpha, -0.5, 1e-3, rng=rng, memory=min(size, 500),
                           sigma_nu=1e-3).generate(size)


CASES = [
    # (chunk size, memory, grid, max_lag)
    (400, 50, make_grid(0.0, 2.0, 0.01), None),          # 201 orders, rank 15 of 51 columns
    (257, 1, make_grid(0.0, 2.0, 0.25), None),           # L = 1: rank 2, truncation at k >= 1
    (1200, 300, make_grid(0.3, 1.9, 0.1), None),
    (1200, 300, np.array([1.7, 0.2, 0.7, 1.2, 2.2]), 500),  # unsorted grid
    (90, 7, make_grid(0.0, 2.0, 0.05), 40),              # correlation size 135: odd
    (200, 30, make_grid(0.0, 2.0, 0.1), 50),             # correlation size 250: even, not 4k
    (501, 499, make_grid(0.0, 2.0, 0.1), 0),             # N = L + 2, one lag
    (300, 40, np.array([0.55]), None),                   # one order
]


@pytest.mark.parametrize('size,memory,alphas,max_lag', CASES)
@pytest.mark.parametrize('demean', [True, False])
def test_fast_curves_equal_the_oracle(size, memory, alphas, max_lag, demean):
    for kind in ('1.4', 'white', 'walk'):
        v = chunk(kind, size, seed=size + memory)
        fast = OrderIdentifier(size, alphas=alphas, memory=memory, demean=demean,
                               max_lag=max_lag, algorithm='fast')(v, curves=True)
        var_c, j_c, f_c = curves_ref(v, alphas, memory, demean=demean, max_lag=max_lag)
        # 1e-9: the requirement; the differences seen are 1e-15..1e-12 (rounding of
        # FFTs of a few thousand points, and of the coefficients' low-rank factors).
        np.testing.assert_allclose(fast.var_curve, var_c, rtol=1e-9)
        np.testing.assert_allclose(fast.j_curve, j_c, rtol=1e-9)
        np.testing.assert_allclose(fast.f_curve, f_c, rtol=1e-9, atol=1e-9 * np.abs(f_c).max())


@pytest.mark.parametrize('kind', ['1.4', 'walk'])
def test_fast_curves_equal_the_oracle_at_paper_size(kind):
    """N = 10,000, L = 1000, the default grid (rank 18 of 201); the oracle on every 20th order."""
    v = chunk(kind, 10000, seed=4)
    fast = OrderIdentifier(10000, algorithm='fast')(v, curves=True)
    every = slice(None, None, 20)
    var_c, j_c, f_c = curves_ref(v, fast.alphas[every], 1000)
    np.testing.assert_allclose(fast.var_curve[every], var_c, rtol=1e-9)
    np.testing.assert_allclose(fast.j_curve[every], j_c, rtol=1e-9)
    np.testing.assert_allclose(fast.f_curve[every], f_c, rtol=1e-9)


@pytest.mark.parametrize('memory,alphas', [(1000, make_grid(0.0, 2.0, 0.01)),
                                           (50, make_grid(0.0, 2.0, 0.01)),
                                           (300, make_grid(0.3, 1.9, 0.1))])
def test_low_rank_factors_reproduce_the_coefficients(memory, alphas):
    """The premise of 'fast': the kept singular triplets give every GL coefficient to rounding."""
    ident = OrderIdentifier(memory + 2, alphas=alphas, memory=memory)
    plan = fractional._FastPlan(ident)
    exact = np.stack([gl_coefficients(a, memory) for a in alphas])
    basis = np.fft.irfft(plan.basis_hat, plan.conv_size, axis=1)[:, :memory + 1]
    # |c_j| <= 1 and the dropped singular values are below eps x the largest (21 on the default
    # grid): every coefficient within 1e-14 absolute, a few times the rounding of the
    # recurrence that computes them
    np.testing.assert_allclose(plan.weights @ basis, exact, rtol=0, atol=1e-14)
    assert plan.rank <= 18  # what the speed rests on: 18 convolutions, not one per order


@pytest.mark.parametrize('size,memory,alphas,max_lag', CASES[:5])
@pytest.mark.parametrize('block', [8, 3])
def test_exact_is_the_released_algorithm_bit_for_bit(size, memory, alphas, max_lag, block):
    v = chunk('1.4', size, seed=7)
    v = v - v.mean()
    got = OrderIdentifier(size, alphas=alphas, memory=memory, max_lag=max_lag, block=block,
                          algorithm='exact')(v, curves=True)
    ref = released_curves(v - v.mean(), alphas, memory, max_lag, block)
    for a, b in zip((got.var_curve, got.j_curve, got.f_curve), ref):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize('block', [8, 5, 1])
def test_exact_rows_reproduce_the_blocks_bit_for_bit(block):
    """The premise of 'auto': one order recomputed alone rounds as inside its block."""
    alphas = make_grid(0.0, 2.0, 0.05)
    ident = OrderIdentifier(700, alphas=alphas, memory=60, block=block)
    for kind in ('0.6', 'walk'):
        v = chunk(kind, 700, seed=block)
        v = v - v.mean()
        curves = np.array(ident._curves(v))
        rows = np.arange(alphas.size)
        np.testing.assert_array_equal(ident._exact_rows(v, rows), curves)
        # and alone, or a few of a block: the other rows of the block are not computed
        for r in range(alphas.size):
            np.testing.assert_array_equal(ident._exact_rows(v, np.array([r])), curves[:, [r]])
        some = np.array([1, 2, 6, 11, 17, 23, 40])
        np.testing.assert_array_equal(ident._exact_rows(v, some), curves[:, some])


@pytest.mark.parametrize('kind', ['0.3', '0.9', '1.4', '1.9', 'white', 'walk', 'tone'])
def test_pruned_orders_can_be_no_minimum(kind, monkeypatch):
    """'auto' without curves computes J only where the sign bounds allow a minimum: check them."""
    alphas = make_grid(0.0, 2.0, 0.01)
    ident = OrderIdentifier(2000, alphas=alphas, memory=400)
    plan = fractional._FastPlan(ident)
    real, bounds = fractional._FastPlan._bounds, []

    def spy(*args):
        got = real(*args)
        bounds.append(got[1].copy())
        return got

    monkeypatch.setattr(fractional._FastPlan, '_bounds', spy)
    v = chunk(kind, 2000, 11)
    v = v - v.mean()
    _, j_pruned, _ = plan.curves(v, prune=True)
    _, j_full, _ = plan.curves(v)
    _, j_exact, _ = ident._curves(v)
    bound = np.full(alphas.size, -np.inf)
    bound[plan.others], = bounds
    # a lower bound of J: the two are sums over ~2000 lags by different transforms (1e-12 seen)
    assert np.all(bound <= j_exact * (1 + 1e-9))
    skipped = np.isinf(j_pruned)
    # what was skipped lies above the band of the minimum and its exact ties
    assert np.all(j_exact[skipped] > j_exact.min() * (1 + fractional.TIE_RTOL))
    # and J where it was computed is the fast value
    np.testing.assert_array_equal(j_pruned[~skipped], j_full[~skipped])
    # the point of it: most orders need no transform (fewer than 40 of 201 computed here)
    assert np.count_nonzero(~skipped) < 40


def same_results(a, b):
    return {k: (getattr(a, k), getattr(b, k)) for k in RESULT_FIELDS
            if getattr(a, k) != getattr(b, k)}


@pytest.mark.parametrize('kind', ['0.3', '0.9', '1.4', '1.9', 'white', 'walk', 'tone'])
def test_auto_results_are_exact_bit_for_bit(kind):
    alphas = make_grid(0.0, 2.0, 0.01)
    auto = OrderIdentifier(2000, alphas=alphas, memory=400)
    exact = OrderIdentifier(2000, alphas=alphas, memory=400, algorithm='exact')
    for seed in range(3):
        v = chunk(kind, 2000, seed)
        assert same_results(auto(v), exact(v)) == {}
    # with curves requested: the same results; the curves equal the exact ones to rounding,
    # bit for bit where the minimum can be, and each curve's minimum is the reported value
    got, ref = auto(v, curves=True), exact(v, curves=True)
    assert same_results(got, ref) == {}
    for name in ('var_curve', 'j_curve', 'f_curve'):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-9, atol=0)
    for curve, ref_curve, low in ((got.var_curve, ref.var_curve, ref.var_min),
                                  (got.j_curve, ref.j_curve, ref.j_min)):
        assert curve.min() == low
        at = np.flatnonzero(curve == low)
        np.testing.assert_array_equal(curve[at], ref_curve[at])


def test_auto_keeps_the_exact_tie_of_orders_zero_and_one():
    # White noise: orders 0 and 1 give the same residual (module doc), so the variance minimum
    # is a tie; 'auto' must report the same tie set and the same largest order as 'exact'.
    alphas = make_grid(0.0, 2.0, 0.05)
    v = chunk('white', 1500, 3)
    auto = OrderIdentifier(1500, alphas=alphas, memory=200)(v)
    exact = OrderIdentifier(1500, alphas=alphas, memory=200, algorithm='exact')(v)
    assert same_results(auto, exact) == {}
    assert len(exact.tied_alphas_var) >= 2 or len(exact.tied_alphas_corr) >= 2


def test_auto_falls_back_to_exact_when_the_fast_curves_are_off(monkeypatch):
    alphas = make_grid(0.0, 2.0, 0.05)
    ident = OrderIdentifier(1000, alphas=alphas, memory=100)
    exact = OrderIdentifier(1000, alphas=alphas, memory=100, algorithm='exact')
    v = chunk('1.4', 1000, 5)
    real = fractional._FastPlan.curves
    calls = []

    def off(self, x, **kwargs):
        var, j, f = real(self, x, **kwargs)
        calls.append(1)
        # off by 1e-6 relative everywhere, 10x the check of the recomputed orders
        return var * (1 + 1e-6), j, f

    monkeypatch.setattr(fractional._FastPlan, 'curves', off)
    spied = []
    real_curves = OrderIdentifier._curves

    def spy(self, x):
        spied.append(1)
        return real_curves(self, x)

    monkeypatch.setattr(OrderIdentifier, '_curves', spy)
    assert same_results(ident(v), exact(v)) == {}
    assert calls and len(spied) == 2  # the fallback of 'auto', and 'exact' itself

    def not_finite(self, x, **kwargs):
        var, j, f = real(self, x, **kwargs)
        j = j.copy()
        j[3] = np.nan
        return var, j, f

    monkeypatch.setattr(fractional._FastPlan, 'curves', not_finite)
    assert same_results(ident(v), exact(v)) == {}
    assert len(spied) == 4


@pytest.mark.parametrize('kind', ['1.9', 'tone'])
def test_auto_needs_no_fallback_when_a_variance_candidate_has_no_fast_j(kind, monkeypatch):
    """A candidate of the variance alone whose J a bound ruled out is no reason to fall back."""
    alphas = make_grid(0.0, 2.0, 0.01)
    auto = OrderIdentifier(2000, alphas=alphas, memory=400)
    exact = OrderIdentifier(2000, alphas=alphas, memory=400, algorithm='exact')
    spied, pruned = [], []
    real_curves, real_locate = OrderIdentifier._curves, OrderIdentifier._locate

    def spy(self, x):
        spied.append(1)
        return real_curves(self, x)

    def locate(self, x, var, j, f):
        rows = np.union1d(fractional._candidates(var), fractional._candidates(j))
        pruned.append(int(np.isinf(j[rows]).sum()))
        return real_locate(self, x, var, j, f)

    monkeypatch.setattr(OrderIdentifier, '_curves', spy)
    monkeypatch.setattr(OrderIdentifier, '_locate', locate)
    for seed in range(3):
        v = chunk(kind, 2000, seed)
        assert same_results(auto(v), exact(v)) == {}
    assert len(spied) == 3       # 'exact' itself, never the fallback of 'auto'
    assert min(pruned) >= 1      # the case: the variance's minimum had its J pruned each time

    # and should the exact J of such an order be in the band after all (a bound that failed),
    # 'auto' does not trust its location: it falls back
    real_rows = OrderIdentifier._exact_rows

    def lower_pruned(self, x, rows):
        out = real_rows(self, x, rows)
        _, j, _ = self._fast.curves(x, prune=True)
        out[1, np.isinf(j[rows])] = 0.5 * out[1].min()
        return out

    monkeypatch.setattr(OrderIdentifier, '_exact_rows', lower_pruned)
    v = chunk(kind, 2000, 0)
    assert same_results(auto(v), exact(v)) == {}
    assert len(spied) == 5


def test_unknown_algorithm_is_refused():
    with pytest.raises(fractional.ParameterError, match='algorithm'):
        OrderIdentifier(100, memory=10, algorithm='quick')
