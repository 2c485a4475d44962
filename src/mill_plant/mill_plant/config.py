"""Parameters of the plant node and how they build the plant core. ROS-free.

Per-axis values are lists in the order x, y, z. The offline simulator builds
the same plant from the same scenario file through `build_plant`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParamSpec,
    algorithm_values,
    boolean,
    in_range,
    non_negative,
    number_list,
    one_of,
    positive,
    positive_int,
    positive_or_inf,
    whole_in,
)
from mill_common.signals import AXES

from mill_plant.axis_plant import REVERSALS, AxisPlant
from mill_plant.cutting import CuttingForceModel
from mill_plant.drive_config import DRIVE_PARAMETERS, DriveParams, RecorderWindow
from mill_plant.models.base import AxisModel, AxisModelParams
from mill_plant.models.rigid import RigidAxisModel, RigidModelParams
from mill_plant.registry import AXIS_MODELS, CUTTING_MODELS
from mill_plant.spindle import SpindleGate

# The rigid model's parameters keep their plain names (mass, pitch, ...): Beltrán 2013
# Table 1 by default; the other models' parameters live under their prefix. The rigid
# model's g is not on the node (it takes the standard gravity).
_BASE = {f.name for f in dataclasses.fields(AxisModelParams)}
_RIGID = tuple(f.name for f in dataclasses.fields(RigidModelParams) if f.name not in _BASE)


def _axis_models(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or len(value) != 3:
        return 'must list 3 model names (x, y, z)'
    for name in value:
        if name not in AXIS_MODELS:
            return f'must name models among {", ".join(AXIS_MODELS)}, got {name!r}'
    return None


def _axes(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or not value:
        return 'must be a non-empty list of axis names'
    for axis in value:
        if axis not in AXES:
            return f'must name axes among {", ".join(AXES)}, got {axis!r}'
    if len(set(value)) != len(value):
        return 'must not repeat an axis'
    return None


@dataclass(frozen=True)
class LockstepClock(ParamSet):
    """Parameters of the node that runs the lockstep (plant node, force-process node)."""

    lockstep_timeout: float = param(
        10.0, "wall time to wait for a step's commands before giving up", positive, unit='s'
    )
    startup_timeout: float = param(
        60.0, 'wall time to wait for the peers to appear', positive, unit='s'
    )


@dataclass(frozen=True)
class LoadChange(ParamSet):
    """A step change of the carried mass."""

    PREFIX: ClassVar[str] = 'load_change'
    time: float = param(
        0.0,
        'time of a step change of the carried mass (workpiece or fixture)',
        non_negative,
        unit='s',
        read_only=True,
    )
    mass: list[float] = param(
        [0.0, 0.0, 0.0],
        'mass added per axis x, y, z at load_change.time [kg]; all 0 = no change',
        number_list(3),
        read_only=True,
    )

    @property
    def start(self) -> float:
        """When the mass changes [s]: inf when no mass is added."""
        return self.time if any(m != 0.0 for m in self.mass) else math.inf


@dataclass(frozen=True)
class MachineParams(LockstepClock):
    """The plant node's own parameters: the plant is built once (read-only) except for
    what only the node's behaviour depends on (publish_ground_truth, the timeouts and
    min_subscribers)."""

    max_torque: list[float] = param(
        [10.0] * 3,
        "drive input limit per axis, in the axis model's input unit [N m or V]; .inf = none",
        number_list(3, positive_or_inf),
        read_only=True,
    )
    initial_position: list[float] = param(
        [-0.075, -0.105, -0.005],
        'axis positions at t = 0',
        number_list(3),
        unit='m',
        read_only=True,
    )
    axis_model: list[str] = param(
        ['rigid'] * 3,
        'dynamic model per axis x, y, z: ' + ', '.join(AXIS_MODELS),
        _axis_models,
        read_only=True,
    )
    gravity: bool = param(
        False,
        'the weight of the carried mass acts on the vertical z axis (Chávez-Conde eq. 3)',
        boolean,
        read_only=True,
    )
    axes: list[str] = param(
        list(AXES), 'axes under control; the others are braked', _axes, read_only=True
    )
    sample_period: float = param(
        0.001, 'sample period T', in_range(1e-6, 1.0), unit='s', read_only=True
    )
    clock_period: float = param(
        0.01,
        'sim time between /clock messages [s] (a multiple of sample_period); every '
        'node with use_sim_time wakes for each one',
        in_range(1e-6, 10.0),
        read_only=True,
    )
    substeps: int = param(4, 'RK4 substeps per sample', whole_in(1, 1000), read_only=True)
    friction_reversal: str = param(
        'stop',
        "a carriage whose velocity crosses zero inside a substep: 'stop' there for the rest "
        "of it; 'through': on from rest at once (for a law that reverses it every sample)",
        one_of(*REVERSALS),
        read_only=True,
    )
    sensor_resolution: float = param(
        0.0, 'encoder resolution [m]; 0 = ideal', non_negative, read_only=True
    )
    cutting_model: str = param(
        'kline', 'cutting force model', CUTTING_MODELS.check(), read_only=True
    )
    publish_ground_truth: bool = param(
        True, 'publish true velocities and disturbances (analysis only)', boolean
    )
    min_subscribers: int = param(
        2,
        'subscribers each state topic needs before the first step (controller, observer)',
        positive_int,
    )


def _full_names(specs: list[tuple[str, ParamSpec]]) -> tuple[ParamSpec, ...]:
    """(full name, spec) pairs, each as a spec named by its full name."""
    return tuple(spec if spec.name == name else replace(spec, name=name) for name, spec in specs)


# The plant node's parameters, by full name: the rigid model's, the machine's, the load
# change's, then those of the cutting models and of the other axis models (read-only).
PLANT_PARAMETERS: tuple[ParamSpec, ...] = (
    *(replace(s, read_only=True) for s in RigidModelParams.specs() if s.name in _RIGID),
    *_full_names(MachineParams.named_specs()),
    *_full_names(LoadChange.named_specs()),
    *_full_names(CUTTING_MODELS.parameter_specs(read_only=True)),
    *_full_names(AXIS_MODELS.parameter_specs(read_only=True, exclude=('rigid',))),
)


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    """The plant node's parameters as (full name, spec): the machine's, then the drive's."""
    return [(spec.name, spec) for spec in PLANT_PARAMETERS] + list(DRIVE_PARAMETERS)


