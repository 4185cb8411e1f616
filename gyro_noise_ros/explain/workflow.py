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
The discrepancy workflow: name the effects that bring a measurement inside its model's band.

:func:`explain` fits the baseline (:mod:`.baseline`), simulates an ensemble of it and compares the
measurement with it on every signature (:mod:`.signatures`). While the part of the gap G that an
added effect could explain (:func:`unexplained_gap`) exceeds :data:`INSIDE_GAP`, every catalogue
effect (:mod:`.effects`) not yet in the model is fitted and tried, and :func:`choose` picks one:
only candidates that shrink G by at least INSIDE_GAP (:func:`accepts`) compete, the smallest
:func:`criterion` wins (a stochastic pick is checked two steps ahead, :func:`_look_ahead`); when
none passes, the loop stops. After a deterministic effect or the lattice the baseline is refitted
(kept if it does not widen the gap). A parametric bootstrap of the final model then gives every
parameter a standard error (:mod:`.uncertainty`).

The result is an :class:`ExplainResult` (``to_dict()`` is the explain.json layout): the steps,
the gaps, ``unexplained``, ``quieter`` (where the measurement is quieter than the model: the
baseline over-estimates the noise, :func:`quieter`) and ``stopped_at_limit``. It is reproducible
for a seed: member j draws from ``numpy.random.default_rng([seed, j, 0])`` and an effect's
stochastic term from ``[seed, j, 1 + catalogue index]`` (common random numbers: two candidate
models differ only by their effect). Rules, reasons and measurements: docs/discrepancy.md.
"""

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
import itertools
import time
from typing import Any

import numpy as np

from . import signatures as sig
from .baseline import BaselineModel, fit_baseline, without_white
from .effects import CATALOGUE, Context, Effect, Params, public_params, Quantization
from .inputs import Measurement
from .signatures import Comparison, FloatArray, Layout, Signatures
from .uncertainty import bootstrap as bootstrap_uncertainty, FinalModel, time_scale_check
from ..errors import ParameterError

#: Passing deterministic candidates a stochastic pick is checked against, two steps ahead
#: (:func:`_look_ahead`): the best by :func:`criterion`.
LOOK_AHEAD = 2
#: How much smaller the two-step criterion must be: a transient fitted to a random walk's own
#: realisation gains 0.4-1.3 on single random-walk records, a ramp or transient hidden with a
#: Gauss-Markov bias 4.9-6.6 (docs/discrepancy.md section 5).
LOOK_AHEAD_MARGIN = 3.0
#: Penalty per parameter of :func:`criterion` (in units of the mean log score): a one-parameter
#: ramp beats a three-parameter transient that mimics it equally well.
PARAM_PENALTY = 0.25
#: The measurement counts as inside the band when G <= INSIDE_GAP (its worst points lie at most ~10
#: % of a band half-width beyond the edge on one signature), and an effect must shrink G by at
#: least this much to be accepted: smaller changes are within the run-to-run scatter of the band
#: edges.
INSIDE_GAP = 0.1
#: Records simulated from the final model for the parameter uncertainties: the standard error is
#: itself uncertain by about 1 / sqrt(2 (B - 1)) = 16 % at B = 20, which Student's t in the
#: interval accounts for; each record costs about one ensemble member.
DEFAULT_BOOTSTRAP = 20
#: Signatures of the noise level: a measurement below their band is quieter than the model.
LEVEL_SIGNATURES = ('allan', 'psd', 'chunk_variance')

#: One candidate tried in a step: (gap, effect, params, deterministic term or None, the members'
#: signatures, the comparisons).
Trial = tuple[float, Effect, Params, FloatArray | None, list[Signatures], dict[str, Comparison]]


@dataclass(frozen=True)
class Step:
    """
    One accepted effect.

    Attributes
    ----------
    effect : str
    params : dict
        Fitted parameters (SI; names in :mod:`.effects`).
    gap_before, gap_after : float
        Scalar gap G before and after adding the effect.
    where : list of str
        Where the measurement left the band before the step.
    where_after : list of str
        Where it still leaves the band after it.
    candidates : dict
        Every candidate tried in this step -> its gap (the chosen one included).
    scores : dict
        Every candidate -> its :func:`criterion` (smaller is better; it ranks the passing
        candidates).
    time_scales : dict
        Parameter -> :func:`.uncertainty.time_scale_check` of its value, for the parameters with
        a time scale: the range the record resolves and whether the value lies inside it.
    before, after : dict
        Signature comparisons before and after (for figures; not serialised).

    """

    effect: str
    params: Params
    gap_before: float
    gap_after: float
    where: list[str]
    where_after: list[str]
    candidates: dict[str, float]
    time_scales: dict[str, dict[str, Any]] = field(default_factory=dict)
    before: dict[str, Comparison] | None = field(repr=False, default=None)
    after: dict[str, Comparison] | None = field(repr=False, default=None)
    scores: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class ExplainResult:
    """
    Outcome of :func:`explain`.

    Attributes
    ----------
    measurement : Measurement
    layout : Layout
    baseline : BaselineModel
        The baseline fitted to the measurement.
    final_baseline : BaselineModel
        The baseline of the final model: refitted to the residual after deterministic effects.
    steps : list of Step
    gap_initial, gap_final : float
    unexplained : bool
        True when the part of the final gap an effect could explain (:func:`unexplained_gap`)
        is above :data:`INSIDE_GAP`.
    where_final : list of str
    comparisons_initial, comparisons_final : dict
        Signature comparisons of the baseline and of the final model.
    tried_last : dict
        Candidates of the final, rejected round (name -> gap), empty if none was tried.
    ensemble : int
    seed : int
    seconds : dict
        Wall time of the phases (s).
    uncertainty : dict
        effect name -> parameter -> {value, stderr, ci95, unit, method, resolved, note}
        (:mod:`.uncertainty`); empty when the bootstrap is off or nothing was named.
    bootstrap : int
        Replicates of the bootstrap (0: off).
    gap_unexplained : float
        :func:`unexplained_gap` of the final model.
    quieter : list of str
        Where the measurement is quieter than the final model (:func:`quieter`): the baseline
        over-estimates the noise there; no effect is missing.
    stopped_at_limit : bool
        The loop stopped at ``max_steps`` with a gap still to explain.

    """

    measurement: Measurement
    layout: Layout
    baseline: BaselineModel
    final_baseline: BaselineModel
    steps: list[Step]
    gap_initial: float
    gap_final: float
    unexplained: bool
    where_final: list[str]
    comparisons_initial: dict[str, Comparison]
    comparisons_final: dict[str, Comparison]
    tried_last: dict[str, float]
    ensemble: int
    seed: int
    seconds: dict[str, float]
    uncertainty: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    bootstrap: int = 0
    gap_unexplained: float = 0.0
    quieter: list[str] = field(default_factory=list)
    stopped_at_limit: bool = False

    @property
    def named(self) -> list[str]:
        """Names of the accepted effects, in order."""
        return [s.effect for s in self.steps]

    def to_dict(self) -> dict[str, Any]:
        """Return the explain.json layout (see docs/discrepancy.md)."""
        meas = self.measurement
        return {
            'input': {
                'source': meas.source,
                'axis': meas.axis,
                'samples': meas.n,
                'rate_hz': meas.rate_hz,
                'duration_s': meas.duration_s,
                'temperature': meas.temperature_c is not None,
                'timebase': (
                    meas.timebase.as_dict()
                    if meas.timebase is not None
                    else None
                ),
            },
            'ensemble': self.ensemble,
            'seed': self.seed,
            'bootstrap': {
                'replicates': self.bootstrap,
                'seed': self.seed,
                'method': 'parametric bootstrap of the final model (docs/discrepancy.md)',
            },
            'baseline': self.baseline.to_dict(),
            'baseline_final': self.final_baseline.to_dict(),
            'steps': [
                {
                    'effect': s.effect,
                    'params': public_params(s.params),
                    'uncertainty': self.uncertainty.get(s.effect, {}),
                    'gap_before': s.gap_before,
                    'gap_after': s.gap_after,
                    'where': s.where,
                    'where_after': s.where_after,
                    'candidates': s.candidates,
                    'candidate_scores': s.scores,
                    'time_scales': s.time_scales,
                }
                for s in self.steps
            ],
            'gap_initial': self.gap_initial,
            'gap_final': self.gap_final,
            'gap_unexplained': self.gap_unexplained,
            'unexplained': self.unexplained,
            'baseline_over_estimates': self.quieter,
            'stopped_at_step_limit': self.stopped_at_limit,
            'where_final': self.where_final,
            'rejected_candidates': self.tried_last,
            'signatures_final': {
                name: {'g': c.g, 'threshold_z': c.threshold}
                for name, c in self.comparisons_final.items()
            },
            'seconds': self.seconds,
        }


class _Model:
    """
    The ensemble of the current model.

    Members with the accepted additive terms already added.
    """

    def __init__(self, meas: Measurement, layout: Layout, baseline: BaselineModel, ensemble: int,
                 seed: int, mapper: Callable[..., Iterable[Any]] = map) -> None:
        self.meas, self.layout, self.seed, self.mapper = meas, layout, seed, mapper
        self.members = [baseline.generator(np.random.default_rng([seed, j, 0])).generate(meas.n)
                        for j in range(ensemble)]
        self.quantization: Params | None = None
        self.stamp_effect: tuple[Effect, Params] | None = None
        self.accepted: dict[str, Params] = {}
        self.stochastic: list[tuple[Effect, Params]] = []

    def rng(self, member: int, effect: Effect) -> np.random.Generator:
        return np.random.default_rng([self.seed, member, 1 + CATALOGUE.index(effect)])

    def _series(self, j: int, trial: tuple[Effect, Params, FloatArray | None] | None,
                ctx: Context | None) -> tuple[FloatArray, FloatArray | None]:
        meas = self.meas
        x = self.members[j]
        quant, stamp_effect = self.quantization, self.stamp_effect
        if trial is not None:
            effect, params, det = trial
            if effect.kind == 'additive':
                x = x + det
            elif effect.kind == 'stochastic':
                assert ctx is not None  # a trial comes with the context it was fitted in
                x = x + effect.term(params, meas.n, meas.rate_hz, self.rng(j, effect), ctx)
            elif effect.kind == 'quantization':
                quant = params
            else:
                stamp_effect = (effect, params)
        if quant is not None:
            x = Quantization.apply(quant, x)
        if stamp_effect is None:
            t = None
        else:
            effect, params = stamp_effect
            assert ctx is not None  # only the first call, before any effect, has no context
            t = effect.stamps(params, meas.n, meas.rate_hz, self.rng(j, effect), ctx)
        return x, t

    def signatures(self, trial: tuple[Effect, Params, FloatArray | None] | None = None,
                   ctx: Context | None = None) -> list[Signatures]:
        # One pure work unit per member, in member order (mapper: local or a Dask cluster's).
        series = (self._series(j, trial, ctx) for j in range(len(self.members)))
        return list(self.mapper(member_signatures, itertools.repeat(self.layout), series,
                                itertools.repeat(self.meas.temperature_c)))

    def rebase(self, baseline: BaselineModel, det_sum: FloatArray, ctx: Context) -> None:
        """Regenerate the members from a refitted baseline, keeping the accepted additive terms."""
        meas = self.meas
        for j in range(len(self.members)):
            x = baseline.generator(np.random.default_rng([self.seed, j, 0])).generate(meas.n)
            x += det_sum
            for effect, params in self.stochastic:
                x += effect.term(params, meas.n, meas.rate_hz, self.rng(j, effect), ctx)
            self.members[j] = x

    def with_additive(self, effect: Effect, params: Params, det: FloatArray) -> '_Model':
        """Return a copy of this model with a deterministic term accepted (for a look ahead)."""
        other = object.__new__(_Model)
        other.__dict__.update(self.__dict__)
        other.members = [x + det for x in self.members]
        other.accepted = {**self.accepted, effect.name: params}
        other.stochastic = list(self.stochastic)
        return other

    def accept(self, effect: Effect, params: Params, det: FloatArray | None,
               ctx: Context) -> None:
        meas = self.meas
        if effect.kind == 'additive':
            for x in self.members:
                x += det
        elif effect.kind == 'stochastic':
            self.stochastic.append((effect, params))
            for j, x in enumerate(self.members):
                x += effect.term(params, meas.n, meas.rate_hz, self.rng(j, effect), ctx)
        elif effect.kind == 'quantization':
            self.quantization = params
        else:
            self.stamp_effect = (effect, params)
        self.accepted[effect.name] = params


def member_signatures(layout: Layout, series: tuple[FloatArray, FloatArray | None],
                      temperature_c: FloatArray | None) -> Signatures:
    """
    Evaluate one ensemble member's signatures (the pure work unit shipped to ``mapper``).

    Parameters
    ----------
    layout : Layout
        Where the signatures are evaluated.
    series : tuple
        ``(x, t)``: the member's rate (rad/s) and stamps (s) or None.
    temperature_c : numpy.ndarray or None
        The measurement's temperature (degC), shared by every member.

    Returns
    -------
    dict
        :func:`.signatures.compute` of the member.

    """
    x, t = series
    return sig.compute(layout, x, t, temperature_c)


def time_scales(effect_name: str, params: Mapping[str, Any], meas: Measurement,
                layout: Layout) -> dict[str, dict[str, Any]]:
    """
    Check every parameter of an effect that has a time scale against what the record resolves.

    Parameters
    ----------
    effect_name : str
        The effect.
    params : dict
        Its fitted parameters.
    meas : Measurement
        The record.
    layout : Layout
        Its signature layout.

    Returns
    -------
    dict
        Parameter -> :func:`.uncertainty.time_scale_check` of the value (parameters without a
        time scale left out).

    """
    public = public_params(params)
    out = {}
    for name in public:
        check = time_scale_check(effect_name, name, public, n=meas.n, rate_hz=meas.rate_hz,
                                 layout=layout)
        if check is not None:
            out[name] = check
    return out


def _changed(new: BaselineModel, old: BaselineModel) -> bool:
    """Tell whether a refitted baseline differs materially (order, f, or a level by over 2 %)."""
    level = np.hypot(new.sigma_w_rad_s, new.sigma_nu_rad_s) / max(
        np.hypot(old.sigma_w_rad_s, old.sigma_nu_rad_s), 1e-300)
    return (new.alpha != old.alpha or abs(new.f - old.f) > 1e-3 or abs(level - 1) > 0.02
            or new.memory_sim != old.memory_sim)


def compare_all(layout: Layout, meas_sig: Signatures,
                member_sig: Sequence[Signatures]) -> dict[str, Comparison]:
    """Compare every signature; returns name -> Comparison."""
    return {name: sig.compare(name, meas_sig[name], np.array([s[name] for s in member_sig]))
            for name in meas_sig}


def where_outside(layout: Layout, comparisons: Mapping[str, Comparison]) -> list[str]:
    """Texts naming where the measurement leaves each band, worst signature first."""
    worst = sorted(comparisons.values(), key=lambda c: -c.g)
    return [sig.describe_where(layout, c) for c in worst if c.outside.any()]


def quieter(comparison: Comparison) -> bool:
    """
    Tell whether a signature shows the baseline over-estimating: left, and only ever below.

    Only the noise-level signatures (:data:`LEVEL_SIGNATURES`) qualify: every point outside their
    band lies below it, i.e. the measurement is quieter than the model there. No catalogue effect
    can remove noise, so such a departure is the baseline's, not a missing effect's.

    Parameters
    ----------
    comparison : Comparison
        One signature's comparison.

    Returns
    -------
    bool

    """
    out = comparison.outside
    return bool(comparison.name in LEVEL_SIGNATURES and out.any()
                and np.all(comparison.z[out] < 0))


def unexplained_gap(comparisons: Mapping[str, Comparison]) -> float:
    """
    Return the part of the gap G that an added effect could explain: G without :func:`quieter`.

    ``comparisons`` maps each signature's name to its Comparison under one model; the result is the
    sum of ln(max(g_s, 1)) over the signatures that are not :func:`quieter`.

    """
    return float(sum(c.gap for c in comparisons.values() if not quieter(c)))


def where_quieter(layout: Layout, comparisons: Mapping[str, Comparison]) -> list[str]:
    """Texts naming where the measurement is quieter than the model (:func:`quieter`)."""
    worst = sorted(comparisons.values(), key=lambda c: -c.g)
    return [sig.describe_where(layout, c) for c in worst if quieter(c)]


def explain(meas: Measurement, *, seed: int = 0, ensemble: int = 16, max_steps: int = 6,
            effects: Sequence[Effect] = CATALOGUE, progress: Callable[[str], None] | None = None,
            bootstrap: int = DEFAULT_BOOTSTRAP,
            mapper: Callable[..., Iterable[Any]] = map) -> ExplainResult:
    """
    Run the discrepancy workflow on one measured axis (module doc).

    Parameters
    ----------
    meas : Measurement
        See :mod:`.inputs`.
    seed : int, keyword-only
        Seed of the ensemble (results are reproducible for a given seed).
    ensemble : int, keyword-only
        Members per ensemble (>= 4).
    max_steps : int, keyword-only
        Most effects to add (>= 0).
    effects : sequence of Effect, keyword-only
        Candidates (default: the whole catalogue).
    progress : callable, optional
        Called with one-line status texts.
    bootstrap : int, keyword-only
        Records simulated from the final model for the parameter uncertainties (0: none, else
        >= 5).
    mapper : callable, keyword-only
        ``mapper(func, *iterables)`` like the builtin ``map`` (results in order), over which the
        ensemble members' signatures (:func:`member_signatures`) and the bootstrap records (the
        pure, picklable :func:`.uncertainty.replicate`) are computed; e.g. the ``map`` of
        :func:`gyro_noise_ros.cluster.make_executor`'s executor. The result does not depend on it.

    Returns
    -------
    ExplainResult

    """
    ensemble, max_steps, seed, bootstrap = _checked(ensemble, max_steps, seed, bootstrap)
    say = progress or (lambda text: None)
    seconds = {}
    t0 = time.perf_counter()
    layout = sig.make_layout(meas.rate, meas.rate_hz, temperature=meas.temperature_c is not None)
    meas_sig = sig.compute(layout, meas.rate, meas.t_s, meas.temperature_c)
    baseline = first_baseline = fit_baseline(meas.rate, meas.rate_hz)
    seconds['fit_baseline'] = time.perf_counter() - t0
    say(f'baseline: alpha={baseline.alpha:.2f} f={baseline.f:.3f} '
        f'sigma_w={baseline.sigma_w_rad_s:.3g} rad/s '
        f'sigma_nu={baseline.sigma_nu_rad_s:.3g} rad/s (L_sim={baseline.memory_sim})')
    t1 = time.perf_counter()
    model = _Model(meas, layout, baseline, ensemble, seed, mapper)
    seconds['simulate_baseline'] = time.perf_counter() - t1
    t2 = time.perf_counter()
    member_sig = model.signatures()
    comparisons = compare_all(layout, meas_sig, member_sig)
    state = _State(baseline=baseline, member_sig=member_sig, comparisons=comparisons,
                   residual=meas.rate.copy())
    say(f'gap {state.gap:.3f}')
    _iterate(state, model, meas_sig, effects, max_steps, say)
    seconds['iterate'] = time.perf_counter() - t2
    uncertainty = {}
    steps = state.steps
    if bootstrap and steps:
        t3 = time.perf_counter()
        final = _final_model(meas, layout, state.baseline, steps, effects, state.det_terms, seed)
        uncertainty = bootstrap_uncertainty(final, bootstrap, values=meas.rate, mapper=mapper)
        seconds['bootstrap'] = time.perf_counter() - t3
        say(f'uncertainties: parametric bootstrap of the final model, {bootstrap} records')
    seconds['total'] = time.perf_counter() - t0
    final_cmp = state.comparisons
    return ExplainResult(measurement=meas, layout=layout, baseline=first_baseline,
                         final_baseline=state.baseline, steps=steps,
                         gap_initial=sig.total_gap(comparisons), gap_final=state.gap,
                         unexplained=unexplained_gap(final_cmp) > INSIDE_GAP,
                         where_final=where_outside(layout, final_cmp),
                         comparisons_initial=comparisons, comparisons_final=final_cmp,
                         tried_last=state.tried_last, ensemble=ensemble, seed=seed,
                         seconds=seconds, uncertainty=uncertainty,
                         bootstrap=bootstrap if steps else 0,
                         gap_unexplained=unexplained_gap(final_cmp),
                         quieter=where_quieter(layout, final_cmp),
                         stopped_at_limit=state.stopped_at_limit)


@dataclass
class _State:
    """The loop's current model: its baseline, signatures, comparisons and what was accepted."""

    baseline: BaselineModel
    member_sig: list[Signatures]
    comparisons: dict[str, Comparison]
    residual: FloatArray
    det_terms: dict[str, FloatArray] = field(default_factory=dict)
    steps: list[Step] = field(default_factory=list)
    tried_last: dict[str, float] = field(default_factory=dict)
    stopped_at_limit: bool = False

    @property
    def gap(self) -> float:
        """Return the scalar gap G of the current model."""
        return sig.total_gap(self.comparisons)


