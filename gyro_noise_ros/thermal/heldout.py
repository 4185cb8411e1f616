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
Held-out scores on simulated runs: every method against the noise floor and against poly3.

For a train -> test pair of shapes and a seed, :func:`score_pair` simulates the two runs
(``thermal.simulate.simulate_pair``: one device, one time compression), fits each method on the
training run, applies it to the test run and takes the residual drift per axis (std of 60-s
means, deg/s). The yardsticks: the **noise floor**, the residual drift of the test run's own
noise (the simulator knows it: what a perfect drift model would leave), and **poly3**, the form
PX4 and ArduPilot evaluate; poly3 is also scored as each firmware applies it (PX4: at 1 Hz, only
after the temperature moved more than 1 degC; ArduPilot: every sample, float32). Rows for the raw
test run and the least-squares oracle on the simulator's true drift terms give the scale.
:func:`summarise` averages seeds into the table ``docs/scripts/thermal_heldout.py`` writes.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
import json
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import methods as registry
from .export import ardupilot_applied_offset, calibration_of, px4_applied_offset
from .metrics import residual_drift_deg_s
from .run import ThermalRun

__all__ = ['BOTH_SIGNS_PAIRS', 'HELDOUT_METHODS', 'HELDOUT_PAIRS', 'HeldoutMethod',
           'PARALLEL_SMALL_BUDGET', 'T_ONLY_DEVICE', 'T_ONLY_PAIRS', 'run_table', 'score_pair',
           'summarise']

#: Train -> test pairs: a warm-up calibration (heating) tested on runs shaped unlike it, and the
#: replicate (heating -> heating) that flatters every method.
HELDOUT_PAIRS = (('heating', 'heating'), ('heating', 'cooling'), ('heating', 'cycle'),
                 ('heating', 'staircase'), ('heating', 'sine'), ('heating', 'cool_reheat'))
#: Pairs trained on a heat-and-cool cycle: dT of both signs and both branches of the hysteresis.
BOTH_SIGNS_PAIRS = (('cycle', 'cooling'), ('cycle', 'staircase'), ('cycle', 'sine'))
#: A device whose drift is a cubic in T alone (no knee, no gradient, no hysteresis): what poly3
#: represents exactly, so the rows of poly3 under each firmware's rule show the rule's own cost.
T_ONLY_DEVICE = {'knee_dps': 0.0, 'gradient_dps_per_c_s': 0.0, 'hysteresis_half_width_c': 0.0}
#: Pairs on that device.
T_ONLY_PAIRS = (('heating', 'cooling'), ('heating', 'sine'))
#: The parallel model's MOPSO budget in the table (its other options at their defaults): the
#: drift part is the lowest mode(s) whatever K and alpha (docs/thermal_model.md).
PARALLEL_SMALL_BUDGET = {'n_particles': 10, 'iterations': 4, 'refine_points': 4,
                         'refine_polish': 4}


@dataclass(frozen=True)
class HeldoutMethod:
    """
    One row of the table: a label, a ``--method`` and its constructor options.

    Attributes
    ----------
    label : str
        Row label.
    method : str
        ``--method`` name.
    options : dict
        Constructor options.
    slow : bool
        Fitted on the first seeds only (``slow_seeds`` of :func:`score_pair`'s caller).

    """

    label: str
    method: str
    options: dict[str, Any] = field(default_factory=dict)
    slow: bool = False


#: The methods of the table, the default first.
HELDOUT_METHODS = (
    HeldoutMethod('lsq_cv (default)', 'lsq_cv'), HeldoutMethod('linear_tdt', 'linear_tdt'),
    HeldoutMethod('bp', 'bp'), HeldoutMethod('poly3', 'poly3'),
    HeldoutMethod('emd_wtd_sabp', 'emd_wtd_sabp', slow=True),
    HeldoutMethod('parallel (small MOPSO budget)', 'parallel', dict(PARALLEL_SMALL_BUDGET),
                  slow=True))


def _row(label: str, residual: NDArray[np.float64], **extra: Any) -> dict[str, Any]:
    return {'method': label, 'residual_deg_s': [float(v) for v in residual], **extra}


def score_pair(train_shape: str, test_shape: str, seed: int, *,
               methods: Sequence[HeldoutMethod] = HELDOUT_METHODS, rate_hz: float = 20.0,
               hours: float = 1.0, device: dict[str, Any] | None = None) -> dict[str, Any]:
    """
    Score methods on one simulated train -> test pair.

    Parameters
    ----------
    train_shape, test_shape : str
        Profile shapes (``thermal.simulate.SHAPES``).
    seed : int
        Seed of the pair.
    methods : sequence of HeldoutMethod, keyword-only
        What to fit.
    rate_hz, hours : float, keyword-only
        Gyro rate (Hz) and training run length (h); the test run is its whole profile.
    device : dict, optional, keyword-only
        Constants of the simulated device other than the defaults (``ThermalModel`` fields).

    Returns
    -------
    dict
        ``train``, ``test``, ``seed``, ``floor_deg_s`` (per axis), ``rate_outside`` (share of
        test samples outside the trained dT range) and ``rows``: per method ``method``,
        ``residual_deg_s`` per axis (and ``terms`` for ``lsq_cv``).

    """
    from .oracle import oracle_residual
    from .simulate import make_profile, simulate_pair, ThermalModel

    model = ThermalModel(**(device or {}))
    (_, train, train_truth), (_, test, test_truth) = simulate_pair(
        seed=seed, rate_hz=rate_hz, hours=hours, model=model,
        profile=make_profile(train_shape), test_profile=make_profile(test_shape))
    rows = [_row('raw', residual_drift_deg_s(test.gyro_rad_s, rate_hz)),
            _row('oracle (true drift terms)', residual_drift_deg_s(
                oracle_residual(train, train_truth, test, test_truth, model), rate_hz))]
    outside = None
    for m in methods:
        fitted = registry.fit_method(m.method, train, rng=np.random.default_rng(seed),
                                     accel=False, **m.options)
        out = np.asarray(fitted.method.apply(test), dtype=float)
        extra = {'terms': list(fitted.method.terms)} if m.method == 'lsq_cv' else {}
        rows.append(_row(m.label, residual_drift_deg_s(out, rate_hz), **extra))
        if m.method == 'poly3':
            rows += _firmware_rows(fitted.method, test, rate_hz)
        if outside is None and getattr(fitted.method, 'uses_rate', False):
            outside = _rate_outside(fitted, test)
    floor = residual_drift_deg_s(test_truth.noise_rad_s, rate_hz)
    return {'train': train_shape, 'test': test_shape, 'seed': int(seed), 'device': device or {},
            'floor_deg_s': [float(v) for v in floor], 'rate_outside': outside, 'rows': rows}


