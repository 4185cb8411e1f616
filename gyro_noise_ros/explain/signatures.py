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
Signatures that compare a measurement with a simulated ensemble, the band and the scalar gap.

Each signature is a vector of points on an axis fixed by the measurement (:class:`Layout`,
:func:`make_layout`), so the measurement and every member are evaluated at the same points
(:func:`compute`): ``allan`` (overlapping ADEV, :mod:`gyro_noise_ros.core.allan`), ``psd`` and
``psd_peak`` (Welch, in log bands), ``chunk_bias`` and ``chunk_variance`` (~100 chunks),
``histogram`` (values, plus the lattice phase when the values sit on a lattice), ``stamps``
(classes of stamp intervals) and ``temperature`` (correlations of the chunk bias with T and
dT/dt), each compared in the domain of :data:`TRANSFORM`.

Band (:func:`compare`): with mu_i, sd_i the ensemble mean and sd of the transformed values (sd
floored by :data:`SD_FLOOR`), ``z_i = (y_i - mu_i) / sd_i`` and ``D_s = max_i |z_i|``; the same
statistic of each member against the other N - 1 gives ``D_s,j``; the band half-width in z units
is ``T_s = max(3, max_j D_s,j, exp(mean ln D_s,j + 3 sd ln D_s,j))``; the measurement is inside
iff ``g_s = D_s / T_s <= 1``. Gap (:func:`total_gap`): ``G = sum_s ln(max(g_s, 1))``, 0 iff
inside every band; every model is judged by its own ensemble. :func:`mean_log_score` is the
proper score that ranks models whose gaps tie. Points, transforms, what each signature exposes:
docs/discrepancy.md section 3.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
import scipy.signal

from ..core.allan import allan_deviation_values

#: Transform and sd floor per signature (see module doc).
TRANSFORM = {'allan': 'log10', 'psd': 'log10', 'psd_peak': 'log10', 'chunk_bias': 'linear',
             'chunk_variance': 'log10', 'histogram': 'sqrt', 'stamps': 'sqrt',
             'temperature': 'linear'}
SD_FLOOR = {'allan': 0.01, 'psd': 0.01, 'psd_peak': 0.01, 'chunk_bias': 0.0,
            'chunk_variance': 0.01, 'histogram': 0.5, 'stamps': 0.5, 'temperature': 0.01}
#: Number of log-standard-deviations of the members' worst deviations that sets the band edge.
BAND_K = 3.0
#: Smallest band half-width in z units: with few or identical members (ideal stamps) the members'
#: own deviations say nothing, and a 3-sigma point-wise band is the conventional floor.
MIN_THRESHOLD = 3.0
STAMP_EDGES = np.array([0.0, 0.5, 1.5, 2.5, 5.5, 20.5, np.inf])
N_CHUNKS = 100
N_BANDS = 40
N_HIST = 32
N_PHASE = 10
#: A float array: float64 at run time; numpy's stubs widen many float64 results to ``floating``.
FloatArray = NDArray[np.floating[Any]]
#: Untransformed signature values of one series: name -> values at the layout's points
#: (:func:`compute`).
Signatures = dict[str, FloatArray]