def _iterate(state: _State, model: _Model, meas_sig: Signatures, effects: Sequence[Effect],
             max_steps: int, say: Callable[[str], None]) -> None:
    """
    Run the loop of the module doc on ``state`` until nothing passes or nothing is left.

    The loop goes on while the part of the gap an effect can explain (:func:`unexplained_gap`)
    exceeds :data:`INSIDE_GAP`; every candidate is judged by the whole gap G.
    """
    meas, layout = model.meas, model.layout
    while unexplained_gap(state.comparisons) > INSIDE_GAP:
        if len(state.steps) >= max_steps:
            state.stopped_at_limit = True
            break
        ctx = Context(meas, state.residual, layout, meas_sig, state.member_sig, model.accepted)
        trials = _trials(model, ctx, effects, say)
        tried = {t[1].name: t[0] for t in trials}
        gap = state.gap
        pick = choose([t[0] for t in trials], [sig.mean_log_score(t[5]) for t in trials],
                      [t[1].n_params for t in trials], gap)
        if pick is None:
            state.tried_last = tried
            break
        pick = _look_ahead(model, ctx, trials, pick, effects, gap, say)
        trial_gap, effect, params, det, trial_sig, trial_cmp = trials[pick]
        model.accept(effect, params, det, ctx)
        if det is not None:
            state.det_terms[effect.name] = det
            state.residual = state.residual - det
        if det is not None or effect.kind == 'quantization':
            state.baseline, trial_sig, trial_cmp, trial_gap = _rebased(
                model, ctx, state.residual, state.baseline, (trial_sig, trial_cmp, trial_gap), say,
                identify=det is not None)
        state.steps.append(Step(
            effect=effect.name, params=params, gap_before=gap, gap_after=trial_gap,
            where=where_outside(layout, state.comparisons),
            where_after=where_outside(layout, trial_cmp), candidates=tried,
            time_scales=time_scales(effect.name, params, meas, layout), before=state.comparisons,
            after=trial_cmp,
            scores={t[1].name: criterion(sig.mean_log_score(t[5]), t[1].n_params)
                    for t in trials}))
        say(f'added {effect.name} {public_params(params)}: gap {gap:.3f} -> {trial_gap:.3f}')
        state.member_sig, state.comparisons = trial_sig, trial_cmp


