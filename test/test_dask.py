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
``--scheduler``: the same pure work units on a Dask cluster give the local run's results.

One ``distributed.LocalCluster`` (2 worker processes, 1 thread each) serves the module. The oracle
of every comparison is the same tool run locally in the same test (in-process, ``jobs=1``, the
path every other test checks): gyro_noise_analyze's chunks.csv must be byte-identical and the
numbers of summary.json equal; a worker killed in the middle of a run changes nothing and every
chunk is written exactly once; the explain ensemble and the thermal MOPSO give the same result.
Without ``distributed`` (or under ``CI=true`` with it missing: a failure) the cluster tests skip
with the reason; the missing-dependency test runs everywhere. The cluster tests are marked slow
(``make test-slow``, which CI runs after ``make test``).
"""

import csv
import functools
import io
import json
import os
import signal
import socket

from gyro_noise_ros import cluster
from gyro_noise_ros.app import analyze as analyze_app
from gyro_noise_ros.cli.analyze import main as analyze_main
from gyro_noise_ros.cli.explain import main as explain_main
from gyro_noise_ros.cli.thermal import main as thermal_main
from gyro_noise_ros.core.simulate import simulate_fractional_noise
import numpy as np
import pytest

HAVE_DASK = cluster.dask_available()
if not HAVE_DASK and os.environ.get('CI') == 'true':
    raise RuntimeError('CI=true but distributed is not installed: `make venv` installs the dask '
                       'extra; test/test_dask.py must run in CI')
needs_dask = pytest.mark.skipif(not HAVE_DASK,
                                reason="distributed not installed (pip install -e '.[dask]')")
#: The tests on the module's LocalCluster (started once, 2 worker processes): ``make test-slow``
#: runs them. Each ships its work to the worker processes and compares it with the local run, so
#: together they cost minutes of CPU on 2 cores (the thermal MOPSO one alone 40-80 s); the
#: cluster-free tests of ``--scheduler`` (unreachable scheduler, distributed missing) stay in
#: ``make test``.
on_the_cluster = pytest.mark.slow

RATE_HZ = 6660.0
#: Small chunks and a coarse grid keep one chunk at a few ms; 14 chunks per axis, 3 axes.
ANALYZE = ['--chunk-size', '1000', '--memory', '60', '--order-grid', '0:2:0.05', '--static',
           'off', '--no-figures', '--quiet']


@pytest.fixture(scope='module')
def dask_cluster():
    if not HAVE_DASK:
        pytest.skip("distributed not installed (pip install -e '.[dask]')")
    import dask
    from distributed import LocalCluster

    # Two worker processes (not threads) so that one can be killed; no dashboard (no bokeh);
    # workers without Dask's MALLOC_TRIM_THRESHOLD_, as docs/scale.md advises (speed only).
    with dask.config.set({'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_': None}):
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None, worker_dashboard_address=None,
                          silence_logs=50) as c:
            yield c


@pytest.fixture(scope='module')
def table(tmp_path_factory):
    """Write a 3-axis CSV record (fractional noise, paper model): 14 chunks of 1000 per axis."""
    rng = np.random.default_rng(12)
    n = 14500
    gyro = np.stack([simulate_fractional_noise(n, 1.3, -0.4, 1e-3, rng=rng, memory=60)
                     for _ in range(3)], 1)
    path = tmp_path_factory.mktemp('dask') / 'rec.csv'
    lines = ['time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s']
    lines += [f'{k / RATE_HZ!r},{float(g[0])!r},{float(g[1])!r},{float(g[2])!r}'
              for k, g in enumerate(gyro)]
    path.write_text('\n'.join(lines) + '\n')
    return path


@pytest.fixture(scope='module')
def local_run(table, tmp_path_factory):
    out = tmp_path_factory.mktemp('local')
    assert analyze_main([str(table), '--out', str(out), '--jobs', '1', *ANALYZE]) == 0
    return out


def _chunks(out):
    return list(csv.DictReader(io.StringIO((out / 'chunks.csv').read_text())))


def _bags(out):
    return json.loads((out / 'summary.json').read_text())['bags']


def _same_as_local(local, out):
    assert (out / 'chunks.csv').read_bytes() == (local / 'chunks.csv').read_bytes()
    assert _bags(out) == _bags(local)
    # every chunk exactly once, in order (the oracle's order: chunk index, then axis)
    keys = [(r['axis'], r['chunk']) for r in _chunks(out)]
    assert len(keys) == len(set(keys)) == 42


@needs_dask
@on_the_cluster
def test_analyze_on_the_cluster_is_identical_to_the_local_run(dask_cluster, table, local_run,
                                                              tmp_path):
    out = tmp_path / 'dask'
    assert analyze_main([str(table), '--out', str(out), '--scheduler',
                         dask_cluster.scheduler_address, *ANALYZE]) == 0
    _same_as_local(local_run, out)
    options = json.loads((out / 'summary.json').read_text())['options']
    assert options['scheduler'] == dask_cluster.scheduler_address


@needs_dask
@on_the_cluster
def test_executor_map_keeps_order_with_a_small_window(dask_cluster):
    pool = cluster.make_executor(scheduler=dask_cluster)
    try:
        got = list(pool.map(pow, range(20), [3] * 20, window=3))
    finally:
        pool.shutdown()
    assert got == [k ** 3 for k in range(20)]
    assert pool.client.status == 'closed'


def alignment(x):
    """Return the address of an array's data modulo 16, as a work unit sees it."""
    return x.ctypes.data % 16


