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
End to end: emulator -> driver -> imu_compensator (a fitted poly3 thermal model) -> noise_analyzer.

The emulator ramps the die temperature and leaks it into the gyro bias with a known linear
sensitivity; the driver publishes what the device reports (REP-145). First a training run
(emulator seed 7) is recorded with ``gyro_noise_record`` and the PX4-style ``poly3`` model is
fitted on the bag with ``gyro_noise_thermal fit`` (the documented path: ``model.json``, loaded by
the node's ``thermal_model_file`` parameter). Then on a held-out run (seed 8) the compensator
subtracts that model's offset, evaluated per imu/temperature message and interpolated onto the
gyro stamps. Two analyzers run side by side,
on ``imu/data_raw`` and remapped onto ``imu/data_compensated``: the first sees the offset drift
the ramp causes, the second sees it gone.
"""
import json
import os
from pathlib import Path
import subprocess
import sys
import time

from _e2e import chunks, collect_diagnostics, free_port, values
from gyro_noise_ros.cli import thermal as thermal_cli
import pytest

pytestmark = pytest.mark.ros

HERE = Path(__file__).resolve().parent

# 2 degC/s (7200 degC/h) and 0.02 (deg/s)/degC per axis: the bias ramps 0.04 (deg/s)/s = 144
# (deg/s)/h, far above the analyzer's slope noise (emulator's default noise, chunks of 2000
# samples, ~20 chunks: a few (deg/s)/h), within the chosen WARN limit's sight (50 (deg/s)/h).
RAMP_C_PER_H = 7200.0
SENSITIVITY_DPS_PER_C = (0.02, -0.02, 0.01)
EXPECTED_DRIFT = [s * RAMP_C_PER_H for s in SENSITIVITY_DPS_PER_C]  # (deg/s)/h
# Wall time of the recorded training run (its temperature span must hold the held-out run's).
TRAIN_S = 14.0
# The analyzers, the recorder and the compensator subscribe reliable: a transport drop on a loaded
# host is retransmitted, not counted. A reliable stream is delivered in order, so after a lost
# message nothing newer arrives until the middleware has repaired it; before the compensator held
# gyro samples for a newer temperature (max_temperature_wait_s), a stalled imu/temperature gave
# newer samples the last offset, held, wrong by 0.04 deg/s per second of stall on this 2 degC/s
# ramp (three of twenty loaded runs then left 26-34 (deg/s)/h on x). docs/compensation.md has the
# twenty loaded runs with the hold.
ANALYZER_PARAMS = ['chunk_size:=2000', 'memory:=200', 'order_grid_step:=0.05',
                   'diagnostics_period_s:=0.5', 'allan:=false',
                   'drift_abs_warn_deg_s_per_h:=50.0', 'drift_abs_error_deg_s_per_h:=100000.0',
                   'reliable:=true']


class _Chain:
    """Start, and always stop, the processes of one run; logs in tmp_path."""

    def __init__(self, tmp_path, tag):
        self.tmp_path, self.tag, self.procs, self.logs = tmp_path, tag, [], []

    def start(self, name, argv, **kw):
        log = open(self.tmp_path / f'{self.tag}_{name}.log', 'w')
        self.logs.append(log)
        kw.setdefault('stdout', subprocess.DEVNULL)
        proc = subprocess.Popen(argv, stderr=log, env=dict(os.environ), **kw)
        self.procs.append(proc)
        return proc

    def driver(self, port, *params):
        """Start the driver on a port nobody serves yet: it retries every 0.2 s."""
        argv = [sys.executable, '-m', 'gyro_noise_ros.nodes.driver', '--ros-args', '-p',
                f'port:=socket://127.0.0.1:{port}', '-p', 'reconnect_period_s:=0.2',
                # 9 s of reliable history at 6.66 kHz (the default is 0.75 s): a reliable
                # subscriber starved for seconds on a loaded host gets the messages resent instead
                # of overwritten (a run at load 13 lost 44 % of the training recording).
                '-p', 'qos_depth:=60000']
        for p in params:
            argv += ['-p', p]
        self.start('driver', argv)

    def emulator(self, port, args):
        """Start the board last, on the driver's port, so the driver connects at its power-on."""
        return self.start('emulator', [sys.executable, '-m', 'gyro_noise_ros.cli.emulator',
                                       '--tcp', f'127.0.0.1:{port}', *args])

    def wait_for_log(self, name, text, timeout_s):
        """Wait until the log of process ``name`` holds ``text``; fail with the logs if not."""
        path = self.tmp_path / f'{self.tag}_{name}.log'
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if text in path.read_text():
                return
            time.sleep(0.2)
        raise AssertionError(f'{name} never logged {text!r}\n{self.text()}')

    def stop(self):
        # Consumers first (the recorder closes its bag), then the driver, then the emulator.
        for proc in reversed(self.procs):
            if proc.poll() is None:
                proc.send_signal(2)
                try:
                    proc.wait(15)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        for log in self.logs:
            log.close()

    def text(self):
        return '\n'.join(f'--- {p.name}\n{p.read_text()[-2000:]}'
                         for p in sorted(self.tmp_path.glob(f'{self.tag}_*.log')))


def _ramp_args(seed, temp_c):
    return ['--seed', str(seed), '--accel-fs-g', '32', '--temp-c', str(temp_c),
            '--temp-drift-c-per-h', str(RAMP_C_PER_H),
            '--temp-sensitivity-dps-per-c', ','.join(map(str, SENSITIVITY_DPS_PER_C))]


def _fit_poly3(bag, out):
    """Fit poly3 on a recorded bag with the command-line tool; return model.json's path."""
    rc = thermal_cli.main(['fit', str(bag), '--method', 'poly3', '--no-figures', '--quiet',
                           '--out', str(out)])
    assert rc == 0
    return out / 'model.json'


@pytest.mark.slow
@pytest.mark.timeout(480)
def test_compensated_stream_shows_the_thermal_drift_gone(tmp_path):
    # 1. Training run, recorded. The nodes first and the board last: the board's temperature
    # ramps from its power-on, connected or not, so a driver that connects late (a loaded host:
    # seconds) would start the recording warmer, and the held-out run could begin below the
    # trained range, where poly3 holds its edge value and the compensated stream keeps the ramp
    # (CI saw 34 (deg/s)/h left on x that way).
    bag = tmp_path / 'train_bag'
    train = _Chain(tmp_path, 'train')
    port = free_port()
    try:
        train.start('recorder', [sys.executable, '-m', 'gyro_noise_ros.nodes.recorder',
                                 '--ros-args', '-p', f'output:={bag}', '-p', 'reliable:=true'])
        train.driver(port)
        up = collect_diagnostics(['lsm6dso32_driver: link'], lambda seen: all(seen.values()),
                                 timeout_s=120)
        assert all(up.values()), train.text()
        train.wait_for_log('recorder', 'recording', 120)
        train.emulator(port, _ramp_args(7, 25.0))
        # TRAIN_S of board time published, not of wall time from the emulator's start: on a
        # loaded host the board can take seconds to listen and the chain can fall behind (runs
        # at load 13 recorded 4-6 s of their 14 that way).
        wanted = int(TRAIN_S * 6667)
        up = collect_diagnostics(
            ['lsm6dso32_driver: link'], lambda seen: any(
                int(values(s)['Samples published']) >= wanted
                for s in seen['lsm6dso32_driver: link']), timeout_s=240)
        assert any(int(values(s)['Samples published']) >= wanted
                   for s in up['lsm6dso32_driver: link']), train.text()
    finally:
        train.stop()
    model_json = _fit_poly3(bag, tmp_path / 'model')
    training = json.loads(model_json.read_text())['training']
    assert training['duration_s'] > TRAIN_S / 2, train.text()

    # 2. Held-out run: raw and compensated side by side.
    test = _Chain(tmp_path, 'test')
    names = [f'{a}: axis {x}' for a in ('analyzer_raw', 'analyzer_comp') for x in 'xyz']
    names.append('imu_compensator: compensation')
    chunks_wanted = 16

    def done(seen):
        return all(seen[n] and chunks(seen[n][-1]) >= chunks_wanted for n in names[:-1]) \
            and bool(seen[names[-1]])

    port = free_port()

    try:
        for name, remap in (('analyzer_raw', []),
                            ('analyzer_comp', ['-r', 'imu/data_raw:=imu/data_compensated'])):
            argv = [sys.executable, '-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args',
                    '-r', f'__node:={name}', *remap]
            for p in ANALYZER_PARAMS:
                argv += ['-p', p]
            test.start(name, argv)
        test.start('compensator', [sys.executable, '-m', 'gyro_noise_ros.nodes.compensator',
                                   '--ros-args', '-p', f'thermal_model_file:={model_json}',
                                   '-p', 'drain_period_s:=0.02', '-p', 'reliable:=true'])
        test.driver(port)
        ready = [*names, 'lsm6dso32_driver: link']
        up = collect_diagnostics(ready, lambda seen: all(seen.values()), timeout_s=120)
        assert all(up.values()), ([n for n in ready if not up[n]], test.text())
        # 27 degC, 2 degC above the training run's start: the held-out run (about 5-10 s, 10-20
        # degC) stays inside the trained 25-53 degC even if a driver connects a second late.
        test.emulator(port, _ramp_args(8, 27.0))
        seen = collect_diagnostics(names, done, timeout_s=150)
    finally:
        test.stop()
    assert done(seen), ({n: seen[n] and chunks(seen[n][-1]) for n in names[:-1]}, test.text())

    comp = values(seen['imu_compensator: compensation'][-1])
    drifts = {a: float(values(seen[f'analyzer_comp: axis {a}'][-1])['Offset drift ((deg/s)/h)'])
              for a in 'xyz'}
    # One line for a campaign of runs (pytest -s): what the hold did in this one.
    print(f"compensator: longest wait {comp['Longest wait for a temperature (s)']} s, held "
          f"offset {comp['Messages compensated with a held offset']}, published "
          f"{comp['Messages published']}, dropped before the node "
          f"{comp['Messages dropped before the node']}; compensated drift "
          + ', '.join(f'{a} {d:.1f}' for a, d in drifts.items()) + ' (deg/s)/h; raw x: '
          + ', '.join(f'{k} {values(seen["analyzer_raw: axis x"][-1]).get(k)}' for k in (
              'Offset drift ((deg/s)/h)', 'Sample rate (Hz)', 'Samples lost',
              'Chunks analysed')))
    assert comp['Thermal model'] == 'poly3'
    # The held-out run stays inside the training run's temperature span (it is shorter).
    assert comp['Temperature range status'] == 'inside', comp
    for axis, expected in zip('xyz', EXPECTED_DRIFT):
        raw = values(seen[f'analyzer_raw: axis {axis}'][-1])
        fixed = values(seen[f'analyzer_comp: axis {axis}'][-1])
        raw_drift = float(raw['Offset drift ((deg/s)/h)'])
        fixed_drift = float(fixed['Offset drift ((deg/s)/h)'])
        # The raw stream carries the emulator's ramp x sensitivity; the analyzer's slope over 16+
        # chunks of 0.3 s has a standard error of a few (deg/s)/h on the emulator's default noise,
        # so 15 % of 72-144 (deg/s)/h is several standard errors wide.
        assert raw_drift == pytest.approx(expected, rel=0.15), (axis, raw_drift, expected)
        # Compensated: left are the slope noise, the model's lag (the offset is held between
        # 52-Hz temperature messages: a constant, which does not tilt the slope) and the fit's
        # error. The last dominates: the emulator's fractional noise (alpha 1.4) wanders slowly,
        # and on a run whose temperature rises monotonically the fit takes part of that wander
        # for temperature dependence, whatever the axis' sensitivity. Measured on x, y, z: 0.3-5.0
        # (deg/s)/h in four runs on a quiet host; 20.2, 19.8, 9.7 in one run inside make test-slow
        # (a loaded host records a shorter training run: the fit sees less of the ramp). Hence one
        # bound for all axes, 20 % of the largest raw drift (29 (deg/s)/h): 80 % of the drift gone.
        limit = 0.2 * max(abs(d) for d in EXPECTED_DRIFT)
        assert abs(fixed_drift) < limit, (axis, fixed_drift, limit, test.text())


# --- The oven: the emulator's thermal model (paper 002 section 4.1, docs/thermal_data.md) ---
#
# ``--thermal oven`` streams the die temperature lagging the oven (tau 600 s) and the gyro bias
# it causes (cubic + knee in T, a term in dT/dt, hysteresis). The whole 14 h profile heats then
# steps down, so a least-squares slope over all of it is not significantly non-zero on every axis
# (measured 1.4 sigma on x): the analyzer's offset drift is a straight line. The test streams the
# profile's first 30 s at 267x compression, i.e. its first 8010 s: the room hold, the heat to
# 60 degC at 2 degC/min and most of the hold there (a warm-up, which is what the seeker's loop
# sees). The bias then moves by (+0.55, -0.14, +0.25) deg/s: offset drift about (67, -23, 27)
# (deg/s)/h at 6-10 sigma of the analyzer's drift standard error (the robust one: the largest of
# OLS, Newey-West and variogram), on 833 Hz with the paper-000 noise (0.058 deg/s per sample).
OVEN_COMPRESS = 267.0
OVEN_DURATION_S = 30.0
# 833 Hz, not 6.66 kHz: the chain (5 processes) must keep up on a loaded 2-core machine; the
# thermal model does not depend on the rate. One Temperature message every 16 samples is the
# sensor's 52 Hz temperature output, as the driver's default decimation (128) gives at 6.66 kHz.
OVEN_ODR_HZ = 833.0
OVEN_TEMPERATURE_DECIMATION = 16
OVEN_ANALYZER_PARAMS = ['chunk_size:=500', 'memory:=200', 'order_grid_step:=0.05',
                        'diagnostics_period_s:=0.5', 'allan:=false', 'reliable:=true']


def _oven_emulator_args(seed):
    return ['--thermal', 'oven', '--thermal-compress', str(OVEN_COMPRESS), '--temp-c', '25.0',
            '--odr-hz', str(OVEN_ODR_HZ), '--accel-fs-g', '32', '--seed', str(seed),
            '--duration-s', str(OVEN_DURATION_S)]


def test_write_bag_temperature_decimation(tmp_path, capsys):
    # The oven test's training bag carries Temperature as the driver publishes it: one message
    # for every N-th sample (N = 16 at 833 Hz is the sensor's 52 Hz), stamped as that sample.
    from gyro_noise_ros.bag import ImuBagReader
    from gyro_noise_ros.cli import emulator as emulator_cli
    import numpy as np

    common = _oven_emulator_args(1)[:-2] + ['--samples', '1000']
    for decimation, expected in ((16, 63), (0, 2)):  # 0: once a second (833 samples)
        bag = tmp_path / f'd{decimation}'
        assert emulator_cli.main(common + ['--write-bag', str(bag),
                                           '--bag-temperature-decimation',
                                           str(decimation)]) == 0
        with ImuBagReader(bag) as reader:
            imu = np.concatenate([b.stamp_ns for b in reader.iter_batches()])
            stamp, temp = reader.read_temperature()
        every = decimation or 833
        np.testing.assert_array_equal(stamp, imu[::every])
        assert stamp.size == expected
        assert np.all((temp > 20.0) & (temp < 30.0))  # room 25 degC + 2 self-heating, early
    assert emulator_cli.main(common + ['--write-bag', str(tmp_path / 'bad'),
                                       '--bag-temperature-decimation', '-1']) == 2
    assert not (tmp_path / 'bad').exists()
    assert 'bag-temperature-decimation' in capsys.readouterr().err


def _statuses_after(seen, marks, name):
    return seen[name][marks[name]:] if marks else []


@pytest.mark.slow
@pytest.mark.timeout(400)
def test_oven_drift_gone_on_the_compensated_stream(tmp_path):
    from gyro_noise_ros.cli import emulator as emulator_cli
    from gyro_noise_ros.core.health import drift_t_threshold

    # 1. Training run (seed 7) at the same compression, written by the emulator as the driver
    # would publish it (--write-bag: same quantisation, Temperature at the same 52 Hz), and the
    # documented fit: the default method bp (causal), inputs T and its trailing-window rate.
    # Training at the live compression matters: the rate input is in degC per real second, 267x
    # the natural rate here; a model trained on an uncompressed run would see rates far outside
    # its training inputs.
    bag = tmp_path / 'oven_train'
    assert emulator_cli.main(_oven_emulator_args(7) + [
        '--write-bag', str(bag),
        '--bag-temperature-decimation', str(OVEN_TEMPERATURE_DECIMATION)]) == 0
    rc = thermal_cli.main(['fit', str(bag), '--method', 'bp', '--no-figures', '--quiet',
                           '--out', str(tmp_path / 'model')])
    assert rc == 0
    model_json = tmp_path / 'model' / 'model.json'
    assert json.loads(model_json.read_text())['causal'] is True

    # 2. Held-out run (seed 8): nodes first, the board last, so the analyzers see the profile
    # from its start (the board's clock runs from power-on, connected or not).
    chain = _Chain(tmp_path, 'oven')
    names = [f'{a}: axis {x}' for a in ('analyzer_raw', 'analyzer_comp') for x in 'xyz']
    names += ['imu_compensator: compensation', 'lsm6dso32_driver: link']
    port = free_port()
    marks = {}  # per status: how many had arrived when the board was seen to have stopped
    emu = None

    def done(seen):
        # Finished when the board has stopped and every analyzer's chunk count has stayed put
        # over its last 4 statuses (2 s) since then: everything sent has been analysed.
        if emu is None or emu.poll() is None:
            return False
        if not marks:
            marks.update({n: len(seen[n]) for n in names})
            return False
        for name in names[:6]:
            after = _statuses_after(seen, marks, name)
            if len(after) < 4 or len({chunks(s) for s in after[-4:]}) != 1:
                return False
        return bool(_statuses_after(seen, marks, names[6]))

    try:
        for name, remap in (('analyzer_raw', []),
                            ('analyzer_comp', ['-r', 'imu/data_raw:=imu/data_compensated'])):
            argv = [sys.executable, '-m', 'gyro_noise_ros.nodes.analyzer', '--ros-args',
                    '-r', f'__node:={name}', *remap]
            for p in OVEN_ANALYZER_PARAMS:
                argv += ['-p', p]
            chain.start(name, argv)
        # The compensator keeps its default best-effort input here (the reliable input is the
        # ramp test's).
        chain.start('compensator', [sys.executable, '-m', 'gyro_noise_ros.nodes.compensator',
                                    '--ros-args', '-p', f'thermal_model_file:={model_json}'])
        chain.driver(port, f'odr_hz:={OVEN_ODR_HZ}',
                     f'temperature_decimation:={OVEN_TEMPERATURE_DECIMATION}')
        up = collect_diagnostics(names, lambda seen: all(seen[n] for n in names), timeout_s=120)
        assert all(up[n] for n in names), ([n for n in names if not up[n]], chain.text())
        emu = chain.emulator(port, _oven_emulator_args(8))
        seen = collect_diagnostics(names, done, timeout_s=240)
    finally:
        chain.stop()
    assert done(seen), ({n: seen[n] and chunks(seen[n][-1]) for n in names[:6]}, chain.text())

    comp = values(seen['imu_compensator: compensation'][-1])
    assert comp['Thermal model'] == 'bp', comp
    assert comp['Temperature range status'] != 'outside', comp
    assert int(comp['Messages published']) > 0.7 * OVEN_DURATION_S * OVEN_ODR_HZ, comp
    for axis in 'xyz':
        raw = values(seen[f'analyzer_raw: axis {axis}'][-1])
        fixed = values(seen[f'analyzer_comp: axis {axis}'][-1])
        n_raw, n_fixed = int(raw['Chunks analysed']), int(fixed['Chunks analysed'])
        # ~48 chunks of 0.6 s in 30 s; a slow start or skipped analyses cost a few.
        assert min(n_raw, n_fixed) >= 30, (axis, n_raw, n_fixed, chain.text())
        raw_drift = float(raw['Offset drift ((deg/s)/h)'])
        fixed_drift = float(fixed['Offset drift ((deg/s)/h)'])
        raw_sigma = float(raw['Offset drift significance (sigma)'])
        fixed_sigma = float(fixed['Offset drift significance (sigma)'])
        # The analyzer's own rule: |slope| / stderr above the two-sided 3-sigma Student-t
        # quantile (3.2 at 48 chunks) is a drift. Raw: measured 6.3-9.8 sigma on five seeds
        # offline, a thermal (deterministic) drift, so the margin is the model's, not luck's.
        assert raw_sigma > drift_t_threshold(3.0, n_raw), (axis, raw, chain.text())
        # Compensated: what is left is the fit's error and the paper-000 noise; measured offline
        # on five held-out seeds (the live evaluator fed as the node feeds it) 0.04-1.4 sigma,
        # |drift| below 0.6 (deg/s)/h. Not significant by the same rule, and below 5 % of the
        # raw drift (23-67 (deg/s)/h), so 'gone' is both statistical and in magnitude.
        assert fixed_sigma < drift_t_threshold(3.0, n_fixed), (axis, fixed, raw, chain.text())
        assert abs(fixed_drift) < 0.05 * abs(raw_drift), (axis, fixed_drift, raw_drift)