def _look_ahead(model: _Model, ctx: Context, trials: Sequence[Trial], pick: int,
                effects: Sequence[Effect], gap: float, say: Callable[[str], None]) -> int:
    """
    Check a stochastic pick against the deterministic candidates that pass, two steps ahead.

    A random walk (or any stochastic bias term) can cover a ramp or a transient by widening its
    band, together with a second stochastic process beside it. So when the pick is stochastic,
    each of the :data:`LOOK_AHEAD` best passing deterministic candidates D is accepted on trial
    and the stochastic effects are tried after it; when a model D + E has a :func:`criterion`
    (its score plus the penalty of both effects' parameters) smaller than the pick's by more
    than :data:`LOOK_AHEAD_MARGIN`, D is chosen instead (the next round will try E). Returns the
    index chosen.
    """
    if trials[pick][1].kind != 'stochastic':
        return pick
    crit = [criterion(sig.mean_log_score(t[5]), t[1].n_params) for t in trials]
    alts = sorted((i for i, t in enumerate(trials)
                   if t[1].kind == 'additive' and t[3] is not None and accepts(t[0], gap)),
                  key=crit.__getitem__)[:LOOK_AHEAD]
    stochastic = [e for e in effects if e.kind == 'stochastic']
    best, best_crit = pick, crit[pick] - LOOK_AHEAD_MARGIN
    for i in alts:
        _, effect, params, det, trial_sig, _ = trials[i]
        assert det is not None  # an additive candidate carries its term
        ahead = model.with_additive(effect, params, det)
        ctx_ahead = Context(ctx.meas, ctx.residual - det, ctx.layout, ctx.meas_sig, trial_sig,
                            ahead.accepted)
        for t in _trials(ahead, ctx_ahead, stochastic, lambda text: None):
            c = criterion(sig.mean_log_score(t[5]), effect.n_params + t[1].n_params)
            if c < best_crit:
                best, best_crit = i, c
    if best != pick:
        say(f'  {trials[best][1].name} then a stochastic effect scores {best_crit:.3f}, '
            f'{trials[pick][1].name} alone {crit[pick]:.3f} (margin {LOOK_AHEAD_MARGIN:g}): '
            f'{trials[best][1].name} first')
    return best


