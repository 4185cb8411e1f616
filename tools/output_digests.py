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
SHA-256 of every output file of every tool on fixed inputs: the check that a change moved code.

Writes seeded inputs once (the emulator's scenario model, the fractional-noise and thermal
simulators), then runs every tool on them as a program, each in a fresh process (``PYTHONPATH``
= the checkout): analyze, explain, calibrate six-position and multi-pose, excitation (a dwell
before/after, a sweep with a reference), reliability, thermal fit/apply/compare/export. What each
tool prints is kept as ``<run>/stdout.txt`` and ``<run>/stderr.txt``.

* without ``--baseline``: prints ``sha256  path`` per output file;
* with ``--baseline CHECKOUT`` (e.g. ``git worktree add /tmp/base <commit>``): runs the same
  tools of that checkout on the same inputs, and prints which files differ, then ``all
  identical`` (exit 0) or how many differ (exit 1).

Not deterministic by nature: the wall times the thermal workflows and explain write (fit,
apply, each explain stage) are made deterministic (their modules read a clock that advances one
second per reading, :data:`CLOCKED`); the UTC time in calibration.yaml and summary.json and the
random ids Bokeh gives a page's figures (report.html: UUIDs and model ids, renamed in order of
first appearance), and with the UTC time the size and SHA-256 a page gives of an input an
earlier run wrote, are compared after normalising (:data:`NORMALISE`). PNGs carry no time stamp.

Usage::

    .venv/bin/python tools/output_digests.py [--tools NAME,NAME] [--baseline CHECKOUT]
        [--workdir DIR] [--keep]
