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
Multi-objective particle swarm optimisation of the VMD parameters (paper 002, section 3.2).

The swarm searches (K, alpha) in [4, 12] x [1000, 10000] with the paper's settings (Np = NR = 40
particles and archive, M = 10 iterations, w = 0.4, c1 = c2 = 1.5) and minimises two fitness
values of the decomposition (our reading: the mean fuzzy entropy and the mean normalised
permutation entropy of its modes). K is rounded to an integer and alpha to 1 before evaluation,
and evaluations are cached by that key; the budget is at most Np x M decompositions.

* Velocity and position (step C3): ``v <- chi (w v + c1 R1 (pbest - x) + c2 R2 (gbest - x))``,
  ``x <- x + v``, clipped to the bounds (the clipped velocity component zeroed).
* Personal best: replaced when dominated, or with probability 1/2 when neither dominates.
* Archive (the "save set"): the non-dominated points so far on an ``n_grid`` x ``n_grid`` grid;
  the leader drawn with probability 1 / (points in its cell) (step C2); above NR points each
  cell with more than one point loses ``ND = Int((|A| - NR) / |A| * Grid[k] + 0.5)`` random
  points (eq. 23), then the most crowded cell until NR remain.
* The pick (the paper gives no rule): the archive point nearest the ideal point (0, 0) of the
  objectives normalised to [0, 1]; ties to the smaller K, then the smaller alpha.
* :func:`refine` (ours): re-evaluates the best points of a search made on a cheaper stand-in
  fitness with a reference fitness, polishes alpha by a compass search, and picks on it.

