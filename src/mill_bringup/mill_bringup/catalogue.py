"""Every kind of node a scenario can launch, and all that is known of each. ROS-free.

A scenario lists its nodes as `NAME PACKAGE EXECUTABLE`; the (package, executable) pair is
looked up here, and whatever needs to know a kind of node reads it from its entry: the
scenario (its parameter specs), the container (how to build it in a shared process), the
layout (which nodes group per axis), the job kinds (which node clocks a job, which are the
axis cores), the runner and the command line. A new kind of node is one entry here, its
console script in its package's setup.py, and its module.

Modules are named as text and imported only when used: reading the catalogue imports
neither rclpy nor any role package.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mill_common.parameters import ParamSpec

# What a node does in the graph.
PLANT = 'plant'  # the drive (simulated machine or hardware): clocks an axis job
TRAJECTORY = 'trajectory'
OBSERVER = 'observer'  # one per axis
CONTROLLER = 'controller'  # one per axis
FORCE_CONTROLLER = 'force_controller'
FORCE_PROCESS = 'force_process'  # the Rubio cutting process: clocks a force job


@dataclass(frozen=True)
class NodeKind:
    package: str
    executable: str
    role: str
    module: str  # the node's module: `python -m MODULE`, its main()
    factory: str  # the callable in `module` that builds the node (rclpy Node options)
    specs: str  # 'module:function' giving its parameter specs [(full name, ParamSpec)]
    lifecycle: bool  # a managed node: it can wait for `configure`/`activate`
    description: str

    @property
    def per_axis(self) -> bool:
        """One per axis, with an `axis` parameter (the per_axis layout groups them)."""
        return self.role in (OBSERVER, CONTROLLER)

    def parameter_specs(self) -> list[tuple[str, ParamSpec]]:
        module, _sep, function = self.specs.partition(':')
        specs: list[tuple[str, ParamSpec]] = getattr(importlib.import_module(module), function)()
        return specs

    def declares(self, name: str) -> bool:
        return any(full == name for full, _spec in self.parameter_specs())

    def build(self) -> Callable[..., Any]:
        """The node's factory (imports rclpy and the node's package)."""
        return getattr(importlib.import_module(self.module), self.factory)


KINDS: tuple[NodeKind, ...] = (
    NodeKind(
        'mill_plant',
        'plant_node',
        PLANT,
        'mill_plant.plant_node',
        'make_node',
        'mill_plant.config:parameter_specs',
        True,
        'the simulated three-axis machine behind the drive front end',
    ),
    NodeKind(
        'mill_trajectory',
        'trajectory_node',
        TRAJECTORY,
        'mill_trajectory.trajectory_node',
        'TrajectoryNode',
        'mill_trajectory.config:parameter_specs',
        False,
        'the reference of all axes',
    ),
    NodeKind(
        'mill_observers',
        'observer_node',
        OBSERVER,
        'mill_observers.observer_node',
        'ObserverNode',
        'mill_observers.config:parameter_specs',
        False,
        'the disturbance observer of one axis',
    ),
    NodeKind(
        'mill_controllers',
        'axis_controller_node',
        CONTROLLER,
        'mill_controllers.axis_controller_node',
        'AxisControllerNode',
        'mill_controllers.config:parameter_specs',
        False,
        'the motion controller of one axis',
    ),
    NodeKind(
        'mill_controllers',
        'force_controller_node',
        FORCE_CONTROLLER,
        'mill_controllers.force_controller_node',
        'ForceControllerNode',
        'mill_controllers.force_control:parameter_specs',
        False,
        'cutting-force control by adaptive feed (Rubio 2013)',
    ),
    NodeKind(
        'mill_plant',
        'force_process_node',
        FORCE_PROCESS,
        'mill_plant.force_process_node',
        'ForceProcessNode',
        'mill_plant.config:force_process_specs',
        False,
        'the drive and cutting process of the force job (Rubio 2013)',
    ),
)
_BY_KEY = {(k.package, k.executable): k for k in KINDS}


class UnknownNodeKind(ValueError):
    """A (package, executable) no scenario can launch; str() lists the known ones."""


def kind_of(package: str, executable: str) -> NodeKind:
    kind = _BY_KEY.get((package, executable))
    if kind is None:
        known = ', '.join(f'{k.package} {k.executable}' for k in KINDS)
        raise UnknownNodeKind(f'no node kind {package} {executable} (known: {known})')
    return kind


def of_role(role: str) -> list[NodeKind]:
    return [k for k in KINDS if k.role == role]


def packages() -> Iterable[str]:
    return sorted({k.package for k in KINDS})