@needs_dask
@on_the_cluster
def test_work_units_get_aligned_arrays_and_full_size_chunks_match(dask_cluster):
    from gyro_noise_ros.core.engine import analyze_chunk, EngineConfig, NoiseEngine

    # Dask alone hands a worker views into the message at any byte offset (float64 at odd
    # addresses were seen, and gave a var_min 1 ulp off): each work unit must see aligned arrays,
    # as in a local process.
    pool = cluster.make_executor(scheduler=dask_cluster.scheduler_address)
    try:
        # (numpy allocates with malloc: 16-byte aligned; pickled bytes keep that alignment)
        assert [pool.submit(alignment, np.arange(float(n))).result() for n in (7, 10000)] == [0, 0]
        # Full-size chunks (10,000 samples, the default grid), as the bench runs them.
        engine = NoiseEngine(EngineConfig(axes=('x',), rate_hz=RATE_HZ))
        rng = np.random.default_rng(3)
        n = 80000
        jobs = engine.ingest(np.arange(n, dtype=np.int64) * 150_150, rng.normal(size=(n, 3)))
        jobs += engine.flush()
        futures = [pool.submit(analyze_chunk, job, curves=True) for job in jobs]
        for job, future in zip(jobs, futures):
            local, remote = analyze_chunk(job, curves=True), future.result()
            assert remote == local
            assert np.array_equal(remote.var_curve, local.var_curve)
            assert np.array_equal(remote.j_curve, local.j_curve)
    finally:
        pool.shutdown()
    assert len(jobs) == 8


@needs_dask
@on_the_cluster
@pytest.mark.filterwarnings('ignore:Port .* is already in use')  # another user's dashboard
def test_workers_are_checked_on_connecting(dask_cluster, monkeypatch):
    from distributed import LocalCluster

    said = []
    pool = cluster.make_executor(scheduler=dask_cluster, warn=said.append)
    pool.shutdown()
    assert said == []  # the fixture's workers run without MALLOC_TRIM_THRESHOLD_
    # A worker in this process (threads) sees this process's environment and version.
    monkeypatch.setenv('MALLOC_TRIM_THRESHOLD_', '65536')
    with LocalCluster(n_workers=1, processes=False, dashboard_address=None,
                      worker_dashboard_address=None) as c:
        cluster.make_executor(scheduler=c, warn=said.append).shutdown()
        assert len(said) == 1
        assert '1 of 1 worker(s) run with a small MALLOC_TRIM_THRESHOLD_' in said[0]
        assert cluster.MALLOC_ADVICE in said[0]
        # a worker with another version of the package is refused
        monkeypatch.setattr(cluster, 'worker_facts', lambda: {'version': '0.0.0-other'})
        with pytest.raises(cluster.ClusterError, match=r'1 worker\(s\) do not have gyro_noise_ros '
                           r'.*\(0.0.0-other\); install the same version'):
            cluster.make_executor(scheduler=c)


@needs_dask
@on_the_cluster
def test_a_task_error_is_the_task_error(dask_cluster):
    # A bug inside a work unit is not a cluster failure: its own exception comes back.
    pool = cluster.make_executor(scheduler=dask_cluster.scheduler_address)
    try:
        with pytest.raises(ZeroDivisionError):
            pool.submit(divmod, 1, 0).result()
    finally:
        pool.shutdown()


