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
Catalogue of effects the discrepancy workflow can add to the baseline: one fitter, one term each.

Every :class:`Effect` has a ``name`` (its key in explain.json), ``n_params``, a ``kind`` and
``fit(ctx) -> dict | None`` (parameters in SI with the unit in the name, or None when the data
show nothing of it; :meth:`Effect.estimate` is the same without the detection test). Its kind
says how it enters the simulation:

* ``'additive'``: :meth:`Effect.term`, zero-mean over the record (the constant stays in the
  baseline bias) and the same in every member (sinusoid, bias_drift, bias_transient,
  temperature_sensitivity);
* ``'stochastic'``: a term drawn per member from the member's own generator (rate_random_walk,
  bias_instability, gauss_markov; fitted on the Allan variance in excess of the ensemble's);
* ``'quantization'``: the member's values rounded onto the fitted lattice (applied last);
* ``'stamps'``: :meth:`Effect.stamps`, the member's stamps (sample_loss, stamp_jitter).

Time inside a term is the nominal sample time ``k / rate_hz``. A fitter reports an effect only
when its statistic on the data exceeds the same statistic on every member of the current
model's ensemble and their mean + :data:`NULL_K` sd (:func:`null_exceeded`). :data:`CATALOGUE`
holds them in the order they are tried. Parameters, models and fitters: docs/discrepancy.md
section 4.
"""

from collections.abc import Callable, Mapping, Sequence
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.interpolate
import scipy.optimize

from .inputs import Measurement
from .signatures import (chunk_series, compare, FloatArray, Layout, Signatures, temperature_edges,
                         temperature_rate)
from ..core.simulate import gauss_markov, gauss_markov_avar


#: The Allan deviation of a first-order Gauss-Markov process peaks at this many correlation times
#: (:func:`gyro_noise_ros.core.simulate.gauss_markov_avar`).
GM_PEAK_TAU = 1.89
#: Standard deviations above the members' mean statistic a detection must lie (and above the worst
#: member). The statistics are non-negative, often chi-square-like with an atom at 0, so the
#: log-normal rule of the bands does not apply; for a chi-square with 1 dof, mean + 5 sd = 8.1 has
#: a tail of 0.4 %.
NULL_K = 5.0
#: An effect's parameters: SI values named with their unit, and private (underscore) entries the
#: simulation or the bootstrap needs (arrays of measured gaps or intervals, Allan weights).
Params = dict[str, Any]


def null_exceeded(stat: float, null: ArrayLike) -> bool:
    """
    Return True when ``stat`` exceeds the members' values ``null`` (module doc).

    Parameters
    ----------
    stat : float
        Statistic of the measurement (>= 0).
    null : array_like
        The same statistic on each ensemble member (>= 0).

    Returns
    -------
    bool

    """
    null = np.asarray(null, dtype=np.float64)
    limit = max(float(null.max()), float(null.mean() + NULL_K * null.std(ddof=1)))
    return bool(stat > limit)


class Context:
    """
    What fitters see.

    The measurement, the residual after accepted deterministic terms, the layout and the current
    model's ensemble signatures.

    Attributes
    ----------
    meas : Measurement or types.SimpleNamespace
        The measurement, or an object with its ``n``, ``rate_hz``, ``t_s``, ``temperature_c``
        and ``rate`` (a simulated record of :mod:`.uncertainty`).
    residual : numpy.ndarray
        Measurement minus the accepted deterministic terms (rad/s).
    layout : Layout
    meas_sig : dict
        Signatures of the measurement.
    member_sig : list of dict
        Signatures of each member of the current model.
    accepted : dict
        name -> params of the effects already in the model.

    A context made only to simulate terms and stamps may have None for ``residual``,
    ``meas_sig`` and ``member_sig``; reading one of them is then a programming error.

    """

    def __init__(self, meas: Measurement | SimpleNamespace, residual: FloatArray | None,
                 layout: Layout, meas_sig: Signatures | None,
                 member_sig: Sequence[Signatures] | None, accepted: Mapping[str, Params]) -> None:
        self.meas = meas
        self._residual = residual
        self.layout = layout
        self._meas_sig = meas_sig
        self._member_sig = member_sig
        self.accepted = accepted

    @property
    def residual(self) -> FloatArray:
        """Measurement minus the accepted deterministic terms (rad/s)."""
        assert self._residual is not None, 'this context has no residual'
        return self._residual

    @property
    def meas_sig(self) -> Signatures:
        """Signatures of the measurement."""
        assert self._meas_sig is not None, 'this context has no measurement signatures'
        return self._meas_sig

    @property
    def member_sig(self) -> Sequence[Signatures]:
        """Signatures of each member of the current model."""
        assert self._member_sig is not None, 'this context has no ensemble signatures'
        return self._member_sig

    @property
    def t_nominal(self) -> FloatArray:
        """Nominal sample times k / rate_hz (s)."""
        return np.arange(self.meas.n) / self.meas.rate_hz

    def members(self, name: str) -> FloatArray:
        """Member values of signature ``name``, shape (N, points)."""
        return np.array([s[name] for s in self.member_sig])


class Effect:
    """
    Base class.

    Name, number of parameters, kind ('additive', 'stochastic', 'quantization', 'stamps').
    """

    name = ''
    n_params = 1
    kind = 'additive'

    def fit(self, ctx: Context) -> Params | None:  # pragma: no cover - interface
        raise NotImplementedError

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        """
        Return the parameters the fitter would report, without its detection test.

        Used to refit the effect on records simulated from the final model (the parametric
        bootstrap of :mod:`.uncertainty`); None when the record gives no estimate. ``near`` holds
        the fitted parameters (an effect may start its search there).
        """
        return self.fit(ctx)

    def term(self, params: Params, n: int, rate_hz: float,  # pragma: no cover - interface
             rng: np.random.Generator | None, ctx: Context) -> FloatArray:
        """Return the additive term in rad/s, ``n`` samples; stochastic ones draw from ``rng``."""
        raise NotImplementedError

    def stamps(self, params: Params, n: int, rate_hz: float,  # pragma: no cover - interface
               rng: np.random.Generator, ctx: Context) -> FloatArray:
        """Return a member's stamps in s, ``n`` samples (the effects of kind 'stamps')."""
        raise NotImplementedError


