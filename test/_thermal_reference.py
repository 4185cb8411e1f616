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

"""Slow, obviously-correct twins of the thermal algorithms (test oracles only)."""

from itertools import permutations
from math import exp, log

import numpy as np


def fuzzy_entropy_loop(x, m=2, r=0.2, theta=2.0):
    """Eqs. 8-15 written out pair by pair."""
    x = list(map(float, x))
    n = len(x)
    width = r * float(np.std(x))

    def phi(dim):
        vecs = []
        for p in range(n - m):
            seg = x[p:p + dim]
            mean = sum(seg) / dim
            vecs.append([v - mean for v in seg])
        total = 0.0
        for p in range(n - m):
            inner = 0.0
            for q in range(n - m):
                if q == p:
                    continue
                d = max(abs(a - b) for a, b in zip(vecs[p], vecs[q]))
                inner += exp(-(d / width) ** theta)
            total += inner / (n - m - 1)
        return total / (n - m)

    return log(phi(m)) - log(phi(m + 1))


def permutation_entropy_loop(x, order=3, delay=1):
    """Eqs. 16-22: count ordinal patterns one by one, normalised by ln(order!)."""
    x = list(map(float, x))
    counts = dict.fromkeys(permutations(range(order)), 0)
    n_vec = len(x) - (order - 1) * delay
    for i in range(n_vec):
        vals = [x[i + j * delay] for j in range(order)]
        pattern = tuple(sorted(range(order), key=lambda j: (vals[j], j)))
        counts[pattern] += 1
    h = 0.0
    for c in counts.values():
        if c:
            p = c / n_vec
            h -= p * log(p)
    return h / log(len(counts))


def sample_entropy_loop(x, m=2, r=0.2):
    """Richman-Moorman sample entropy, first n - m templates, Chebyshev distance < r std."""
    x = list(map(float, x))
    tol = r * float(np.std(x))
    n = len(x)
    a = b = 0
    for p in range(n - m):
        for q in range(p + 1, n - m):
            if max(abs(x[p + i] - x[q + i]) for i in range(m)) < tol:
                b += 1
                if max(abs(x[p + i] - x[q + i]) for i in range(m + 1)) < tol:
                    a += 1
    return -log(a / b)


def vmd_loop(signal, k, alpha, tau=0.0, tol=1e-7, max_iter=500):
    """
    VMD as in the authors' reference code: full two-sided FFT, shifted, loops over modes.

    Uniform initial centre frequencies, mirrored signal, modes updated one after the other
    (eq. 4 with the reference code's ``1 + alpha (f - f_k)^2``), eq. 5, eq. 6, eq. 7.
    """
    f = np.asarray(signal, dtype=float)
    n = f.size
    half = n // 2
    ext = np.concatenate([f[:half][::-1], f, f[half:][::-1]])
    t_len = ext.size
    freqs = np.arange(t_len) / t_len - 0.5
    f_hat = np.fft.fftshift(np.fft.fft(ext))
    f_hat_plus = f_hat.copy()
    f_hat_plus[:t_len // 2] = 0
    u = np.zeros((k, t_len), dtype=complex)
    omega = np.array([0.5 * i / k for i in range(k)])
    lam = np.zeros(t_len, dtype=complex)
    pos = slice(t_len // 2, t_len)
    for _ in range(max_iter):
        u_old = u.copy()
        for i in range(k):
            others = sum(u[j] for j in range(k) if j != i)
            u[i] = (f_hat_plus - others - lam / 2) / (1 + alpha * (freqs - omega[i]) ** 2)
            power = np.abs(u[i, pos]) ** 2
            omega[i] = np.dot(freqs[pos], power) / power.sum()
        lam = lam + tau * (u.sum(axis=0) - f_hat_plus)
        change = sum(np.sum(np.abs(u[i] - u_old[i]) ** 2)
                     / max(np.sum(np.abs(u_old[i]) ** 2), 1e-300) for i in range(k))
        if _ > 0 and change < tol:
            break
    modes = []
    for i in range(k):
        full = np.zeros(t_len, dtype=complex)
        full[pos] = u[i, pos]
        # Hermitian completion of the one-sided spectrum (Nyquist bin left at zero).
        full[1:t_len // 2] = np.conj(u[i, pos][1:][::-1])
        modes.append(np.real(np.fft.ifft(np.fft.ifftshift(full)))[half:half + n])
    order = np.argsort(omega)
    return np.array(modes)[order], omega[order]


def tfpf_peak_loop(x, n, window, band=(0.05, 0.45), grid=8192):
    """TFPF estimate at interior sample n: eq. 26 summed term by term on a fine grid."""
    x = np.asarray(x, dtype=float)
    lo, hi = x.min(), x.max()
    f_lo, f_hi = band
    s = f_lo + (f_hi - f_lo) * (x - lo) / (hi - lo)
    half = window // 2
    h = np.hamming(window)

    def phase(i):
        return float(np.sum(s[:i])) + 0.5 * s[i]

    best_f, best_w = 0.0, -np.inf
    for g in range(grid):
        f = 0.5 * g / grid
        w = 0.0
        for tau in range(-half, half + 1):
            w += h[tau + half] * np.cos(2 * np.pi * (phase(n + tau) - phase(n - tau))
                                        - 4 * np.pi * f * tau)
        if w > best_w:
            best_f, best_w = f, w
    return lo + (best_f - f_lo) / (f_hi - f_lo) * (hi - lo)


def elman_forward_loop(theta, x, n1, n2):
    """Eq. 33 with explicit matrices: unpack the weight vector, run the recurrence."""
    theta = list(map(float, theta))
    n_in = len(x[0])

    def take(rows, cols):
        nonlocal theta
        block = np.array(theta[:rows * cols]).reshape(rows, cols)
        theta = theta[rows * cols:]
        return block

    w1, w2, ai = take(n1, n1), take(n1, n_in), take(n1, 1)[:, 0]
    w3, w4, aj = take(n2, n1), take(n2, n2), take(n2, 1)[:, 0]
    w5, ak = take(1, n2)[0], take(1, 1)[0, 0]

    def sig(v):
        return 1.0 / (1.0 + np.exp(-v))

    ic, ih = np.full(n1, 0.5), np.full(n2, 0.5)
    out = []
    for row in x:
        oi = sig(w1 @ ic + w2 @ np.asarray(row, dtype=float) - ai)
        oh = sig(w3 @ oi + w4 @ ih - aj)
        out.append(float(w5 @ oh - ak))
        ic, ih = oi, oh
    return np.array(out)
