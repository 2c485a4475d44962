"""Parameters of the observer node and how they build the observer core. ROS-free."""

from __future__ import annotations

from typing import Any

from mill_common.parameters import (
    ParamSpec,
    algorithm_values,
    axis_node_specs,
    check_design_period,
    non_negative,
    number,
    text,
)
from mill_models.axis_data import nominal_input_gain
from mill_models.loop_tuning import loop_tuning

from mill_observers.base import Observer
from mill_observers.observer_loop import ObserverLoop
from mill_observers.registry import OBSERVERS


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    specs = axis_node_specs()
    specs.append(
        ('observer', ParamSpec('observer', 'gpi', 'observer algorithm', OBSERVERS.check()))
    )
    specs.append(
        (
            'blend_time',
            ParamSpec(
                'blend_time',
                0.05,
                'after a run-time change of observer or gains, the time constant with which the '
                "estimate moves from the old observer's last value to the new one's [s]",
                non_negative,
            ),
        )
    )
    specs.append(
        (
            'hold_torque',
            ParamSpec(
                'hold_torque',
                0.0,
                'the input that holds the axis at rest when the job starts (a vertical '
                "axis's weight, in the plant's input unit): the observer starts from the "
                'disturbance it balances, so the axis does not sag when its brake lets go',
                number,
            ),
        )
    )
    specs.append(
        (
            'controller_node',
            ParamSpec(
                'controller_node',
                '',
                'the node whose commands this observer accepts; "" = <axis>_controller',
                text,
                read_only=True,
            ),
        )
    )
    return specs + OBSERVERS.parameter_specs()


def build_observer(values: dict[str, Any]) -> Observer:
    cls = OBSERVERS.get(values['observer'])
    check_design_period(values)
    own = algorithm_values(cls, values)
    if own.get('omega_o') == 0.0:  # the tuning rule's bandwidth for this rate and delay
        rule = loop_tuning(values['sample_period'], values['command_delay'])
        own['omega_o'] = rule.omega_o * own.get('bandwidth_factor', 1.0)
    gain = values['input_gain'] or nominal_input_gain(values['axis'])
    return cls.from_parameters(gain, values['sample_period'], own)


def build_observer_loop(values: dict[str, Any]) -> ObserverLoop:
    """The observer's per-sample step, as the node and the offline simulator run it."""
    return ObserverLoop(
        build_observer(values),
        values['command_delay'],
        values['sample_period'],
        values['blend_time'],
        values['hold_torque'],
    )
