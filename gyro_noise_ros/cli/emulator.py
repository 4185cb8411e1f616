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
portenta_emulator: the Portenta H7 + LSM6DSO32 board, emulated, speaking the wire protocol.

Serves ``docs/portenta_link.md`` on a pseudo-terminal (default; prints the device path) or on a
loopback TCP port (``--tcp 127.0.0.1:0``; prints the pyserial URL ``socket://127.0.0.1:PORT``), one
line on stdout, flushed. It answers CONFIGURE commands with ACK/NAK, streams SAMPLES frames paced
in real time at the ODR (``--speed`` times faster), and keeps sampling while no host is connected
(samples the host could not receive show up as a counter gap flagged FLAG_SAMPLE_LOST on the next
sample sent, like the real board whose USB buffer is full). With ``--write-sd DIR`` it writes SD
log files as fast as it can instead. The transports are :mod:`gyro_noise_ros.link.serve`; this
module turns the command line into the board and its options.

Examples::

    portenta_emulator --link /tmp/ttyPORTENTA            # pty, stable symlink, real time, forever
    portenta_emulator --tcp 127.0.0.1:0 --speed 4 --seed 3 --corrupt-rate 1e-5 \
        --disconnect-every-s 10
    portenta_emulator --write-sd logs/ --duration-s 60 --sd-file-bytes 1000000 --helium-delay-s 10

Exit status 0 on SIGINT/SIGTERM or at the end of ``--samples``/``--duration-s``; 2 for a bad
option, 5 when the link cannot be served, 6 when an output (``--write-sd``, ``--write-bag``,
``--truth-out``, ``--stats-out``) cannot be written (see ``cli/_common.py``).
"""

import argparse
from pathlib import Path
import signal
import sys
from typing import Any, BinaryIO

import numpy as np

from ._common import run_cli
from ._scenario import (add_scenario_arguments, scenario_from_args, THERMAL_CHOICES,
                        thermal_from_args, write_bag)
from ..errors import OutputError, ParameterError
from ..link import lsm6dso32 as lsm
from ..link.emulator import (
    BoardModel,
    DEFAULT_ALPHA,
    DEFAULT_BIAS_DPS,
    DEFAULT_F,
    FaultInjector,
    HeliumTransient,
    PAPER_NOISE_STD_DPS,
    TRUTH_DTYPE,
    Vibration,
)
from ..link.protocol import MAX_SAMPLES_PER_FRAME
from ..link.sdlog import FAT32_MAX_FILE_BYTES
from ..link.serve import (Counters, SdOptions, serve, ServeOptions, stats_line, Stopper,
                          total_samples, TX_BUFFER_BYTES, write_sd_logs)
from ..outputs import atomic_write_text

PROG = 'portenta_emulator'
#: Options not named after the parameter they set (errors name parameters: cli/_common).
RENAMED = {'out_dir': '--write-sd'}


def _float_list(text: str) -> float | tuple[float, ...]:
    try:
        values = [float(v) for v in text.split(',')]
    except ValueError as err:
        raise argparse.ArgumentTypeError(
            f'expected a number or three comma-separated numbers, got {text!r}') from err
    if len(values) not in (1, 3):
        raise argparse.ArgumentTypeError(f'expected 1 or 3 values, got {text!r}')
    return values[0] if len(values) == 1 else tuple(values)


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of portenta_emulator.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split('\n\n')[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    _add_output_arguments(p)
    _add_run_arguments(p)
    _add_configuration_arguments(p)
    _add_sensor_arguments(p)
    _add_fault_arguments(p)
    add_scenario_arguments(p)
    return p


def _add_output_arguments(p: argparse.ArgumentParser) -> None:
    """Add where the board writes: a pseudo-terminal, TCP or SD files."""
    out = p.add_argument_group('output (default: a pseudo-terminal)')
    out.add_argument('--tcp', metavar='HOST:PORT',
                     help='serve on a loopback TCP port instead (port 0: any)')
    out.add_argument('--link', metavar='PATH',
                     help='pty only: keep a symlink PATH -> the pty (survives replug)')
    out.add_argument('--write-sd', metavar='DIR',
                     help='write SD log files into DIR instead of serving')
    out.add_argument('--sd-file-bytes', type=int, default=FAT32_MAX_FILE_BYTES,
                     help='SD file size limit (bytes)')
    out.add_argument('--sequence-id', type=int, default=1, help='SD sequence id')
    out.add_argument('--rtc-unix-s', type=int, default=0,
                     help='SD header RTC time at power-on (0 = unset)')
    out.add_argument('--truth-out', metavar='FILE',
                     help='append the ground truth of every sample (TRUTH_DTYPE)')
    out.add_argument('--stats-out', metavar='FILE',
                     help='write the fault/traffic counters as JSON at exit')


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Add the seed, the pace and the length of the run."""
    run = p.add_argument_group('run')
    run.add_argument('--seed', type=int, default=0,
                     help='seed of the sample streams (faults use seed+1)')
    run.add_argument('--speed', type=float, default=1.0, help='pace at this multiple of real time')
    run.add_argument('--samples', type=int, help='stop after this many samples')
    run.add_argument('--duration-s', type=float, help='stop after this much board time (s)')
    run.add_argument('--batch', type=int, default=16, help='samples per frame (FIFO watermark)')
    run.add_argument('--tx-buffer-bytes', type=int, default=TX_BUFFER_BYTES,
                     help='board transmit buffer; samples that do not fit are dropped and flagged')


def _add_configuration_arguments(p: argparse.ArgumentParser) -> None:
    """Add the board's power-on configuration."""
    cfg = p.add_argument_group('power-on configuration')
    cfg.add_argument('--odr-hz', type=float, default=6667.0, help=f'one of {lsm.ODRS_HZ}')
    cfg.add_argument('--gyro-fs-dps', type=int, default=2000,
                     help=f'one of {lsm.GYRO_FULL_SCALES_DPS}')
    cfg.add_argument('--accel-fs-g', type=int, default=4, help=f'one of {lsm.ACCEL_FULL_SCALES_G}')
    cfg.add_argument('--seq0', type=int, default=0, help='first sequence number (wrap tests)')
    cfg.add_argument('--t0-us', type=int, default=0,
                     help='device time at power-on (us, wrap tests)')
    cfg.add_argument('--clock-ppm', type=float, default=0.0, help='board clock error (ppm)')


def _add_sensor_arguments(p: argparse.ArgumentParser) -> None:
    """Add the sensor model: noise, bias, temperature, vibration."""
    noise = p.add_argument_group('sensor model')
    noise.add_argument('--alpha', type=float, default=DEFAULT_ALPHA,
                       help='fractional order (paper 000 eq. 2)')
    noise.add_argument('--f', type=float, default=DEFAULT_F,
                       help='noise parameter f (paper 000 eq. 2)')
    noise.add_argument('--noise-std-dps', type=float, default=PAPER_NOISE_STD_DPS,
                       help='stationary gyro noise standard deviation (deg/s)')
    noise.add_argument('--bias-dps', type=_float_list, default=DEFAULT_BIAS_DPS,
                       help='gyro bias x,y,z (deg/s)')
    noise.add_argument('--temp-c', type=float, default=25.0,
                       help='die temperature at power-on (degC)')
    noise.add_argument('--temp-drift-c-per-h', type=float, default=0.0,
                       help='temperature ramp (degC/h)')
    noise.add_argument('--temp-sensitivity-dps-per-c', type=_float_list, default=0.0,
                       help='gyro bias change per degC (deg/s/degC)')
    noise.add_argument('--helium-amplitude-dps', type=_float_list, default=0.0,
                       help='helium-like bias rise, final value (deg/s); 0 = off')
    noise.add_argument('--helium-delay-s', type=float, default=5400.0,
                       help='delay before the rise (s)')
    noise.add_argument('--helium-tau-s', type=float, default=7200.0,
                       help='time constant of the rise (s)')
    noise.add_argument('--thermal', choices=THERMAL_CHOICES, default='off',
                       help='the thermal model of docs/thermal_data.md (die lag, bias from '
                            'temperature and its rate, hysteresis, accelerometer offset) with '
                            'an oven profile: oven (paper 002, from --temp-c), heating, '
                            'cooling, staircase, staircase_down, cycle, cool_reheat, soak, '
                            'sine; replaces --temp-drift-c-per-h and '
                            '--temp-sensitivity-dps-per-c')
    noise.add_argument('--thermal-compress', type=float, default=60.0,
                       help='run the thermal profile this many times faster (the ~14 h oven '
                            'in 14 min at 60)')
    noise.add_argument('--vibration-hz', type=float, default=0.0,
                       help='sinusoidal vibration frequency (Hz)')
    noise.add_argument('--vibration-dps', type=_float_list, default=0.0,
                       help='vibration rate amplitude (deg/s)')
    noise.add_argument('--vibration-g', type=_float_list, default=0.0,
                       help='vibration accel amplitude (g)')


def _add_fault_arguments(p: argparse.ArgumentParser) -> None:
    """Add the faults injected into the link and the samples."""
    fault = p.add_argument_group('fault injection')
    fault.add_argument('--corrupt-rate', type=float, default=0.0,
                       help='probability per byte sent/written')
    fault.add_argument('--drop-flagged-rate', type=float, default=0.0,
                       help='probability per sample of a board-side drop that the board flags')
    fault.add_argument('--drop-unflagged-rate', type=float, default=0.0,
                       help='probability per sample of a silent drop (only the counter shows it)')
    fault.add_argument(
        '--fifo-overrun-rate', type=float, default=0.0,
        help='probability per sample slot of a sensor FIFO overrun (1-32 samples lost in the '
        'sensor, invisible to seq, next sample flagged FIFO_OVERRUN; at most one per frame)')
    fault.add_argument('--disconnect-after', type=int,
                       help='unplug once after this many samples sent')
    fault.add_argument('--disconnect-every-s', type=float,
                       help='unplug after every this many seconds connected')
    fault.add_argument('--unplug-s', type=float, default=1.0, help='how long an unplug lasts (s)')


def board_from_args(args: 'argparse.Namespace | list[str]') -> BoardModel:
    """
    Build the BoardModel that ``portenta_emulator`` with these arguments runs.

    Parameters
    ----------
    args : argparse.Namespace or list of str
        Parsed arguments, or a command line (without the program name).

    Returns
    -------
    BoardModel
        Same seed and options give the same samples, sample for sample.

    """
    if not isinstance(args, argparse.Namespace):
        args = build_parser().parse_args(list(args))
    helium = None
    if np.any(np.asarray(args.helium_amplitude_dps) != 0):
        helium = HeliumTransient(amplitude_dps=args.helium_amplitude_dps,
                                 delay_s=args.helium_delay_s, tau_s=args.helium_tau_s)
    vibration = None
    if args.vibration_hz > 0:
        vibration = Vibration(frequency_hz=args.vibration_hz, amplitude_dps=args.vibration_dps,
                              accel_amplitude_g=args.vibration_g)
    scenario = scenario_from_args(args)
    # with a scenario the specific force comes from its motion (gravity follows the attitude)
    extra: dict[str, Any] = ({} if scenario is None else
                             {'scenario': scenario, 'accel_g': (0.0, 0.0, 0.0)})
    return BoardModel(rng=np.random.default_rng(args.seed), odr_hz=args.odr_hz,
                      gyro_fs_dps=args.gyro_fs_dps, accel_fs_g=args.accel_fs_g, alpha=args.alpha,
                      f=args.f, noise_std_dps=args.noise_std_dps, bias_dps=args.bias_dps,
                      temperature_c=args.temp_c, temp_drift_c_per_h=args.temp_drift_c_per_h,
                      temp_sensitivity_dps_per_c=args.temp_sensitivity_dps_per_c, helium=helium,
                      vibration=vibration, clock_ppm=args.clock_ppm, seq0=args.seq0,
                      t0_us=args.t0_us, thermal=thermal_from_args(args), **extra)


def _check_args(args: argparse.Namespace) -> None:
    if args.speed <= 0 or not np.isfinite(args.speed):
        raise ParameterError(f'--speed must be > 0, got {args.speed}')
    if not 1 <= args.batch <= MAX_SAMPLES_PER_FRAME:
        raise ParameterError(f'--batch must be in 1..{MAX_SAMPLES_PER_FRAME}, got {args.batch}')
    if args.samples is not None and args.samples < 0:
        raise ParameterError(f'--samples must be >= 0, got {args.samples}')
    if args.duration_s is not None and not args.duration_s >= 0:
        raise ParameterError(f'--duration-s must be >= 0, got {args.duration_s}')
    if args.write_sd and args.samples is None and args.duration_s is None:
        raise ParameterError('--write-sd needs --samples or --duration-s')
    if not 0 <= args.fifo_overrun_rate < 1:
        raise ParameterError(
            f'--fifo-overrun-rate must be in [0, 1), got {args.fifo_overrun_rate}')
    if args.tx_buffer_bytes < 4096:
        raise ParameterError(f'--tx-buffer-bytes must be >= 4096, got {args.tx_buffer_bytes}')
    if args.unplug_s < 0:
        raise ParameterError(f'--unplug-s must be >= 0, got {args.unplug_s}')
    if args.disconnect_every_s is not None and not args.disconnect_every_s > 0:
        raise ParameterError(f'--disconnect-every-s must be > 0, got {args.disconnect_every_s}')
    compress = args.thermal_compress
    if args.thermal != 'off' and not (np.isfinite(compress) and compress > 0):
        raise ParameterError(f'--thermal-compress must be > 0, got {args.thermal_compress}')
    for option, path in (('--truth-out', args.truth_out), ('--stats-out', args.stats_out)):
        if path is None:
            continue
        if Path(path).is_dir():
            raise OutputError(f'{option} {path!r} is a folder, not a file')
        if not Path(path).parent.is_dir():
            raise OutputError(f'{option} {path!r}: its folder does not exist')
    if args.tcp and args.write_sd:
        raise ParameterError('--tcp and --write-sd exclude each other')
    if args.link and (args.tcp or args.write_sd):
        raise ParameterError('--link applies to the pseudo-terminal only')


def _write_sd(args: argparse.Namespace, board: BoardModel, faults: FaultInjector,
              truth_fh: BinaryIO | None, counters: Counters) -> int:
    total = total_samples(args.samples, args.duration_s, board.odr_hz)
    assert total is not None  # _check_args: --write-sd needs --samples or --duration-s
    options = SdOptions(out_dir=args.write_sd, total=total,
                        sequence_id=args.sequence_id, max_file_bytes=args.sd_file_bytes,
                        batch=args.batch, rtc_unix_s=args.rtc_unix_s,
                        corrupt=args.corrupt_rate > 0, overruns=args.fifo_overrun_rate > 0)
    for path in write_sd_logs(board, faults, counters, truth_fh, options):
        print(path, flush=True)
    return 0


def _serve(args: argparse.Namespace, board: BoardModel, faults: FaultInjector,
           truth_fh: BinaryIO | None, counters: Counters, stopper: Stopper) -> int:
    options = ServeOptions(
        tcp=args.tcp, link=args.link, speed=args.speed, batch=args.batch,
        tx_buffer_bytes=args.tx_buffer_bytes,
        total=total_samples(args.samples, args.duration_s, board.odr_hz),
        disconnect_after=args.disconnect_after, disconnect_every_s=args.disconnect_every_s,
        unplug_s=args.unplug_s)
    # a twin board warms the numba kernels up before the pacing clock starts: a JIT stall would
    # come out as a burst
    return serve(board, faults, options, counters=counters, stopper=stopper, truth_fh=truth_fh,
                 warm=board_from_args(args), on_port=lambda name: print(name, flush=True))


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    _check_args(args)
    board = board_from_args(args)
    faults = FaultInjector(np.random.default_rng(args.seed + 1),
                           drop_flagged_rate=args.drop_flagged_rate,
                           drop_unflagged_rate=args.drop_unflagged_rate,
                           corrupt_rate=args.corrupt_rate,
                           fifo_overrun_rate=args.fifo_overrun_rate)
    counters = Counters()
    stopper = Stopper()
    old = {sig: signal.signal(sig, stopper) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        truth_fh = open(args.truth_out, 'ab') if args.truth_out else None
    except OSError as err:
        raise OutputError(f'--truth-out {args.truth_out!r} cannot be written: '
                          f'{err.strerror or err}') from err
    try:
        if args.write_bag or args.write_sd:
            try:
                if args.write_bag:
                    code = write_bag(args, board, truth_fh, counters)
                else:
                    code = _write_sd(args, board, faults, truth_fh, counters)
            except OSError as err:  # an SD file, the bag or the truth log: nothing is read
                where = f' ({err.filename})' if err.filename else ''
                raise OutputError(f'cannot write: {err.strerror or err}{where}') from err
        else:
            code = _serve(args, board, faults, truth_fh, counters, stopper)
    finally:
        if truth_fh is not None:
            truth_fh.close()
        for sig, handler in old.items():
            signal.signal(sig, handler)
        if counters.samples_generated or sys.exc_info()[0] is None:
            # (a refusal before the first sample says only its one error line)
            line = stats_line(counters, faults, board)
            if args.stats_out:
                atomic_write_text(args.stats_out, line + '\n')
            print(f'{PROG}: {line}', file=sys.stderr, flush=True)
    return code


def main(argv: list[str] | None = None) -> int:
    """
    Run portenta_emulator.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.

    """
    return run_cli(PROG, _body, argv, renamed=RENAMED)


__all__ = ['main', 'build_parser', 'board_from_args', 'TRUTH_DTYPE']

if __name__ == '__main__':
    sys.exit(main())
