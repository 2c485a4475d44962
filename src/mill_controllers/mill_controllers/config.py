"""Parameters of the axis controller node and how they build the controller core. ROS-free."""

from __future__ import annotations

from typing import Any

from mill_common.parameters import (
    ParamSpec,
    algorithm_values,
    axis_node_specs,
    check_design_period,
    non_negative,
    non_negative_int,
    positive_or_inf,
    text,
)
from mill_models.axis_data import nominal_input_gain
from mill_models.loop_tuning import loop_tuning

from mill_controllers.base import AxisController
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.registry import CONTROLLERS


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    specs = axis_node_specs()
    specs.append(
        (
            'controller',
            ParamSpec(
                'controller',
                'adrc',
                'control law (see README: algorithms)',
                CONTROLLERS.check(),
            ),
        )
    )
    specs.append(
        (
            'blend_time',
            ParamSpec(
                'blend_time',
                0.05,
                'after a run-time change of controller or gains, the time constant with which '
                "the old law's output fades into the new one's [s]; 0 = at the next sample",
                non_negative,
            ),
        )
    )
    specs.append(
        (
            'observer_node',
            ParamSpec(
                'observer_node',
                '',
                'the node whose estimates this controller accepts; "" = <axis>_observer',
                text,
                True,
            ),
        )
    )
    specs.append(
        (
            'trajectory_node',
            ParamSpec(
                'trajectory_node',
                'trajectory',
                'the node whose reference this controller accepts',
                text,
                True,
            ),
        )
    )
    specs.append(
        (
            'following_error_limit',
            ParamSpec(
                'following_error_limit',
                0.005,
                'following-error trip: |measured position - reference| above this latches a '
                'brake request (effort NaN: the drive brakes the axis) until reset by the '
                'reset_trip service (a new limit leaves a trip latched) [m]; .inf disables it',
                positive_or_inf,
            ),
        )
    )
    specs.append(
        (
            'max_state_gap',
            ParamSpec(
                'max_state_gap',
                10,
                'realtime: a gap of this many sample periods or more between two states means '
                "the drive has stopped the axis (set it to the drive's brake_after): the "
                'controller trips; reset, it re-arms holding the position it measures and '
                'takes the reference up again once it comes within half the following-error '
                'limit; 0: off',
                non_negative_int,
                True,
            ),
        )
    )
    return specs + CONTROLLERS.parameter_specs()


def input_gain(values: dict[str, Any]) -> float:
    return values['input_gain'] or nominal_input_gain(values['axis'])


def build_controller(values: dict[str, Any]) -> AxisController:
    cls = CONTROLLERS.get(values['controller'])
    check_design_period(values)
    own = algorithm_values(cls, values)
    if own.get('omega_c') == 0.0:  # the tuning rule's bandwidth for this rate and delay
        own['omega_c'] = loop_tuning(values['sample_period'], values['command_delay']).omega_c
    return cls.from_parameters(input_gain(values), values['sample_period'], own)


def build_loop(values: dict[str, Any]) -> AxisControlLoop:
    """The controller's per-sample step, as the node and the offline simulator run it."""
    return AxisControlLoop(
        build_controller(values),
        values['sample_period'],
        values['following_error_limit'],
        values['command_delay'],
        values['blend_time'],
        values['max_state_gap'],
    )
