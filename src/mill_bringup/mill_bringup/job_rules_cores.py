"""The job's rules on each axis's cores (mill_bringup.job_config): the controllers and
observers build from their values, the law commands the unit the axis model takes, reads
the disturbance in the unit the observer gives, and has the model it designs with.
ROS-free.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from mill_common.build_check import BUILD_ERRORS, build_failure
from mill_common.signals import AXES
from mill_controllers.base import AxisController
from mill_controllers.config import build_controller, build_loop, check_other_laws
from mill_controllers.force_control import ForceFeedLoop
from mill_observers.config import build_observer_loop, check_other_observers
from mill_observers.registry import OBSERVERS

from mill_bringup.catalogue import CONTROLLER, FORCE_CONTROLLER, OBSERVER
from mill_bringup.job_config_types import Failure, JobConfig, Side


def command_unit(c: JobConfig) -> list[Failure]:
    """The law commands the unit the plant's axis model takes."""
    out = []
    plant = c.plant
    for axis, a in c.axis_configs.items():
        if a.output_unit == a.input_unit or plant is None:
            continue
        law = c.node(a.controller).values['controller']
        model = c.node(plant).values['axis_model'][AXES.index(axis)]
        mine = Side(a.controller, f'controller {law} OUTPUT_UNIT', a.output_unit)
        theirs = Side(plant, f'axis_model {model} ({axis}) INPUT_UNIT', a.input_unit)
        out.append(
            Failure(
                'command_unit',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.controller} runs {law}, which commands '
                f'{a.output_unit}, but {plant} drives it with axis model {model}, which takes '
                f'{a.input_unit}: use a law and an axis model with the same unit',
            )
        )
    return out


def law_disturbance_unit(law: type[AxisController]) -> str | None:
    """The unit a law reads the observer's disturbance in, if its class declares one
    (DISTURBANCE_UNIT); None: the law declares none, and the rule does not apply."""
    unit = getattr(law, 'DISTURBANCE_UNIT', None)
    return unit if isinstance(unit, str) else None


def disturbance_unit(c: JobConfig) -> list[Failure]:
    """The observer estimates the disturbance in the unit the law reads it in."""
    out = []
    for axis, a in c.axis_configs.items():
        wanted = law_disturbance_unit(a.law)
        if wanted is None or wanted == a.disturbance_unit:
            continue
        law = c.node(a.controller).values['controller']
        kind = c.node(a.observer).values['observer']
        mine = Side(a.observer, f'observer {kind} DISTURBANCE_UNIT', a.disturbance_unit)
        theirs = Side(a.controller, f'controller {law} DISTURBANCE_UNIT', wanted)
        out.append(
            Failure(
                'disturbance_unit',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.observer} (observer {kind}) estimates '
                f'the disturbance in {a.disturbance_unit} but {a.controller} ({law}) reads it '
                f'in {wanted}: use an observer whose estimate the law can use',
            )
        )
    return out


def _nothing(_values: dict[str, Any]) -> None:
    """(A force controller builds its one law at start-up, and switches to no other.)"""


def cores_build(c: JobConfig) -> list[Failure]:
    """Every axis controller, observer and force controller can build its cores from its
    values, as the node does at start-up: the running law or observer, and each other one
    given gains other than its defaults (a switch to it later must not fail). Its design
    period is the rule design_period's, so it is left out here."""
    builds: dict[str, tuple[str, Callable[[dict[str, Any]], Any], Callable[..., None]]] = {
        CONTROLLER: ('controller', build_loop, check_other_laws),
        OBSERVER: ('observer', build_observer_loop, check_other_observers),
        FORCE_CONTROLLER: ('force_controller', ForceFeedLoop.from_parameters, _nothing),
    }
    out = []
    for n in c.nodes:
        if n.role not in builds:
            continue
        choice, build, check_others = builds[n.role]
        values = {**n.values, 'design_period': 0.0}
        try:
            build(values)
            check_others(values)
        except BUILD_ERRORS as exc:
            defaults = {k: spec.default for k, spec in n.kind.parameter_specs()}
            given = {k: v for k, v in n.values.items() if v != defaults.get(k)}
            out.append(
                Failure(
                    'cores_build',
                    (Side(n.name, choice, values[choice]), Side(n.name, 'values', given)),
                    f'{n.name}: {choice} {values[choice]} cannot run with its values: '
                    f'{build_failure(exc)}',
                )
            )
    return out


def model_providers() -> list[str]:
    """The observers that provide a model (PROVIDES_MODEL)."""
    return [name for name in OBSERVERS if OBSERVERS.get(name).PROVIDES_MODEL]


def model_provided(c: JobConfig) -> list[Failure]:
    """A law that designs with the observer's model (needs_model) has an observer that
    provides one (PROVIDES_MODEL). needs_model belongs to the law as built (adaptive_pi: its
    model_source), so the law is built to ask it; its gains' rate is design_period's rule."""
    out = []
    for axis, a in c.axis_configs.items():
        if a.observer_class.PROVIDES_MODEL:
            continue
        values = {**c.node(a.controller).values, 'design_period': 0.0}
        if not build_controller(values).needs_model:
            continue
        law = values['controller']
        kind = c.node(a.observer).values['observer']
        mine = Side(a.controller, f'controller {law} needs_model', True)
        theirs = Side(a.observer, f'observer {kind} PROVIDES_MODEL', False)
        out.append(
            Failure(
                'model',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.controller} ({law}) designs with the '
                f"observer's model estimate, but {a.observer} (observer {kind}) estimates none "
                f'(use observer {" or ".join(model_providers())})',
            )
        )
    return out