def build_cutting(values: Mapping[str, Any]) -> CuttingForceModel:
    cls = CUTTING_MODELS.get(values['cutting_model'])
    return cls.from_parameters(algorithm_values(cls, values))


def build_axis_model(values: Mapping[str, Any], axis: int) -> AxisModel:
    machine = MachineParams.from_node_values(values)
    cls = AXIS_MODELS.get(machine.axis_model[axis])
    own = {n: values[n] for n in _RIGID} if cls is RigidAxisModel else algorithm_values(cls, values)
    return cls.from_parameters(axis, own, machine.gravity and axis == 2)


def build_plant(values: Mapping[str, Any]) -> AxisPlant:
    """The plant: every axis its model (axis_model), all coupled through the cutting force;
    with `spindle: reference` the force passes a SpindleGate, closed until the spindle runs."""
    machine = MachineParams.from_node_values(values)
    load = LoadChange.from_node_values(values)
    cutting = build_cutting(values)
    if DriveParams.from_node_values(values).spindle == 'reference':
        cutting = SpindleGate(cutting, running=False)
    return AxisPlant(
        [build_axis_model(values, i) for i in range(len(AXES))],
        cutting,
        initial_position=tuple(machine.initial_position),
        max_input=tuple(machine.max_torque),
        substeps=machine.substeps,
        reversal=machine.friction_reversal,
        load_change_time=load.start,
        load_change_mass=tuple(load.mass),
    )


def _feed_limits(value: Any) -> str | None:
    reason = number_list(2)(value)
    if reason:
        return reason
    if not value[0] <= value[1]:
        return 'needs lowest <= highest [mm/s]'
    return None


@dataclass(frozen=True)
class ForceProcessParams(LockstepClock, RecorderWindow):
    """The force-process node's own parameters; the process model's follow
    (force_process_specs)."""

    feed_axis: str = param(
        'x',
        'axis whose reference velocity [m/s] is the feed command',
        one_of(*AXES),
        read_only=True,
    )
    feed_limits: list[float] = param(
        [0.0, 20.0],
        "the drive's feed range [lowest, highest] [mm/s]: the reconstructed "
        'command is clamped to it',
        _feed_limits,
        read_only=True,
    )
    trace_intervals: int = param(
        32,
        'grid intervals per sample of the force published on /mill/cutting_force/trace',
        whole_in(1, 1000),
        read_only=True,
    )
    min_subscribers: int = param(
        1,
        'subscribers /mill/cutting_force needs before the first step (the controller)',
        positive_int,
    )


FORCE_PROCESS_PARAMETERS: tuple[ParamSpec, ...] = _full_names(ForceProcessParams.named_specs())


def force_process_specs() -> list[tuple[str, ParamSpec]]:
    """Parameters of the force-process plant node (Rubio 2013 eq. (1)-(3))."""
    # Imported here: the process model needs scipy, which the plant node does without.
    from mill_models.force_process import ForceProcessModel

    model = [
        (f'{ForceProcessModel.PREFIX}.{s.name}', replace(s, read_only=True))
        for s in ForceProcessModel.PARAMETERS
    ]
    return [(spec.name, spec) for spec in FORCE_PROCESS_PARAMETERS] + model
