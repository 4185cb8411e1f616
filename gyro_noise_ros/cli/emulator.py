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

Exit status (``errors.EXIT_CODES``): 0 at the end of ``--samples``/``--duration-s``; 130/143 on
SIGINT/SIGTERM (the statistics line, then ``interrupted``; the SD logs and the bag stop within a
block of 65,536 samples and leave nothing under their final names); 2 a bad option (a length of
no sample, or one that cannot fit on the disk); 5 the link cannot be served; 6 an output cannot
be written, or exists without ``--overwrite``.
"""

import argparse
from pathlib import Path
import signal
import sys
from typing import Any, BinaryIO

import numpy as np

from ._common import add_overwrite_argument, check_fits_disk, finite_float, run_cli
from ._scenario import (add_scenario_arguments, scenario_from_args, THERMAL_CHOICES,
                        thermal_from_args, write_bag)
from ..errors import Interrupted, OutputError, ParameterError
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
from ..link.protocol import encode_samples, MAX_SAMPLES_PER_FRAME, SAMPLE_DTYPE
from ..link.sdlog import FAT32_MAX_FILE_BYTES
from ..link.serve import (Counters, SdOptions, serve, ServeOptions, stats_line, Stopper,
                          total_samples, TX_BUFFER_BYTES, write_sd_logs)
from ..outputs import atomic_write_text, check_new_dir, check_new_file, check_out_dir

PROG = 'portenta_emulator'
#: OUT_TEMP is an int16 word at 256 LSB/degC around 25 degC: the die temperatures the board can
#: report (degC); --temp-c outside would be clipped to a false value.
TEMP_RANGE_C = (lsm.TEMPERATURE_OFFSET_C - 32768 / lsm.TEMPERATURE_LSB_PER_C,
                lsm.TEMPERATURE_OFFSET_C + 32767 / lsm.TEMPERATURE_LSB_PER_C)
#: Options not named after the parameter they set (errors name parameters: cli/_common).
RENAMED = {'out_dir': '--write-sd'}


def _float_list(text: str) -> float | tuple[float, ...]:
    try:
        values = [finite_float(v) for v in text.split(',')]
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(
            f'expected a number or three comma-separated finite numbers, got {text!r}') from err
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
    add_overwrite_argument(out, 'write into a --write-sd folder that is not empty (the '
                           "sequence's old log files are replaced, other files kept), replace an "
                           'existing --write-bag bag or --stats-out file (without it they are '
                           'refused, exit 6)')


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Add the seed, the pace and the length of the run."""
    run = p.add_argument_group('run')
    run.add_argument('--seed', type=int, default=0,
                     help='seed of the sample streams (faults use seed+1)')
    run.add_argument('--speed', type=finite_float, default=1.0,
                     help='pace at this multiple of real time')
    run.add_argument('--samples', type=int, help='stop after this many samples')
    run.add_argument('--duration-s', type=finite_float, help='stop after this much board time (s)')
    run.add_argument('--batch', type=int, default=16, help='samples per frame (FIFO watermark)')
    run.add_argument('--tx-buffer-bytes', type=int, default=TX_BUFFER_BYTES,
                     help='board transmit buffer; samples that do not fit are dropped and flagged')


def _add_configuration_arguments(p: argparse.ArgumentParser) -> None:
    """Add the board's power-on configuration."""
    cfg = p.add_argument_group('power-on configuration')
    cfg.add_argument('--odr-hz', type=finite_float, default=6667.0, help=f'one of {lsm.ODRS_HZ}')
    cfg.add_argument('--gyro-fs-dps', type=int, default=2000,
                     help=f'one of {lsm.GYRO_FULL_SCALES_DPS}')
    cfg.add_argument('--accel-fs-g', type=int, default=4, help=f'one of {lsm.ACCEL_FULL_SCALES_G}')
    cfg.add_argument('--seq0', type=int, default=0, help='first sequence number (wrap tests)')
    cfg.add_argument('--t0-us', type=int, default=0,
                     help='device time at power-on (us, wrap tests)')
    cfg.add_argument('--clock-ppm', type=finite_float, default=0.0, help='board clock error (ppm)')


