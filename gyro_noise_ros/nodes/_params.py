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
Parameter tables of the nodes: one declaration per parameter, checked at start and at runtime.

Only node modules import this file (it imports rclpy). Every node module defines ``NODE_NAME``
and ``PARAMETERS`` (a tuple of :class:`ParamSpec`) and declares it with
:func:`declare_parameter_table`; ``config/<NODE_NAME>.yaml`` lists every entry with its default
and, in the trailing comment, ``[unit]`` (``test/test_node_params.py`` checks it). Limits that live
in a pure dataclass give their rows through :func:`specs_from_dataclass`, so the description and
unit are written once.
"""

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, fields, MISSING
import difflib
import math
import re
import sys
from typing import Any

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                ParameterType, SetParametersResult)
from rclpy.exceptions import ParameterException
from rclpy.node import Node
import yaml

from ..errors import ParameterError

_PYTHON_TO_ROS_TYPE = {
    bool: ParameterType.PARAMETER_BOOL,
    int: ParameterType.PARAMETER_INTEGER,
    float: ParameterType.PARAMETER_DOUBLE,
    str: ParameterType.PARAMETER_STRING,
}
#: Array parameters by element type (a list default's first element).
_PYTHON_TO_ROS_ARRAY_TYPE = {
    bool: ParameterType.PARAMETER_BOOL_ARRAY,
    int: ParameterType.PARAMETER_INTEGER_ARRAY,
    float: ParameterType.PARAMETER_DOUBLE_ARRAY,
    str: ParameterType.PARAMETER_STRING_ARRAY,
}

_ROS_TYPE_NAME = {
    ParameterType.PARAMETER_BOOL: 'a boolean (true/false)',
    ParameterType.PARAMETER_INTEGER: 'an integer',
    ParameterType.PARAMETER_DOUBLE: 'a floating-point number (write 1.0, not 1)',
    ParameterType.PARAMETER_STRING: 'a string',
    ParameterType.PARAMETER_BYTE_ARRAY: 'an array of bytes',
    ParameterType.PARAMETER_BOOL_ARRAY: 'an array of booleans ([true, false])',
    ParameterType.PARAMETER_INTEGER_ARRAY: 'an array of integers ([1, 2])',
    ParameterType.PARAMETER_DOUBLE_ARRAY: 'an array of floating-point numbers ([0.0, 1.0], not '
                                          '[0, 1])',
    ParameterType.PARAMETER_STRING_ARRAY: "an array of strings (['a', 'b'])",
}


def _type_name(ros_type: int) -> str:
    return _ROS_TYPE_NAME.get(ros_type, f'of ROS parameter type {ros_type}')


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
    default: Any
    description: str
    unit: str = ''
    read_only: bool = False
    min_value: float | None = None
    max_value: float | None = None
    choices: tuple = ()
    pattern: str = ''

    @property
    def ros_type(self) -> int:
        """Return the ``rcl_interfaces/ParameterType`` constant of :attr:`default`."""
        if isinstance(self.default, (list, tuple)):
            element = type(self.default[0]) if self.default else float
            return _PYTHON_TO_ROS_ARRAY_TYPE[element]
        return _PYTHON_TO_ROS_TYPE[type(self.default)]

    def descriptor(self) -> ParameterDescriptor:
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
            assert self.max_value is not None  # both or neither (see the class docstring)
            if self.ros_type == ParameterType.PARAMETER_INTEGER:
                desc.integer_range = [IntegerRange(from_value=int(self.min_value),
                                                   to_value=int(self.max_value), step=0)]
            else:
                desc.floating_point_range = [FloatingPointRange(from_value=float(self.min_value),
                                                                to_value=float(self.max_value),
                                                                step=0.0)]
        return desc

    def check(self, value: Any) -> None:
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
        if isinstance(self.default, (list, tuple)):
            values = list(value)
            if len(values) != len(self.default) or not all(
                    math.isfinite(v) for v in values if isinstance(v, float)):
                raise ParameterError(f"parameter '{self.name}' = {values!r} must be "
                                     f'{len(self.default)} finite values')
            return
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


def declare_parameter_table(node: Node, table: Sequence[ParamSpec], *,
                            on_change: Callable[[dict[str, Any]], None] | None = None
                            ) -> dict[str, Any]:
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
        An override has the wrong type, is out of range, is not one of the choices, or names a
        parameter the table lacks.

    """
    by_name = {spec.name: spec for spec in table}
    values: dict[str, Any] = {}
    for spec in table:
        try:
            value = node.declare_parameter(spec.name, spec.default, spec.descriptor()).value
        except ParameterException as err:
            raise ParameterError(_explain_parameter_exception(spec, err)) from err
        spec.check(value)
        values[spec.name] = value
    # the node's one table is declared: a name given that it lacks is refused now, before the
    # node's start-up work (run_node checks again once the node is built)
    refuse_unknown_parameters(node)

    def _validate(params: Sequence[Any]) -> SetParametersResult:
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


