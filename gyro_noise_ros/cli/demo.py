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
``make demo``: the whole story on one machine, from an emulated board to the offline report.

``python -m gyro_noise_ros.cli.demo --out demo_out [--quick]`` starts, as subprocesses on a private
``ROS_DOMAIN_ID``:

1. ``noise_analyzer`` (live analysis, diagnostics), ``gyro_noise_record`` (the bag), the
   diagnostics monitor (``gyro_noise_monitor``) and ``lsm6dso32_driver`` (which retries its port
   until the board is there);
2. ``portenta_emulator`` on a loopback TCP port, seeded, with a scripted helium-like bias
   transient: a quiet phase, then a first-order rise of the bias of every axis;

prints the analyzer's diagnostics as they arrive (one line per chunk: level, bias, drift and orders
per axis; the message of any axis that is not OK), and checks the story: the verdict is OK in the
quiet phase and turns WARN (offset drift above its limit) when the bias rises. It then stops the
live part (driver first, so the recorder and analyzer take the last messages, then recorder,
analyzer, monitor, emulator), runs ``gyro_noise_analyze`` on the recording, and ends by printing
where the tables and figures are.

Demo settings, and why (every one is an ordinary parameter of the tools):

- The board runs at real time (``--speed 1``) and the transient is compressed instead (seconds, not
  the paper's hours): the driver maps device time onto host time, so at ``--speed k`` the stamps
  would run k times fast and every rate-dependent number would be off by k; and five processes at
  6.66 kHz already take about one of the two cores. ``--speed`` is available for faster machines.
- Drift is judged by absolute limits over the last ``history_chunks`` chunks (a sliding window, so
  the verdict follows the transient): WARN above 1 (deg/s)/h, ERROR above 100 (deg/s)/h. The
  emulated quiet bias drifts by a few hundredths of (deg/s)/h; the scripted rise starts at
  ``amplitude / tau`` = 6 (deg/s)/h (36 in ``--quick``).
- Samples lost: WARN above 5 %, ERROR above 25 % of the expected samples (the tools' defaults are
  0.01 % and 1 %). On a busy shared machine the DDS transport drops some messages when a receiving
  process is not scheduled for tens of milliseconds; the losses are still counted and printed, but
  they should not hide the drift story. ``docs/demo.md`` explains how to read them.

Exit status: 0 when the story ran and the report was written; 1 when a component failed (its log
is named) or the drift was not detected; 2 for a bad option; 6 when ``--out`` cannot be used (a
file, a folder that is not a previous demo output, not writable); 130 on Ctrl-C. Every subprocess
is stopped on every path. ``GYRO_NOISE_DEMO.txt`` in ``--out`` says whether the run finished; the
report folder appears only complete (``gyro_noise_analyze`` stages its files).
"""

import argparse
from dataclasses import dataclass
import os
from pathlib import Path
import queue
import random
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

from ._common import check_out_option, run_cli
from ..errors import GyroNoiseError, OutputError, ParameterError
from ..monitor_lines import parse_axis_parts
from ..outputs import atomic_write_text

PROG = 'gyro_noise_demo'
_MARKER = 'GYRO_NOISE_DEMO.txt'


class DemoError(GyroNoiseError):
    """A component of the demo failed (message names it and its log)."""

    exit_code = 1


@dataclass(frozen=True)
class Story:
    """
    Timing and thresholds of one demo run.

    Attributes
    ----------
    quiet_s : float
        Board time before the helium-like rise starts (s).
    tau_s : float
        Time constant of the rise (s).
    amplitude_dps : float
        Final bias change of every axis (deg/s).
    live_s : float
        How long the live part runs once the driver streams (s).
    history_chunks : int
        Sliding window of the analyzer's sequence statistics (chunks).
    chunk_size : int
        Samples per chunk.

    """

    quiet_s: float
    tau_s: float
    amplitude_dps: float
    live_s: float
    history_chunks: int
    chunk_size: int = 10000


FULL = Story(quiet_s=40.0, tau_s=60.0, amplitude_dps=0.1, live_s=100.0, history_chunks=20)
QUICK = Story(quiet_s=14.0, tau_s=10.0, amplitude_dps=0.1, live_s=32.0, history_chunks=8)

DEMO_ANALYZER_PARAMS = {
    'drift_abs_warn_deg_s_per_h': 1.0,
    'drift_abs_error_deg_s_per_h': 100.0,
    'lost_fraction_warn': 0.05,
    'lost_fraction_error': 0.25,
    'analysis_queue_chunks': 20,
    'hardware_id': 'lsm6dso32@portenta_emulator',
}


def build_parser():
    """
    Return the argument parser of the demo.

    Returns
    -------
    argparse.ArgumentParser

    """
    p = argparse.ArgumentParser(prog=PROG, description='Emulated board -> driver -> live analyzer '
                                'and recorder -> offline report, with a helium-like bias '
                                'transient.')
    p.add_argument('--out', default='demo_out', metavar='DIR',
                   help='output directory (created; a previous demo output there is replaced)')
    p.add_argument('--quick', action='store_true', help='short story (about 1 minute) for tests')
    p.add_argument('--seed', type=int, default=1, help='seed of the emulated sensor')
    p.add_argument('--speed', type=float, default=1.0,
                   help='emulator pace as a multiple of real time (see the module doc before '
                   'raising it)')
    p.add_argument('--storage', default='sqlite3', choices=('sqlite3', 'mcap'), help='bag storage')
    p.add_argument('--jobs', type=int, default=2, help='worker processes of the offline analysis')
    p.add_argument('--domain-id', type=int, default=None,
                   help='ROS_DOMAIN_ID (default: random 100..200)')
    return p


def _free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def _prepare_out(out):
    out = Path(out)
    check_out_option(out)
    if out.exists() and any(out.iterdir()) and not (out / _MARKER).exists():
        raise OutputError(
            f'--out {str(out)!r} exists and is not a previous demo output; choose another')
    try:
        for name in ('recording', 'report', 'logs'):
            if (out / name).is_dir():
                shutil.rmtree(out / name)
            elif (out / name).exists():
                (out / name).unlink()
        (out / 'logs').mkdir(parents=True, exist_ok=True)
        _mark(out, finished=False)
    except OSError as err:
        raise OutputError(f'--out {str(out)!r} cannot be prepared: {err.strerror or err}') from err
    return out


def _mark(out, *, finished):
    """Say in the marker file whether the demo output is complete (a stopped run is not)."""
    state = ('finished: the report is complete' if finished else
             'NOT FINISHED: a run is going on, or was stopped or failed')
    atomic_write_text(out / _MARKER, f'Written by gyro_noise_ros.cli.demo; {state}. The next '
                      'demo run replaces this directory.\n')


class Processes:
    """
    The demo's subprocesses: start, watch, stop in order, always clean up.

    Each child runs in its own session so a Ctrl-C at the terminal reaches only the demo, which
    then stops the children in a sensible order instead of all at once.
    """

    def __init__(self, env, log_dir):
        self.env = env
        self.log_dir = Path(log_dir)
        self.procs = {}
        self.logs = {}
        self.stopping = set()

    def start(self, name, args, *, capture_stdout=False):
        log = self.log_dir / f'{name}.log'
        fh = open(log, 'w')  # noqa: SIM115 - closed with the process in stop()
        stdout = subprocess.PIPE if capture_stdout else fh
        proc = subprocess.Popen([sys.executable, '-m', *args], env=self.env, stdout=stdout,
                                stderr=fh, stdin=subprocess.DEVNULL, start_new_session=True,
                                text=True, bufsize=1)
        self.procs[name] = (proc, fh)
        self.logs[name] = log
        return proc

    def log_text(self, name):
        try:
            return self.logs[name].read_text(errors='replace')
        except OSError:
            return ''

    def last_lines(self, name, n=3):
        lines = [ln for ln in self.log_text(name).splitlines() if ln.strip()]
        return ' | '.join(lines[-n:]) if lines else '(empty log)'

    def check(self):
        """Raise DemoError if a process not being stopped has exited."""
        for name, (proc, _) in self.procs.items():
            if name not in self.stopping and proc.poll() is not None:
                raise DemoError(f'{name} exited with code {proc.returncode}; log '
                                f'{self.logs[name]}: {self.last_lines(name)}')

    def wait_for_log(self, name, pattern, timeout_s, what):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self.check()
            if re.search(pattern, self.log_text(name)):
                return
            time.sleep(0.2)
        raise DemoError(f'{name}: no sign of {what} after {timeout_s:.0f} s; log '
                        f'{self.logs[name]}: {self.last_lines(name)}')

    def stop(self, name, timeout_s=15.0):
        """SIGINT one process and wait; SIGKILL if it does not stop. Return its exit code."""
        entry = self.procs.get(name)
        if entry is None:
            return None
        proc, fh = entry
        self.stopping.add(name)
        if proc.poll() is None:
            try:
                proc.send_signal(signal.SIGINT)
                proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=10)
            except ProcessLookupError:
                pass
        fh.close()
        return proc.returncode

    def stop_all(self, order):
        for name in [*order, *[n for n in self.procs if n not in order]]:
            try:
                self.stop(name)
            except Exception:  # noqa: BLE001 - cleanup must reach every process
                entry = self.procs.get(name)
                if entry and entry[0].poll() is None:
                    entry[0].kill()


def _ros_args(params):
    out = ['--ros-args']
    for key, value in params.items():
        text = ('true' if value else 'false') if isinstance(value, bool) else str(value)
        out += ['-p', f'{key}:={text}']
    return out


def _reader(stream, lines):
    for line in iter(stream.readline, ''):
        lines.put(line.rstrip('\n'))
    lines.put(None)


def _body(argv):
    args = build_parser().parse_args(argv)
    story = QUICK if args.quick else FULL
    if not 0.1 <= args.speed <= 100:
        raise ParameterError(f'--speed must be in [0.1, 100], got {args.speed}')
    if args.domain_id is not None and not 0 <= args.domain_id <= 232:
        raise ParameterError(f'--domain-id must be a ROS_DOMAIN_ID in 0..232, got '
                             f'{args.domain_id}')
    if args.jobs < 1:
        raise ParameterError(f'--jobs must be >= 1, got {args.jobs}')
    out = _prepare_out(args.out)
    domain = args.domain_id if args.domain_id is not None else random.randint(100, 200)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED='1')
    port = _free_port()
    url = f'socket://127.0.0.1:{port}'
    procs = Processes(env, out / 'logs')

    # A SIGTERM to the demo gets the same orderly cleanup as Ctrl-C.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    t_start = time.monotonic()
    print(f'{PROG}: ROS_DOMAIN_ID={domain}; logs in {out / "logs"}', flush=True)
    warn_limit = DEMO_ANALYZER_PARAMS['drift_abs_warn_deg_s_per_h']
    error_limit = DEMO_ANALYZER_PARAMS['drift_abs_error_deg_s_per_h']
    print(f'{PROG}: story: {story.quiet_s:.0f} s quiet, then the bias of every axis rises by '
          f'{story.amplitude_dps} deg/s with a time constant of {story.tau_s:.0f} s '
          f'(initial drift {story.amplitude_dps / story.tau_s * 3600:.0f} (deg/s)/h); live part '
          f'{story.live_s:.0f} s; drift limits WARN {warn_limit:g} / ERROR {error_limit:g} '
          f'(deg/s)/h over the last {story.history_chunks} chunks', flush=True)
    try:
        recording = out / 'recording'
        procs.start('noise_analyzer', ['gyro_noise_ros.nodes.analyzer', *_ros_args(
            {**DEMO_ANALYZER_PARAMS, 'history_chunks': story.history_chunks,
             'chunk_size': story.chunk_size})])
        procs.start('gyro_noise_record', ['gyro_noise_ros.nodes.recorder', *_ros_args(
            {'output': str(recording), 'storage': args.storage})])
        echo = procs.start('monitor', ['gyro_noise_ros.nodes.monitor', '--compact'],
                           capture_stdout=True)
        lines = queue.Queue()
        threading.Thread(target=_reader, args=(echo.stdout, lines), daemon=True).start()
        procs.start('lsm6dso32_driver', ['gyro_noise_ros.nodes.driver', *_ros_args({'port': url})])
        print(f'{PROG}: starting the nodes ...', flush=True)
        procs.wait_for_log('noise_analyzer', r'analysing ', 120, 'start-up')
        procs.wait_for_log('gyro_noise_record', r'recording ', 120, 'start-up')
        procs.wait_for_log('lsm6dso32_driver', r'\S', 120, 'start-up')
        # The monitor prints the analyzer's periodic (STALE) diagnostics once discovery is done.
        _wait_line(lines, procs, 120)
        procs.start('portenta_emulator', [
            'gyro_noise_ros.cli.emulator', '--tcp', f'127.0.0.1:{port}', '--seed', str(args.seed),
            '--speed', str(args.speed), '--helium-amplitude-dps', str(story.amplitude_dps),
            '--helium-delay-s', str(story.quiet_s), '--helium-tau-s', str(story.tau_s)])
        procs.wait_for_log('lsm6dso32_driver', r'streaming from', 120, 'the board streaming')
        t_stream = time.monotonic()
        print(f'{PROG}: the board is streaming ({time.monotonic() - t_start:.0f} s after start); '
              'diagnostics of noise_analyzer:', flush=True)
        seen = _live(lines, procs, story, args.speed, t_stream)
    except KeyboardInterrupt:
        print(f'\n{PROG}: interrupted; stopping every process', file=sys.stderr, flush=True)
        procs.stop_all(['lsm6dso32_driver', 'gyro_noise_record', 'noise_analyzer', 'monitor',
                        'portenta_emulator'])
        return 130
    except BaseException:
        procs.stop_all(['lsm6dso32_driver', 'gyro_noise_record', 'noise_analyzer', 'monitor',
                        'portenta_emulator'])
        raise
    finally:
        signal.signal(signal.SIGTERM, previous)

    # Orderly stop: no new data, let the last messages be taken, then close the bag.
    try:
        procs.stop('lsm6dso32_driver')
        time.sleep(1.0)
        rc = procs.stop('gyro_noise_record', timeout_s=60)
        record_line = next((ln for ln in procs.log_text('gyro_noise_record').splitlines()
                            if ln.startswith('gyro_noise_record: received')), '')
        if rc != 0 or not (recording / 'metadata.yaml').exists():
            raise DemoError(f'gyro_noise_record did not close the bag cleanly (exit {rc}); log '
                            f'{procs.logs["gyro_noise_record"]}: '
                            f'{procs.last_lines("gyro_noise_record")}')
        print(f'{PROG}: {record_line.split(": ", 1)[-1]}', flush=True)
    finally:
        procs.stop_all(['noise_analyzer', 'monitor', 'portenta_emulator'])

    _check_story(seen, story)

    report = out / 'report'
    print(f'{PROG}: offline analysis of the recording with gyro_noise_analyze ...', flush=True)
    cmd = [sys.executable, '-m', 'gyro_noise_ros.cli.analyze', str(recording), '--out',
           str(report), '--jobs', str(args.jobs), '--label', 'demo']
    try:
        done = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, timeout=900)
    except subprocess.TimeoutExpired as err:
        raise DemoError('gyro_noise_analyze took more than 15 minutes') from err
    if done.returncode == 130:
        raise KeyboardInterrupt
    if done.returncode != 0:
        raise DemoError(
            f'gyro_noise_analyze failed with exit code {done.returncode}: {" ".join(cmd)}')
    if not (report / 'summary.json').is_file():
        # never exit 0 having analysed nothing
        raise DemoError(f'gyro_noise_analyze exited 0 but wrote no {report / "summary.json"}')
    _mark(out, finished=True)
    _print_outputs(report, time.monotonic() - t_start)
    return 0


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def _next_line(lines, procs, deadline):
    """Return the monitor's next line, None at the deadline; raise if a process or it died."""
    while time.monotonic() < deadline:
        procs.check()
        try:
            line = lines.get(timeout=0.2)
        except queue.Empty:
            continue
        if line is None:
            raise DemoError('the diagnostics monitor stopped')
        return line
    return None


def _wait_line(lines, procs, timeout_s):
    line = _next_line(lines, procs, time.monotonic() + timeout_s)
    if line is None:
        raise DemoError(f'no diagnostics from noise_analyzer after {timeout_s:.0f} s '
                        f'(DDS discovery?); logs in {procs.log_dir}')
    return line


def _live(lines, procs, story, speed, t_stream):
    """Print the monitor's lines until the live part is over; return (elapsed_s, line) pairs."""
    seen = []
    end = t_stream + story.live_s / speed
    while True:
        line = _next_line(lines, procs, end)
        if line is None:
            break
        elapsed = (time.monotonic() - t_stream) * speed
        phase = 'quiet' if elapsed < story.quiet_s else 'rise '
        print(f'  [{elapsed:6.1f} s {phase}] {line}', flush=True)
        seen.append((elapsed, line))
    return seen


def _check_story(seen, story):
    """Check that after the rise began some axis was WARN or ERROR with its drift above limit."""
    chunk_lines = [(t, ln) for t, ln in seen if ' chunk ' in ln]
    if not chunk_lines:
        raise DemoError('the analyzer reported no chunk: did the driver publish? see the logs')
    rise = [ln for t, ln in chunk_lines if t >= story.quiet_s]
    quiet = [ln for t, ln in chunk_lines if t < story.quiet_s]
    limit = DEMO_ANALYZER_PARAMS['drift_abs_warn_deg_s_per_h']
    warned = [ln for ln in rise if any(level in ('WARN', 'ERROR') and drift > limit
                                       for _, level, drift in parse_axis_parts(ln))]
    if not warned:
        raise DemoError('the drift was not detected: no axis turned WARN with its drift above '
                        'the limit after the bias rose '
                        f'({len(rise)} chunk reports in the rise phase)')
    ok_quiet = sum(ln.startswith('OK') for ln in quiet)
    print(f'{PROG}: story checked: {ok_quiet} of {len(quiet)} quiet-phase reports OK; after the '
          f'rise began, {len(warned)} of {len(rise)} reports had an axis at WARN or worse with '
          f'its drift above {limit:g} (deg/s)/h', flush=True)


def _print_outputs(report, elapsed_s):
    names = ['report.html', 'summary.md', 'summary.json', 'chunks.csv', 'allan.csv', 'imu.yaml']
    print(f'\n{PROG}: done in {elapsed_s:.0f} s. Tables and figures:', flush=True)
    for name in names:
        path = report / name
        if path.exists():
            print(f'  {path}')
    for path in sorted(report.glob('*.png')):
        print(f'  {path}')
    print(f'  (open {report / "report.html"} first; docs/demo.md explains every number)',
          flush=True)


def main(argv=None):
    """
    Run the demo.

    Parameters
    ----------
    argv : list of str or None
        Arguments without the program name (None: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code (module doc).

    """
    return run_cli(PROG, _body, argv)


if __name__ == '__main__':
    sys.exit(main())
