"""ROS parameters from ParamSpecs: declared with their types, ranges and descriptions,
checked, changed atomically.

At start-up every value given to the node (`-p`, parameter files) is checked before it is
declared: a parameter file that holds nothing for the node (nor for another node of its
process), a name the node does not declare, a value of the wrong type and a value its check
refuses each end the node with one line naming the parameter. Each parameter is declared
statically typed, with the range and constraint text its check gives (`ros2 param
describe`). A change at run time is coerced (an integer for a double), checked by ROS
against the declared type and range, validated by the spec and then applied by the node's
`apply` callback, which builds the node's cores from the full set of would-be values; if
any of them refuses, or the cores cannot be built (a ValueError or an ArithmeticError such
as an OverflowError: mill_common.build_check), the change is rejected with its reason in one
line and the node keeps its previous configuration and cores; so is a name the node does
not declare, with the closest one it has.
"""

from __future__ import annotations

import array
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
from rclpy.exceptions import ParameterNotDeclaredException
from rclpy.node import Node
from rclpy.parameter import Parameter

from mill_common.build_check import BUILD_ERRORS, build_failure
from mill_common.param_sources import parameter_sources, params_file_miss, params_files
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    UnknownParameterError,
    coerce,
    is_ros_parameter,
    shown,
    unknown_parameters_message,
    validate,
    value_type,
)

ROS_TYPES = {
    'bool': ParameterType.PARAMETER_BOOL,
    'integer': ParameterType.PARAMETER_INTEGER,
    'double': ParameterType.PARAMETER_DOUBLE,
    'string': ParameterType.PARAMETER_STRING,
    'bool_array': ParameterType.PARAMETER_BOOL_ARRAY,
    'integer_array': ParameterType.PARAMETER_INTEGER_ARRAY,
    'double_array': ParameterType.PARAMETER_DOUBLE_ARRAY,
    'string_array': ParameterType.PARAMETER_STRING_ARRAY,
}
INT64_MAX = 2**63 - 1

# The command line the node's process was started with (run_node sets it; else sys.argv):
# rcl does not tell which overrides came from `-p` and which from a shared file entry.
command_line: list[str] | None = None
# The names of the nodes that share the node's process (run_nodes sets them: a container's
# nodes): a parameter file given to a container must hold something for one of them.
process_nodes: tuple[str, ...] = ()


class CoresNotBuilt(ValueError):
    """At start-up: the node's cores cannot be built from the values it was given; str() is
    one line naming those values and the failure (mill_common.build_check)."""


class UndeclaredParameter(ParameterNotDeclaredException):
    """A change of a name the node does not declare; str() names it, with the closest name.

    rclpy's own exception lists no name (`undeclared parameter(s): []`: its check hands
    list() a generator that any() has already consumed); raised first, from the pre-set
    callback, this one is what `ros2 param set` shows as the reason.
    """

    def __init__(self, message: str) -> None:
        Exception.__init__(self, message)


def _plain(value: Any) -> Any:
    if isinstance(value, array.array):
        return list(value)
    return value


def descriptor(spec: ParamSpec) -> ParameterDescriptor:
    """The ROS descriptor of a spec: its type, description, read-only flag, and, where its
    check is a `Constraint`, the constraint text and the closed range of accepted numbers."""
    kind = value_type(spec)
    check = spec.check
    d = ParameterDescriptor(
        description=spec.description,
        read_only=spec.read_only,
        type=ROS_TYPES[kind],
        additional_constraints=getattr(check, 'text', '') or '',
        dynamic_typing=False,
    )
    bounds = getattr(check, 'bounds', None)
    if bounds is not None and kind == 'double':
        d.floating_point_range = [
            FloatingPointRange(from_value=float(bounds[0]), to_value=float(bounds[1]), step=0.0)
        ]
    elif bounds is not None and kind == 'integer':
        lo, hi = bounds
        low = math.floor(lo) + 1 if getattr(check, 'low_open', False) else math.ceil(lo)
        high = INT64_MAX if hi == math.inf else math.floor(hi)
        d.integer_range = [IntegerRange(from_value=low, to_value=high, step=1)]
    return d


def declare_with_value(node: Node, name: str, value: Any, spec: ParamSpec) -> None:
    """Declare `name` statically typed, holding `value`, also when it is an empty list.

    rclpy takes a declared parameter's type from its value, and reads [] as a byte array;
    declared by type alone, the parameter would be "not set", and rclpy's GetParameters
    answers no value at all for a request that names one unset parameter (`ros2 param dump`
    then shows `ros__parameters: {}`). So an empty list is declared by its type, writable,
    then given [] as a value of that type (before the node's set-callbacks are registered),
    and a read-only one gets its read-only descriptor last.
    """
    full = descriptor(spec)
    if value != []:
        node.declare_parameter(name, value, full, ignore_override=True)
        return
    kind = Parameter.Type(ROS_TYPES[value_type(spec)])
    writable = descriptor(spec)
    writable.read_only = False
    node.declare_parameter(name, kind, writable, ignore_override=True)
    (result,) = node.set_parameters([Parameter(name, kind, [])])
    if not result.successful:
        raise ParameterError(name, [], result.reason)
    if full.read_only:
        node.set_descriptor(name, full)