def _explain_parameter_exception(spec: ParamSpec, err: Exception) -> str:
    text = str(err)
    if 'expecting type' in text:
        return (f"parameter '{spec.name}' must be {_type_name(spec.ros_type)}: "
                f'{text.split(": ")[0]}')
    if spec.min_value is not None:
        return (f"parameter '{spec.name}' is outside [{spec.min_value}, {spec.max_value}]"
                + (f' {spec.unit}' if spec.unit else '') + f': {text}')
    return f"parameter '{spec.name}': {text}"


def _default_text(spec: ParamSpec) -> str:
    if isinstance(spec.default, bool):
        return 'true' if spec.default else 'false'
    if isinstance(spec.default, str):
        return repr(spec.default)
    if isinstance(spec.default, (list, tuple)):
        return '[' + ', '.join(_default_text(ParamSpec('', v, '')) for v in spec.default) + ']'
    return f'{spec.default!r}'


def parameter_help(prog: str, table: Sequence[ParamSpec], summary: str = '') -> str:
    """
    Return the ``--help`` text of a node: usage, then every parameter of its one table.

    Parameters
    ----------
    prog : str
        The executable.
    table : sequence of ParamSpec
        The node's ``PARAMETERS``.
    summary : str
        One paragraph on what the node does (its module docstring's first).

    Returns
    -------
    str
        Each parameter with its default, unit, range or choices, read-only mark and description.

    """
    lines = [f'usage: {prog} [--help] [--ros-args [-p NAME:=VALUE ...] [--params-file FILE] '
             '[-r __ns:=/NAMESPACE] ...]', '']
    if summary:
        lines += [' '.join(summary.strip().split('\n\n')[0].split()), '']
    lines.append('parameters (default [unit]; config/' f'{prog}.yaml lists them too):')
    for spec in table:
        unit = f' [{spec.unit}]' if spec.unit else ''
        limits = []
        if spec.min_value is not None:
            limits.append(f'{spec.min_value:g}..{spec.max_value:g}')
        if spec.choices:
            limits.append('one of ' + ', '.join(str(c) for c in spec.choices))
        if spec.read_only:
            limits.append('read-only')
        extra = f" ({'; '.join(limits)})" if limits else ''
        lines.append(f'  {spec.name} = {_default_text(spec)}{unit}{extra}')
        lines.append(f'      {spec.description}')
    lines += ['', "rclpy's own: use_sim_time = false (take time from /clock). Another name is "
              'refused (exit code 2).', '']
    return '\n'.join(lines)


def unknown_parameters(node: Node) -> list[str]:
    """
    Return the parameters given to ``node`` (``-p``, ``--params-file``) that it never declared.

    rclpy silently ignores an override whose name the node does not declare, so a misspelt
    parameter would change nothing without a word; rclpy's own parameters (``use_sim_time``,
    ``start_type_description_service``) are declared by rclpy and pass.

    Parameters
    ----------
    node : rclpy.node.Node
        A node whose parameters are all declared.

    Returns
    -------
    list of str
        The undeclared names, sorted.

    """
    # rclpy keeps the overrides addressed to this node (command line and parameter files) there
    given = getattr(node, '_parameter_overrides', None) or {}
    return sorted(name for name in given if not node.has_parameter(name))


