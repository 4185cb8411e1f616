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
Elman network trained by beetle antennae search (paper 002, eqs. 28-34).

The network maps the temperature field M = [T, dT] (degC, degC/s; eq. 28) to the drift S (the
gyro's unit, rad/s; eq. 29) with two sigmoid hidden layers, each fed back through a context layer
holding its previous output (eq. 33; the linear output layer is our reading of its open f)::

    OI(k) = sigmoid(W1 OI(k - 1) + W2 X(k) - a_i)
    OH(k) = sigmoid(W3 OI(k) + W4 OH(k - 1) - a_j)
    Y(k)  = W5 OH(k) - a_k

Inputs and output are scaled to [-1, 1] with the training ranges (the scalers are part of the
model), except ``symmetric`` columns (the rate), divided by their largest magnitude so that a
steady temperature stays 0. Contexts start at 0.5; the recurrence runs at the fixed step ``dt_s``
it was trained on.

All weights and thresholds form one vector found by beetle antennae search (eqs. 30-32, 34):
antennae at ``x +- d b`` along a random unit direction b, a step
``x <- x - lam b sign(f(x + d b) - f(x - d b))`` towards the lower mean squared error, decay
``d <- 0.95 d + 0.01``, ``lam <- 0.95 lam``, restarted in ``epochs`` (one epoch is the paper's
algorithm). Ours, beyond the paper: L-BFGS from BAS's best point on the same fitness with its
exact gradient (back-propagation through time, :func:`_mse_grad`; ``refine_iterations = 0`` is
BAS alone), and :func:`fit_drift`, a stated basis (cubic in T, linear in dT) before the network.
Why, and the measured errors of each stage: docs/thermal_model.md (Elman network section).
"""

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from gyro_noise_ros.errors import InputDataError, ParameterError
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.optimize

# (best weights, their fitness, per step (d, step, fitness)) of bas_minimize.
_BasResult = tuple[NDArray[np.float64], float, list[tuple[float, float, float]]]


@numba.njit(cache=True)
def _offsets(n_in: int, n1: int,
             n2: int) -> tuple[int, int, int, int, int, int, int, int]:  # pragma: no cover - JIT
    """Return where W1, W2, a_i, W3, W4, a_j, W5 and a_k start in the weight vector."""
    o_w2 = n1 * n1
    o_ai = o_w2 + n1 * n_in
    o_w3 = o_ai + n1
    o_w4 = o_w3 + n2 * n1
    o_aj = o_w4 + n2 * n2
    o_w5 = o_aj + n2
    return 0, o_w2, o_ai, o_w3, o_w4, o_aj, o_w5, o_w5 + n2


@numba.njit(cache=True)
def _unpack(theta: NDArray[np.float64], n_in: int, n1: int,
            n2: int) -> tuple[Any, ...]:  # pragma: no cover - JIT
    """Return views of W1, W2, a_i, W3, W4, a_j, W5 and the scalar a_k (eq. 33)."""
    o_w1, o_w2, o_ai, o_w3, o_w4, o_aj, o_w5, o_ak = _offsets(n_in, n1, n2)
    return (theta[o_w1:o_w2].reshape(n1, n1), theta[o_w2:o_ai].reshape(n1, n_in),
            theta[o_ai:o_w3], theta[o_w3:o_w4].reshape(n2, n1),
            theta[o_w4:o_aj].reshape(n2, n2), theta[o_aj:o_w5], theta[o_w5:o_ak], theta[o_ak])


@numba.njit(cache=True)
def _forward(theta: NDArray[np.float64], x: NDArray[np.float64], n1: int,
             n2: int) -> NDArray[np.float64]:  # pragma: no cover - JIT
    """Run the Elman recurrence of eq. 33 over inputs x (n, n_in); return y (n,)."""
    n, n_in = x.shape
    w1, w2, ai, w3, w4, aj, w5, ak = _unpack(theta, n_in, n1, n2)
    oi = np.full(n1, 0.5)
    oh = np.full(n2, 0.5)
    new_i = np.empty(n1)
    new_h = np.empty(n2)
    y = np.empty(n)
    for k in range(n):
        for i in range(n1):
            s = -ai[i]
            for j in range(n1):
                s += w1[i, j] * oi[j]
            for j in range(n_in):
                s += w2[i, j] * x[k, j]
            new_i[i] = 1.0 / (1.0 + np.exp(-s))
        for i in range(n2):
            s = -aj[i]
            for j in range(n1):
                s += w3[i, j] * new_i[j]
            for j in range(n2):
                s += w4[i, j] * oh[j]
            new_h[i] = 1.0 / (1.0 + np.exp(-s))
        out = -ak
        for j in range(n2):
            out += w5[j] * new_h[j]
        y[k] = out
        oi[:] = new_i
        oh[:] = new_h
    return y


@numba.njit(cache=True)
def _mse_grad(theta: NDArray[np.float64], x: NDArray[np.float64], y: NDArray[np.float64], n1: int,
              n2: int) -> tuple[float, NDArray[np.float64]]:  # pragma: no cover - JIT
    """Return (mean squared error of eq. 34, its gradient) by back-propagation through time."""
    n, n_in = x.shape
    w1, w2, ai, w3, w4, aj, w5, ak = _unpack(theta, n_in, n1, n2)
    _, o_w2, o_ai, o_w3, o_w4, o_aj, o_w5, o_ak = _offsets(n_in, n1, n2)
    # forward pass, keeping every state (row k + 1 is step k; row 0 the 0.5 start)
    oi = np.full((n + 1, n1), 0.5)
    oh = np.full((n + 1, n2), 0.5)
    err = np.empty(n)
    for k in range(n):
        for i in range(n1):
            s = -ai[i]
            for j in range(n1):
                s += w1[i, j] * oi[k, j]
            for j in range(n_in):
                s += w2[i, j] * x[k, j]
            oi[k + 1, i] = 1.0 / (1.0 + np.exp(-s))
        for i in range(n2):
            s = -aj[i]
            for j in range(n1):
                s += w3[i, j] * oi[k + 1, j]
            for j in range(n2):
                s += w4[i, j] * oh[k, j]
            oh[k + 1, i] = 1.0 / (1.0 + np.exp(-s))
        out = -ak
        for j in range(n2):
            out += w5[j] * oh[k + 1, j]
        err[k] = out - y[k]
    mse = 0.0
    for k in range(n):
        mse += err[k] * err[k]
    mse /= n
    # backward pass
    g = np.zeros(theta.size)
    g_w1 = g[0:o_w2].reshape(n1, n1)
    g_w2 = g[o_w2:o_ai].reshape(n1, n_in)
    g_w3 = g[o_w3:o_w3 + n2 * n1].reshape(n2, n1)
    g_w4 = g[o_w4:o_w4 + n2 * n2].reshape(n2, n2)
    carry_i = np.zeros(n1)
    carry_h = np.zeros(n2)
    d_h = np.zeros(n2)
    d_i = np.zeros(n1)
    for k in range(n - 1, -1, -1):
        dy = 2.0 * err[k] / n
        g[o_ak] -= dy
        for j in range(n2):
            g[o_w5 + j] += dy * oh[k + 1, j]
            h = oh[k + 1, j]
            d_h[j] = (dy * w5[j] + carry_h[j]) * h * (1.0 - h)
        for i in range(n2):
            g[o_aj + i] -= d_h[i]
            for j in range(n1):
                g_w3[i, j] += d_h[i] * oi[k + 1, j]
            for j in range(n2):
                g_w4[i, j] += d_h[i] * oh[k, j]
        for j in range(n1):
            s = carry_i[j]
            for i in range(n2):
                s += w3[i, j] * d_h[i]
            v = oi[k + 1, j]
            d_i[j] = s * v * (1.0 - v)
        for i in range(n1):
            g[o_ai + i] -= d_i[i]
            for j in range(n1):
                g_w1[i, j] += d_i[i] * oi[k, j]
            for j in range(n_in):
                g_w2[i, j] += d_i[i] * x[k, j]
        for j in range(n2):
            s = 0.0
            for i in range(n2):
                s += w4[i, j] * d_h[i]
            carry_h[j] = s
        for j in range(n1):
            s = 0.0
            for i in range(n1):
                s += w1[i, j] * d_i[i]
            carry_i[j] = s
    return mse, g


def n_weights(n_in: int, hidden: Sequence[int]) -> int:
    """Return the length of the weight vector of an Elman network (eq. 33)."""
    n1, n2 = hidden
    return int(_offsets(int(n_in), int(n1), int(n2))[-1]) + 1


def bas_minimize(fun: Callable[[NDArray[np.float64]], float], x0: ArrayLike, *,
                 rng: np.random.Generator, iterations: int = 100, epochs: int = 1, d0: float = 1.0,
                 step0: float = 1.0) -> _BasResult:
    """
    Minimise ``fun`` by beetle antennae search (eqs. 30-32, the paper's decay rules).

    Parameters
    ----------
    fun : callable
        ``fun(x) -> float`` to minimise.
    x0 : array_like
        Starting point (n,).
    rng : numpy.random.Generator, keyword-only
        Source of the random directions.
    iterations : int, keyword-only
        Steps per epoch.
    epochs : int, keyword-only
        Restarts of d and lam from ``d0`` and ``step0`` at the best point so far.
    d0, step0 : float, keyword-only
        Initial antenna length d and step lam.

    Returns
    -------
    tuple
        (best x, best value, history of (d, lam, value) per step).

    """
    x = np.array(x0, dtype=float)
    best_x, best_f = x.copy(), float(fun(x))
    history = []
    for _ in range(int(epochs)):
        x = best_x.copy()
        d, lam = float(d0), float(step0)
        for _ in range(int(iterations)):
            b = rng.standard_normal(x.size)
            b /= np.linalg.norm(b) + 1e-300
            f_r = float(fun(x + d * b))
            f_l = float(fun(x - d * b))
            x = x - lam * b * np.sign(f_r - f_l)
            f_x = float(fun(x))
            for cand, val in ((x, f_x), (x + d * b, f_r), (x - d * b, f_l)):
                if val < best_f:
                    best_x, best_f = cand.copy(), val
            history.append((d, lam, f_x))
            d = 0.95 * d + 0.01
            lam = 0.95 * lam
    return best_x, best_f, history


@dataclass(frozen=True)
class ElmanModel:
    """
    A fitted Elman network with its input/output scalers.

    Attributes
    ----------
    theta : numpy.ndarray
        Weights and thresholds (eq. 33), layout of :func:`_forward`.
    hidden : tuple
        Sizes of the two hidden layers.
    x_lo, x_hi : numpy.ndarray
        Input scaling: each input column maps ``[x_lo, x_hi]`` to [-1, 1] (T in degC, dT in
        degC/s; for dT the span is symmetric about 0, see :func:`fit_elman`).
    y_lo, y_hi : float
        Training range of the output, mapped to [-1, 1].
    dt_s : float
        Step of the recurrence, seconds.
    train_mse : float
        Final fitness (eq. 34) on the normalised training output.
    bas_mse : float or None
        Fitness after beetle antennae search, before the local refinement (None: not recorded).
    theta_bas : numpy.ndarray or None
        Weights after beetle antennae search, before the local refinement.

    """

    theta: np.ndarray
    hidden: tuple
    x_lo: np.ndarray
    x_hi: np.ndarray
    y_lo: float
    y_hi: float
    dt_s: float
    train_mse: float
    bas_mse: float | None = None
    theta_bas: NDArray[np.float64] | None = None

    def predict(self, inputs: ArrayLike, *, theta: ArrayLike | None = None) -> NDArray[np.float64]:
        """
        Return the output (n,) for inputs (n, n_in) sampled every ``dt_s`` seconds.

        ``theta`` evaluates other weights with this model's scalers (e.g. :attr:`theta_bas`).
        """
        x = np.asarray(inputs, dtype=float)
        span = np.where(self.x_hi > self.x_lo, self.x_hi - self.x_lo, 1.0)
        xn = 2.0 * (x - self.x_lo) / span - 1.0
        weights = self.theta if theta is None else np.asarray(theta, dtype=float)
        yn = _forward(weights, np.ascontiguousarray(xn), self.hidden[0], self.hidden[1])
        return self.y_lo + (yn + 1.0) * 0.5 * (self.y_hi - self.y_lo)

    def to_dict(self) -> dict[str, Any]:
        """Return every parameter as JSON-able values."""
        d = {'theta': self.theta.tolist(), 'hidden': list(self.hidden),
             'x_lo': self.x_lo.tolist(), 'x_hi': self.x_hi.tolist(),
             'y_lo': self.y_lo, 'y_hi': self.y_hi, 'dt_s': self.dt_s,
             'train_mse': self.train_mse}
        if self.bas_mse is not None:
            d['bas_mse'] = self.bas_mse
        if self.theta_bas is not None:
            d['theta_bas'] = np.asarray(self.theta_bas).tolist()
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'ElmanModel':
        """Rebuild a model from :meth:`to_dict` output (older files lack the BAS stage)."""
        bas = d.get('theta_bas')
        return cls(theta=np.asarray(d['theta'], dtype=float), hidden=tuple(d['hidden']),
                   x_lo=np.asarray(d['x_lo'], dtype=float),
                   x_hi=np.asarray(d['x_hi'], dtype=float), y_lo=float(d['y_lo']),
                   y_hi=float(d['y_hi']), dt_s=float(d['dt_s']),
                   train_mse=float(d['train_mse']),
                   bas_mse=None if d.get('bas_mse') is None else float(d['bas_mse']),
                   theta_bas=None if bas is None else np.asarray(bas, dtype=float))


def fit_elman(inputs: ArrayLike, target: ArrayLike, *, dt_s: float, rng: np.random.Generator,
              hidden: Sequence[int] = (6, 6), iterations: int = 100, epochs: int = 20,
              d0: float = 1.0, step0: float = 1.0, init_scale: float = 0.5,
              refine_iterations: int = 300, symmetric: Sequence[int] = (),
              weight_decay: float = 0.0) -> ElmanModel:
    """
    Fit an Elman network to a target series: beetle antennae search, then a local refinement.

    Parameters
    ----------
    inputs : array_like
        (n, n_in) input sequence, e.g. columns T (degC) and dT (degC/s), on a grid of step
        ``dt_s``.
    target : array_like
        (n,) output sequence (the drift part, rad/s).
    dt_s : float, keyword-only
        Grid step, seconds (stored; predictions must use the same step).
    rng : numpy.random.Generator, keyword-only
        Initial weights and search directions.
    hidden : tuple, keyword-only
        Sizes of the two hidden layers.
    iterations, epochs, d0, step0 : keyword-only
        Beetle antennae search settings (see :func:`bas_minimize`).
    init_scale : float, keyword-only
        Standard deviation of the random initial weights.
    refine_iterations : int, keyword-only
        Iterations of L-BFGS (scipy) on the same fitness from the best point BAS found, with
        the exact gradient (back-propagation through time); 0 keeps BAS's weights (the paper's
        algorithm alone).
    symmetric : sequence of int, keyword-only
        Input columns scaled by their largest magnitude (0 stays 0, the span is
        ``[-max |x|, max |x|]``) instead of their min..max: a rate, whose zero is the steady
        state and whose sign a one-way training run may never change.
    weight_decay : float, keyword-only
        Adds ``weight_decay * |theta|^2`` to the fitness (both stages): small weights keep
        the sigmoids near their linear range, so the network stays smooth where the training
        run has no data.

    Returns
    -------
    ElmanModel
        The network with the lowest training MSE found, and its scalers.

    """
    x = np.asarray(inputs, dtype=float)
    y = np.asarray(target, dtype=float).reshape(-1)
    if x.ndim != 2 or x.shape[0] != y.size or y.size < 2:
        raise InputDataError(f'inputs (n, n_in) and target (n,) do not match: {x.shape}, '
                             f'{y.shape}')
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputDataError('fit_elman: inputs or target contain NaN or Inf')
    hidden = tuple(int(h) for h in hidden)
    if len(hidden) != 2 or min(hidden) < 1:
        raise ParameterError(f'hidden must be two sizes >= 1, got {hidden!r}')
    if int(refine_iterations) < 0:
        raise ParameterError(f'refine_iterations must be >= 0, got {refine_iterations!r}')
    x_lo, x_hi = x.min(axis=0), x.max(axis=0)
    for col in symmetric:
        if not 0 <= int(col) < x.shape[1]:
            raise ParameterError(f'symmetric column {col!r} out of range 0..{x.shape[1] - 1}')
        big = float(np.max(np.abs(x[:, int(col)])))
        x_lo[int(col)], x_hi[int(col)] = -big, big
    y_lo, y_hi = float(y.min()), float(y.max())
    if y_hi == y_lo:
        y_hi = y_lo + 1.0
    span = np.where(x_hi > x_lo, x_hi - x_lo, 1.0)
    xn = np.ascontiguousarray(2.0 * (x - x_lo) / span - 1.0)
    yn = 2.0 * (y - y_lo) / (y_hi - y_lo) - 1.0

    wd = float(weight_decay)

    def mse(theta: NDArray[np.float64]) -> float:
        return float(np.mean((_forward(theta, xn, hidden[0], hidden[1]) - yn) ** 2)
                     + wd * np.dot(theta, theta))

    def mse_grad(theta: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        value, grad = _mse_grad(theta, xn, yn, hidden[0], hidden[1])
        return value + wd * np.dot(theta, theta), grad + 2.0 * wd * theta

    theta0 = init_scale * rng.standard_normal(n_weights(x.shape[1], hidden))
    theta_bas, bas_mse, _ = bas_minimize(mse, theta0, rng=rng, iterations=iterations,
                                         epochs=epochs, d0=d0, step0=step0)
    theta, best = theta_bas, bas_mse
    if int(refine_iterations) > 0:
        res = scipy.optimize.minimize(mse_grad, theta_bas, jac=True, method='L-BFGS-B',
                                      options={'maxiter': int(refine_iterations)})
        # keep whichever is better: L-BFGS returns its last point, which a line search that
        # failed on a flat stretch may leave no better than the start
        refined = mse(res.x)
        if refined < best:
            theta, best = np.asarray(res.x, dtype=float), refined
    return ElmanModel(theta=theta, hidden=hidden, x_lo=x_lo, x_hi=x_hi, y_lo=y_lo, y_hi=y_hi,
                      dt_s=float(dt_s), train_mse=best, bas_mse=float(bas_mse),
                      theta_bas=np.asarray(theta_bas, dtype=float))


#: Stated bases of :class:`DriftModel` (least squares first, the network on what is left).
DRIFT_BASES = ('cubic_rate', 'none')


def drift_basis(inputs: ArrayLike, t_ref_c: float, base: str) -> NDArray[np.float64]:
    """
    Return the design matrix of a stated drift basis at inputs (n, 2) = [T, dT].

    ``'cubic_rate'``: ``1, d, d^2, d^3, dT`` with ``d = T - t_ref_c`` (a cubic in temperature
    and a term linear in its rate: the form of a thermal-gradient drift); ``'none'``: no
    columns.

    Parameters
    ----------
    inputs : array_like
        (n, 2): T (degC), dT (degC/s).
    t_ref_c : float
        Centre of the polynomial (degC).
    base : str
        One of :data:`DRIFT_BASES`.

    Returns
    -------
    numpy.ndarray
        (n, 5) or (n, 0).

    """
    x = np.asarray(inputs, dtype=float)
    if base == 'none':
        return np.zeros((x.shape[0], 0))
    if base != 'cubic_rate':
        raise ParameterError(f'drift base must be one of {DRIFT_BASES}, got {base!r}')
    d = x[:, 0] - t_ref_c
    return np.column_stack([np.ones_like(d), d, d * d, d * d * d, x[:, 1]])


@dataclass(frozen=True)
class DriftModel:
    """
    The drift model of the parallel model: a stated basis plus an Elman network on the rest.

    ``predict(M) = basis(M) @ coef + network(clip(M))``: the basis (least squares) continues
    beyond the trained range of [T, dT]; the network's part is evaluated with its inputs held
    at the edge of that range (a network extrapolates to anything; the basis extrapolates the
    way its stated form says).

    Attributes
    ----------
    base : str
        One of :data:`DRIFT_BASES`.
    t_ref_c : float
        Centre of the basis polynomial (degC).
    coef : numpy.ndarray
        Basis coefficients (output unit per unit of each column).
    network : ElmanModel
        The network trained on the target minus the basis fit.
    range_lo, range_hi : numpy.ndarray
        Trained range of each input (the network's inputs are clipped to it).

    """

    base: str
    t_ref_c: float
    coef: np.ndarray
    network: ElmanModel
    range_lo: np.ndarray
    range_hi: np.ndarray

    @property
    def dt_s(self) -> float:
        """float: step of the grid the model runs on (s)."""
        return self.network.dt_s

    def outside(self, inputs: ArrayLike) -> NDArray[np.bool_]:
        """Return a boolean (n,) marking input rows outside the trained range."""
        x = np.asarray(inputs, dtype=float)
        return np.any((x < self.range_lo) | (x > self.range_hi), axis=1)

    def base_part(self, inputs: ArrayLike) -> NDArray[np.float64]:
        """Return the basis part of the prediction (n,)."""
        return drift_basis(inputs, self.t_ref_c, self.base) @ self.coef

    def predict(self, inputs: ArrayLike, *, theta: ArrayLike | None = None) -> NDArray[np.float64]:
        """Return the drift (n,) at inputs (n, 2) on the grid (``theta``: see ElmanModel)."""
        x = np.asarray(inputs, dtype=float)
        held = np.clip(x, self.range_lo, self.range_hi)
        return self.base_part(x) + self.network.predict(held, theta=theta)

    def to_dict(self) -> dict[str, Any]:
        """Return every parameter as JSON-able values."""
        return {'base': self.base, 't_ref_c': self.t_ref_c, 'coef': self.coef.tolist(),
                'range_lo': self.range_lo.tolist(), 'range_hi': self.range_hi.tolist(),
                'network': self.network.to_dict()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'DriftModel':
        """
        Rebuild from :meth:`to_dict` output, or from an older model's bare network dict.

        A bare :class:`ElmanModel` dict (the drift model before the basis existed) becomes
        ``base = 'none'`` with the network's own scaling range as the trained range.
        """
        if 'network' not in d:
            net = ElmanModel.from_dict(d)
            return cls(base='none', t_ref_c=0.0, coef=np.zeros(0), network=net,
                       range_lo=np.full(net.x_lo.size, -np.inf),
                       range_hi=np.full(net.x_hi.size, np.inf))
        return cls(base=str(d['base']), t_ref_c=float(d['t_ref_c']),
                   coef=np.asarray(d['coef'], dtype=float),
                   network=ElmanModel.from_dict(d['network']),
                   range_lo=np.asarray(d['range_lo'], dtype=float),
                   range_hi=np.asarray(d['range_hi'], dtype=float))


def fit_drift(inputs: ArrayLike, target: ArrayLike, *, dt_s: float, rng: np.random.Generator,
              base: str = 'cubic_rate', **network_options: Any) -> DriftModel:
    """
    Fit a :class:`DriftModel`: least squares on the stated basis, then the network on the rest.

    Parameters
    ----------
    inputs : array_like
        (n, 2) [T (degC), dT (degC/s)] on a grid of step ``dt_s``.
    target : array_like
        (n,) the drift part (rad/s).
    dt_s : float, keyword-only
        Grid step (s).
    rng : numpy.random.Generator, keyword-only
        For the network (:func:`fit_elman`).
    base : str, keyword-only
        One of :data:`DRIFT_BASES`.
    **network_options
        Passed to :func:`fit_elman` (``symmetric=(1,)`` unless given).

    Returns
    -------
    DriftModel

    """
    x = np.asarray(inputs, dtype=float)
    y = np.asarray(target, dtype=float).reshape(-1)
    if x.ndim != 2 or x.shape[1] != 2 or x.shape[0] != y.size:
        raise InputDataError(f'fit_drift needs inputs (n, 2) and target (n,), got {x.shape}, '
                             f'{y.shape}')
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputDataError('fit_drift: inputs or target contain NaN or Inf')
    t_ref = float(np.mean(x[:, 0]))
    a = drift_basis(x, t_ref, base)
    coef = np.zeros(a.shape[1])
    if a.shape[1]:
        if x.shape[0] < 2 * a.shape[1]:
            raise InputDataError(f'fit_drift: {x.shape[0]} grid points for a {a.shape[1]}-term '
                                 'basis')
        # columns scaled to rms 1 for conditioning (d^3 spans ~1e4 where dT spans ~1e-2)
        scale = np.sqrt(np.mean(a * a, axis=0))
        scale = np.where(scale > 0, scale, 1.0)
        coef = np.linalg.lstsq(a / scale, y, rcond=None)[0] / scale
    network_options.setdefault('symmetric', (1,))
    net = fit_elman(x, y - a @ coef, dt_s=dt_s, rng=rng, **network_options)
    return DriftModel(base=base, t_ref_c=t_ref, coef=coef, network=net,
                      range_lo=x.min(axis=0), range_hi=x.max(axis=0))
