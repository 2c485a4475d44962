"""Parameters of the plant node and how they build the plant core. ROS-free.

Per-axis values are lists in the order x, y, z. The offline simulator builds
the same plant from the same scenario file through `build_plant`.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

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
)
from mill_common.signals import AXES

from mill_plant.axis_plant import REVERSALS, AxisPlant
from mill_plant.cutting import CuttingForceModel
from mill_plant.drive_config import DRIVE_PARAMETERS, RECORDER_WINDOW
from mill_plant.models.base import AxisModel
from mill_plant.models.rigid import RigidAxisModel
from mill_plant.registry import AXIS_MODELS, CUTTING_MODELS
from mill_plant.spindle import SpindleGate

# The rigid model's parameters keep their plain names (mass, pitch, ...): Beltrán 2013
# Table 1 by default; the other models' parameters live under their prefix.
_RIGID = ('mass', 'screw_inertia', 'pitch', 'cart_damping', 'screw_damping', 'coulomb_friction')


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


def _full_names(specs: list[tuple[str, ParamSpec]]) -> tuple[ParamSpec, ...]:
    """Registry specs (PREFIX.name, spec), each as a spec named by its full name."""
    return tuple(replace(spec, name=name) for name, spec in specs)


# Parameters of the node that runs the lockstep (plant node, force-process node).
LOCKSTEP_TIMEOUT = ParamSpec(
    'lockstep_timeout',
    10.0,
    "wall time to wait for a step's commands before giving up [s]",
    positive,
)
STARTUP_TIMEOUT = ParamSpec(
    'startup_timeout', 60.0, 'wall time to wait for the peers to appear [s]', positive
)

# The plant node's parameters, by full name: the plant is built once (read-only) except
# for what only the node's behaviour depends on (the last four).
PLANT_PARAMETERS: tuple[ParamSpec, ...] = (
    *(replace(s, read_only=True) for s in RigidAxisModel.PARAMETERS if s.name in _RIGID),
    ParamSpec(
        'max_torque',
        [10.0] * 3,
        "drive input limit per axis, in the axis model's input unit [N m or V]; .inf = none",
        number_list(3, positive_or_inf),
        read_only=True,
    ),
    ParamSpec(
        'initial_position',
        [-0.075, -0.105, -0.005],
        'axis positions at t = 0 [m]',
        number_list(3),
        read_only=True,
    ),
    ParamSpec(
        'axis_model',
        ['rigid'] * 3,
        'dynamic model per axis x, y, z: ' + ', '.join(AXIS_MODELS),
        _axis_models,
        read_only=True,
    ),
    ParamSpec(
        'gravity',
        False,
        'the weight of the carried mass acts on the vertical z axis (Chávez-Conde eq. 3)',
        boolean,
        read_only=True,
    ),
    ParamSpec(
        'load_change.time',
        0.0,
        'time of a step change of the carried mass (workpiece or fixture) [s]',
        non_negative,
        read_only=True,
    ),
    ParamSpec(
        'load_change.mass',
        [0.0, 0.0, 0.0],
        'mass added per axis x, y, z at load_change.time [kg]; all 0 = no change',
        number_list(3),
        read_only=True,
    ),
    ParamSpec(
        'axes', list(AXES), 'axes under control; the others are braked', _axes, read_only=True
    ),
    ParamSpec('sample_period', 0.001, 'sample period T [s]', in_range(1e-6, 1.0), read_only=True),
    ParamSpec(
        'clock_period',
        0.01,
        'sim time between /clock messages [s] (a multiple of sample_period); every '
        'node with use_sim_time wakes for each one',
        in_range(1e-6, 10.0),
        read_only=True,
    ),
    ParamSpec('substeps', 4, 'RK4 substeps per sample', positive_int, read_only=True),
    ParamSpec(
        'friction_reversal',
        'stop',
        "a carriage whose velocity crosses zero inside a substep: 'stop' there for the rest "
        "of it; 'through': on from rest at once (for a law that reverses it every sample)",
        one_of(*REVERSALS),
        read_only=True,
    ),
    ParamSpec(
        'sensor_resolution', 0.0, 'encoder resolution [m]; 0 = ideal', non_negative, read_only=True
    ),
    ParamSpec(
        'cutting_model', 'kline', 'cutting force model', CUTTING_MODELS.check(), read_only=True
    ),
    *_full_names(CUTTING_MODELS.parameter_specs(read_only=True)),
    *_full_names(AXIS_MODELS.parameter_specs(read_only=True, exclude=('rigid',))),
    ParamSpec(
        'publish_ground_truth',
        True,
        'publish true velocities and disturbances (analysis only)',
        boolean,
    ),
    LOCKSTEP_TIMEOUT,
    STARTUP_TIMEOUT,
    ParamSpec(
        'min_subscribers',
        2,
        'subscribers each state topic needs before the first step (controller, observer)',
        positive_int,
    ),
)


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    """The plant node's parameters as (full name, spec): the machine's, then the drive's."""
    return [(spec.name, spec) for spec in PLANT_PARAMETERS] + list(DRIVE_PARAMETERS)


