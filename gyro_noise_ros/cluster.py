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
Where the pure work units run: local worker processes, or a Dask distributed cluster.

The tools hand their heavy, pure work units (one chunk of one axis in gyro_noise_analyze, one
ensemble member's signatures in gyro_noise_explain, one MOPSO particle in gyro_noise_thermal) to a
:class:`concurrent.futures.Executor` and take the results back in submission order.
:func:`make_executor` returns that executor:

* no scheduler: a :class:`~concurrent.futures.ProcessPoolExecutor` of ``jobs`` processes, or
  ``None`` for ``jobs <= 1`` (the caller then runs in-process);
* ``scheduler='tcp://host:8786'``: a :class:`DaskExecutor` on a ``distributed.Client``, tasks
  submitted ``pure=True`` (a task Dask runs again after losing a worker gives the same result).

Results are bit-identical to a local run: a task travels as one pickle (protocol 4, arrays
in-band) that the worker unpickles into aligned arrays, as a local worker process does (Dask's own
views may sit at odd addresses, where numpy sums differ in the last bit), and back the same way.
``distributed`` is optional (pip extra ``dask``), imported only when a scheduler is named; without
it a scheduler gives :class:`~gyro_noise_ros.errors.ParameterError` (exit 2) naming the extra. A
scheduler that cannot be reached, or is lost during the run, gives
:class:`~gyro_noise_ros.errors.ClusterError` (exit 5). Measurements: docs/scale.md.
"""

import asyncio
import collections
from collections.abc import Callable, Iterable, Iterator
import concurrent.futures as cf
import itertools
import logging
import os
import pickle
from typing import Any, ParamSpec, TypeVar

from . import __version__
from .errors import ClusterError, ParameterError

_T = TypeVar('_T')
_P = ParamSpec('_P')

#: pip extra that installs Dask distributed.
EXTRA = 'dask'
#: The one line shown when ``distributed`` is missing.
MISSING = ('{scheduler} needs Dask distributed, which is not installed: pip install '
           f"'gyro_noise_ros[{EXTRA}]', or pip install distributed, or apt install "
           'python3-distributed')


def dask_available() -> bool:
    """
    Tell whether ``distributed`` can be imported.

    Returns
    -------
    bool

    """
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


#: Local worker processes allowed per usable CPU: beyond it a process pool only adds memory
#: (each worker holds its own interpreter and kernels, ~150 MB) and contention; --jobs 99999
#: once forked 4,500 processes on a 2-core machine.
MAX_JOBS_PER_CPU = 4


def usable_cpus() -> int:
    """
    Return the number of CPUs this process may run on.

    Returns
    -------
    int

    """
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def check_jobs(jobs: int) -> None:
    """
    Refuse a number of local worker processes this machine cannot run (exit code 2).

    Parameters
    ----------
    jobs : int
        ``--jobs``.

    Raises
    ------
    ParameterError
        Below 1, or above :data:`MAX_JOBS_PER_CPU` times :func:`usable_cpus`.

    """
    limit = MAX_JOBS_PER_CPU * usable_cpus()
    if not 1 <= int(jobs) <= limit:
        raise ParameterError(f'{{jobs}} must be 1 to {limit} ({MAX_JOBS_PER_CPU} per usable '
                             f'CPU), got {jobs}', parameters=('jobs',))


def make_executor(jobs: int = 1, scheduler: Any = None, *, timeout_s: float | None = None,
                  warn: Callable[[str], None] | None = None) -> cf.Executor | None:
    """
    Return the executor for the work units: local processes, or a Dask cluster.

    Parameters
    ----------
    jobs : int
        Worker processes without a scheduler (``<= 1``: ``None`` is returned and the caller
        works in-process). Ignored with a scheduler (the cluster has its own workers).
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``, ``host:8786``), or a cluster object
        with a ``scheduler_address`` (e.g. a ``distributed.LocalCluster``).
    timeout_s : float, optional
        Connection timeout (s); default Dask's ``distributed.comm.timeouts.connect`` (30 s,
        environment variable ``DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT``).
    warn : callable, optional
        Called with one line of text about the cluster's set-up (workers started with Dask's
        default ``MALLOC_TRIM_THRESHOLD_=65536``: about 2x slower, see docs/scale.md).

    Returns
    -------
    concurrent.futures.Executor or None
        ``shutdown()`` it at the end (for a :class:`DaskExecutor` that closes the client).

    Raises
    ------
    ParameterError
        ``distributed`` is not installed, the address is empty, or ``jobs`` is more than this
        machine can run (:func:`check_jobs`).
    ClusterError
        The scheduler cannot be reached, or a worker lacks this version of gyro_noise_ros.

    """
    if scheduler is None:
        if int(jobs) <= 1:
            return None
        check_jobs(jobs)
        return cf.ProcessPoolExecutor(max_workers=int(jobs))
    address = getattr(scheduler, 'scheduler_address', scheduler)
    if not isinstance(address, str) or not address.strip():
        raise ParameterError(f'{{scheduler}} needs an address such as tcp://host:8786, got '
                             f'{address!r}', parameters=('scheduler',))
    try:
        import distributed
    except ImportError:
        raise ParameterError(MISSING, parameters=('scheduler',)) from None
    import dask.utils

    address = address.strip()
    if timeout_s is None:
        timeout_s = dask.utils.parse_timedelta(
            dask.config.get('distributed.comm.timeouts.connect'), 's')
    try:
        # Probe first: a Client that fails to start prints a traceback when it is collected.
        asyncio.run(_probe(address, float(timeout_s)))
        client = distributed.Client(address, set_as_default=False, timeout=float(timeout_s))
    except (OSError, TimeoutError, ValueError, TypeError) as err:
        raise _cluster_error(address, 'cannot connect to a Dask scheduler there '
                             f'({_reason(err)})') from None
    restore = _mute_dask_logs()
    try:
        _check_workers(client, address, warn)
    except BaseException:
        client.close()
        restore()
        raise
    return DaskExecutor(client, restore=restore)


def _mute_dask_logs() -> Callable[[], None]:
    """
    Keep Dask's own log handlers (stderr) to CRITICAL while the tool's client is open.

    distributed logs a lost scheduler as an ERROR with a traceback on stderr; the tools say it
    in one line (:class:`ClusterError`). Returns the function that restores the levels.
    """
    saved = [(h, h.level) for name in ('distributed', 'tornado')
             for h in logging.getLogger(name).handlers]
    for handler, _ in saved:
        handler.setLevel(max(handler.level, logging.CRITICAL))

    def restore() -> None:
        for handler, level in saved:
            handler.setLevel(level)

    return restore


async def _probe(address: str, timeout_s: float) -> None:
    from distributed.comm import connect
    from distributed.security import Security

    # the client's TLS settings (distributed.comm.tls) for tls:// addresses, as Client uses them
    args = Security().get_connection_args('client')
    comm = await connect(address, timeout=timeout_s, **args)
    await comm.close()


def _reason(err: BaseException) -> str:
    text = ' '.join(str(err).split())
    return f'{type(err).__name__}: {text}' if text else type(err).__name__


def worker_facts() -> dict[str, str | None]:
    """
    Return what the client checks on every worker (runs on the worker).

    ``version`` (gyro_noise_ros's) and ``malloc_trim_threshold`` (the glibc environment variable
    ``MALLOC_TRIM_THRESHOLD_``, None when unset).

    """
    return {'version': __version__,
            'malloc_trim_threshold': os.environ.get('MALLOC_TRIM_THRESHOLD_')}


def _small_trim(value: str | None) -> bool:
    """Tell whether a MALLOC_TRIM_THRESHOLD_ value makes glibc return freed memory too eagerly."""
    if value is None:
        return False
    try:
        return int(value) < 2**25  # glibc's own adaptive thresholds go up to 32 MiB
    except ValueError:
        return False


#: Set-up line for workers (docs/scale.md). Dask's nanny exports MALLOC_TRIM_THRESHOLD_=65536 to
#: its workers: glibc then returns freed memory at once and stops adapting its mmap threshold
#: (128 kB), so every temporary array of the identification comes with fresh page faults: about
#: 2x the CPU time per chunk.
MALLOC_ADVICE = ('set distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_ to null in the '
                 "workers' Dask configuration for about twice the speed (docs/scale.md)")


def _check_workers(client: Any, address: str, warn: Callable[[str], None] | None) -> None:
    """Refuse workers without this version of gyro_noise_ros; warn about a slow set-up."""
    try:
        found = client.run(worker_facts, on_error='return')
    except (OSError, TimeoutError) as err:
        raise _cluster_error(address, _reason(err)) from None
    bad = {w: (f.get('version') if isinstance(f, dict) else 'not installed')
           for w, f in found.items()
           if not (isinstance(f, dict) and f.get('version') == __version__)}
    if bad:
        listed = ', '.join(f'{w} ({v})' for w, v in sorted(bad.items())[:3])
        more = f' and {len(bad) - 3} more' if len(bad) > 3 else ''
        raise _cluster_error(
            address, f'{len(bad)} worker(s) do not have gyro_noise_ros {__version__}: '
            f'{listed}{more}; install the same version on every worker')
    trimmed = sum(1 for f in found.values() if _small_trim(f.get('malloc_trim_threshold')))
    if trimmed and warn is not None:
        warn(f'Dask scheduler {address}: {trimmed} of {len(found)} worker(s) run with '
             f'a small MALLOC_TRIM_THRESHOLD_ (the Dask default); {MALLOC_ADVICE}')


class DaskExecutor(cf.Executor):
    """
    A :class:`concurrent.futures.Executor` on a ``distributed.Client`` (pure tasks).

    ``submit`` returns a plain :class:`concurrent.futures.Future`; its ``result()`` raises the
    task's own exception, or :class:`ClusterError` when Dask gives up on the task (the scheduler
    lost, a task that killed ``distributed.scheduler.allowed-failures`` workers); cancelling it
    before it finishes cancels the Dask task.
    ``map`` yields results in input order and keeps at most ``2 x threads`` tasks in flight.
    ``shutdown`` closes the client. Build it with :func:`make_executor`.

    Parameters
    ----------
    client : distributed.Client
        Connected client; owned (closed by :meth:`shutdown`).
    restore : callable, optional
        Called after the client is closed (restores Dask's log levels).

    Attributes
    ----------
    client : distributed.Client
    address : str
        The scheduler's address.

    """

    def __init__(self, client: Any, *, restore: Callable[[], None] | None = None) -> None:
        self.client = client
        self._restore = restore
        self.address: str = client.scheduler.address
        self._pending: set[Any] = set()
        self._closed = False

    @property
    def nthreads(self) -> int:
        """Return the worker threads in the cluster now (>= 1)."""
        return max(1, sum(self.client.nthreads().values()))

    def submit(self, fn: Callable[_P, _T], /, *args: _P.args,
               **kwargs: _P.kwargs) -> 'cf.Future[_T]':
        """
        Submit ``fn(*args, **kwargs)`` as a pure Dask task.

        Parameters
        ----------
        fn : callable
            Importable on the workers (a module-level function of gyro_noise_ros).
        *args, **kwargs
            Its arguments (picklable).

        Returns
        -------
        concurrent.futures.Future

        """
        if self._closed:
            raise RuntimeError('cannot submit after shutdown')
        import cloudpickle

        payload = cloudpickle.dumps((fn, args, kwargs), protocol=_PROTOCOL)
        task = self.client.submit(run_pickled, payload, pure=True)
        out: cf.Future[_T] = cf.Future()
        self._pending.add(task)
        address = self.address

        def cancelled(out: 'cf.Future[_T]') -> None:
            if out.cancelled():  # the caller gave up on it: so does the cluster
                task.cancel()

        def done(task: Any) -> None:
            self._pending.discard(task)
            if out.done():
                return
            try:
                value, error = pickle.loads(task.result()), None
            except BaseException as err:  # noqa: B902 - handed to the waiting caller
                value, error = None, _translate(err, address)
            try:
                if error is None:
                    out.set_result(value)
                else:
                    out.set_exception(error)
            except cf.InvalidStateError:  # cancelled meanwhile
                pass

        out.add_done_callback(cancelled)
        task.add_done_callback(done)
        return out

    def map(self, fn: Callable[..., _T], *iterables: Iterable[Any],  # noqa: A003
            timeout: float | None = None, chunksize: int = 1,
            window: int | None = None) -> Iterator[_T]:
        """
        Return an iterator of ``fn(*args)`` over ``zip(*iterables)``, in order.

        Parameters
        ----------
        fn : callable
            The work unit (as for :meth:`submit`).
        *iterables
            Consumed lazily: at most ``window`` calls are in flight.
        timeout : float, optional
            Seconds to wait for each result.
        chunksize : int
            Ignored (for signature compatibility).
        window : int, optional
            Calls in flight (default ``2 x`` the cluster's threads).

        Returns
        -------
        iterator

        """
        window = int(window) if window else 2 * self.nthreads
        args = zip(*iterables)

        def results() -> Iterator[_T]:
            inflight = collections.deque(self.submit(fn, *a)
                                         for a in itertools.islice(args, window))
            try:
                while inflight:
                    value = inflight.popleft().result(timeout)
                    inflight.extend(self.submit(fn, *a) for a in itertools.islice(args, 1))
                    yield value
            finally:
                for f in inflight:
                    f.cancel()

        return results()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """
        Cancel what is left if asked, and close the client (the cluster keeps running).

        Parameters
        ----------
        wait : bool
            Wait for pending tasks unless ``cancel_futures``.
        cancel_futures : bool
            Cancel pending tasks.

        """
        if self._closed:
            return
        self._closed = True
        pending = list(self._pending)
        try:
            if cancel_futures and pending:
                self.client.cancel(pending)
            elif wait and pending:
                import distributed

                distributed.wait(pending)
        finally:
            try:
                self.client.close()
            finally:
                if self._restore is not None:
                    self._restore()


#: Pickle protocol of tasks and results: 4 keeps numpy arrays in-band (protocol 5 without a
#: buffer callback would too; 4 says so plainly).
_PROTOCOL = 4


def run_pickled(payload: bytes) -> bytes:
    """
    Run one work unit on a Dask worker: unpickle ``(fn, args, kwargs)``, call, pickle the result.

    Parameters
    ----------
    payload : bytes
        ``cloudpickle.dumps((fn, args, kwargs), protocol=4)``.

    Returns
    -------
    bytes
        The pickled result (protocol 4).

    """
    fn, args, kwargs = pickle.loads(payload)
    return pickle.dumps(fn(*args, **kwargs), protocol=_PROTOCOL)


def _translate(err: BaseException, address: str) -> BaseException:
    """Turn Dask's failures of the cluster (not of the task) into ClusterError."""
    name = type(err).__name__
    if isinstance(err, cf.CancelledError) or name in ('CancelledError', 'FutureCancelledError'):
        return _cluster_error(address, 'a task was cancelled by Dask (scheduler lost or '
                              f'restarted?): {_reason(err)}')
    if name == 'KilledWorker':
        return _cluster_error(address, 'Dask gave up on a task that was running on workers '
                              f'that died ({_reason(err)}); see the logs of the workers '
                              '(memory?)')
    if isinstance(err, (ModuleNotFoundError, ImportError)):
        return _cluster_error(address, f'a worker cannot import the work unit ({_reason(err)}); '
                              f'install gyro_noise_ros {__version__} on every worker')
    if isinstance(err, (OSError, TimeoutError)) and not hasattr(err, 'exit_code'):
        return _cluster_error(address, _reason(err))
    return err


def _cluster_error(address: str, text: str) -> ClusterError:
    """Return the ClusterError ``'<the scheduler parameter> <address>: <text>'``."""
    return ClusterError(f'{{scheduler}} {address}: {text}', parameters=('scheduler',))
