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
Standard errors and 95 % intervals of the accepted effect parameters: a parametric bootstrap.

:func:`bootstrap` simulates ``B`` records from the model the workflow ended with
(:class:`FinalModel`: the final baseline and every accepted effect, built as the ensemble members
are, seeded ``default_rng([seed, REPLICATE_OFFSET + b, ...])``; one record per :func:`replicate`,
pure and picklable, so a scheduler can map it) and refits every accepted effect on each with its
fitter's estimator (:meth:`~.effects.Effect.estimate`): deterministic effects on the record minus
the deterministic terms accepted before them, Allan-fitted ones on the excess over the
leave-one-out mean of the other records with the weights the fit used, stamp effects on the
stamps. The lattice is not bootstrapped (a simulated record sits on it exactly): its step and
offset are the LS line through the measured levels (:func:`lattice_uncertainty`).

Per parameter (:func:`summarise`): value, stderr (the refits' sd about the value; a grid
parameter adds spacing / sqrt 12), ``ci95 = value +/- t(0.975, m - 1) stderr`` for m successful
refits (clipped at 0 where a parameter cannot be negative), unit, method, ``resolved`` and
``note``. Unresolved: fewer than :data:`MIN_OK_FRACTION` of the refits succeed, the interval
reaches 0 (or spans the circle for a phase), the refits' mean lies more than :data:`BIAS_LIMIT`
stderr from the value, or a time scale lies outside what the record resolves
(:func:`resolvable_range`, :func:`time_scale_check`: then the bound the record gives, never a
value). The bootstrap is conditional on the fitted baseline and on the choice of effects. Rules,
reasons and the coverage measured: docs/discrepancy.md section 9.
"""

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, overload

import numpy as np
import scipy.stats

from .baseline import BaselineModel
from .effects import (_AllanFitted, Context, Effect, GaussMarkov, GM_PEAK_TAU, NAMES, Params,
                      Quantization)
from .signatures import FloatArray, lattice_fit, Layout
from ..core.allan import allan_deviation_values

#: Replicate b uses member index REPLICATE_OFFSET + b in the seed sequence: never an ensemble
#: member's index.
REPLICATE_OFFSET = 1 << 20
#: Fewer successful refits than this fraction of B: the parameter is unresolved.
MIN_OK_FRACTION = 0.8
#: Refits' mean further than this many (bootstrap) standard errors from the value: unresolved.
BIAS_LIMIT = 3.0
METHOD_BOOTSTRAP = 'parametric bootstrap'
METHOD_LATTICE = 'lattice least squares'

#: Unit and kind of every effect parameter. Kinds: 'scale' (> 0), 'signed', 'angle' (rad),
#: 'location' (no zero test), 'count' (no standard error).
PARAMETERS = {
    'step_rad_s': ('rad/s', 'scale'),
    'offset_rad_s': ('rad/s', 'location'),
    'amplitude_rad_s': ('rad/s', 'signed'),
    'frequency_hz': ('Hz', 'scale'),
    'phase_rad': ('rad', 'angle'),
    'slope_rad_s2': ('rad/s^2', 'signed'),
    'delay_s': ('s', 'location'),
    'time_constant_s': ('s', 'scale'),
    'k_rad_s_per_sqrt_s': ('rad/s/sqrt(s)', 'scale'),
    'b_rad_s': ('rad/s', 'scale'),
    'sigma_rad_s': ('rad/s', 'scale'),
    'correlation_time_s': ('s', 'scale'),
    'coefficient_rad_s_per_degc': ('rad/s/degC', 'signed'),
    'rate_coefficient_rad_s_per_degc_per_s': ('rad/s/(degC/s)', 'signed'),
    'gap_rate_per_s': ('1/s', 'scale'),
    'mean_lost_samples': ('samples', 'scale'),
    'max_lost_samples': ('samples', 'count'),
    'jitter_rms_s': ('s', 'scale'),
    'short_interval_fraction': ('1', 'scale'),
}


@dataclass(frozen=True)
class FinalModel:
    """
    What a replicate needs to simulate the final model and refit its effects (picklable).

    Attributes
    ----------
    n : int
        Samples.
    rate_hz : float
        Nominal rate (Hz).
    temperature_c : numpy.ndarray or None
        Measured temperature (drives temperature_sensitivity).
    layout : Layout
        Signature layout of the measurement.
    baseline : BaselineModel
        The final baseline.
    accepted : tuple
        (Effect, params) of every accepted effect, in order.
    det_terms : dict
        name -> the simulated term (rad/s, n samples) of each accepted deterministic effect.
    seed : int
        Seed of the run.

    """

    n: int
    rate_hz: float
    temperature_c: FloatArray | None
    layout: Layout
    baseline: BaselineModel
    accepted: tuple[tuple[Effect, Params], ...]
    det_terms: dict[str, FloatArray]
    seed: int

    def meas(self, rate: FloatArray | None = None,
             t_s: FloatArray | None = None) -> SimpleNamespace:
        """Return the measurement-like object the fitters read."""
        return SimpleNamespace(n=self.n, rate_hz=self.rate_hz, temperature_c=self.temperature_c,
                               rate=rate, t_s=t_s)


def _rng(model: FinalModel, index: int, stream: int) -> np.random.Generator:
    return np.random.default_rng([model.seed, REPLICATE_OFFSET + int(index), stream])


def simulate(model: FinalModel, index: int) -> tuple[FloatArray, FloatArray | None]:
    """
    Simulate replicate ``index`` of the final model.

    Built as the ensemble members are (:mod:`.workflow`): baseline, deterministic terms, stochastic
    terms, then the lattice and the stamps.

    Returns
    -------
    tuple
        (x in rad/s, stamps in s or None for ideal stamps).

    """
    n, rate_hz = model.n, model.rate_hz
    ctx = Context(model.meas(), None, model.layout, None, None, {})
    x = model.baseline.generator(_rng(model, index, 0)).generate(n)
    for term in model.det_terms.values():
        x += term
    quant, t = None, None
    for effect, params in model.accepted:
        stream = 1 + NAMES.index(effect.name)
        if effect.kind == 'stochastic':
            x += effect.term(params, n, rate_hz, _rng(model, index, stream), ctx)
        elif effect.kind == 'quantization':
            quant = params
        elif effect.kind == 'stamps':
            t = effect.stamps(params, n, rate_hz, _rng(model, index, stream), ctx)
    if quant is not None:
        x = Quantization.apply(quant, x)
    return x, t


def replicate(model: FinalModel, index: int) -> dict[str, Any]:
    """
    Simulate replicate ``index`` and refit every accepted effect on it (pure; picklable).

    The one function :func:`bootstrap` maps over the replicates (a scheduler may run it anywhere).

    Parameters
    ----------
    model : FinalModel
        The final model.
    index : int
        Replicate number (0 .. B - 1).

    Returns
    -------
    dict
        effect name -> refitted params (or None), and ``'_avar'`` -> the replicate's Allan
        variance on the layout ((rad/s)^2) when a stochastic effect is accepted.

    """
    x, t = simulate(model, index)
    t_s = t if t is not None else np.arange(model.n) / model.rate_hz
    meas = model.meas(rate=x, t_s=t_s)
    out: dict[str, Any] = {}
    earlier: list[str] = []
    for effect, params in model.accepted:
        # the fitter saw the record minus the deterministic terms accepted before it: so does the
        # refit (the later ones stay in, as they were in the measurement)
        residual = x
        for name in earlier:
            residual = residual - model.det_terms[name]
        if effect.name in model.det_terms:
            earlier.append(effect.name)
        if effect.kind in ('stochastic', 'quantization'):
            continue
        try:
            out[effect.name] = effect.estimate(Context(meas, residual, model.layout, None, None,
                                                       {}), near=params)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            out[effect.name] = None
    if any(effect.kind == 'stochastic' for effect, _ in model.accepted):
        out['_avar'] = allan_deviation_values(x, model.rate_hz, taus=model.layout.m) ** 2
    return out


def _allan_refits(model: FinalModel, effect: _AllanFitted, params: Params,
                  avar: FloatArray) -> list[Params]:
    """Refit a stochastic effect on each replicate's leave-one-out excess (module doc)."""
    count = avar.shape[0]
    ctx = Context(model.meas(), None, model.layout, None, None, {})
    extras, templ = effect.templates(ctx)
    if isinstance(effect, GaussMarkov):
        tcs = np.array([e['correlation_time_s'] for e in extras])
        r_hat = int(np.argmin(np.abs(np.log(tcs / params['correlation_time_s']))))
    else:
        r_hat = 0
    loo = (avar.sum(axis=0)[None, :] - avar) / (count - 1)
    excess = avar - loo + effect.amplitude(params) * templ[r_hat][None, :]
    weights = params.get('_allan_weights')
    stat, amp = effect.best(templ, effect.weights(avar) if weights is None else weights, excess)
    best = np.argmax(stat, axis=0)
    return [effect.params(float(amp[r, b]), extras[r]) for b, r in enumerate(best)]


