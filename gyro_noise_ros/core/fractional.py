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
Fractional-order identification of gyroscope noise (paper 000, section 2, eqs. 1-14).

Model (eq. 2): ``Delta^alpha v[k+1] = f v[k] + w[k]`` with the truncated Grunwald-Letnikov backward
difference (eqs. 3-5)::

    Delta^alpha x[k] = sum_{j=0}^{L(k)} c_j(alpha) x[k-j],   c_j(alpha) = (-1)^j binom(alpha, j),
    L(k) = min(k, L)

where ``k`` counts samples from the start of the analysed chunk (each chunk starts a fresh memory).
For each order on a grid, ``f`` is the least-squares solution of eqs. (6)-(8) and the source noise
is the equation error of eq. (9), ``w[k] = Delta^alpha v[k+1] - f v[k]`` for ``k = 0 .. N-2``
(``n = N - 1`` values). Two order estimates (section 2, last part):

* variance method: the order minimising ``var(w)`` (population variance, mean of ``w`` removed);
* correlation method: the order minimising ``J = sum_{m=0}^{M} |R_w(m)|`` (eq. 13) with the biased
  autocorrelation ``R_w(m) = (1/n) sum_{k=0}^{n-1-m} w[k+m] w[k]`` (eq. 14); by default every lag,
  ``M = n - 1``.