@dataclass(frozen=True)
class Layout:
    """
    Points at which every signature is evaluated, fixed by the measurement.

    Attributes
    ----------
    rate_hz : float
        Nominal rate (Hz).
    n : int
        Samples.
    m : numpy.ndarray
        Allan cluster sizes (samples); tau = m / rate_hz.
    nperseg : int
        Welch segment length.
    band_edges : numpy.ndarray
        Frequency band edges (Hz) of the PSD signatures (each band holds at least one Welch bin).
    chunk : int
        Chunk length of the bias / variance / temperature signatures.
    hist_edges : numpy.ndarray
        Value histogram edges (rad/s).
    lattice : tuple or None
        (step_rad_s, offset_rad_s) of the measurement's value lattice, when it has one.
    temperature : bool
        Whether the temperature signature is evaluated.

    """

    rate_hz: float
    n: int
    m: NDArray[np.int64]
    nperseg: int
    band_edges: FloatArray
    chunk: int
    hist_edges: FloatArray
    lattice: tuple[float, float] | None = None
    temperature: bool = False

    @property
    def tau_s(self) -> FloatArray:
        """Allan cluster times (s)."""
        return self.m / self.rate_hz

    @property
    def chunk_t_s(self) -> FloatArray:
        """Mid-times of the chunks (s, nominal)."""
        k = self.n // self.chunk
        return (np.arange(k) + 0.5) * self.chunk / self.rate_hz

    @property
    def band_centers_hz(self) -> FloatArray:
        """Geometric centres of the PSD bands (Hz)."""
        return np.sqrt(self.band_edges[:-1] * self.band_edges[1:])


def find_lattice(x: FloatArray) -> tuple[float, float] | None:
    """
    Find the value lattice of quantised samples, ``x = offset + k * step`` with integer k.

    Parameters
    ----------
    x : numpy.ndarray
        Samples (rad/s).

    Returns
    -------
    tuple or None
        ``(step, offset)`` in rad/s, or None when fewer than 99 % of the samples lie within 2 % of
        a step of one lattice, or the values are not on a few levels (more than n / 4 distinct
        values).

    """
    sd = float(np.std(x))
    # rounding far below any realistic LSB keeps text-file round-off from splitting one level in
    # two
    eps = 1e-7 * sd
    levels = np.unique(np.round(x / eps)) * eps
    if levels.size < 3 or levels.size > x.size // 4:
        return None
    d = np.diff(levels)
    d = d[d > 1e-4 * sd]
    if d.size == 0:
        return None
    q0 = float(d.min())
    k = np.round(d / q0)
    step = float(np.sum(d * k) / np.sum(k * k))
    # circular mean: levels a hair below a lattice point must not average with those a hair above
    # it
    offset = float(np.angle(np.mean(np.exp(2j * np.pi * levels / step))) / (2 * np.pi) * step)
    phase = np.mod(x - offset + 0.5 * step, step) / step - 0.5
    if np.mean(np.abs(phase) < 0.02) < 0.99:
        return None
    step, offset, _ = lattice_fit(levels, step, offset)
    return step, offset


def lattice_fit(levels: FloatArray, step: float,
                offset: float) -> tuple[float, float, FloatArray | None]:
    """
    Least-squares lattice through the distinct values: ``level = offset + k step``, k integer.

    Parameters
    ----------
    levels : numpy.ndarray
        Distinct sample values (rad/s).
    step, offset : float
        A first lattice (rad/s), which fixes each level's index k.

    Returns
    -------
    tuple
        ``(step, offset, cov)``: the LS step and offset (the offset reduced modulo the step into
        [-step/2, step/2): the lattice is the same, the number readable), and the 2 x 2 covariance
        of (step, offset) from the levels' scatter about the line (None with fewer than 3 levels
        on the lattice). Levels further than 2 % of a step from the lattice are left out.

    """
    k = np.round((levels - offset) / step)
    on = np.abs(levels - offset - k * step) < 0.02 * step
    levels, k = levels[on], k[on]
    if levels.size < 3:
        return step, float(np.mod(offset + 0.5 * step, step) - 0.5 * step), None
    for _ in range(2):
        design = np.column_stack((k, np.ones_like(k)))
        coef, *_ = np.linalg.lstsq(design, levels, rcond=None)
        # renumber the levels so that the intercept is the reduced offset
        shift = np.floor((coef[1] + 0.5 * coef[0]) / coef[0])
        if shift == 0:
            break
        k = k + shift
    resid = levels - design @ coef
    # find_lattice rounds the values to 1e-7 of their sd (about 2e-8 of the levels' sd): that
    # rounding is the least scatter the levels can show
    eps = 2e-8 * float(np.std(levels))
    s2 = max(float(resid @ resid) / (levels.size - 2), eps ** 2 / 12.0)
    cov = s2 * np.linalg.inv(design.T @ design)
    return float(coef[0]), float(coef[1]), cov