def _add_sensor_arguments(p: argparse.ArgumentParser) -> None:
    """Add the sensor model: noise, bias, temperature, vibration."""
    noise = p.add_argument_group('sensor model')
    noise.add_argument('--alpha', type=finite_float, default=DEFAULT_ALPHA,
                       help='fractional order (paper 000 eq. 2)')
    noise.add_argument('--f', type=finite_float, default=DEFAULT_F,
                       help='noise parameter f (paper 000 eq. 2)')
    noise.add_argument('--noise-std-dps', type=finite_float, default=PAPER_NOISE_STD_DPS,
                       help='stationary gyro noise standard deviation (deg/s)')
    noise.add_argument('--bias-dps', type=_float_list, default=DEFAULT_BIAS_DPS,
                       help='gyro bias x,y,z (deg/s)')
    noise.add_argument('--temp-c', type=finite_float, default=25.0,
                       help='die temperature at power-on (degC)')
    noise.add_argument('--temp-drift-c-per-h', type=finite_float, default=0.0,
                       help='temperature ramp (degC/h)')
    noise.add_argument('--temp-sensitivity-dps-per-c', type=_float_list, default=0.0,
                       help='gyro bias change per degC (deg/s/degC)')
    noise.add_argument('--helium-amplitude-dps', type=_float_list, default=0.0,
                       help='helium-like bias rise, final value (deg/s); 0 = off')
    noise.add_argument('--helium-delay-s', type=finite_float, default=5400.0,
                       help='delay before the rise (s)')
    noise.add_argument('--helium-tau-s', type=finite_float, default=7200.0,
                       help='time constant of the rise (s)')
    noise.add_argument('--thermal', choices=THERMAL_CHOICES, default='off',
                       help='the thermal model of docs/thermal_data.md (die lag, bias from '
                            'temperature and its rate, hysteresis, accelerometer offset) with '
                            'an oven profile: oven (paper 002, from --temp-c), heating, '
                            'cooling, staircase, staircase_down, cycle, cool_reheat, soak, '
                            'sine; replaces --temp-drift-c-per-h and '
                            '--temp-sensitivity-dps-per-c')
    noise.add_argument('--thermal-compress', type=finite_float, default=60.0,
                       help='run the thermal profile this many times faster (the ~14 h oven '
                            'in 14 min at 60)')
    noise.add_argument('--vibration-hz', type=finite_float, default=0.0,
                       help='sinusoidal vibration frequency (Hz)')
    noise.add_argument('--vibration-dps', type=_float_list, default=0.0,
                       help='vibration rate amplitude (deg/s)')
    noise.add_argument('--vibration-g', type=_float_list, default=0.0,
                       help='vibration accel amplitude (g)')


def _add_fault_arguments(p: argparse.ArgumentParser) -> None:
    """Add the faults injected into the link and the samples."""
    fault = p.add_argument_group('fault injection')
    fault.add_argument('--corrupt-rate', type=finite_float, default=0.0,
                       help='probability per byte sent/written')
    fault.add_argument('--drop-flagged-rate', type=finite_float, default=0.0,
                       help='probability per sample of a board-side drop that the board flags')
    fault.add_argument('--drop-unflagged-rate', type=finite_float, default=0.0,
                       help='probability per sample of a silent drop (only the counter shows it)')
    fault.add_argument(
        '--fifo-overrun-rate', type=finite_float, default=0.0,
        help='probability per sample slot of a sensor FIFO overrun (1-32 samples lost in the '
        'sensor, invisible to seq, next sample flagged FIFO_OVERRUN; at most one per frame)')
    fault.add_argument('--disconnect-after', type=int,
                       help='unplug once after this many samples sent')
    fault.add_argument('--disconnect-every-s', type=finite_float,
                       help='unplug after every this many seconds connected')
    fault.add_argument('--unplug-s', type=finite_float, default=1.0,
                       help='how long an unplug lasts (s)')


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
    if args.speed <= 0:
        raise ParameterError(f'--speed must be > 0, got {args.speed}')
    _check_integers(args)
    if not 1 <= args.batch <= MAX_SAMPLES_PER_FRAME:
        raise ParameterError(f'--batch must be in 1..{MAX_SAMPLES_PER_FRAME}, got {args.batch}')
    if args.samples is not None and args.samples < 1:
        raise ParameterError(f'--samples must be >= 1, got {args.samples}')
    if args.duration_s is not None and not args.duration_s > 0:
        raise ParameterError(f'--duration-s must be > 0, got {args.duration_s}')
    if args.duration_s is not None and round(args.duration_s * args.odr_hz) < 1:
        raise ParameterError(f'--duration-s {args.duration_s:g} s holds no sample at --odr-hz '
                             f'{args.odr_hz:g}')
    if not TEMP_RANGE_C[0] <= args.temp_c <= TEMP_RANGE_C[1]:
        raise ParameterError(f'--temp-c must be in {TEMP_RANGE_C[0]:.1f}..{TEMP_RANGE_C[1]:.1f} '
                             f'degC (what OUT_TEMP can report), got {args.temp_c:g}')
    if args.write_sd and args.write_bag:
        raise ParameterError('--write-sd and --write-bag exclude each other: run the emulator '
                             'once for each')
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
    if args.thermal != 'off' and not args.thermal_compress > 0:
        raise ParameterError(f'--thermal-compress must be > 0, got {args.thermal_compress}')
    if args.tcp and args.write_sd:
        raise ParameterError('--tcp and --write-sd exclude each other')
    if args.link and (args.tcp or args.write_sd):
        raise ParameterError('--link applies to the pseudo-terminal only')
    _check_outputs(args)


