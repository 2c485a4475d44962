"""ROS parameters from ParamSpecs: declared with descriptions, checked, changed atomically.

A change at run time is validated and then applied by the node's `apply`
callback; if either refuses, the change is rejected with its reason and the
node keeps its previous configuration.
"""

from __future__ import annotations

import array
from collections.abc import Callable, Sequence
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from mill_common.parameters import ParameterError, ParamSpec, coerce, validate


def _plain(value: Any) -> Any:
    if isinstance(value, array.array):
        return list(value)
    return value


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
        values: dict[str, Any] = {}
        for name, spec in specs:
            descriptor = ParameterDescriptor(
                description=spec.description, read_only=spec.read_only, dynamic_typing=True
            )
            node.declare_parameter(name, spec.default, descriptor)
            given = node.get_parameter(name)
            typed = self._typed(given)
            if typed is not given and not spec.read_only:
                node.set_parameters([typed])  # keep the declared type: 12 -> 12.0
            values[name] = validate(spec, _plain(typed.value), name)
        try:
            apply(values)
        except ParameterError:
            raise
        except ValueError as exc:
            raise ParameterError('configuration', '', str(exc)) from exc
        self.values = values
        node.add_pre_set_parameters_callback(self._coerce)
        node.add_on_set_parameters_callback(self._on_set)

    def _typed(self, param: Parameter) -> Parameter:
        """An integer given for a float parameter, as that float (`param set ... 20`)."""
        spec = self._specs.get(param.name)
        if spec is None:
            return param
        value = _plain(param.value)
        coerced = coerce(spec, value)
        if repr(coerced) == repr(value):  # also tells 12 from 12.0 inside lists
            return param
        return Parameter(param.name, value=coerced)

    def _coerce(self, params: list[Parameter]) -> list[Parameter]:
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
                self._node.get_logger().warning(f'rejected: {exc}')
                return SetParametersResult(successful=False, reason=str(exc))
            changed.append(param.name)
        if not changed:
            return SetParametersResult(successful=True)
        try:
            self._apply(candidate)
        except ValueError as exc:  # ParameterError is a ValueError
            self._node.get_logger().warning(f'rejected: {exc}')
            return SetParametersResult(successful=False, reason=str(exc))
        self.values = candidate
        for name in changed:
            self._node.get_logger().info(f'parameter {name} = {candidate[name]!r}')
        return SetParametersResult(successful=True)