def _firmware_rows(poly: Any, test: ThermalRun, rate_hz: float) -> list[dict[str, Any]]:
    """poly3 as PX4 and as ArduPilot apply it to the test run."""
    cal = calibration_of(poly)
    gyro = np.asarray(test.gyro_rad_s, dtype=float)
    return [_row('poly3 as PX4 applies it (1 Hz, > 1 degC)', residual_drift_deg_s(
                 gyro - px4_applied_offset(cal, test.t_s, test.temperature_c), rate_hz)),
            _row('poly3 as ArduPilot applies it', residual_drift_deg_s(
                 gyro - ardupilot_applied_offset(cal, test.temperature_c), rate_hz))]


def _rate_outside(fitted: Any, test: ThermalRun) -> float:
    from .run import temperature_rate_c_s

    rate = temperature_rate_c_s(test.t_s, test.temperature_c, start='nan')
    rep = registry.range_report(fitted.training, test.temperature_c, rate)
    return (rep.rate_below + rep.rate_above) / rep.samples


def summarise(scores: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """
    Average the seeds of each pair and method: ratios to the floor and to poly3, per axis.

    Parameters
    ----------
    scores : sequence of dict
        :func:`score_pair` results (any pairs, seeds and methods).

    Returns
    -------
    list of dict
        Per device, pair and method, in first-seen order: ``device``, ``train``, ``test``,
        ``method``, ``seeds``,
        ``residual_deg_s`` (mean over seeds, per axis), ``over_floor`` (mean over seeds of
        residual / floor, per axis), ``worst_over_floor`` (largest over seeds and axes),
        ``over_poly3`` (mean over seeds of residual / poly3's, per axis; None without poly3),
        ``rate_outside`` (mean over seeds) and ``terms`` (the lsq_cv choices, per seed).

    """
    groups: dict[tuple[str, str, str, str], list[tuple[dict[str, Any], dict[str, Any]]]] = {}
    for score in scores:
        device = json.dumps(score.get('device') or {}, sort_keys=True)
        for row in score['rows']:
            groups.setdefault((device, score['train'], score['test'], row['method']),
                              []).append((score, row))
    out = []
    for (device, train, test, method), items in groups.items():
        res = np.array([row['residual_deg_s'] for _, row in items])
        floor = np.array([score['floor_deg_s'] for score, _ in items])
        p3 = [_poly3(score) for score, _ in items]
        over_p3 = None
        if all(p is not None for p in p3):
            over_p3 = (res / np.array(p3)).mean(axis=0).tolist()
        outside = [s['rate_outside'] for s, _ in items if s['rate_outside'] is not None]
        out.append({'device': json.loads(device), 'train': train, 'test': test,
                    'method': method, 'seeds': len(items),
                    'residual_deg_s': res.mean(axis=0).tolist(),
                    'over_floor': (res / floor).mean(axis=0).tolist(),
                    'worst_over_floor': float((res / floor).max()), 'over_poly3': over_p3,
                    'rate_outside': float(np.mean(outside)) if outside else None,
                    'terms': [row['terms'] for _, row in items if 'terms' in row]})
    return out


def _poly3(score: dict[str, Any]) -> list[float] | None:
    for row in score['rows']:
        if row['method'] == 'poly3':
            return list(row['residual_deg_s'])
    return None


def run_table(pairs: Sequence[tuple[str, str]], seeds: Sequence[int], *,
              methods: Sequence[HeldoutMethod] = HELDOUT_METHODS, slow_seeds: int = 3,
              rate_hz: float = 20.0, hours: float = 1.0, device: dict[str, Any] | None = None,
              progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """
    Score every pair and seed (slow methods on the first ``slow_seeds`` seeds only).

    Parameters
    ----------
    pairs : sequence of (str, str)
        Train and test shapes.
    seeds : sequence of int
        Seeds.
    methods : sequence of HeldoutMethod, keyword-only
        Rows.
    slow_seeds : int, keyword-only
        Seeds the slow methods (``HeldoutMethod.slow``) are fitted on.
    rate_hz, hours : float, keyword-only
        As :func:`score_pair`.
    device : dict, optional, keyword-only
        As :func:`score_pair`.
    progress : callable, optional, keyword-only
        Called with one line per pair and seed.

    Returns
    -------
    list of dict
        The :func:`score_pair` results.

    """
    scores = []
    for train, test in pairs:
        for i, seed in enumerate(seeds):
            chosen = [m for m in methods if not m.slow or i < slow_seeds]
            scores.append(score_pair(train, test, seed, methods=chosen, rate_hz=rate_hz,
                                     hours=hours, device=device))
            if progress is not None:
                progress(f'{train} -> {test}, seed {seed}: {len(chosen)} methods')
    return scores
