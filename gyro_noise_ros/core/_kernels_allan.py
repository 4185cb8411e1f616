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
numba kernels of the Allan-deviation estimator (private).

Called only through :mod:`gyro_noise_ros.core.allan`, which validates shapes, dtypes and values.
Plain-numpy twins live in ``test/_allan_reference.py``.

Bit-exactness contract: the batch estimator and the incremental accumulator must give identical
floating-point results for the same data, whatever the batch boundaries. So every sum below is
sequential in a fixed index order, with a fixed lane structure (term ``t`` goes to lane ``t % 4``)
and a fixed fold point (every :data:`FOLD_TERMS` terms the four lanes are added and folded into a
Neumaier-compensated total). The batch kernel and the accumulator implement the same arithmetic,
operation for operation: the fully overlapping taus by one streaming loop per tau over a batch
(:func:`_terms`, :func:`_acf_run`, shared by both), the strided levels term by term;
``fastmath`` stays off (``JIT_OPTIONS``) so LLVM neither re-associates nor contracts into FMAs
(the four lanes of a row of terms go into one vector, lane by lane).
"""

from typing import Any

from gyro_noise_ros.core.jit import JIT_OPTIONS
import numba
import numpy as np
from numpy.typing import NDArray

#: Annotations of the kernels' arrays: float64 and int64 (short, so signatures stay one line).
_F = NDArray[np.float64]
_I = NDArray[np.int64]

#: Terms per fold of the four partial sums into the compensated total. A power of two and a
#: multiple of 4, so a 4-term group never straddles a fold point.
FOLD_TERMS = 4096
_FOLD_MASK = FOLD_TERMS - 1

#: Positions of the phase array processed for every tau before moving on (cache blocking: the
#: x[i] stream and the x[i+m], x[i+2m] streams of the short taus are shared by all taus while a
#: block is processed). Measured on 4e7 samples, octave taus: 8192 -> 4.6, 32768 -> 2.7,
#: 131072 -> 3.2, unblocked -> 4.4 ns per term (shorter blocks restart the prefetchers too often).
BLOCK = 32768

#: Columns of the per-tau noise-identification sums (see :func:`_acf_push`).
N_ACF = 19
# column indices of the lag-1 ACF running sums
_N = 0          # number of m-averages z_j
_SZ = 1         # sum z_j
_SJZ = 2        # sum j z_j
_SZZ = 3        # sum z_j^2
_SZZ1 = 4       # sum z_j z_{j+1}
_Z0 = 5         # first z
_ZL = 6         # last z
_SW = 7         # first differences w_j = z_{j+1} - z_j: sum, sum of squares, lag-1 products
_SWW = 8
_SWW1 = 9
_W0 = 10
_WL = 11
_SV = 12        # second differences v_j = w_{j+1} - w_j
_SVV = 13
_SVV1 = 14
_V0 = 15
_VL = 16
_NW = 17        # number of w
_NV = 18        # number of v


@numba.njit(**JIT_OPTIONS)
def _integrate(  # pragma: no cover - compiled
        y: NDArray[np.floating[Any]], offset: float, state: _F, out: _F) -> None:
    """
    Neumaier-compensated running sum of ``y - offset`` into ``out`` (len(y)).

    ``state`` = [s, c] carries the running sum and its compensation between calls, so
    integrating in pieces gives the same bits as integrating at once.
    out[k] = s_k + c_k, the prefix sum rounded once (error <= 1 ulp of |x|, independent of k).
    """
    s = state[0]
    c = state[1]
    for k in range(y.shape[0]):
        v = y[k] - offset
        t = s + v
        if abs(s) >= abs(v):
            c += (s - t) + v
        else:
            c += (v - t) + s
        s = t
        out[k] = s + c
    state[0] = s
    state[1] = c


@numba.njit(**JIT_OPTIONS)
def _fold(lanes: _F, tot: _F, j: int) -> None:  # pragma: no cover - compiled
    """Add the four lanes of tau ``j`` into its compensated total and clear them."""
    b = (lanes[j, 0] + lanes[j, 1]) + (lanes[j, 2] + lanes[j, 3])
    s = tot[j, 0]
    t = s + b
    if abs(s) >= abs(b):
        tot[j, 1] += (s - t) + b
    else:
        tot[j, 1] += (b - t) + s
    tot[j, 0] = t
    lanes[j, 0] = 0.0
    lanes[j, 1] = 0.0
    lanes[j, 2] = 0.0
    lanes[j, 3] = 0.0


@numba.njit(**JIT_OPTIONS)
def _finish(lanes: _F, tot: _F, j: int) -> float:  # pragma: no cover - compiled
    """Return the sum of squares of tau ``j`` so far (lanes folded into a copy of the total)."""
    b = (lanes[j, 0] + lanes[j, 1]) + (lanes[j, 2] + lanes[j, 3])
    s = tot[j, 0]
    c = tot[j, 1]
    t = s + b
    if abs(s) >= abs(b):
        c += (s - t) + b
    else:
        c += (b - t) + s
    return t + c


@numba.njit(**JIT_OPTIONS)
def _add_term(  # pragma: no cover - compiled
        lanes: _F, tot: _F, counts: _I, j: int, d: float) -> None:
    """Add one second difference ``d`` to tau ``j`` (same arithmetic as the batch loop)."""
    t = counts[j]
    lanes[j, t & 3] += d * d
    t += 1
    counts[j] = t
    if (t & _FOLD_MASK) == 0:
        _fold(lanes, tot, j)


@numba.njit(**JIT_OPTIONS)  # pragma: no cover - compiled (on the decorator: the def is full)
def _avar_sums(x: _F, ms: _I, strides: _I, n_terms: _I, lanes: _F, tot: _F, counts: _I) -> None:
    """
    Sum the squared second differences of the phase ``x`` for every tau.

    Term t of tau j is d = (x[i + 2m] - 2 x[i + m]) + x[i] with i = t * strides[j],
    t = 0 .. n_terms[j] - 1 (paper 001 eq. 7 without the 1/(2 tau^2 n) factor).
    ``lanes`` (n_tau x 4), ``tot`` (n_tau x 2) and ``counts`` (n_tau) are zero on entry and hold
    the accumulator state on return; :func:`_finish` gives the sums.
    """
    n_tau = ms.shape[0]
    last_pos = 0
    for j in range(n_tau):
        p = (n_terms[j] - 1) * strides[j] + 1
        if p > last_pos:
            last_pos = p
    for b in range(0, last_pos, BLOCK):
        e = b + BLOCK
        for j in range(n_tau):
            m = ms[j]
            s = strides[j]
            nt = n_terms[j]
            t = (b + s - 1) // s
            t1 = (e + s - 1) // s
            if t1 > nt:
                t1 = nt
            if t >= t1:
                continue
            _terms(x, t * s, s, m, t1 - t, t, lanes, tot, j)
            counts[j] = t1


@numba.njit(**JIT_OPTIONS)
def _acf_push(acf: _F, j: int, z: float) -> None:  # pragma: no cover - compiled
    """
    Append the m-average ``z`` to the lag-1 ACF running sums of tau ``j``.

    Keeps, for z and its first (w) and second (v) differences, the sums needed by the
    lag-1 autocorrelation noise identification (Riley & Greenhall 2004) without storing the series.
    """
    n = acf[j, _N]
    jj = n
    if n == 0.0:
        acf[j, _Z0] = z
    else:
        zp = acf[j, _ZL]
        acf[j, _SZZ1] += zp * z
        w = z - zp
        nw = acf[j, _NW]
        if nw == 0.0:
            acf[j, _W0] = w
        else:
            wp = acf[j, _WL]
            acf[j, _SWW1] += wp * w
            v = w - wp
            nv = acf[j, _NV]
            if nv == 0.0:
                acf[j, _V0] = v
            else:
                acf[j, _SVV1] += acf[j, _VL] * v
            acf[j, _SV] += v
            acf[j, _SVV] += v * v
            acf[j, _VL] = v
            acf[j, _NV] = nv + 1.0
        acf[j, _SW] += w
        acf[j, _SWW] += w * w
        acf[j, _WL] = w
        acf[j, _NW] = nw + 1.0
    acf[j, _SZ] += z
    acf[j, _SJZ] += jj * z
    acf[j, _SZZ] += z * z
    acf[j, _ZL] = z
    acf[j, _N] = n + 1.0


@numba.njit(**JIT_OPTIONS)
def _acf_sums(x: _F, ms: _I, acf: _F) -> None:  # pragma: no cover - compiled
    """Feed each m-average z_j = (x[(j+1)m] - x[jm]) / m of the phase ``x`` to _acf_push."""
    n_x = x.shape[0]
    for j in range(ms.shape[0]):
        m = ms[j]
        n_avg = (n_x - 1) // m
        if n_avg > 0:
            _acf_run(x, m, m, n_avg, acf, j)


@numba.njit(**JIT_OPTIONS)
def _accumulate(  # pragma: no cover - compiled
        y: NDArray[np.floating[Any]], offset: float, integ: _F, k0: int, buf: _F, ring: _F,
        level_pos: _I, n_levels_active: int, ms: _I, level_of: _I, level_end: _I,
        next_push: _I, lanes: _F, tot: _F, counts: _I, acf: _F) -> tuple[int, int]:
    """
    Incremental twin of ``_integrate`` + ``_avar_sums`` + ``_acf_sums``, levels >= 1.

    ``k0`` is the number of rate samples already seen (phase points x_0 .. x_k0 exist, x_0 = 0).
    Level 0 (every phase point) is the linear buffer ``buf``: ``buf[0 .. h - 1]`` holds x_{k0 - h
    + 1} .. x_k0 on entry (``h = buf.shape[0] - y.shape[0]``, the points before x_0 unused) and
    the points of this batch are written after them; the taus of level 0 are summed from it by
    :func:`_level0` after this call. Row L - 1 of ``ring`` keeps x_k for k a multiple of 2**L
    (L >= 1), the last ring.shape[1] = 2 * half + 1 of them; ``level_pos[L]`` is the row position
    of the newest one. Taus are sorted by m, their levels (``level_of``) are non-decreasing,
    ``level_end[L]`` counts the taus of levels <= L. Taus of level L use only that row, so their
    terms start at i = 0 and advance in steps of 2**L (m is a multiple of 2**L and m / 2**L <=
    half). Level L + 1 is seeded from level L when level L holds x_0 .. x_{half * 2**L} (nothing
    overwritten yet); the first tau of level L + 1 has m >= half * 2**L, so its first m-average
    and term come no earlier. ``next_push[j]`` is the k of the next m-average of tau j. Returns
    (k, n_levels_active).
    """
    ring_len = ring.shape[1]
    n_levels = ring.shape[0] + 1
    half = (ring_len - 1) // 2
    hist = buf.shape[0] - y.shape[0]
    s = integ[0]
    c = integ[1]
    k = k0
    for q in range(y.shape[0]):
        v = y[q] - offset
        t = s + v
        if abs(s) >= abs(v):
            c += (s - t) + v
        else:
            c += (v - t) + s
        s = t
        xk = s + c
        k += 1
        buf[hist + q] = xk
        top = 0
        active = n_levels_active
        if active == 1 and n_levels > 1 and k == half:
            # level 1 seeded from x_0, x_2, ..., x_half (buf[hist + q] is x_k = x_half)
            for pp in range(0, half + 1, 2):
                ring[0, pp >> 1] = buf[hist + q - half + pp]
            level_pos[1] = half >> 1
            n_levels_active = 2
            if (k & 1) == 0:
                top = 1   # x_k is also the newest point of level 1 (half even)
        for lev in range(1, active):
            if (k & ((1 << lev) - 1)) != 0:
                break
            p = level_pos[lev] + 1
            if p == ring_len:
                p = 0
            level_pos[lev] = p
            ring[lev - 1, p] = xk
            top = lev
            if (lev + 1 == n_levels_active and n_levels_active < n_levels
                    and (k >> lev) == half):
                for pp in range(0, half + 1, 2):
                    ring[lev, pp >> 1] = ring[lev - 1, pp]
                level_pos[lev + 1] = half >> 1
                n_levels_active += 1
                if ((k >> lev) & 1) == 0:
                    # x_k is also the newest point of the new row (half even): a tau of that
                    # level with m == k has its first m-average now
                    top = lev + 1
        for j in range(level_end[0], level_end[top]):
            m = ms[j]
            if m > k:
                break
            lev = level_of[j]
            qq = m >> lev
            p = level_pos[lev]
            i1 = p - qq
            if i1 < 0:
                i1 += ring_len
            x1 = ring[lev - 1, i1]
            if k >= 2 * m:
                i0 = i1 - qq
                if i0 < 0:
                    i0 += ring_len
                d = (xk - 2.0 * x1) + ring[lev - 1, i0]
                _add_term(lanes, tot, counts, j, d)
            if k == next_push[j]:
                _acf_push(acf, j, (xk - x1) / m)
                next_push[j] = k + m
    integ[0] = s
    integ[1] = c
    return k, n_levels_active


@numba.njit(**JIT_OPTIONS)
def _level0(buf: _F, base: int, k1: int, ms: _I, n0: int, lanes: _F, tot: _F, counts: _I,
            next_push: _I, acf: _F) -> None:  # pragma: no cover - compiled
    """
    Add the terms and m-averages of the level-0 taus (fully overlapping) up to x_k1, by tau.

    ``buf[i - base]`` is x_i for base <= i <= k1 (filled by :func:`_accumulate`); taus 0 ..
    n0 - 1 are those of level 0. Each tau continues from its own state (``counts``: its next term
    t, starting at i = t; ``next_push``: the k of its next m-average), with the arithmetic of
    :func:`_terms` (lane t % 4, fold every FOLD_TERMS terms) and of the per-sample loop, so
    the sums are those of the batch estimator bit for bit whatever the batch boundaries. Taus
    are independent, so taking them one at a time over the whole batch changes no bit and lets
    each run as one streaming loop.
    """
    for j in range(n0):
        m = ms[j]
        t = counts[j]
        t1 = k1 - 2 * m + 1
        if t1 > t:
            _terms(buf, t - base, 1, m, t1 - t, t, lanes, tot, j)
            counts[j] = t1
        kk = next_push[j]
        if kk <= k1:
            next_push[j] = _acf_run(buf, kk - base, m, (k1 - kk) // m + 1, acf, j) + base


@numba.njit(**JIT_OPTIONS)
def _terms(x: _F, i: int, step: int, m: int, count: int, t: int, lanes: _F, tot: _F,
           j: int) -> None:  # pragma: no cover - compiled
    """
    Add ``count`` terms ``(x[i + 2m] - 2 x[i + m]) + x[i]`` (i advancing by ``step``) to tau j.

    ``t`` is the index of the first of them in its tau's sequence: term t goes to lane t % 4, and
    the lanes are folded into the total after every FOLD_TERMS-th term (:func:`_add_term` adding
    them one by one gives the same bits). Between the odd terms at either end of a segment, rows
    of four terms (one per lane) go through :func:`_lane_rows`.
    """
    t1 = t + count
    acc = np.empty(4)
    for u in range(4):
        acc[u] = lanes[j, u]
    while t < t1:
        # one segment = up to the next fold point, so the rows need no fold test
        seg = min(t1, (t // FOLD_TERMS + 1) * FOLD_TERMS)
        head = min(seg, (t + 3) & ~3)
        i = _single_terms(x, i, step, m, t, head, acc)
        t = head
        groups = (seg - t) >> 2
        if groups > 0:
            _lane_rows(x, i, step, m, groups, acc)
            t += 4 * groups
            i += 4 * groups * step
        i = _single_terms(x, i, step, m, t, seg, acc)
        t = seg
        if (t & _FOLD_MASK) == 0:
            for u in range(4):
                lanes[j, u] = acc[u]
            _fold(lanes, tot, j)
            acc[:] = 0.0
    for u in range(4):
        lanes[j, u] = acc[u]


@numba.njit(**JIT_OPTIONS)
def _single_terms(x: _F, i: int, step: int, m: int, t0: int, t1: int,
                  acc: _F) -> int:  # pragma: no cover - compiled
    """Add the terms t0 .. t1 - 1 (from x[i] on) to their lanes ``acc[t % 4]``; return i after."""
    for t in range(t0, t1):
        d = (x[i + 2 * m] - 2.0 * x[i + m]) + x[i]
        acc[t & 3] += d * d
        i += step
    return i


@numba.njit(**JIT_OPTIONS)
def _lane_rows(x: _F, i: int, step: int, m: int, groups: int,
               acc: _F) -> None:  # pragma: no cover - compiled
    """
    Add ``groups`` rows of four terms (from x[i] on, i advancing by ``step``) to ``acc[0 .. 3]``.

    Term u of a row goes to lane u. With ``step`` 1 the compiler packs each row into one vector:
    the same operations per lane, no reassociation, so the bits of the scalar loop.
    """
    if step == 1:
        far = x[i + 2 * m:i + 2 * m + 4 * groups].reshape(groups, 4)
        mid = x[i + m:i + m + 4 * groups].reshape(groups, 4)
        near = x[i:i + 4 * groups].reshape(groups, 4)
        for g in range(groups):
            for u in range(4):
                d = (far[g, u] - 2.0 * mid[g, u]) + near[g, u]
                acc[u] += d * d
        return
    for g in range(groups):
        for u in range(4):
            d = (x[i + 2 * m] - 2.0 * x[i + m]) + x[i]
            acc[u] += d * d
            i += step


@numba.njit(**JIT_OPTIONS)
def _acf_run(x: _F, i: int, m: int, count: int, acf: _F,
             j: int) -> int:  # pragma: no cover - compiled
    """
    Push ``count`` m-averages ``(x[i] - x[i - m]) / m`` (i advancing by m) to tau ``j``.

    The arithmetic of :func:`_acf_push`, push for push, with the running sums held in locals
    between pushes instead of in ``acf`` (same operations, same order: same bits). Returns the
    index after the last average.
    """
    n = acf[j, _N]
    sz = acf[j, _SZ]
    sjz = acf[j, _SJZ]
    szz = acf[j, _SZZ]
    szz1 = acf[j, _SZZ1]
    z0 = acf[j, _Z0]
    zl = acf[j, _ZL]
    sw = acf[j, _SW]
    sww = acf[j, _SWW]
    sww1 = acf[j, _SWW1]
    w0 = acf[j, _W0]
    wl = acf[j, _WL]
    sv = acf[j, _SV]
    svv = acf[j, _SVV]
    svv1 = acf[j, _SVV1]
    v0 = acf[j, _V0]
    vl = acf[j, _VL]
    nw = acf[j, _NW]
    nv = acf[j, _NV]
    for _ in range(count):
        z = (x[i] - x[i - m]) / m
        i += m
        if n == 0.0:
            z0 = z
        else:
            szz1 += zl * z
            w = z - zl
            if nw == 0.0:
                w0 = w
            else:
                sww1 += wl * w
                v = w - wl
                if nv == 0.0:
                    v0 = v
                else:
                    svv1 += vl * v
                sv += v
                svv += v * v
                vl = v
                nv = nv + 1.0
            sw += w
            sww += w * w
            wl = w
            nw = nw + 1.0
        sz += z
        sjz += n * z
        szz += z * z
        zl = z
        n = n + 1.0
    acf[j, _N] = n
    acf[j, _SZ] = sz
    acf[j, _SJZ] = sjz
    acf[j, _SZZ] = szz
    acf[j, _SZZ1] = szz1
    acf[j, _Z0] = z0
    acf[j, _ZL] = zl
    acf[j, _SW] = sw
    acf[j, _SWW] = sww
    acf[j, _SWW1] = sww1
    acf[j, _W0] = w0
    acf[j, _WL] = wl
    acf[j, _SV] = sv
    acf[j, _SVV] = svv
    acf[j, _SVV1] = svv1
    acf[j, _V0] = v0
    acf[j, _VL] = vl
    acf[j, _NW] = nw
    acf[j, _NV] = nv
    return i