def make_layout(x: FloatArray, rate_hz: float, *, temperature: bool = False) -> Layout:
    """
    Fix the signature points from the measurement.

    Parameters
    ----------
    x : numpy.ndarray
        Measured angular rate (rad/s).
    rate_hz : float
        Nominal rate (Hz).
    temperature : bool, keyword-only
        Include the temperature signature.

    Returns
    -------
    Layout

    """
    n = x.shape[0]
    m_max = n // 10
    count = int(np.floor(2 * np.log2(m_max))) + 1
    m = np.unique(np.round(2.0 ** (np.arange(count) / 2)).astype(np.int64))
    nperseg = int(min(4096, 2 ** int(np.floor(np.log2(n // 16)))))
    # band edges half-way between Welch bins, log-spaced from bin 2 up, so no band is empty
    k_edges = np.unique(np.round(np.geomspace(2, nperseg // 2, N_BANDS + 1)))
    band_edges = (k_edges - 0.5) * rate_hz / nperseg
    chunk = max(64, n // N_CHUNKS)
    mu, sd = float(np.mean(x)), float(np.std(x))
    hist_edges = np.linspace(mu - 4 * sd, mu + 4 * sd, N_HIST + 1)
    return Layout(rate_hz=float(rate_hz), n=n, m=m, nperseg=nperseg, band_edges=band_edges,
                  chunk=chunk, hist_edges=hist_edges, lattice=find_lattice(x),
                  temperature=bool(temperature))


def welch(x: FloatArray, rate_hz: float,
          nperseg: int) -> tuple[FloatArray, FloatArray]:
    """
    Welch PSD estimate: Hann window, 50 % overlap, mean removed once, one-sided density.

    Equal to ``scipy.signal.welch(x - mean(x), fs, 'hann', nperseg, detrend=False)`` (checked in
    the tests) without its per-segment bookkeeping, which dominated the ensemble run time.

    Parameters
    ----------
    x : numpy.ndarray
        Samples (rad/s).
    rate_hz : float
        Sample rate (Hz).
    nperseg : int
        Segment length (even).

    Returns
    -------
    tuple of numpy.ndarray
        Frequencies (Hz) and PSD ((rad/s)^2 / Hz).

    """
    window = scipy.signal.get_window('hann', nperseg)
    segs = np.lib.stride_tricks.sliding_window_view(x - x.mean(), nperseg)[::nperseg // 2]
    spec = np.fft.rfft(segs * window, axis=1)
    pxx = np.mean(spec.real ** 2 + spec.imag ** 2, axis=0) / (rate_hz * (window @ window))
    pxx[1:-1] *= 2.0
    return np.fft.rfftfreq(nperseg, 1.0 / rate_hz), pxx


def chunk_series(values: FloatArray, chunk: int) -> tuple[FloatArray, FloatArray]:
    """Return per-chunk means and variances (ddof 1) of the complete chunks of ``values``."""
    k = values.shape[0] // chunk
    blocks = values[:k * chunk].reshape(k, chunk)
    return blocks.mean(axis=1), blocks.var(axis=1, ddof=1)


def temperature_edges(temperature_c: FloatArray, rate_hz: float,
                      chunk: int) -> tuple[FloatArray, FloatArray]:
    """
    Return the times (s) of the chunk boundaries and the temperature (degC) there.

    Boundary j lies half a sample before the first sample of chunk j.

    Each boundary value is the intercept of a least-squares line through the samples within
    ``max(4, chunk // 8)`` samples of the boundary (one-sided at the ends of the record), which
    averages the sensor's LSB steps out and, unlike a window mean, is unbiased on a slope.
    """
    n = temperature_c.shape[0]
    k = n // chunk
    edge = np.arange(k + 1) * chunk - 0.5
    half = max(4, chunk // 8)
    lo = np.clip(np.ceil(edge - half), 0, n).astype(np.int64)
    hi = np.clip(np.floor(edge + half) + 1, 0, n).astype(np.int64)
    index = np.arange(n, dtype=np.float64)
    c0 = np.concatenate(([0.0], np.cumsum(temperature_c)))
    c1 = np.concatenate(([0.0], np.cumsum(index * temperature_c)))
    m = (hi - lo).astype(np.float64)
    sk = (lo + hi - 1) * m / 2.0
    skk = ((hi - 1) * hi * (2 * hi - 1) - (lo - 1) * lo * (2 * lo - 1)) / 6.0
    sy = c0[hi] - c0[lo]
    su = sk - m * edge
    suu = skk - 2.0 * edge * sk + m * edge * edge
    suy = (c1[hi] - c1[lo]) - edge * sy
    den = m * suu - su * su
    slope = np.where(den > 0, (m * suy - su * sy) / np.where(den > 0, den, 1.0), 0.0)
    value = (sy - slope * su) / m
    return edge / rate_hz, value


def temperature_rate(temperature_c: FloatArray, rate_hz: float,
                     chunk: int) -> tuple[FloatArray, FloatArray]:
    """
    Return chunk-mean temperature (degC) and the chunk mean of its rate dT/dt (degC/s).

    The mean of dT/dt over a chunk is exactly the temperature difference between its ends over its
    duration; the end values come from :func:`temperature_edges`. (A central difference of the
    chunk means, used before, is 2 % low for a cycle of 17 chunks, enough to bias a fitted rate
    coefficient by tens of standard errors.)
    """
    t_mean, _ = chunk_series(temperature_c, chunk)
    _, edge = temperature_edges(temperature_c, rate_hz, chunk)
    return t_mean, np.diff(edge) * rate_hz / chunk


def compute(layout: Layout, x: FloatArray, t_s: FloatArray | None,
            temperature_c: FloatArray | None = None) -> Signatures:
    """
    Evaluate every signature of one series on the layout (untransformed values).

    Parameters
    ----------
    layout : Layout
        Where each signature is evaluated.
    x : numpy.ndarray
        Angular rate (rad/s), ``layout.n`` samples.
    t_s : numpy.ndarray or None
        Sample times (s); None means ideal stamps k / rate_hz.
    temperature_c : numpy.ndarray or None
        Temperature per sample (degC), needed when ``layout.temperature``.

    Returns
    -------
    dict
        name -> 1-D numpy.ndarray.

    """
    out: Signatures = {}
    out['allan'] = allan_deviation_values(x, layout.rate_hz, taus=layout.m)
    freq, pxx = welch(x, layout.rate_hz, layout.nperseg)
    bands = layout.band_edges.size - 1
    band = np.digitize(freq, layout.band_edges) - 1
    ok = (band >= 0) & (band < bands)
    sums = np.bincount(band[ok], weights=pxx[ok], minlength=bands)
    counts = np.bincount(band[ok], minlength=bands)
    out['psd'] = sums / np.maximum(counts, 1)
    peak = np.zeros(bands)
    np.maximum.at(peak, band[ok], pxx[ok])
    out['psd_peak'] = peak / np.maximum(out['psd'], 1e-300)
    bias, var = chunk_series(x, layout.chunk)
    out['chunk_bias'] = bias
    out['chunk_variance'] = var
    hist = _uniform_counts(x, layout.hist_edges[0], layout.hist_edges[-1], N_HIST)
    if layout.lattice is not None:
        step, offset = layout.lattice
        # lattice points land at phase 0.05, the middle of the first bin, far from any bin edge
        phase = np.mod(x - offset + 0.05 * step, step) / step
        hist = np.concatenate((hist, _uniform_counts(phase, 0.0, 1.0, N_PHASE)))
    out['histogram'] = hist
    if t_s is None:
        out['stamps'] = np.zeros(STAMP_EDGES.size - 1)
        out['stamps'][1] = layout.n - 1
    else:
        out['stamps'] = np.histogram(np.diff(t_s) * layout.rate_hz,
                                     bins=STAMP_EDGES)[0].astype(np.float64)
    if layout.temperature:
        assert temperature_c is not None  # a layout with temperature is made for a record with it
        t_mean, t_rate = temperature_rate(temperature_c, layout.rate_hz, layout.chunk)
        out['temperature'] = np.array([_corr(bias, t_mean), _corr(bias, t_rate)])
    return out


def _uniform_counts(x: FloatArray, lo: float, hi: float, bins: int) -> FloatArray:
    """
    Count as np.histogram(x, bins, range=(lo, hi)), via bincount.

    Values outside are dropped, hi is inclusive.
    """
    scaled = (x - lo) * (bins / (hi - lo))
    inside = (scaled >= 0) & (x <= hi)
    idx = np.minimum(scaled[inside].astype(np.int64), bins - 1)
    return np.bincount(idx, minlength=bins).astype(np.float64)


def _corr(a: FloatArray, b: FloatArray) -> float:
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt((a @ a) * (b @ b))
    return float(a @ b / den) if den > 0 else 0.0


def transform(name: str, values: ArrayLike) -> FloatArray:
    """Apply the comparison transform of signature ``name`` (module doc)."""
    kind = TRANSFORM[name]
    if kind == 'log10':
        return np.log10(np.maximum(values, 1e-300))
    if kind == 'sqrt':
        return np.sqrt(np.maximum(values, 0.0))
    return np.asarray(values, dtype=np.float64)


def points(layout: Layout, name: str) -> tuple[str, str, FloatArray]:
    """
    Return the x-axis of signature ``name`` (label and values) for plots and the ``where`` text.

    Returns
    -------
    tuple
        (label, unit, numpy.ndarray)

    """
    if name == 'allan':
        return 'tau', 's', layout.tau_s
    if name in ('psd', 'psd_peak'):
        return 'frequency', 'Hz', layout.band_centers_hz
    if name in ('chunk_bias', 'chunk_variance'):
        return 'time', 's', layout.chunk_t_s
    if name == 'histogram':
        centres = 0.5 * (layout.hist_edges[:-1] + layout.hist_edges[1:])
        if layout.lattice is not None:
            centres = np.concatenate((centres, np.arange(N_PHASE) / N_PHASE))
        return (
            'value',
            'rad/s (then lattice phase)' if layout.lattice is not None else 'rad/s',
            centres,
        )
    if name == 'stamps':
        return 'interval / period', '', 0.5 * (STAMP_EDGES[:-1]
                                               + np.minimum(STAMP_EDGES[1:], 40.0))
    return 'correlation with', '(T, dT/dt)', np.array([0.0, 1.0])


@dataclass(frozen=True)
class Comparison:
    """
    Measurement against ensemble on one signature (definitions in the module doc).

    Attributes
    ----------
    name : str
    y : numpy.ndarray
        Transformed measurement values.
    mu, sd : numpy.ndarray
        Ensemble mean and (floored) sd of the transformed member values.
    z : numpy.ndarray
        Measurement z per point.
    threshold : float
        T_s, the band half-width in z units.
    g : float
        D_s / T_s (> 1: outside the band).
    outside : numpy.ndarray of bool
        Points where |z| > T_s.

    """

    name: str
    y: FloatArray
    mu: FloatArray
    sd: FloatArray
    z: FloatArray
    threshold: float
    g: float
    outside: NDArray[np.bool_]

    @property
    def gap(self) -> float:
        """Return this signature's share of the scalar gap, ln(max(g, 1))."""
        return float(np.log(max(self.g, 1.0)))


def compare(name: str, measured: ArrayLike, members: ArrayLike) -> Comparison:
    """
    Compare one signature of the measurement with the ensemble (module doc).

    Parameters
    ----------
    name : str
        Signature name (a key of the layout).
    measured : array_like
        Untransformed measurement values.
    members : array_like
        Untransformed member values, shape (N, points).

    Returns
    -------
    Comparison

    """
    y = transform(name, measured)
    yy = transform(name, np.asarray(members))
    count = yy.shape[0]
    floor = SD_FLOOR[name]
    mu = yy.mean(axis=0)
    sd = np.maximum(yy.std(axis=0, ddof=1), floor)
    # leave-one-out mean and sd of the other N - 1 members, in closed form
    s1 = yy.sum(axis=0)
    s2 = (yy * yy).sum(axis=0)
    mu_l = (s1[None, :] - yy) / (count - 1)
    var_l = (s2[None, :] - yy * yy - (count - 1) * mu_l * mu_l) / (count - 2)
    sd_l = np.maximum(np.sqrt(np.maximum(var_l, 0.0)), floor)
    tiny = 1e-12 * (np.abs(mu) + 1e-300)
    sd = np.maximum(sd, tiny)
    sd_l = np.maximum(sd_l, tiny[None, :])
    d_members = np.max(np.abs(yy - mu_l) / sd_l, axis=1)
    z = (y - mu) / sd
    log_d = np.log(np.maximum(d_members, 1e-6))
    threshold = float(max(MIN_THRESHOLD, d_members.max(),
                          np.exp(log_d.mean() + BAND_K * log_d.std(ddof=1))))
    d = float(np.max(np.abs(z)))
    return Comparison(name=name, y=y, mu=mu, sd=sd, z=z, threshold=threshold, g=d / threshold,
                      outside=np.abs(z) > threshold)


def total_gap(comparisons: Mapping[str, Comparison]) -> float:
    """Return the scalar gap G = sum_s ln(max(g_s, 1)) (module doc)."""
    return float(sum(c.gap for c in comparisons.values()))


def mean_log_score(comparisons: Mapping[str, Comparison]) -> float:
    """
    Return sum_s mean_i (z_i^2 / 2 + ln sd_i): a Gaussian negative log-likelihood per point.

    The gap is 0 for every model whose bands contain the measurement; this secondary score still
    tells such models apart (the workflow uses it only among candidates with tied gaps). Unlike the
    z alone it is a proper score: a model cannot win by widening its band (the ln sd term), only by
    putting its ensemble where the measurement is.
    """
    return float(sum(np.mean(0.5 * c.z ** 2 + np.log(c.sd)) for c in comparisons.values()))


def describe_where(layout: Layout, comparison: Comparison) -> str:
    """
    Return a short text naming where the measurement leaves the band of one signature.

    Parameters
    ----------
    layout : Layout
        The layout the comparison was computed on.
    comparison : Comparison
        The comparison to describe.

    Returns
    -------
    str
        Empty if inside the band.

    """
    if not comparison.outside.any():
        return ''
    name = comparison.name
    label, unit, xs = points(layout, name)
    idx = np.flatnonzero(comparison.outside)
    side = 'above' if comparison.z[idx].mean() > 0 else 'below'
    if name == 'temperature':
        which = ['T', 'dT/dt']
        return (
            f'correlation of chunk bias with {", ".join(which[i] for i in idx)} outside the band'
        )
    if name == 'stamps':
        labels = ['<0.5', '0.5-1.5', '1.5-2.5', '2.5-5.5', '5.5-20.5', '>20.5']
        return (
            f'stamp intervals (periods) {", ".join(labels[i] for i in idx)} counts {side} the band'
        )
    if name == 'histogram' and layout.lattice is not None and idx.max() >= N_HIST:
        return (f'values sit on a lattice of {layout.lattice[0]:.4g} rad/s '
                'that the model does not produce')
    lo, hi = xs[idx.min()], xs[idx.max()]
    return (f'{name} {side} the band for {label} {lo:.4g}..{hi:.4g} {unit} '
            f'({idx.size} of {xs.size} points)')
