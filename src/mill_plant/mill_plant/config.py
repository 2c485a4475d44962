"""Parameters of the plant node and how they build the plant core. ROS-free.

Per-axis values are lists in the order x, y, z. The offline simulator builds
the same plant from the same scenario file through `build_plant`.
"""

from __future__ import annotations

import math
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
)
from mill_common.signals import AXES

from mill_plant.cutting import NoCutting, StepForce
from mill_plant.kline_force import KlineCuttingForce
from mill_plant.rigid_axis import BELTRAN_TABLE1, RigidAxisParams
from mill_plant.three_axis import ThreeAxisPlant

CUTTING_MODELS = ('kline', 'step', 'none')


def _table(field: str) -> list[float]:
    return [float(getattr(BELTRAN_TABLE1[a], field)) for a in AXES]


def _axes(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or not value:
        return 'must be a non-empty list of axis names'
    for axis in value:
        if axis not in AXES:
            return f'must name axes among {", ".join(AXES)}, got {axis!r}'
    if len(set(value)) != len(value):
        return 'must not repeat an axis'
    return None


def _three(description: str, defaults: list[float], each=number) -> ParamSpec:
    return ParamSpec('', defaults, description, number_list(3, each))


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    # Paper defaults: Beltrán 2013 Table 1 and the cutting data of its force section.
    model = [
        ('mass', _three('carriage mass m per axis x, y, z [kg]', _table('mass'), positive)),
        (
            'screw_inertia',
            _three('ball-screw inertia J per axis [kg m^2]', _table('screw_inertia'), positive),
        ),
        ('pitch', _three('ball-screw pitch p per axis [m/rev]', _table('pitch'), positive)),
        (
            'cart_damping',
            _three('guideway damping c_b per axis [N s/m]', _table('cart_damping'), non_negative),
        ),
        (
            'screw_damping',
            _three(
                'screw-bearing damping c_t per axis, translational [N s/m]',
                _table('screw_damping'),
                non_negative,
            ),
        ),
        (
            'coulomb_friction',
            _three('Coulomb friction mu per axis [N]', _table('coulomb_friction'), non_negative),
        ),
        ('max_torque', _three('drive torque limit per axis [N m]', [10.0] * 3, positive)),
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
        )
    if model == 'step':
        return StepForce(tuple(values['step.force']), values['step.start_time'])
    return NoCutting()


def build_plant(values: dict[str, Any]) -> ThreeAxisPlant:
    axes = [
        RigidAxisParams(
            mass=values['mass'][i],
            screw_inertia=values['screw_inertia'][i],
            pitch=values['pitch'][i],
            cart_damping=values['cart_damping'][i],
            screw_damping=values['screw_damping'][i],
            coulomb_friction=values['coulomb_friction'][i],
        )
        for i in range(len(AXES))
    ]
    return ThreeAxisPlant(
        axes,
        build_cutting(values),
        initial_position=tuple(values['initial_position']),
        max_torque=tuple(values['max_torque']),
        substeps=values['substeps'],
    )
