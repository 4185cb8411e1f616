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
Small ROS helpers shared by the node modules: QoS, timers, diagnostics, ``main()``, polled takes.

Only modules under ``gyro_noise_ros/nodes/`` may import this file: it imports rclpy and message
packages. Parameter tables are :mod:`._params` (re-exported here).

Conventions every node module follows (``test/test_node_params.py`` relies on them):

- ``NODE_NAME``: the default node name, also the stem of ``config/<NODE_NAME>.yaml``.
- ``PARAMETERS``: a tuple of :class:`ParamSpec`, the single table the node declares with
  :func:`declare_parameter_table`.
- ``main(args=None)`` calls :func:`run_node`, the Jazzy ``main()`` pattern with parameter errors
  turned into one line on stderr and exit code 2.

What diagnostic_updater would give (it is not installable from PyPI) is written here in its shape:
:func:`diagnostic_status` builds a ``DiagnosticStatus`` named ``'<node>: <task>'`` with string
values; the levels come from the pure diagnostics (``core.health``, ``link.health``,
``diagnostics/``).
"""

from collections.abc import Callable, Iterable, Sequence
import ctypes
import signal
import sys
import threading
from typing import Any, NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import rclpy
from rclpy.callback_groups import CallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from rclpy.utilities import remove_ros_args

from ._dds_profile import use_package_profile
from ._params import (declare_parameter_table, parameter_help, ParamSpec,
                      refuse_unknown_parameters, specs_from_dataclass)
from ..cli._startup import quiet_finalisers, take_pending
from ..errors import GyroNoiseError, ParameterError
from ..link.sequence import SequenceGapCounter

__all__ = ['declare_parameter_table', 'diagnostic_array', 'diagnostic_status',
           'diagnostics_publisher', 'driver_qos', 'ERROR', 'OK', 'ParamSpec', 'PolledGroup',
           'run_node', 'sensor_data_qos', 'SequenceGapCounter', 'specs_from_dataclass', 'STALE',
           'take_all', 'unused_callback', 'wall_timer', 'WARN']

#: ``DiagnosticStatus`` levels, as the ``bytes`` rclpy uses for the ``byte`` field.
OK = DiagnosticStatus.OK
WARN = DiagnosticStatus.WARN
ERROR = DiagnosticStatus.ERROR
STALE = DiagnosticStatus.STALE


def sensor_data_qos(depth: int, reliable: bool = False) -> QoSProfile:
    """
    Return the sensor-data QoS (best effort, volatile, keep last) with a chosen depth.

    What consumers subscribe with (REP-2003): a best-effort subscription matches both reliable
    and best-effort publishers. rclpy's ``qos_profile_sensor_data`` keeps only 5 messages; a
    6.66 kHz stream arriving in bursts needs a deeper history so a subscriber that wakes every few
    milliseconds loses nothing.

    With ``reliable`` the subscription asks for reliable delivery instead (the nodes' ``reliable``
    parameter): the middleware then retransmits what a busy host missed, so a transport drop is
    not counted as a lost sensor sample; it matches only reliable publishers (the driver is one).

    Parameters
    ----------
    depth : int
        History depth in messages.
    reliable : bool
        Reliable instead of best-effort delivery.

    Returns
    -------
    rclpy.qos.QoSProfile

    """
    reliability = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth), reliability=reliability,
                      durability=DurabilityPolicy.VOLATILE)


def driver_qos(depth: int) -> QoSProfile:
    """
    Return the QoS a driver publishes with (REP-2003): reliable, volatile, keep last ``depth``.

    A reliable publisher serves every subscriber, default-QoS (reliable) ones such as RViz as well
    as best-effort sensor-data ones; a best-effort one silently starves every reliable subscriber.
    ``depth`` (messages) must hold the bursts of a 6.66 kHz stream.

    """
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth),
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def wall_timer(node: Node, period_s: float, callback: Callable[[], Any]) -> Timer:
    """
    Create a timer of ``period_s`` s on the steady (wall) clock, whatever ``use_sim_time`` says.

    Draining subscriptions and periodic diagnostics must keep their cadence when ``/clock`` is
    late, paused or absent (``ros2 bag play --clock``): on the ROS clock such a timer stops, the
    queues overflow and samples never lost are reported lost. Stamps still come from the node
    clock.

    """
    return node.create_timer(period_s, callback, clock=Clock(clock_type=ClockType.STEADY_TIME))


# Free heap pages given back by the running nodes (seconds between two malloc_trim calls).
HEAP_TRIM_PERIOD_S = 10.0


def _malloc_trim() -> Callable[[], int] | None:
    """Return glibc's ``malloc_trim(0)`` as a call, or None where the C library has none."""
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError):  # not glibc (musl, macOS): nothing to do
        return None
    trim.argtypes = [ctypes.c_size_t]
    trim.restype = ctypes.c_int
    return lambda: int(trim(0))


