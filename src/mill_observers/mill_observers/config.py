"""Parameters of the observer node and how they build the observer core. ROS-free."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from mill_common.build_check import BUILD_ERRORS, build_failure, changed_choices
from mill_common.declared import ParamSet, param
from mill_common.node_params import axis_node_specs, check_design_period
from mill_common.parameters import ParamSpec, algorithm_values, non_negative, number, text
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
    """The observer's per-sample step, as the node and the offline simulator run it, tried
    on three samples; ValueError or ArithmeticError (mill_common.build_check) if it cannot
    be built: a float overflow, a singular design, numpy's overflow, division by zero or
    invalid value, or estimates that are not finite (its derived gains are not)."""
    own = ObserverNodeParams.from_node_values(values)
    with np.errstate(over='raise', divide='raise', invalid='raise'):
        loop = ObserverLoop(
            build_observer(values),
            values['command_delay'],
            values['sample_period'],
            own.blend_time,
            own.hold_torque,
        )
        _try_at_rest(loop, values['observer'])
    return loop


def _try_at_rest(loop: ObserverLoop, name: str) -> None:
    """ValueError unless a copy of `loop` estimates finite values for an axis at rest, then
    measured 1 mm away, with no command (a non-finite gain times a zero error is not
    finite)."""
    trial = copy.deepcopy(loop)
    acted = None
    for y in (0.0, 1e-3, 1e-3):
        est = trial.step(y, acted)
        acted = 0.0
        if not all(math.isfinite(v) for v in (est.position, est.velocity, est.disturbance)):
            raise ValueError(
                f'{name} cannot run with these values: it estimates {est} for an axis at '
                f'rest, measured at {1e3 * y:g} mm'
            )


def defaults() -> dict[str, Any]:
    """Every parameter of the node at its declared default."""
    return {name: spec.default for name, spec in parameter_specs()}


def check_other_observers(values: dict[str, Any], old: dict[str, Any] | None = None) -> None:
    """A change of the gains of an observer that does not run: a candidate of it built with
    the would-be values (ValueError naming it if it cannot be built), so that a later
    switch to it cannot fail on them. old None: at start-up, every observer whose gains
    differ from their defaults."""
    for name in changed_choices(OBSERVERS, values, defaults() if old is None else old):
        try:
            build_observer_loop({**values, 'observer': name})
        except BUILD_ERRORS as exc:
            raise ValueError(f'{name} (not the running observer): {build_failure(exc)}') from exc