def grid_resolution(model: FinalModel, effect: Effect,
                    params: Mapping[str, Any]) -> dict[str, float]:
    """Return parameter -> rounding sd (spacing / sqrt 12) of the grid it was found on."""
    root12 = np.sqrt(12.0)
    if isinstance(effect, GaussMarkov):
        # the grid of GaussMarkov.templates: 3 / fs .. longest tau / GM_PEAK_TAU
        ratio = (float(model.layout.tau_s[-1]) / GM_PEAK_TAU) / (3.0 / model.rate_hz)
        return {'correlation_time_s': params['correlation_time_s'] * np.log(ratio)
                / (effect.GRID_POINTS - 1) / root12}
    return {}


#: Parameters with a time scale: name -> 'time' (the value is a time) or 'frequency' (1 / time).
TIME_SCALES = {'correlation_time_s': 'time', 'time_constant_s': 'time',
               'frequency_hz': 'frequency'}


def resolvable_range(effect_name: str, name: str, params: Mapping[str, Any], *, n: int,
                     rate_hz: float, layout: Layout) -> tuple[float, float, str, str] | None:
    """
    Return the time scales (s) a record resolves for one parameter (module doc table).

    Parameters
    ----------
    effect_name, name : str
        Effect and parameter names.
    params : dict
        The effect's fitted parameters (the transient's ``delay_s``).
    n : int, keyword-only
        Samples of the record.
    rate_hz : float, keyword-only
        Nominal rate (Hz).
    layout : Layout
        Signature layout of the record (Allan taus, chunk length).

    Returns
    -------
    tuple or None
        ``(shortest_s, longest_s, why_short, why_long)``; None for a parameter without a time
        scale.

    """
    duration = n / rate_hz
    if effect_name == 'gauss_markov' and name == 'correlation_time_s':
        tau_max = float(layout.tau_s[-1])
        return (3.0 / rate_hz, tau_max / GM_PEAK_TAU,
                '3 samples: shorter is the own first-order dynamics of the baseline',
                f'the longest Allan tau ({tau_max:.3g} s) / {GM_PEAK_TAU}: the Allan peak at '
                f'{GM_PEAK_TAU} tc must be seen')
    if effect_name == 'bias_transient' and name == 'time_constant_s':
        after = duration - float(params['delay_s'])
        return (layout.chunk / rate_hz, after,
                'one chunk: a faster rise is a step in the chunk means',
                f'the {after:.3g} s the record shows after the onset')
    if effect_name == 'sinusoid' and name == 'frequency_hz':
        return (2.0 / rate_hz, duration, 'a period of 2 samples (Nyquist)',
                f'a period of the whole record ({duration:.3g} s)')
    return None


