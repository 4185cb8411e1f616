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
Slow, obviously-correct twins of gyro_noise_ros.core.fractional (paper 000 eqs. 3-14): the oracle.

Each step is written as the paper states it, with no FFT and no shared code with the package:
coefficients from the binomial definition (eq. 4), the truncated sum (eqs. 3, 5) by direct
convolution, f by the pseudoinverse (eq. 8), the biased autocorrelation (eq. 14) by direct
correlation.
"""

import numpy as np
from scipy.special import binom


def gl_coefficients_ref(alpha, memory):
    """(-1)^j binom(alpha, j) for j = 0..L (eq. 4 with the sign of eq. 3)."""
    j = np.arange(memory + 1)
    return (-1.0) ** j * binom(alpha, j)


def gl_difference_loop(x, alpha, memory):
    """Eq. (3) with L(k) = min(k, L) (eq. 5), as two nested loops (small inputs only)."""
    c = gl_coefficients_ref(alpha, memory)
    out = np.zeros(len(x))
    for k in range(len(x)):
        for j in range(min(k, memory) + 1):
            out[k] += c[j] * x[k - j]
    return out


def curves_ref(v, alphas, memory, *, demean=True, max_lag=None):
    """Return (var_curve, j_curve, f_curve) computed per order with numpy.convolve / correlate."""
    v = np.asarray(v, dtype=np.float64)
    if demean:
        v = v - v.mean()
    big_n = len(v)
    n = big_n - 1
    max_lag = n - 1 if max_lag is None else max_lag
    var_c, j_c, f_c = [], [], []
    for alpha in alphas:
        c = gl_coefficients_ref(alpha, memory)
        diff = np.convolve(v, c)[:big_n]        # Delta^alpha v[k], k = 0..N-1 (direct method)
        d = diff[1:]                            # D(alpha, k+1), eq. (7)
        w_reg = v[:-1]                          # W(k), eq. (7)
        f = (np.linalg.pinv(w_reg[:, None]) @ d).item()   # eq. (8)
        w = d - f * w_reg                       # eq. (9)
        r = np.correlate(w, w, mode='full')[n - 1:] / n   # eq. (14), biased, lags 0..n-1
        var_c.append(np.var(w))
        j_c.append(np.sum(np.abs(r[:max_lag + 1])))       # eq. (13)
        f_c.append(f)
    return np.array(var_c), np.array(j_c), np.array(f_c)