def heap_trim_timer(node: Node, period_s: float = HEAP_TRIM_PERIOD_S) -> Timer | None:
    """
    Give the process's free heap pages back to the system every ``period_s`` (glibc only).

    A node allocates numpy arrays of 0.1-10 MB from several threads (the executor, the analysis
    worker, the middleware's). Once glibc's dynamic mmap threshold has risen past them they come
    from the heap, and the holes they leave stay resident: the analyzer's RSS rose ~15 MB in 5
    minutes at 6.66 kHz while its allocated bytes stayed level (docs/scale.md, memory).
    ``malloc_trim(0)`` returns whole free pages (1-9 ms a call, measured) without touching the
    hot path; a fixed ``M_MMAP_THRESHOLD`` would, at 2.5x the analysis' CPU time.

    Parameters
    ----------
    node : rclpy.node.Node
        The node owning the timer.
    period_s : float
        Seconds between two calls.

    Returns
    -------
    rclpy.timer.Timer or None
        None where the C library has no ``malloc_trim``.

    """
    trim = _malloc_trim()
    if trim is None:
        return None
    return wall_timer(node, period_s, trim)


def diagnostics_publisher(node: Node) -> Publisher:
    """
    Create the ``/diagnostics`` publisher as diagnostic_updater does (absolute topic, reliable).

    It publishes ``diagnostic_msgs/DiagnosticArray`` for ``node``, keeping the last 10.

    """
    return node.create_publisher(DiagnosticArray, '/diagnostics', 10)


def diagnostic_status(name: str, hardware_id: str, level: bytes, message: str,
                      values: Iterable[tuple[str, object]]) -> DiagnosticStatus:
    """
    Build one ``DiagnosticStatus`` in diagnostic_updater's shape.

    ``name`` is ``'<node name>: <task>'``, ``hardware_id`` a stable device identifier, ``level``
    :data:`OK`, :data:`WARN`, :data:`ERROR` or :data:`STALE`, ``message`` one sentence naming the
    worst item; ``values`` are (readable key with the unit in parentheses, value) pairs, a value
    not yet a string formatted by ``str`` (format floats first to control the digits).

    """
    return DiagnosticStatus(level=level, name=name, message=message, hardware_id=hardware_id,
                            values=[KeyValue(key=k, value=v if isinstance(v, str) else str(v))
                                    for k, v in values])


def diagnostic_array(stamp: Any, statuses: Iterable[DiagnosticStatus]) -> DiagnosticArray:
    """
    Wrap statuses into a stamped ``DiagnosticArray``.

    Parameters
    ----------
    stamp : builtin_interfaces.msg.Time
        Usually ``node.get_clock().now().to_msg()``.
    statuses : sequence of DiagnosticStatus
        The statuses, in order.

    Returns
    -------
    diagnostic_msgs.msg.DiagnosticArray

    """
    msg = DiagnosticArray(status=list(statuses))
    msg.header.stamp = stamp
    return msg