def _zero_mean(x: FloatArray) -> FloatArray:
    return x - x.mean()


# --------------------------------------------------------------------------------------------------
# value lattice


class Quantization(Effect):
    """
    Output rounded to a lattice (LSB).

    Fitted from the values themselves (see signatures.find_lattice).
    """

    name = 'quantization'
    n_params = 2
    kind = 'quantization'

    def fit(self, ctx: Context) -> Params | None:
        if ctx.layout.lattice is None:
            return None
        step, offset = ctx.layout.lattice
        return {'step_rad_s': step, 'offset_rad_s': offset}

    @staticmethod
    def apply(params: Mapping[str, Any], x: FloatArray) -> FloatArray:
        """Round ``x`` onto the lattice."""
        step, offset = params['step_rad_s'], params['offset_rad_s']
        return offset + step * np.round((x - offset) / step)


# --------------------------------------------------------------------------------------------------
# deterministic additive terms


class Sinusoid(Effect):
    """
    A sine at one frequency.

    Found as the strongest line of the periodogram over its local background; the frequency is
    refined from the three DFT bins around the peak (Candan 2011) and then by Gauss-Newton steps of
    the least-squares sine fit (the maximum-likelihood frequency in white noise), amplitude and
    phase by linear least squares at that frequency.
    """

    name = 'sinusoid'
    n_params = 3

    @staticmethod
    def _line_ratio(x: FloatArray) -> tuple[NDArray[np.complex128], FloatArray]:
        coef = np.fft.rfft(x - x.mean())
        spec = coef.real ** 2 + coef.imag ** 2
        # local background: median of blocks of 64 bins (a line occupies 1-3 bins), interpolated
        block = 64
        nb = spec.shape[0] // block
        med = np.median(spec[:nb * block].reshape(nb, block), axis=1) / np.log(2.0)
        centres = (np.arange(nb) + 0.5) * block
        background = np.interp(np.arange(spec.shape[0]), centres, med)
        ratio = spec / np.maximum(background, 1e-300)
        # at least 10 cycles per record: slower 'lines' are the bias effects' business
        ratio[:10] = 0.0
        return coef, ratio

    @staticmethod
    def line(x: FloatArray, rate_hz: float, k: int | None, coef: NDArray[np.complex128] | None,
             start_hz: float | None = None) -> dict[str, float] | None:
        """
        Fit the sine whose periodogram peak is bin ``k`` (class doc).

        Parameters
        ----------
        x : numpy.ndarray
            Samples (rad/s).
        rate_hz : float
            Sample rate (Hz).
        k : int
            Peak bin of ``numpy.fft.rfft(x - mean)``, 1 <= k < bins - 1.
        coef : numpy.ndarray
            That rfft.
        start_hz : float, optional
            Start the refinement here instead of at the three-bin estimate (``k`` and ``coef``
            are then not used): the bootstrap refits a line near its fitted frequency.

        Returns
        -------
        dict or None
            ``amplitude_rad_s``, ``frequency_hz``, ``phase_rad``; None when the least-squares
            refinement leaves the bin it started in.

        """
        n = x.shape[0]
        bin_w = 2.0 * np.pi * rate_hz / n
        if start_hz is None:
            assert k is not None and coef is not None  # needed without start_hz (docstring)
            lo, mid, hi = coef[k - 1], coef[k], coef[k + 1]
            den = 2.0 * mid - lo - hi
            delta = float(np.real((lo - hi) / den)) if den != 0 else 0.0
            # Candan's bias correction of Jacobsen's estimator for the rectangular window
            delta = float(np.clip(delta * np.tan(np.pi / n) / (np.pi / n), -0.5, 0.5))
            start = (k + delta) * bin_w
        else:
            start = 2.0 * np.pi * float(start_hz)
        omega = start
        t = np.arange(n) / rate_hz
        tc = t - t.mean()
        y = x - x.mean()
        ty = tc * y
        tc2 = tc * tc
        # Gauss-Newton from a start within a fraction of a bin converges in 1-3 steps; it stops
        # when the step is below 1e-3 bin (far below the frequency's standard error)
        for _ in range(4):
            a, b, step = _sine_gauss_newton(y, ty, t, tc, tc2, omega)
            if not np.isfinite(step) or abs(omega + step - start) > bin_w:
                if start_hz is not None:
                    return None
                break
            if abs(step) < 1e-3 * bin_w:
                break
            omega += step
        else:
            a, b, _ = _sine_gauss_newton(y, ty, t, tc, tc2, omega)
        return {'amplitude_rad_s': float(np.hypot(a, b)),
                'frequency_hz': float(omega / (2 * np.pi)), 'phase_rad': float(np.arctan2(b, a))}

    def fit(self, ctx: Context) -> Params | None:
        x = ctx.residual
        coef, ratio = self._line_ratio(x)
        k = int(np.argmax(ratio))
        # exponential (chi-square 2 dof) periodogram ordinates: P(ratio > r) = exp(-r); ask for a
        # false-alarm probability of 1e-3 over all bins
        if ratio[k] < np.log(ratio.shape[0]) + np.log(1e3) or k + 1 >= coef.shape[0]:
            return None
        params = self.line(x, ctx.meas.rate_hz, k, coef)
        assert params is not None  # only a refinement from start_hz returns None
        freq = params['frequency_hz']
        # the line must also be where the measurement leaves the psd or psd_peak band: a steep
        # background (random walk, flicker) fools the local-median test at low frequency, but the
        # ensemble of the current model has the same steep background
        edges = ctx.layout.band_edges
        band = int(np.searchsorted(edges, freq)) - 1
        if 0 <= band < edges.size - 1:
            # narrow low bands hold one Welch bin, where a line raises the band mean, not the peak
            # ratio
            outside = [
                abs(c.z[band]) > c.threshold
                for c in (
                    compare(name, ctx.meas_sig[name], ctx.members(name))
                    for name in ('psd', 'psd_peak')
                )
            ]
            if not any(outside):
                return None
        return params

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        """
        Return the parameters of the strongest line without the detection test (or None).

        With ``near`` (fitted parameters) the line is refined from their frequency instead of
        searched for (the bootstrap refit: no periodogram, and None if it leaves that bin).
        """
        x = ctx.residual
        if near is not None:
            return self.line(x, ctx.meas.rate_hz, None, None, start_hz=near['frequency_hz'])
        coef, ratio = self._line_ratio(x)
        k = int(np.argmax(ratio))
        if k < 1 or k + 1 >= coef.shape[0]:
            return None
        return self.line(x, ctx.meas.rate_hz, k, coef)

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        t = np.arange(n) / rate_hz
        return _zero_mean(params['amplitude_rad_s']
                          * np.sin(2 * np.pi * params['frequency_hz'] * t + params['phase_rad']))


