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
gyro_noise_import: convert the SD-card log files of one Portenta sequence into a rosbag2.

Reads the files in (sequence, file index) order from their headers, streams them through the link
decoder in constant memory, scales to SI with the configuration in force (file headers and ACK
frames, or ``--gyro-fs-dps``/``--accel-fs-g`` which override both), and writes ``sensor_msgs/Imu``
(every sample) and ``sensor_msgs/Temperature`` (decimated to ``--temperature-rate-hz``); the
workflow is :func:`gyro_noise_ros.app.importer.import_logs`. Corrupt regions are skipped and
reported, never fatal.

Stamps are the unwrapped 32-bit microsecond device clock anchored by ``--start-time``: ``auto``
(default: ``rtc`` when a header carries an RTC time, else ``zero``), ``rtc`` (the header's
``rtc_unix_s`` is the host time of its ``t_us``), ``zero`` (first sample at 0 s) or a UNIX time
(s) of the first sample. Bag time (the storage's receive time) equals the header stamp.

The bag is built under a hidden name beside ``--out`` and renamed when it is complete, so an
interrupted or failed import leaves nothing that looks like a bag. A log file given twice, or
files holding the same samples, are refused before anything is written. Details:
docs/portenta_link.md.

Example::

    gyro_noise_import /media/sd/S001F*.GNL --out seq1_bag --storage mcap
"""

import argparse
import os
import sys

from ._common import add_overwrite_argument, OVERWRITE_BAG_HELP, run_cli
from ..app.importer import import_logs, ImportReport, TEMPERATURE_ODR_HZ

PROG = 'gyro_noise_import'


def format_report(rep: ImportReport, *, max_regions: int = 20) -> str:
    """
    Return the human-readable import report.

    Parameters
    ----------
    rep : ImportReport
        The import report.
    max_regions : int, keyword-only
        Corrupt regions listed (all are counted).

    Returns
    -------
    str

    """
    lines = [f'{PROG}: sequence {rep.sequence_id}, {len(rep.files)} file(s) -> {rep.bag} '
             f'({rep.storage})']
    for info in rep.files:
        head = info.header
        desc = (f'file {head.file_index}, first seq {head.first_seq}' if head is not None
                else 'header unreadable')
        lines.append(f'  {os.path.basename(info.path)}  {info.size_bytes} bytes  {desc}')
    total = rep.samples_written + rep.samples_lost
    pct = 100.0 * rep.samples_lost / total if total else 0.0
    first_ns, last_ns = rep.first_stamp_ns, rep.last_stamp_ns
    assert first_ns is not None and last_ns is not None  # an import writes samples or fails
    span = (last_ns - first_ns) / 1e9
    lines += [
        f'samples written        {rep.samples_written}',
        f'samples lost           {rep.samples_lost} ({pct:.4f} %; {rep.samples_flagged_lost} '
        'flagged by the board)', f'temperature messages   {rep.temperature_written}',
        f'CRC errors             {rep.crc_errors}', f'resyncs                {rep.resyncs}',
        f'bytes discarded        {rep.bytes_discarded}',
        f'truncated frames       {rep.frames_truncated}',
        f'time jumps             {rep.time_jumps}',
        f'missing files          {", ".join(map(str, rep.missing_file_indices)) or "none"}',
        f'stamps                 {first_ns / 1e9:.6f} s .. '
        f'{last_ns / 1e9:.6f} s ' f'({span:.3f} s, epoch {rep.epoch})',
        'scaling                ' + '; '.join(f'gyro +/-{g} dps, accel +/-{a} g, ODR {o} Hz' for g,
                                              a, o in rep.configurations),
        f'corrupt regions        {rep.corrupt_region_count}',]
    for region in rep.corrupt_regions[:max_regions]:
        lines.append(
            f'  {os.path.basename(region.path)} @ {region.offset} (+{region.length} bytes)')
    if rep.corrupt_region_count > max_regions:
        lines.append(f'  ... {rep.corrupt_region_count - max_regions} more')
    return '\n'.join(lines)


def build_parser() -> argparse.ArgumentParser:
    """
    Return the argument parser of gyro_noise_import.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split('\n\n')[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument('logs', nargs='+', metavar='LOG', help='SD log files of one sequence')
    p.add_argument('--out', required=True, help='bag directory to create')
    add_overwrite_argument(p, OVERWRITE_BAG_HELP)
    p.add_argument('--storage', choices=('mcap', 'sqlite3'), default='mcap',
                   help='rosbag2 storage (mcap: fastest, rosbag2 default; see docs/scale.md)')
    p.add_argument('--topic', default='imu/data_raw', help='Imu topic')
    p.add_argument('--temperature-topic', default='imu/temperature', help='Temperature topic')
    p.add_argument('--frame-id', default='imu_link')
    p.add_argument('--gyro-fs-dps', type=int, help='force the gyro full scale (deg/s)')
    p.add_argument('--accel-fs-g', type=int, help='force the accelerometer full scale (g)')
    p.add_argument('--start-time', default='auto',
                   help='auto, rtc, zero, or UNIX seconds of the first sample')
    p.add_argument('--temperature-rate-hz', type=float, default=TEMPERATURE_ODR_HZ,
                   help='Temperature messages per second (0: none)')
    p.add_argument('--angular-velocity-variance', type=float, default=0.0,
                   help='(rad/s)^2, 0 = unknown')
    p.add_argument('--linear-acceleration-variance', type=float, default=0.0,
                   help='(m/s^2)^2, 0 = unknown')
    p.add_argument('--temperature-variance', type=float, default=0.0, help='degC^2, 0 = unknown')
    p.add_argument('--chunk-bytes', type=int, default=1 << 20, help='read size (bytes)')
    p.add_argument('--threads', choices=('auto', '1', '2'), default='auto',
                   help='2: a second thread writes the bag while the next blocks are decoded; '
                        '1: one thread, the least CPU; auto: 2 when two CPUs are usable')
    return p


def _body(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    rep = import_logs(args.logs, args.out, storage=args.storage, topic=args.topic,
                      temperature_topic=args.temperature_topic, frame_id=args.frame_id,
                      gyro_fs_dps=args.gyro_fs_dps, accel_fs_g=args.accel_fs_g,
                      start_time=args.start_time, temperature_rate_hz=args.temperature_rate_hz,
                      angular_velocity_variance=args.angular_velocity_variance,
                      linear_acceleration_variance=args.linear_acceleration_variance,
                      temperature_variance=args.temperature_variance, chunk_bytes=args.chunk_bytes,
                      threads=None if args.threads == 'auto' else int(args.threads),
                      overwrite=args.overwrite)
    print(format_report(rep), flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    """
    Run gyro_noise_import on ``argv`` (without the program name); return the exit status.

    0 (also with corrupt regions skipped); 2 a bad option or a log file named twice; 3 a log file
    missing; 4 logs that are not one sequence or hold no valid sample; 6 ``--out`` exists (without
    ``--overwrite``) or the bag cannot be written; 130/143 interrupted. Whatever the failure, no
    bag is left under ``--out`` and an existing one is kept.

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