"""

import argparse
from collections.abc import Callable, Iterator, Sequence
import contextlib
import hashlib
import os
from pathlib import Path
import re
import runpy
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Any
import warnings

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
#: Stamps of the first sample of every input recording (ns).
T0_NS = 1_700_000_000 * 10**9
G = 9.80665

#: (file name pattern, regular expression, replacement) applied before hashing.
NORMALISE: tuple[tuple[str, str, str], ...] = (
    (r'calibration\.yaml$', r' on \d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ', ' on <utc>'),
    (r'\.(json|html)$', r'"created_utc": "[^"]*"', '"created_utc": "<utc>"'),
    # an input that an earlier run wrote (a relative path: thermal apply's model.json) holds a
    # time: its size and SHA-256 on the page follow it (the file itself is compared normalised)
    (r'\.html$', r'<tr><td>([^/<][^<]*)</td><td>\d+</td><td><code>[0-9a-f]{64}</code>',
     r'<tr><td>\1</td><td><size></td><td><code><sha256></code>'),
)
#: Modules whose measured wall times go into the files: their ``time`` becomes a :class:`_Clock`.
CLOCKED = ('gyro_noise_ros.app.thermal', 'gyro_noise_ros.explain.workflow')
_UUID = re.compile(r'[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}')
_BOKEH_ID = re.compile(r'(?<=")p\d+(?=")')


# ---- inputs ----------------------------------------------------------------------------------

def _write_bag(path: Path, t_s: np.ndarray, accel: np.ndarray, gyro: np.ndarray, *,
               temperature: tuple[np.ndarray, np.ndarray] | None = None,
               extra: dict[str, tuple[np.ndarray, np.ndarray]] | None = None) -> str:
    """Write an Imu rosbag2 (stamps T0 + t); ``extra``: more Imu topics, (gyro, accel) each."""
    from gyro_noise_ros.bag import ImuBagWriter

    stamps = T0_NS + np.round(np.asarray(t_s) * 1e9).astype(np.int64)
    topic = None if temperature is None else '/imu/temperature'
    with ImuBagWriter(path, temperature_topic=topic) as writer:
        writer.write_imu(stamps, gyro, accel)
        for name, (g, a) in (extra or {}).items():
            writer.write_imu(stamps, g, a, topic=name)
        if temperature is not None:
            ts, temp = temperature
            writer.write_temperature(T0_NS + np.round(ts * 1e9).astype(np.int64), temp)
    return str(path)


def _ramp(t_s: np.ndarray, start_c: float, per_s: float) -> tuple[np.ndarray, np.ndarray]:
    ts = np.arange(float(t_s[0]), float(t_s[-1]), 1.0)
    return ts, start_c + per_s * ts


def _scenario_record(motion: Any, seconds: float, seed: int, *, rate_hz: float = 100.0,
                     errors: Any = None, accel_noise: float = 0.04,
                     gyro_noise: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from gyro_noise_ros.calibration.emulate import Scenario, SensorErrors, simulate

    rng = np.random.default_rng(seed)
    sc = Scenario(motion, errors or SensorErrors(), rate_hz, rng)
    return simulate(sc, int(round(seconds * rate_hz)), rate_hz, rng=rng,
                    accel_noise_m_s2=accel_noise, gyro_noise_rad_s=gyro_noise)


def _noise_inputs(folder: Path) -> None:
    from gyro_noise_ros.core.simulate import FractionalNoise

    rng = np.random.default_rng(11)
    n, rate = 30_000, 100.0
    gyro = np.stack([FractionalNoise(1.2, -1.0, 1e-3, rng=rng).generate(n) for _ in range(3)],
                    axis=1)
    t = np.arange(n) / rate
    accel = np.tile([0.0, 0.0, G], (n, 1))
    _write_bag(folder / 'noise', t, accel, gyro, temperature=_ramp(t, 25.0, 0.01))


def _six_inputs(folder: Path) -> None:
    from gyro_noise_ros.calibration.emulate import SixPosition

    six = SixPosition(dwell_s=20.0, move_s=4.0)
    rec = _scenario_record(six, six.duration_s, 4)
    _write_bag(folder / 'six', *rec, temperature=_ramp(rec[0], 30.0, 0.01))


def _multi_inputs(folder: Path) -> None:
    from gyro_noise_ros.calibration.emulate import MultiPose

    multi = MultiPose(poses=12, dwell_s=20.0, move_s=5.0, lead_s=5.0)
    _write_bag(folder / 'multi', *_scenario_record(multi, multi.duration_s, 6))


def _excitation_inputs(folder: Path) -> None:
    from gyro_noise_ros.calibration.emulate import Excitation

    for name, amplitude, seed in (('dwell_before', 0.3, 1), ('dwell_after', 0.28, 2)):
        motion = Excitation(sensor='accel', axis='x', amplitude=amplitude * G, frequency_hz=8.0)
        _write_bag(folder / name, *_scenario_record(motion, 30.0, seed))
    sweep = Excitation(sensor='accel', axis='y', amplitude=0.3 * G, frequency_hz=5.0,
                       sweep_to_hz=10.0, sweep_rate_hz_s=0.5)
    t = np.arange(4000) / 100.0
    ref = sweep.reference(t)
    noise = np.random.default_rng(3).normal(0.0, 0.04, ref.shape)
    accel = ref * 1.03 + [0.0, 0.0, G] + noise
    zeros = np.zeros_like(ref)
    _write_bag(folder / 'sweep', t, accel, zeros, extra={'/shaker/imu': (zeros, ref)})


def _reliability_inputs(folder: Path) -> None:
    from gyro_noise_ros.calibration.emulate import SensorErrors, SixPosition, Static

    rate = 10.0
    n_acc, n_gyr = 0.02 / np.sqrt(rate), 2e-3 / np.sqrt(rate)
    errors = SensorErrors(accel_bias_instability_m_s2=n_acc / 2 / 0.664,
                          accel_random_walk_m_s2_sqrt_s=n_acc / 5,
                          gyro_bias_instability_rad_s=n_gyr / 2 / 0.664,
                          gyro_random_walk_rad_s_sqrt_s=n_gyr / 5)
    for name, err, seed in (('static_before', errors, 1),
                            ('static_after', errors.stressed(instability_factor=2.0), 2)):
        rec = _scenario_record(Static(), 12_000.0, seed, rate_hz=rate, errors=err,
                               accel_noise=0.02, gyro_noise=2e-3)
        temp = _ramp(rec[0], 25.0, 1 / 12_000.0) if name == 'static_before' else None
        _write_bag(folder / name, *rec, temperature=temp)
    six = SixPosition(dwell_s=20.0, move_s=4.0)
    _write_bag(folder / 'six_after', *_scenario_record(six, six.duration_s, 5,
                                                       errors=SensorErrors().stressed()))


def _thermal_inputs(folder: Path) -> None:
    from gyro_noise_ros.app.thermal import simulate, write_simulate

    # as ``gyro_noise_thermal simulate --seed 2 --shape heating --test-shape cooling
    # --hours 0.25 --rate-hz 10``: train/ and test/ with the truth beside them (the oracle rows)
    write_simulate(simulate(seed=2, hours=0.25, rate_hz=10.0, shape='heating',
                            test_shape='cooling'), folder / 'thermal')


#: Input makers, by the tools that read what they write.
_INPUTS: dict[str, Callable[[Path], None]] = {
    'noise': _noise_inputs, 'six': _six_inputs, 'multi': _multi_inputs,
    'excitation': _excitation_inputs, 'reliability': _reliability_inputs,
    'thermal': _thermal_inputs}


# ---- the tools -------------------------------------------------------------------------------

#: Tool runs in order: (name, CLI module, argv with {in} the inputs folder, inputs it needs).
#: Outputs go to the relative folder named after the run (the run's cwd is its output root,
#: so the command lines recorded in the files are the same in every checkout).
TOOLS: tuple[tuple[str, str, tuple[str, ...], tuple[str, ...]], ...] = (
    ('analyze', 'analyze', ('{in}/noise', '--out', 'analyze', '--quiet'), ('noise',)),
    ('explain', 'explain', ('{in}/noise', '--out', 'explain', '--ensemble', '4',
                            '--max-steps', '1', '--bootstrap', '5', '--quiet'), ('noise',)),
    ('calibrate_six', 'calibrate', ('{in}/six', '--out', 'calibrate_six'), ('six',)),
    ('calibrate_multi', 'calibrate', ('{in}/multi', '--mode', 'multi-pose', '--latitude', '45',
                                      '--out', 'calibrate_multi'), ('multi',)),
    ('excitation_dwell', 'excitation', ('{in}/dwell_before', '{in}/dwell_after', '--sensor',
                                        'accel', '--axis', 'x', '--dwell', '8', '--out',
                                        'excitation_dwell'), ('excitation',)),
    ('excitation_sweep', 'excitation', ('{in}/sweep', '--topic', '/imu/data_raw', '--sensor',
                                        'accel', '--axis', 'y', '--sweep', '5', '10', '0.5',
                                        '--reference-topic', '/shaker/imu', '--out',
                                        'excitation_sweep'), ('excitation',)),
    ('reliability', 'reliability', ('--before-calibration', '{in}/six', '--before-static',
                                    '{in}/static_before', '--after-calibration',
                                    '{in}/six_after', '--after-static', '{in}/static_after',
                                    '--out', 'reliability'), ('six', 'reliability')),
    ('thermal_fit', 'thermal', ('fit', '{in}/thermal/train', '--method', 'parallel_small',
                                '--out', 'thermal_fit'), ('thermal',)),
    ('thermal_fit_poly3', 'thermal', ('fit', '{in}/thermal/train', '--method', 'poly3',
                                      '--no-figures', '--out', 'thermal_fit_poly3'),
     ('thermal',)),
    ('thermal_apply', 'thermal', ('apply', '{in}/thermal/test', '--model',
                                  'thermal_fit/model.json', '--f-lo-hz', '0.5', '--out',
                                  'thermal_apply'), ('thermal',)),
    ('thermal_compare', 'thermal', ('compare', '{in}/thermal/train', '{in}/thermal/test',
                                    '--methods', 'poly3,linear_tdt,parallel_small',
                                    '--f-lo-hz', '0.5', '--out', 'thermal_compare'),
     ('thermal',)),
    ('thermal_export', 'thermal', ('export', '--model', 'thermal_fit_poly3/model.json',
                                   '--out', 'thermal_export'), ('thermal',)),
)
#: Runs another one needs first.
_NEEDS = {'thermal_apply': ('thermal_fit',), 'thermal_export': ('thermal_fit_poly3',)}
#: The parallel model with the small MOPSO and network budget of the tests (same code).
SMALL_PARALLEL = {'n_particles': 4, 'iterations': 2, 'fitness_samples': 128, 'elman_epochs': 3,
                  'elman_samples': 500, 'refine_points': 2, 'refine_polish': 2,
                  'refine_samples': 256, 'elman_refine': 100}


def _selected(names: Sequence[str] | None) -> list[str]:
    known = [t[0] for t in TOOLS]
    if not names:
        return known
    unknown = [n for n in names if n not in known]
    if unknown:
        raise SystemExit(f'--tools: unknown {", ".join(unknown)} (known: {", ".join(known)})')
    wanted = set(names)
    for name in names:
        wanted.update(_NEEDS.get(name, ()))
    return [n for n in known if n in wanted]


def make_inputs(folder: Path, tools: Sequence[str]) -> None:
    """Write the inputs the ``tools`` read into ``folder`` (seeded: the same bytes each time)."""
    folder.mkdir(parents=True, exist_ok=True)
    needed = {need for name, _, _, needs in TOOLS if name in tools for need in needs}
    for key, maker in _INPUTS.items():
        if key in needed:
            maker(folder)


class _Clock:
    """The ``time`` module, but ``monotonic`` and ``perf_counter`` advance 1 s per reading."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        self.now += 1.0
        return self.now

    perf_counter = monotonic

    def __getattr__(self, name: str) -> Any:
        return getattr(time, name)


