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
Plain-numpy twins of the Allan kernels (slow, obviously correct; tests only).

Each function states the kernel it mirrors. No compensation tricks beyond what is said: these are
the textbook formulas (paper 001 eq. 7, SP 1065 eqs. 9 and 11, Riley & Greenhall lag-1 ACF).
"""

import numpy as np


def phase_longdouble(y, offset):
    """
    Twin of ``_integrate``.

    Prefix sums of y - offset in extended precision, rounded to float64.
    """
    acc = np.cumsum(np.asarray(y, dtype=np.longdouble) - np.longdouble(offset))
    return np.concatenate(([0.0], acc.astype(np.float64)))


def avar_from_phase(x, m, stride=1):
    """
    Twin of ``_avar_sums``.

    Mean of (x[i+2m] - 2x[i+m] + x[i])^2 / (2 m^2), i = 0, stride, ...
    """
    d = x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m]
    d = d[::stride]
    return float(np.sum(d * d) / (2.0 * m * m * d.size)), d.size


def avar_rate(y, m, *, overlapping=True, stride=None):
    """Overlapping (or non-overlapping, or strided) AVAR of rate samples y (unit tau0 cancels)."""
    y = np.asarray(y, dtype=np.float64)
    x = np.concatenate(([0.0], np.cumsum(y - y.mean())))
    if stride is None:
        stride = 1 if overlapping else m
    return avar_from_phase(x, m, stride)


def avar_naive(y, m):
    """Compute the overlapping AVAR with a plain cumulative sum of the raw samples (no offset)."""
    x = np.concatenate(([0.0], np.cumsum(np.asarray(y, dtype=np.float64))))
    return avar_from_phase(x, m, 1)[0]


def lag1_acf(z):
    """Lag-1 autocorrelation with the mean removed."""
    z = z - z.mean()
    return float(np.sum(z[:-1] * z[1:]) / np.sum(z * z))


def lag1_alpha(y, m):
    """
    Twin of the lag-1 ACF noise identification (Riley & Greenhall 2004) on rate data.

    Non-overlapping m-averages, least-squares line removed (np.polyfit), differenced until
    delta = r1 / (1 + r1) < 0.25 or d = 2; alpha = -round(2 delta) - 2 d. Returns (alpha, r1 at
    d=0).
    """
    y = np.asarray(y, dtype=np.float64)
    n = y.size // m
    z = y[:n * m].reshape(n, m).mean(axis=1)
    j = np.arange(n)
    z = z - np.polyval(np.polyfit(j, z, 1), j)
    first = None
    for d in range(3):
        r1 = lag1_acf(z)
        if first is None:
            first = r1
        delta = r1 / (1.0 + r1)
        if delta < 0.25 or d == 2:
            return int(-np.floor(2.0 * delta + 0.5) - 2 * d), first
        z = np.diff(z)
    raise AssertionError('unreachable')


def edf_white_fm_nonoverlapping(n_terms):
    """
    Exact EDF of the non-overlapping AVAR of white FM: terms d_j = z_{j+1} - z_j of iid averages.

    Var(d_j^2) = 8 s^4, Cov(d_j^2, d_{j+1}^2) = 2 s^4, E sum = 2 M s^2, so
    EDF = 2 E^2 / Var = 2 M^2 / (3 M - 1).
    """
    big_m = float(n_terms)
    return 2.0 * big_m * big_m / (3.0 * big_m - 1.0)
