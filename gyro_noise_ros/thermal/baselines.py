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
The baselines the parallel model of paper 002 is measured against, as ThermalMethods.

- ``raw``: the gyro output unchanged (causal).
- ``wtd``: wavelet-threshold denoising (Donoho-Johnstone universal threshold, soft), the
  paper's first comparison; removes noise, keeps the drift (non-causal).
- ``bp``: a back-propagation network (one sigmoid hidden layer) from [T, dT] to the gyro
  offset, the paper's second comparison (causal).
- ``emd_wtd_sabp``: EMD; the fast IMFs denoised by WTD; the slow IMFs and the residue (the
  drift) compensated by a BP network found by simulated annealing and refined by gradient
  descent, the paper's third comparison (non-causal).
- ``poly3``: the PX4 / ArduPilot thermal calibration, per axis a cubic of the gyro offset in
  (T - T_ref) (causal); it cannot represent a drift that depends on dT.
- ``linear_tdt``: linear least squares on the monomials of T and dT up to total degree 3 (causal).

T in degC, dT in degC/s, always :func:`~gyro_noise_ros.thermal.run.temperature_rate_c_s` (causal
trailing-window slope), so what is fitted offline is what the live node evaluates; rates in
rad/s. Causal methods give ``drift_rad_s(temperature_c, dtemp_c_s)``, and ``apply(run)`` is
exactly ``gyro - drift_rad_s(T, dT)``. Outside the trained range of T and dT each method states
what it does (``out_of_range``, :func:`gyro_noise_ros.thermal.methods.range_report`): ``poly3``
holds the offset at the range's ends (as PX4 and ArduPilot do), ``linear_tdt`` extrapolates its
polynomial, ``bp`` and ``emd_wtd_sabp`` continue their network linearly along its gradient.
Equations and constants: ``docs/thermal_data.md``.
"""

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .run import (DEFAULT_RATE_WINDOW_S, rate_support, RateSupport, RateWindowError,
                  temperature_rate_c_s, ThermalRun)
from ..errors import InputDataError, ParameterError

#: A temperature model needs at least this temperature span in its training run (degC).
MIN_TEMPERATURE_SPAN_C = 1.0
#: A method that uses dT needs a training run at least this many rate windows long: one to fill
#: the trailing window, one of filled rates to see dT vary (with less, a 10-term fit on a 5-s run
#: once gave coefficients of several rad/s).
MIN_TRAINING_WINDOWS = 2.0

# Two, three and four float arrays: (t, gyro, temperature) of a run, a network's weights
# unpacked (W1, b1, W2, b2) or its scalers (x mean, x std, y mean, y std).
_Pair = tuple[NDArray[np.float64], NDArray[np.float64]]
_Triple = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
_Quad = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
# A network's linear shortcut: its basis and coefficients (k, 3).
_Shortcut = tuple['_PolyBasis', NDArray[np.floating[Any]]]
# A decomposition: denoised (n, 3), drift (n, 3), IMF classes per axis and segment.
_Decomposition = tuple[NDArray[np.float64], NDArray[np.float64], list[list[list[str]]]]


# -------------------------------------------------------------------------------------------
# shared pieces


def _check_run(run: ThermalRun, *,
               need_temperature: bool) -> _Triple:
    """Validate a ThermalRun; return (t, gyro, temperature) as float arrays."""
    t = np.asarray(run.t_s, dtype=float)
    gyro = np.asarray(run.gyro_rad_s, dtype=float)
    temp = np.asarray(run.temperature_c, dtype=float)
    if t.ndim != 1 or gyro.shape != (t.size, 3) or temp.shape != t.shape:
        raise InputDataError(f'run {run.name!r}: t_s (n,), gyro_rad_s (n, 3) and temperature_c '
                             f'(n,) expected, got {t.shape}, {gyro.shape}, {temp.shape}')
    if t.size < 16:
        raise InputDataError(f'run {run.name!r} has {t.size} samples, at least 16 needed')
    if not (np.all(np.isfinite(gyro)) and np.all(np.isfinite(t))):
        raise InputDataError(f'run {run.name!r}: gyro or stamps hold NaN or Inf')
    if need_temperature:
        if not np.all(np.isfinite(temp)):
            raise InputDataError(f'run {run.name!r}: temperature holds NaN or Inf')
    return t, gyro, temp


def check_rate_training(t: NDArray[np.float64], window_s: float, name: str) -> None:
    """
    Refuse a training run too short for a method that uses dT (:data:`MIN_TRAINING_WINDOWS`).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (n,), s.
    window_s : float
        The method's rate window (s).
    name : str
        Run label for the message.

    Raises
    ------
    RateWindowError
        Shorter than ``MIN_TRAINING_WINDOWS * window_s``.

    """
    duration = float(t[-1] - t[0]) if t.size else 0.0
    need = MIN_TRAINING_WINDOWS * float(window_s)
    if duration < need:
        raise RateWindowError(f'run {name!r} is {duration:.3g} s long; a method that uses dT '
                              f'needs at least {need:g} s ({MIN_TRAINING_WINDOWS:g} windows of '
                              f'the {float(window_s):g}-s temperature rate: one to fill it, the '
                              'rest to fit)')


def rate_fit_inputs(run: ThermalRun, rate_window_s: float,
                    method: str) -> tuple[_Triple, RateSupport, tuple[str, ...]]:
    """
    Check a training run for a temperature model with a dT term; say whether dT can be fitted.

    Parameters
    ----------
    run : ThermalRun
        The training run.
    rate_window_s : float
        The method's rate window (s).
    method : str
        Its name, for the note.

    Returns
    -------
    (t, gyro, temperature) : tuple of numpy.ndarray
        The checked arrays.
    support : RateSupport
        :func:`~gyro_noise_ros.thermal.run.rate_support` of the run.
    notes : tuple of str
        The note of a method fitted without its dT term (empty when dT is supported).

    Raises
    ------
    InputDataError
        A malformed run, a temperature span under :data:`MIN_TEMPERATURE_SPAN_C`, or a run
        shorter than :data:`MIN_TRAINING_WINDOWS` rate windows.

    """
    t, gyro, temp = _check_run(run, need_temperature=True)
    _check_span(temp, run.name)
    check_rate_training(t, rate_window_s, run.name)
    support = rate_support(t, temp, window_s=rate_window_s)
    return (t, gyro, temp), support, support.notes(method)


def _check_span(temp: NDArray[np.float64], name: str) -> None:
    span = float(np.ptp(temp))
    if span < MIN_TEMPERATURE_SPAN_C:
        raise InputDataError(f'run {name!r} spans {span:.3f} degC of temperature; a temperature '
                             f'model needs at least {MIN_TEMPERATURE_SPAN_C} degC')


def _require_fitted(method: Any, attribute: str) -> None:
    if getattr(method, attribute) is None:
        raise ParameterError(f'method {method.name!r} is not fitted: call fit() or from_dict()')


def _as_pair(temperature_c: ArrayLike,
             dtemp_c_s: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    temp = np.asarray(temperature_c, dtype=float).reshape(-1)
    rate = np.broadcast_to(np.asarray(dtemp_c_s, dtype=float), temp.shape)
    return temp, rate


def _block_means(values: NDArray[np.float64], max_points: int) -> NDArray[np.float64]:
    """Average consecutive blocks so at most ``max_points`` rows remain (last block partial)."""
    n = values.shape[0]
    size = max(1, int(np.ceil(n / max_points)))
    if size == 1:
        return values.copy()
    edges = np.arange(0, n, size)
    sums = np.add.reduceat(values, edges, axis=0)
    counts = np.diff(np.append(edges, n)).reshape((-1,) + (1,) * (values.ndim - 1))
    return sums / counts


def wavelet_denoise(x: ArrayLike, *, wavelet: str = 'db4', level: int = 6, mode: str = 'symmetric',
                    sigma: str = 'finest') -> NDArray[np.float64]:
    """
    Wavelet-threshold denoising with the universal threshold and soft thresholding.

    Every detail coefficient d is replaced by ``sign(d) max(|d| - lambda, 0)`` with
    ``lambda = sigma sqrt(2 ln n)`` (Donoho & Johnstone 1994); ``sigma = median(|d_1|) / 0.6745``
    from the finest level (``sigma='finest'``, VisuShrink) or from each level's own
    coefficients (``sigma='level'``, for coloured noise). The approximation is kept.

    Parameters
    ----------
    x : array_like
        Signal (n,).
    wavelet : str, keyword-only
        PyWavelets wavelet name.
    level : int, keyword-only
        Decomposition depth (reduced to the largest the length allows).
    mode : str, keyword-only
        PyWavelets signal-extension mode.
    sigma : {'finest', 'level'}, keyword-only
        Where the noise level comes from.

    Returns
    -------
    numpy.ndarray
        Denoised signal (n,).

    """
    import pywt

    x = np.asarray(x, dtype=float)
    if sigma not in ('finest', 'level'):
        raise ParameterError(f"sigma must be 'finest' or 'level', got {sigma!r}")
    w = pywt.Wavelet(wavelet)
    depth = max(1, min(int(level), pywt.dwt_max_level(x.size, w.dec_len)))
    coeffs = pywt.wavedec(x, w, mode=mode, level=depth)
    factor = np.sqrt(2.0 * np.log(x.size))
    finest = np.median(np.abs(coeffs[-1])) / 0.6745
    out = [coeffs[0]]
    for d in coeffs[1:]:
        s = finest if sigma == 'finest' else np.median(np.abs(d)) / 0.6745
        out.append(pywt.threshold(d, s * factor, mode='soft'))
    return pywt.waverec(out, w, mode=mode)[:x.size]


def simulated_annealing(fun: Callable[[NDArray[np.float64]], float], x0: ArrayLike,
                        rng: np.random.Generator, *, iterations: int = 3000, step: float = 0.3,
                        t0_ratio: float = 0.1,
                        t_end_ratio: float = 1e-4) -> tuple[NDArray[np.float64], float]:
    """
    Minimise ``fun`` by simulated annealing (Metropolis acceptance, geometric cooling).

    Temperature ``T_k = T_0 r^k`` from ``T_0 = t0_ratio f(x0)`` down to ``t_end_ratio T_0``;
    the proposal is ``x + s_k N(0, I)`` with ``s_k = step sqrt(T_k / T_0)``; a worse candidate is
    accepted with probability ``exp(-(f_new - f) / T_k)``. The best point seen is returned.

    Parameters
    ----------
    fun : callable
        Objective, array (d,) -> float.
    x0 : array_like
        Start (d,).
    rng : numpy.random.Generator
        Proposal and acceptance draws.
    iterations : int, keyword-only
        Objective evaluations after the first.
    step : float, keyword-only
        Initial proposal standard deviation.
    t0_ratio, t_end_ratio : float, keyword-only
        Initial temperature relative to f(x0), final relative to the initial.

    Returns
    -------
    x_best : numpy.ndarray
    f_best : float

    """
    x = np.array(x0, dtype=float)
    fx = float(fun(x))
    best, f_best = x.copy(), fx
    t0 = t0_ratio * max(abs(fx), 1e-300)
    cool = t_end_ratio ** (1.0 / max(int(iterations), 1))
    temp = t0
    for _ in range(int(iterations)):
        cand = x + step * np.sqrt(temp / t0) * rng.standard_normal(x.size)
        fc = float(fun(cand))
        if fc <= fx or rng.random() < np.exp(-(fc - fx) / temp):
            x, fx = cand, fc
            if fx < f_best:
                best, f_best = x.copy(), fx
        temp *= cool
    return best, f_best


class _Mlp:
    """One hidden layer of logistic sigmoids (paper 002 eq. 34), linear output; flat weights."""

    def __init__(self, n_in: int, n_hidden: int, n_out: int) -> None:
        self.shape = (int(n_in), int(n_hidden), int(n_out))
        self.size = n_in * n_hidden + n_hidden + n_hidden * n_out + n_out

    def unpack(self, theta: NDArray[np.float64]) -> _Quad:
        n_in, h, n_out = self.shape
        i = 0
        w1 = theta[i:i + n_in * h].reshape(n_in, h)
        i += n_in * h
        b1 = theta[i:i + h]
        i += h
        w2 = theta[i:i + h * n_out].reshape(h, n_out)
        i += h * n_out
        return w1, b1, w2, theta[i:i + n_out]

    def init(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """Xavier-uniform weights, zero biases."""
        n_in, h, n_out = self.shape
        theta = np.zeros(self.size)
        w1, _, w2, _ = self.unpack(theta)
        w1[...] = rng.uniform(-1, 1, w1.shape) * np.sqrt(6.0 / (n_in + h))
        w2[...] = rng.uniform(-1, 1, w2.shape) * np.sqrt(6.0 / (h + n_out))
        return theta

    def forward(self, theta: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
        w1, b1, w2, b2 = self.unpack(theta)
        return 1.0 / (1.0 + np.exp(-(x @ w1 + b1))) @ w2 + b2

    def mse(self, theta: NDArray[np.float64], x: NDArray[np.float64],
            y: NDArray[np.float64]) -> float:
        return float(np.mean((self.forward(theta, x) - y) ** 2))

    def mse_and_grad(self, theta: NDArray[np.float64], x: NDArray[np.float64],
                     y: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        w1, b1, w2, b2 = self.unpack(theta)
        hid = 1.0 / (1.0 + np.exp(-(x @ w1 + b1)))
        err = hid @ w2 + b2 - y
        scale = 2.0 / err.size
        g_out = err * scale
        g_hid = (g_out @ w2.T) * hid * (1.0 - hid)
        grad = np.concatenate([(x.T @ g_hid).ravel(), g_hid.sum(0), (hid.T @ g_out).ravel(),
                               g_out.sum(0)])
        return float(np.mean(err ** 2)), grad


def train_gradient_descent(mlp: _Mlp, theta: NDArray[np.float64], x: NDArray[np.float64],
                           y: NDArray[np.float64], *, epochs: int,
                           learning_rate: float) -> NDArray[np.float64]:
    """
    Back-propagation: full-batch gradient descent on the MSE with Adam steps.

    Adam (Kingma & Ba 2015; beta1 0.9, beta2 0.999) rather than a fixed step, so one learning
    rate works on every run.

    Parameters
    ----------
    mlp : _Mlp
        Network shape.
    theta : numpy.ndarray
        Start weights (flat).
    x, y : numpy.ndarray
        Inputs (n, n_in) and targets (n, n_out), standardised.
    epochs : int, keyword-only
        Gradient steps.
    learning_rate : float, keyword-only
        Adam step size.

    Returns
    -------
    numpy.ndarray
        Trained weights.

    """
    theta = theta.copy()
    m = np.zeros_like(theta)
    v = np.zeros_like(theta)
    b1, b2, eps = 0.9, 0.999, 1e-8
    for k in range(1, int(epochs) + 1):
        _, g = mlp.mse_and_grad(theta, x, y)
        m = b1 * m + (1 - b1) * g
        v = b2 * v + (1 - b2) * g * g
        theta -= learning_rate * (m / (1 - b1 ** k)) / (np.sqrt(v / (1 - b2 ** k)) + eps)
    return theta


#: Basis of the networks' linear shortcut: linear_tdt's default (cubic in T, linear in dT).
SHORTCUT_DEGREE, SHORTCUT_RATE_DEGREE = 3, 1


class _DriftNet:
    """
    A fitted drift model from [T, dT] to a 3-axis offset: linear shortcut plus network.

    ``offset = P(T, dT) + N(T, dT)``: P is least squares on the shortcut basis (linear_tdt's
    default monomials, or nothing with ``shortcut=False``), N one hidden layer of sigmoids fitted
    to what P leaves. P extrapolates as a polynomial. Inside the trained box
    ``[x_min, x_max]`` N is the network; outside, the network at the nearest point of the box
    plus its gradient there times the step out (a first-order Taylor continuation): sigmoids
    saturate, so the raw network would hold its edge value, which is clipping by another name.
    """

    def __init__(self, hidden: int, theta: ArrayLike, x_mean: ArrayLike, x_std: ArrayLike,
                 y_mean: ArrayLike, y_std: ArrayLike, x_min: ArrayLike, x_max: ArrayLike, *,
                 shortcut: _Shortcut | None = None, uses_rate: bool = True) -> None:
        self.mlp = _Mlp(2, hidden, 3)
        self.hidden = int(hidden)
        self.theta = np.asarray(theta, dtype=float)
        self.x_mean, self.x_std = np.asarray(x_mean, float), np.asarray(x_std, float)
        self.y_mean, self.y_std = np.asarray(y_mean, float), np.asarray(y_std, float)
        self.x_min, self.x_max = np.asarray(x_min, float), np.asarray(x_max, float)
        self.shortcut = shortcut   # None or (_PolyBasis, coef (k, 3))
        # False: dT is held at 0 (the training run could not support a dT term)
        self.uses_rate = bool(uses_rate)

    @classmethod
    def standardise(cls, x: NDArray[np.float64],
                    y: NDArray[np.float64]) -> _Quad:
        x_std = np.where(x.std(0) > 0, x.std(0), 1.0)
        y_std = np.where(y.std(0) > 0, y.std(0), 1.0)
        return x.mean(0), x_std, y.mean(0), y_std

    def _value_and_jacobian(self,
                            x: NDArray[np.float64]) -> _Pair:
        """Network output (n, 3) and d output / d input (n, 2, 3) in physical units."""
        w1, b1, w2, b2 = self.mlp.unpack(self.theta)
        xs = (x - self.x_mean) / self.x_std
        hid = 1.0 / (1.0 + np.exp(-(xs @ w1 + b1)))
        value = (hid @ w2 + b2) * self.y_std + self.y_mean
        slope = hid * (1.0 - hid)
        jac = np.einsum('ih,nh,ho->nio', w1, slope, w2)
        return value, jac * self.y_std[None, None, :] / self.x_std[None, :, None]

    def network(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the network part N at inputs x (n, 2), continued linearly outside the box."""
        edge = np.clip(x, self.x_min, self.x_max)
        value, jac = self._value_and_jacobian(edge)
        rows = (edge != x).any(axis=1)
        if rows.any():
            value[rows] += np.einsum('ni,nio->no', (x - edge)[rows], jac[rows])
        return value

    def predict(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike) -> NDArray[np.float64]:
        temp, rate = _as_pair(temperature_c, dtemp_c_s)
        if not self.uses_rate:
            rate = np.zeros_like(temp)
        value = self.network(np.column_stack([temp, rate]))
        if self.shortcut is not None:
            basis, coef = self.shortcut
            value += basis(temp, rate) @ coef
        return value

    def to_dict(self) -> dict[str, Any]:
        d = {'hidden': self.hidden, 'weights': self.theta.tolist(),
             'input_mean': self.x_mean.tolist(), 'input_std': self.x_std.tolist(),
             'output_mean_rad_s': self.y_mean.tolist(), 'output_std_rad_s': self.y_std.tolist(),
             'input_min': self.x_min.tolist(), 'input_max': self.x_max.tolist(),
             'beyond_input_range': 'network: linear continuation along its gradient at the '
                                   'nearest trained point; shortcut: the polynomial',
             'shortcut': None, 'uses_rate': self.uses_rate}
        if self.shortcut is not None:
            basis, coef = self.shortcut
            d['shortcut'] = {'degree': basis.degree, 'rate_degree': basis.rate_degree,
                             'terms': basis.names(), 'centre': basis.centre.tolist(),
                             'scale': basis.scale.tolist(), 'coef_rad_s': coef.tolist()}
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> '_DriftNet':
        shortcut = None
        sc = d.get('shortcut')
        if sc:
            basis = _PolyBasis(sc['degree'], sc['rate_degree'], sc['centre'], sc['scale'])
            shortcut = (basis, np.asarray(sc['coef_rad_s'], dtype=float).reshape(-1, 3))
        return cls(d['hidden'], d['weights'], d['input_mean'], d['input_std'],
                   d['output_mean_rad_s'], d['output_std_rad_s'], d['input_min'], d['input_max'],
                   shortcut=shortcut, uses_rate=bool(d.get('uses_rate', True)))


