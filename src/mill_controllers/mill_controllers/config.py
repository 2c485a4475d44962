"""Parameters of the axis controller node and how they build the controller core. ROS-free."""

from __future__ import annotations

import copy
import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from mill_common.build_check import BUILD_ERRORS, build_failure, changed_choices
from mill_common.declared import param
from mill_common.hold_window import HoldWindow
from mill_common.node_params import axis_node_specs, check_design_period
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    algorithm_values,
    boolean,
    non_negative,
    positive,
    positive_or_inf,
    text,
)
from mill_common.signals import AxisReference, ControlInputs, Estimate
from mill_models.axis_data import nominal_input_gain
from mill_models.loop_tuning import loop_tuning

from mill_controllers.base import BASE_INPUTS, AxisController
from mill_controllers.command_shaping import (
    BacklashParams,
    CommandFilterParams,
    CommandShaping,
    FrictionCompensationParams,
)
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.registry import CONTROLLERS


@dataclass(frozen=True)
class ControllerNodeParams(HoldWindow):
    """The controller node's own parameters (beside every per-axis node's and the laws')."""

    controller: str = param('adrc', 'control law (see README: algorithms)', CONTROLLERS.check())
    blend_time: float = param(
        0.05,
        'after a run-time change of controller or gains, the time constant with which '
        "the old law's output fades into the new one's [s]; 0 = at the next sample",
        non_negative,
    )
    observer_node: str = param(
        '',
        'the node whose estimates this controller accepts; "" = <axis>_observer',
        text,
        read_only=True,
    )
    trajectory_node: str = param(
        'trajectory',
        'the node whose reference this controller accepts',
        text,
        read_only=True,
    )
    following_error_limit: float = param(
        0.005,
        'following-error trip: |measured position - reference| above this latches a '
        'brake request (effort NaN: the drive brakes the axis) until reset by the '
        'reset_trip service (a new limit leaves a trip latched) [m]; .inf disables it',
        positive_or_inf,
    )
    gap_trip: bool = param(
        True,
        'realtime: trip when the drive says in its state that it has stopped the axis (and, '
        'from a driver that does not say, after a gap of the window H(v) of the hold '
        'parameters excursion, max_hold, hold_deviation, which the drive declares the '
        'same); a shorter gap is reported, never tripped on; reset, the controller re-arms '
        'holding the position it measures and takes the reference up again once it comes '
        'within half the following-error limit; false: never (it knows nothing of the '
        "drive's stops)",
        boolean,
        read_only=True,
    )
    min_following_error: float = param(
        0.0,
        'the following-error limit at rest, growing linearly with the reference speed to '
        'following_error_limit at max_velocity (LinuxCNC MIN_FERROR and FERROR); 0 = the '
        'fixed following_error_limit at every speed',
        non_negative,
        unit='m',
        read_only=True,
    )
    max_velocity: float = param(
        0.1,
        'the reference speed at which the following-error limit reaches '
        'following_error_limit (used only with min_following_error > 0)',
        positive,
        unit='m/s',
        read_only=True,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.min_following_error > self.following_error_limit:
            raise ParameterError(
                'min_following_error',
                self.min_following_error,
                f'above following_error_limit = {self.following_error_limit!r}',
            )


SHAPING = (CommandFilterParams, FrictionCompensationParams, BacklashParams)


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    shaping = [spec for cls in SHAPING for spec in cls.named_specs()]
    return (
        axis_node_specs()
        + ControllerNodeParams.named_specs()
        + shaping
        + CONTROLLERS.parameter_specs()
    )


def build_shaping(values: dict[str, Any]) -> CommandShaping:
    """The command shaping the values ask for (inactive when all are at their defaults)."""
    return CommandShaping(
        values['sample_period'],
        CommandFilterParams.from_node_values(values),
        FrictionCompensationParams.from_node_values(values),
        BacklashParams.from_node_values(values),
    )


def input_gain(values: dict[str, Any]) -> float:
    return values['input_gain'] or nominal_input_gain(values['axis'])


def build_controller(values: dict[str, Any]) -> AxisController:
    """The law `controller` names, built from the values and tried on two samples at rest;
    ValueError or ArithmeticError (mill_common.build_check) if it cannot be built: a float
    overflow, a singular design, numpy's overflow, division by zero or invalid value, or a
    law whose command is not finite (its derived gains are not)."""
    cls = CONTROLLERS.get(values['controller'])
    check_design_period(values)
    params = cls.PARAMS.from_values(algorithm_values(cls, values))
    if cls.PARAMS.rule_fields():  # a 0 stands for the tuning rule's value at this rate, delay
        rule = loop_tuning(values['sample_period'], values['command_delay'])
        params = params.tuned({'omega_c': rule.omega_c, 'omega_o': rule.omega_o})
    with np.errstate(over='raise', divide='raise', invalid='raise'):
        law = cls.from_params(input_gain(values), values['sample_period'], params)
        if not law.needs_model:  # (a law that needs the observer's model gets it at run time)
            _try_at_rest(law, values['controller'], values['sample_period'])
    return law


def _try_at_rest(law: AxisController, name: str, sample_period: float) -> None:
    """ValueError unless a copy of `law` commands a finite value on the axis at rest at the
    reference, then 1 mm from it (a non-finite gain times a zero error is not finite)."""
    trial = copy.deepcopy(law)
    at_rest = Estimate(0.0, 0.0, 0.0)
    for k, y in enumerate((0.0, 1e-3)):
        u = trial.compute(
            ControlInputs(k * sample_period, y, AxisReference(0.0, 0.0, 0.0), at_rest)
        )
        if not math.isfinite(u):
            raise ValueError(
                f'{name} cannot run with these values: it commands {u} on an axis at rest '
                f'{1e3 * y:g} mm from its reference'
            )


def defaults() -> dict[str, Any]:
    """Every parameter of the node at its declared default."""
    return {name: spec.default for name, spec in parameter_specs()}


# Parameters whose change keeps the running law (the others replace it, without a bump).
KEEPS_LAW = ('blend_time', 'following_error_limit', 'input_warn_time', 'input_timeout')


def rebuilds_law(values: Mapping[str, Any], old: Mapping[str, Any]) -> bool:
    """Whether a parameter change replaces the running law (else only the blend time, the
    following-error limit and the input watch change)."""
    return any(values[k] != old[k] for k in values if k not in KEEPS_LAW)


def unseen_input(law: AxisController, seen: Collection[str]) -> str | None:
    """An input the law needs each sample, beyond the base ones, of which no sample has
    arrived yet (a switch to it is refused); None: every one has."""
    return next((s for s in law.required_inputs() if s not in BASE_INPUTS and s not in seen), None)


def check_other_laws(values: dict[str, Any], old: dict[str, Any] | None = None) -> None:
    """A change of the gains of a law that does not run: a candidate of that law built with
    the would-be values (ValueError, ArithmeticError naming it if it cannot be built), so
    that a later switch to it cannot fail on them. old None: at start-up, every law whose
    gains differ from their defaults."""
    for name in changed_choices(CONTROLLERS, values, defaults() if old is None else old):
        try:
            build_controller({**values, 'controller': name})
        except BUILD_ERRORS as exc:
            raise ValueError(f'{name} (not the running law): {build_failure(exc)}') from exc


def build_loop(values: dict[str, Any]) -> AxisControlLoop:
    """The controller's per-sample step, as the node and the offline simulator run it."""
    return AxisControlLoop(
        build_controller(values),
        values['sample_period'],
        values['following_error_limit'],
        values['command_delay'],
        values['blend_time'],
        HoldWindow.from_node_values(values) if values['gap_trip'] else None,
        values['min_following_error'],
        values['max_velocity'],
        build_shaping(values),
    )
