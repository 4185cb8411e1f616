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
The paper's parallel processing model (paper 002, section 3.5, Figure 7), per gyro axis.

:class:`ParallelModel` is a ``ThermalMethod`` of :mod:`.run` (rad/s, degC; ``causal = False``: VMD
and TFPF need the whole record, the live node refuses it). **Fit** on a training run:

1. MOPSO (:mod:`.mopso`) chooses (K, alpha) minimising the mean fuzzy and permutation entropy of
   the modes of a VMD, on ``fitness_windows`` windows of ``fitness_samples`` samples (cached,
   over ``workers`` processes), then :func:`.mopso.refine` re-ranks the best points on a
   reference fitness (the whole run, or longer windows); ``fitness_samples=None`` is the naive
   whole-run search.
2. VMD of the whole run with (K, alpha), warm-started (at most ``full_vmd_iter`` iterations);
   the modes classified by sample entropy (:mod:`.classify`) into drift, mixed, noise.
3. The drift model (:func:`.elman.fit_drift`) learns the drift part from [T, dT] on block means
   (at most ``elman_samples`` points): the stated basis ``drift_base``, then an Elman network on
   what it leaves (``drift_base='none'`` with no decay is the paper's network alone).

**Apply** to another run: VMD with the trained K, alpha (warm-started, centre frequencies through
Hz), the new modes classified, noise modes dropped, TFPF (:mod:`.tfpf`) on the sum of the mixed
modes, the drift model's prediction subtracted from the sum of the drift modes (inputs held at
the trained range's edge beyond it, counted in ``last_info``), the two parts added.
:meth:`ParallelModel.report_figures` draws the paper's Figures 11, 12 and 14-17 from what
``apply`` kept (:func:`.parallel_figures.parallel_figures`). Options, file format, costs and
measurements: docs/thermal_model.md (the parallel model section).
"""

from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from pathlib import Path
from typing import Any
import weakref

from gyro_noise_ros.cluster import make_executor
from gyro_noise_ros.errors import InputDataError, ParameterError
from gyro_noise_ros.outputs import StrPath
from gyro_noise_ros.plotting import envelope as full_envelope
from gyro_noise_ros.thermal.classify import classify_modes, ModeClasses
from gyro_noise_ros.thermal.elman import DriftModel, fit_drift
from gyro_noise_ros.thermal.mopso import mopso, PAPER_BOUNDS, refine, VmdFitness
from gyro_noise_ros.thermal.parallel_figures import PANEL_POINTS, parallel_figures
from gyro_noise_ros.thermal.run import (DEFAULT_RATE_WINDOW_S, temperature_rate_c_s,
                                        ThermalRun)
from gyro_noise_ros.thermal.tfpf import tfpf
from gyro_noise_ros.thermal.vmd import vmd, VmdResult
import numpy as np
from numpy.typing import ArrayLike, NDArray

# (gyro (n, 3) rad/s, temperature (n,) degC, its rate (n,) degC/s) of a run.
_Inputs = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]

#: Options of :class:`ParallelModel` and their defaults (the paper's MOPSO settings).
DEFAULT_OPTIONS = {
    'bounds': [list(b) for b in PAPER_BOUNDS],
    'n_particles': 40,
    'archive_size': 40,
    'iterations': 10,
    'w': 0.4,
    'c1': 1.5,
    'c2': 1.5,
    'fitness_samples': 256,
    'fitness_windows': 4,
    'refine_points': 10,
    'refine_polish': 16,
    'refine_samples': 1024,
    'refine_windows': 4,
    'vmd_tol': 1e-7,
    'vmd_max_iter': 500,
    'full_vmd_iter': 30,
    'apply_vmd_iter': 3,
    'drift_max': 0.5,
    'noise_min': 1.5,
    'entropy_samples': 2000,
    'entropy_scale': None,
    'tfpf_window': 31,
    'elman_hidden': [6, 6],
    'elman_iterations': 100,
    'elman_epochs': 20,
    'elman_samples': 2000,
    'elman_refine': 300,
    'elman_weight_decay': 1e-3,
    'drift_base': 'cubic_rate',
    'rate_window_s': DEFAULT_RATE_WINDOW_S,
    'workers': 1,
}


def fitness_windows(x: NDArray[np.float64], n: int | None, count: int) -> NDArray[np.float64]:
    """
    Return ``count`` windows (count, n) spread evenly over ``x`` (``x`` itself if too short).

    The windows' starts are equally spaced from the first to the last possible one, so the
    first starts the record and the last ends it; ``n = None`` or ``count * n >= len(x)``
    gives the whole record (1, len(x)).
    """
    if n is None or int(n) * int(count) >= x.size:
        return x[None, :]
    n, count = int(n), int(count)
    starts = np.linspace(0, x.size - n, count).round().astype(int)
    return np.stack([x[s:s + n] for s in starts])


def block_means(x: ArrayLike, q: int) -> NDArray[np.float64]:
    """Return the means of consecutive blocks of ``q`` samples (the last block may be short)."""
    x = np.asarray(x, dtype=float)
    idx = np.arange(0, x.shape[0], q)
    sums = np.add.reduceat(x, idx, axis=0)
    counts = np.diff(np.append(idx, x.shape[0]))
    return sums / (counts if x.ndim == 1 else counts[:, None])


class ParallelModel:
    """
    MOVMD-TFPF and BAS-Elman parallel model (paper 002, Figure 7); a ``ThermalMethod``.

    Keyword options are those of :data:`DEFAULT_OPTIONS` (see the module docstring and
    docs/thermal_model.md). After :meth:`apply`, :attr:`last_info` holds per-axis diagnostics
    (centre frequencies, classes and sample entropies of the modes: the paper's Figure 13).
    """

    name = 'parallel'
    causal = False
    #: Executor of the MOPSO fitness evaluations (e.g. a Dask cluster's, from
    #: :func:`gyro_noise_ros.cluster.make_executor`), set by the caller, who shuts it down; None:
    #: ``workers`` local processes. Where the work runs, not what it computes: not an option,
    #: not in :meth:`to_dict` (the fit is the same either way).
    executor: Executor | None = None

    def __init__(self, **options: Any) -> None:
        unknown = set(options) - set(DEFAULT_OPTIONS)
        if unknown:
            raise ParameterError(f'unknown ParallelModel options: {sorted(unknown)}')
        self.options = {**DEFAULT_OPTIONS, **options}
        for name in ('fitness_samples', 'refine_samples'):
            fs = self.options[name]
            if fs is not None and int(fs) < 64:
                raise ParameterError(f'{name} must be >= 64 or None, got {fs!r}')
        if int(self.options['refine_points']) < 0 or int(self.options['refine_polish']) < 0:
            raise ParameterError('refine_points and refine_polish must be >= 0')
        self.axes: list[dict[str, Any]] | None = None
        self.rate_hz: float | None = None
        self.temperature_range_c: list[float] | None = None
        self.fit_info: list[dict[str, Any]] | None = None
        self.last_info: list[dict[str, Any]] | None = None
        self._report_parts: tuple[Callable[[], Any], list[dict[str, Any]]] | None = None

    # -- fitting ---------------------------------------------------------------------------
    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Learn K, alpha, the mode classes and the drift network per axis from one run."""
        x_all, temp, rate = self._inputs(run)
        o = self.options
        axes: list[dict[str, Any]]
        info: list[dict[str, Any]]
        axes, info = [], []
        own = None if self.executor is not None else make_executor(int(o['workers']))
        pool = self.executor if self.executor is not None else own
        try:
            for a in range(3):
                axes.append(self._fit_axis(x_all[:, a], temp, rate, run.rate_hz, rng, pool,
                                           info))
        finally:
            if own is not None:
                # an interrupt must not wait for the particles still queued (SIGINT/SIGTERM)
                own.shutdown(cancel_futures=True)
        self.axes = axes
        self.rate_hz = float(run.rate_hz)
        self.temperature_range_c = [float(temp.min()), float(temp.max())]
        self.fit_info = info

    def _fit_axis(self, x: NDArray[np.float64], temp: NDArray[np.float64],
                  rate: NDArray[np.float64], rate_hz: float, rng: np.random.Generator,
                  pool: Executor | None, info: list[dict[str, Any]]) -> dict[str, Any]:
        o = self.options
        # Independent streams: the network's start does not depend on how many draws the
        # swarm made, so options that change the search leave the network's seed alone.
        swarm_rng, elman_rng = rng.spawn(2)
        segs = fitness_windows(x, o['fitness_samples'], o['fitness_windows'])
        fitness = VmdFitness(np.ascontiguousarray(segs), tol=o['vmd_tol'],
                             max_iter=int(o['vmd_max_iter']))
        bounds = tuple(tuple(b) for b in o['bounds'])
        map_fn = map if pool is None else pool.map
        res = mopso(fitness, rng=swarm_rng, bounds=bounds,
                    n_particles=int(o['n_particles']), archive_size=int(o['archive_size']),
                    iterations=int(o['iterations']), w=o['w'], c1=o['c1'], c2=o['c2'],
                    map_fn=map_fn)
        ref_segs = fitness_windows(x, o['refine_samples'], o['refine_windows'])
        if segs.size != x.size and int(o['refine_points']) > 0:
            # The windowed fitness misranks points; re-evaluate the best of them (and polish
            # the pick) with the reference fitness: the whole run when it is at most
            # refine_windows x refine_samples long, longer windows otherwise.
            reference = VmdFitness(np.ascontiguousarray(ref_segs), tol=o['vmd_tol'],
                                   max_iter=int(o['vmd_max_iter']))
            res = refine(res, reference, points=int(o['refine_points']),
                         polish=int(o['refine_polish']), bounds=bounds, map_fn=map_fn)
        if segs.size == x.size:
            dec = vmd(x, k=res.k, alpha=res.alpha, tol=o['vmd_tol'],
                      max_iter=int(o['vmd_max_iter']))
        else:
            start = vmd(segs[segs.shape[0] // 2], k=res.k, alpha=res.alpha, tol=o['vmd_tol'],
                        max_iter=int(o['vmd_max_iter']))
            dec = vmd(x, k=res.k, alpha=res.alpha, tol=o['vmd_tol'], solver='exact',
                      center_freqs=start.center_freqs, max_iter=int(o['full_vmd_iter']),
                      workers=int(o['workers']))
        cls = self._classify(dec)
        drift = dec.modes[cls.mask('drift')].sum(axis=0)
        q = max(1, -(-x.size // int(o['elman_samples'])))
        elman = fit_drift(block_means(np.c_[temp, rate], q), block_means(drift, q),
                          dt_s=q / rate_hz, rng=elman_rng, base=o['drift_base'],
                          hidden=tuple(o['elman_hidden']),
                          iterations=int(o['elman_iterations']), epochs=int(o['elman_epochs']),
                          refine_iterations=int(o['elman_refine']),
                          weight_decay=float(o['elman_weight_decay']))
        info.append(self._axis_info(dec, cls, rate_hz))
        info[-1]['mopso'] = {'evaluations': res.evaluations, 'requested': res.requested,
                             'archive_k': res.archive_params[:, 0].astype(int).tolist(),
                             'archive_alpha': res.archive_params[:, 1].tolist(),
                             'archive_fuzzy_entropy': res.archive_fitness[:, 0].tolist(),
                             'archive_permutation_entropy': res.archive_fitness[:, 1].tolist(),
                             'reference_evaluations': res.reference_evaluations,
                             'search_k': (res.k if res.search_pick is None
                                          else int(res.search_pick[0])),
                             'search_alpha': (res.alpha if res.search_pick is None
                                              else float(res.search_pick[1])),
                             'fitness_shape': list(segs.shape),
                             'reference_shape': (list(ref_segs.shape) if res.search_pick
                                                 is not None else list(segs.shape))}
        return {'k': res.k, 'alpha': res.alpha,
                'fitness': {'fuzzy_entropy': res.fitness[0],
                            'permutation_entropy': res.fitness[1]},
                'center_freqs_hz': (dec.center_freqs * rate_hz).tolist(),
                'classes': list(cls.classes),
                'sample_entropy': cls.sample_entropy.tolist(),
                'elman': elman.to_dict()}

    # -- applying --------------------------------------------------------------------------
    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return the denoised, drift-compensated angular rate (n, 3), rad/s."""
        if self.axes is None:
            raise ParameterError('ParallelModel.apply called before fit (or from_dict)')
        x_all, temp, rate = self._inputs(run)
        o = self.options
        out = np.empty_like(x_all)
        info, parts = [], []
        for a, ax in enumerate(self.axes):
            x = x_all[:, a]
            freqs = np.clip(np.asarray(ax['center_freqs_hz']) / run.rate_hz, 0.0, 0.5)
            dec = vmd(x, k=ax['k'], alpha=ax['alpha'], tol=o['vmd_tol'], solver='exact',
                      center_freqs=freqs, max_iter=int(o['apply_vmd_iter']),
                      workers=int(o['workers']))
            cls = self._classify(dec)
            mixed_in = dec.modes[cls.mask('mixed')].sum(axis=0)
            mixed = mixed_in
            if cls.mask('mixed').any():
                mixed = tfpf(mixed_in, window=int(o['tfpf_window']))
            drift = dec.modes[cls.mask('drift')].sum(axis=0)
            elman = DriftModel.from_dict(ax['elman'])
            out[:, a] = mixed + drift - self._drift_prediction(elman, run, temp, rate)
            info.append(self._axis_info(dec, cls, run.rate_hz))
            info[-1]['outside_trained_range_fraction'] = self._outside(elman, run, temp, rate)
            parts.append(self._plot_parts(run, a, dec, info[-1], mixed_in, mixed, drift, elman))
        self.last_info = info
        key: Callable[[], ThermalRun | None]
        try:
            key = weakref.ref(run)
        except TypeError:  # a run type without weak references: hold it until the next apply
            def key() -> ThermalRun:
                return run
        self._report_parts = (key, parts)
        return out

    def drift_prediction_rad_s(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return the Elman networks' drift (n, 3), rad/s, on a run's [T, dT]."""
        if self.axes is None:
            raise ParameterError('ParallelModel used before fit (or from_dict)')
        _, temp, rate = self._inputs(run)
        return np.column_stack([
            self._drift_prediction(DriftModel.from_dict(ax['elman']), run, temp, rate)
            for ax in self.axes])

    @staticmethod
    def _outside(elman: DriftModel, run: ThermalRun, temp: NDArray[np.float64],
                 rate: NDArray[np.float64]) -> float:
        """Fraction of the network's grid points outside the trained [T, dT] range."""
        q = max(1, int(round(elman.dt_s * run.rate_hz)))
        return float(np.mean(elman.outside(block_means(np.c_[temp, rate], q))))

    @staticmethod
    def _drift_prediction(elman: DriftModel, run: ThermalRun, temp: NDArray[np.float64],
                          rate: NDArray[np.float64]) -> NDArray[np.float64]:
        q = max(1, int(round(elman.dt_s * run.rate_hz)))
        pred = elman.predict(block_means(np.c_[temp, rate], q))
        centres = np.arange(pred.size) * q + 0.5 * (min(q, temp.size) - 1)
        return np.interp(np.arange(temp.size), centres, pred)

    # -- report ----------------------------------------------------------------------------
    def report_figures(self, run: ThermalRun, out_dir: StrPath) -> list[tuple[str | None, str]]:
        """
        Draw the paper's Figures 11, 12 and 14-17 for a run; return (file name, caption) each.

        The drawing is :func:`.parallel_figures.parallel_figures`; this is the
        method hook of ``ThermalMethod``. The run's decomposition comes from the last
        :meth:`apply` if it was called on this same run object, else ``apply(run)`` is run
        once (which also replaces :attr:`last_info`).

        Parameters
        ----------
        run : ThermalRun
            The run the figures describe.
        out_dir : pathlib.Path
            Existing directory the PNG files are written to.

        Returns
        -------
        list of (str or None, str)
            File name relative to ``out_dir`` (None: no figure) and a caption citing the paper
            figure it mirrors ('Fig. N').

        """
        if self.axes is None:
            raise ParameterError('ParallelModel used before fit (or from_dict)')
        return parallel_figures(self, run, self._parts_for(run), Path(out_dir))

    def _parts_for(self, run: ThermalRun) -> list[dict[str, Any]]:
        kept = self._report_parts
        if kept is None or kept[0]() is not run:
            self.apply(run)
        assert self._report_parts is not None  # set by apply
        return self._report_parts[1]

    def _plot_parts(self, run: ThermalRun, a: int, dec: VmdResult, info: Mapping[str, Any],
                    mixed_in: NDArray[np.float64], mixed_out: NDArray[np.float64],
                    drift: NDArray[np.float64], elman: DriftModel) -> dict[str, Any]:
        """Keep what the report figures need of one axis of an apply, at plot size."""
        def envelope(t: NDArray[Any], y: NDArray[Any]) -> tuple[NDArray[Any], NDArray[Any]]:
            return full_envelope(t, y, PANEL_POINTS)

        t_h = np.asarray(run.t_s, dtype=float) / 3600.0
        n = t_h.size
        span = min(n, 20 * int(self.options['tfpf_window']))
        zoom = slice((n - span) // 2, (n - span) // 2 + span)
        denoised = mixed_out + drift
        q = max(1, int(round(elman.dt_s * run.rate_hz)))
        return {'t_h': envelope(t_h, drift)[0],
                'input': envelope(t_h, np.asarray(run.gyro_rad_s)[:, a])[1],
                'modes': [envelope(t_h, m)[1] for m in dec.modes],
                'center_freqs_hz': list(info['center_freqs_hz']),
                'classes': list(info['classes']),
                'mixed_in': envelope(t_h, mixed_in)[1],
                'mixed_out': envelope(t_h, mixed_out)[1],
                'denoised': envelope(t_h, denoised)[1],
                'zoom': zoom, 'zoom_mixed_in': mixed_in[zoom].copy(),
                'zoom_mixed_out': mixed_out[zoom].copy(), 'zoom_denoised': denoised[zoom].copy(),
                'drift_blocks': block_means(drift, q), 'q': q}

    def network_grid(self, run: ThermalRun,
                     q: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """
        Return the drift model's inputs on a run's grid of ``q`` samples, and the grid's times.

        Parameters
        ----------
        run : ThermalRun
            The run.
        q : int
            Samples per grid point (the network's step).

        Returns
        -------
        inputs : numpy.ndarray
            (m, 2): block means of T (degC) and dT (degC/s).
        t_h : numpy.ndarray
            (m,) time of each grid point (h).

        """
        _, temp, rate = self._inputs(run)
        t = np.asarray(run.t_s, dtype=float)
        grid = block_means(np.c_[temp, rate], q)
        centres = np.arange(grid.shape[0]) * q + 0.5 * (min(q, t.size) - 1)
        return grid, np.interp(centres, np.arange(t.size), t) / 3600.0

    # -- helpers ---------------------------------------------------------------------------
    def _classify(self, dec: VmdResult) -> ModeClasses:
        o = self.options
        return classify_modes(dec.modes, dec.center_freqs, drift_max=o['drift_max'],
                              noise_min=o['noise_min'], max_samples=int(o['entropy_samples']),
                              scale=(None if o['entropy_scale'] is None
                                     else int(o['entropy_scale'])))

    @staticmethod
    def _axis_info(dec: VmdResult, cls: ModeClasses, rate_hz: float) -> dict[str, Any]:
        return {'center_freqs_hz': (dec.center_freqs * rate_hz).tolist(),
                'center_freqs_cyc_per_sample': dec.center_freqs.tolist(),
                'classes': list(cls.classes),
                'sample_entropy': cls.sample_entropy.tolist(),
                'entropy_scale': cls.scale,
                'mode_rms_rad_s': np.sqrt(np.mean(dec.modes ** 2, axis=1)).tolist(),
                'vmd_iterations': dec.iterations}

    def _inputs(self,
                run: ThermalRun) -> _Inputs:
        x = np.asarray(run.gyro_rad_s, dtype=float)
        temp = np.asarray(run.temperature_c, dtype=float)
        t = np.asarray(run.t_s, dtype=float)
        if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] != temp.size or t.size != temp.size:
            raise InputDataError(f'run arrays do not match: gyro {x.shape}, temperature '
                                 f'{temp.shape}, t {t.shape}')
        if x.shape[0] < 64:
            raise InputDataError(f'the parallel model needs at least 64 samples, got {x.shape[0]}')
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(temp))):
            raise InputDataError('the run contains NaN or Inf samples')
        rate = temperature_rate_c_s(t, temp, window_s=self.options['rate_window_s'])
        return x, temp, rate

    # -- serialisation ---------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Return every fitted parameter as a JSON-serialisable dict."""
        if self.axes is None:
            raise ParameterError('ParallelModel.to_dict called before fit')
        return {'method': 'parallel', 'causal': False, 'options': self.options,
                'rate_hz': self.rate_hz, 'temperature_range_c': self.temperature_range_c,
                'axes': self.axes}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'ParallelModel':
        """Rebuild a fitted model from :meth:`to_dict` output."""
        if d.get('method') != 'parallel':
            raise ParameterError(f"not a parallel model: method = {d.get('method')!r}")
        model = cls(**d.get('options', {}))
        model.axes = d['axes']
        model.rate_hz = d.get('rate_hz')
        model.temperature_range_c = d.get('temperature_range_c')
        return model