def _training_pairs(t: NDArray[np.float64], temp: NDArray[np.float64], target: NDArray[np.float64],
                    *, rate_window_s: float, max_points: int,
                    use_rate: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """[T, dT] (dT 0 without ``use_rate``) and target (n, 3), block-averaged to ``max_points``."""
    rate = temperature_rate_c_s(t, temp, window_s=rate_window_s)
    if not use_rate:
        rate = np.zeros_like(rate)
    rows = _block_means(np.column_stack([temp, rate, target]), max_points)
    return rows[:, :2], rows[:, 2:]


# -------------------------------------------------------------------------------------------
# methods


class RawMethod:
    """
    The gyro output unchanged: the reference every method is compared with.

    Attributes
    ----------
    name : str
        ``'raw'``.
    causal : bool
        True.

    """

    name = 'raw'
    causal = True
    uses_rate = False
    uses_temperature = False
    out_of_range = 'nothing is learnt, nothing is extrapolated'

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Learn nothing (the run is still checked)."""
        _check_run(run, need_temperature=False)

    def drift_rad_s(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike) -> NDArray[np.float64]:
        """Return zeros (n, 3), rad/s."""
        temp, _ = _as_pair(temperature_c, dtemp_c_s)
        return np.zeros((temp.size, 3))

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return a copy of the angular rate (n, 3), rad/s."""
        return _check_run(run, need_temperature=False)[1].copy()

    def to_dict(self) -> dict[str, Any]:
        """Return ``{'method': 'raw', 'temperature_range_c': None}``."""
        return {'method': self.name, 'temperature_range_c': None}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'RawMethod':
        """Rebuild from :meth:`to_dict`."""
        _check_method(cls, d)
        return cls()


def _check_method(cls: type[Any], d: Any) -> None:
    if not isinstance(d, dict) or d.get('method') != cls.name:
        got = d.get('method') if isinstance(d, dict) else type(d).__name__
        raise ParameterError(f'{cls.__name__}.from_dict needs method {cls.name!r}, got {got!r}')


class TemperaturePolynomial:
    """
    PX4 / ArduPilot style thermal calibration: a polynomial of the offset in (T - T_ref).

    Fit (PX4 ``process_sensor_caldata.py``): T_min and T_max are the training run's extremes,
    ``T_ref = (T_min + T_max) / 2``, and per axis the coefficients X0..X3 of
    ``offset = sum_i X_i (T - T_ref)^i`` are the least-squares fit to the output. Apply (PX4's
    documented compensation): the offset at T held within [T_min, T_max] is subtracted; beyond
    the trained range the offset stays at its value at the nearest end (:attr:`out_of_range`,
    counted by :func:`~gyro_noise_ros.thermal.methods.range_report`). PX4 names them
    ``TC_G0_X{i}_{axis}``, ``TC_G0_TREF``, ``TC_G0_TMIN``, ``TC_G0_TMAX`` (offsets in rad/s
    there as here); :mod:`gyro_noise_ros.thermal.export` writes them. A polynomial in T alone
    cannot represent a drift that depends on dT (thermal gradients) or on the direction of the
    last temperature change (hysteresis).

    With ``relative=True`` the constant X0 is set to 0 after the fit, so the offset is the
    change from ``T_ref``: the form of the accelerometer's compensation, whose offset at one
    temperature (and gravity) belong to the six-position calibration.

    Parameters
    ----------
    order : int, keyword-only
        Polynomial order (3 in PX4 and ArduPilot).
    relative : bool, keyword-only
        Remove the constant term (see above).

    """

    name = 'poly3'
    causal = True
    uses_rate = False
    out_of_range = ('T beyond the trained range: the offset is held at its value at the nearest '
                    "end (PX4's and ArduPilot's formula); dT is not an input")

    def __init__(self, *, order: int = 3, relative: bool = False) -> None:
        if not (isinstance(order, (int, np.integer)) and 0 <= order <= 8):
            raise ParameterError(f'order must be an integer in 0..8, got {order!r}')
        self.order = int(order)
        self.relative = bool(relative)
        # (3, order + 1), rad/s per degC^i, lowest power first
        self.coef: NDArray[np.floating[Any]] | None = None
        self.t_ref_c: float | None = None
        self.t_min_c: float | None = None
        self.t_max_c: float | None = None

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Least-squares fit of the polynomial per axis (``rng`` unused: deterministic)."""
        _, gyro, temp = _check_run(run, need_temperature=True)
        _check_span(temp, run.name)
        self.t_min_c, self.t_max_c = float(temp.min()), float(temp.max())
        self.t_ref_c = 0.5 * (self.t_min_c + self.t_max_c)
        coef = np.polynomial.polynomial.polyfit(temp - self.t_ref_c, gyro, self.order)
        self.coef = np.asarray(coef).T.copy()
        if self.relative:
            self.coef[:, 0] = 0.0

    def drift_rad_s(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike) -> NDArray[np.float64]:
        """
        Return the offset (n, 3), rad/s, at temperatures ``temperature_c`` (degC).

        ``dtemp_c_s`` is accepted for the common signature and not used.
        """
        _require_fitted(self, 'coef')
        assert self.coef is not None and self.t_ref_c is not None
        temp, _ = _as_pair(temperature_c, dtemp_c_s)
        d = np.clip(temp, self.t_min_c, self.t_max_c) - self.t_ref_c
        return np.polynomial.polynomial.polyval(d, self.coef.T).T.reshape(temp.size, 3)

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return ``gyro - drift_rad_s(T, dT)`` (n, 3), rad/s."""
        t, gyro, temp = _check_run(run, need_temperature=True)
        return gyro - self.drift_rad_s(temp, np.zeros_like(temp))

    def to_dict(self) -> dict[str, Any]:
        """Return the order, T_ref/T_min/T_max (degC) and the coefficients per axis (rad/s)."""
        _require_fitted(self, 'coef')
        assert self.coef is not None
        return {'method': self.name, 'order': self.order, 'relative': self.relative,
                't_ref_c': self.t_ref_c, 't_min_c': self.t_min_c, 't_max_c': self.t_max_c,
                'coef_rad_s': self.coef.tolist(),
                'temperature_range_c': [self.t_min_c, self.t_max_c]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'TemperaturePolynomial':
        """Rebuild a fitted model from :meth:`to_dict`."""
        _check_method(cls, d)
        m = cls(order=int(d['order']), relative=bool(d.get('relative', False)))
        m.t_ref_c, m.t_min_c, m.t_max_c = (float(d[k]) for k in ('t_ref_c', 't_min_c', 't_max_c'))
        m.coef = np.asarray(d['coef_rad_s'], dtype=float).reshape(3, m.order + 1)
        return m


def _monomials(degree: int, rate_degree: int | None = None) -> list[tuple[int, int]]:
    """Exponent pairs (p, q) of T^p dT^q with p + q <= degree and q <= rate_degree."""
    rate_degree = degree if rate_degree is None else rate_degree
    return [(p, total - p) for total in range(degree + 1) for p in range(total, -1, -1)
            if total - p <= rate_degree]


class _PolyBasis:
    """
    Monomials of x = (T - T_c) / T_s and r = (dT - R_c) / R_s (centre, half-range of a run).

    Evaluated as they are anywhere: beyond the range they extrapolate the polynomial.
    """

    def __init__(self, degree: int, rate_degree: int, centre: ArrayLike, scale: ArrayLike) -> None:
        self.degree, self.rate_degree = int(degree), int(rate_degree)
        self.centre = np.asarray(centre, dtype=float)
        self.scale = np.asarray(scale, dtype=float)
        self.terms = _monomials(self.degree, self.rate_degree)

    @classmethod
    def spanning(cls, degree: int, rate_degree: int, lo: ArrayLike, hi: ArrayLike) -> '_PolyBasis':
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        return cls(degree, rate_degree, 0.5 * (lo + hi),
                   np.where(hi > lo, 0.5 * (hi - lo), 1.0))

    def __call__(self, temp: ArrayLike, rate: ArrayLike) -> NDArray[np.float64]:
        x = (np.asarray(temp, dtype=float) - self.centre[0]) / self.scale[0]
        r = (np.asarray(rate, dtype=float) - self.centre[1]) / self.scale[1]
        return np.column_stack([x ** p * r ** q for p, q in self.terms])

    def names(self) -> list[str]:
        return [f'x^{p} r^{q}' for p, q in self.terms]


class LinearTdT:
    """
    Linear least squares of the offset on monomials of T and dT.

    ``offset_i = sum a_{i,pq} x^p r^q`` over ``p + q <= degree`` and ``q <= rate_degree``, with
    ``x = (T - T_c) / T_s`` and ``r = (dT - R_c) / R_s`` (centre and half-ranges of the training
    run, for conditioning). The default (degree 3, rate_degree 1) gives 7 terms: 1, x, r, x^2,
    x r, x^3, x^2 r: a cubic in T plus a thermal-gradient term whose gain may vary with T.
    Powers of dT are left out by default because a training run rarely spans both signs of dT
    (the usual warm-up calibration only heats): the full degree-3 basis (``rate_degree=3``, 10
    terms) fits r^2 and r^3 to noise and extrapolates them to cooling 8-14 times worse than the
    oracle (``docs/thermal.md``, "Held-out shapes"). Fitted over every sample (normal equations
    accumulated in chunks): plain least squares on the basis. Beyond the trained range the
    polynomial is extrapolated as fitted (:attr:`out_of_range`).

    Parameters
    ----------
    degree : int, keyword-only
        Highest total degree (1..5).
    rate_degree : int, keyword-only
        Highest power of dT (0..degree; 0 is a polynomial in T only).
    rate_window_s : float, keyword-only
        Window of :func:`~gyro_noise_ros.thermal.run.temperature_rate_c_s` (s).

    """

    name = 'linear_tdt'
    causal = True
    uses_rate = True
    out_of_range = 'T and dT beyond the trained range: the fitted polynomial is extrapolated'

    def __init__(self, *, degree: int = 3, rate_degree: int = 1,
                 rate_window_s: float = DEFAULT_RATE_WINDOW_S) -> None:
        if not (isinstance(degree, (int, np.integer)) and 1 <= degree <= 5):
            raise ParameterError(f'degree must be an integer in 1..5, got {degree!r}')
        if not (isinstance(rate_degree, (int, np.integer)) and 0 <= rate_degree <= degree):
            raise ParameterError(f'rate_degree must be an integer in 0..degree, got '
                                 f'{rate_degree!r}')
        if not rate_window_s > 0:
            raise ParameterError(f'rate_window_s must be > 0, got {rate_window_s!r}')
        self.degree = int(degree)
        self.rate_degree = int(rate_degree)
        self.rate_window_s = float(rate_window_s)
        self.coef: NDArray[np.floating[Any]] | None = None   # (3, n_terms)
        self.basis: _PolyBasis | None = None
        # each (2,): T, dT
        self.lo: NDArray[np.float64] | None = None
        self.hi: NDArray[np.float64] | None = None
        self.notes: tuple[str, ...] = ()

    @property
    def n_terms(self) -> int:
        """int: number of monomials."""
        return len(_monomials(self.degree, self.rate_degree))

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Least squares over every sample (``rng`` unused: deterministic)."""
        (t, gyro, temp), support, notes = rate_fit_inputs(run, self.rate_window_s, self.name)
        self.notes = notes
        if not support.supported:
            # a dT column whose spread is its noise would be scaled by a vanishing range
            self.rate_degree = 0
        self.uses_rate = self.rate_degree > 0
        rate = temperature_rate_c_s(t, temp, window_s=self.rate_window_s)
        both = np.column_stack([temp, rate])
        self.lo, self.hi = both.min(0), both.max(0)
        self.basis = _PolyBasis.spanning(self.degree, self.rate_degree, self.lo, self.hi)
        n_terms = self.n_terms
        ata = np.zeros((n_terms, n_terms))
        aty = np.zeros((n_terms, gyro.shape[1]))
        for lo in range(0, t.size, 262144):
            a = self.basis(temp[lo:lo + 262144], rate[lo:lo + 262144])
            ata += a.T @ a
            aty += a.T @ gyro[lo:lo + 262144]
        sol, _, rank, _ = np.linalg.lstsq(ata, aty, rcond=None)
        if rank < n_terms:
            raise InputDataError(f'run {run.name!r}: T and dT do not vary enough to fit '
                                 f'{n_terms} terms (rank {rank})')
        self.coef = sol.T

    def drift_rad_s(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike) -> NDArray[np.float64]:
        """Return the offset (n, 3), rad/s, at temperatures (degC) and rates (degC/s)."""
        _require_fitted(self, 'coef')
        assert self.coef is not None and self.basis is not None
        temp, rate = _as_pair(temperature_c, dtemp_c_s)
        return self.basis(temp, rate) @ self.coef.T

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return ``gyro - drift_rad_s(T, temperature_rate_c_s(t, T))`` (n, 3), rad/s."""
        t, gyro, temp = _check_run(run, need_temperature=True)
        return gyro - self.drift_rad_s(
            temp, temperature_rate_c_s(t, temp, window_s=self.rate_window_s))

    def to_dict(self) -> dict[str, Any]:
        """Return the degrees, window, scaling, ranges and coefficients per axis (rad/s)."""
        _require_fitted(self, 'coef')
        assert self.coef is not None and self.basis is not None
        assert self.lo is not None and self.hi is not None
        return {'method': self.name, 'degree': self.degree, 'rate_degree': self.rate_degree,
                'rate_window_s': self.rate_window_s, 'terms': self.basis.names(),
                'centre': self.basis.centre.tolist(), 'scale': self.basis.scale.tolist(),
                'input_min': self.lo.tolist(), 'input_max': self.hi.tolist(),
                'coef_rad_s': self.coef.tolist(), 'notes': list(self.notes),
                'temperature_range_c': [float(self.lo[0]), float(self.hi[0])]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'LinearTdT':
        """Rebuild a fitted model from :meth:`to_dict` (no ``rate_degree``: the full basis)."""
        _check_method(cls, d)
        degree = int(d['degree'])
        m = cls(degree=degree, rate_degree=int(d.get('rate_degree', degree)),
                rate_window_s=float(d['rate_window_s']))
        m.basis = _PolyBasis(m.degree, m.rate_degree, d['centre'], d['scale'])
        m.lo, m.hi = np.asarray(d['input_min'], float), np.asarray(d['input_max'], float)
        m.coef = np.asarray(d['coef_rad_s'], dtype=float).reshape(-1, m.n_terms)
        m.uses_rate, m.notes = m.rate_degree > 0, tuple(d.get('notes', ()))
        return m


class WaveletThreshold:
    """
    Wavelet-threshold denoising (WTD) of each axis, the paper's first comparison.

    See :func:`wavelet_denoise`. It learns nothing from the training run: the threshold comes
    from the run being processed, as WTD is defined. It removes noise, not drift, and needs the
    whole record (non-causal).

    Parameters
    ----------
    wavelet : str, keyword-only
        PyWavelets name; 'db4' by default (the paper does not say which).
    level : int, keyword-only
        Decomposition depth.
    mode : str, keyword-only
        Signal extension; 'symmetric' keeps the drift's ends free of wrap-around.
    sigma : {'finest', 'level'}, keyword-only
        Noise level from the finest details, or per level.

    """

    name = 'wtd'
    causal = False
    uses_rate = False
    uses_temperature = False
    out_of_range = 'temperature is not an input'

    def __init__(self, *, wavelet: str = 'db4', level: int = 6, mode: str = 'symmetric',
                 sigma: str = 'finest') -> None:
        import pywt

        if wavelet not in pywt.wavelist(kind='discrete'):
            raise ParameterError(f'wavelet must be a discrete PyWavelets name, got {wavelet!r}')
        if mode not in pywt.Modes.modes:
            raise ParameterError(f'mode must be one of {pywt.Modes.modes}, got {mode!r}')
        if not (isinstance(level, (int, np.integer)) and level >= 1):
            raise ParameterError(f'level must be an integer >= 1, got {level!r}')
        if sigma not in ('finest', 'level'):
            raise ParameterError(f"sigma must be 'finest' or 'level', got {sigma!r}")
        self.wavelet, self.level, self.mode, self.sigma = wavelet, int(level), mode, sigma

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Learn nothing (WTD is defined on the record it denoises); the run is checked."""
        _check_run(run, need_temperature=False)

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return the denoised angular rate (n, 3), rad/s."""
        gyro = _check_run(run, need_temperature=False)[1]
        return np.column_stack([wavelet_denoise(gyro[:, i], wavelet=self.wavelet,
                                                level=self.level, mode=self.mode,
                                                sigma=self.sigma) for i in range(3)])

    def to_dict(self) -> dict[str, Any]:
        """Return the wavelet settings."""
        return {'method': self.name, 'wavelet': self.wavelet, 'level': self.level,
                'mode': self.mode, 'sigma': self.sigma, 'threshold': 'universal, soft',
                'temperature_range_c': None}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'WaveletThreshold':
        """Rebuild from :meth:`to_dict`."""
        _check_method(cls, d)
        return cls(wavelet=d['wavelet'], level=int(d['level']), mode=d['mode'],
                   sigma=d['sigma'])


class BPNetwork:
    """
    Back-propagation network from [T, dT] to the gyro offset, the paper's second comparison.

    One hidden layer of ``hidden`` logistic sigmoids and a linear output per axis, inputs and
    outputs standardised, trained by full-batch gradient descent (Adam steps) on the MSE. The
    training pairs are block means of the run (at most ``max_points``), which averages the
    noise out of the target and bounds the cost. Beyond the trained box of [T, dT] the network
    is continued linearly from the nearest trained point along its gradient (:attr:`out_of_range`).

    By default (``shortcut=True``) the network has a linear shortcut: least squares on
    linear_tdt's default basis (a cubic in T plus dT, T dT, T^2 dT) first, the network on what
    that leaves. Without it (``shortcut=False``, the paper's plain network) a sigmoid layer
    extrapolates dT badly: trained on heating only and tested on cooling it left 4.4 times the
    oracle's drift, with the shortcut 1.4 (``docs/thermal.md``, "Held-out shapes").

    Parameters
    ----------
    hidden : int, keyword-only
        Hidden units.
    epochs : int, keyword-only
        Gradient steps.
    learning_rate : float, keyword-only
        Adam step size (standardised units).
    max_points : int, keyword-only
        Training pairs after block averaging.
    rate_window_s : float, keyword-only
        Window of the temperature rate (s).
    shortcut : bool, keyword-only
        Fit the linear shortcut first (see above).

    """

    name = 'bp'
    causal = True
    uses_rate = True
    out_of_range = ('T and dT beyond the trained range: the network at the nearest trained point '
                    'plus its gradient there times the step out (linear continuation)')

    def __init__(self, *, hidden: int = 12, epochs: int = 2000, learning_rate: float = 0.01,
                 max_points: int = 2000, rate_window_s: float = DEFAULT_RATE_WINDOW_S,
                 shortcut: bool = True) -> None:
        _check_net_options(hidden, epochs, learning_rate, max_points, rate_window_s)
        self.hidden, self.epochs = int(hidden), int(epochs)
        self.learning_rate, self.max_points = float(learning_rate), int(max_points)
        self.rate_window_s = float(rate_window_s)
        self.shortcut = bool(shortcut)
        self.net: _DriftNet | None = None
        self.train_mse: float | None = None
        self.notes: tuple[str, ...] = ()

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Fit the shortcut and train the network on the run's block means (``rng``: weights)."""
        (t, gyro, temp), support, notes = rate_fit_inputs(run, self.rate_window_s, self.name)
        self.notes, self.uses_rate = notes, support.supported
        x, y = _training_pairs(t, temp, gyro, rate_window_s=self.rate_window_s,
                               max_points=self.max_points, use_rate=self.uses_rate)
        self.net, self.train_mse = _fit_net(x, y, self.hidden, rng, sa_iterations=0,
                                            epochs=self.epochs, learning_rate=self.learning_rate,
                                            shortcut=self.shortcut, use_rate=self.uses_rate)

    def drift_rad_s(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike) -> NDArray[np.float64]:
        """Return the offset (n, 3), rad/s, at temperatures (degC) and rates (degC/s)."""
        _require_fitted(self, 'net')
        assert self.net is not None
        return self.net.predict(temperature_c, dtemp_c_s)

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return ``gyro - drift_rad_s(T, temperature_rate_c_s(t, T))`` (n, 3), rad/s."""
        t, gyro, temp = _check_run(run, need_temperature=True)
        return gyro - self.drift_rad_s(
            temp, temperature_rate_c_s(t, temp, window_s=self.rate_window_s))

    def to_dict(self) -> dict[str, Any]:
        """Return the options, the weights, the scaling and the training MSE."""
        _require_fitted(self, 'net')
        assert self.net is not None
        return {'method': self.name, 'epochs': self.epochs, 'learning_rate': self.learning_rate,
                'max_points': self.max_points, 'rate_window_s': self.rate_window_s,
                'shortcut': self.shortcut, 'notes': list(self.notes),
                'train_mse_standardised': self.train_mse, 'network': self.net.to_dict(),
                'temperature_range_c': [float(self.net.x_min[0]), float(self.net.x_max[0])]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'BPNetwork':
        """Rebuild a fitted model from :meth:`to_dict`."""
        _check_method(cls, d)
        m = cls(hidden=int(d['network']['hidden']), epochs=int(d['epochs']),
                learning_rate=float(d['learning_rate']), max_points=int(d['max_points']),
                rate_window_s=float(d['rate_window_s']),
                shortcut=bool(d['network'].get('shortcut')))
        m.net = _DriftNet.from_dict(d['network'])
        m.train_mse = d.get('train_mse_standardised')
        m.uses_rate, m.notes = m.net.uses_rate, tuple(d.get('notes', ()))
        return m


def _check_net_options(hidden: int, epochs: int, learning_rate: float, max_points: int,
                       rate_window_s: float) -> None:
    for label, value in (('hidden', hidden), ('max_points', max_points)):
        if not (isinstance(value, (int, np.integer)) and value >= 1):
            raise ParameterError(f'{label} must be an integer >= 1, got {value!r}')
    if not (isinstance(epochs, (int, np.integer)) and epochs >= 0):
        raise ParameterError(f'epochs must be an integer >= 0, got {epochs!r}')
    if not learning_rate > 0:
        raise ParameterError(f'learning_rate must be > 0, got {learning_rate!r}')
    if not rate_window_s > 0:
        raise ParameterError(f'rate_window_s must be > 0, got {rate_window_s!r}')


def _fit_net(x: NDArray[np.float64], y: NDArray[np.float64], hidden: int, rng: np.random.Generator,
             *, sa_iterations: int, epochs: int, learning_rate: float,
             shortcut: bool = True, use_rate: bool = True) -> tuple[_DriftNet, float]:
    """
    Fit the shortcut (least squares), then the network on what it leaves; return (net, mse).

    The network is standardised, initialised, annealed (optional), then back-propagated; the
    MSE is the network's, in standardised units of the target it was fitted to.
    """
    basis = None
    if shortcut:
        basis = _PolyBasis.spanning(SHORTCUT_DEGREE, SHORTCUT_RATE_DEGREE if use_rate else 0,
                                    x.min(0), x.max(0))
        a = basis(x[:, 0], x[:, 1])
        coef, _, rank, _ = np.linalg.lstsq(a, y, rcond=None)
        if rank < a.shape[1]:
            raise InputDataError(f'T and dT do not vary enough to fit the {a.shape[1]}-term '
                                 f'linear shortcut (rank {rank}); use shortcut=False')
        y = y - a @ coef
    x_mean, x_std, y_mean, y_std = _DriftNet.standardise(x, y)
    xs, ys = (x - x_mean) / x_std, (y - y_mean) / y_std
    mlp = _Mlp(2, hidden, 3)
    theta = mlp.init(rng)
    if sa_iterations:
        theta, _ = simulated_annealing(lambda th: mlp.mse(th, xs, ys), theta, rng,
                                       iterations=sa_iterations)
    if epochs:
        theta = train_gradient_descent(mlp, theta, xs, ys, epochs=epochs,
                                       learning_rate=learning_rate)
    net = _DriftNet(hidden, theta, x_mean, x_std, y_mean, y_std, x.min(0), x.max(0),
                    shortcut=None if basis is None else (basis, coef), uses_rate=use_rate)
    return net, mlp.mse(theta, xs, ys)


def _segments(n: int, size: int | None) -> list[tuple[int, int]]:
    """[lo, hi) bounds covering 0..n, consecutive ones overlapping by size // 8."""
    if size is None or n <= size:
        return [(0, n)]
    overlap = size // 8
    bounds, lo = [], 0
    while lo + size < n - overlap:
        bounds.append((lo, lo + size))
        lo += size - overlap
    bounds.append((lo, n))
    return bounds


def zero_crossing_hz(imf: ArrayLike, duration_s: float) -> float:
    """
    Return the mean frequency of an oscillation from its zero crossings (Hz).

    Parameters
    ----------
    imf : array_like
        Signal (n,).
    duration_s : float
        Its length (s).

    Returns
    -------
    float
        ``crossings / (2 duration_s)``.

    """
    s = np.signbit(np.asarray(imf, dtype=float))
    return float(np.count_nonzero(s[1:] != s[:-1])) / (2.0 * duration_s)


class EmdWtdSaBp:
    """
    EMD + WTD + SA-BP, the paper's third (and strongest) comparison.

    Each axis is decomposed by EMD (PyEMD, cubic-spline envelopes). IMFs whose zero-crossing
    frequency (:func:`zero_crossing_hz`) exceeds ``split_hz`` are the noisy part, each denoised
    by WTD; the other IMFs and the residue are the drift part. A BP network (as
    :class:`BPNetwork`) learns the drift part from [T, dT]; its weights are found by simulated
    annealing (:func:`simulated_annealing`) and refined by back-propagation. Output: the
    denoised noisy part plus the drift part minus the predicted drift. Needs the whole record
    (non-causal).

    PyEMD's cost grows faster than the length (5 s for 90 000 samples, 25 s for 180 000), so a
    long record is decomposed in segments of ``segment_samples`` overlapping by
    ``segment_samples // 8``, cross-faded linearly (the weights sum to one); the slow drift then
    lands in each segment's residue, which is still the drift part.

    Parameters
    ----------
    split_hz : float, optional, keyword-only
        Noise/drift boundary (Hz); None: 100 / (training run length), i.e. IMFs with more than
        about 100 oscillations over the run are noise. Stored once fitted.
    max_imf : int, keyword-only
        Most IMFs EMD extracts.
    segment_samples : int or None, keyword-only
        EMD segment length (>= 256); None decomposes the whole record at once.
    wavelet, wtd_level : keyword-only
        WTD settings for the noisy IMFs.
    hidden, sa_iterations, epochs, learning_rate, max_points, rate_window_s : keyword-only
        Network, annealing and training settings.
    shortcut : bool, keyword-only
        The network's linear shortcut, as in :class:`BPNetwork` (the annealing and the
        back-propagation train the network on what the shortcut leaves).

    """

    name = 'emd_wtd_sabp'
    causal = False
    uses_rate = True
    out_of_range = BPNetwork.out_of_range

    def __init__(self, *, split_hz: float | None = None, max_imf: int = 10,
                 segment_samples: int | None = 65536, wavelet: str = 'db4', wtd_level: int = 6,
                 hidden: int = 8, sa_iterations: int = 3000, epochs: int = 500,
                 learning_rate: float = 0.01, max_points: int = 2000,
                 rate_window_s: float = DEFAULT_RATE_WINDOW_S, shortcut: bool = True) -> None:
        _check_net_options(hidden, epochs, learning_rate, max_points, rate_window_s)
        self.shortcut = bool(shortcut)
        if split_hz is not None and not split_hz > 0:
            raise ParameterError(f'split_hz must be > 0, got {split_hz!r}')
        if segment_samples is not None and not (isinstance(segment_samples, (int, np.integer))
                                                and segment_samples >= 256):
            raise ParameterError(f'segment_samples must be None or an integer >= 256, got '
                                 f'{segment_samples!r}')
        self.segment_samples = None if segment_samples is None else int(segment_samples)
        if not (isinstance(max_imf, (int, np.integer)) and max_imf >= 1):
            raise ParameterError(f'max_imf must be an integer >= 1, got {max_imf!r}')
        if not (isinstance(sa_iterations, (int, np.integer)) and sa_iterations >= 0):
            raise ParameterError(f'sa_iterations must be an integer >= 0, got {sa_iterations!r}')
        self.split_hz = None if split_hz is None else float(split_hz)
        self.max_imf, self.wavelet, self.wtd_level = int(max_imf), wavelet, int(wtd_level)
        self.hidden, self.sa_iterations, self.epochs = int(hidden), int(sa_iterations), int(epochs)
        self.learning_rate, self.max_points = float(learning_rate), int(max_points)
        self.rate_window_s = float(rate_window_s)
        self.net: _DriftNet | None = None
        self.train_mse: float | None = None
        # per axis: list of 'noise' / 'drift' of the training run
        self.imf_classes: list[list[list[str]]] | None = None
        self.notes: tuple[str, ...] = ()

    def decompose(self, t: NDArray[np.float64], gyro: NDArray[np.float64],
                  split_hz: float) -> _Decomposition:
        """
        Split each axis into its WTD-denoised noisy part and its drift part.

        Parameters
        ----------
        t : numpy.ndarray
            Times (n,), s.
        gyro : numpy.ndarray
            Angular rate (n, 3), rad/s.
        split_hz : float
            Noise/drift boundary (Hz).

        Returns
        -------
        denoised : numpy.ndarray
            (n, 3) sum of the denoised noisy IMFs.
        drift : numpy.ndarray
            (n, 3) sum of the slow IMFs and the residue.
        classes : list of list of list of str
            Per axis and segment, 'noise' or 'drift' for each IMF.

        """
        from PyEMD import EMD

        denoised = np.zeros_like(gyro)
        drift = np.zeros_like(gyro)
        classes: list[list[list[str]]] = [[] for _ in range(3)]
        bounds = _segments(t.size, self.segment_samples)
        overlap = bounds[0][1] - bounds[1][0] if len(bounds) > 1 else 0
        ramp = (np.arange(overlap) + 0.5) / max(overlap, 1)
        for k, (lo, hi) in enumerate(bounds):
            weight = np.ones(hi - lo)
            if k > 0:
                weight[:overlap] = ramp
            if k < len(bounds) - 1:
                weight[hi - lo - overlap:] = 1.0 - ramp
            duration = float(t[hi - 1] - t[lo]) or 1.0
            for i in range(3):
                emd = EMD()
                emd.emd(gyro[lo:hi, i], t[lo:hi], max_imf=self.max_imf)
                imfs, residue = emd.get_imfs_and_residue()
                seg_drift = residue.copy()
                seg_noise = np.zeros(hi - lo)
                labels = []
                for imf in imfs:
                    if zero_crossing_hz(imf, duration) > split_hz:
                        labels.append('noise')
                        seg_noise += wavelet_denoise(imf, wavelet=self.wavelet,
                                                     level=self.wtd_level)
                    else:
                        labels.append('drift')
                        seg_drift += imf
                drift[lo:hi, i] += weight * seg_drift
                denoised[lo:hi, i] += weight * seg_noise
                classes[i].append(labels)
        return denoised, drift, classes

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Decompose the run, then anneal and train the network on its drift part."""
        (t, gyro, temp), support, notes = rate_fit_inputs(run, self.rate_window_s, self.name)
        self.notes, self.uses_rate = notes, support.supported
        split = self.split_hz if self.split_hz is not None else 100.0 / float(t[-1] - t[0])
        _, drift, classes = self.decompose(t, gyro, split)
        x, y = _training_pairs(t, temp, drift, rate_window_s=self.rate_window_s,
                               max_points=self.max_points, use_rate=self.uses_rate)
        self.net, self.train_mse = _fit_net(x, y, self.hidden, rng,
                                            sa_iterations=self.sa_iterations,
                                            epochs=self.epochs, learning_rate=self.learning_rate,
                                            shortcut=self.shortcut, use_rate=self.uses_rate)
        self.split_hz = split
        self.imf_classes = classes

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return denoised noisy part + drift part - predicted drift (n, 3), rad/s."""
        _require_fitted(self, 'net')
        assert self.net is not None and self.split_hz is not None
        t, gyro, temp = _check_run(run, need_temperature=True)
        denoised, drift, _ = self.decompose(t, gyro, self.split_hz)
        rate = temperature_rate_c_s(t, temp, window_s=self.rate_window_s)
        return denoised + drift - self.net.predict(temp, rate)

    def to_dict(self) -> dict[str, Any]:
        """Return the options, the split, the training IMF classes and the network."""
        _require_fitted(self, 'net')
        assert self.net is not None
        return {'method': self.name, 'split_hz': self.split_hz, 'max_imf': self.max_imf,
                'segment_samples': self.segment_samples,
                'wavelet': self.wavelet, 'wtd_level': self.wtd_level,
                'sa_iterations': self.sa_iterations, 'epochs': self.epochs,
                'learning_rate': self.learning_rate, 'max_points': self.max_points,
                'rate_window_s': self.rate_window_s, 'shortcut': self.shortcut,
                'imf_classes': self.imf_classes, 'notes': list(self.notes),
                'train_mse_standardised': self.train_mse, 'network': self.net.to_dict(),
                'temperature_range_c': [float(self.net.x_min[0]), float(self.net.x_max[0])]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'EmdWtdSaBp':
        """Rebuild a fitted model from :meth:`to_dict`."""
        _check_method(cls, d)
        seg = d.get('segment_samples')
        m = cls(split_hz=float(d['split_hz']), max_imf=int(d['max_imf']),
                segment_samples=None if seg is None else int(seg), wavelet=d['wavelet'],
                wtd_level=int(d['wtd_level']), hidden=int(d['network']['hidden']),
                sa_iterations=int(d['sa_iterations']), epochs=int(d['epochs']),
                learning_rate=float(d['learning_rate']), max_points=int(d['max_points']),
                rate_window_s=float(d['rate_window_s']),
                shortcut=bool(d['network'].get('shortcut')))
        m.net = _DriftNet.from_dict(d['network'])
        m.train_mse = d.get('train_mse_standardised')
        m.imf_classes = d.get('imf_classes')
        m.uses_rate, m.notes = m.net.uses_rate, tuple(d.get('notes', ()))
        return m


#: Every baseline, by its ``--method`` name.
BASELINES = {cls.name: cls for cls in (RawMethod, WaveletThreshold, BPNetwork, EmdWtdSaBp,
                                       TemperaturePolynomial, LinearTdT)}
