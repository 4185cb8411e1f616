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
Slow, obviously-correct twin of the six-position estimator (the oracle of test_calibration).

Generic least squares over all 18 scalar equations ``l_j(dwell) = sum_i A[j, i] true_i + b_j``
with the nominal true specific force of each dwell, solved with numpy.linalg.lstsq row by row,
plus the paper's eq. 3 bias by an explicit loop.
"""

import numpy as np

ORDER = ('+x', '-x', '+y', '-y', '+z', '-z')


def nominal_true(orientation, g):
    v = np.zeros(3)
    v['xyz'.index(orientation[1])] = g if orientation[0] == '+' else -g
    return v


def lstsq_matrix(means, g):
    """Return (A, b_ls) from the 18 equations (A = I + diag(S) + M)."""
    design = np.array([np.append(nominal_true(o, g), 1.0) for o in ORDER])
    a = np.zeros((3, 3))
    b = np.zeros(3)
    for j in range(3):
        coef, *_ = np.linalg.lstsq(design, np.array([means[k][j] for k in range(6)]), rcond=None)
        a[j] = coef[:3]
        b[j] = coef[3]
    return a, b


def paper_bias(means):
    """Return paper 001 eq. 3: b_i = (l_i(+i) + l_i(-i)) / 2, by a loop."""
    out = []
    for i, ax in enumerate('xyz'):
        up = means[ORDER.index('+' + ax)][i]
        down = means[ORDER.index('-' + ax)][i]
        out.append((up + down) / 2.0)
    return np.array(out)


def paper_scale(means, g):
    """Return paper 001 eq. 4: S_i = (l_i(+i) - l_i(-i) - 2g) / 2g, by a loop."""
    out = []
    for i, ax in enumerate('xyz'):
        up = means[ORDER.index('+' + ax)][i]
        down = means[ORDER.index('-' + ax)][i]
        out.append((up - down - 2.0 * g) / (2.0 * g))
    return np.array(out)