def time_scale_check(effect_name: str, name: str, params: Mapping[str, Any],
                     interval: Sequence[float] | None = None, *, n: int, rate_hz: float,
                     layout: Layout) -> dict[str, Any] | None:
    """
    Tell whether the record resolves a time-scale parameter, and the bound when it does not.

    Parameters
    ----------
    effect_name, name : str
        Effect and parameter names.
    params : dict
        The effect's fitted parameters (``params[name]`` is the value).
    interval : sequence of float, optional
        The value's 95 % interval ``[lo, hi]`` in the parameter's unit (default: the value).
    n, rate_hz, layout : keyword-only
        As :func:`resolvable_range`.

    Returns
    -------
    dict or None
        None for a parameter without a time scale; else ``resolvable`` ([low, high] in the
        parameter's unit), ``resolved``, ``bound`` ({'lower', 'upper'} in the parameter's unit,
        None where open; None when resolved) and ``note`` ('' when resolved).

    """
    limits = resolvable_range(effect_name, name, params, n=n, rate_hz=rate_hz, layout=layout)
    if limits is None:
        return None
    shortest, longest, why_short, why_long = limits
    value = float(params[name])
    lo, hi = (value, value) if interval is None else (float(interval[0]), float(interval[1]))
    frequency = TIME_SCALES[name] == 'frequency'

    def as_time(v: float) -> float:
        return 1.0 / v if frequency else v

    @overload
    def as_param(t: float) -> float: ...

    @overload
    def as_param(t: None) -> None: ...

    def as_param(t: float | None) -> float | None:
        return None if t is None else (1.0 / t if frequency else t)

    # the interval in time (a frequency interval reverses); 0 Hz is an infinite period
    t_lo, t_hi = ((as_time(hi), as_time(lo) if lo > 0 else np.inf) if frequency else (lo, hi))
    resolvable = sorted([as_param(shortest), as_param(longest)])
    # at the limit itself counts as outside: a fit stopped by its search range
    short = t_lo <= shortest * (1.0 + 1e-9)
    long = t_hi >= longest * (1.0 - 1e-9)
    out: dict[str, Any] = {
        'resolvable': [float(resolvable[0]), float(resolvable[1])], 'resolved': True,
        'bound': None, 'note': ''}
    if not (short or long):
        return out
    if long and not short:
        lower_t = min(max(t_lo, 0.0), longest)
        bound = {'lower': lower_t, 'upper': None}
        note = f'unresolved: longer than the record resolves ({why_long})'
    elif short and not long:
        upper_t = max(t_hi, shortest)
        bound = {'lower': None, 'upper': upper_t}
        note = f'unresolved: shorter than the record resolves ({why_short})'
    else:
        bound = {'lower': None, 'upper': None}
        note = (f'unresolved: the interval runs past both ends of what the record resolves '
                f'({shortest:.3g} to {longest:.3g} s)')
    if frequency:
        # a lower bound on the period is an upper bound on the frequency
        bound = {'lower': as_param(bound['upper']), 'upper': as_param(bound['lower'])}
    out.update(resolved=False, bound=bound, note=note)
    return out


