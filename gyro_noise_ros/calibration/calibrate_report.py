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
The text files of ``gyro_noise_calibrate``, rendered from its document (calibration.json).

Input: the dict ``CalibrationResult.as_dict()`` returns (SI, units in the keys; a null is a value
that was not finite). Outputs: :func:`calibration_yaml` (calibration.yaml, the ROS 2 parameter
file ``imu_compensator`` loads: SI), :func:`calibration_markdown` (calibration.md: paper 001
Table 6 layout, accelerometer biases in mg and scale factors in %, gyro in deg/s, the checks and
the dwells) and :func:`table6_rows` (the Table 6 numbers, which reliability.json and the
command line print too). The workflow that computes the document and writes the files is
:mod:`..app.calibrate`; the HTML page, :mod:`..htmlreport.calibrate`.
"""

from collections.abc import Iterable
import math
from typing import Any

import numpy as np

from .multipose import gravity_check_words
from ..formatting import plus_minus
from ..units import MG_TO_M_S2

__all__ = ['calibration_markdown', 'calibration_yaml', 'table6_rows']


def _yaml_list(values: Iterable[Any]) -> str:
    """Return a YAML flow list of doubles, repr() each (lossless); a null is written nan."""
    return '[' + ', '.join(repr(math.nan if v is None else float(v))
                           for v in np.ravel(np.asarray(values, dtype=object))) + ']'


def calibration_yaml(doc: dict[str, Any], *, written_utc: str) -> str:
    """
    Return the ``calibration.yaml`` ROS 2 parameter file of a calibration document.

    Parameters
    ----------
    doc : dict
        The ``calibration.json`` document.
    written_utc : str, keyword-only
        When the file is written (ISO 8601 UTC), for its first comment line.

    Returns
    -------
    str
        Comment lines (sources, gravity, model, frame, units), then ``/**: ros__parameters:``
        with the biases (accel m/s^2, gyro rad/s), scale factors (dimensionless),
        misalignments (3x3 row-major, zero diagonal) and the gravity used (m/s^2).

    """
    gyro = doc['gyro']
    lines = [
        f'# {doc["mode"]} calibration written by gyro_noise_calibrate {doc["version"]} on '
        f'{written_utc}',
        '# Sources: ' + ', '.join(doc['sources']),
        f'# Gravity used: {doc["gravity_m_s2"]!r} m/s^2 ({doc["gravity_source"]})',
        f'# Model: {doc["model"]}; compensation: true = inv(I + diag(S) + M) @ (measured - bias)',
        f'# Frame: {doc["frame"]}',
        '# Units: accel bias m/s^2, gyro bias rad/s, scale factors dimensionless '
        '(-0.0002 = -0.02 %), misalignment 3x3 row-major with zero diagonal',
    ]
    if gyro['note']:
        lines.append(f'# Gyro: {gyro["note"]}')
    lines += [
        '/**:',
        '  ros__parameters:',
        f'    accel_bias_m_s2: {_yaml_list(doc["accel"]["bias_m_s2"])}',
        f'    accel_scale_factor: {_yaml_list(doc["accel"]["scale_factor"])}',
        f'    accel_misalignment: {_yaml_list(doc["accel"]["misalignment"])}',
        f'    gyro_bias_rad_s: {_yaml_list(gyro["bias_rad_s"])}',
        f'    gyro_scale_factor: {_yaml_list(gyro["scale_factor"])}',
        f'    gyro_misalignment: {_yaml_list(gyro["misalignment"])}',
        f'    calibration_gravity_m_s2: {float(doc["gravity_m_s2"])!r}',
    ]
    return '\n'.join(lines) + '\n'


def table6_rows(doc: dict[str, Any]) -> list[tuple[str, float, float]]:
    """
    Return the paper Table 6 rows (bias in mg, scale factor in %) of a calibration document.

    Parameters
    ----------
    doc : dict
        The ``calibration.json`` document.

    Returns
    -------
    list of (str, float, float)
        Name, value and standard uncertainty in the printed unit.

    """
    a = doc['accel']
    rows = [(f'b{ax}', a['bias_m_s2'][i] / MG_TO_M_S2, a['bias_sigma_m_s2'][i] / MG_TO_M_S2)
            for i, ax in enumerate('xyz')]
    rows += [(f'S{ax}', a['scale_factor'][i] * 100.0, a['scale_factor_sigma'][i] * 100.0)
             for i, ax in enumerate('xyz')]
    return rows


def calibration_markdown(doc: dict[str, Any]) -> str:
    """
    Return ``calibration.md``: Table 6 layout, cross-axis terms, gyro, checks, dwells.

    Parameters
    ----------
    doc : dict
        The ``calibration.json`` document.

    Returns
    -------
    str

    """
    title = ('Six-position calibration (paper 001 Table 6 layout)'
             if doc['mode'] == 'six-position' else 'Multi-pose calibration (|a| = g, imu_tk)')
    out = [f'# {title}', '',
           f'Gravity used: {doc["gravity_m_s2"]:.5f} m/s^2 ({doc["gravity_source"]}). '
           'mg = 9.80665e-3 m/s^2. Frame: ' + doc['frame'] + '.', '',
           'Uncertainties: one standard uncertainty, against the value during the calibration, '
           'from the variogram of the dwells (white noise and bias wander between dwells).', '']
    out += _accelerometer_lines(doc)
    # the turns' block of the document is there when the gyro was estimated from them
    out += _gyro_lines(doc, turns='turns' in doc['gyro'])
    out += _check_lines(doc)
    out += _dwell_lines(doc)
    return '\n'.join(out) + '\n'


def _accelerometer_lines(doc: dict[str, Any]) -> list[str]:
    """Return the Table 6 rows and the cross-axis terms of the accelerometer (calibration.md)."""
    out = ['| parameter | value | std. uncertainty |', '|---|---|---|']
    for name, value, sig in table6_rows(doc):
        unit = 'mg' if name.startswith('b') else '%'
        out.append(f'| {name} | {value:.4f} {unit} | {sig:.4f} {unit} |')
    m = np.asarray(doc['accel']['misalignment'], dtype=float)
    ms = np.asarray([[np.nan if v is None else v for v in row]
                     for row in doc['accel']['misalignment_sigma']], dtype=float)
    out += ['', 'Accelerometer cross-axis terms (row = measured axis, column = true axis, %, '
            '+/- one standard uncertainty):', '', '| | x | y | z |', '|---|---|---|---|']
    for j, ax in enumerate('xyz'):
        out.append(f'| {ax} | ' + ' | '.join(
            '-' if i == j else plus_minus(100 * m[j, i], 100 * ms[j, i], '.4f')
            for i in range(3)) + ' |')
    return out


def _gyro_lines(doc: dict[str, Any], *, turns: bool) -> list[str]:
    """Return the gyro section: biases, scale factors and, from ``turns``, cross-axis terms."""
    gyro = doc['gyro']
    gb = np.degrees(np.asarray(gyro['bias_rad_s']))
    gs = np.degrees(np.asarray(gyro['bias_sigma_rad_s']))
    out = ['', '## Gyro', '',
           '| axis | bias (deg/s) | scale factor (%) |', '|---|---|---|']
    est = np.asarray(gyro.get('estimated', np.zeros((3, 3), bool)))
    for i, ax in enumerate('xyz'):
        if est[i, i]:
            scale = plus_minus(100 * gyro['scale_factor'][i],
                               100 * gyro['scale_factor_sigma'][i], '.4f')
        else:
            scale = 'not estimated'
        out.append(f'| {ax} | {gb[i]:.5f} +/- {gs[i]:.5f} | {scale} |')
    if turns:
        gm = np.asarray(gyro['misalignment'])
        gms = np.asarray([[np.nan if v is None else v for v in row]
                          for row in gyro['misalignment_sigma']], dtype=float)
        out += ['', f'Gyro cross-axis terms (%), from {gyro["turns"]} turns between static '
                f'poses (chi2 {gyro["chi2"]:.1f} for {gyro["dof"]} degrees of freedom):', '',
                '| | x | y | z |', '|---|---|---|---|']
        for j, ax in enumerate('xyz'):
            cells = []
            for i in range(3):
                if i == j:
                    cells.append('-')
                elif est[j, i]:
                    cells.append(plus_minus(100 * gm[j, i], 100 * gms[j, i], '.4f'))
                else:
                    cells.append('not estimated')
            out.append(f'| {ax} | ' + ' | '.join(cells) + ' |')
    if gyro['note']:
        out += ['', f'Gyro: {gyro["note"]}.']
    return out


def _check_lines(doc: dict[str, Any]) -> list[str]:
    """Return the indicators, the gravity check and the consistency of opposite dwells."""
    u = doc['uniformity']
    out = ['', '## Indicators (paper 001 section 6)', '',
           '- uniformity of the biases (std, ddof=1): '
           f'{u["accel_bias_std_m_s2"] / MG_TO_M_S2:.4f} mg',
           f'- uniformity of the scale factors (std, ddof=1): '
           f'{100 * u["accel_scale_factor_std"]:.4f} %']
    gc = doc['gravity_check']
    out += ['', '## Gravity check (leave-one-out)', '']
    if gc['consistent'] is None:
        out.append(f'{gravity_check_words(gc)}.')
    else:
        out += [f'Each dwell calibrated by the others; |a| - g against its standard deviation, '
                f'false-alarm {gc["alpha"]:g} over all dwells. Mean |a| raw '
                f'{gc["mean_norm_raw_m_s2"]:.4f} m/s^2, held-out calibrated '
                f'{gc["loo_mean_norm_m_s2"]:.5f} m/s^2; verdict: {gravity_check_words(gc)}.',
                '', '| dwell | abs(a) - g (mg) | sigma (mg) | z | verdict |',
                '|---|---|---|---|---|']
    for c in gc['dwells']:
        out.append(f'| {c["dwell"]} | {c["residual_m_s2"] / MG_TO_M_S2:+.4f} | '
                   f'{c["sigma_m_s2"] / MG_TO_M_S2:.4f} | {c["z"]:+.2f} | '
                   f'{"consistent" if c["consistent"] else "inconsistent"} |')
    if doc['consistency']['pairs']:
        out += ['', '## Consistency of opposite dwells (a tilt cannot pass silently)', '',
                '| pair | disagreement (mg) | sigma (mg) | p | verdict |',
                '|---|---|---|---|---|']
        for c in doc['consistency']['pairs']:
            dis = float(np.linalg.norm(c['disagreement_m_s2'])) / MG_TO_M_S2
            out.append(f'| +/-{c["axis"]} | {dis:.4f} | {c["sigma_m_s2"] / MG_TO_M_S2:.4f} | '
                       f'{c["p_value"]:.3g} | '
                       f'{"consistent" if c["consistent"] else "inconsistent"} |')
    return out


def _dwell_lines(doc: dict[str, Any]) -> list[str]:
    """Return the table of the dwells used (calibration.md's last section)."""
    out = ['', '## Dwells', '', '| dwell | start (s) | duration (s) | samples | NaN/Inf dropped '
           '| tilt (deg) | recording |', '|---|---|---|---|---|---|---|']
    for d in doc['dwells']:
        out.append(f'| {d["orientation"]} | {d["t_start_s"]:.2f} | {d["duration_s"]:.2f} | '
                   f'{d["samples"]} | {d["non_finite_samples"]} | {d["tilt_deg"]:.2f} | '
                   f'{d["source"]} |')
    return out