@contextlib.contextmanager
def _harness() -> Iterator[None]:
    """Register ``parallel_small`` and clock the :data:`CLOCKED` modules; undo both after."""
    import importlib

    from gyro_noise_ros.thermal import methods
    from gyro_noise_ros.thermal.parallel import ParallelModel

    class SmallParallel(ParallelModel):
        name = 'parallel_small'

        def __init__(self, **options: Any) -> None:
            super().__init__(**{**SMALL_PARALLEL, **options})

    methods.register_method('parallel_small', SmallParallel)
    clocked = [importlib.import_module(name) for name in CLOCKED]
    clocked = [m for m in clocked if hasattr(m, 'time')]
    for module in clocked:
        setattr(module, 'time', _Clock())
    try:
        yield
    finally:
        for module in clocked:
            setattr(module, 'time', time)
        methods._registered.pop('parallel_small', None)


@contextlib.contextmanager
def _cwd(path: Path) -> Iterator[None]:
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def run_one(name: str, inputs: Path, out: Path) -> int:
    """
    Run one tool as its program would (``python -m gyro_noise_ros.cli.X ARGS``) in this process.

    The run's cwd is ``out`` and its outputs go to ``out/<name>``; return its exit code.
    """
    _, module, argv, _ = next(t for t in TOOLS if t[0] == name)
    prog = f'gyro_noise_ros.cli.{module}'
    old = sys.argv
    sys.argv = [prog, *(a.replace('{in}', str(inputs)) for a in argv)]
    try:
        with _harness(), _cwd(out), warnings.catch_warnings():
            # in a process that imported the module already (a test): it runs again as __main__
            warnings.filterwarnings('ignore', '.* found in sys.modules', RuntimeWarning)
            runpy.run_module(prog, run_name='__main__', alter_sys=True)
    except SystemExit as done:
        return done.code if isinstance(done.code, int) else 1
    finally:
        sys.argv = old
    return 0