def _checked(ensemble: int, max_steps: int, seed: int,
             bootstrap: int) -> tuple[int, int, int, int]:
    """Return the integer settings of :func:`explain`; ParameterError names a bad one."""
    ensemble, max_steps, seed = int(ensemble), int(max_steps), int(seed)
    if ensemble < 4:
        raise ParameterError(f'ensemble must be >= 4 members, got {ensemble}')
    if max_steps < 0:
        raise ParameterError(f'max_steps must be >= 0, got {max_steps}')
    if seed < 0:
        raise ParameterError(f'seed must be >= 0, got {seed}')
    bootstrap = int(bootstrap)
    if bootstrap != 0 and bootstrap < 5:
        raise ParameterError(f'bootstrap must be 0 (off) or >= 5 records, got {bootstrap}')
    return ensemble, max_steps, seed, bootstrap


def _trials(model: _Model, ctx: Context, effects: Sequence[Effect],
            say: Callable[[str], None]) -> list[Trial]:
    """
    Fit every candidate not yet in the model and simulate the model with it.

    Returns ``[(gap, effect, params, deterministic term or None, signatures, comparisons)]`` of
    the candidates whose fit found parameters, in catalogue order.
    """
    meas, layout = ctx.meas, ctx.layout
    trials = []
    for effect in effects:
        if effect.name in model.accepted:
            continue
        params = effect.fit(ctx)
        if params is None:
            continue
        det = effect.term(params, meas.n, meas.rate_hz, None,
                          ctx) if effect.kind == 'additive' else None
        trial_sig = model.signatures((effect, params, det), ctx)
        trial_cmp = compare_all(layout, ctx.meas_sig, trial_sig)
        trial_gap = sig.total_gap(trial_cmp)
        say(f'  candidate {effect.name}: gap {trial_gap:.3f}')
        trials.append((trial_gap, effect, params, det, trial_sig, trial_cmp))
    return trials


