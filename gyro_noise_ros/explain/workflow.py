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
The discrepancy workflow.

Fit the baseline, simulate an ensemble, find where the measurement leaves the band, name the
missing effect, add it, show the gap shrink (see docs/discrepancy.md).

Loop (at most ``max_steps`` times):

1. compare the measurement with the current model's ensemble on every signature
   (:mod:`.signatures`); stop if the gap G is 0 (inside every band);
2. every catalogue effect not yet in the model runs its fitter on the data (:mod:`.effects`); each
   one that reports parameters is added to the model on trial, the ensemble re-simulated (same
   member seeds:
   common random numbers, so the trials differ only by the effect) and the gap recomputed;
3. the candidate with the smallest gap wins; among candidates within :data:`TIE_GAP` of it
   (typically several models that all bring the measurement inside the bands) the one with the
   smallest :func:`~.signatures.mean_log_score` plus :data:`PARAM_PENALTY` per parameter (so a ramp
   beats a three-parameter transient that mimics it equally well); it is accepted when it shrinks
   the gap by at least :data:`INSIDE_GAP`, else the loop stops and the record is "unexplained" at
   the places still outside the band;
4. after a deterministic additive effect (sinusoid, ramp, transient, temperature) is accepted, the
   baseline is refitted to the residual (measurement minus the accepted deterministic terms): a
   strong line or ramp distorts the first identification. If the refit differs materially the
   members are regenerated (same seeds) and, unless that widens the gap, the refitted baseline is
   kept and the step's gap_after is the gap with it (memory: the previous members are held until
   decided).

Ensemble. ``ensemble`` members (default 16) of the baseline are generated once, each with its own
seeded generator (``numpy.random.default_rng([seed, member, 0])``); an accepted additive effect is
added into the members in place (its stochastic draws use ``default_rng([seed, member, 1 +
catalogue index])``), the lattice and stamp effects are applied when a member is evaluated. Memory:
``ensemble`` float64 copies of the record (16 x 3.6e6 samples = 460 MB for 1 h at 1 kHz).

Uncertainties. After the loop every accepted effect parameter gets a standard error and a 95 %
interval from a parametric bootstrap of the final model (:mod:`.uncertainty`, ``bootstrap``
records, default :data:`DEFAULT_BOOTSTRAP`; 0 switches it off).
"""

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
import itertools
import time
from typing import Any

import numpy as np

from . import signatures as sig
from .baseline import BaselineModel, fit_baseline
from .effects import CATALOGUE, Context, Effect, Params, public_params, Quantization
from .inputs import Measurement
from .signatures import Comparison, FloatArray, Layout, Signatures
from .uncertainty import bootstrap as bootstrap_uncertainty, FinalModel, time_scale_check
from ..errors import ParameterError

#: Candidates whose gap is within this of the best one count as tied; among them the smallest
#: mean_log_score + PARAM_PENALTY * (number of parameters) wins.
TIE_GAP = 0.05
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
        True when the gap is still above :data:`INSIDE_GAP` after the last step.
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
                    'time_scales': s.time_scales,
                }
                for s in self.steps
            ],
            'gap_initial': self.gap_initial,
            'gap_final': self.gap_final,
            'unexplained': self.unexplained,
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
    gap = sig.total_gap(comparisons)
    initial, gap_initial = comparisons, gap
    residual = meas.rate.copy()
    det_terms: dict[str, FloatArray] = {}
    steps: list[Step] = []
    tried_last: dict[str, float] = {}
    say(f'gap {gap:.3f}')
    while gap > INSIDE_GAP and len(steps) < max_steps:
        ctx = Context(meas, residual, layout, meas_sig, member_sig, model.accepted)
        trials = _trials(model, ctx, effects, say)
        tried = {t[1].name: t[0] for t in trials}
        if not trials:
            tried_last = {}
            break
        trial_gap, effect, params, det, trial_sig, trial_cmp = _choose(trials)
        if trial_gap > gap - INSIDE_GAP:
            tried_last = tried
            break
        model.accept(effect, params, det, ctx)
        if det is not None:
            det_terms[effect.name] = det
            residual = residual - det
            baseline, trial_sig, trial_cmp, trial_gap = _rebased(
                model, ctx, residual, baseline, (trial_sig, trial_cmp, trial_gap), say)
        steps.append(Step(effect=effect.name, params=params, gap_before=gap, gap_after=trial_gap,
                          where=where_outside(layout, comparisons),
                          where_after=where_outside(layout, trial_cmp), candidates=tried,
                          time_scales=time_scales(effect.name, params, meas, layout),
                          before=comparisons, after=trial_cmp))
        say(f'added {effect.name} {public_params(params)}: gap {gap:.3f} -> {trial_gap:.3f}')
        member_sig, comparisons, gap = trial_sig, trial_cmp, trial_gap
    seconds['iterate'] = time.perf_counter() - t2
    uncertainty = {}
    if bootstrap and steps:
        t3 = time.perf_counter()
        final = _final_model(meas, layout, baseline, steps, effects, det_terms, seed)
        uncertainty = bootstrap_uncertainty(final, bootstrap, values=meas.rate, mapper=mapper)
        seconds['bootstrap'] = time.perf_counter() - t3
        say(f'uncertainties: parametric bootstrap of the final model, {bootstrap} records')
    seconds['total'] = time.perf_counter() - t0
    return ExplainResult(measurement=meas, layout=layout, baseline=first_baseline,
                         final_baseline=baseline, steps=steps, gap_initial=gap_initial,
                         gap_final=gap, unexplained=gap > INSIDE_GAP,
                         where_final=where_outside(layout, comparisons),
                         comparisons_initial=initial, comparisons_final=comparisons,
                         tried_last=tried_last, ensemble=ensemble, seed=seed, seconds=seconds,
                         uncertainty=uncertainty, bootstrap=bootstrap if steps else 0)


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


def _choose(trials: Sequence[Trial]) -> Trial:
    """Return the trial of smallest gap; among those within TIE_GAP, the best-scoring simplest."""
    best_gap = min(t[0] for t in trials)
    tied = [t for t in trials if t[0] <= best_gap + TIE_GAP]
    return min(tied, key=lambda t: sig.mean_log_score(t[5]) + PARAM_PENALTY * t[1].n_params)


def _rebased(model: _Model, ctx: Context, residual: FloatArray, baseline: BaselineModel,
             trial: tuple[list[Signatures], dict[str, Comparison], float],
             say: Callable[[str], None]) -> tuple[BaselineModel, list[Signatures],
                                                  dict[str, Comparison], float]:
    """
    Refit the baseline on the residual once a deterministic term is accepted, if it changed.

    The deterministic term distorted the first fit (a strong line or ramp shifts the identified
    order): refit the baseline on the residual and regenerate the members; kept only if it does
    not widen the gap. Returns ``(baseline, signatures, comparisons, gap)``: the refitted model's,
    or ``baseline`` and ``trial`` (signatures, comparisons, gap) as they were.
    """
    meas = ctx.meas
    trial_sig, trial_cmp, trial_gap = trial
    refit = fit_baseline(residual, meas.rate_hz)
    if not _changed(refit, baseline):
        return baseline, trial_sig, trial_cmp, trial_gap
    members = list(model.members)
    model.rebase(refit, meas.rate - residual, ctx)
    refit_sig = model.signatures(None, ctx)
    refit_cmp = compare_all(ctx.layout, ctx.meas_sig, refit_sig)
    refit_gap = sig.total_gap(refit_cmp)
    if refit_gap <= trial_gap:
        say(f'  baseline refitted on the residual: alpha={refit.alpha:.2f} f={refit.f:.3f}')
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
