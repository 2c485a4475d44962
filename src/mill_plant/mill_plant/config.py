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
    boolean,
    in_range,
    non_negative,
    number,
    number_list,
    one_of,
    positive,
    positive_int,
    positive_or_inf,
)
from mill_common.signals import AXES
from mill_models.axis_data import RigidAxisParams

from mill_plant.cutting import NoCutting, StepForce
from mill_plant.drive_config import DRIVE_PARAMETERS
from mill_plant.harmonic_force import PARAMETERS as HARMONIC_PARAMETERS
from mill_plant.harmonic_force import from_parameters as harmonic_force
from mill_plant.kline_force import (
    BELTRAN_FEED_RATE,
    BELTRAN_PROGRAM,
    KlineCuttingForce,
)
from mill_plant.kline_force import PATHS as KLINE_PATHS
from mill_plant.models.base import AxisModel
from mill_plant.models.flexible import FlexibleAxisModel
from mill_plant.models.rigid import RigidAxisModel
from mill_plant.models.transfer_function import TransferFunctionAxisModel
from mill_plant.models.velocity_drive import VelocityDriveAxisModel
from mill_plant.multi_axis import MultiAxisPlant
from mill_plant.three_axis import ThreeAxisPlant

CUTTING_MODELS = ('kline', 'step', 'harmonic', 'none')

# The axis_model parameter value -> class (one file per model in mill_plant.models).
AXIS_MODELS: dict[str, type[AxisModel]] = {
    'rigid': RigidAxisModel,  # Beltrán 2013 eq. (1)-(3); Chávez-Conde eq. (1)-(3) with gravity
    'flexible': FlexibleAxisModel,  # Chávez-Conde eq. (4)-(6)
    'transfer_function': TransferFunctionAxisModel,  # Maharof 2018 eq. (1), input in V
    'velocity_drive': VelocityDriveAxisModel,  # Hatwesh 2013 eq. (1)-(6), input in V
}
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


def _program(value: Any) -> str | None:
    reason = number_list()(value)
    if reason:
        return reason
    if len(value) < 6 or len(value) % 3:
        return 'must list at least two points x, y, z (a multiple of 3 numbers)'
    return None


def _points(flat: list[float]) -> list[list[float]]:
    return [flat[i : i + 3] for i in range(0, len(flat), 3)]


