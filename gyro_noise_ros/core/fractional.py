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

where ``k`` counts samples from the start of the analysed chunk (the chunk is the paper's unit of
identification, so each chunk starts a fresh memory). For each order on a grid, ``f`` is the
least-squares solution of eqs. (6)-(8) and the source noise is the equation error of eq. (9),
``w[k] = Delta^alpha v[k+1] - f v[k]`` for ``k = 0 .. N-2`` (``n = N - 1`` values).

Two order estimates (section 2, last part):

* variance method: the order minimising ``var(w)`` (population variance, mean of ``w`` removed);
* correlation method: the order minimising ``J = sum_{m=0}^{M} |R_w(m)|`` (eq. 13) with the biased
  autocorrelation estimate ``R_w(m) = (1/n) sum_{k=0}^{n-1-m} w[k+m] w[k]`` (eq. 14); by default
  every lag, ``M = n - 1``.

Exact ties. For any data, order 0 and order 1 give the *same* residual: ``c_j`` vanishes for ``j >=
2`` at both orders and the ``c_1 v[k]`` term is absorbed by ``f`` (``f_0 = f_1 + 1``). The same
holds for any two orders whose coefficients differ only in ``c_0, c_1``, which on a grid means
exactly {0, 1}. When the minimum of a curve is attained (within a relative 1e-9, far above rounding
and far below any real difference) at several grid orders, the **largest** tied order is reported,
because the paper reads order 1 as the integer-order (first-order colour) model of eq. (1); the tie
is reported in ``tied_alphas_*`` and never hidden.
"""

from dataclasses import dataclass

import numpy as np
import scipy.fft

from ..errors import InputDataError, ParameterError

#: Default memory length L of the truncated GL difference (paper 000: "L = 1000 is used for all
#: computations").
DEFAULT_MEMORY = 1000

#: Relative tolerance under which two grid values of a criterion count as an exact tie (see module
#: doc).
TIE_RTOL = 1e-9


def default_grid():
    """
    Return the default order grid, 0.00 to 2.00 in steps of 0.01, both ends included.

    Returns
    -------
    numpy.ndarray
        201 orders (dimensionless).

    """
    return np.round(np.arange(201) * 0.01, 10)


def make_grid(start, stop, step):
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
    count = int(np.floor((stop - start) / step + 1e-9)) + 1
    if count > 100000:
        raise ParameterError(f'order grid {start}:{stop}:{step} has {count} points (max 100000)')
    return np.round(start + step * np.arange(count), 10)


def parse_grid(text):
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


def gl_coefficients(alpha, memory=DEFAULT_MEMORY):
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


def gl_difference(x, alpha, *, memory=DEFAULT_MEMORY):
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
    tied_alphas_var: tuple
    tied_alphas_corr: tuple
    bias: float
    alphas: np.ndarray
    var_curve: np.ndarray = None
    j_curve: np.ndarray = None
    f_curve: np.ndarray = None


class OrderIdentifier:
    """
    Identify the fractional order of chunks of a fixed length, fast (paper 000 eqs. 3-14).

    The GL filters of every grid order are transformed once; each chunk then costs one forward FFT,
    and per order one inverse FFT (the truncated difference), one forward and one inverse FFT (the
    full autocorrelation of the source noise). The results equal the direct per-order convolution
    and correlation to rounding (checked in ``test/test_fractional.py`` against
    ``test/_fractional_reference.py``).

    Parameters
    ----------
    chunk_size : int
        N, the number of samples per chunk (> memory + 2... at least ``memory + 2``).
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
        Orders processed per vectorised block (memory/speed trade-off only).

    """

    def __init__(self, chunk_size, *, alphas=None, memory=DEFAULT_MEMORY, demean=True,
                 max_lag=None, block=8):
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
        self.max_lag = max_lag
        self.demean = bool(demean)
        self.block = max(1, int(block))
        self._conv_size = scipy.fft.next_fast_len(chunk_size + self.memory, real=True)
        self._corr_size = scipy.fft.next_fast_len(self.n + self.max_lag + 1, real=True)
        coeffs = np.stack([gl_coefficients(a, self.memory) for a in self.alphas])
        self._coeff_hat = scipy.fft.rfft(coeffs, self._conv_size, axis=1)

    def __call__(self, chunk, *, curves=False):
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
        var_curve, j_curve, f_curve = self._curves(v)
        return _summarise(self.alphas, var_curve, j_curve, f_curve, bias, curves)

    def _curves(self, v):
        n, size = self.n, self._conv_size
        w_reg = v[:-1]
        ww = float(w_reg @ w_reg)
        if ww == 0.0:
            raise InputDataError(
                'the chunk is constant after removing its mean: the order is undefined')
        v_hat = scipy.fft.rfft(v, size)
        k = len(self.alphas)
        var_curve = np.empty(k)
        j_curve = np.empty(k)
        f_curve = np.empty(k)
        # w is written into a zero-padded buffer so the correlation FFT needs no padding copy
        padded = np.zeros((self.block, self._corr_size))
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
            power = np.multiply(spec, spec.conj(), out=spec)
            r = scipy.fft.irfft(power, self._corr_size, axis=1)
            j_curve[start:stop] = np.abs(r[:, :self.max_lag + 1]).sum(axis=1) / n
            f_curve[start:stop] = f
        return var_curve, j_curve, f_curve


def identify_order(chunk, *, alphas=None, memory=DEFAULT_MEMORY, demean=True, max_lag=None,
                   curves=False):
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


def validate_chunk(chunk, size):
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


def select_minimum(alphas, curve):
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


def _summarise(alphas, var_curve, j_curve, f_curve, bias, curves):
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


def _check_memory(memory):
    try:
        memory_i = int(memory)
    except (TypeError, ValueError) as err:
        raise ParameterError(f'memory L must be an integer, got {memory!r}') from err
    if memory_i != memory or memory_i < 1:
        raise ParameterError(f'memory L must be an integer >= 1, got {memory!r}')
    return memory_i