def _dot(a: FloatArray, b: FloatArray) -> float:
    """
    Return the dot product of two 1-D arrays without BLAS.

    OpenBLAS ``ddot`` wakes its thread pool; on a loaded machine that costs ~20 ms per call
    against ~10 us for einsum at 20,000 samples.
    """
    return float(np.einsum('i,i->', a, b))


def _sine_gauss_newton(y: FloatArray, ty: FloatArray, t: FloatArray, tc: FloatArray,
                       tc2: FloatArray, omega: float) -> tuple[float, float, float]:
    """
    Least-squares sine at ``omega`` and one Gauss-Newton step of its frequency.

    Model ``a sin(w t) + b cos(w t) + c0 + c1 tc`` (tc: centred time; the offset and the linear
    trend are nuisance terms, so a ramp in the record does not leak into the line); the step
    solves the linearised LS problem in (a, b, c0, c1, dw) with the frequency derivative
    ``tc (a cos - b sin)``. The normal equations are built from sums of cos(2 w t) and sin(2 w t)
    weighted by 1, tc, tc^2, of cos and sin weighted by the same, and of y and tc y against cos and
    sin: two trigonometric evaluations and fourteen dot products per call, O(n).

    Returns
    -------
    tuple
        (a, b) of the LS fit at ``omega`` and the step dw (rad/s).

    """
    cos, sin = np.cos(omega * t), np.sin(omega * t)
    # cos(2 w t) and sin(2 w t)
    cos2, sin2 = cos * cos - sin * sin, 2.0 * sin * cos
    n = y.shape[0]
    s2 = complex(cos2.sum(), sin2.sum())
    t1 = complex(_dot(tc, cos2), _dot(tc, sin2))
    t2 = complex(_dot(tc2, cos2), _dot(tc2, sin2))
    tye = complex(_dot(ty, cos), _dot(ty, sin))
    ss, cc, sc = (n - s2.real) / 2, (n + s2.real) / 2, s2.imag / 2
    s1, c1 = float(sin.sum()), float(cos.sum())
    st, ct = _dot(tc, sin), _dot(tc, cos)
    st2, ct2 = _dot(tc2, sin), _dot(tc2, cos)
    tt, t0 = float(tc2.sum()), float(tc.sum())
    ys, yc = _dot(y, sin), _dot(y, cos)
    rhs = np.array([ys, yc, float(y.sum()), float(ty.sum())])
    gram = np.array([[ss, sc, s1, st], [sc, cc, c1, ct], [s1, c1, n, t0], [st, ct, t0, tt]])
    try:
        a, b = np.linalg.solve(gram, rhs)[:2]
    except np.linalg.LinAlgError:
        return float('nan'), float('nan'), float('nan')
    # g = tc (a cos - b sin): its sums against sin, cos, 1, tc, itself and y
    tss, tcc, tsc = (t0 - t1.real) / 2, (t0 + t1.real) / 2, t1.imag / 2
    gg = (a * a + b * b) / 2 * tt + (a * a - b * b) / 2 * t2.real - a * b * t2.imag
    g = np.array([a * tsc - b * tss, a * tcc - b * tsc, a * ct - b * st, a * ct2 - b * st2])
    gy = a * tye.real - b * tye.imag
    full = np.block([[gram, g[:, None]], [g[None, :], np.array([[gg]])]])
    try:
        step = float(np.linalg.solve(full, np.append(rhs, gy))[4])
    except np.linalg.LinAlgError:
        step = float('nan')
    return float(a), float(b), step