def summarise(value: float, refits: Sequence[float | None], *, unit: str, kind: str,
              floor: float = 0.0, replicates: int | None = None) -> dict[str, Any]:
    """
    Return the standard error, interval and resolution of one parameter (module doc).

    Parameters
    ----------
    value : float
        The fitted value.
    refits : sequence of float
        The bootstrap refits (NaN or None for a failed refit).
    unit, kind : str, keyword-only
        See :data:`PARAMETERS`.
    floor : float, keyword-only
        Grid rounding sd added in quadrature.
    replicates : int, keyword-only
        B (default: len(refits)).

    Returns
    -------
    dict
        ``value``, ``stderr``, ``ci95`` [lo, hi], ``unit``, ``method``, ``resolved``, ``note``.

    """
    count = len(refits) if replicates is None else int(replicates)
    out: dict[str, Any] = {
        'value': float(value), 'stderr': None, 'ci95': None, 'unit': unit,
        'method': f'{METHOD_BOOTSTRAP} ({count} replicates)', 'resolved': False, 'note': ''}
    if kind == 'count':
        out['method'] = 'none'
        out['note'] = 'a count (the largest measured gap), no standard error'
        return out
    arr = np.array([np.nan if r is None else r for r in refits], dtype=np.float64)
    arr = arr[np.isfinite(arr)]
    if arr.size < max(2, MIN_OK_FRACTION * count):
        out['note'] = f'unresolved: the refit failed on {count - arr.size} of {count} replicates'
        return out
    dev = arr - value
    if kind == 'angle':
        dev = np.angle(np.exp(1j * dev))
    boot_sd = float(np.std(dev, ddof=1))
    stderr = float(np.hypot(boot_sd, floor))
    t = float(scipy.stats.t.ppf(0.975, arr.size - 1))
    lo, hi = value - t * stderr, value + t * stderr
    if kind == 'scale':
        lo = max(lo, 0.0)
    out.update(stderr=stderr, ci95=[float(lo), float(hi)], resolved=True)
    shift = float(np.mean(dev))
    if kind in ('scale', 'signed') and t * stderr >= abs(value):
        out.update(resolved=False,
                   note=f'unresolved: the 95 % interval reaches 0 (relative stderr '
                   f'{stderr / max(abs(value), 1e-300):.2g})')
    elif kind == 'angle' and t * stderr >= np.pi:
        out.update(resolved=False, note='unresolved: the 95 % interval spans the whole circle')
    elif boot_sd > 0 and abs(shift) > BIAS_LIMIT * boot_sd and abs(shift) > floor:
        out.update(resolved=False,
                   note=f'unresolved: the refits average {value + shift:.4g} {unit}, '
                   f'{abs(shift) / boot_sd:.1f} stderr from the value: the model does not '
                   'reproduce its own estimate')
    return out