def _refuse_plain_arguments(argv: list[str], prog: str, help_text: str) -> int | None:
    """``--help``: print the table and return 0; another argument outside --ros-args: 2."""
    try:
        plain = remove_ros_args(argv)[1:]
    except RuntimeError:  # malformed --ros-args: rclpy.init says so, in one line (run_node)
        return None
    if '-h' in plain or '--help' in plain:
        print(help_text, end='')
        return 0
    if plain:
        print(f'{prog}: error: unknown argument {plain[0]!r}: parameters go after --ros-args '
              f'(-p name:=value, --params-file FILE; {prog} --help lists them)',
              file=sys.stderr)
        return ParameterError.exit_code
    return None


def _remember_signals(received: list[int]) -> dict[int, Any]:
    """
    Note SIGINT and SIGTERM in ``received`` (Python handlers put under rclpy's).

    rclpy's own handlers, installed by ``rclpy.init`` after these, shut the context down (the spin
    ends) and then call these, so the exit code can say which signal it was.
    """
    def note(signum: int, frame: Any) -> None:
        received.append(signum)

    old: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(sig) is not signal.SIG_IGN:
                old[sig] = signal.signal(sig, note)
    return old


def run_node(node_factory: Callable[[], Node | Sequence[Node]], args: list[str] | None = None,
             *, prog: str, parameters: Sequence[ParamSpec] | None = None,
             summary: str = '', help_text: str | None = None) -> int:
    """
    Run a node with the Jazzy ``main()`` pattern; start-up errors give one line and an exit code.

    ``rclpy.init(args=args)``; build the node; refuse parameters it did not declare; ``rclpy.spin``
    until SIGINT, SIGTERM or an external shutdown; always ``destroy_node()`` and
    ``rclpy.try_shutdown()``. A node stopped by a signal says ``<prog>: interrupted`` and exits
    with 128 + the signal (``errors.EXIT_CODES``).

    Parameters
    ----------
    node_factory : callable
        ``node_factory() -> rclpy.node.Node`` or a sequence of nodes (spun together in one
        thread, destroyed in that order); may raise :class:`GyroNoiseError` (bad parameters).
    args : list of str or None
        Command line for ``rclpy.init`` (None: ``sys.argv``).
    prog : str
        Program name used as the error-line prefix.
    parameters : sequence of ParamSpec, optional, keyword-only
        The node's table: then ``--help`` prints it (nothing starts) and any other argument
        outside ``--ros-args`` is refused. None: the caller parses its own arguments.
    summary : str, keyword-only
        What the node does, for ``--help`` (its module docstring).
    help_text : str or None, keyword-only
        The whole ``--help`` text, instead of the one made of ``parameters`` and ``summary``.

    Returns
    -------
    int
        Exit code: 0, 130/143 after SIGINT/SIGTERM, or the error class's code (2 for bad or
        unknown parameters and malformed ROS arguments, 3 an unreadable input file, 6 an
        unwritable output).

    """
    argv = sys.argv if args is None else list(args)
    if parameters is not None:
        code = _refuse_plain_arguments(argv, prog, help_text or parameter_help(
            prog, parameters, summary))
        if code is not None:
            return code
    received: list[int] = []
    old = _remember_signals(received)
    early = take_pending()  # a signal while the program imported its libraries
    if early is not None:
        received.append(early)
    try:
        if received:
            return _interrupted(prog, received[0])
        return _init_and_spin(node_factory, argv, prog, received)
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