Everything random comes from one ``numpy.random.Generator`` (a deterministic function of the
seed). Fitness functions are plain picklable callables evaluated through ``map_fn`` (``map`` by
default; a process pool's distributes them). Detail: docs/thermal_model.md (MOPSO section).
"""

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.entropy import fuzzy_entropy, permutation_entropy
from gyro_noise_ros.thermal.vmd import vmd
import numpy as np
from numpy.typing import ArrayLike, NDArray

#: The paper's search box: K in [4, 12], alpha in [1000, 10000].
PAPER_BOUNDS = ((4.0, 12.0), (1000.0, 10000.0))

# A fitness: (k, alpha) -> (f1, f2); the map-like function that evaluates it over points;
# the search box ((k_min, k_max), (alpha_min, alpha_max)).
Fitness = Callable[[tuple[int, float]], Iterable[float]]
MapFn = Callable[..., Iterable[Any]]
Bounds = Sequence[Sequence[float]]


@dataclass(frozen=True)
class VmdFitness:
    """
    The two fitness values of a VMD of a signal; a pure, picklable callable.

    Calling it with ``(k, alpha)`` decomposes ``signal`` and returns
    ``(mean fuzzy entropy, mean normalised permutation entropy)`` of the modes. A 2-D
    ``signal`` (w, n) holds w windows of one record: each is decomposed and the means run over
    all their modes.
    """

    signal: np.ndarray
    fe_m: int = 2
    fe_r: float = 0.2
    pe_order: int = 4
    pe_delay: int = 1
    tol: float = 1e-7
    max_iter: int = 500

    def __call__(self, key: tuple[int, float]) -> tuple[float, float]:
        """Return (FE, PE) for ``key = (k, alpha)``."""
        k, alpha = key
        modes = np.concatenate([
            vmd(seg, k=int(k), alpha=float(alpha), tol=self.tol, max_iter=self.max_iter).modes
            for seg in np.atleast_2d(self.signal)])
        fe = np.mean([fuzzy_entropy(m, m=self.fe_m, r=self.fe_r) for m in modes])
        pe = np.mean([permutation_entropy(m, order=self.pe_order, delay=self.pe_delay)
                      for m in modes])
        return float(fe), float(pe)


@dataclass(frozen=True)
class MopsoResult:
    """
    Outcome of :func:`mopso`.

    Attributes
    ----------
    k : int
        Chosen number of modes.
    alpha : float
        Chosen bandwidth penalty.
    fitness : tuple
        (FE, PE) of the chosen point.
    archive_params : numpy.ndarray
        Pareto archive (n, 2): K, alpha.
    archive_fitness : numpy.ndarray
        Their fitness (n, 2).
    evaluations : int
        Distinct (K, alpha) decomposed.
    requested : int
        Fitness requests (particles times iterations); the rest were cache hits.
    history : list
        Per iteration, the positions (Np, 2) and fitness (Np, 2) evaluated (paper Figure 11).
    reference_evaluations : int
        Points re-evaluated with the reference fitness by :func:`refine` (0 without it).
    search_pick : tuple or None
        After :func:`refine`, the (K, alpha) the search fitness alone would have picked.

    """

    k: int
    alpha: float
    fitness: tuple
    archive_params: np.ndarray
    archive_fitness: np.ndarray
    evaluations: int
    requested: int
    history: list = field(repr=False, default_factory=list)
    reference_evaluations: int = 0
    search_pick: tuple | None = None


def dominates(a: ArrayLike, b: ArrayLike, *, margin: float = 0.0) -> bool:
    """
    Return True when fitness ``a`` Pareto-dominates ``b`` (minimisation).

    With ``margin > 0``, ``a`` must also be better than ``b`` by more than that fraction of
    ``|b|`` in at least one objective (differences below the fitness's resolution ignored).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.all(a <= b) and np.any(a < b - margin * np.abs(b)))


def _key(p: Sequence[float] | NDArray[np.float64]) -> tuple[int, float]:
    """Return the cache key of a position: K rounded to an integer, alpha to 1."""
    return int(round(p[0])), float(round(p[1]))


def _cells(fit: NDArray[np.float64], n_grid: int) -> NDArray[np.int_]:
    lo = fit.min(axis=0)
    hi = fit.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    idx = np.floor((fit - lo) / span * n_grid).astype(int)
    idx = np.clip(idx, 0, n_grid - 1)
    return idx[:, 0] * n_grid + idx[:, 1]


def _non_dominated(params: NDArray[np.float64],
                   fit: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    keep: list[int] = []
    for i in range(len(fit)):
        if not any(dominates(fit[j], fit[i]) for j in range(len(fit)) if j != i):
            # Drop exact duplicates of a point already kept.
            if not any(np.array_equal(params[i], params[j]) for j in keep):
                keep.append(i)
    return params[keep], fit[keep]


def _truncate(params: NDArray[np.float64], fit: NDArray[np.float64], size: int, n_grid: int,
              gen: np.random.Generator) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Shrink the archive to ``size`` by eq. 23, then from the most crowded cell."""
    if len(fit) <= size:
        return params, fit
    cells = _cells(fit, n_grid)
    n_a = len(fit)
    drop: list[Any] = []
    for c in np.unique(cells):
        members = np.flatnonzero(cells == c)
        if members.size > 1:
            nd = int((n_a - size) / n_a * members.size + 0.5)
            if nd:
                drop.extend(gen.choice(members, size=min(nd, members.size - 1),
                                       replace=False))
    keep = np.setdiff1d(np.arange(n_a), drop)
    params, fit = params[keep], fit[keep]
    while len(fit) > size:
        cells = _cells(fit, n_grid)
        vals, counts = np.unique(cells, return_counts=True)
        members = np.flatnonzero(cells == vals[np.argmax(counts)])
        victim = gen.choice(members)
        keep = np.arange(len(fit)) != victim
        params, fit = params[keep], fit[keep]
    return params, fit


def _leader(params: NDArray[np.float64], fit: NDArray[np.float64], n_grid: int,
            gen: np.random.Generator) -> NDArray[np.float64]:
    cells = _cells(fit, n_grid)
    _, inverse, counts = np.unique(cells, return_inverse=True, return_counts=True)
    weight = 1.0 / counts[inverse]
    return params[gen.choice(len(fit), p=weight / weight.sum())]


def pick_compromise(params: NDArray[np.float64], fit: ArrayLike) -> int:
    """
    Pick one point of a Pareto set: nearest to the ideal point after min-max normalisation.

    Ties go to the smaller K, then the smaller alpha. Returns the index into ``params``.
    """
    fit = np.asarray(fit, dtype=float)
    lo, hi = fit.min(axis=0), fit.max(axis=0)
    norm = (fit - lo) / np.where(hi > lo, hi - lo, 1.0)
    dist = np.round(np.hypot(norm[:, 0], norm[:, 1]), 12)
    order = np.lexsort((params[:, 1], params[:, 0], dist))
    return int(order[0])


def mopso(fitness: Fitness, *, rng: np.random.Generator, bounds: Bounds = PAPER_BOUNDS,
          n_particles: int = 40, archive_size: int = 40, iterations: int = 10, w: float = 0.4,
          c1: float = 1.5, c2: float = 1.5, chi: float = 1.0, n_grid: int = 7,
          map_fn: MapFn = map) -> MopsoResult:
    """
    Search (K, alpha) minimising two fitness values with a multi-objective particle swarm.

    Parameters
    ----------
    fitness : callable
        ``fitness((k, alpha)) -> (f1, f2)`` with integer k and integer-valued alpha; pure and
        picklable to be distributed (e.g. :class:`VmdFitness`).
    rng : numpy.random.Generator, keyword-only
        The only source of randomness.
    bounds : tuple, keyword-only
        ((k_min, k_max), (alpha_min, alpha_max)).
    n_particles, archive_size, iterations : int, keyword-only
        Np, NR and M of the paper (40, 40, 10).
    w, c1, c2, chi : float, keyword-only
        Inertia weight, learning factors and contraction factor of the velocity update.
    n_grid : int, keyword-only
        Grid divisions per objective for the archive's density.
    map_fn : callable, keyword-only
        ``map``-like function used to evaluate the uncached points of one iteration in order.

    Returns
    -------
    MopsoResult
        The picked point, the archive, evaluation counts and the per-iteration history.

    """
    lo = np.array([b[0] for b in bounds], dtype=float)
    hi = np.array([b[1] for b in bounds], dtype=float)
    if lo.shape != (2,) or np.any(hi < lo):
        raise ParameterError(f'bounds must be ((k_min, k_max), (a_min, a_max)), got {bounds!r}')
    if lo[0] < 1 or lo[1] <= 0:
        raise ParameterError('bounds: K must be >= 1 and alpha > 0')
    if min(n_particles, archive_size, iterations, n_grid) < 1:
        raise ParameterError('n_particles, archive_size, iterations and n_grid must be >= 1')
    gen = rng
    cache = {}
    requested = 0

    def evaluate(pos: NDArray[np.float64]) -> NDArray[np.float64]:
        nonlocal requested
        keys = [_key(p) for p in pos]
        requested += len(keys)
        todo = list(dict.fromkeys(k for k in keys if k not in cache))
        for k, f in zip(todo, map_fn(fitness, todo)):
            cache[k] = tuple(float(v) for v in f)
        return np.array([cache[k] for k in keys])

    pos = lo + (hi - lo) * gen.random((n_particles, 2))
    vel = np.zeros_like(pos)
    fit = evaluate(pos)
    history = [(pos.copy(), fit.copy())]
    pbest, pbest_fit = pos.copy(), fit.copy()
    arch_p, arch_f = _non_dominated(np.array([_key(p) for p in pos], dtype=float), fit)
    arch_p, arch_f = _truncate(arch_p, arch_f, archive_size, n_grid, gen)
    for _ in range(iterations - 1):
        leaders = np.array([_leader(arch_p, arch_f, n_grid, gen) for _ in range(n_particles)])
        r1 = gen.random((n_particles, 2))
        r2 = gen.random((n_particles, 2))
        vel = chi * (w * vel + c1 * r1 * (pbest - pos) + c2 * r2 * (leaders - pos))
        pos = pos + vel
        out = (pos < lo) | (pos > hi)
        pos = np.clip(pos, lo, hi)
        vel[out] = 0.0
        fit = evaluate(pos)
        history.append((pos.copy(), fit.copy()))
        coin = gen.random(n_particles)
        for i in range(n_particles):
            if dominates(fit[i], pbest_fit[i]) or (
                    not dominates(pbest_fit[i], fit[i]) and coin[i] < 0.5):
                pbest[i], pbest_fit[i] = pos[i], fit[i]
        cand_p = np.vstack([arch_p, [_key(p) for p in pos]])
        cand_f = np.vstack([arch_f, fit])
        arch_p, arch_f = _non_dominated(cand_p, cand_f)
        arch_p, arch_f = _truncate(arch_p, arch_f, archive_size, n_grid, gen)
    best = pick_compromise(arch_p, arch_f)
    return MopsoResult(k=int(arch_p[best, 0]), alpha=float(arch_p[best, 1]),
                       fitness=tuple(arch_f[best]), archive_params=arch_p,
                       archive_fitness=arch_f, evaluations=len(cache), requested=requested,
                       history=history)


def pareto_ranks(fit: ArrayLike) -> NDArray[np.int_]:
    """
    Return the non-dominated sorting rank of each point (0 for the first front).

    Rank r holds the points dominated only by points of ranks below r (minimisation).
    """
    fit = np.asarray(fit, dtype=float).reshape(-1, 2)
    n = len(fit)
    # dom[i, j]: point i dominates point j.
    le = np.all(fit[:, None, :] <= fit[None, :, :], axis=2)
    lt = np.any(fit[:, None, :] < fit[None, :, :], axis=2)
    dom = le & lt
    ranks = np.full(n, -1)
    left = np.ones(n, dtype=bool)
    r = 0
    while left.any():
        front = left & ~dom[left].any(axis=0)
        ranks[front] = r
        left &= ~front
        r += 1
    return ranks


def evaluated_points(result: MopsoResult) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the distinct (K, alpha) keys a search evaluated and their fitness, (m, 2) each."""
    seen: dict[tuple[int, float], tuple[float, ...]] = {}
    for pos, fit in result.history:
        for p, f in zip(pos, fit):
            seen.setdefault(_key(p), tuple(float(v) for v in f))
    keys = np.array(list(seen), dtype=float).reshape(-1, 2)
    return keys, np.array(list(seen.values()), dtype=float).reshape(-1, 2)


def refine(result: MopsoResult, fitness: Fitness, *, points: int = 10, polish: int = 16,
           bounds: Bounds = PAPER_BOUNDS, map_fn: MapFn = map) -> MopsoResult:
    """
    Re-evaluate a search's most promising points with a reference fitness and pick again.

    1. Screening: the candidates are the distinct (K, alpha) the search evaluated, ordered by
       their Pareto rank under the search's fitness (:func:`pareto_ranks`), then by the
       compromise distance of :func:`pick_compromise` within their rank, then by K and alpha;
       each K's first candidate comes first (the search fitness may misrank K, the structural
       parameter), then the others in that order. The first ``points`` are evaluated with
       ``fitness``.
    2. Polish: a compass search around the current pick (K, alpha): (K, alpha - s) and
       (K, alpha + s), in the first round also (K - 1, alpha) and (K + 1, alpha) (rounded,
       inside ``bounds``, not yet evaluated), are evaluated and the pick is taken again over
       the non-dominated set of every reference evaluation; the alpha step s starts at a
       quarter of the alpha range and halves whenever the pick does not move, until
       ``polish`` evaluations are spent or s < 1.

    The archive returned is the non-dominated set of all reference evaluations and the pick
    follows :func:`pick_compromise` on the reference fitness. Deterministic (no randomness).

    Parameters
    ----------
    result : MopsoResult
        Outcome of :func:`mopso` (its ``history`` is used).
    fitness : callable
        The reference fitness, ``fitness((k, alpha)) -> (f1, f2)``, pure and picklable.
    points : int, keyword-only
        Screening evaluations (>= 1).
    polish : int, keyword-only
        Polish evaluations (>= 0).
    bounds : tuple, keyword-only
        ((k_min, k_max), (alpha_min, alpha_max)) of the search.
    map_fn : callable, keyword-only
        ``map``-like function for the evaluations (in order).

    Returns
    -------
    MopsoResult
        The new pick, archive and fitness (reference), ``reference_evaluations`` and
        ``search_pick`` set; counts and history of the search kept.

    """
    if int(points) < 1 or int(polish) < 0:
        raise ParameterError(f'points must be >= 1 and polish >= 0, got {points!r}, '
                             f'{polish!r}')
    k_lo, k_hi = int(round(bounds[0][0])), int(round(bounds[0][1]))
    a_lo, a_hi = float(bounds[1][0]), float(bounds[1][1])
    keys, fit = evaluated_points(result)
    ranks = pareto_ranks(fit)
    dist = np.empty(len(fit))
    for r in np.unique(ranks):
        members = ranks == r
        f = fit[members]
        lo, hi = f.min(axis=0), f.max(axis=0)
        norm = (f - lo) / np.where(hi > lo, hi - lo, 1.0)
        dist[members] = np.round(np.hypot(norm[:, 0], norm[:, 1]), 12)
    order = np.lexsort((keys[:, 1], keys[:, 0], dist, ranks))
    first = np.zeros(len(order), dtype=bool)
    first[np.unique(keys[order, 0], return_index=True)[1]] = True
    order = np.concatenate([order[first], order[~first]])[:int(points)]
    done = {}

    def evaluate(todo: Sequence[tuple[int, float]]) -> None:
        for key, f in zip(todo, map_fn(fitness, todo)):
            done[key] = tuple(float(v) for v in f)

    def pick() -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
        p, f = _non_dominated(np.array(list(done), dtype=float),
                              np.array(list(done.values()), dtype=float))
        return p, f, pick_compromise(p, f)

    evaluate([_key(p) for p in keys[order]])
    arch_p, arch_f, best = pick()
    step = (a_hi - a_lo) / 4.0
    spent = 0
    while spent < int(polish) and step >= 1.0:
        k, a = int(arch_p[best, 0]), float(arch_p[best, 1])
        probes = [(k, float(round(min(max(v, a_lo), a_hi)))) for v in (a - step, a + step)]
        if not spent:
            probes += [(j, a) for j in (k - 1, k + 1) if k_lo <= j <= k_hi]
        probes = [q for q in dict.fromkeys(probes) if q not in done][:int(polish) - spent]
        if probes:
            evaluate(probes)
            spent += len(probes)
            arch_p, arch_f, best = pick()
        if not probes or _key(arch_p[best]) == (k, a):
            step /= 2.0
    return MopsoResult(k=int(arch_p[best, 0]), alpha=float(arch_p[best, 1]),
                       fitness=tuple(arch_f[best]), archive_params=arch_p,
                       archive_fitness=arch_f, evaluations=result.evaluations,
                       requested=result.requested, history=result.history,
                       reference_evaluations=len(done),
                       search_pick=(result.k, result.alpha))
