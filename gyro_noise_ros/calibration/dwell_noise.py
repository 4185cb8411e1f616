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
Covariance of dwell means under bias wander: the Allan-type variogram of one sensor.

Every number a static calibration gives is a linear combination ``sum_d c_d m_d`` of dwell means
``m_d``; under bias wander (flicker, random walk) the dwells are correlated, which the spread of
the window means inside a dwell cannot show. The **variogram** of the window means does,
``gamma(lag) = E[(y(t + lag) - y(t))^2] / 2`` (the Allan variance at lag = tau). For a
**contrast** (``sum_d c_d = 0``) the variance follows from it alone, whatever the process (the
variogram identity of intrinsically stationary processes; weights = samples per window)::

    var(sum_d c_d m_d) = - sum_d sum_e c_d c_e G[d, e],
    G[d, e] = mean of gamma(|t_i - t_k|) over the windows i of dwell d and k of dwell e

The variogram is modelled on window means of length w (lag >= w; 0 at lag 0) as::

    gamma(lag) = a + b ln(lag / w) + c lag / w,        a, b, c >= 0

(``a`` white noise, ``b`` a flicker floor, ``c`` a random walk, K^2 w / 2), fitted by non-negative
least squares to the empirical variogram of the window means inside the dwells (all axes of one
sensor pooled) and, when the calibration gives them, to the expected sum of squares of its
residuals, which ties the model to the wander between dwells. Units: those of the samples
(m/s^2 or rad/s), squared for variances; lags in s. The uncertainty covers the estimate minus the
value *during* the calibration (docs/reliability.md section 1, "Uncertainties that hold with bias
wander").
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls

from ..errors import InputDataError

#: Re-weighting passes of the fit (the weights are 1 / model; two passes settle it).
FIT_PASSES = 3


def _basis(lag_s: ArrayLike, window_s: float) -> NDArray[np.float64]:
    lag = np.asarray(lag_s, dtype=np.float64)
    on = lag > 0.5 * window_s
    x = np.where(on, lag / window_s, 1.0)
    # the log term starts at one window (a variogram is never negative); windows closer than
    # that come from dwells of different recordings that overlap in time
    return np.stack([on * 1.0, on * np.log(np.maximum(x, 1.0)), on * x], axis=-1)


@dataclass(frozen=True)
class DwellNoise:
    """
    Variogram model of one sensor's window means and the dwell-mean covariance it implies.

    Attributes
    ----------
    window_s : float
        Window length w (s).
    coef : numpy.ndarray
        (3,) ``(a, b, c)`` of the module docstring, in the squared unit of the sensor.
    gamma_basis : numpy.ndarray
        (3, m, m): the dwell-pair means of each basis function (``G`` per coefficient).
    weights : numpy.ndarray
        (m,) samples of each dwell (the weights of "the value during the calibration").
    white_factor : numpy.ndarray
        (m,) ``sum n_i^2 / (sum n_i)^2`` over each dwell's windows: white noise of variance
        ``a`` per window mean averages to ``a * white_factor`` in the dwell mean.

    """

    window_s: float
    coef: np.ndarray
    gamma_basis: np.ndarray
    weights: np.ndarray
    white_factor: np.ndarray

    @property
    def gamma(self) -> NDArray[np.float64]:
        """numpy.ndarray: (m, m) ``G[d, e]`` of the module docstring (all three terms)."""
        return np.tensordot(self.coef, self.gamma_basis, axes=1)

    def variogram(self, lag_s: ArrayLike) -> NDArray[np.float64]:
        """
        Return the modelled variogram of window means at the lags ``lag_s`` (s).

        In the dwell values' unit squared: ``a + b ln(lag / w) + c lag / w`` (module docstring).

        """
        return _basis(lag_s, self.window_s) @ self.coef

    def covariance(self, loading: ArrayLike) -> NDArray[np.float64]:
        """
        Return the covariance of ``theta_p = sum_dj L[p, d, j] m_dj`` against its truth.

        The truth of a parameter carrying the bias (its weights over the dwells sum to 1 on an
        axis) is the bias *during the calibration*: the sample-weighted mean of the wander. So
        the white part (``a``: noise of the measurement, independent window to window) enters
        with the weights as they are, the wander part (``b``, ``c``) with the weights minus
        their sum times the dwells' share of the samples, which makes them a contrast (module
        docstring). For a parameter that is already a contrast the two coincide with
        ``-L G L'``. The three axes are independent and share the model.

        Parameters
        ----------
        loading : array_like
            (p, m, 3) weights of each parameter on the dwell means of each axis; or (p, m) for
            one axis.

        Returns
        -------
        numpy.ndarray
            (p, p).

        """
        L = np.asarray(loading, dtype=np.float64)
        if L.ndim == 2:
            L = L[:, :, None]
        w = self.weights / self.weights.sum()
        white = self.coef[0] * np.einsum('pdj,d,qdj->pq', L, self.white_factor, L)
        contrast = L - L.sum(axis=1, keepdims=True) * w[None, :, None]
        wander = np.tensordot(self.coef[1:], self.gamma_basis[1:], axes=1)
        return white - np.einsum('pdj,de,qej->pq', contrast, wander, contrast)

    def variance(self, c: ArrayLike) -> float | NDArray[np.float64]:
        """
        Return the variance of ``sum_d c_d m_d`` on one axis against its truth (``covariance``).

        Parameters
        ----------
        c : array_like
            (m,) or (k, m) weights.

        Returns
        -------
        float or numpy.ndarray

        """
        c = np.asarray(c, dtype=np.float64)
        cov = self.covariance(np.atleast_2d(c))
        return float(cov[0, 0]) if c.ndim == 1 else np.diag(cov)


def _empirical(values: Sequence[NDArray[np.float64]], lmax: int) -> list[tuple[int, float, int]]:
    """Pooled empirical variogram of window means at lags 1..lmax: [(lag, gamma, pairs)]."""
    out = []
    for lag in range(1, lmax + 1):
        s, n = 0.0, 0
        for y in values:
            if y.shape[0] > lag:
                d = y[lag:] - y[:-lag]
                s += float(np.sum(d * d))
                n += d.size
        if n:
            out.append((lag, 0.5 * s / n, n))
    return out


def _gamma_basis(times: Sequence[NDArray[np.float64]], counts: Sequence[NDArray[np.float64]],
                 window_s: float) -> NDArray[np.float64]:
    m = len(times)
    out = np.zeros((3, m, m))
    for d in range(m):
        for e in range(d, m):
            lag = np.abs(times[d][:, None] - times[e][None, :])
            wt = counts[d][:, None] * counts[e][None, :]
            b = (_basis(lag, window_s) * wt[..., None]).sum(axis=(0, 1)) / wt.sum()
            if d != e:
                b[0] = 1.0      # two dwells never share a sample, whatever their stamps say
            out[:, d, e] = out[:, e, d] = b
    return out


class DwellNoiseFitter:
    """
    Fit the variogram model of one sensor to its dwells, possibly several times (module doc).

    The empirical variogram and the dwell-pair basis are computed once; :meth:`fit` then takes
    a different residual constraint each time (leave-one-out checks refit without the dwell
    under test, so a bad dwell cannot hide itself by inflating the noise).

    Parameters
    ----------
    times : sequence of numpy.ndarray
        Per dwell, the window centre stamps (s).
    counts : sequence of numpy.ndarray
        Per dwell, the samples of each window.
    values : sequence of numpy.ndarray
        Per dwell, the (k, 3) window means.

    Raises
    ------
    InputDataError
        No dwell has two windows (nothing to read a variogram from).

    """

    def __init__(self, times: Sequence[ArrayLike], counts: Sequence[ArrayLike],
                 values: Sequence[ArrayLike]) -> None:
        times_s = [np.asarray(t, dtype=np.float64) for t in times]
        samples = [np.asarray(c, dtype=np.float64) for c in counts]
        means = [np.asarray(v, dtype=np.float64) for v in values]
        spacing = [np.diff(t) for t in times_s if t.size > 1]
        if not spacing:
            raise InputDataError('the noise model needs dwells of at least two windows')
        self.window_s = float(np.median(np.concatenate(spacing)))
        lmax = max(1, min(v.shape[0] for v in means) // 2)
        self._emp = _empirical(means, lmax)
        self.basis = _gamma_basis(times_s, samples, self.window_s)
        self.weights = np.array([c.sum() for c in samples])
        self.white_factor = np.array([np.sum(c * c) / c.sum() ** 2 for c in samples])

    def fit(self, *, residual_loading: ArrayLike | None = None,
            residuals: ArrayLike | None = None) -> DwellNoise:
        """
        Fit the model, with the residual sum of squares as one more equation when given.

        Parameters
        ----------
        residual_loading : array_like, optional, keyword-only
            (r, m, 3): residual r of the calibration fit as a combination of the dwell means
            (contrasts over d for each axis), e.g. the residual projector. With ``residuals``.
        residuals : array_like, optional, keyword-only
            (r,) the residuals themselves.

        Returns
        -------
        DwellNoise

        """
        gb, window_s = self.basis, self.window_s
        extra: tuple[NDArray[np.float64], float, float] | None = None
        if residual_loading is not None and residuals is not None:
            H = np.asarray(residual_loading, dtype=np.float64)
            rss = float(np.sum(np.asarray(residuals, dtype=np.float64) ** 2))
            # E[sum_r (sum_dj H e)^2] = -sum_rj H[r,:,j] G H[r,:,j], one column per coefficient
            row = np.array([-np.einsum('rdj,de,rej->', H, gb[q], H) for q in range(3)])
            dof = max(1.0, float(np.linalg.matrix_rank(H.reshape(H.shape[0], -1))))
            extra = (row, rss, dof)
        coef: NDArray[np.float64] | None = None
        for _ in range(FIT_PASSES):
            rows: list[NDArray[np.float64]] = []
            rhs: list[float] = []
            wts: list[float] = []
            for lag, g, n in self._emp:
                f = _basis(lag * window_s, window_s)
                model = g if coef is None else max(float(f @ coef), 1e-300)
                if model <= 0:
                    continue
                rows.append(f)
                rhs.append(g)
                # relative standard error of a variogram point: sqrt(2 / independent pairs)
                wts.append(np.sqrt(max(1.0, n / lag) / 2.0) / model)
            if extra is not None and extra[1] > 0:
                row, rss, dof = extra
                model = rss if coef is None else max(float(row @ coef), 1e-300)
                rows.append(row)
                rhs.append(rss)
                # a sum of squares with dof degrees of freedom: relative error sqrt(2 / dof)
                wts.append(np.sqrt(dof / 2.0) / model)
            if not rows:
                coef = np.zeros(3)
                break
            a = np.asarray(rows) * np.asarray(wts)[:, None]
            coef, _ = nnls(a, np.asarray(rhs) * np.asarray(wts))
        assert coef is not None  # FIT_PASSES >= 1
        return DwellNoise(window_s, coef, gb, self.weights, self.white_factor)


def fit_dwell_noise(times: Sequence[ArrayLike], counts: Sequence[ArrayLike],
                    values: Sequence[ArrayLike], *, residual_loading: ArrayLike | None = None,
                    residuals: ArrayLike | None = None) -> DwellNoise:
    """
    Fit the variogram model of one sensor to its dwells once: :meth:`DwellNoiseFitter.fit`.

    ``times``, ``counts`` and ``values`` are as in :class:`DwellNoiseFitter`, the keywords as in
    :meth:`DwellNoiseFitter.fit`.

    """
    return DwellNoiseFitter(times, counts, values).fit(residual_loading=residual_loading,
                                                       residuals=residuals)