def _init_and_spin(node_factory: Callable[[], Node | Sequence[Node]], argv: list[str],
                   prog: str, received: list[int]) -> int:
    use_package_profile()  # a node killed -9 is dropped by the others in 3 s, not 20
    try:
        rclpy.init(args=argv)
    except RuntimeError as err:
        # A malformed or unknown --ros-args (e.g. "-p name:=" with no value, "--bogus") fails here,
        # before any node exists. rclpy raises RCLInvalidROSArgsError or UnknownROSArgsError, which
        # it exposes only in its private _rclpy_pybind11 module; both derive from RuntimeError,
        # so the public base class is caught and the class name says which.
        kind = type(err).__name__
        what = 'unknown ROS arguments' if kind == 'UnknownROSArgsError' else 'bad ROS arguments'
        print(f'{prog}: error: {what}: {str(err).split(", at ")[0]}', file=sys.stderr)
        return ParameterError.exit_code
    nodes: tuple[Node, ...] = ()
    error: GyroNoiseError | None = None
    try:
        built = node_factory()
        nodes = (built,) if isinstance(built, Node) else tuple(built)
        for node in nodes:
            refuse_unknown_parameters(node, argv)
        heap_trim_timer(nodes[0])
        _spin(nodes)
    except GyroNoiseError as err:
        error = err
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:  # noqa: BLE001 - only the shutdown race below is swallowed
        # SIGINT/SIGTERM shut the context down from rclpy's signal handler; a spin caught
        # building its wait set at that moment raises RCLError ("the given context is not
        # valid"): that is the requested shutdown, not a failure.
        if rclpy.ok() and not received:
            raise
    finally:
        try:
            for node in nodes:  # in order: a driver stops its thread before its listener goes
                node.destroy_node()  # a recorder closes its bag: that may fail (disk full)
        except GyroNoiseError as err:
            error = error or err
        finally:
            rclpy.try_shutdown()
    if error is not None:
        print(f'{prog}: error: {error}', file=sys.stderr)
        return error.exit_code
    return _interrupted(prog, received[0]) if received else 0


def _spin(nodes: Sequence[Node]) -> None:
    """``rclpy.spin`` of one node, or of several in the global executor (one thread)."""
    if len(nodes) == 1:
        rclpy.spin(nodes[0])
        return
    executor = rclpy.get_global_executor()
    try:
        for node in nodes:
            executor.add_node(node)
        while executor.context.ok():
            executor.spin_once()
    finally:
        for node in nodes:
            executor.remove_node(node)


def _interrupted(prog: str, signum: int) -> int:
    quiet_finalisers()
    print(f'{prog}: interrupted' + ('' if signum == signal.SIGINT else
                                    f' ({signal.Signals(signum).name})'),
          file=sys.stderr, flush=True)
    return 128 + signum


# Polled raw subscriptions (shared by the analyzer and the recorder): ROS_ON_PIP.md measured that
# draining raw=True subscriptions from one timer is the cheap way to take 6.66 kHz in rclpy.

class PolledGroup(CallbackGroup):
    """
    A callback group whose entities the executor never waits on nor runs.

    The node takes the messages of such a subscription itself (``sub.handle.take_message``) from a
    timer, so a 6.66 kHz topic costs one executor wake-up per drain period instead of one per
    message.
    """

    def can_execute(self, entity: Any) -> bool:
        return False

    def beginning_execution(self, entity: Any) -> bool:
        return False

    def ending_execution(self, entity: Any) -> None:
        pass


def take_all(sub: Subscription, msg_type: type,
             limit: int | None = None) -> tuple[list[bytes], list[int], list[int]]:
    """
    Take every message queued on a raw subscription, or the oldest ``limit`` of them.

    Parameters
    ----------
    sub : rclpy.subscription.Subscription
        Created with ``raw=True``.
    msg_type : type
        Its message class.
    limit : int or None
        Most messages to take (None: all): a caller that processes a backlog in bounded batches
        keeps its temporaries small.

    Returns
    -------
    raws : list of bytes
        Serialised messages, oldest first.
    received_ns : list of int
        Receive time of each (``MessageInfo['received_timestamp']``, system clock, ns).
    sequence : list of int
        DDS publication sequence number of each (0 if the middleware does not give one).

    """
    raws: list[bytes] = []
    received: list[int] = []
    sequence: list[int] = []
    left = -1 if limit is None else int(limit)
    handle = sub.handle
    with handle:
        take = handle.take_message
        while left:
            item = take(msg_type, True)
            if item is None:
                break
            raw, info = item
            raws.append(raw)
            received.append(info.get('received_timestamp') or 0)
            sequence.append(info.get('publication_sequence_number') or 0)
            left -= 1
    return raws, received, sequence


# Never called: PolledGroup keeps the executor from calling it (hence no coverage).
def unused_callback(_msg: Any) -> NoReturn:  # pragma: no cover
    """Refuse to run: the callback rclpy requires of a polled subscription (see PolledGroup)."""
    raise AssertionError('polled subscriptions are drained by the node, not by the executor')
