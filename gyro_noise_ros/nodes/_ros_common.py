"""
Small ROS helpers shared by the node modules (driver, analyzer, recorder).

Only modules under ``gyro_noise_ros/nodes/`` may import this file: it imports rclpy and message
packages.

Conventions every node module follows (``test/test_node_params.py`` relies on them):

- ``NODE_NAME``: the default node name, also the stem of ``config/<NODE_NAME>.yaml``.
- ``PARAMETERS``: a tuple of :class:`ParamSpec`, the single table the node declares with
  :func:`declare_parameter_table`; the YAML file lists every entry with its default and, in the
  trailing comment, ``[unit]`` (``[-]`` when dimensionless).
- ``main(args=None)`` calls :func:`run_node`, the Jazzy ``main()`` pattern with parameter errors
  turned into one line on stderr and exit code 2.

What diagnostic_updater would give (it is not installable from PyPI) is written here in its shape:
:func:`diagnostic_status` builds a ``DiagnosticStatus`` named ``'<node>: <task>'`` with string
values, :func:`worst` picks the level and the one-sentence message from explicit checks.
"""

from dataclasses import dataclass, fields, MISSING
import math
import re
import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                ParameterType, SetParametersResult)
import rclpy
from rclpy.callback_groups import CallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..errors import GyroNoiseError, ParameterError

#: ``DiagnosticStatus`` levels, as the ``bytes`` rclpy uses for the ``byte`` field.
OK = DiagnosticStatus.OK
WARN = DiagnosticStatus.WARN
ERROR = DiagnosticStatus.ERROR
STALE = DiagnosticStatus.STALE

_LEVEL_RANK = {OK: 0, WARN: 1, ERROR: 2, STALE: 3}

_PYTHON_TO_ROS_TYPE = {
    bool: ParameterType.PARAMETER_BOOL,
    int: ParameterType.PARAMETER_INTEGER,
    float: ParameterType.PARAMETER_DOUBLE,
    str: ParameterType.PARAMETER_STRING,
}

_ROS_TYPE_NAME = {
    ParameterType.PARAMETER_BOOL: 'a boolean (true/false)',
    ParameterType.PARAMETER_INTEGER: 'an integer',
    ParameterType.PARAMETER_DOUBLE: 'a floating-point number (write 1.0, not 1)',
    ParameterType.PARAMETER_STRING: 'a string',
}


@dataclass(frozen=True)
class ParamSpec:
    """
    One row of a node's parameter table.

    Parameters
    ----------
    name : str
        snake_case name with a unit suffix where the unit is not SI-obvious (``odr_hz``).
    default : bool, int, float or str
        Default value; its Python type is the ROS parameter type (1.0 is a double, 1 an integer).
    description : str
        One sentence for ``ros2 param describe``.
    unit : str
        Unit of the value, written in the YAML comment as ``[unit]``; ``''`` when dimensionless.
    read_only : bool
        True where a change at runtime would not take effect (port, rates, full scales).
    min_value, max_value : int or float or None
        Inclusive range, put into the descriptor so rclpy enforces it at start and at runtime;
        give both or neither.
    choices : tuple
        Allowed values when the set is discrete (the descriptor cannot say so; checked by
        :func:`declare_parameter_table` and the set-parameters callback it installs).
    pattern : str
        Regular expression a string value must match in full (e.g. a frame id); ``''``: any.

    """

    name: str
    default: object
    description: str
    unit: str = ''
    read_only: bool = False
    min_value: object = None
    max_value: object = None
    choices: tuple = ()
    pattern: str = ''

    @property
    def ros_type(self):
        """Return the ``rcl_interfaces/ParameterType`` constant of :attr:`default`."""
        return _PYTHON_TO_ROS_TYPE[type(self.default)]

    def descriptor(self):
        """
        Build the ``ParameterDescriptor`` of this row.

        Returns
        -------
        rcl_interfaces.msg.ParameterDescriptor
            Description with the unit, read_only flag, range and a text form of the choices.

        """
        text = self.description + (f' [{self.unit}]' if self.unit else '')
        desc = ParameterDescriptor(name=self.name, type=self.ros_type, description=text,
                                   read_only=self.read_only)
        if self.choices:
            desc.additional_constraints = 'one of ' + ', '.join(str(c) for c in self.choices)
        elif self.pattern:
            desc.additional_constraints = f'matches {self.pattern}'
        if self.min_value is not None:
            if self.ros_type == ParameterType.PARAMETER_INTEGER:
                desc.integer_range = [IntegerRange(from_value=int(self.min_value),
                                                   to_value=int(self.max_value), step=0)]
            else:
                desc.floating_point_range = [FloatingPointRange(from_value=float(self.min_value),
                                                                to_value=float(self.max_value),
                                                                step=0.0)]
        return desc

    def check(self, value):
        """
        Validate a value against the range and the choices of this row.

        Parameters
        ----------
        value : object
            Candidate value (already of the right type: rclpy checks types).

        Raises
        ------
        ParameterError
            Naming the parameter, the bad value and what is allowed.

        """
        if self.pattern and not re.fullmatch(self.pattern, value):
            raise ParameterError(
                f"parameter '{self.name}' = {value!r} does not match {self.pattern}")
        if self.choices and value not in self.choices:
            raise ParameterError(f"parameter '{self.name}' = {value!r} is not one of "
                                 + ', '.join(repr(c) for c in self.choices))
        if self.min_value is not None and not self.min_value <= value <= self.max_value:
            raise ParameterError(f"parameter '{self.name}' = {value!r} is outside "
                                 f'[{self.min_value}, {self.max_value}]'
                                 + (f' {self.unit}' if self.unit else ''))
        if isinstance(value, float) and not math.isfinite(value):
            raise ParameterError(f"parameter '{self.name}' = {value!r} is not finite")


