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
The per-axis entries of summary.json and its writer (SI, the unit in every key, NaN as null).

Units: the engine works in SI (rad/s); the customary values beside the SI ones are converted at
this edge and named with their unit (``bias_mean_deg_s``, ``offset_drift_deg_s_per_h``). The keys
are documented in ``docs/offline_tool.md``.
"""

from collections.abc import Mapping
import json
import math
from pathlib import Path
from typing import Any, SupportsFloat

import numpy as np

from ..core.health import HealthVerdict, reference_dict, ROBUST_JSON_KEY
from ..core.readout import AllanReadout
from ..core.results import AxisSummary, rad_s2_to_deg_s_per_h
from ..outputs import StrPath
from ..units import RAD_TO_DEG

__all__ = ['accelerometer_readout_dict', 'allan_terms_dict', 'axis_summary_dict', 'json_num',
           'write_json']

_DEG2 = RAD_TO_DEG ** 2


def json_num(value: SupportsFloat) -> float | None:
    """Return ``value`` as a float for JSON, NaN and infinities as None."""
    value = float(value)
    return value if math.isfinite(value) else None


def axis_summary_dict(summary: AxisSummary, *,
                      verdict: HealthVerdict | None = None) -> dict[str, Any]:
    """
    Turn an :class:`..core.results.AxisSummary` into the per-axis entry of summary.json.

    Parameters
    ----------
    summary : AxisSummary
        The axis' sequence statistics and counts.
    verdict : HealthVerdict, optional, keyword-only
        Added under ``health`` when given.

    Returns
    -------
    dict
        Keys carry their units (module doc); NaN becomes null.

    """
    seq = summary.sequence
    d = seq.drift
    readout = getattr(summary, 'readout', None)
    out = {
        'chunks': seq.chunks,
        'chunks_nan': summary.chunks_nan,
        'chunks_dropped': summary.chunks_dropped,
        'chunks_failed': summary.chunks_failed,
        'chunks_skipped': summary.chunks_skipped,
        'nan_samples': summary.nan_samples,
        'tail_samples': seq.tail_samples,
        'bias_mean_deg_s': json_num(seq.bias_mean * RAD_TO_DEG),
        'offset_drift_deg_s_per_h': json_num(rad_s2_to_deg_s_per_h(d.slope)),
        'offset_drift_abs_deg_s_per_h': json_num(abs(rad_s2_to_deg_s_per_h(d.slope))),
        'offset_drift_stderr_deg_s_per_h': json_num(rad_s2_to_deg_s_per_h(d.stderr)),
        'offset_drift_span_s': json_num(d.span_s),
        'offset_drift_rad_s2': json_num(d.slope),
        'offset_drift_stderr_rad_s2': json_num(d.stderr),
        'mean_variance_deg2_s2': json_num(seq.mean_variance * _DEG2),
        'variance_of_variances_deg4_s4': json_num(seq.variance_of_variances * _DEG2**2),
        'mean_variance_rad2_s2': json_num(seq.mean_variance),
        'variance_of_variances_rad4_s4': json_num(seq.variance_of_variances),
        'alpha_var_mean': json_num(seq.alpha_var_mean),
        'alpha_var_variance': json_num(seq.alpha_var_variance),
        'alpha_corr_mean': json_num(seq.alpha_corr_mean),
        'alpha_corr_variance': json_num(seq.alpha_corr_variance),
        'alpha_var_multimodal': bool(getattr(seq, 'alpha_var_modes', ())),
        'alpha_var_modes': [
            {'order': m, 'chunks': c} for m, c in getattr(seq, 'alpha_var_modes', ())
        ],
        'alpha_corr_multimodal': bool(getattr(seq, 'alpha_corr_modes', ())),
        'alpha_corr_modes': [
            {'order': m, 'chunks': c} for m, c in getattr(seq, 'alpha_corr_modes', ())
        ],
        'ties_var': seq.ties_var,
        'ties_corr': seq.ties_corr,
        'temperature_mean_c': json_num(summary.temperature_mean_c),
        'allan': allan_terms_dict(summary.noise_terms),
        'allan_datasheet': (
            readout.as_dict()
            if readout is not None
            else None
        ),
    }
    # what a later run's --reference check compares with (core/health.py)
    out[ROBUST_JSON_KEY] = reference_dict(seq)
    if verdict is not None:
        out['health'] = {'level': verdict.level, 'message': verdict.message,
                         'items': [{'key': k, 'value': v, 'level': lv} for k, v,
                                   lv in verdict.items]}
    return out


def accelerometer_readout_dict(readout: AllanReadout | None) -> dict[str, Any] | None:
    """
    Return the accelerometer entry of summary.json from an axis' readout (SI, units in keys).

    The readout of specific force in m/s^2 is read exactly as for the angular rate: its "angle
    random walk" is the velocity random walk (m/s/sqrt(s) = m/s^2/sqrt(Hz), Kalibr's
    accelerometer_noise_density), its "rate random walk" the acceleration random walk
    (m/s^3/sqrt(Hz), accelerometer_random_walk).

    Parameters
    ----------
    readout : core.readout.AllanReadout or None
        Readout of one accelerometer axis.

    Returns
    -------
    dict or None

    """
    if readout is None:
        return None
    r = readout
    return {k: (json_num(v) if isinstance(v, float) else v) for k, v in {
        'velocity_random_walk_m_s2_per_sqrt_hz': r.arw_rad_per_sqrt_s,
        'velocity_random_walk_ci_low_m_s2_per_sqrt_hz': r.arw_ci_low_rad_per_sqrt_s,
        'velocity_random_walk_ci_high_m_s2_per_sqrt_hz': r.arw_ci_high_rad_per_sqrt_s,
        'velocity_random_walk_from_region': r.arw_from_region,
        'bias_stability_m_s2': r.bias_stability_rad_s,
        'bias_stability_ci_low_m_s2': r.bias_stability_ci_low_rad_s,
        'bias_stability_ci_high_m_s2': r.bias_stability_ci_high_rad_s,
        'bias_stability_tau_s': r.bias_stability_tau_s,
        'bias_stability_upper_bound': r.bias_stability_upper_bound,
        'bias_instability_m_s2': r.bias_instability_rad_s,
        'acceleration_random_walk_m_s3_per_sqrt_hz': r.rate_random_walk_rad_per_s_sqrt_s,
        'acceleration_random_walk_resolved': r.rate_random_walk_resolved,
        'acceleration_random_walk_bound_m_s3_per_sqrt_hz':
            r.rate_random_walk_bound_rad_per_s_sqrt_s,
        'fit_quality': r.fit_quality,
    }.items()}


def allan_terms_dict(terms: Any) -> dict[str, Any] | None:
    """
    Return the fitted Allan noise terms as a JSON dict (SI values, units in the keys), or None.

    Parameters
    ----------
    terms : object or None
        The noise-term fit of :mod:`..core.allan`; either a mapping or a dataclass-like object
        whose public float attributes are named with their unit.

    Returns
    -------
    dict or None

    """
    if terms is None:
        return None
    if hasattr(terms, 'as_dict'):
        raw = terms.as_dict()
    elif isinstance(terms, dict):
        raw = terms
    else:
        raw = {k: getattr(terms, k) for k in dir(terms) if not k.startswith('_')}
    out: dict[str, Any] = {}
    for key, value in raw.items():
        if callable(value):
            continue
        if isinstance(value, (bool, int, float, np.floating, np.integer)):
            out[key] = json_num(value) if isinstance(value, (float, np.floating)) else int(value)
        elif isinstance(value, str):
            out[key] = value
        elif isinstance(value, dict):
            out[key] = {k: (json_num(v) if isinstance(v, (float, int, np.floating)) else v)
                        for k, v in value.items()}
    return out


def write_json(path: StrPath, doc: Mapping[str, Any]) -> None:
    """Write the JSON-serialisable ``doc`` to ``path``, indented (NaN must already be None)."""
    Path(path).write_text(json.dumps(doc, indent=2, allow_nan=False) + '\n')