class NodeParameters:
    """Owns a node's validated parameter values; `apply(values)` rebuilds the node's cores."""

    def __init__(
        self,
        node: Node,
        specs: Sequence[tuple[str, ParamSpec]],
        apply: Callable[[dict[str, Any]], None],
    ) -> None:
        self._node = node
        self._specs = dict(specs)
        self._apply = apply
        self._check_files()
        given = self._given_values()
        values: dict[str, Any] = {}
        for name, spec in specs:
            value = validate(spec, given.get(name, spec.default), name)
            # The value is checked already: the override is not read a second time.
            declare_with_value(node, name, value, spec)
            values[name] = value
        try:
            apply(values)
        except ParameterError:
            raise
        except BUILD_ERRORS as exc:  # the values given, as a run-time change names them
            asked = ', '.join(f'{name}={shown(values[name])}' for name in given if name in values)
            raise CoresNotBuilt(f'{asked or "the defaults"}: {build_failure(exc)}') from exc
        self.values = values
        node.add_pre_set_parameters_callback(self._coerce)
        node.add_on_set_parameters_callback(self._on_set)

    def _check_files(self) -> None:
        """ValueError naming a parameter file that gives this process's nodes nothing."""
        node = self._node
        namespace = node.get_namespace().rstrip('/')
        fqns = [node.get_fully_qualified_name()]
        fqns += [f'{namespace}/{n}' for n in process_nodes if n != node.get_name()]
        for path in params_files(command_line if command_line is not None else sys.argv):
            problem = params_file_miss(path, fqns)
            if problem:
                raise ValueError(f'--params-file {path}: {problem}')

    def _given_values(self) -> dict[str, Any]:
        """The values given to the node (-p, parameter files), refusing unknown names.

        A name given directly (-p, the node's own file entry) must be declared by a spec or
        by ROS; a name from a file's shared entry (`/**`) the node does not declare is
        ignored: it is there for other nodes.
        """
        node = self._node
        # rclpy keeps the overrides rcl gathered for this node here (name -> Parameter).
        overrides = {n: _plain(p.value) for n, p in node._parameter_overrides.items()}
        declared = set(self._specs) | set(node.list_parameters([], 0).names)
        unknown = {n: v for n, v in overrides.items() if n not in declared}
        unknown = {n: v for n, v in unknown.items() if not is_ros_parameter(n)}
        if unknown:
            argv = command_line if command_line is not None else sys.argv
            sources = parameter_sources(argv, node.get_name(), node.get_fully_qualified_name())
            shared_only = sources.shared - sources.direct
            unknown = {n: v for n, v in unknown.items() if n not in shared_only}
        if unknown:
            raise UnknownParameterError(unknown, declared, node.get_fully_qualified_name())
        given = {n: v for n, v in overrides.items() if n in self._specs}
        for name, value in given.items():
            if value is None and value_type(self._specs[name]).endswith('_array'):
                given[name] = []  # rcl reads `[]` in a parameter file as no value
        return given

    def _typed(self, param: Parameter) -> Parameter:
        """An integer given for a float parameter, as that float (`param set ... 20`); an
        empty list as one of the parameter's type."""
        spec = self._specs.get(param.name)
        if spec is None:
            return param
        value = _plain(param.value)
        if value == [] and param.type_ != Parameter.Type(ROS_TYPES[value_type(spec)]):
            return Parameter(param.name, Parameter.Type(ROS_TYPES[value_type(spec)]), [])
        coerced = coerce(spec, value)
        if repr(coerced) == repr(value):  # also tells 12 from 12.0 inside lists
            return param
        return Parameter(param.name, value=coerced)

    def _coerce(self, params: list[Parameter]) -> list[Parameter]:
        node = self._node
        undeclared = {p.name: _plain(p.value) for p in params if not node.has_parameter(p.name)}
        if undeclared and not getattr(node, '_allow_undeclared_parameters', False):
            known = list(self._specs) + list(node.list_parameters([], 0).names)
            message = unknown_parameters_message(undeclared, known, node.get_fully_qualified_name())
            node.get_logger().warning(f'rejected: {message}')
            raise UndeclaredParameter(message)
        return [self._typed(p) for p in params]

    def _on_set(self, params: list) -> SetParametersResult:
        candidate = dict(self.values)
        changed = []
        for param in params:
            spec = self._specs.get(param.name)
            if spec is None:
                continue  # e.g. use_sim_time: not ours to check
            try:
                candidate[param.name] = validate(spec, _plain(param.value), param.name)
            except ParameterError as exc:
                return self._refuse(str(exc))
            changed.append(param.name)
        if not changed:
            return SetParametersResult(successful=True)
        try:
            self._apply(candidate)
        except ParameterError as exc:
            return self._refuse(str(exc))
        except BUILD_ERRORS as exc:  # the cores cannot be built: the old ones run on
            asked = ', '.join(f'{name}={shown(candidate[name])}' for name in changed)
            return self._refuse(f'{asked}: {build_failure(exc)}')
        self.values = candidate
        for name in changed:
            self._node.get_logger().info(f'parameter {name} = {candidate[name]!r}')
        return SetParametersResult(successful=True)

    def _refuse(self, reason: str) -> SetParametersResult:
        self._node.get_logger().warning(f'rejected: {reason}')
        return SetParametersResult(successful=False, reason=reason)