def declare_parameter_table(node, table, *, on_change=None):
    """
    Declare every row of a parameter table on a node and return the values.

    Type, range and choice violations of the overrides (``--ros-args -p``, ``--params-file``,
    ``parameter_overrides``) become one :class:`ParameterError` naming the parameter and value, so
    :func:`run_node` can print one line and exit with code 2 instead of a traceback.

    Parameters
    ----------
    node : rclpy.node.Node
        The node to declare on.
    table : sequence of ParamSpec
        The node's ``PARAMETERS``.
    on_change : callable or None
        ``on_change(dict name -> new value)``, called after rclpy accepted a runtime change of
        parameters that are not read_only (ranges and choices already checked). None: no hook.

    Returns
    -------
    dict
        Parameter name to value.

    Raises
    ------
    ParameterError
        An override has the wrong type, is out of range, or is not one of the choices.

    """
    by_name = {spec.name: spec for spec in table}
    values = {}
    for spec in table:
        try:
            value = node.declare_parameter(spec.name, spec.default, spec.descriptor()).value
        except ParameterException as err:
            raise ParameterError(_explain_parameter_exception(spec, err)) from err
        spec.check(value)
        values[spec.name] = value

    def _validate(params):
        for param in params:
            spec = by_name.get(param.name)
            if spec is None:
                continue
            try:
                spec.check(param.value)
            except ParameterError as err:
                return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(_validate)
    if on_change is not None:
        node.add_post_set_parameters_callback(
            lambda params: on_change({p.name: p.value for p in params if p.name in by_name}))
    return values


def _explain_parameter_exception(spec, err):
    text = str(err)
    if 'expecting type' in text:
        return (f"parameter '{spec.name}' must be {_ROS_TYPE_NAME[spec.ros_type]}: "
                f'{text.split(": ")[0]}')
    if spec.min_value is not None:
        return (f"parameter '{spec.name}' is outside [{spec.min_value}, {spec.max_value}]"
                + (f' {spec.unit}' if spec.unit else '') + f': {text}')
    return f"parameter '{spec.name}': {text}"


def sensor_data_qos(depth):
    """
    Return the sensor-data QoS (best effort, volatile, keep last) with a chosen depth.

    What consumers subscribe with (REP-2003): a best-effort subscription matches both reliable
    and best-effort publishers. rclpy's ``qos_profile_sensor_data`` keeps only 5 messages; a
    6.66 kHz stream arriving in bursts needs a deeper history so a subscriber that wakes every few
    milliseconds loses nothing.

    Parameters
    ----------
    depth : int
        History depth in messages.

    Returns
    -------
    rclpy.qos.QoSProfile

    """
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth),
                      reliability=ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.VOLATILE)


