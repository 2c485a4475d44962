"""The job's rules with a force controller (mill_bringup.job_config): it designs with the
process model the force process runs, the feed range and the override range agree, and an
axis job's lockstep override comes once per control period. ROS-free.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mill_common.parameters import algorithm_values
from mill_models.force_process import ForceProcessModel

from mill_bringup.catalogue import FORCE_CONTROLLER, FORCE_PROCESS
from mill_bringup.job_config_types import Failure, JobConfig, NodeConfig, Side, same_period


def _one(c: JobConfig, role: str) -> NodeConfig | None:
    nodes = c.of_role(role)
    return nodes[0] if len(nodes) == 1 else None


def _process_model(values: Mapping[str, Any]) -> dict[str, Any]:
    return algorithm_values(ForceProcessModel, dict(values))


Said = tuple[str, str, Any]  # a side of a rule: node, what of it, its value


def _failure(c: JobConfig, rule: str, first: Said, second: Said, why: str) -> Failure:
    """The one way this file says a rule is broken: its two sides, and why, in the job's
    scenario."""
    return Failure(rule, (Side(*first), Side(*second)), f'scenario {c.scenario}: {why}')


def force_model(c: JobConfig) -> list[Failure]:
    """The force controller designs with the process model the force process runs."""
    plant, ctrl = _one(c, FORCE_PROCESS), _one(c, FORCE_CONTROLLER)
    if plant is None or ctrl is None:
        return []
    runs, designs = _process_model(plant.values), _process_model(ctrl.values)
    out = []
    for key in sorted(k for k in runs if runs[k] != designs.get(k)):
        name = f'{ForceProcessModel.PREFIX}.{key}'
        out.append(
            _failure(
                c,
                'force_model',
                (plant.name, name, runs[key]),
                (ctrl.name, name, designs.get(key)),
                f'{plant.name} and {ctrl.name} disagree on {name} ({runs[key]!r} and '
                f'{designs.get(key)!r}): the controller designs with the process model the '
                'plant runs',
            )
        )
    return out


def feed_limits(c: JobConfig) -> list[Failure]:
    """The force process's feed range is the controller's override range times its feed."""
    plant, ctrl = _one(c, FORCE_PROCESS), _one(c, FORCE_CONTROLLER)
    if plant is None or ctrl is None:
        return []
    cv = ctrl.values
    wanted = [cv['override.min'] * cv['nominal_feed'], cv['override.max'] * cv['nominal_feed']]
    given = list(plant.values['feed_limits'])
    if given == wanted:
        return []
    return [
        _failure(
            c,
            'feed_limits',
            (plant.name, 'feed_limits', given),
            (ctrl.name, 'override range × nominal_feed', wanted),
            f"{plant.name}'s feed_limits {given} differ from {ctrl.name}'s override range "
            f'times nominal_feed, [{wanted[0]:g}, {wanted[1]:g}] mm/s',
        )
    ]


def override_range(c: JobConfig) -> list[Failure]:
    """The trajectory clamps the feed override to the force controller's override range."""
    ctrl, trajectory = _one(c, FORCE_CONTROLLER), c.trajectory
    if ctrl is None or trajectory is None:
        return []
    tv, cv = c.node(trajectory).values, ctrl.values
    if not tv['feed_override.enabled']:
        return []
    mine = [tv['feed_override.min'], tv['feed_override.max']]
    theirs = [cv['override.min'], cv['override.max']]
    if mine == theirs:
        return []
    return [
        _failure(
            c,
            'override_range',
            (trajectory, 'feed_override.min, .max', mine),
            (ctrl.name, 'override.min, .max', theirs),
            f"{trajectory}'s feed_override range [{mine[0]:g}, {mine[1]:g}] differs from the "
            f"force controller's override range [{theirs[0]:g}, {theirs[1]:g}] "
            f"({ctrl.name}'s override.min, .max)",
        )
    ]


def override_period(c: JobConfig) -> list[Failure]:
    """An axis job's lockstep feed override comes once per control period, one spindle
    revolution of the force controller's model (the trajectory's feed_override.period)."""
    ctrl, trajectory = _one(c, FORCE_CONTROLLER), c.trajectory
    if c.plant is None or ctrl is None or trajectory is None:
        return []
    tv = c.node(trajectory).values
    given = tv['feed_override.period']
    if not (tv['feed_override.enabled'] and tv['feed_override.lockstep'] and given > 0):
        return []  # no lockstep override, or a period not given (the job says so)
    period = ForceProcessModel.from_parameters(_process_model(ctrl.values)).sample_period
    if same_period(given, period):
        return []
    return [
        _failure(
            c,
            'override_period',
            (trajectory, 'feed_override.period', given),
            (ctrl.name, 'spindle revolution 60/S_s', period),
            f"{trajectory}'s feed_override.period {given!r} s is not the force controller's "
            f"control period ({ctrl.name}'s spindle revolution 60/S_s = {period!r} s)",
        )
    ]