@needs_dask
@on_the_cluster
def test_explain_ensemble_on_the_cluster_is_identical(dask_cluster):
    from gyro_noise_ros.explain.synthetic import make_record
    from gyro_noise_ros.explain.workflow import explain

    meas, _ = make_record(('sinusoid',), np.random.default_rng([1, 7]), n=10000)
    local = explain(meas, seed=1, ensemble=6, max_steps=1)
    pool = cluster.make_executor(scheduler=dask_cluster.scheduler_address)
    try:
        remote = explain(meas, seed=1, ensemble=6, max_steps=1, mapper=pool.map)
    finally:
        pool.shutdown()
    a, b = local.to_dict(), remote.to_dict()
    a.pop('seconds')
    b.pop('seconds')
    assert a == b
    assert a['steps'], 'the small case must take at least one step (members re-evaluated)'
    for name, c in local.comparisons_final.items():
        d = remote.comparisons_final[name]
        assert np.array_equal(c.mu, d.mu) and np.array_equal(c.sd, d.sd)


@needs_dask
@on_the_cluster
def test_explain_cli_with_scheduler_writes_the_local_explain_json(dask_cluster, table, tmp_path):
    # The CLI wiring: --scheduler reaches explain() (no step needed here: the initial ensemble
    # is already evaluated through the cluster).
    common = [str(table), '--axis', 'x', '--ensemble', '4', '--max-steps', '0', '--static', 'off',
              '--quiet']
    assert explain_main([*common, '--out', str(tmp_path / 'local')]) == 0
    assert explain_main([*common, '--out', str(tmp_path / 'dask'), '--scheduler',
                         dask_cluster.scheduler_address]) == 0
    docs = []
    for name in ('local', 'dask'):
        doc = json.loads((tmp_path / name / 'explain.json').read_text())
        doc.pop('seconds')
        docs.append(doc)
    assert docs[0] == docs[1]
    assert docs[0]['ensemble'] == 4 and docs[0]['input']['samples'] == 14500


def _thermal_bag(path, seed):
    from _thermal_toy import write_thermal_bag

    rate = 20.0
    rng = np.random.default_rng(seed)
    t = np.arange(1600) / rate
    temp_t = np.arange(0.0, t[-1] + 1.0, 1.0)
    temp = 10.0 + 30.0 * 0.5 * (1 - np.cos(2 * np.pi * temp_t / (t[-1] + 1.0)))
    temp_at = np.interp(t, temp_t, temp)
    gyro = rng.normal(0.0, 2e-3, (t.size, 3)) + np.outer(temp_at - 25.0, [2e-4, -1e-4, 5e-5])
    write_thermal_bag(path, t, gyro, temp_t, temp)
    return str(path)


@needs_dask
@on_the_cluster
def test_thermal_mopso_particles_on_the_cluster_give_the_same_model(dask_cluster, tmp_path):
    from gyro_noise_ros.thermal import methods
    from gyro_noise_ros.thermal.bag_io import read_thermal_run

    # The paper's MOPSO budget (40 particles x 10 iterations) would take minutes here; a small
    # one runs the same code path (the particles evaluated through the executor's map). The CLI
    # passes its --scheduler executor to fit_method exactly so (the exit-5 test shows it connects).
    run, _ = read_thermal_run(_thermal_bag(tmp_path / 'train', 5))
    small = {'n_particles': 6, 'iterations': 2, 'fitness_samples': 128, 'elman_epochs': 2,
             'elman_iterations': 5, 'elman_samples': 400, 'refine_points': 2, 'refine_polish': 2,
             'refine_samples': 256}
    local = methods.fit_method('parallel', run, rng=np.random.default_rng(4), **small)
    pool = cluster.make_executor(scheduler=dask_cluster.scheduler_address)
    try:
        remote = methods.fit_method('parallel', run, rng=np.random.default_rng(4), executor=pool,
                                    **small)
    finally:
        pool.shutdown()
    assert remote.method.executor is None  # not kept: the model does not know where it ran
    assert json.dumps(remote.method.to_dict()) == json.dumps(local.method.to_dict())
    assert local.method.fit_info[0]['mopso']['evaluations'] > 6


def _free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