def _check_integers(args: argparse.Namespace) -> None:
    """Refuse integers outside what the seed, the wire and the SD file names can hold."""
    for option, value, top in (('--seed', args.seed, None), ('--seq0', args.seq0, 2**32 - 1),
                               ('--t0-us', args.t0_us, 2**32 - 1),
                               # SD names are 8.3: S<sss>F<fff>.GNL holds three digits
                               ('--sequence-id', args.sequence_id, 999),
                               ('--disconnect-after', args.disconnect_after, None)):
        if value is not None and not (value >= 0 and (top is None or value <= top)):
            limit = f'0..{top}' if top is not None else '>= 0'
            raise ParameterError(f'{option} must be {limit}, got {value}')


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse outputs that cannot be written or hold data, before the first sample."""
    for option, value in (('--write-sd', args.write_sd), ('--write-bag', args.write_bag),
                          ('--truth-out', args.truth_out), ('--stats-out', args.stats_out)):
        if value is not None and not value.strip():  # '' would read as "not given"
            raise OutputError(f'{option} is empty: give a name')
    if args.truth_out is not None:
        # --truth-out appends (documented): an existing file is extended, never replaced
        if Path(args.truth_out).is_dir():
            raise OutputError(f'--truth-out {args.truth_out!r} is a folder, not a file')
        if not Path(args.truth_out).parent.is_dir():
            raise OutputError(f'--truth-out {args.truth_out!r}: its folder does not exist')
    if args.stats_out is not None:
        check_new_file(args.stats_out, parameter='stats_out', overwrite=args.overwrite)
    if args.write_sd:
        check_out_dir(args.write_sd, parameter='write_sd', overwrite=args.overwrite)
    if args.write_bag:
        check_new_dir(args.write_bag, parameter='write_bag', overwrite=args.overwrite)


def _write_sd(args: argparse.Namespace, board: BoardModel, faults: FaultInjector,
              truth_fh: BinaryIO | None, counters: Counters, stopper: Stopper) -> int:
    total = total_samples(args.samples, args.duration_s, board.odr_hz)
    assert total is not None  # _check_args: --write-sd needs --samples or --duration-s
    frame = len(encode_samples(np.zeros(args.batch, SAMPLE_DTYPE)))
    size = f'--samples {args.samples}' if args.duration_s is None else (
        f'--duration-s {args.duration_s:g}')
    check_fits_disk(args.write_sd, total * frame / args.batch, size)
    if args.truth_out:
        check_fits_disk(args.truth_out, total * TRUTH_DTYPE.itemsize, f'{size} --truth-out')
    options = SdOptions(out_dir=args.write_sd, total=total,
                        sequence_id=args.sequence_id, max_file_bytes=args.sd_file_bytes,
                        batch=args.batch, rtc_unix_s=args.rtc_unix_s,
                        corrupt=args.corrupt_rate > 0, overruns=args.fifo_overrun_rate > 0,
                        overwrite=args.overwrite)
    for path in write_sd_logs(board, faults, counters, truth_fh, options, stopper):
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
                    code = write_bag(args, board, truth_fh, counters, stopper)
                else:
                    code = _write_sd(args, board, faults, truth_fh, counters, stopper)
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
    if stopper.signum is not None and not (args.write_bag or args.write_sd):
        raise Interrupted(stopper.signum)  # the serving loop ended on SIGINT/SIGTERM
    return code


def main(argv: list[str] | None = None) -> int:
    """
    Run portenta_emulator; return its exit status.

    ``argv`` holds the arguments without the program name (None: ``sys.argv[1:]``).

    """
    return run_cli(PROG, _body, argv, renamed=RENAMED)


__all__ = ['main', 'build_parser', 'board_from_args', 'TRUTH_DTYPE']

if __name__ == '__main__':
    sys.exit(main())