def _three(description: str, defaults: list[float], each=number) -> ParamSpec:
    return ParamSpec('', defaults, description, number_list(3, each))


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    # The rigid model's parameters keep their plain names (mass, pitch, ...): Beltrán 2013
    # Table 1 by default; the other models' parameters live under their prefix.
    model = [(spec.name, spec) for spec in RigidAxisModel.PARAMETERS if spec.name in _RIGID]
    model += [
        (
            'max_torque',
            _three(
                "drive input limit per axis, in the axis model's input unit [N m or V]; "
                '.inf = none',
                [10.0] * 3,
                positive_or_inf,
            ),
        ),
        (
            'initial_position',
            _three('axis positions at t = 0 [m]', [-0.075, -0.105, -0.005]),
        ),
    ]
    specs: list[tuple[str, ParamSpec]] = []
    for name, spec in model:
        specs.append((name, ParamSpec(name, spec.default, spec.description, spec.check, True)))
    ro = True
    specs += [
        (
            'axis_model',
            ParamSpec(
                'axis_model',
                ['rigid'] * 3,
                'dynamic model per axis x, y, z: ' + ', '.join(AXIS_MODELS),
                _axis_models,
                ro,
            ),
        ),
        (
            'gravity',
            ParamSpec(
                'gravity',
                False,
                'the weight of the carried mass acts on the vertical z axis (Chávez-Conde eq. 3)',
                boolean,
                ro,
            ),
        ),
        (
            'load_change.time',
            ParamSpec(
                'time',
                0.0,
                'time of a step change of the carried mass (workpiece or fixture) [s]',
                non_negative,
                ro,
            ),
        ),
        (
            'load_change.mass',
            ParamSpec(
                'mass',
                [0.0, 0.0, 0.0],
                'mass added per axis x, y, z at load_change.time [kg]; all 0 = no change',
                number_list(3),
                ro,
            ),
        ),
        (
            'axes',
            ParamSpec('axes', list(AXES), 'axes under control; the others are braked', _axes, ro),
        ),
        (
            'sample_period',
            ParamSpec('sample_period', 0.001, 'sample period T [s]', in_range(1e-6, 1.0), ro),
        ),
        (
            'clock_period',
            ParamSpec(
                'clock_period',
                0.01,
                'sim time between /clock messages [s] (a multiple of sample_period); every '
                'node with use_sim_time wakes for each one',
                in_range(1e-6, 10.0),
                ro,
            ),
        ),
        (
            'substeps',
            ParamSpec('substeps', 4, 'RK4 substeps per sample', positive_int, ro),
        ),
        (
            'sensor_resolution',
            ParamSpec(
                'sensor_resolution', 0.0, 'encoder resolution [m]; 0 = ideal', non_negative, ro
            ),
        ),
        (
            'cutting_model',
            ParamSpec('cutting_model', 'kline', 'cutting force model', one_of(*CUTTING_MODELS), ro),
        ),
        (
            'kline.specific_energy',
            ParamSpec(
                'specific_energy',
                1.37e9,
                'u_s, energy per removed volume [J/m^3] (0.5 hp min/in^3)',
                positive,
                ro,
            ),
        ),
        (
            'kline.spindle_speed',
            ParamSpec('spindle_speed', 1800.0, 'spindle speed N [rpm]', positive, ro),
        ),
        ('kline.teeth', ParamSpec('teeth', 2, 'cutter teeth n_t', positive_int, ro)),
        (
            'kline.tool_diameter',
            ParamSpec('tool_diameter', 0.010, 'cutter diameter D [m]', positive, ro),
        ),
        (
            'kline.radial_depth',
            ParamSpec(
                'radial_depth', 0.010, 'radial depth of cut b [m] (b = D: slot)', positive, ro
            ),
        ),
        (
            'kline.helix_angle',
            ParamSpec('helix_angle', 45.0, 'cutting-edge angle lambda [deg]', in_range(0, 89), ro),
        ),
        (
            'kline.workpiece_min',
            ParamSpec(
                'workpiece_min', [-0.1, -0.12], 'workpiece corner x, y [m]', number_list(2), ro
            ),
        ),
        (
            'kline.workpiece_max',
            ParamSpec(
                'workpiece_max', [0.03, 0.0], 'workpiece corner x, y [m]', number_list(2), ro
            ),
        ),
        (
            'kline.workpiece_top',
            ParamSpec('workpiece_top', 0.0, 'z of the workpiece top surface [m]', number, ro),
        ),
        (
            'kline.chip',
            ParamSpec(
                'chip',
                'tool',
                "whose x-y path since the previous tooth is the chip: 'programmed' = "
                "kline.program's (Beltrán 2013's quasi-static assumption), 'tool' = the tool's",
                one_of(*KLINE_PATHS),
                ro,
            ),
        ),
        (
            'kline.depth',
            ParamSpec(
                'depth',
                'tool',
                "depth of cut d_a = workpiece_top - z: 'programmed' = z of kline.program "
                "(Beltrán 2013's constant depth), 'tool' = the tool's z",
                one_of(*KLINE_PATHS),
                ro,
            ),
        ),
        (
            'kline.program',
            ParamSpec(
                'program',
                [v for p in BELTRAN_PROGRAM for v in p],
                "the programmed path for 'programmed' chip or depth: corners x0, y0, z0, x1, "
                '... [m], straight segments from t = 0 (as trajectory linear.waypoints)',
                _program,
                ro,
            ),
        ),
        (
            'kline.program_feed_rate',
            ParamSpec(
                'program_feed_rate',
                BELTRAN_FEED_RATE,
                'speed along kline.program [m/s] (as trajectory linear.feed_rate)',
                positive,
                ro,
            ),
        ),
        (
            'step.force',
            ParamSpec(
                'force',
                [0.0, 100.0, 0.0],
                'constant force Fx, Fy, Fz after the step [N]',
                number_list(3),
                ro,
            ),
        ),
        (
            'step.start_time',
            ParamSpec('start_time', 1.0, 'time the step force starts [s]', non_negative, ro),
        ),
        *[
            (
                f'harmonic.{spec.name}',
                ParamSpec(spec.name, spec.default, spec.description, spec.check, ro),
            )
            for spec in HARMONIC_PARAMETERS
        ],
        *[
            (
                f'{cls.PREFIX}.{spec.name}',
                ParamSpec(spec.name, spec.default, spec.description, spec.check, ro),
            )
            for cls in AXIS_MODELS.values()
            if cls is not RigidAxisModel
            for spec in cls.PARAMETERS
        ],
        (
            'publish_ground_truth',
            ParamSpec(
                'publish_ground_truth',
                True,
                'publish true velocities and disturbances (analysis only)',
                boolean,
            ),
        ),
        (
            'lockstep_timeout',
            ParamSpec(
                'lockstep_timeout',
                10.0,
                "wall time to wait for a step's commands before giving up [s]",
                positive,
            ),
        ),
        (
            'startup_timeout',
            ParamSpec(
                'startup_timeout', 60.0, 'wall time to wait for the peers to appear [s]', positive
            ),
        ),
        (
            'min_subscribers',
            ParamSpec(
                'min_subscribers',
                2,
                'subscribers each state topic needs before the first step (controller, observer)',
                positive_int,
            ),
        ),
    ]
    specs += list(DRIVE_PARAMETERS)
    return [
        (name, ParamSpec(name, s.default, s.description, s.check, s.read_only)) for name, s in specs
    ]