def lattice_uncertainty(x: FloatArray, step: float,
                        offset: float) -> dict[str, dict[str, Any]]:
    """
    Return the standard errors of a value lattice's step and offset (module doc).

    Parameters
    ----------
    x : numpy.ndarray
        Measured samples (rad/s).
    step, offset : float
        The lattice found by :func:`~.signatures.find_lattice` (itself the least-squares line of
        :func:`~.signatures.lattice_fit`).

    Returns
    -------
    dict
        ``step_rad_s`` and ``offset_rad_s`` -> the :func:`summarise` layout (method
        ``lattice least squares``).

    """
    eps = 1e-7 * float(np.std(x))
    levels = np.unique(np.round(x / eps)) * eps
    _, _, cov = lattice_fit(levels, step, offset)
    out = {}
    for i, (name, value) in enumerate((('step_rad_s', step), ('offset_rad_s', offset))):
        entry: dict[str, Any] = {
            'value': float(value), 'stderr': None, 'ci95': None, 'unit': 'rad/s',
            'method': METHOD_LATTICE, 'resolved': False,
            'note': 'unresolved: fewer than 3 levels on the lattice'}
        if cov is not None:
            stderr = float(np.sqrt(cov[i, i]))
            # the levels' scatter is round-off, not Gaussian noise: the normal quantile
            entry.update(stderr=stderr, ci95=[float(value - 1.96 * stderr),
                                              float(value + 1.96 * stderr)],
                         resolved=True, note='')
        out[name] = entry
    return out