# ---- digests ---------------------------------------------------------------------------------

def _renumber(pattern: 're.Pattern[str]', text: str, tag: str) -> str:
    seen: dict[str, str] = {}

    def name(m: 're.Match[str]') -> str:
        return seen.setdefault(m.group(0), f'{tag}{len(seen)}')

    return pattern.sub(name, text)


def normalised(path: Path) -> bytes:
    """Return a file's bytes with what is not deterministic by nature replaced (NORMALISE)."""
    data = path.read_bytes()
    rules = [(p, r) for f, p, r in NORMALISE if re.search(f, path.name)]
    if not rules and path.suffix != '.html':
        return data
    text = data.decode('utf-8')
    for pattern, repl in rules:
        text = re.sub(pattern, repl, text)
    if path.suffix == '.html':
        text = _renumber(_BOKEH_ID, _renumber(_UUID, text, 'uuid-'), 'bokeh-')
    return text.encode('utf-8')


def digests(out: Path) -> dict[str, str]:
    """Return ``{relative path: sha256 of the normalised bytes}`` of every file under ``out``."""
    return {str(p.relative_to(out)): hashlib.sha256(normalised(p)).hexdigest()
            for p in sorted(out.rglob('*')) if p.is_file()}


# ---- the controller ----------------------------------------------------------------------------

def _imported_from(root: Path, workdir: Path) -> Path:
    """Return the folder of the ``gyro_noise_ros`` that ``PYTHONPATH=root`` imports."""
    out = subprocess.run(
        [sys.executable, '-c', 'import gyro_noise_ros; print(gyro_noise_ros.__file__)'],
        cwd=workdir, env=dict(os.environ, PYTHONPATH=str(root)), capture_output=True, text=True,
        check=True).stdout.strip()
    return Path(out).resolve().parent


