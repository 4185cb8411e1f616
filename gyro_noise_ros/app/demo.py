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
The demo's workflow: an emulated board, the live nodes, a recording, the offline report.

Shared by ``gyro_noise_demo`` (``make demo``; the story, its settings and exit codes are in that
module's docstring and ``docs/demo.md``). :func:`run_demo` starts the nodes and the emulator as
subprocesses in a private ROS graph (a ``ROS_DOMAIN_ID`` checked free on this host and held while
the demo runs, localhost-only discovery: :func:`gyro_noise_ros.rosgraph.lease_domain`), prints the
analyzer's diagnostics as they arrive, checks the story (OK in the quiet phase, WARN once the
bias rises), stops everything in order, runs ``gyro_noise_analyze`` on the recording and returns
a :class:`DemoResult`. Every subprocess is stopped on every path.
"""

from dataclasses import dataclass
import os
from pathlib import Path
import queue
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from typing import Any, IO

from .. import rosgraph
from ..errors import (EXIT_INTERRUPTED, EXIT_TERMINATED, GyroNoiseError, Interrupted, OutputError,
                      ParameterError)
from ..monitor_lines import parse_axis_parts
from ..outputs import atomic_write_text

#: The tool named in the printed lines.
TOOL = 'gyro_noise_demo'
#: The file in the output folder that says whether the demo output is complete.
MARKER = 'GYRO_NOISE_DEMO.txt'
#: Stop order of the live processes on an interrupt or an error.
_STOP_ORDER = ['lsm6dso32_driver', 'gyro_noise_record', 'noise_analyzer', 'monitor',
               'portenta_emulator']


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

DEMO_ANALYZER_PARAMS: dict[str, Any] = {
    'drift_abs_warn_deg_s_per_h': 1.0,
    'drift_abs_error_deg_s_per_h': 100.0,
    'lost_fraction_warn': 0.05,
    'lost_fraction_error': 0.25,
    'analysis_queue_chunks': 20,
    'hardware_id': 'lsm6dso32@portenta_emulator',
}


@dataclass(frozen=True)
class DemoParams:
    """
    One demo run.

    Attributes
    ----------
    out : str
        Output folder (a previous demo output there is replaced only with ``overwrite``).
    quick : bool
        The short story (:data:`QUICK`) instead of :data:`FULL`.
    seed : int
        Seed of the emulated sensor.
    speed : float
        Emulator pace as a multiple of real time (0.1..100).
    storage : str
        Bag storage (``'sqlite3'`` or ``'mcap'``).
    jobs : int
        Worker processes of the offline analysis.
    domain_id : int or None
        ``ROS_DOMAIN_ID`` (None: one in 1..101 checked free on this host and held while the
        demo runs).
    overwrite : bool
        Replace a previous demo output in ``out`` (``--overwrite``; ``make demo`` gives it).

    Raises
    ------
    ParameterError
        An option out of its range.

    """

    out: str = 'demo_out'
    quick: bool = False
    seed: int = 1
    speed: float = 1.0
    storage: str = 'sqlite3'
    jobs: int = 2
    domain_id: int | None = None
    overwrite: bool = False

    def __post_init__(self) -> None:
        if not 0.1 <= self.speed <= 100:
            raise ParameterError(f'--speed must be in [0.1, 100], got {self.speed}')
        if self.domain_id is not None and not 0 <= self.domain_id <= 232:
            raise ParameterError(f'--domain-id must be a ROS_DOMAIN_ID in 0..232, got '
                                 f'{self.domain_id}')
        if self.jobs < 1:
            raise ParameterError(f'--jobs must be >= 1, got {self.jobs}')
        if self.seed < 0:
            raise ParameterError(f'--seed must be >= 0, got {self.seed}')

    @property
    def story(self) -> 'Story':
        """Story: the timing and thresholds of this run."""
        return QUICK if self.quick else FULL


@dataclass(frozen=True)
class DemoResult:
    """
    What a demo run did.

    Attributes
    ----------
    report : pathlib.Path
        The offline report folder.
    elapsed_s : float
        Wall time of the run (s).

    """

    report: Path
    elapsed_s: float = 0.0


def run_demo(params: DemoParams) -> DemoResult:
    """
    Run the demo: the live part, the orderly stop, the story check, the offline report.

    Parameters
    ----------
    params : DemoParams
        The run's options (the output folder already checked by the caller).

    Returns
    -------
    DemoResult

    Raises
    ------
    DemoError
        A component failed (its log is named) or the drift was not detected.
    OutputError
        The output folder cannot be prepared.
    KeyboardInterrupt
        Interrupted (SIGINT; SIGTERM as :class:`~gyro_noise_ros.errors.Interrupted`): every
        process was stopped first.

    """
    # Held until the demo ends: another demo, a test run or a bench on this host skips it.
    lease = rosgraph.lease_domain() if params.domain_id is None else None
    try:
        domain = lease.domain_id if lease else params.domain_id
        assert domain is not None  # leased when not given
        return _run(params, domain)
    finally:
        if lease is not None:
            lease.release()


def _run(params: DemoParams, domain: int) -> DemoResult:
    story = params.story
    out = _prepare_out(Path(params.out), overwrite=params.overwrite)
    env = rosgraph.isolated_env(domain, dict(os.environ, PYTHONUNBUFFERED='1'))
    procs = Processes(env, out / 'logs')
    t_start = time.monotonic()
    print(f'{TOOL}: ROS_DOMAIN_ID={domain} (localhost only); logs in {out / "logs"}', flush=True)
    _print_story(story)
    recording = out / 'recording'
    seen = _live_part(params, procs, recording, t_start)
    _close_recording(procs, recording)
    _check_story(seen, story)
    report = out / 'report'
    _offline_report(params, env, recording, report)
    _mark(out, finished=True)
    return DemoResult(report=report, elapsed_s=time.monotonic() - t_start)


def _print_story(story: Story) -> None:
    warn_limit = DEMO_ANALYZER_PARAMS['drift_abs_warn_deg_s_per_h']
    error_limit = DEMO_ANALYZER_PARAMS['drift_abs_error_deg_s_per_h']
    print(f'{TOOL}: story: {story.quiet_s:.0f} s quiet, then the bias of every axis rises by '
          f'{story.amplitude_dps} deg/s with a time constant of {story.tau_s:.0f} s '
          f'(initial drift {story.amplitude_dps / story.tau_s * 3600:.0f} (deg/s)/h); live part '
          f'{story.live_s:.0f} s; drift limits WARN {warn_limit:g} / ERROR {error_limit:g} '
          f'(deg/s)/h over the last {story.history_chunks} chunks', flush=True)


def _live_part(params: DemoParams, procs: 'Processes', recording: Path,
               t_start: float) -> list[tuple[float, str]]:
    """Start the nodes and the emulator, print the diagnostics (an interrupt stops them all)."""
    story = params.story
    port = _free_port()
    url = f'socket://127.0.0.1:{port}'
    # A SIGTERM to the demo gets the same orderly cleanup as Ctrl-C.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        procs.start('noise_analyzer', ['gyro_noise_ros.nodes.analyzer', *_ros_args(
            {**DEMO_ANALYZER_PARAMS, 'history_chunks': story.history_chunks,
             'chunk_size': story.chunk_size})])
        procs.start('gyro_noise_record', ['gyro_noise_ros.nodes.recorder', *_ros_args(
            {'output': str(recording), 'storage': params.storage})])
        echo = procs.start('monitor', ['gyro_noise_ros.nodes.monitor', '--compact'],
                           capture_stdout=True)
        lines: queue.Queue[str | None] = queue.Queue()  # None: the monitor's end
        threading.Thread(target=_reader, args=(echo.stdout, lines), daemon=True).start()
        procs.start('lsm6dso32_driver', ['gyro_noise_ros.nodes.driver', *_ros_args({'port': url})])
        print(f'{TOOL}: starting the nodes ...', flush=True)
        procs.wait_for_log('noise_analyzer', r'analysing ', 120, 'start-up')
        procs.wait_for_log('gyro_noise_record', r'recording ', 120, 'start-up')
        procs.wait_for_log('lsm6dso32_driver', r'\S', 120, 'start-up')
        # The monitor prints the analyzer's periodic (STALE) diagnostics once discovery is done.
        _wait_line(lines, procs, 120)
        procs.start('portenta_emulator', [
            'gyro_noise_ros.cli.emulator', '--tcp', f'127.0.0.1:{port}',
            '--seed', str(params.seed), '--speed', str(params.speed),
            '--helium-amplitude-dps', str(story.amplitude_dps),
            '--helium-delay-s', str(story.quiet_s), '--helium-tau-s', str(story.tau_s)])
        procs.wait_for_log('lsm6dso32_driver', r'streaming from', 120, 'the board streaming')
        t_stream = time.monotonic()
        print(f'{TOOL}: the board is streaming ({time.monotonic() - t_start:.0f} s after start); '
              'diagnostics of noise_analyzer:', flush=True)
        return _live(lines, procs, story, params.speed, t_stream)
    except BaseException:
        procs.stop_all(_STOP_ORDER)
        raise
    finally:
        signal.signal(signal.SIGTERM, previous)


def _close_recording(procs: 'Processes', recording: Path) -> None:
    """Orderly stop: no new data, let the last messages be taken, then close the bag."""
    try:
        procs.stop('lsm6dso32_driver')
        time.sleep(1.0)
        rc = procs.stop('gyro_noise_record', timeout_s=60)
        record_line = next((ln for ln in procs.log_text('gyro_noise_record').splitlines()
                            if ln.startswith('gyro_noise_record: received')), '')
        if rc != EXIT_INTERRUPTED or not (recording / 'metadata.yaml').exists():
            raise DemoError(f'gyro_noise_record did not close the bag cleanly (exit {rc}); log '
                            f'{procs.logs["gyro_noise_record"]}: '
                            f'{procs.last_lines("gyro_noise_record")}')
        print(f'{TOOL}: {record_line.split(": ", 1)[-1]}', flush=True)
    finally:
        procs.stop_all(['noise_analyzer', 'monitor', 'portenta_emulator'])


def _offline_report(params: DemoParams, env: dict[str, str], recording: Path,
                    report: Path) -> None:
    """Run gyro_noise_analyze on the recording (the tool, as a user would)."""
    print(f'{TOOL}: offline analysis of the recording with gyro_noise_analyze ...', flush=True)
    cmd = [sys.executable, '-m', 'gyro_noise_ros.cli.analyze', str(recording), '--out',
           str(report), '--jobs', str(params.jobs), '--label', 'demo']
    try:
        done = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, timeout=900)
    except subprocess.TimeoutExpired as err:
        raise DemoError('gyro_noise_analyze took more than 15 minutes') from err
    if done.returncode in (EXIT_INTERRUPTED, EXIT_TERMINATED):
        raise Interrupted(done.returncode - 128)
    if done.returncode != 0:
        raise DemoError(
            f'gyro_noise_analyze failed with exit code {done.returncode}: {" ".join(cmd)}')
    if not (report / 'summary.json').is_file():
        # never exit 0 having analysed nothing
        raise DemoError(f'gyro_noise_analyze exited 0 but wrote no {report / "summary.json"}')


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def _prepare_out(out: Path, *, overwrite: bool) -> Path:
    if out.exists() and any(out.iterdir()):
        if not (out / MARKER).exists():
            raise OutputError(
                f'{{out}} {str(out)!r} exists and is not a previous demo output; choose another',
                parameters=('out',))
        if not overwrite:
            raise OutputError(f'{{out}} {str(out)!r} holds a previous demo output: give '
                              '{overwrite} to replace it, or another folder',
                              parameters=('out', 'overwrite'))
    try:
        for name in ('recording', 'report', 'logs'):
            if (out / name).is_dir():
                shutil.rmtree(out / name)
            elif (out / name).exists():
                (out / name).unlink()
        (out / 'logs').mkdir(parents=True, exist_ok=True)
        _mark(out, finished=False)
    except OSError as err:
        raise OutputError(f'{{out}} {str(out)!r} cannot be prepared: {err.strerror or err}',
                          parameters=('out',)) from err
    return out


def _mark(out: Path, *, finished: bool) -> None:
    """Say in the marker file whether the demo output is complete (a stopped run is not)."""
    state = ('finished: the report is complete' if finished else
             'NOT FINISHED: a run is going on, or was stopped or failed')
    atomic_write_text(out / MARKER, f'Written by gyro_noise_ros.cli.demo; {state}. The next '
                      'demo run replaces this directory.\n')


class Processes:
    """
    The demo's subprocesses: start, watch, stop in order, always clean up.

    Each child runs in its own session so a Ctrl-C at the terminal reaches only the demo, which
    then stops the children in a sensible order instead of all at once.
    """

    def __init__(self, env: dict[str, str], log_dir: 'os.PathLike[str] | str') -> None:
        self.env = env
        self.log_dir = Path(log_dir)
        self.procs: dict[str, tuple[subprocess.Popen, IO[str]]] = {}  # name -> (process, log)
        self.logs: dict[str, Path] = {}
        self.stopping: set[str] = set()

    def start(self, name: str, args: list[str], *,
              capture_stdout: bool = False) -> subprocess.Popen:
        log = self.log_dir / f'{name}.log'
        fh = open(log, 'w')  # noqa: SIM115 - closed with the process in stop()
        stdout = subprocess.PIPE if capture_stdout else fh
        proc = subprocess.Popen([sys.executable, '-m', *args], env=self.env, stdout=stdout,
                                stderr=fh, stdin=subprocess.DEVNULL, start_new_session=True,
                                text=True, bufsize=1)
        self.procs[name] = (proc, fh)
        self.logs[name] = log
        return proc

    def log_text(self, name: str) -> str:
        try:
            return self.logs[name].read_text(errors='replace')
        except OSError:
            return ''

    def last_lines(self, name: str, n: int = 3) -> str:
        lines = [ln for ln in self.log_text(name).splitlines() if ln.strip()]
        return ' | '.join(lines[-n:]) if lines else '(empty log)'

    def check(self) -> None:
        """Raise DemoError if a process not being stopped has exited."""
        for name, (proc, _) in self.procs.items():
            if name not in self.stopping and proc.poll() is not None:
                raise DemoError(f'{name} exited with code {proc.returncode}; log '
                                f'{self.logs[name]}: {self.last_lines(name)}')

    def wait_for_log(self, name: str, pattern: str, timeout_s: float, what: str) -> None:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self.check()
            if re.search(pattern, self.log_text(name)):
                return
            time.sleep(0.2)
        raise DemoError(f'{name}: no sign of {what} after {timeout_s:.0f} s; log '
                        f'{self.logs[name]}: {self.last_lines(name)}')

    def stop(self, name: str, timeout_s: float = 15.0) -> int | None:
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

    def stop_all(self, order: list[str]) -> None:
        for name in [*order, *[n for n in self.procs if n not in order]]:
            try:
                self.stop(name)
            except Exception:  # noqa: BLE001 - cleanup must reach every process
                entry = self.procs.get(name)
                if entry and entry[0].poll() is None:
                    entry[0].kill()


def _ros_args(params: dict[str, Any]) -> list[str]:
    out = ['--ros-args']
    for key, value in params.items():
        text = ('true' if value else 'false') if isinstance(value, bool) else str(value)
        out += ['-p', f'{key}:={text}']
    return out


def _reader(stream: IO[str], lines: queue.Queue) -> None:
    for line in iter(stream.readline, ''):
        lines.put(line.rstrip('\n'))
    lines.put(None)


def _interrupt(signum: int, frame: Any) -> None:
    raise Interrupted(signum)


def _next_line(lines: queue.Queue, procs: 'Processes', deadline: float) -> str | None:
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


def _wait_line(lines: queue.Queue, procs: 'Processes', timeout_s: float) -> str:
    line = _next_line(lines, procs, time.monotonic() + timeout_s)
    if line is None:
        raise DemoError(f'no diagnostics from noise_analyzer after {timeout_s:.0f} s '
                        f'(DDS discovery?); logs in {procs.log_dir}')
    return line


def _live(lines: queue.Queue, procs: 'Processes', story: Story, speed: float,
          t_stream: float) -> list[tuple[float, str]]:
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


def _check_story(seen: list[tuple[float, str]], story: Story) -> None:
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
    print(f'{TOOL}: story checked: {ok_quiet} of {len(quiet)} quiet-phase reports OK; after the '
          f'rise began, {len(warned)} of {len(rise)} reports had an axis at WARN or worse with '
          f'its drift above {limit:g} (deg/s)/h', flush=True)