def build_cutting(values: dict[str, Any]):
    model = values['cutting_model']
    if model == 'kline':
        return KlineCuttingForce(
            specific_energy=values['kline.specific_energy'],
            spindle_speed_rpm=values['kline.spindle_speed'],
            teeth=values['kline.teeth'],
            tool_diameter=values['kline.tool_diameter'],
            radial_depth=values['kline.radial_depth'],
            helix_angle=math.radians(values['kline.helix_angle']),
            workpiece_min=tuple(values['kline.workpiece_min']),
            workpiece_max=tuple(values['kline.workpiece_max']),
            workpiece_top=values['kline.workpiece_top'],
            chip=values['kline.chip'],
            depth=values['kline.depth'],
            program=_points(values['kline.program']),
            program_feed_rate=values['kline.program_feed_rate'],
        )
    if model == 'step':
        return StepForce(tuple(values['step.force']), values['step.start_time'])
    if model == 'harmonic':
        return harmonic_force(_prefixed(values, 'harmonic'))
    return NoCutting()


def _prefixed(values: dict[str, Any], prefix: str) -> dict[str, Any]:
    cut = len(prefix) + 1
    return {k[cut:]: v for k, v in values.items() if k.startswith(prefix + '.')}


def _load_changes(values: dict[str, Any]) -> bool:
    return any(m != 0.0 for m in values['load_change.mass'])


def build_axis_model(values: dict[str, Any], axis: int) -> AxisModel:
    cls = AXIS_MODELS[values['axis_model'][axis]]
    own = {n: values[n] for n in _RIGID} if cls is RigidAxisModel else _prefixed(values, cls.PREFIX)
    gravity = values['gravity'] and axis == 2
    return cls.from_parameters(axis, own, gravity)


def build_plant(values: dict[str, Any]) -> ThreeAxisPlant | MultiAxisPlant:
    """Three rigid axes: the Beltrán plant (fast, unrolled); any other mix: MultiAxisPlant."""
    rigid_only = all(m == 'rigid' for m in values['axis_model'])
    if rigid_only and not values['gravity'] and not _load_changes(values):
        axes = [RigidAxisParams(**{n: values[n][i] for n in _RIGID}) for i in range(len(AXES))]
        return ThreeAxisPlant(
            axes,
            build_cutting(values),
            initial_position=tuple(values['initial_position']),
            max_torque=tuple(values['max_torque']),
            substeps=values['substeps'],
        )
    return MultiAxisPlant(
        [build_axis_model(values, i) for i in range(len(AXES))],
        build_cutting(values),
        initial_position=tuple(values['initial_position']),
        max_input=tuple(values['max_torque']),
        substeps=values['substeps'],
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


def force_process_specs() -> list[tuple[str, ParamSpec]]:
    """Parameters of the force-process plant node (Rubio 2013 eq. (1)-(3))."""
    from mill_models.force_process import ForceProcessModel

    lockstep = {name: spec for name, spec in parameter_specs()}
    specs = [
        (
            'feed_axis',
            ParamSpec(
                'feed_axis',
                'x',
                'axis whose reference velocity [m/s] is the feed command',
                one_of(*AXES),
                True,
            ),
        ),
        (
            'feed_limits',
            ParamSpec(
                'feed_limits',
                [0.0, 20.0],
                "the drive's feed range [lowest, highest] [mm/s]: the reconstructed "
                'command is clamped to it',
                _feed_limits,
                True,
            ),
        ),
        (
            'trace_intervals',
            ParamSpec(
                'trace_intervals',
                32,
                'grid intervals per sample of the force published on /mill/cutting_force/trace',
                positive_int,
                True,
            ),
        ),
        ('lockstep_timeout', lockstep['lockstep_timeout']),
        ('startup_timeout', lockstep['startup_timeout']),
        (
            'min_subscribers',
            ParamSpec(
                'min_subscribers',
                1,
                'subscribers /mill/cutting_force needs before the first step (the controller)',
                positive_int,
            ),
        ),
    ]
    model = [
        (f'{ForceProcessModel.PREFIX}.{s.name}', replace(s, read_only=True))
        for s in ForceProcessModel.PARAMETERS
    ]
    return specs + model