def driver_qos(depth):
    """
    Return the QoS a driver publishes with (REP-2003): reliable, volatile, keep last ``depth``.

    A reliable publisher serves every subscriber, the default-QoS (reliable) ones such as RViz or a
    user's node as well as best-effort sensor-data ones; a best-effort publisher silently starves
    every reliable subscriber.

    Parameters
    ----------
    depth : int
        History depth in messages (deep enough for the bursts of a 6.66 kHz stream).

    Returns
    -------
    rclpy.qos.QoSProfile

    """
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth),
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def specs_from_dataclass(cls, *, read_only, float_range=(0.0, 1.0e9), int_range=(0, 1_000_000)):
    """
    Return one :class:`ParamSpec` per field of a frozen dataclass of limits, from its metadata.

    The dataclass is the single source of each parameter's name, default, description and unit
    (``field(metadata={'description': ..., 'unit': ..., 'min': ..., 'max': ...})``), so the node's
    table, its YAML file and the docs cannot drift apart.

    Parameters
    ----------
    cls : type
        A dataclass whose fields have defaults and a ``description`` in their metadata.
    read_only : bool
        Whether the parameters are read-only.
    float_range, int_range : (number, number)
        Range of a field whose metadata gives none.

    Returns
    -------
    tuple of ParamSpec

    """
    rows = []
    for f in fields(cls):
        if f.default is MISSING:
            raise TypeError(f'{cls.__name__}.{f.name} has no default')
        meta = f.metadata
        lo, hi = float_range if isinstance(f.default, float) else int_range
        default = f.default if isinstance(f.default, float) else int(f.default)
        rows.append(ParamSpec(f.name, default, meta.get('description', f.name),
                              unit=meta.get('unit', ''), read_only=read_only,
                              min_value=type(default)(meta.get('min', lo)),
                              max_value=type(default)(meta.get('max', hi))))
    return tuple(rows)


def wall_timer(node, period_s, callback):
    """
    Create a timer on the steady (wall) clock, whatever ``use_sim_time`` says.

    Draining subscriptions and periodic diagnostics must keep their cadence when ``/clock`` is
    late, paused or absent (``ros2 bag play --clock`` under ``use_sim_time:=true``): on the ROS
    clock such a timer stops, the subscription queues overflow and the analyzer reports samples
    lost that were never lost. Stamps still come from the node clock.

    Parameters
    ----------
    node : rclpy.node.Node
        The node owning the timer.
    period_s : float
        Period (s of wall time).
    callback : callable
        Called without arguments.

    Returns
    -------
    rclpy.timer.Timer

    """
    return node.create_timer(period_s, callback, clock=Clock(clock_type=ClockType.STEADY_TIME))


def diagnostics_publisher(node):
    """
    Create the ``/diagnostics`` publisher as diagnostic_updater does (absolute topic, reliable).

    Parameters
    ----------
    node : rclpy.node.Node
        The publishing node.

    Returns
    -------
    rclpy.publisher.Publisher
        Publisher of ``diagnostic_msgs/DiagnosticArray``.

    """
    return node.create_publisher(DiagnosticArray, '/diagnostics', 10)


def worst(checks, ok_message):
    """
    Pick the level and message of the worst failed check (the first one among equals).

    Parameters
    ----------
    checks : iterable of (level, str)
        Level and one-sentence message of each check that did not pass.
    ok_message : str
        Message when the iterable is empty.

    Returns
    -------
    (bytes, str)
        Level and message for :func:`diagnostic_status`.

    """
    level, message = OK, ok_message
    for check_level, check_message in checks:
        if _LEVEL_RANK[check_level] > _LEVEL_RANK[level]:
            level, message = check_level, check_message
    return level, message


