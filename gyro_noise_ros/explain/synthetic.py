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
Records with hidden effects, drawn at random from documented ranges (the proof of the workflow).

:func:`make_record` builds a :class:`~.inputs.Measurement` of the paper's baseline (000 eqs. 2,
10, 11; :func:`draw_baseline`) with the named effects hidden in it (:func:`draw_effect`). Each
effect is drawn from a range tied to the record, so that it is visible but not dominant: sizes in
units of the baseline's sd, of the noise of a chunk mean (:data:`CHUNKS` chunks), of its white
noise at the effect's time scale, time scales in units of the record length. With several
effects they are drawn in :data:`DRAW_ORDER` and each is sized against the record drawn so far
(its "rest"), so that each stands out of the others as it would out of the baseline alone.

:func:`outcome` explains one such record and says how the workflow did (and, on request,
whether each hidden effect is needed: the workflow restricted to the others leaves the record
unexplained); :func:`sweep` counts outcomes over seeds; :func:`coverage` measures the coverage of
the parameters' 95 % intervals. Every record is reproducible from its seed. The ranges and why,
and the measured rates: docs/discrepancy.md section 6.
"""

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from .effects import BiasTransient, Effect, flicker_noise, Params
from .inputs import make_measurement, Measurement
from .signatures import chunk_series, FloatArray
from ..core.allan import allan_deviation_values
from ..core.simulate import (check_stability, gauss_markov, gauss_markov_avar,
                             simulate_fractional_noise)

CHUNKS = 100
EFFECTS = ('quantization', 'sinusoid', 'bias_drift', 'bias_transient', 'rate_random_walk',
           'bias_instability', 'gauss_markov', 'temperature_sensitivity', 'sample_loss')
#: The order the effects of one record are drawn in: the stochastic bias terms first, so that
#: every later effect is sized against everything drawn before it (its "rest"), the value and
#: stamp maps last.
DRAW_ORDER = ('rate_random_walk', 'bias_instability', 'gauss_markov', 'sinusoid', 'bias_drift',
              'bias_transient', 'temperature_sensitivity', 'quantization', 'sample_loss')


def draw_baseline(rng: np.random.Generator) -> dict[str, float]:
    """Draw baseline parameters from the module-doc ranges; returns a dict."""
    while True:
        alpha = rng.uniform(0.8, 1.2)
        f = rng.uniform(-1.0, -0.6)
        if check_stability(round(alpha, 6), round(f, 6), 1000).stable:
            break
    sigma_w = rng.uniform(0.5e-3, 2e-3)
    return {'alpha': round(alpha, 6), 'f': round(f, 6), 'sigma_w': sigma_w,
            'sigma_nu': sigma_w * rng.uniform(0.0, 0.5), 'bias': rng.uniform(-0.02, 0.02)}


def _sign(rng: np.random.Generator) -> float:
    return 1.0 if rng.random() < 0.5 else -1.0


def draw_effect(name: str, rng: np.random.Generator, *, sigma: float, rate_hz: float,
                n: int, rest: FloatArray | None = None) -> dict[str, Any]:
    """
    Draw the parameters of effect ``name`` from the ranges of docs/discrepancy.md section 6.

    Parameters
    ----------
    name : str
        A catalogue name (see :data:`EFFECTS`).
    rng : numpy.random.Generator
        Random generator for the drawn parameters.
    sigma : float, keyword-only
        Sample sd of the baseline (rad/s).
    rate_hz : float, keyword-only
        Sample rate (Hz).
    n : int, keyword-only
        Samples.
    rest : numpy.ndarray, optional, keyword-only
        The record drawn so far when other effects are in it (rad/s): the noise the effect must
        stand out of is then the larger of the baseline's and the rest's, at the effect's own
        scale (the sd of the chunk means; the Allan deviation at the effect's time scale).
        None: the baseline alone (its white-noise levels).

    Returns
    -------
    dict
        Parameters with the catalogue's names (SI).

    """
    duration = n / rate_hz
    white = sigma / np.sqrt(rate_hz)
    s_c = sigma / np.sqrt(n // CHUNKS)
    if rest is not None:
        s_c = max(s_c, float(np.std(chunk_series(rest, n // CHUNKS)[0])))

    def adev(tau: float) -> float:
        """Return the noise an Allan-fitted effect must cross at tau (white, or the rest's)."""
        level = white / np.sqrt(tau)
        if rest is None:
            return float(level)
        m = max(1, int(round(tau * rate_hz)))
        return max(float(level), float(allan_deviation_values(rest, rate_hz, taus=[m])[0]))

    if name == 'quantization':
        step = rng.uniform(0.1, 0.6) * sigma
        return {'step_rad_s': step, 'offset_rad_s': rng.uniform(0, step)}
    if name == 'sinusoid':
        return {'amplitude_rad_s': rng.uniform(0.15, 0.5) * sigma,
                'frequency_hz': float(np.exp(rng.uniform(np.log(0.01), np.log(0.4)))) * rate_hz,
                'phase_rad': rng.uniform(0, 2 * np.pi)}
    if name == 'bias_drift':
        return {'slope_rad_s2': _sign(rng) * rng.uniform(15, 30) * s_c / duration}
    if name == 'bias_transient':
        return {'amplitude_rad_s': _sign(rng) * rng.uniform(15, 30) * s_c,
                'delay_s': rng.uniform(0.1, 0.4) * duration,
                'time_constant_s': rng.uniform(0.04, 0.15) * duration}
    if name == 'rate_random_walk':
        # the +1/2 line K sqrt(tau / 3) crosses the rest's curve at tc
        tc = float(np.exp(rng.uniform(np.log(duration / 300), np.log(duration / 60))))
        return {'k_rad_s_per_sqrt_s': np.sqrt(3.0) * adev(tc) / np.sqrt(tc)}
    if name == 'bias_instability':
        # the flicker floor 0.664 B meets the rest's curve at tc
        tc = float(np.exp(rng.uniform(np.log(duration / 1000), np.log(duration / 200))))
        return {'b_rad_s': adev(tc) / 0.664}
    if name == 'gauss_markov':
        corr = float(np.exp(rng.uniform(np.log(duration / 100), np.log(duration / 30))))
        ratio = rng.uniform(3, 5)
        unit = np.sqrt(gauss_markov_avar(2 * corr, 1.0, corr))
        return {'sigma_rad_s': ratio * adev(2 * corr) / unit, 'correlation_time_s': corr}
    if name == 'temperature_sensitivity':
        d_temp = rng.uniform(3, 8)
        t_temp = rng.uniform(0.15, 0.4) * duration
        k_t = _sign(rng) * rng.uniform(20, 40) * s_c / d_temp
        k_dt = 0.0 if rng.random() < 0.5 else _sign(rng) * rng.uniform(0.5, 1.0) * k_t * t_temp
        return {'coefficient_rad_s_per_degc': k_t, 'rate_coefficient_rad_s_per_degc_per_s': k_dt,
                '_delta_degc': d_temp, '_time_constant_s': t_temp,
                '_cycle_degc': rng.uniform(0.3, 1.0) * d_temp,
                '_cycle_s': rng.uniform(1 / 6, 1 / 2) * duration,
                '_cycle_phase': rng.uniform(0, 2 * np.pi)}
    if name == 'sample_loss':
        events = int(rng.integers(5, 31))
        return {'events': events, 'lost': np.minimum(rng.geometric(0.5, size=events), 20)}
    raise ValueError(f'unknown effect {name!r}')


def make_record(effects: Sequence[str], rng: np.random.Generator, *, n: int = 60000,
                rate_hz: float = 100.0, baseline: Mapping[str, float] | None = None,
                ) -> tuple[Measurement, dict[str, Any]]:
    """
    Build a measurement with the given effects hidden in baseline noise.

    Parameters
    ----------
    effects : sequence of str
        Effect names (empty: effect-free data).
    rng : numpy.random.Generator
        Random generator for the record and the effect parameters.
    n : int, keyword-only
        Samples.
    rate_hz : float, keyword-only
        Sample rate (Hz).
    baseline : dict, optional
        Baseline parameters (drawn when None).

    Returns
    -------
    tuple
        (Measurement, truth) where truth is {'baseline': ..., effect name: params}.

    """
    base = draw_baseline(rng) if baseline is None else baseline
    x = simulate_fractional_noise(n, base['alpha'], base['f'], base['sigma_w'], rng=rng,
                                  sigma_nu=base['sigma_nu'], bias=base['bias'])
    sigma = float(np.std(x))
    t = np.arange(n) / rate_hz
    truth = {'baseline': base}
    temperature = None
    stamps = t
    quant = None
    drawn = False
    for name in sorted(effects, key=DRAW_ORDER.index):
        p = draw_effect(name, rng, sigma=sigma, rate_hz=rate_hz, n=n, rest=x if drawn else None)
        drawn = drawn or name not in ('quantization', 'sample_loss')
        truth[name] = p
        if name == 'quantization':
            quant = p
        elif name == 'sinusoid':
            x = x + p['amplitude_rad_s'] * np.sin(2 * np.pi * p['frequency_hz'] * t
                                                  + p['phase_rad'])
        elif name == 'bias_drift':
            x = x + p['slope_rad_s2'] * t
        elif name == 'bias_transient':
            x = x + p[
                'amplitude_rad_s'] * BiasTransient.shape(t, p['delay_s'], p['time_constant_s'])
        elif name == 'rate_random_walk':
            x = x + np.cumsum(rng.standard_normal(n)) * p['k_rad_s_per_sqrt_s'] / np.sqrt(rate_hz)
        elif name == 'bias_instability':
            x = x + flicker_noise(n, rate_hz, p['b_rad_s'], rng)
        elif name == 'gauss_markov':
            x = x + gauss_markov(n, rate_hz, std=p['sigma_rad_s'],
                                 corr_time_s=p['correlation_time_s'], rng=rng)
        elif name == 'temperature_sensitivity':
            omega = 2 * np.pi / p['_cycle_s']
            temperature = (25.0 + p['_delta_degc'] * -np.expm1(-t / p['_time_constant_s'])
                           + p['_cycle_degc'] * np.sin(omega * t + p['_cycle_phase']))
            rate = (p['_delta_degc'] / p['_time_constant_s'] * np.exp(-t / p['_time_constant_s'])
                    + p['_cycle_degc'] * omega * np.cos(omega * t + p['_cycle_phase']))
            x = x + p['coefficient_rad_s_per_degc'] * temperature \
                + p['rate_coefficient_rad_s_per_degc_per_s'] * rate
            # a 0.01 degC sensor LSB and a little read noise
            temperature = np.round((temperature + rng.normal(0, 0.005, n)) / 0.01) * 0.01
        elif name == 'sample_loss':
            extra = np.zeros(n)
            np.add.at(extra, rng.integers(1, n, size=p['events']), p['lost'])
            stamps = (np.arange(n) + np.cumsum(extra)) / rate_hz
    if quant is not None:
        x = quant['offset_rad_s'] + quant['step_rad_s'] * np.round((x - quant['offset_rad_s'])
                                                                   / quant['step_rad_s'])
    meas = make_measurement(x, t_s=stamps, rate_hz=rate_hz, temperature_c=temperature,
                            source='synthetic')
    return meas, truth


def outcome(hidden: Sequence[str], seed: int, *, n: int = 20000, rate_hz: float = 100.0,
            ensemble: int = 8, needed: bool = False) -> dict[str, Any]:
    """
    Explain one record with ``hidden`` effects and say how the workflow did.

    Parameters
    ----------
    hidden : sequence of str
        The hidden effects (empty: effect-free); the record is
        ``make_record(hidden, numpy.random.default_rng([seed, 7]))``.
    seed : int
        Seed of the record and of the ensemble.
    n, rate_hz, ensemble : keyword-only
        Samples, sample rate (Hz) and ensemble members (no bootstrap: the counts do not use it).
    needed : bool, keyword-only
        Also tell, for each hidden effect, whether the record needs it: the workflow restricted
        to the *other* hidden effects leaves the record unexplained (one more run per effect).

    Returns
    -------
    dict
        ``named`` (in order), ``first_correct``, ``all_found``, ``inside`` (not unexplained),
        ``extra`` (an effect named that is not hidden), ``gap_initial``, ``gap_final`` and, with
        ``needed``, ``needed`` (effect -> bool) and ``detectable`` (every hidden effect needed).

    """
    from .effects import CATALOGUE
    from .workflow import explain

    meas, _ = make_record(hidden, np.random.default_rng([seed, 7]), n=n, rate_hz=rate_hz)
    result = explain(meas, seed=seed, ensemble=ensemble, bootstrap=0)
    named = result.named
    out: dict[str, Any] = {
        'hidden': list(hidden), 'seed': int(seed), 'named': named,
        'first_correct': bool(named[:1] and named[0] in hidden) if hidden else not named,
        'all_found': set(hidden) <= set(named), 'inside': not result.unexplained,
        'extra': bool(set(named) - set(hidden)), 'gap_initial': result.gap_initial,
        'gap_final': result.gap_final}
    if needed:
        out['needed'] = {
            name: explain(meas, seed=seed, ensemble=ensemble, bootstrap=0,
                          effects=[e for e in CATALOGUE if e.name in hidden and e.name != name]
                          ).unexplained
            for name in hidden}
        out['detectable'] = all(out['needed'].values())
    return out


def sweep(effects: Sequence[Sequence[str]], seeds: Iterable[int], *, n: int = 60000,
          rate_hz: float = 100.0, ensemble: int = 16,
          progress: Callable[[str], None] | None = None) -> dict[str, dict[str, int]]:
    """
    Run the workflow on ``seeds`` records per entry of ``effects`` and count the outcomes.

    Parameters
    ----------
    effects : sequence of tuple of str
        Each entry is the set of hidden effects of one case (empty tuple: effect-free).
    seeds : sequence of int
        Seeds, one record per seed and combination.
    n, rate_hz, ensemble : keyword-only
        Samples per record, sample rate (Hz) and ensemble members, as in :func:`.workflow.explain`.
    progress : callable, optional
        Called with one line per run.

    Returns
    -------
    dict
        case name -> {'runs', 'first_correct', 'all_found', 'inside', 'explained', 'named_any',
        'extra'} ('explained': first correct, all found and inside on the same record); for the
        effect-free case ``named_any`` / ``runs`` is the false-alarm rate.

    """
    table = {}
    for hidden in effects:
        key = '+'.join(hidden) or 'none'
        row = {'runs': 0, 'first_correct': 0, 'all_found': 0, 'inside': 0, 'explained': 0,
               'named_any': 0, 'extra': 0}
        for seed in seeds:
            got = outcome(hidden, seed, n=n, rate_hz=rate_hz, ensemble=ensemble)
            row['runs'] += 1
            for key_ in ('first_correct', 'all_found', 'inside', 'extra'):
                row[key_] += got[key_]
            # all three at once on the same record (the tests' notion of an explained record)
            row['explained'] += (got['first_correct'] and got['all_found'] and got['inside']
                                 if hidden else not got['named'])
            row['named_any'] += bool(got['named'])
            if progress:
                progress(f"{key} seed {seed}: named {got['named']}, gap "
                         f"{got['gap_initial']:.2f} -> {got['gap_final']:.2f}")
        table[key] = row
    return table


def coverage(case: Sequence[str], seeds: Iterable[int], *, n: int = 20000,
             rate_hz: float = 100.0, replicates: int = 20, members: int = 8) -> dict[str, Any]:
    """
    Count how often the 95 % interval of each effect parameter holds the hidden value.

    The effects of ``case`` are fitted with the fitters' estimators (deterministic ones in the
    order given, each on the record minus the others fitted so far; Allan-fitted ones against
    ``members`` baseline-only members, as the workflow's ensemble) and bootstrapped with the
    *true* baseline (:mod:`.uncertainty` is conditional on the baseline by design; the baseline
    fit takes seconds).

    Parameters
    ----------
    case : tuple of str
        Hidden effects (sinusoid, bias_drift, bias_transient, temperature_sensitivity,
        rate_random_walk, bias_instability, gauss_markov).
    seeds : sequence of int
        One record per seed.
    n, rate_hz : keyword-only
        Samples and rate (Hz).
    replicates, members : int, keyword-only
        Bootstrap records; null members of the Allan fits.

    Returns
    -------
    dict
        parameter -> {'runs', 'inside', 'z_sd'} (z: (value - true) / stderr), plus
        ``'_not_fitted'``: records on which an Allan-fitted effect was not detected.

    """
    from types import SimpleNamespace

    from .baseline import BaselineModel, simulation_memory
    from .effects import CATALOGUE, Context
    from .signatures import make_layout
    from ..core.allan import allan_deviation_values
    from .uncertainty import bootstrap, FinalModel

    by_name = {e.name: e for e in CATALOGUE}
    supported = ('sinusoid', 'bias_drift', 'bias_transient', 'temperature_sensitivity',
                 'rate_random_walk', 'bias_instability', 'gauss_markov')
    for name in case:
        if name not in supported:
            raise ValueError(f'coverage: {name!r} is not one of {", ".join(supported)}')
    rows: dict[str, dict[str, Any]] = {}
    missed = 0
    for seed in seeds:
        meas, truth = make_record(case, np.random.default_rng([seed, 17]), n=n, rate_hz=rate_hz)
        b = truth['baseline']
        base = BaselineModel(bias_rad_s=b['bias'], alpha=b['alpha'], f=b['f'],
                             sigma_w_rad_s=b['sigma_w'], sigma_nu_rad_s=b['sigma_nu'],
                             memory_fit=1000,
                             memory_sim=simulation_memory(b['alpha'], b['f'], rate_hz),
                             chunk_size=0, chunks_identified=0, psd_misfit=0.0)
        layout = make_layout(meas.rate, rate_hz, temperature=meas.temperature_c is not None)
        m = SimpleNamespace(n=meas.n, rate_hz=rate_hz, t_s=meas.t_s,
                            temperature_c=meas.temperature_c, rate=meas.rate)
        accepted: list[tuple[Effect, Params]] = []
        det: dict[str, FloatArray] = {}
        for name in case:
            effect = by_name[name]
            if effect.kind == 'stochastic':
                null: list[dict[str, FloatArray]] = [
                    {'allan': allan_deviation_values(base.generator(
                        np.random.default_rng([seed, j, 99])).generate(n), rate_hz,
                        taus=layout.m)}
                    for j in range(members)]
                ctx = Context(m, meas.rate, layout,
                              {'allan': allan_deviation_values(meas.rate, rate_hz,
                                                               taus=layout.m)},
                              null, {})
                params = effect.fit(ctx)
            else:
                residual = meas.rate - sum(det.values()) if det else meas.rate
                ctx = Context(m, residual, layout, None, None, {})
                params = effect.estimate(ctx)
                if params is not None:
                    det[name] = effect.term(params, n, rate_hz, None, ctx)
            if params is None:
                break
            accepted.append((effect, params))
        if len(accepted) < len(case):
            missed += 1
            continue
        model = FinalModel(n=n, rate_hz=rate_hz, temperature_c=meas.temperature_c, layout=layout,
                           baseline=base, accepted=tuple(accepted), det_terms=det, seed=seed)
        for effect_name, entries in bootstrap(model, replicates).items():
            for name, entry in entries.items():
                true = truth[effect_name].get(name)
                if true is None or entry['stderr'] is None or not entry['stderr'] > 0:
                    continue
                diff = entry['value'] - true
                if entry['unit'] == 'rad':
                    diff = float(np.angle(np.exp(1j * diff)))
                row = rows.setdefault(f'{effect_name}.{name}', {'runs': 0, 'inside': 0, 'z': []})
                row['runs'] += 1
                row['inside'] += bool(abs(diff) <= entry['ci95'][1] - entry['value']
                                      if entry['unit'] == 'rad'
                                      else entry['ci95'][0] <= true <= entry['ci95'][1])
                row['z'].append(diff / entry['stderr'])
    out: dict[str, Any] = {
        k: {'runs': r['runs'], 'inside': r['inside'], 'z_sd': float(np.std(r['z']))}
        for k, r in rows.items()}
    out['_not_fitted'] = missed
    return out