def _centred_fit_stat(basis: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """
    RSS reductions of one-regressor fits.

    Basis (R, K) and y (..., K) -> (..., R), plus amplitudes.
    """
    bc = basis - basis.mean(axis=1, keepdims=True)
    yc = y - y.mean(axis=-1, keepdims=True)
    norm = np.einsum('rk,rk->r', bc, bc)
    proj = yc @ bc.T
    return proj ** 2 / norm, proj / norm


class BiasDrift(Effect):
    """Linear ramp of the bias, fitted to the chunk-bias series by least squares."""

    name = 'bias_drift'
    n_params = 1

    def fit(self, ctx: Context) -> Params | None:
        t = ctx.layout.chunk_t_s
        basis = t[None, :]
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        stat, amp = _centred_fit_stat(basis, y)
        null, _ = _centred_fit_stat(basis, ctx.members('chunk_bias'))
        if not null_exceeded(float(stat[0]), null[:, 0]):
            return None
        return {'slope_rad_s2': float(amp[0])}

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        _, amp = _centred_fit_stat(ctx.layout.chunk_t_s[None, :], y)
        return {'slope_rad_s2': float(amp[0])}

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        t = np.arange(n) / rate_hz
        return _zero_mean(params['slope_rad_s2'] * t)


class BiasTransient(Effect):
    """
    Delayed first-order rise or decay of the bias.

    Grid search over delay and time constant (detection), then the least-squares delay and time
    constant on the chunk means (Nelder-Mead from the best grid point, amplitude by linear LS).
    """

    name = 'bias_transient'
    n_params = 3

    @staticmethod
    def shape(t: FloatArray, delay: float, tc: float) -> FloatArray:
        """Return the unit transient 1 - exp(-(t - delay) / tc) for t >= delay, else 0."""
        return np.where(t >= delay, -np.expm1(-np.maximum(t - delay, 0.0) / tc), 0.0)

    @staticmethod
    def chunk_shape(edges: FloatArray, delay: float, tc: float) -> FloatArray:
        """
        Return the mean of the unit transient over each interval of ``edges`` (s), in closed form.

        The integral of 1 - exp(-(t - d) / tc) from max(a, d) to b, divided by b - a.
        """
        a, b = edges[:-1], edges[1:]
        lo = np.maximum(a, delay)
        inside = b > delay
        decay = (np.exp(-np.maximum(lo - delay, 0.0) / tc)
                 - np.exp(-np.maximum(b - delay, 0.0) / tc))
        return np.where(inside, (b - lo) - tc * decay, 0.0) / (b - a)

    #: Grid of the delay (fractions of the record, linear) and of the time constant (fractions of
    #: the record, geometric) of the detection; the estimate is then refined off the grid.
    DELAY_GRID = np.linspace(0.0, 0.8, 17)
    TC_GRID = np.geomspace(1.0 / 300.0, 1.0, 20)

    def _grid(self, t: FloatArray,
              duration: float) -> tuple[list[tuple[float, float]], FloatArray]:
        pairs = [(d * duration, c * duration) for d in self.DELAY_GRID for c in self.TC_GRID]
        return pairs, np.array([self.shape(t, d, c) for d, c in pairs])

    def _refine(self, ctx: Context, y: FloatArray, delay: float, tc: float) -> Params:
        """Least-squares (amplitude, delay, tc) on the chunk means ``y``, from a start point."""
        chunk, rate_hz = ctx.layout.chunk, ctx.meas.rate_hz
        duration = ctx.meas.n / rate_hz
        edges = np.arange(y.shape[0] + 1) * chunk / rate_hz
        yc = y - y.mean()

        def fit(p: FloatArray) -> tuple[float, float]:
            d, c = p[0] * duration, np.exp(p[1]) * duration
            basis = self.chunk_shape(edges, d, c)
            basis = basis - basis.mean()
            norm = basis @ basis
            amp = (basis @ yc) / norm if norm > 0 else 0.0
            return amp, float(((yc - amp * basis) ** 2).sum())

        def rss(p: FloatArray) -> float:
            if not (0.0 <= p[0] <= 0.95 and np.log(1e-3) <= p[1] <= np.log(10.0)):
                return float('inf')
            return fit(p)[1]

        start = np.array([delay / duration, np.log(tc / duration)])
        res = scipy.optimize.minimize(rss, start, method='Nelder-Mead',
                                      options={'xatol': 1e-4, 'fatol': 1e-12 * (yc @ yc),
                                               'initial_simplex': [start, start + [0.02, 0.0],
                                                                   start + [0.0, 0.2]]})
        best = res.x if np.isfinite(res.fun) and res.fun <= rss(start) else start
        amp = fit(best)[0]
        return {'amplitude_rad_s': float(amp), 'delay_s': float(best[0] * duration),
                'time_constant_s': float(np.exp(best[1]) * duration)}

    def _grid_best(self, ctx: Context,
                   y: FloatArray) -> tuple[list[tuple[float, float]], FloatArray, FloatArray, int]:
        pairs, basis = self._grid(ctx.layout.chunk_t_s, ctx.meas.n / ctx.meas.rate_hz)
        stat, _ = _centred_fit_stat(basis, y)
        best = int(np.argmax(stat))
        return pairs, basis, stat, best

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        pairs, _, _, best = self._grid_best(ctx, y)
        return self._refine(ctx, y, *pairs[best])

    def fit(self, ctx: Context) -> Params | None:
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        pairs, basis, stat, best = self._grid_best(ctx, y)
        null, _ = _centred_fit_stat(basis, ctx.members('chunk_bias'))
        if not null_exceeded(float(stat[best]), null.max(axis=1)):
            return None
        return self._refine(ctx, y, *pairs[best])

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        t = np.arange(n) / rate_hz
        return _zero_mean(params['amplitude_rad_s']
                          * self.shape(t, params['delay_s'], params['time_constant_s']))


class TemperatureSensitivity(Effect):
    """
    Bias proportional to temperature and to its rate (paper 002).

    Fitted by least squares on the chunk series.
    """

    name = 'temperature_sensitivity'
    n_params = 2

    def _regressors(self, ctx: Context) -> tuple[FloatArray, FloatArray]:
        temp = ctx.meas.temperature_c
        assert temp is not None  # the callers return None without a temperature
        return temperature_rate(temp, ctx.meas.rate_hz, ctx.layout.chunk)

    def fit(self, ctx: Context) -> Params | None:
        if ctx.meas.temperature_c is None:
            return None
        t_mean, t_rate = self._regressors(ctx)
        design = np.column_stack((np.ones_like(t_mean), t_mean - t_mean.mean(), t_rate))
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        members = ctx.members('chunk_bias')

        def reduction(values: FloatArray) -> tuple[FloatArray, FloatArray]:
            coef, *_ = np.linalg.lstsq(design, values.T, rcond=None)
            fitted = design @ coef
            yc = values.T - values.T.mean(axis=0)
            return (yc ** 2).sum(axis=0) - ((values.T - fitted) ** 2).sum(axis=0), coef

        stat, coef = reduction(y[None, :])
        null, _ = reduction(members)
        if not null_exceeded(float(stat[0]), null):
            return None
        return {'coefficient_rad_s_per_degc': float(coef[1, 0]),
                'rate_coefficient_rad_s_per_degc_per_s': float(coef[2, 0])}

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        if ctx.meas.temperature_c is None:
            return None
        t_mean, t_rate = self._regressors(ctx)
        design = np.column_stack((np.ones_like(t_mean), t_mean - t_mean.mean(), t_rate))
        y = chunk_series(ctx.residual, ctx.layout.chunk)[0]
        coef, *_ = np.linalg.lstsq(design, y, rcond=None)
        return {'coefficient_rad_s_per_degc': float(coef[1]),
                'rate_coefficient_rad_s_per_degc_per_s': float(coef[2])}

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        temp = ctx.meas.temperature_c
        assert temp is not None  # fitted only on a record with temperature
        chunk = ctx.layout.chunk
        # dT/dt at every sample: the derivative of the cubic spline through the chunk-boundary
        # temperatures, whose mean over each chunk is the fitted regressor exactly
        edge_t, edge_temp = temperature_edges(temp, rate_hz, chunk)
        t = np.arange(n) / rate_hz
        rate = scipy.interpolate.CubicSpline(edge_t, edge_temp).derivative()(t)
        return _zero_mean(params['coefficient_rad_s_per_degc'] * (temp - temp.mean())
                          + params['rate_coefficient_rad_s_per_degc_per_s'] * rate)


# --------------------------------------------------------------------------------------------------
# stochastic additive terms, fitted on the Allan variance in excess of the current model


def allan_template_from_psd(psd: Callable[[FloatArray], FloatArray], tau_s: FloatArray,
                            rate_hz: float, duration_s: float) -> FloatArray:
    """
    Allan variance of a process with PSD ``psd(f)`` (paper 001 eq. 8), integrated numerically.

    sigma^2(tau) = 4 int S(f) sin^4(pi f tau) / (pi f tau)^2 df over 1 / T .. fs / 2.

    Parameters
    ----------
    psd : callable
        f (Hz) -> PSD ((rad/s)^2 / Hz), the two-sided density of the IEEE 952 convention.
    tau_s : numpy.ndarray
        Cluster times (s).
    rate_hz, duration_s : float
        Sample rate (Hz) and record length (s): the integration limits.

    Returns
    -------
    numpy.ndarray
        Allan variance ((rad/s)^2).

    """
    freq = np.geomspace(1.0 / duration_s, rate_hz / 2.0, 6000)
    x = np.pi * np.outer(tau_s, freq)
    integrand = psd(freq)[None, :] * np.sin(x) ** 4 / x ** 2
    return 4.0 * np.trapezoid(integrand, freq, axis=1)


class _AllanFitted(Effect):
    """
    Common part.

    Weighted least squares of a template to the excess Allan variance, null from members.
    """

    kind = 'stochastic'

    def templates(self, ctx: Context,  # pragma: no cover - interface
                  ) -> tuple[list[dict[str, float]], FloatArray]:
        """Return (list of extra-params dicts, array (R, taus) of unit-amplitude templates)."""
        raise NotImplementedError

    @staticmethod
    def weights(members: FloatArray) -> FloatArray:
        """Return the inverse-variance weights of the Allan variances ``members`` (N, taus)."""
        mean = members.mean(axis=0)
        # the sd floor keeps a 5 % model tolerance at short tau, where the members agree very
        # closely
        return 1.0 / np.maximum(members.std(axis=0, ddof=1), 0.05 * mean) ** 2

    @staticmethod
    def best(templ: FloatArray, w: FloatArray,
             excess: FloatArray) -> tuple[FloatArray, FloatArray]:
        """
        Weighted LS amplitude of each template on each excess Allan variance.

        Parameters
        ----------
        templ : numpy.ndarray
            Unit-amplitude templates (R, taus).
        w : numpy.ndarray
            Weights (taus,).
        excess : numpy.ndarray
            Excess Allan variances (K, taus) ((rad/s)^2).

        Returns
        -------
        tuple of numpy.ndarray
            The RSS reduction and the amplitude (clipped at 0), each (R, K).

        """
        num = (templ * w) @ excess.T
        den = (templ ** 2 * w).sum(axis=1)
        amp = np.maximum(num, 0.0) / den[:, None]
        return amp ** 2 * den[:, None], amp

    def amplitude(self, params: Mapping[str, Any]) -> float:
        """Return the template amplitude of ``params`` (Allan variance scale, (rad/s)^2)."""
        raise NotImplementedError  # pragma: no cover - interface

    def params(self, amp: float, extra: Mapping[str, float]) -> Params:
        """Return the parameters of template amplitude ``amp`` and its extra parameters."""
        raise NotImplementedError  # pragma: no cover - interface

    def fit(self, ctx: Context) -> Params | None:
        avar_m = ctx.meas_sig['allan'] ** 2
        members = ctx.members('allan') ** 2
        mean = members.mean(axis=0)
        extras, templ = self.templates(ctx)
        w = self.weights(members)

        def best(excess: FloatArray) -> tuple[FloatArray, FloatArray]:
            return self.best(templ, w, excess)

        stat, amp = best((avar_m - mean)[None, :])
        # leave-one-out null: each member against the mean of the others
        count = members.shape[0]
        loo = members - (members.sum(axis=0)[None, :] - members) / (count - 1)
        null, _ = best(loo)
        r = int(np.argmax(stat[:, 0]))
        if not null_exceeded(
                float(stat[r, 0]), null.max(axis=0)) or not self.resolved(r, len(extras)):
            return None
        # the weights travel with the parameters (private): the bootstrap refits with the same
        # estimator
        return {**self.params(float(amp[r, 0]), extras[r]), '_allan_weights': w}

    def resolved(self, index: int, count: int) -> bool:
        """Tell whether the record tells the best template (of ``count``) from its neighbours."""
        return True


class RateRandomWalk(_AllanFitted):
    """Random walk of the bias (Allan variance K^2 tau / 3)."""

    name = 'rate_random_walk'
    n_params = 1

    def templates(self, ctx: Context) -> tuple[list[dict[str, float]], FloatArray]:
        return [{}], (ctx.layout.tau_s / 3.0)[None, :]

    def params(self, amp: float, extra: Mapping[str, float]) -> Params:
        return {'k_rad_s_per_sqrt_s': float(np.sqrt(amp))}

    def amplitude(self, params: Mapping[str, Any]) -> float:
        return params['k_rad_s_per_sqrt_s'] ** 2

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        assert rng is not None  # a stochastic term draws from the member's generator
        steps = rng.standard_normal(n) * params['k_rad_s_per_sqrt_s'] / np.sqrt(rate_hz)
        return _zero_mean(np.cumsum(steps))


def flicker_noise(n: int, rate_hz: float, b_rad_s: float, rng: np.random.Generator) -> FloatArray:
    """
    Flicker bias with PSD B^2 / (2 pi f) (IEEE 952 convention) from 1 / T to fs / 2.

    Made by spectral shaping.
    """
    spec = np.fft.rfft(rng.standard_normal(n))
    freq = np.fft.rfftfreq(n, 1.0 / rate_hz)
    gain = np.zeros_like(freq)
    # IEEE 952 PSDs are two-sided densities (paper 001 eq. 8 integrates them over f >= 0 with the
    # factor 4); white unit-variance samples have two-sided density 1 / fs
    gain[1:] = np.sqrt(b_rad_s ** 2 / (2 * np.pi * freq[1:]) * rate_hz)
    return np.fft.irfft(spec * gain, n)


class BiasInstability(_AllanFitted):
    """Flicker (1/f) bias: the Allan floor of the bias instability B."""

    name = 'bias_instability'
    n_params = 1

    def templates(self, ctx: Context) -> tuple[list[dict[str, float]], FloatArray]:
        duration = ctx.meas.n / ctx.meas.rate_hz
        t = allan_template_from_psd(lambda f: 1.0 / (2 * np.pi * f), ctx.layout.tau_s,
                                    ctx.meas.rate_hz, duration)
        return [{}], t[None, :]

    def params(self, amp: float, extra: Mapping[str, float]) -> Params:
        return {'b_rad_s': float(np.sqrt(amp))}

    def amplitude(self, params: Mapping[str, Any]) -> float:
        return params['b_rad_s'] ** 2

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        assert rng is not None  # a stochastic term draws from the member's generator
        return _zero_mean(flicker_noise(n, rate_hz, params['b_rad_s'], rng))


class GaussMarkov(_AllanFitted):
    """
    First-order Gauss-Markov bias.

    Correlation time on a log grid (3 / fs .. the longest tau / 1.89), variance by LS.
    """

    name = 'gauss_markov'
    n_params = 2

    def templates(self, ctx: Context) -> tuple[list[dict[str, float]], FloatArray]:
        tau = ctx.layout.tau_s
        # the Allan deviation of a Gauss-Markov process peaks at 1.89 tc: a longer tc shows only
        # its rise, which a random walk or a flicker bias gives as well (one parameter fewer)
        tcs = np.geomspace(3.0 / ctx.meas.rate_hz, float(tau[-1]) / GM_PEAK_TAU,
                           self.GRID_POINTS)
        return [{'correlation_time_s': float(c)} for c in tcs], np.array(
            [gauss_markov_avar(tau, 1.0, c) for c in tcs])

    #: Geometric grid of the correlation time: 3 / fs .. longest tau / 1.89 in this many points.
    GRID_POINTS = 30

    def params(self, amp: float, extra: Mapping[str, float]) -> Params:
        return {'sigma_rad_s': float(np.sqrt(amp)), **extra}

    def amplitude(self, params: Mapping[str, Any]) -> float:
        return params['sigma_rad_s'] ** 2

    def resolved(self, index: int, count: int) -> bool:
        # the best correlation time at the top of the grid wants a longer one still: the Allan
        # peak is not seen, a random walk or a flicker bias looks the same
        return index < count - 1

    def term(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator | None,
             ctx: Context) -> FloatArray:
        assert rng is not None  # a stochastic term draws from the member's generator
        return _zero_mean(gauss_markov(n, rate_hz, std=params['sigma_rad_s'],
                                       corr_time_s=params['correlation_time_s'], rng=rng))


# --------------------------------------------------------------------------------------------------
# stamps


def _intervals(ctx: Context) -> FloatArray:
    return np.diff(ctx.meas.t_s) * ctx.meas.rate_hz


def jittery(intervals: FloatArray) -> bool:
    """Tell whether over 1 % of the stamp intervals are below half a period (bursty delivery)."""
    return bool(np.mean(intervals < 0.5) > 0.01)


class SampleLoss(Effect):
    """
    Gaps in otherwise regular stamps.

    Poisson gap events, lost counts resampled from the measured gaps.
    """

    name = 'sample_loss'
    n_params = 2
    kind = 'stamps'

    def fit(self, ctx: Context) -> Params | None:
        d = _intervals(ctx)
        if jittery(d):
            return None
        gaps = d[d > 1.5]
        if gaps.size == 0:
            return None
        lost = np.round(gaps) - 1
        return {'gap_rate_per_s': float(gaps.size / (ctx.meas.n / ctx.meas.rate_hz)),
                'mean_lost_samples': float(lost.mean()), 'max_lost_samples': int(lost.max()),
                '_lost': lost}

    def stamps(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator,
               ctx: Context) -> FloatArray:
        """Ideal stamps with gaps inserted (s)."""
        events = rng.poisson(params['gap_rate_per_s'] * n / rate_hz)
        extra = np.zeros(n)
        if events:
            where = rng.integers(1, n, size=events)
            np.add.at(extra, where, rng.choice(params['_lost'], size=events))
        return (np.arange(n) + np.cumsum(extra)) / rate_hz


class StampJitter(Effect):
    """
    Bursty or jittered stamps (host-side receive times).

    Intervals resampled from the measurement.
    """

    name = 'stamp_jitter'
    n_params = 2
    kind = 'stamps'

    def fit(self, ctx: Context) -> Params | None:
        d = _intervals(ctx)
        if not jittery(d):
            return None
        return self.estimate(ctx)

    def estimate(self, ctx: Context, near: Params | None = None) -> Params | None:
        d = _intervals(ctx)
        k = np.arange(ctx.meas.n)
        line = np.polyval(np.polyfit(k, ctx.meas.t_s, 1), k)
        return {'jitter_rms_s': float(np.sqrt(np.mean((ctx.meas.t_s - line) ** 2))),
                'short_interval_fraction': float(np.mean(d < 0.5)), '_intervals': d}

    def stamps(self, params: Params, n: int, rate_hz: float, rng: np.random.Generator,
               ctx: Context) -> FloatArray:
        """Stamps from resampled measured intervals (s)."""
        d = rng.choice(params['_intervals'], size=n - 1)
        return np.concatenate(([0.0], np.cumsum(d))) / rate_hz


#: The catalogue in the order candidates are listed in reports.
CATALOGUE: tuple[Effect, ...] = (
    Quantization(), Sinusoid(), BiasDrift(), BiasTransient(), RateRandomWalk(), BiasInstability(),
    GaussMarkov(), TemperatureSensitivity(), SampleLoss(), StampJitter())
NAMES = tuple(e.name for e in CATALOGUE)


def public_params(params: Mapping[str, Any]) -> dict[str, Any]:
    """Parameters without the private (underscore) entries, for explain.json."""
    return {k: v for k, v in params.items() if not k.startswith('_')}