def build_cutting(values: dict[str, Any]) -> CuttingForceModel:
    cls = CUTTING_MODELS.get(values['cutting_model'])
    return cls.from_parameters(algorithm_values(cls, values))


def _load_changes(values: dict[str, Any]) -> bool:
    return any(m != 0.0 for m in values['load_change.mass'])


def build_axis_model(values: dict[str, Any], axis: int) -> AxisModel:
    cls = AXIS_MODELS.get(values['axis_model'][axis])
    own = {n: values[n] for n in _RIGID} if cls is RigidAxisModel else algorithm_values(cls, values)
    gravity = values['gravity'] and axis == 2
    return cls.from_parameters(axis, own, gravity)


def build_plant(values: dict[str, Any]) -> AxisPlant:
    """The plant: every axis its model (axis_model), all coupled through the cutting force;
    with `spindle: reference` the force passes a SpindleGate, closed until the spindle runs."""
    cutting = build_cutting(values)
    if values.get('spindle', 'on') == 'reference':
        cutting = SpindleGate(cutting, running=False)
    return AxisPlant(
        [build_axis_model(values, i) for i in range(len(AXES))],
        cutting,
        initial_position=tuple(values['initial_position']),
        max_input=tuple(values['max_torque']),
        substeps=values['substeps'],
        reversal=values['friction_reversal'],
        load_change_time=values['load_change.time'] if _load_changes(values) else math.inf,
        load_change_mass=tuple(values['load_change.mass']),
    )


def _feed_limits(value: Any) -> str | None:
    reason = number_list(2)(value)
    if reason:
        return reason
    if not value[0] <= value[1]:
        return 'needs lowest <= highest [mm/s]'
    return None


# The force-process node's own parameters; the process model's follow (force_process_specs).
FORCE_PROCESS_PARAMETERS: tuple[ParamSpec, ...] = (
    ParamSpec(
        'feed_axis',
        'x',
        'axis whose reference velocity [m/s] is the feed command',
        one_of(*AXES),
        read_only=True,
    ),
    ParamSpec(
        'feed_limits',
        [0.0, 20.0],
        "the drive's feed range [lowest, highest] [mm/s]: the reconstructed "
        'command is clamped to it',
        _feed_limits,
        read_only=True,
    ),
    ParamSpec(
        'trace_intervals',
        32,
        'grid intervals per sample of the force published on /mill/cutting_force/trace',
        positive_int,
        read_only=True,
    ),
    LOCKSTEP_TIMEOUT,
    STARTUP_TIMEOUT,
    RECORDER_WINDOW,
    ParamSpec(
        'min_subscribers',
        1,
        'subscribers /mill/cutting_force needs before the first step (the controller)',
        positive_int,
    ),
)


def force_process_specs() -> list[tuple[str, ParamSpec]]:
    """Parameters of the force-process plant node (Rubio 2013 eq. (1)-(3))."""
    # Imported here: the process model needs scipy, which the plant node does without.
    from mill_models.force_process import ForceProcessModel

    model = [
        (f'{ForceProcessModel.PREFIX}.{s.name}', replace(s, read_only=True))
        for s in ForceProcessModel.PARAMETERS
    ]
    return [(spec.name, spec) for spec in FORCE_PROCESS_PARAMETERS] + model