Orders 0 and 1 give the same residual for any data (``f_0 = f_1 + 1``): when a curve's minimum is
attained at several grid orders (within a relative 1e-9), the **largest** is reported (order 1 is
the paper's integer-order model of eq. 1) and the tie is listed in ``tied_alphas_*``
(docs/analysis.md). :class:`OrderIdentifier` does it for chunks of one size.
"""

import dataclasses
from dataclasses import dataclass
import os

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray
import scipy.fft
import threadpoolctl

from . import _kernels_fractional as _kf
from ..errors import InputDataError, ParameterError

#: Default memory length L of the truncated GL difference (paper 000: "L = 1000 is used for all
#: computations").
DEFAULT_MEMORY = 1000

#: Relative tolerance under which two grid values of a criterion count as an exact tie (see module
#: doc).
TIE_RTOL = 1e-9


def default_grid() -> NDArray[np.float64]:
    """
    Return the default order grid, 0.00 to 2.00 in steps of 0.01, both ends included.

    Returns
    -------
    numpy.ndarray
        201 orders (dimensionless).

    """
    return np.round(np.arange(201) * 0.01, 10)


def make_grid(start: float, stop: float, step: float) -> NDArray[np.float64]:
    """
    Return an order grid from ``start`` to ``stop`` inclusive in steps of ``step``.

    Parameters
    ----------
    start, stop : float
        First and last order (dimensionless); ``stop >= start``.
    step : float
        Positive step.

    Returns
    -------
    numpy.ndarray
        The grid, rounded to 10 decimals so that e.g. 1.0 is exactly representable as a grid point.

    """
    start, stop, step = float(start), float(stop), float(step)
    if not all(np.isfinite([start, stop, step])):
        raise ParameterError(f'order grid {start}:{stop}:{step} must be finite')
    if step <= 0:
        raise ParameterError(f'order grid step must be > 0, got {step}')
    if stop < start:
        raise ParameterError(f'order grid stop ({stop}) must be >= start ({start})')
    points = np.floor((stop - start) / step + 1e-9) + 1  # float: may be huge, or inf
    if not points <= 100000:
        raise ParameterError(f'order grid {start:g}:{stop:g}:{step:g} has {points:.3g} points '
                             '(max 100000)')
    return np.round(start + step * np.arange(int(points)), 10)


def parse_grid(text: str) -> NDArray[np.float64]:
    """
    Parse ``'START:STOP:STEP'`` (the ``--order-grid`` syntax) into a grid.

    Parameters
    ----------
    text : str
        Three numbers separated by colons, e.g. ``'0:2:0.01'``.

    Returns
    -------
    numpy.ndarray

    """
    parts = str(text).split(':')
    if len(parts) != 3:
        raise ParameterError(f'order grid must be START:STOP:STEP, got {text!r}')
    try:
        values = [float(p) for p in parts]
    except ValueError as err:
        raise ParameterError(f'order grid must be START:STOP:STEP numbers, got {text!r}') from err
    return make_grid(*values)


def gl_coefficients(alpha: float, memory: int = DEFAULT_MEMORY) -> NDArray[np.float64]:
    """
    Return the Grunwald-Letnikov coefficients c_j = (-1)^j binom(alpha, j), j = 0..L.

    Paper 000 eq. (4), with the sign (-1)^j of eq. (3) folded in. Computed by the stable recurrence
    ``c_j = c_{j-1} (j - 1 - alpha) / j``, which gives exact zeros past an integer order.

    Parameters
    ----------
    alpha : float
        Order of the difference (dimensionless, any real).
    memory : int
        L, the number of past samples (>= 0).

    Returns
    -------
    numpy.ndarray
        ``L + 1`` coefficients, ``c_0 = 1``.

    """
    memory = _check_memory(memory)
    alpha = float(alpha)
    if not np.isfinite(alpha):
        raise ParameterError(f'alpha must be finite, got {alpha}')
    j = np.arange(1, memory + 1, dtype=np.float64)
    c = np.empty(memory + 1)
    c[0] = 1.0
    c[1:] = np.cumprod((j - 1.0 - alpha) / j)
    return c


def gl_difference(x: npt.ArrayLike, alpha: float, *,
                  memory: int = DEFAULT_MEMORY) -> NDArray[np.float64]:
    """
    Return the truncated GL difference Delta^alpha x[k] for k = 0 .. len(x) - 1.

    Paper 000 eqs. (3)-(5): ``sum_{j=0}^{min(k, L)} c_j x[k-j]``, with k counted from ``x[0]``.

    Parameters
    ----------
    x : array_like
        Samples (any unit; the result has the same unit).
    alpha : float
        Order (dimensionless).
    memory : int, keyword-only
        L (default 1000).

    Returns
    -------
    numpy.ndarray

    """
    x = np.asarray(x, dtype=np.float64)
    c = gl_coefficients(alpha, memory)
    n = x.shape[0]
    size = scipy.fft.next_fast_len(n + c.shape[0] - 1, real=True)
    y = scipy.fft.irfft(scipy.fft.rfft(x, size) * scipy.fft.rfft(c, size), size)
    return y[:n]


@dataclass(frozen=True)
class OrderIdentification:
    """
    Result of the fractional-order identification of one chunk (paper 000 eqs. 6-14).

    Attributes
    ----------
    alpha_var, f_var : float
        Order and LS noise parameter minimising the source-noise variance (variance method).
    var_min : float
        That minimum variance, in the squared unit of the input (e.g. (rad/s)^2).
    alpha_corr, f_corr : float
        Order and LS parameter minimising J (correlation method).
    j_min : float
        That minimum of J, in the squared unit of the input.
    tied_alphas_var, tied_alphas_corr : tuple of float
        All grid orders whose criterion equals the minimum within :data:`TIE_RTOL` (length 1 = no
        tie).
    bias : float
        The chunk mean (removed before identification when ``demean`` is on), in the input unit.
    alphas : numpy.ndarray
        The order grid.
    var_curve, j_curve, f_curve : numpy.ndarray or None
        var(w)(alpha), J(alpha) and f(alpha) over the grid when curves were requested.

    """

    alpha_var: float
    f_var: float
    var_min: float
    alpha_corr: float
    f_corr: float
    j_min: float
    tied_alphas_var: tuple[float, ...]
    tied_alphas_corr: tuple[float, ...]
    bias: float
    alphas: np.ndarray
    var_curve: np.ndarray | None = None
    j_curve: np.ndarray | None = None
    f_curve: np.ndarray | None = None


#: Algorithms of :class:`OrderIdentifier`: see its doc.
ALGORITHMS = ('auto', 'exact', 'fast')

#: Relative difference allowed between the fast and the exact criterion values when the fast
#: curves only locate the minimum (algorithm ``'auto'``). Every order whose fast value lies within
#: this of the tie band of the fast minimum is recomputed exactly; the differences measured are
#: 1e-14 to 1e-11 (``test/test_fractional_fast.py``), and each chunk checks them again on the
#: orders it recomputes (10x tighter) before trusting the location.
LOCATE_RTOL = 1e-6

#: Singular values of the grid's coefficient matrix below this fraction of the largest are left
#: out by the fast algorithm (:class:`_FastPlan`): the machine epsilon, so the low-rank
#: coefficients equal the computed ones to their own rounding.
RANK_RTOL = float(np.finfo(np.float64).eps)

#: Orders per matrix product and transform batch of the fast algorithm.
FAST_BLOCK = 16

#: Frequency bins per matrix product when the fast algorithm needs only sums over the spectra
#: (:meth:`_FastPlan._bounds`): the product's output stays in cache for the pass that reads it
#: (128 to 512 measured alike, 10,001 bins at once 1.6x slower).
FAST_TILE = 128

#: Every ANCHOR_STEP-th order (by value) has its J computed when the fast curves only locate the
#: minimum; the others are bounded from their neighbouring anchors (:meth:`_FastPlan._pruned`).
#: With 10, on the default grid: 21 anchors, and J at 1 to 8 other orders on fractional,
#: white, random-walk and tone chunks, instead of 201.
ANCHOR_STEP = 10


class OrderIdentifier:
    """
    Identify the fractional order of chunks of a fixed length, fast (paper 000 eqs. 3-14).

    Three algorithms give the same orders; they differ in speed and in the last bits of the
    criterion values:

    * ``'exact'``: the GL filters of every grid order are transformed once; each chunk then costs
      one forward FFT and, per order, one inverse FFT (the truncated difference), one forward and
      one inverse FFT (the full autocorrelation of the source noise), in blocks of ``block``
      orders. Its values are the reference of the package: bit for bit those of every earlier
      release.
    * ``'fast'``: the coefficient matrix of the grid is of low numerical rank (:class:`_FastPlan`):
      r basis filters (18 for the default grid and memory) are convolved with the chunk and
      transformed, and the difference spectra of all orders are one matrix product; per order
      then only the residual spectrum ``D - f V``, its variance by Parseval, and one inverse
      transform of its power spectrum for J. Equal to the direct per-order convolution to
      rounding (about 1e-14), not to the bit of ``'exact'``.
    * ``'auto'`` (default): the fast curves locate the minimum of each criterion (without
      ``curves``, J only where a lower bound of it allows a minimum: about 25 of 201 orders,
      :meth:`_FastPlan._pruned`); the orders whose
      fast value lies within :data:`LOCATE_RTOL` of the tie band are recomputed by ``'exact'``
      (their whole ``block``, as ``'exact'`` computes it) and the minimum, its ties, f and the
      reported values are taken from those exact values. The results are therefore bit for bit
      those of ``'exact'`` as long as the fast curves are within :data:`LOCATE_RTOL` of the exact
      ones (they are within ~1e-11); when the recomputed orders disagree by more than a tenth of
      that, or a fast value is not finite, the chunk falls back to ``'exact'``. With
      ``curves=True`` the curves are the fast ones with the recomputed exact values in place
      (equal to the oracle to rounding, and their minima are the reported values bit for bit);
      use ``'exact'`` for the released curves to the bit.

    The results equal the direct per-order convolution and correlation to rounding (checked in
    ``test/test_fractional.py`` and ``test/test_fractional_fast.py`` against
    ``test/_fractional_reference.py``).

    Parameters
    ----------
    chunk_size : int
        N, the number of samples per chunk (at least ``memory + 2``).
    alphas : array_like, keyword-only
        Order grid (default 0.00:2.00:0.01).
    memory : int, keyword-only
        L of eq. (5) (default 1000).
    demean : bool, keyword-only
        Remove the chunk mean before identification (default True; the mean is reported as the
        bias).
    max_lag : int or None, keyword-only
        Largest lag M in J (eq. 13); None = all lags, ``n - 1``.
    block : int, keyword-only
        Orders processed per vectorised block. It sets the blocks of ``'exact'`` and so the last
        bits of its values (the matrix-vector product of a block rounds by block): keep the
        default to reproduce earlier results.
    algorithm : {'auto', 'exact', 'fast'}, keyword-only
        See above (default 'auto').

    """

    def __init__(self, chunk_size: int, *, alphas: npt.ArrayLike | None = None,
                 memory: int = DEFAULT_MEMORY, demean: bool = True, max_lag: int | None = None,
                 block: int = 8, algorithm: str = 'auto') -> None:
        self.memory = _check_memory(memory)
        self.alphas = default_grid() if alphas is None else np.asarray(
            alphas, dtype=np.float64).ravel()
        if self.alphas.size == 0:
            raise ParameterError('the order grid is empty')
        if not np.all(np.isfinite(self.alphas)):
            raise ParameterError('the order grid contains NaN or Inf')
        chunk_size = int(chunk_size)
        if chunk_size < self.memory + 2:
            raise ParameterError(
                f'chunk_size ({chunk_size}) must be at least memory L + 2 = {self.memory + 2}')
        self.chunk_size = chunk_size
        self.n = chunk_size - 1
        if max_lag is None:
            max_lag = self.n - 1
        max_lag = int(max_lag)
        if not 0 <= max_lag <= self.n - 1:
            raise ParameterError(
                f'max_lag must be in [0, {self.n - 1}] for chunk_size {chunk_size}, '
                f'got {max_lag}')
        if algorithm not in ALGORITHMS:
            raise ParameterError(f'algorithm must be one of {ALGORITHMS}, got {algorithm!r}')
        self.algorithm = algorithm
        self.max_lag = max_lag
        self.demean = bool(demean)
        self.block = max(1, int(block))
        _check_table_memory(self.alphas.size, chunk_size, self.memory)
        self._conv_size = scipy.fft.next_fast_len(chunk_size + self.memory, real=True)
        self._corr_size = scipy.fft.next_fast_len(self.n + self.max_lag + 1, real=True)
        self._coeffs = np.stack([gl_coefficients(a, self.memory) for a in self.alphas])
        self._coeff_hat = scipy.fft.rfft(self._coeffs, self._conv_size, axis=1)
        self._fast: _FastPlan | None = None  # _FastPlan, built on first use

    def __call__(self, chunk: npt.ArrayLike, *, curves: bool = False) -> OrderIdentification:
        """
        Identify one chunk.

        Parameters
        ----------
        chunk : array_like
            ``chunk_size`` samples of angular rate (any unit; rad/s in this package).
        curves : bool, keyword-only
            Also return var(alpha), J(alpha) and f(alpha) over the grid.

        Returns
        -------
        OrderIdentification

        """
        v = validate_chunk(chunk, self.chunk_size)
        bias = float(v.mean())
        if self.demean:
            v = v - bias
        _regressor(v)
        with _blas_threads().limit(limits=1):
            return self._identify(v, bias, curves)

    def _identify(self, v: NDArray[np.float64], bias: float,
                  curves: bool) -> OrderIdentification:
        """Identify the (demeaned) chunk ``v`` by :attr:`algorithm`; see :meth:`__call__`."""
        if self.algorithm == 'exact':
            var_curve, j_curve, f_curve = self._curves(v)
            return _summarise(self.alphas, var_curve, j_curve, f_curve, bias, curves)
        if self._fast is None:
            self._fast = _FastPlan(self)
        fast = self._fast.curves(v, prune=self.algorithm == 'auto' and not curves)
        if self.algorithm == 'fast':
            return _summarise(self.alphas, *fast, bias, curves)
        located = self._locate(v, *fast)
        if located is None:
            return _summarise(self.alphas, *self._curves(v), bias, curves)
        rows, exact = located
        k = len(self.alphas)
        held = np.full((3, k), np.inf)
        held[2] = np.nan
        held[:, rows] = exact
        result = _summarise(self.alphas, held[0], held[1], held[2], bias, False)
        if not curves:
            return result
        # The curves: the fast values, with the exact values where they were recomputed, so the
        # minimum of each curve is the reported one, bit for bit.
        spliced = np.array(fast)
        spliced[:, rows] = exact
        return dataclasses.replace(result, var_curve=spliced[0], j_curve=spliced[1],
                                   f_curve=spliced[2])

    def _curves(self, v: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Return the criterion curves by the 'exact' algorithm (every order, in blocks)."""
        n, size = self.n, self._conv_size
        w_reg, ww = _regressor(v)
        v_hat = scipy.fft.rfft(v, size)
        k = len(self.alphas)
        var_curve = np.empty(k)
        j_curve = np.empty(k)
        f_curve = np.empty(k)
        # w is written into a zero-padded buffer so the correlation FFT needs no padding copy
        padded = np.zeros((self.block, self._corr_size))
        conj = np.empty((self.block, self._corr_size // 2 + 1), dtype=np.complex128)
        for start in range(0, k, self.block):
            stop = min(k, start + self.block)
            rows = stop - start
            diff = scipy.fft.irfft(self._coeff_hat[start:stop] * v_hat, size, axis=1)
            d = diff[:, 1:n + 1]
            f = (d @ w_reg) / ww
            w = padded[:rows, :n]
            np.multiply(f[:, None], w_reg, out=w)
            np.subtract(d, w, out=w)
            var_curve[start:stop] = w.var(axis=1)
            spec = scipy.fft.rfft(padded[:rows], axis=1)
            # the same operands, in the same order, as spec * spec.conj() (the complex product
            # rounds its imaginary part differently when the operands are swapped)
            power = np.multiply(spec, np.conjugate(spec, out=conj[:rows]), out=spec)
            r = scipy.fft.irfft(power, self._corr_size, axis=1)
            j_curve[start:stop] = np.abs(r[:, :self.max_lag + 1]).sum(axis=1) / n
            f_curve[start:stop] = f
        return var_curve, j_curve, f_curve

    def _exact_rows(self, v: NDArray[np.float64],
                    rows: NDArray[np.intp]) -> NDArray[np.float64]:
        """
        Return var, J and f of the grid orders ``rows`` exactly as :meth:`_curves` computes them.

        f is a matrix-vector product over the block of each order, as in :meth:`_curves`: the
        same product on a block whose other rows are zero (each row's dot product is its own,
        rounded by its position in the block); everything else is per order, and numpy and
        pocketfft round a row alike whether it is alone or in a block (``test/
        test_fractional_fast.py`` checks this against :meth:`_curves`).
        """
        n, size, blk = self.n, self._conv_size, self.block
        w_reg, ww = _regressor(v)
        v_hat = scipy.fft.rfft(v, size)
        k = len(self.alphas)
        out = np.empty((3, rows.shape[0]))
        padded = np.zeros((1, self._corr_size))
        w = padded[:, :n]
        for b in np.unique(rows // blk):
            start = int(b) * blk
            stop = min(k, start + blk)
            wanted = np.unique(rows[(rows >= start) & (rows < stop)]) - start
            diff = np.zeros((stop - start, size))
            diff[wanted] = scipy.fft.irfft(self._coeff_hat[start + wanted] * v_hat, size, axis=1)
            d = diff[:, 1:n + 1]
            f = (d @ w_reg) / ww
            for pos in np.flatnonzero((rows >= start) & (rows < stop)):
                r = int(rows[pos]) - start
                np.multiply(f[r], w_reg, out=w[0])
                np.subtract(d[r], w[0], out=w[0])
                var = w.var(axis=1)
                spec = scipy.fft.rfft(padded, axis=1)
                power = np.multiply(spec, spec.conj(), out=spec)
                corr = scipy.fft.irfft(power, self._corr_size, axis=1)
                out[0, pos] = var[0]
                out[1, pos] = (np.abs(corr[:, :self.max_lag + 1]).sum(axis=1) / n)[0]
                out[2, pos] = f[r]
        return out

    def _locate(self, v: NDArray[np.float64], var_fast: NDArray[np.float64],
                j_fast: NDArray[np.float64], f_fast: NDArray[np.float64]
                ) -> tuple[NDArray[np.intp], NDArray[np.float64]] | None:
        """
        Return the grid orders where a minimum can be, and their exact values.

        ``(rows, values)``: ``values`` is a (3, len(rows)) array of var, J and f.

        None when the fast curves cannot be trusted for this chunk (not finite, or farther from
        the exact values than :data:`LOCATE_RTOL` / 10 on the recomputed orders). A candidate of
        the variance whose J a sign bound ruled out (+inf, no fast value) has its exact J checked
        against the exact minimum instead: above its tie band, as the bound proved.
        """
        # J is +inf where the sign bounds ruled a minimum out (_FastPlan._pruned)
        if not (np.all(np.isfinite(var_fast)) and np.isfinite(j_fast.min())
                and not np.isnan(j_fast).any()):
            return None
        if not (var_fast.min() > 0.0 and j_fast.min() > 0.0):
            return None  # a residual that vanishes: relative bounds say nothing there
        rows = np.union1d(_candidates(var_fast), _candidates(j_fast))
        exact = self._exact_rows(v, rows)
        guard = 0.1 * LOCATE_RTOL
        for fast, ex in ((var_fast[rows], exact[0]), (j_fast[rows], exact[1])):
            # a candidate of the variance alone may have had its J ruled out by a bound (+inf):
            # there is no fast value to compare; its exact J must then lie above the band
            known = np.isfinite(fast)
            if not (np.all(np.isfinite(ex)) and np.all(
                    np.abs(fast[known] - ex[known]) <= guard * np.abs(ex[known]))):
                return None
            if not np.all(ex[~known] > ex[known].min() * (1.0 + TIE_RTOL)):
                return None
        return rows, exact


_BLAS: list[threadpoolctl.ThreadpoolController] = []


def _blas_threads() -> threadpoolctl.ThreadpoolController:
    """
    Return the controller of numpy's BLAS thread pools (found once per process).

    An identification runs its matrix products on one BLAS thread: they are a few million
    operations each, and OpenBLAS' threads spin between them (measured on 2 cores under load:
    96 instead of 21 ms of CPU per chunk). The results do not depend on it (each dot product is
    one thread's either way); ``gyro_noise_analyze`` runs on one BLAS thread anyway.
    """
    if not _BLAS:
        _BLAS.append(threadpoolctl.ThreadpoolController().select(user_api='blas'))
    return _BLAS[0]


def _regressor(v: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """Return ``(v[:-1], v[:-1] @ v[:-1])`` (eq. 7's regressor and its energy), or raise."""
    w_reg = v[:-1]
    ww = float(w_reg @ w_reg)
    if ww == 0.0:
        raise InputDataError(
            'the chunk is constant after removing its mean: the order is undefined')
    return w_reg, ww


def _candidates(curve: NDArray[np.float64]) -> NDArray[np.intp]:
    """
    Return the grid indices whose exact value may be the minimum or tie with it.

    If every fast value is within a relative ``d`` = :data:`LOCATE_RTOL` of its exact value,
    every exact tie of the exact minimum ``e*`` has a fast value at most ``(1 + d)(1 + TIE_RTOL)
    e*``, and ``e*`` is at most ``low / (1 - d)`` (``low`` the fast minimum; both criteria are
    non-negative).
    """
    return np.flatnonzero(curve <= _band(float(curve.min())))


def _band(low: float) -> float:
    """Return the largest fast value that may be a minimum or its tie, given the lowest one."""
    return low * (1.0 + TIE_RTOL) * (1.0 + LOCATE_RTOL) / (1.0 - LOCATE_RTOL)


class _FastPlan:
    """
    The set-up of the 'fast' algorithm for one :class:`OrderIdentifier` (see its doc).

    The truncated difference (eq. 5) is linear in the coefficients, and the (K, L + 1) matrix C of
    the grid's coefficients is of low numerical rank: its singular values fall about tenfold per
    index (default grid, L = 1000: 21.2, 6.5, 1.8, ..., 3e-15 at the 18th, 2e-16 at the 19th). So
    ``C = A B`` to rounding, with the r rows of B whose singular values exceed
    :data:`RANK_RTOL` of the largest (r = 18 of 201 on the default grid) and ``A = U S``; the
    difference of every order is ``d_a = sum_r A[a, r] e_r``, ``e_r`` the truncated difference with
    the coefficients ``B[r]``. A chunk costs r FFT convolutions and r transforms of the ``e_r`` on
    the correlation size S (spectra X); the spectra of all K differences are one matrix product
    ``D = A X``. Per order: ``f = A (E v[:-1]) / ww`` (eq. 8); the residual spectrum ``W = D - f
    V`` (V the transform of the regressor ``v[0 .. n - 1]``); its variance by Parseval, less the
    squared mean ``W(0) / n``; J from one inverse transform of ``|W|^2`` (a DCT-I done as a
    half-length real FFT when S is a multiple of 4).
    """

    def __init__(self, ident: OrderIdentifier) -> None:
        self.ident = ident
        u, sing, basis = np.linalg.svd(ident._coeffs, full_matrices=False)
        rank = max(1, int(np.count_nonzero(sing > RANK_RTOL * sing[0])))
        self.rank = rank
        self.weights = np.ascontiguousarray(u[:, :rank] * sing[:rank])
        self.conv_size = scipy.fft.next_fast_len(ident.chunk_size + ident.memory, real=True)
        self.basis_hat = np.fft.rfft(basis[:rank], self.conv_size, axis=1)
        s = ident._corr_size
        self.nyquist = s // 2 if s % 2 == 0 else -1
        # The autocorrelation by a half-length FFT needs S = 2N with N even.
        self.cosine: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        if s % 4 == 0:
            half = np.arange(s // 2) * (2.0 * np.pi / s)
            self.cosine = (np.sin(half), np.cos(half))
        # the anchors of the sign bounds (:meth:`_pruned`): every ANCHOR_STEP-th order by value
        # and the last; each other order between the two anchors around it
        self.anchors: NDArray[np.intp] | None = None
        order = np.argsort(ident.alphas, kind='stable')
        if self.cosine is not None and order.size > 2 * ANCHOR_STEP:
            at = np.unique(np.append(np.arange(0, order.size, ANCHOR_STEP), order.size - 1))
            rest = np.setdiff1d(np.arange(order.size), at)
            self.anchors, self.others = order[at], order[rest]
            self.upper = np.searchsorted(at, rest).astype(np.int64)
            self.lower = self.upper - 1
            self.anchor_weights = self.weights[self.anchors]
            self.other_weights = self.weights[self.others]

    def curves(self, v: NDArray[np.float64], *, prune: bool = False
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """
        Return (var_curve, j_curve, f_curve) of the demeaned chunk ``v`` (fast algorithm).

        ``prune``: J only where a minimum can be (:meth:`_pruned`); +inf at the other orders.
        """
        ident = self.ident
        s = ident._corr_size
        w_reg, ww = _regressor(v)
        k = ident.alphas.shape[0]
        # e_r written into a zero-padded buffer: numpy's transform pads with a slower copy
        padded = np.empty((self.rank, s))
        padded[:, ident.n:] = 0.0
        e = padded[:, :ident.n]
        e[:] = np.fft.irfft(self.basis_hat * np.fft.rfft(v, self.conv_size), self.conv_size,
                            axis=1)[:, 1:ident.chunk_size]
        f_all = (self.weights @ (e @ w_reg)) / ww
        spectra = np.fft.rfft(padded, axis=1).view(np.float64)
        reg_hat = np.fft.rfft(w_reg, s)
        if prune and self.anchors is not None:
            return self._pruned(spectra, f_all, reg_hat)
        out = np.empty((3, k))
        out[2] = f_all
        rows = min(k, FAST_BLOCK)
        d = np.empty((rows, spectra.shape[1]))
        for start in range(0, k, FAST_BLOCK):
            stop = min(k, start + FAST_BLOCK)
            spec = d[:stop - start].view(np.complex128)
            np.matmul(self.weights[start:stop], spectra, out=d[:stop - start])
            f = f_all[start:stop]
            energy = self._criteria(spec, f, reg_hat, out[1, start:stop])
            out[0, start:stop] = self._variance(spec[:, 0].real, f, reg_hat, energy)
        return out[0], out[1], out[2]

    def _variance(self, dc: NDArray[np.float64], f: NDArray[np.float64],
                  reg_hat: NDArray[np.complex128],
                  energy: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the residual variances of orders from ``Re D(0)`` and their Parseval sums."""
        n = self.ident.n
        # var = mean(w^2) - mean(w)^2: the LS residual is orthogonal to the regressor, which
        # holds the chunk's level, so its mean stays small against its spread (mean^2 / var
        # <= 0.03 on white, walk, tone and fractional chunks with and without demean)
        mean = (dc - f * reg_hat[0].real) / n
        return energy / (self.ident._corr_size * n) - mean * mean

    def _criteria(self, spec: NDArray[np.complex128], f: NDArray[np.float64],
                  reg_hat: NDArray[np.complex128], j: NDArray[np.float64],
                  signs: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Fill J of a block of orders from their difference spectra; return their energies."""
        ident = self.ident
        rows = spec.shape[0]
        energy = np.empty(rows)
        if self.cosine is not None:
            sin_t, cos_t = self.cosine
            folded = np.empty((rows, sin_t.shape[0]))
            odd = np.empty(rows)
            _kf.cosine_prep(spec, f, reg_hat, sin_t, cos_t, folded, odd, energy)
            _kf.cosine_abs_sum(np.fft.rfft(folded, axis=1), odd, ident.max_lag + 1,
                               1.0 / (sin_t.shape[0] * ident.n), j,
                               np.empty((0, 0)) if signs is None else signs)
        else:
            power = np.empty(spec.shape, dtype=np.complex128)
            _kf.residual_power(spec, f, reg_hat, self.nyquist, power, energy)
            corr = np.fft.irfft(power, ident._corr_size, axis=1)
            _kf.abs_sum(corr, ident.max_lag + 1, j, 1.0 / ident.n)
        return energy

    def _pruned(self, spectra: NDArray[np.float64], f_all: NDArray[np.float64],
                reg_hat: NDArray[np.complex128]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """
        Return the curves with J only at the anchors and where the sign bounds allow a minimum.

        For any signs s_m, ``J >= sum_m s_m R(m) / n`` (eq. 13), and that sum is linear in the
        power spectrum: ``P . c_s`` with ``c_s`` a cosine transform of s. J is computed at every
        :data:`ANCHOR_STEP`-th order (by sorted order) with the signs of its lags; every other
        order gets the larger of the bounds with the signs of the anchors on either side (no
        transform), and its J only when that bound, less :data:`LOCATE_RTOL`, does not exceed
        the band where the minimum and its ties can be (:func:`_candidates` of the anchors'
        lowest J, a bound that can only be larger than the final one). Elsewhere J is +inf.
        """
        ident = self.ident
        assert self.cosine is not None and self.anchors is not None  # by the caller
        sin_t, cos_t = self.cosine
        big_n, k = sin_t.shape[0], ident.alphas.shape[0]
        out = np.empty((3, k))
        out[2] = f_all
        out[1] = np.inf
        anchors, others = self.anchors, self.others
        signs = np.zeros((anchors.size, big_n + 1))
        for start in range(0, anchors.size, FAST_BLOCK):
            rows = anchors[start:start + FAST_BLOCK]
            spec = (self.anchor_weights[start:start + FAST_BLOCK] @ spectra).view(np.complex128)
            j = np.empty(rows.size)
            energy = self._criteria(spec, f_all[rows], reg_hat, j,
                                    signs[start:start + FAST_BLOCK])
            out[0, rows] = self._variance(spec[:, 0].real, f_all[rows], reg_hat, energy)
            out[1, rows] = j
        folded = np.empty((anchors.size, big_n))
        odd = np.empty(anchors.size)
        _kf.cosine_fold(signs, sin_t, cos_t, folded, odd)
        weights = np.empty_like(signs)
        _kf.cosine_values(np.fft.rfft(folded, axis=1), odd, weights)
        # the transform counts lag 0 half (DCT-I) and the sum wants it whole; the end bins of
        # the half spectrum count half in the inverse transform
        weights += 0.5 * signs[:, :1]
        weights[:, 0] *= 0.5
        weights[:, -1] *= 0.5
        limit = _band(float(out[1, anchors].min())) / (1.0 - LOCATE_RTOL)
        f = f_all[others]
        energy, bound, dc = self._bounds(spectra, f, reg_hat, weights, 1.0 / (big_n * ident.n))
        out[0, others] = self._variance(dc, f, reg_hat, energy)
        keep = np.flatnonzero(~(bound > limit))   # NaN bounds kept: they prove nothing
        if keep.size:
            spec = (self.other_weights[keep] @ spectra).view(np.complex128)
            j = np.empty(keep.size)
            self._criteria(spec, f[keep], reg_hat, j)
            out[1, others[keep]] = j
        return out[0], out[1], out[2]

    def _bounds(self, spectra: NDArray[np.float64], f: NDArray[np.float64],
                reg_hat: NDArray[np.complex128], weights: NDArray[np.float64], scale: float
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """
        Return the Parseval sums, sign bounds and bin-0 values of the non-anchor orders.

        ``(energy, bound, dc)``, one value per order of :attr:`others` (``f`` their f): the
        difference spectra ``D = A X`` are made :data:`FAST_TILE` bins at a time, each tile
        read by :func:`._kernels_fractional.power_bound_tile` while it is in cache;
        ``bound = scale * max(P . c_lower, P . c_upper)`` (:meth:`_pruned`), ``dc = Re D(0)``.
        """
        rows, bins = self.others.size, reg_hat.shape[0]
        acc = np.zeros((rows, 4))
        buffer = np.empty(rows * 2 * min(bins, FAST_TILE))
        dc = np.empty(rows)
        for start in range(0, bins, FAST_TILE):
            stop = min(bins, start + FAST_TILE)
            d = buffer[:rows * 2 * (stop - start)].reshape(rows, 2 * (stop - start))
            np.matmul(self.other_weights, spectra[:, 2 * start:2 * stop], out=d)
            if start == 0:
                dc[:] = d[:, 0]
            _kf.power_bound_tile(d.view(np.complex128), f, reg_hat, weights, self.lower,
                                 self.upper, start, acc)
        bound = scale * np.maximum(acc[:, 2], acc[:, 3])
        return acc[:, 1] + 2.0 * acc[:, 0], bound, dc


def identify_order(chunk: npt.ArrayLike, *, alphas: npt.ArrayLike | None = None,
                   memory: int = DEFAULT_MEMORY, demean: bool = True, max_lag: int | None = None,
                   curves: bool = False) -> OrderIdentification:
    """
    Identify the fractional order of one chunk (convenience wrapper of :class:`OrderIdentifier`).

    Parameters
    ----------
    chunk : array_like
        Samples of angular rate (rad/s in this package).
    alphas, memory, demean, max_lag : keyword-only
        See :class:`OrderIdentifier`.
    curves : bool, keyword-only
        Also return the var(alpha), J(alpha) and f(alpha) curves.

    Returns
    -------
    OrderIdentification

    """
    chunk = np.asarray(chunk, dtype=np.float64)
    if chunk.ndim != 1:
        raise InputDataError(f'a chunk must be one-dimensional, got shape {chunk.shape}')
    ident = OrderIdentifier(chunk.shape[0], alphas=alphas, memory=memory,
                            demean=demean, max_lag=max_lag)
    return ident(chunk, curves=curves)


def validate_chunk(chunk: npt.ArrayLike, size: int) -> NDArray[np.float64]:
    """
    Return ``chunk`` as a float64 vector of ``size`` finite samples, or raise InputDataError.

    Parameters
    ----------
    chunk : array_like
        Samples.
    size : int
        Required length.

    Returns
    -------
    numpy.ndarray

    """
    v = np.asarray(chunk, dtype=np.float64)
    if v.ndim != 1:
        raise InputDataError(f'a chunk must be one-dimensional, got shape {v.shape}')
    if v.shape[0] != size:
        raise InputDataError(f'chunk has {v.shape[0]} samples, expected {size}')
    bad = ~np.isfinite(v)
    if bad.any():
        first = int(np.argmax(bad))
        raise InputDataError(
            f'chunk has {int(bad.sum())} NaN/Inf sample(s), first at index {first}')
    if np.ptp(v) == 0.0:
        raise InputDataError(f'chunk is constant (all samples = {v[0]!r}): the order is undefined')
    return v


def select_minimum(alphas: NDArray[np.float64],
                   curve: NDArray[np.float64]) -> tuple[int, NDArray[np.intp]]:
    """
    Return (index, tied indices) of the minimum of ``curve`` under the tie rule of the module doc.

    Parameters
    ----------
    alphas : numpy.ndarray
        Grid orders.
    curve : numpy.ndarray
        Criterion over the grid.

    Returns
    -------
    tuple
        Index of the reported order (the largest among exact ties) and the array of tied indices.

    """
    finite = np.isfinite(curve)
    if not finite.any():
        raise InputDataError(
            'the identification criterion is not finite for any order on the grid')
    low = np.min(curve[finite])
    tied = np.flatnonzero(finite & (curve <= low + TIE_RTOL * abs(low)))
    best = tied[np.argmax(alphas[tied])]
    return int(best), tied


def _summarise(alphas: NDArray[np.float64], var_curve: NDArray[np.float64],
               j_curve: NDArray[np.float64], f_curve: NDArray[np.float64], bias: float,
               curves: bool) -> OrderIdentification:
    iv, tv = select_minimum(alphas, var_curve)
    ij, tj = select_minimum(alphas, j_curve)
    return OrderIdentification(
        alpha_var=float(alphas[iv]), f_var=float(f_curve[iv]), var_min=float(var_curve[iv]),
        alpha_corr=float(alphas[ij]), f_corr=float(f_curve[ij]), j_min=float(j_curve[ij]),
        tied_alphas_var=tuple(float(a) for a in alphas[tv]),
        tied_alphas_corr=tuple(float(a) for a in alphas[tj]),
        bias=bias, alphas=alphas,
        var_curve=var_curve if curves else None,
        j_curve=j_curve if curves else None,
        f_curve=f_curve if curves else None)


def physical_memory_bytes() -> int | None:
    """
    Return the machine's physical memory in bytes, or None where the OS does not say.

    Returns
    -------
    int or None

    """
    try:
        pages, page = os.sysconf('SC_PHYS_PAGES'), os.sysconf('SC_PAGE_SIZE')
    except (AttributeError, ValueError, OSError):  # Windows has no sysconf
        return None
    return pages * page if pages > 0 and page > 0 else None


def table_bytes(orders: int, chunk_size: int, memory: int) -> int:
    """
    Estimate the bytes of the spectra an :class:`OrderIdentifier` keeps (its largest tables).

    Per grid order (``orders`` of them), the complex128 half spectrum of the GL coefficients padded
    to about ``chunk_size + memory`` points, for the exact and the fast algorithm: 16 B a point.
    """
    return 16 * int(orders) * (int(chunk_size) + int(memory))


def _check_table_memory(orders: int, chunk_size: int, memory: int) -> None:
    # Refuse before allocating: a chunk size beyond the machine otherwise ends in a MemoryError
    # (or an OverflowError in the FFT planner) deep inside numpy/scipy. Half of the physical
    # memory leaves room for the data, the worker processes and the rest of the system.
    total = physical_memory_bytes()
    need = table_bytes(orders, chunk_size, memory)
    if total is not None and need > total // 2:
        raise ParameterError(
            f'chunk_size ({chunk_size}) with memory L = {memory} needs about '
            f'{need / 2**30:.3g} GiB for the tables of the {orders} grid orders, more than half '
            f"of this machine's {total / 2**30:.3g} GiB; the paper uses 10000 samples per chunk")


def _check_memory(memory: int) -> int:
    try:
        memory_i = int(memory)
    except (TypeError, ValueError) as err:
        raise ParameterError(f'memory L must be an integer, got {memory!r}') from err
    if memory_i != memory or memory_i < 1:
        raise ParameterError(f'memory L must be an integer >= 1, got {memory!r}')
    return memory_i