def params_file_sections(argv: Sequence[str]) -> list[tuple[str, str, list[str]]]:
    """
    Return the parameter-file sections of a command line: ``(file, node key, names)`` each.

    Every ``--params-file FILE`` of ``argv`` is read; a section is a key path ending in
    ``ros__parameters`` (``/**``, ``noise_analyzer``, ``/robot1/noise_analyzer``), its names
    flattened with dots as rclpy does. A file that cannot be read is left to rclpy (it refuses it).

    Parameters
    ----------
    argv : sequence of str
        The program's arguments.

    Returns
    -------
    list of tuple

    """
    files = [argv[i + 1] for i, arg in enumerate(argv[:-1]) if arg == '--params-file']
    sections: list[tuple[str, str, list[str]]] = []
    for path in files:
        try:
            with open(path, encoding='utf-8') as f:
                doc = yaml.safe_load(f)
        except (OSError, UnicodeDecodeError, yaml.YAMLError):
            continue

        def walk(value: Any, keys: list[str], path: str = path) -> None:
            if not isinstance(value, dict):
                return
            for key, sub in value.items():
                if key == 'ros__parameters':
                    sections.append((path, '/'.join(k.strip('/') for k in keys),
                                     _flat_names(sub)))
                else:
                    walk(sub, [*keys, str(key)])
        walk(doc, [])
    return sections


def _flat_names(value: Any, prefix: str = '') -> list[str]:
    """Names of a ``ros__parameters`` mapping, nested keys joined by dots."""
    if not isinstance(value, dict):
        return [prefix] if prefix else []
    return [name for key, sub in value.items()
            for name in _flat_names(sub, f'{prefix}.{key}' if prefix else str(key))]


def wildcard_only(names: Sequence[str], node: Node,
                  argv: Sequence[str]) -> dict[str, str]:
    """
    Return the names that reach ``node`` only from a wildcard section of a parameter file.

    A section keyed with ``*`` (``/**``, ``/robot1/*``) is meant for several nodes: a name in it
    that this node lacks is another node's, not a typo. A name given with ``-p`` or in a section
    ending in the node's own name (``lsm6dso32_driver``, ``/robot1/lsm6dso32_driver``,
    ``/*/lsm6dso32_driver``) counts as addressed to this node.

    Parameters
    ----------
    names : sequence of str
        Undeclared names (:func:`unknown_parameters`).
    node : rclpy.node.Node
        The node.
    argv : sequence of str
        The program's arguments (``--ros-args -p ... --params-file ...``).

    Returns
    -------
    dict
        Name -> the file of the wildcard section that holds it.

    """
    own_keys = {node.get_name(), node.get_fully_qualified_name().strip('/')}
    own: set[str] = {argv[i + 1].split(':=', 1)[0] for i, arg in enumerate(argv[:-1])
                     if arg in ('-p', '--param')}
    wild: dict[str, str] = {}
    for path, key, section in params_file_sections(argv):
        if key in own_keys or key.split('/')[-1] == node.get_name():
            own.update(section)
        elif '*' in key:
            for name in section:
                wild.setdefault(name, path)
    return {name: wild[name] for name in names if name in wild and name not in own}


#: (node, parameter) pairs already warned about (a node checks at declaration and before spin).
_WARNED: set[tuple[str, str]] = set()


#: Set by :func:`running_together`: the parameter names of the nodes of this process, and its
#: command line.
_TOGETHER: list[tuple[frozenset[str], tuple[str, ...]]] = []