def accepts(trial_gap: float, gap: float) -> bool:
    """
    Tell whether a candidate meets the acceptance rule: it shrinks the gap by >= INSIDE_GAP.

    ``trial_gap`` is the gap G of the model with the candidate, ``gap`` that of the current model.

    """
    return bool(trial_gap <= gap - INSIDE_GAP)


def criterion(score: float, n_params: int) -> float:
    """
    Return the penalised score that ranks tied candidates: log score + PARAM_PENALTY per parameter.

    ``score`` is :func:`.signatures.mean_log_score` of the candidate model (a Gaussian negative
    log-likelihood per point, summed over the signatures), ``n_params`` the candidate effect's
    parameter count; smaller is better.

    """
    return float(score) + PARAM_PENALTY * int(n_params)


def choose(gaps: Sequence[float], scores: Sequence[float], n_params: Sequence[int],
           gap: float) -> int | None:
    """
    Choose the next effect among candidates: only those that meet the acceptance rule compete.

    Rule (docs/discrepancy.md section 5): the candidates that shrink the gap by at least
    :data:`INSIDE_GAP` (:func:`accepts`) pass; among them the smallest :func:`criterion` (the
    proper log score of the model with the candidate plus :data:`PARAM_PENALTY` per parameter)
    wins; ties of the criterion go to the smaller gap, then to the first given. A candidate that
    fails the rule never wins, so the workflow never stops while one passes; and a model that
    passes by widening its band (a random walk covering a ramp) loses to one that puts its
    ensemble where the measurement is.

    Parameters
    ----------
    gaps : sequence of float
        Gap G of the model with each candidate.
    scores : sequence of float
        :func:`.signatures.mean_log_score` of each candidate model.
    n_params : sequence of int
        Parameter count of each candidate effect.
    gap : float
        Gap of the current model.

    Returns
    -------
    int or None
        Index of the chosen candidate; None when none passes.

    """
    passing = [i for i, g in enumerate(gaps) if accepts(g, gap)]
    if not passing:
        return None
    return min(passing, key=lambda i: (criterion(scores[i], n_params[i]), gaps[i], i))


