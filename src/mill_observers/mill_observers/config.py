"""Parameters of the observer node and how they build the observer core. ROS-free."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mill_common.declared import ParamSet, param
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


@dataclass(frozen=True)
class ObserverNodeParams(ParamSet):
    """The observer node's own parameters (beside every axis node's and the cores')."""

    observer: str = param('gpi', 'observer algorithm', OBSERVERS.check())
    blend_time: float = param(
        0.05,
        'after a run-time change of observer or gains, the time constant with which the '
        "estimate moves from the old observer's last value to the new one's",
        non_negative,
        unit='s',
    )
    hold_torque: float = param(
        0.0,
        'the input that holds the axis at rest when the job starts (a vertical '
        "axis's weight, in the plant's input unit): the observer starts from the "
        'disturbance it balances, so the axis does not sag when its brake lets go',
        number,
    )
    controller_node: str = param(
        '',
        'the node whose commands this observer accepts; "" = <axis>_controller',
        text,
        read_only=True,
    )


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return axis_node_specs() + ObserverNodeParams.named_specs() + OBSERVERS.parameter_specs()


def build_observer(values: dict[str, Any]) -> Observer:
    cls = OBSERVERS.get(ObserverNodeParams.from_node_values(values).observer)
    check_design_period(values)
    # a parameter declared with a rule quantity takes the rule's value for this rate and delay
    rule = loop_tuning(values['sample_period'], values['command_delay'])
    params = cls.PARAMS.from_values(algorithm_values(cls, values)).tuned(
        {'omega_c': rule.omega_c, 'omega_o': rule.omega_o}
    )
    gain = values['input_gain'] or nominal_input_gain(values['axis'])
    return cls(gain, values['sample_period'], params)  # type: ignore[call-arg]


def build_observer_loop(values: dict[str, Any]) -> ObserverLoop:
    """The observer's per-sample step, as the node and the offline simulator run it."""
    own = ObserverNodeParams.from_node_values(values)
    return ObserverLoop(
        build_observer(values),
        values['command_delay'],
        values['sample_period'],
        own.blend_time,
        own.hold_torque,
    )
