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
The scenarios of ``portenta_emulator``: reliability motion, thermal profiles, direct bag output.

Kept apart from ``cli/emulator.py`` (which only calls :func:`add_scenario_arguments`,
:func:`scenario_from_args` and :func:`write_bag`); the model is
:mod:`gyro_noise_ros.calibration.emulate`. With ``--scenario`` the board's static specific force
is replaced by the scenario's motion seen through the configured sensor errors; the board's own
noise, gyro bias (``--bias-dps``) and temperature model stay. ``--write-bag DIR`` writes the
samples the driver would publish (quantised at the configured full scales, scaled to SI) straight
into a rosbag2, as fast as they are generated: no pacing, no serial link. See
``docs/reliability.md``.

The thermal part: ``--thermal SHAPE`` (:data:`THERMAL_CHOICES`) builds the board's
:class:`~gyro_noise_ros.thermal.simulate.ThermalStream` (:func:`thermal_from_args`): the paper's
oven from ``--temp-c``, or a held-out shape (heating, cooling, staircases, cycles, soak, sine) at
its own set-points, compressed ``--thermal-compress`` times. See ``docs/thermal_data.md``.
"""

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO, TYPE_CHECKING

import numpy as np

from ._common import check_fits_disk
from ..bag import ImuBagWriter
from ..calibration.emulate import (Excitation, MultiPose, PAPER_AFTER_BIAS_MG,
                                   PAPER_AFTER_SCALE_PCT, PAPER_BEFORE_BIAS_MG,
                                   PAPER_BEFORE_SCALE_PCT, Scenario, SensorErrors, SixPosition,
                                   Static)
from ..calibration.sixpos import normal_gravity
from ..errors import ParameterError
from ..link import lsm6dso32 as lsm
from ..outputs import staged_new_dir
from ..units import DEG_TO_RAD, MG_TO_M_S2, STANDARD_GRAVITY_M_S2

if TYPE_CHECKING:
    from ..link.emulator import BoardModel
    from ..thermal.simulate import ThermalStream

#: Default cross-axis terms (%), xy, xz, yx, yz, zx, zy (a few tenths of a degree).
DEFAULT_MISALIGNMENT_PCT = (0.10, -0.05, 0.08, 0.03, -0.10, 0.05)
#: Flicker factor of --stress: widens the default bias-instability interval by ~+125 %
#: (paper 001: 420 s -> 945 s), from the IEEE 952 model with the default levels.
DEFAULT_STRESS_INSTABILITY = 1.7
#: Random-walk coefficient relative to the white-noise density: with the flicker plateau at half
#: the white ADEV at 1 s this puts the interval at ~1 s .. ~450 s (paper: 420 s).
RANDOM_WALK_PER_WHITE = 1.0 / 11.5
#: Epoch of the stamps of --write-bag (UNIX s).
BAG_EPOCH_NS = 1_700_000_000 * 10**9
#: Bytes a --write-bag bag takes per sample and Imu stream (the Temperature messages of 1 Hz
#: included), measured: 200,000 samples made 78.6 MB (sqlite3) and 74.2 MB (mcap); rounded up.
BAG_BYTES_PER_SAMPLE = 400
#: ``--thermal`` values: off, then the profiles of ``thermal.simulate.SHAPES``.
THERMAL_CHOICES = ('off', 'oven', 'heating', 'cooling', 'staircase', 'staircase_down', 'cycle',
                   'cool_reheat', 'soak', 'sine')


def thermal_from_args(args: argparse.Namespace) -> 'ThermalStream | None':
    """
    Build the board's thermal stream of ``--thermal`` (None for ``off``).

    The drift law's constant terms (gyro bias, accelerometer offset at 25 degC) are left out:
    the board has its own ``--bias-dps`` and accelerometer offset; what the profile adds is the
    temperature-dependent part. ``oven`` starts at ``--temp-c`` (its room); the other shapes
    keep their own set-points (``docs/thermal_data.md``).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``portenta_emulator`` arguments (``thermal``, ``thermal_compress``, ``temp_c``).

    Returns
    -------
    ThermalStream or None

    """
    shape = getattr(args, 'thermal', 'off')
    if shape == 'off':
        return None
    from ..thermal.simulate import make_profile, ThermalModel, ThermalStream

    room = args.temp_c if shape == 'oven' else None
    return ThermalStream(ThermalModel(bias_dps=0.0, accel_bias_mg=0.0), make_profile(shape),
                         compress=args.thermal_compress, room_c=room)


def _floats(count: int) -> Callable[[str], tuple[float, ...]]:
    def parse(text: str) -> tuple[float, ...]:
        try:
            vals = tuple(float(v) for v in text.split(','))
        except ValueError as err:
            raise argparse.ArgumentTypeError(f'expected {count} comma-separated numbers, '
                                             f'got {text!r}') from err
        if len(vals) not in ((1, count) if count == 3 else (count,)):
            raise argparse.ArgumentTypeError(f'expected {count} numbers, got {text!r}')
        return vals * 3 if len(vals) == 1 else vals
    return parse


def _tilt(text: str) -> tuple[str, float]:
    orientation, sep, deg = text.partition(':')
    try:
        value = float(deg)
    except ValueError:
        value = None
    if not sep or value is None or not np.isfinite(value):
        raise argparse.ArgumentTypeError(f'expected DWELL:DEG such as +x:4, got {text!r}')
    return orientation.strip(), value


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    """
    Add the reliability-scenario options to the emulator's parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The ``portenta_emulator`` parser.

    """
    g = parser.add_argument_group('reliability scenario (paper 001, docs/reliability.md)')
    g.add_argument('--scenario', choices=('static', 'six-position', 'multi-pose', 'sine',
                                          'sweep'),
                   help='motion: rest, six-position calibration sequence, multi-pose sequence '
                        '(>= 9 arbitrary static poses, imu_tk), sine dwell or sweep')
    g.add_argument('--write-bag', metavar='DIR',
                   help='write a rosbag2 directly (no pacing, no link; needs --duration-s or '
                        '--samples, default the scenario length)')
    g.add_argument('--bag-storage', choices=('sqlite3', 'mcap'), default='sqlite3')
    g.add_argument('--bag-temperature-decimation', type=int, default=0, metavar='N',
                   help='--write-bag: a Temperature message for every N-th sample, as the '
                        "driver's temperature_decimation does (128: 52 Hz at 6.66 kHz); 0: once "
                        'a second')
    g.add_argument('--orientation', default='+z', help='axis up at rest (+x .. -z)')
    g.add_argument('--latitude', type=float, default=45.0,
                   help='latitude (deg): Earth rate and WGS-84 gravity of the scenario')
    g.add_argument('--dwell-s', type=float, default=60.0, help='six-position dwell length (s)')
    g.add_argument('--move-s', type=float, default=5.0, help='rotation between dwells (s)')
    g.add_argument('--lead-s', type=float, default=5.0, help='rest before the first dwell (s)')
    g.add_argument('--order', default='+z,-z,+x,-x,+y,-y', help='six-position order')
    g.add_argument('--tilt', type=_tilt, action='append', default=[], metavar='DWELL:DEG',
                   help='six-position: tilt that dwell by DEG about a horizontal axis (a badly '
                        'seated fixture), e.g. +x:4; repeatable')
    g.add_argument('--poses', type=int, default=18,
                   help='multi-pose: number of static poses (>= 9 for the calibration)')
    g.add_argument('--accel-bias-mg', type=_floats(3),
                   help='accelerometer bias (mg); default paper Table 6 (before, or after with '
                        '--stress)')
    g.add_argument('--accel-scale-pct', type=_floats(3),
                   help='accelerometer scale factor (%%); default paper Table 6')
    g.add_argument('--accel-misalignment-pct', type=_floats(6),
                   default=DEFAULT_MISALIGNMENT_PCT,
                   help='cross-axis terms xy,xz,yx,yz,zx,zy (%%; [j,i]: true i into measured j)')
    g.add_argument('--gyro-scale-pct', type=_floats(3), default=(0.0, 0.0, 0.0),
                   help='gyro scale factor (%%)')
    g.add_argument('--gyro-misalignment-pct', type=_floats(6), default=(0.0,) * 6,
                   help='gyro cross-axis terms (%%)')
    g.add_argument('--accel-bias-instability-ug', type=float,
                   help='accelerometer IEEE 952 bias instability B (ug); default: plateau at '
                        'half the white-noise ADEV at 1 s')
    g.add_argument('--accel-random-walk-ug-sqrt-s', type=float,
                   help='accelerometer random walk (ug/sqrt(s)); default white density / 11.5')
    g.add_argument('--gyro-bias-instability-dps', type=float,
                   help='gyro bias instability B (deg/s); default as for the accelerometer')
    g.add_argument('--gyro-random-walk-dps-sqrt-s', type=float,
                   help='gyro rate random walk (deg/s/sqrt(s)); default white / 11.5')
    g.add_argument('--stress', action='store_true',
                   help='after the stress: Table 6 "after" values, cross-axis terms x2, bias '
                        'instability x --stress-instability-factor, gyro bias +0.05 deg/s')
    g.add_argument('--stress-instability-factor', type=float, default=DEFAULT_STRESS_INSTABILITY)
    g.add_argument('--excite-sensor', choices=('accel', 'gyro'), default='accel')
    g.add_argument('--excite-axis', choices=('x', 'y', 'z'), default='x')
    g.add_argument('--excite-amplitude', type=float, default=0.3,
                   help='excitation amplitude (g for accel, deg/s for gyro)')
    g.add_argument('--excite-hz', type=float, default=8.0,
                   help='sine dwell frequency, or sweep start (Hz)')
    g.add_argument('--sweep-to-hz', type=float, default=10.0, help='sweep end frequency (Hz)')
    g.add_argument('--sweep-rate-hz-s', type=float, default=0.5, help='sweep rate (Hz/s)')
    g.add_argument('--excite-start-s', type=float, default=2.0, help='rest before (s)')
    g.add_argument('--reference-topic', default='/shaker/imu',
                   help='--write-bag: Imu topic of the ideal reference sensor (sine/sweep)')


def scenario_from_args(args: argparse.Namespace) -> Scenario | None:
    """
    Build the scenario of parsed emulator arguments (None without ``--scenario``).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``portenta_emulator`` arguments.

    Returns
    -------
    Scenario or None

    """
    if not getattr(args, 'scenario', None):
        return None
    g = normal_gravity(args.latitude)
    if args.scenario in ('sine', 'sweep'):
        nyquist = args.odr_hz / 2.0
        top = max(args.excite_hz, args.sweep_to_hz if args.scenario == 'sweep' else 0.0)
        if not (np.isfinite(top) and top < nyquist):
            name = '--sweep-to-hz' if top != args.excite_hz else '--excite-hz'
            raise ParameterError(f'{name} {top:g} Hz is not below Nyquist ({nyquist:g} Hz at '
                                 f'--odr-hz {args.odr_hz:g})')
    if args.tilt and args.scenario != 'six-position':
        raise ParameterError('--tilt applies to --scenario six-position')
    motion: SixPosition | MultiPose | Static | Excitation
    if args.scenario == 'six-position':
        motion = SixPosition(order=tuple(o.strip() for o in args.order.split(',')),
                             dwell_s=args.dwell_s, move_s=args.move_s, lead_s=args.lead_s,
                             gravity_m_s2=g, latitude_deg=args.latitude,
                             tilts=tuple(args.tilt))
    elif args.scenario == 'multi-pose':
        motion = MultiPose(poses=args.poses, dwell_s=args.dwell_s, move_s=args.move_s,
                           lead_s=args.lead_s, gravity_m_s2=g, latitude_deg=args.latitude)
    else:
        static = motion = Static(orientation=args.orientation, gravity_m_s2=g,
                                 latitude_deg=args.latitude)
        if args.scenario in ('sine', 'sweep'):
            unit = MG_TO_M_S2 * 1e3 if args.excite_sensor == 'accel' else DEG_TO_RAD
            motion = Excitation(
                sensor=args.excite_sensor, axis=args.excite_axis,
                amplitude=args.excite_amplitude * unit, frequency_hz=args.excite_hz,
                sweep_to_hz=args.sweep_to_hz if args.scenario == 'sweep' else None,
                sweep_rate_hz_s=args.sweep_rate_hz_s, start_s=args.excite_start_s, base=static)
    # white-noise ADEV at 1 s: accel density / sqrt(2) (one-sided density over ODR/2); gyro
    # std / sqrt(ODR) (the board's fractional noise is nearly white)
    from ..link.emulator import ACCEL_NOISE_DENSITY_UG_RTHZ
    n_acc = ACCEL_NOISE_DENSITY_UG_RTHZ * 1e-6 * STANDARD_GRAVITY_M_S2 / np.sqrt(2.0)
    n_gyr = args.noise_std_dps * DEG_TO_RAD / np.sqrt(args.odr_hz)
    b_acc = (args.accel_bias_instability_ug * 1e-6 * STANDARD_GRAVITY_M_S2
             if args.accel_bias_instability_ug is not None else n_acc / 2.0 / 0.664)
    k_acc = (args.accel_random_walk_ug_sqrt_s * 1e-6 * STANDARD_GRAVITY_M_S2
             if args.accel_random_walk_ug_sqrt_s is not None else n_acc * RANDOM_WALK_PER_WHITE)
    b_gyr = (args.gyro_bias_instability_dps * DEG_TO_RAD
             if args.gyro_bias_instability_dps is not None
             else n_gyr / 2.0 / 0.664)
    k_gyr = (args.gyro_random_walk_dps_sqrt_s * DEG_TO_RAD if args.gyro_random_walk_dps_sqrt_s
             is not None else n_gyr * RANDOM_WALK_PER_WHITE)
    bias = args.accel_bias_mg or (PAPER_AFTER_BIAS_MG if args.stress else PAPER_BEFORE_BIAS_MG)
    scale = args.accel_scale_pct or (PAPER_AFTER_SCALE_PCT if args.stress
                                     else PAPER_BEFORE_SCALE_PCT)
    errors = SensorErrors(
        accel_bias_m_s2=np.asarray(bias) * MG_TO_M_S2,
        accel_scale_factor=np.asarray(scale) / 100.0,
        accel_misalignment=np.asarray(args.accel_misalignment_pct) / 100.0,
        gyro_scale_factor=np.asarray(args.gyro_scale_pct) / 100.0,
        gyro_misalignment=np.asarray(args.gyro_misalignment_pct) / 100.0,
        accel_bias_instability_m_s2=b_acc, accel_random_walk_m_s2_sqrt_s=k_acc,
        gyro_bias_instability_rad_s=b_gyr, gyro_random_walk_rad_s_sqrt_s=k_gyr)
    if args.stress:
        errors = errors.stressed(instability_factor=args.stress_instability_factor,
                                 accel_bias_m_s2=errors.accel_bias_m_s2,
                                 accel_scale_factor=errors.accel_scale_factor,
                                 gyro_bias_change_rad_s=0.05 * DEG_TO_RAD)
    # its own stream: the board's noise stays sample for sample what it is without a scenario
    rng = np.random.default_rng([args.seed, 2])
    return Scenario(motion, errors, args.odr_hz, rng)


def scenario_length_s(scenario: Scenario) -> float | None:
    """
    Return the natural length of a scenario (s), or None when it has none.

    Parameters
    ----------
    scenario : Scenario
        The scenario.

    Returns
    -------
    float or None

    """
    motion = scenario.motion
    if isinstance(motion, (SixPosition, MultiPose)):
        return motion.duration_s + motion.lead_s
    return None


def write_bag(args: argparse.Namespace, board: 'BoardModel', truth_fh: BinaryIO | None = None,
              counters: Any = None, stopper: Any = None) -> int:
    """
    Write the board's samples straight into a rosbag2 (``--write-bag``).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed emulator arguments.
    board : BoardModel
        The board (with its scenario, if any).
    truth_fh : file, optional
        Ground-truth log (TRUTH_DTYPE records).
    counters : object, optional
        The emulator's traffic counters (``samples_generated``, ``samples_sent``), for its
        closing statistics line.
    stopper : link.serve.Stopper, optional
        Checked once per block of 65,536 samples (SIGINT, SIGTERM): the staged bag is then
        removed.

    Returns
    -------
    int
        Exit status 0.

    """
    total = None
    if args.samples is not None:
        total = args.samples
    if args.duration_s is not None:
        n = int(round(args.duration_s * board.odr_hz))
        total = n if total is None else min(total, n)
    if total is None and board.scenario is not None:
        length = scenario_length_s(board.scenario)
        total = None if length is None else int(round(length * board.odr_hz))
    if total is None or total <= 0:
        raise ParameterError('--write-bag needs --duration-s or --samples (a positive length)')
    if isinstance(board.scenario.motion if board.scenario else None, Excitation) and (
            '/' + args.reference_topic.lstrip('/') in ('/imu/data_raw', '/imu/temperature')):
        raise ParameterError(f'--reference-topic {args.reference_topic!r} is a topic of the '
                             'board itself: the reference needs a topic of its own')
    streams = 2 if isinstance(board.scenario.motion if board.scenario else None, Excitation) else 1
    size = (f'--samples {args.samples}' if args.samples is not None else
            f'--duration-s {args.duration_s:g}' if args.duration_s is not None else
            f'--scenario {args.scenario}')
    check_fits_disk(args.write_bag, total * streams * BAG_BYTES_PER_SAMPLE, size)
    with staged_new_dir(args.write_bag, parameter='write_bag',
                        overwrite=getattr(args, 'overwrite', False)) as stage:
        # built under a hidden holder and renamed when complete: an error or Ctrl-C leaves no
        # bag folder behind to block the retry (the stage already carries the bag's name, which
        # the writer gives its storage file)
        _write_samples(args, board, stage, total, truth_fh, counters, stopper)
    print(args.write_bag, flush=True)
    return 0


def _write_samples(args: argparse.Namespace, board: 'BoardModel', path: Path, total: int,
                   truth_fh: BinaryIO | None, counters: Any, stopper: Any) -> None:
    from ..link.emulator import truth_records

    motion = board.scenario.motion if board.scenario is not None else None
    gyro_lsb = lsm.gyro_sensitivity_rad_s_per_lsb(board.gyro_fs_dps)
    accel_lsb = lsm.accel_sensitivity_m_s2_per_lsb(board.accel_fs_g)
    every = args.bag_temperature_decimation or max(1, int(round(board.odr_hz)))
    if every < 0:
        raise ParameterError(f'--bag-temperature-decimation must be >= 0, got {every}')
    done = 0
    with ImuBagWriter(path, storage=args.bag_storage) as w:
        while done < total:
            if stopper is not None:
                stopper.check()
            n = min(65536, total - done)
            s = board.next_samples(n)
            truth = board.last_truth
            assert truth is not None  # next_samples left it
            stamps = BAG_EPOCH_NS + np.round(truth.time_s * 1e9).astype(np.int64)
            w.write_imu(stamps, s['gyro'] * gyro_lsb, s['accel'] * accel_lsb)
            first = (-done) % every
            w.write_temperature(stamps[first::every], lsm.temperature_c(s['temp'][first::every]))
            if isinstance(motion, Excitation):
                ref = motion.reference(truth.time_s)
                zero = np.zeros_like(ref)
                acc, gyr = (ref, zero) if motion.sensor == 'accel' else (zero, ref)
                w.write_imu(stamps, gyr, acc, topic=args.reference_topic)
            if truth_fh is not None:
                truth_fh.write(truth_records(truth).tobytes())
            done += n
            if counters is not None:
                counters.samples_generated += n
                counters.samples_sent += n