def diagnostic_status(name, hardware_id, level, message, values):
    """
    Build one ``DiagnosticStatus`` in diagnostic_updater's shape.

    Parameters
    ----------
    name : str
        ``'<node name>: <task>'``.
    hardware_id : str
        Stable identifier of the device (e.g. ``'lsm6dso32@/dev/ttyACM0'``).
    level : bytes
        :data:`OK`, :data:`WARN`, :data:`ERROR` or :data:`STALE`.
    message : str
        One sentence naming the worst item.
    values : sequence of (str, object)
        Readable keys with the unit in parentheses and their values; values are formatted with
        ``str`` unless already strings (format floats before passing them to control digits).

    Returns
    -------
    diagnostic_msgs.msg.DiagnosticStatus

    """
    return DiagnosticStatus(level=level, name=name, message=message, hardware_id=hardware_id,
                            values=[KeyValue(key=k, value=v if isinstance(v, str) else str(v))
                                    for k, v in values])


def diagnostic_array(stamp, statuses):
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


def run_node(node_factory, args=None, *, prog):
    """
    Run a node with the Jazzy ``main()`` pattern; start-up errors give one line and an exit code.

    ``rclpy.init(args=args)``; build the node; ``rclpy.spin`` until Ctrl-C or an external shutdown;
    always ``destroy_node()`` and ``rclpy.try_shutdown()``.

    Parameters
    ----------
    node_factory : callable
        ``node_factory() -> rclpy.node.Node``; may raise :class:`GyroNoiseError` (bad parameters).
    args : list of str or None
        Command line for ``rclpy.init`` (None: ``sys.argv``).
    prog : str
        Program name used as the error-line prefix.

    Returns
    -------
    int
        Exit code: 0, or the error class's code (2 for bad parameters or malformed ROS arguments).

    """
    try:
        rclpy.init(args=args)
    except RuntimeError as err:
        # A malformed or unknown --ros-args (e.g. "-p name:=" with no value, "--bogus") fails here,
        # before any node exists. rclpy raises RCLInvalidROSArgsError or UnknownROSArgsError, which
        # it exposes only in its private _rclpy_pybind11 module; both derive from RuntimeError,
        # so the public base class is caught and the class name says which.
        kind = type(err).__name__
        what = 'unknown ROS arguments' if kind == 'UnknownROSArgsError' else 'bad ROS arguments'
        print(f'{prog}: error: {what}: {str(err).split(", at ")[0]}', file=sys.stderr)
        return ParameterError.exit_code
    node = None
    try:
        node = node_factory()
        rclpy.spin(node)
    except GyroNoiseError as err:
        print(f'{prog}: error: {err}', file=sys.stderr)
        return err.exit_code
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


# Polled raw subscriptions (shared by the analyzer and the recorder): ROS_ON_PIP.md measured that
# draining raw=True subscriptions from one timer is the cheap way to take 6.66 kHz in rclpy.

class PolledGroup(CallbackGroup):
    """
    A callback group whose entities the executor never waits on nor runs.

    The node takes the messages of such a subscription itself (``sub.handle.take_message``) from a
    timer, so a 6.66 kHz topic costs one executor wake-up per drain period instead of one per
    message.
    """

    def can_execute(self, entity):
        return False

    def beginning_execution(self, entity):
        return False

    def ending_execution(self, entity):
        pass


def take_all(sub, msg_type):
    """
    Take every message queued on a raw subscription.

    Parameters
    ----------
    sub : rclpy.subscription.Subscription
        Created with ``raw=True``.
    msg_type : type
        Its message class.

    Returns
    -------
    raws : list of bytes
        Serialised messages, oldest first.
    received_ns : list of int
        Receive time of each (``MessageInfo['received_timestamp']``, system clock, ns).
    sequence : list of int
        DDS publication sequence number of each (0 if the middleware does not give one).

    """
    raws, received, sequence = [], [], []
    handle = sub.handle
    with handle:
        take = handle.take_message
        while True:
            item = take(msg_type, True)
            if item is None:
                break
            raw, info = item
            raws.append(raw)
            received.append(info.get('received_timestamp') or 0)
            sequence.append(info.get('publication_sequence_number') or 0)
    return raws, received, sequence


def unused_callback(_msg):  # pragma: no cover - PolledGroup keeps the executor from calling it
    """Refuse to run: the callback rclpy requires of a polled subscription (see PolledGroup)."""
    raise AssertionError('polled subscriptions are drained by the node, not by the executor')