def _flag_transient_amplitude(entry: Mapping[str, dict[str, Any]]) -> None:
    """
    Flag a transient's amplitude when its time constant is longer than the record resolves.

    Over a record much shorter than tc the rise is A t / tc: only the initial slope A / tc is
    measured, and A grows with the unresolved tc.
    """
    tc, amp = entry.get('time_constant_s'), entry.get('amplitude_rad_s')
    if tc is None or amp is None or not amp['resolved']:
        return
    if tc.get('bound') is not None and tc['bound'].get('lower') is not None:
        amp.update(resolved=False, note='unresolved: the time constant is longer than the record '
                   'resolves, so only the initial slope amplitude / time constant is measured')


def bootstrap(model: FinalModel, replicates: int, *, values: FloatArray | None = None,
              mapper: Callable[..., Iterable[Any]] = map) -> dict[str, dict[str, dict[str, Any]]]:
    """
    Return standard errors and intervals of every accepted effect parameter (module doc).

    Parameters
    ----------
    model : FinalModel
        The final model of the workflow.
    replicates : int
        B, records simulated from it (>= 2).
    values : numpy.ndarray, keyword-only
        The measured samples (rad/s), for the quantization lattice.
    mapper : callable, keyword-only
        ``mapper(func, iterable)`` like the builtin ``map`` (the default); the only place the
        replicates are computed, so a parallel scheduler can be put here.

    Returns
    -------
    dict
        effect name -> parameter -> ``{value, stderr, ci95, unit, method, resolved, note}``.

    """
    from functools import partial

    count = int(replicates)
    results = list(mapper(partial(replicate, model), range(count)))
    avar = (np.array([r['_avar'] for r in results]) if results and '_avar' in results[0]
            else None)
    out = {}
    for effect, params in model.accepted:
        public = {k: v for k, v in params.items() if not k.startswith('_')}
        if effect.kind == 'quantization':
            assert values is not None  # the measured samples come with a quantization effect
            lattice = lattice_uncertainty(values, public['step_rad_s'], public['offset_rad_s'])
            out[effect.name] = lattice
            continue
        if effect.kind == 'stochastic':
            # the stochastic effects are the Allan-fitted ones, and their replicates hold '_avar'
            assert isinstance(effect, _AllanFitted) and avar is not None
            refits = _allan_refits(model, effect, params, avar)
        else:
            refits = [r[effect.name] for r in results]
        floors = grid_resolution(model, effect, params)
        entry = {}
        for name, value in public.items():
            unit, kind = PARAMETERS.get(name, ('', 'location'))
            entry[name] = summarise(value, [None if r is None else r.get(name) for r in refits],
                                    unit=unit, kind=kind, floor=floors.get(name, 0.0),
                                    replicates=count)
            if entry[name]['resolved']:
                check = time_scale_check(effect.name, name, public, entry[name]['ci95'],
                                         n=model.n, rate_hz=model.rate_hz, layout=model.layout)
                if check is not None and not check['resolved']:
                    entry[name].update(resolved=False, note=check['note'], bound=check['bound'])
        _flag_transient_amplitude(entry)
        out[effect.name] = entry
    return out


def format_value(entry: Mapping[str, Any], digits: int = 4) -> str:
    """
    Return ``value +/- stderr unit`` (or the reason there is none) for reports.

    The value is given to the second significant digit of the standard error.
    """
    value, stderr, unit = entry['value'], entry['stderr'], entry['unit']
    unit = '' if unit == '1' else f' {unit}'
    if stderr is None or not np.isfinite(stderr):
        return f'{value:.{digits}g}{unit} (no standard error)'
    if stderr > 0 and value != 0:
        places = int(np.floor(np.log10(abs(value)))) - int(np.floor(np.log10(stderr))) + 2
        places = min(max(places, 2), 10)
    else:
        places = digits
    return f'{value:.{places}g} ± {stderr:.2g}{unit}'


__all__ = ['FinalModel', 'PARAMETERS', 'TIME_SCALES', 'bootstrap', 'format_value',
           'lattice_uncertainty', 'replicate', 'resolvable_range', 'simulate', 'summarise',
           'time_scale_check']