def _rebased(model: _Model, ctx: Context, residual: FloatArray, baseline: BaselineModel,
             trial: tuple[list[Signatures], dict[str, Comparison], float],
             say: Callable[[str], None], *, identify: bool = True,
             ) -> tuple[BaselineModel, list[Signatures], dict[str, Comparison], float]:
    """
    Refit the baseline once a deterministic term or the lattice is accepted, if it changed.

    A deterministic term distorted the first fit (a strong line or ramp shifts the identified
    order): the baseline is identified again on the residual (``identify``). A lattice in the
    model rounds the members, so the baseline's levels must leave out the rounding noise the
    record already holds, q^2 / 12 (:func:`.baseline.without_white`). The members are
    regenerated and the refit kept only if it does not widen the gap. Returns ``(baseline,
    signatures, comparisons, gap)``: the refitted model's, or ``baseline`` and ``trial``
    (signatures, comparisons, gap) as they were.
    """
    meas = ctx.meas
    trial_sig, trial_cmp, trial_gap = trial
    refit = fit_baseline(residual, meas.rate_hz) if identify else baseline
    if model.quantization is not None:
        step = float(model.quantization['step_rad_s'])
        refit = without_white(refit, residual, meas.rate_hz, step * step / 12.0)
    if not _changed(refit, baseline):
        return baseline, trial_sig, trial_cmp, trial_gap
    members = list(model.members)
    model.rebase(refit, meas.rate - residual, ctx)
    refit_sig = model.signatures(None, ctx)
    refit_cmp = compare_all(ctx.layout, ctx.meas_sig, refit_sig)
    refit_gap = sig.total_gap(refit_cmp)
    if refit_gap <= trial_gap:
        say(f'  baseline refitted: alpha={refit.alpha:.2f} f={refit.f:.3f} '
            f'sigma_w={refit.sigma_w_rad_s:.3g} rad/s sigma_nu={refit.sigma_nu_rad_s:.3g} rad/s')
        return refit, refit_sig, refit_cmp, refit_gap
    model.members = members
    return baseline, trial_sig, trial_cmp, trial_gap


def _final_model(meas: Measurement, layout: Layout, baseline: BaselineModel,
                 steps: Sequence[Step], effects: Sequence[Effect],
                 det_terms: dict[str, FloatArray], seed: int) -> FinalModel:
    """Return the model the workflow ended with, for the parametric bootstrap."""
    by_name = {effect.name: effect for effect in effects}
    return FinalModel(n=meas.n, rate_hz=meas.rate_hz, temperature_c=meas.temperature_c,
                      layout=layout, baseline=baseline,
                      accepted=tuple((by_name[s.effect], s.params) for s in steps),
                      det_terms=det_terms, seed=seed)