@contextmanager
def running_together(tables: Sequence[Sequence[ParamSpec]],
                     argv: Sequence[str]) -> Iterator[None]:
    """
    Build several nodes of one process in this block: a ``-p`` name one of them declares passes.

    A ``-p NAME:=VALUE`` (or a name in a wildcard section of a parameter file) reaches every node
    of the process; a node that lacks the name passes it over in silence when another node's
    table, given here, declares it (:func:`refuse_unknown_parameters`). A name in a parameter
    file's section of the node itself is still refused.

    Parameters
    ----------
    tables : sequence of sequence of ParamSpec
        The ``PARAMETERS`` of each node of the process.
    argv : sequence of str
        The program's command line (its ``-p`` names and ``--params-file`` files).

    """
    _TOGETHER.append((frozenset(spec.name for table in tables for spec in table), tuple(argv)))
    try:
        yield
    finally:
        _TOGETHER.pop()


def _a_siblings(names: Sequence[str], node: Node) -> set[str]:
    """
    Return the ``names`` another node built together with ``node`` declares, given to all nodes.

    Given with ``-p`` or in a wildcard section (``/**``); not those of the node's own section of
    a parameter file (a name there that the node lacks is a mistake, whoever else declares it).
    """
    if not _TOGETHER:
        return set()
    declared, argv = _TOGETHER[-1]
    own = {name for _, key, section in params_file_sections(argv)
           if key.split('/')[-1] == node.get_name() for name in section}
    return {name for name in names if name in declared and name not in own}


def refuse_unknown_parameters(node: Node, argv: Sequence[str] | None = None) -> None:
    """
    Refuse the undeclared parameters addressed to ``node``; warn about a shared file's others.

    Parameters
    ----------
    node : rclpy.node.Node
        A node whose parameters are all declared.
    argv : sequence of str, optional
        The program's arguments (default ``sys.argv``), to tell a wildcard section's names
        (:func:`wildcard_only`: a warning naming the file) from names given to this node.

    Raises
    ------
    ParameterError
        A name given with ``-p`` or in the node's own section that it does not declare.

    """
    unknown = unknown_parameters(node)
    if unknown:
        sibling = _a_siblings(unknown, node)
        unknown = [name for name in unknown if name not in sibling]
    if not unknown:
        return
    shared = wildcard_only(unknown, node, sys.argv if argv is None else argv)
    for name, path in shared.items():
        if (node.get_name(), name) in _WARNED:     # checked when declared and again at spin
            continue
        _WARNED.add((node.get_name(), name))
        node.get_logger().warning(
            f'parameter {name!r} of the shared (wildcard) section of {path} is not one of '
            f"{node.get_name()}'s: ignored (--help lists them)")
    refused = [name for name in unknown if name not in shared]
    if refused:
        raise unknown_parameter_error(node, refused)


def unknown_parameter_error(node: Node, names: Sequence[str]) -> ParameterError:
    """
    Return the one-line refusal of unknown parameters, with the closest known name of each.

    Parameters
    ----------
    node : rclpy.node.Node
        The node (its declared parameters).
    names : sequence of str
        :func:`unknown_parameters`.

    Returns
    -------
    ParameterError

    """
    known = sorted(node.list_parameters([], 0).names)  # depth 0: every declared name
    parts = []
    for name in names:
        close = difflib.get_close_matches(name, known, n=1)
        parts.append(repr(name) + (f' (did you mean {close[0]!r}?)' if close else ''))
    what = 'parameter' if len(names) == 1 else 'parameters'
    others = (', nor does any other node of this process'
              if _TOGETHER and not set(names) & _TOGETHER[-1][0] else '')
    return ParameterError(f'unknown {what} {", ".join(parts)}: {node.get_name()} declares no '
                          f'such parameter{others} (--help lists them)')


def specs_from_dataclass(cls: type[Any], *, read_only: bool,
                         float_range: tuple[float, float] = (0.0, 1.0e9),
                         int_range: tuple[int, int] = (0, 1_000_000)) -> tuple[ParamSpec, ...]:
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
    rows: list[ParamSpec] = []
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
