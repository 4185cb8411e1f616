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
gyro_noise_calibrate: six-position static calibration of accelerometer and gyro (paper 001).

Usage::

    gyro_noise_calibrate BAG [BAG ...] [--topic T] [--gravity M_S2 | --latitude DEG [--height M]]
        [--min-static-s S] [--window-s S] [--accel-std-max M_S2] [--gyro-rate-max RAD_S]
        [--max-tilt-deg DEG] --out DIR

One recording holding the six static dwells (any order, motion in between) or six recordings.
Static dwells are found and classified by :mod:`gyro_noise_ros.calibration.static`; the estimates
come from :mod:`gyro_noise_ros.calibration.sixpos`. Writes ``calibration.json``,
``calibration.yaml`` (ROS 2 parameter file for the compensation node) and ``calibration.md``
(paper Table 6 layout) into DIR. Exit codes: 0 ok, 2 bad option, 3 unreadable recording, 4 the
dwells cannot give a calibration (missing, duplicate, tilted, too short, never static, all-zero
accelerometer); ``docs/reliability.md``.
"""

import argparse
import datetime
import json
import math
import os
import sys

import numpy as np

from ._common import run_cli
from .. import __version__
from ..calibration import records
from ..calibration.sixpos import (gravity_check, normal_gravity, six_position, STANDARD_GRAVITY,
                                  uniformity)
from ..calibration.static import (DetectorSettings, find_dwells, ORIENTATIONS, select_six,
                                  WindowAccumulator)
from ..errors import ParameterError

PROG = 'gyro_noise_calibrate'
MODEL = 'measured = (I + diag(scale_factor) + misalignment) @ true + bias'
#: One milli-g in m/s^2 (standard gravity, as the paper's mg).
MG = STANDARD_GRAVITY * 1e-3


def build_parser():
    """
    Return the argument parser of gyro_noise_calibrate.

    Returns
    -------
    argparse.ArgumentParser

    """
    d = DetectorSettings()
    p = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        description='Six-position static calibration (paper 001 eqs. 3-4): accelerometer bias, '
        'scale factor and cross-axis terms, gyro bias, uniformity and gravity check.')
    p.add_argument('bags', nargs='+', metavar='BAG',
                   help='one recording with the six dwells, or six recordings (rosbag2 or ROS 1)')
    p.add_argument('--out', required=True, metavar='DIR', help='output directory (created)')
    p.add_argument('--topic', help='sensor_msgs/Imu topic (default: the single Imu topic)')
    g = p.add_mutually_exclusive_group()
    g.add_argument('--gravity', type=float, metavar='M_S2', help='local gravity (m/s^2)')
    g.add_argument('--latitude', type=float, metavar='DEG',
                   help='geodetic latitude (deg) for WGS-84 normal gravity')
    p.add_argument('--height', type=float, default=0.0, metavar='M',
                   help='ellipsoidal height (m), with --latitude')
    p.add_argument('--rate-hz', type=float, help='nominal sample rate (default: from the stamps)')
    det = p.add_argument_group('static-dwell detector (docs/reliability.md)')
    det.add_argument('--min-static-s', type=float, default=d.min_static_s,
                     help='shortest usable dwell (s)')
    det.add_argument('--window-s', type=float, default=d.window_s, help='detector window (s)')
    det.add_argument('--accel-std-max', type=float, default=d.accel_std_max_m_s2, metavar='M_S2',
                     help='largest per-axis accel std of a static window (m/s^2)')
    det.add_argument('--gyro-rate-max', type=float, default=d.gyro_rate_max_rad_s,
                     metavar='RAD_S',
                     help='largest distance of a static window gyro mean from the median (rad/s)')
    det.add_argument('--merge-tol', type=float, default=d.merge_tol_m_s2, metavar='M_S2',
                     help='largest mean change between windows of one dwell (m/s^2)')
    det.add_argument('--trim-windows', type=int, default=d.trim_windows,
                     help='windows dropped at each end of a dwell')
    det.add_argument('--max-tilt-deg', type=float, default=d.max_tilt_deg,
                     help='largest angle between a dwell and its axis (deg)')
    return p


def resolve_gravity(gravity=None, latitude=None, height=0.0):
    """
    Return the gravity to use and how it was obtained.

    Parameters
    ----------
    gravity : float, optional
        Explicit local gravity (m/s^2).
    latitude : float, optional
        Geodetic latitude (deg) for WGS-84 normal gravity.
    height : float
        Ellipsoidal height (m).

    Returns
    -------
    (float, str, str or None)
        Gravity (m/s^2), its description, a warning line or None.

    """
    if gravity is not None:
        if not (math.isfinite(gravity) and 5.0 < gravity < 15.0):
            raise ParameterError(f'--gravity must be in m/s^2 (5..15), got {gravity!r}')
        return float(gravity), 'given (--gravity)', None
    if latitude is not None:
        g = normal_gravity(latitude, height)
        return g, f'WGS-84 normal gravity at latitude {latitude:g} deg, height {height:g} m', None
    return (STANDARD_GRAVITY, 'standard gravity 9.80665 (no local value given)',
            'no --gravity or --latitude: using standard gravity 9.80665 m/s^2; the scale factors '
            'then carry the local gravity anomaly (up to +/-0.3 %)')


def settings_from_args(args):
    """
    Return the detector settings of parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of gyro_noise_calibrate.

    Returns
    -------
    DetectorSettings

    """
    return DetectorSettings(window_s=args.window_s, accel_std_max_m_s2=args.accel_std_max,
                            gyro_rate_max_rad_s=args.gyro_rate_max, merge_tol_m_s2=args.merge_tol,
                            trim_windows=args.trim_windows, min_static_s=args.min_static_s,
                            max_tilt_deg=args.max_tilt_deg)


def detect(paths, *, topic=None, settings=DetectorSettings(), rate_hz=None):
    """
    Stream each recording through the window statistics and find its dwells.

    Parameters
    ----------
    paths : sequence of path
        Recordings.
    topic : str, optional, keyword-only
        Imu topic.
    settings : DetectorSettings, keyword-only
        Detector thresholds.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz).

    Returns
    -------
    list of Detection

    """
    out = []
    for path in paths:
        acc = None
        for rate, t, accel, gyro in records.iter_imu(path, topic=topic, rate_hz=rate_hz):
            if acc is None:
                acc = WindowAccumulator(rate, window_s=settings.window_s, source=str(path))
            acc.update(t, accel, gyro)
        out.append(find_dwells(acc.result(), settings))
    return out


def calibrate(paths, *, gravity_m_s2, topic=None, settings=DetectorSettings(), rate_hz=None):
    """
    Run the whole six-position calibration on recordings and return the JSON document.

    Parameters
    ----------
    paths : sequence of path
        One recording with six dwells, or six recordings.
    gravity_m_s2 : float, keyword-only
        Local gravity (m/s^2).
    topic : str, optional, keyword-only
        Imu topic.
    settings : DetectorSettings, keyword-only
        Detector thresholds.
    rate_hz : float, optional, keyword-only
        Nominal rate (Hz).

    Returns
    -------
    (dict, SixPositionResult)
        The ``calibration.json`` document and the estimate.

    Raises
    ------
    InputDataError
        The dwells do not give a calibration (see :func:`select_six`).
    BagError
        A recording cannot be read.

    """
    detections = detect(paths, topic=topic, settings=settings, rate_hz=rate_hz)
    chosen = select_six(detections, settings)
    dw = [chosen[o] for o in ORIENTATIONS]
    means = np.array([d.accel_mean_m_s2 for d in dw])
    res = six_position(means, gravity_m_s2, accel_sems_m_s2=[d.accel_sem_m_s2 for d in dw],
                       gyro_means_rad_s=[d.gyro_mean_rad_s for d in dw],
                       gyro_sems_rad_s=[d.gyro_sem_rad_s for d in dw])
    raw, cal = gravity_check(means, res)
    doc = {
        'gravity_m_s2': res.gravity_m_s2,
        'model': MODEL,
        'sources': [str(p) for p in paths],
        'dwells': [d.as_dict() for d in sorted(dw, key=lambda x: (x.source, x.t_start_s))],
        'accel': {
            'bias_m_s2': res.accel_bias_m_s2.tolist(),
            'bias_sigma_m_s2': res.accel_bias_sigma_m_s2.tolist(),
            'scale_factor': res.accel_scale_factor.tolist(),
            'scale_factor_sigma': res.accel_scale_factor_sigma.tolist(),
            'misalignment': res.accel_misalignment.tolist(),
            'misalignment_sigma': res.accel_misalignment_sigma.tolist(),
            'dwell_scatter_m_s2': res.accel_residual_m_s2,
        },
        'gyro': {
            'bias_rad_s': res.gyro_bias_rad_s.tolist(),
            'bias_sigma_rad_s': res.gyro_bias_sigma_rad_s.tolist(),
            'scale_factor': [0.0, 0.0, 0.0],
            'misalignment': np.zeros((3, 3)).tolist(),
            'scale_factor_estimated': False,
            'note': 'static dwells see only the Earth rate: gyro scale factor and misalignment '
                    'are not estimated (0); Earth rate cancels in the bias between opposite '
                    'dwells',
        },
        'uniformity': {
            'accel_bias_std_m_s2': uniformity(res.accel_bias_m_s2),
            'accel_scale_factor_std': uniformity(res.accel_scale_factor),
            'gyro_bias_std_rad_s': uniformity(res.gyro_bias_rad_s),
        },
        'gravity_check': {'mean_norm_raw_m_s2': raw, 'mean_norm_calibrated_m_s2': cal},
        'detector': {k: getattr(settings, k) for k in settings.__dataclass_fields__},
        'non_finite_samples': int(sum(d.non_finite_samples for d in detections)),
        'short_dwells': [d.as_dict() for det in detections for d in det.short],
        'version': __version__,
    }
    return doc, res


def _fmt(values):
    return '[' + ', '.join(repr(float(v)) for v in np.ravel(values)) + ']'


def yaml_text(doc, gravity_note=''):
    """
    Return the ``calibration.yaml`` ROS 2 parameter file of a calibration document.

    Parameters
    ----------
    doc : dict
        The ``calibration.json`` document.
    gravity_note : str
        How the gravity was obtained (comment).

    Returns
    -------
    str

    """
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ')
    lines = [
        f'# Six-position calibration written by {PROG} {doc.get("version", "")} on {stamp}',
        '# Sources: ' + ', '.join(doc['sources']),
        f'# Gravity used: {doc["gravity_m_s2"]!r} m/s^2 ({gravity_note})',
        f'# Model: {MODEL}; compensation: true = inv(I + diag(S) + M) @ (measured - bias)',
        '# Units: accel bias m/s^2, gyro bias rad/s, scale factors dimensionless '
        '(-0.0002 = -0.02 %), misalignment 3x3 row-major with zero diagonal',
        '/**:',
        '  ros__parameters:',
        f'    accel_bias_m_s2: {_fmt(doc["accel"]["bias_m_s2"])}',
        f'    accel_scale_factor: {_fmt(doc["accel"]["scale_factor"])}',
        f'    accel_misalignment: {_fmt(doc["accel"]["misalignment"])}',
        f'    gyro_bias_rad_s: {_fmt(doc["gyro"]["bias_rad_s"])}',
        f'    gyro_scale_factor: {_fmt(doc["gyro"]["scale_factor"])}',
        f'    gyro_misalignment: {_fmt(doc["gyro"]["misalignment"])}',
        f'    calibration_gravity_m_s2: {float(doc["gravity_m_s2"])!r}',
    ]
    return '\n'.join(lines) + '\n'


def table6_rows(doc):
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
    rows = [(f'b{ax}', a['bias_m_s2'][i] / MG, a['bias_sigma_m_s2'][i] / MG)
            for i, ax in enumerate('xyz')]
    rows += [(f'S{ax}', a['scale_factor'][i] * 100.0, a['scale_factor_sigma'][i] * 100.0)
             for i, ax in enumerate('xyz')]
    return rows


def markdown(doc):
    """
    Return ``calibration.md``: Table 6 layout, cross-axis terms, gyro bias and indicators.

    Parameters
    ----------
    doc : dict
        The ``calibration.json`` document.

    Returns
    -------
    str

    """
    out = ['# Six-position calibration (paper 001 Table 6 layout)', '',
           f'Gravity used: {doc["gravity_m_s2"]:.5f} m/s^2. mg = 9.80665e-3 m/s^2. '
           'Uncertainties: one standard error, from the spread of the 1 s window means or the '
           'dwell-to-dwell scatter about the model, whichever is larger.', '',
           '| parameter | value | std. uncertainty |', '|---|---|---|']
    for name, value, sig in table6_rows(doc):
        unit = 'mg' if name.startswith('b') else '%'
        out.append(f'| {name} | {value:.3f} {unit} | {sig:.3f} {unit} |')
    m = np.asarray(doc['accel']['misalignment'])
    out += ['', 'Cross-axis terms (misalignment, row = measured axis, column = true axis, %):', '',
            '| | x | y | z |', '|---|---|---|---|']
    for j, ax in enumerate('xyz'):
        out.append(f'| {ax} | ' + ' | '.join(f'{100 * v:.3f}' for v in m[j]) + ' |')
    gb = np.degrees(doc['gyro']['bias_rad_s'])
    gs = np.degrees(doc['gyro']['bias_sigma_rad_s'])
    out += ['', 'Gyro bias (deg/s): ' + ', '.join(f'{v:.4f} +/- {s:.4f}' for v, s in zip(gb, gs)),
            '', '## Indicators (paper 001 section 6)', '',
            f'- uniformity of the biases (std, ddof=1): '
            f'{doc["uniformity"]["accel_bias_std_m_s2"] / MG:.3f} mg',
            f'- uniformity of the scale factors (std, ddof=1): '
            f'{100 * doc["uniformity"]["accel_scale_factor_std"]:.3f} %',
            f'- gravity check, mean |a| over the dwells: raw '
            f'{doc["gravity_check"]["mean_norm_raw_m_s2"]:.4f} m/s^2, calibrated '
            f'{doc["gravity_check"]["mean_norm_calibrated_m_s2"]:.4f} m/s^2', '',
            '## Dwells', '', '| orientation | start (s) | duration (s) | samples | tilt (deg) | '
            'recording |', '|---|---|---|---|---|---|']
    for d in doc['dwells']:
        out.append(f'| {d["orientation"]} | {d["t_start_s"]:.2f} | {d["duration_s"]:.2f} | '
                   f'{d["samples"]} | {d["tilt_deg"]:.2f} | {d["source"]} |')
    return '\n'.join(out) + '\n'


def write_outputs(out_dir, doc, gravity_note=''):
    """
    Write calibration.json, calibration.yaml and calibration.md into a directory.

    Parameters
    ----------
    out_dir : path
        Output directory (created).
    doc : dict
        The calibration document.
    gravity_note : str
        How the gravity was obtained.

    """
    os.makedirs(out_dir, exist_ok=True)
    doc = dict(doc, gravity_source=gravity_note)
    with open(os.path.join(out_dir, 'calibration.json'), 'w') as fh:
        json.dump(doc, fh, indent=2)
    with open(os.path.join(out_dir, 'calibration.yaml'), 'w') as fh:
        fh.write(yaml_text(doc, gravity_note))
    with open(os.path.join(out_dir, 'calibration.md'), 'w') as fh:
        fh.write(markdown(doc))


def _body(argv):
    args = build_parser().parse_args(argv)
    if args.height != 0.0 and args.latitude is None:
        raise ParameterError('--height needs --latitude')
    gravity, note, warning = resolve_gravity(args.gravity, args.latitude, args.height)
    if warning:
        print(f'{PROG}: warning: {warning}', file=sys.stderr)
    settings = settings_from_args(args)
    doc, _ = calibrate(args.bags, gravity_m_s2=gravity, topic=args.topic, settings=settings,
                       rate_hz=args.rate_hz)
    if doc['non_finite_samples']:
        print(f'{PROG}: warning: {doc["non_finite_samples"]} samples in windows holding NaN/Inf '
              'were left out of the dwells', file=sys.stderr)
    write_outputs(args.out, doc, note)
    for d in doc['dwells']:
        print(f'dwell {d["orientation"]}: t={d["t_start_s"]:.1f} s, {d["duration_s"]:.1f} s, '
              f'{d["samples"]} samples ({d["source"]})')
    for name, value, sig in table6_rows(doc):
        unit = 'mg' if name.startswith('b') else '%'
        print(f'{name} = {value:.3f} +/- {sig:.3f} {unit}')
    print(f'wrote {os.path.join(args.out, "calibration.json")}, calibration.yaml, calibration.md')
    return 0


def main(argv=None):
    """
    Run gyro_noise_calibrate.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