def run_checkout(root: Path, inputs: Path, out: Path, tools: Sequence[str],
                 workdir: Path) -> dict[str, str]:
    """
    Run the ``tools`` of the checkout ``root`` on ``inputs``, each in a fresh process.

    What each prints goes to ``out/<name>/stdout.txt`` and ``stderr.txt``. Returns
    :func:`digests` of ``out``.
    """
    got = _imported_from(root, workdir)
    if got != (root / 'gyro_noise_ros').resolve():
        raise SystemExit(f'PYTHONPATH={root} imports gyro_noise_ros from {got}')
    env = dict(os.environ, PYTHONPATH=str(root))
    out.mkdir(parents=True, exist_ok=True)
    for name in tools:
        cmd = [sys.executable, str(Path(__file__).resolve()), '--run-one', name, str(inputs),
               str(out)]
        # cwd outside both checkouts, so that PYTHONPATH decides which code is imported
        proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
        if proc.returncode != 0:
            raise SystemExit(f'{root}: {name}: exit {proc.returncode}:\n{proc.stdout[-2000:]}'
                             f'{proc.stderr[-4000:]}')
        (out / name / 'stdout.txt').write_text(proc.stdout)
        (out / name / 'stderr.txt').write_text(proc.stderr)
    return digests(out)


def compare(new: dict[str, str], base: dict[str, str]) -> list[tuple[str, str]]:
    """Return ``(path, 'identical' | 'DIFFERENT' | 'only in new' | 'only in baseline')``."""
    rows = []
    for name in sorted(set(new) | set(base)):
        if name not in base:
            rows.append((name, 'only in new'))
        elif name not in new:
            rows.append((name, 'only in baseline'))
        else:
            rows.append((name, 'identical' if new[name] == base[name] else 'DIFFERENT'))
    return rows


def _git_head(root: Path) -> str:
    try:
        return subprocess.run(['git', '-C', str(root), 'rev-parse', '--short', 'HEAD'],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return '?'


def _controller(args: argparse.Namespace, tmp: Path) -> int:
    tools = _selected(args.tools.split(',') if args.tools else None)
    started = time.perf_counter()
    make_inputs(tmp / 'inputs', tools)
    print(f'inputs written in {time.perf_counter() - started:.1f} s: {tmp / "inputs"}')
    started = time.perf_counter()
    new = run_checkout(ROOT, tmp / 'inputs', tmp / 'new', tools, tmp)
    print(f'{len(tools)} tool runs of {ROOT} (git {_git_head(ROOT)}): {len(new)} files in '
          f'{time.perf_counter() - started:.1f} s (load {os.getloadavg()[0]:.1f})')
    if not args.baseline:
        for name, digest in new.items():
            print(f'{digest}  {name}')
        return 0
    base_root = Path(args.baseline).resolve()
    started = time.perf_counter()
    base = run_checkout(base_root, tmp / 'inputs', tmp / 'baseline', tools, tmp)
    print(f'the same of {base_root} (git {_git_head(base_root)}): {len(base)} files in '
          f'{time.perf_counter() - started:.1f} s (load {os.getloadavg()[0]:.1f})')
    rows = compare(new, base)
    for name, verdict in rows:
        print(f'  {verdict:16s} {name}')
    bad = [name for name, verdict in rows if verdict != 'identical']
    print('all identical' if not bad else f'{len(bad)} of {len(rows)} files differ')
    return 0 if not bad else 1


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, make the inputs, run the tools, print the digests or the comparison."""
    p = argparse.ArgumentParser(description=(__doc__ or '').strip().splitlines()[0])
    p.add_argument('--tools', help='comma-separated runs (default: all): '
                   + ', '.join(t[0] for t in TOOLS))
    p.add_argument('--baseline', metavar='CHECKOUT',
                   help='checkout of the code to compare with, on the same inputs')
    p.add_argument('--workdir', type=Path, help='where the temporary folder goes')
    p.add_argument('--keep', action='store_true', help='keep the inputs and outputs')
    p.add_argument('--run-one', nargs=3, metavar=('NAME', 'INPUTS', 'OUT'),
                   help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.run_one:
        name, inputs, out = args.run_one
        return run_one(name, Path(inputs), Path(out))
    tmp = Path(tempfile.mkdtemp(prefix='output_digests_', dir=args.workdir))
    try:
        return _controller(args, tmp)
    finally:
        if args.keep:
            print(f'kept: {tmp}')
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