@needs_dask
@pytest.mark.parametrize('tool', ['analyze', 'explain', 'thermal'])
def test_unreachable_scheduler_is_one_line_and_exit_5(tool, table, tmp_path, capsys):
    import dask

    address = f'tcp://127.0.0.1:{_free_port()}'  # nothing listens there
    argv = {'analyze': lambda: analyze_main([str(table), '--out', str(tmp_path / 'o'),
                                             '--scheduler', address, *ANALYZE]),
            'explain': lambda: explain_main([str(table), '--axis', 'x', '--out',
                                             str(tmp_path / 'o'), '--scheduler', address]),
            'thermal': lambda: thermal_main(['fit', _thermal_bag(tmp_path / 'b', 1), '--out',
                                             str(tmp_path / 'o'), '--scheduler', address])}
    with dask.config.set({'distributed.comm.timeouts.connect': '1s'}):
        assert argv[tool]() == 5
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f'gyro_noise_{tool}: error: --scheduler {address}: cannot connect')


@needs_dask
# slow: a fresh interpreter that imports distributed and the analyzer (10-20 s); the same line
# in-process is test_unreachable_scheduler_is_one_line_and_exit_5
@pytest.mark.slow
def test_unreachable_scheduler_whole_process_stderr_is_one_line(table, tmp_path):
    # In a process of its own: nothing may print after the error line (e.g. a half-started
    # Client's traceback when it is collected at exit).
    import subprocess
    import sys

    address = f'tcp://127.0.0.1:{_free_port()}'
    env = {**os.environ, 'DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT': '1s'}
    proc = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.analyze', str(table), '--out',
                           str(tmp_path / 'o'), '--scheduler', address, *ANALYZE],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 5
    assert proc.stderr.strip().splitlines() == [
        f'gyro_noise_analyze: error: --scheduler {address}: cannot connect to a Dask scheduler '
        f'there (OSError: Timed out trying to connect to {address} after 1 s)']


def test_without_distributed_scheduler_is_one_line_naming_the_extra(table, tmp_path, capsys,
                                                                    monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, 'distributed', None)  # import distributed -> ImportError
    assert not cluster.dask_available()
    assert analyze_main([str(table), '--out', str(tmp_path / 'o'), '--scheduler',
                         'tcp://127.0.0.1:8786', *ANALYZE]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    missing = cluster.MISSING.replace('{scheduler}', '--scheduler')  # the tool names its option
    assert err == [f'gyro_noise_analyze: error: {missing}']
    assert "pip install 'gyro_noise_ros[dask]'" in err[0]
    # without --scheduler nothing needs it
    assert analyze_main([str(table), '--out', str(tmp_path / 'p'), '--jobs', '1', *ANALYZE]) == 0


def die_once(marker, chunk, job, **kwargs):
    """
    Run analyze_chunk, but SIGKILL the worker process the first time chunk ``chunk`` of y runs.

    The marker file (created atomically) records the killed process id; the retried task finds it
    and runs normally. Runs on the Dask workers (imported there by reference: the spawned worker
    processes inherit this process's sys.path).
    """
    from gyro_noise_ros.core.engine import analyze_chunk

    if job.axis == 'y' and job.chunk == chunk:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os.kill(os.getpid(), signal.SIGKILL)
    return analyze_chunk(job, **kwargs)


@needs_dask
@on_the_cluster
def test_a_worker_killed_mid_run_loses_and_duplicates_nothing(dask_cluster, table, local_run,
                                                              tmp_path, monkeypatch):
    # The worker process running chunk 5 of axis y dies in the middle of the run (SIGKILL, as
    # the kernel's OOM killer or a pulled cable would end it): Dask computes the task again on
    # a live worker; every chunk is in chunks.csv once and the files equal the local run's.
    marker = tmp_path / 'killed.pid'
    monkeypatch.setattr(analyze_app, 'analyze_chunk', functools.partial(die_once, str(marker), 5))
    out = tmp_path / 'killed'
    assert analyze_main([str(table), '--out', str(out), '--scheduler',
                         dask_cluster.scheduler_address, *ANALYZE]) == 0
    assert marker.exists(), 'the work unit never ran chunk 5 of y: nothing was tested'
    pid = int(marker.read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # that worker process is gone
    _same_as_local(local_run, out)
    # the nanny restarts the worker: the cluster is whole again for later users
    from distributed import Client

    with Client(dask_cluster.scheduler_address, set_as_default=False) as client:
        client.wait_for_workers(2, timeout=120)
        assert pid not in client.run(os.getpid).values()
