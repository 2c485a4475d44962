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
            Failure(
                'force_model',
                (Side(plant.name, name, runs[key]), Side(ctrl.name, name, designs.get(key))),
                f'scenario {c.scenario}: {plant.name} and {ctrl.name} disagree on {name} '
                f'({runs[key]!r} and {designs.get(key)!r}): the controller designs with the '
                'process model the plant runs',
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
        Failure(
            'feed_limits',
            (
                Side(plant.name, 'feed_limits', given),
                Side(ctrl.name, 'override range × nominal_feed', wanted),
            ),
            f"scenario {c.scenario}: {plant.name}'s feed_limits {given} differ from "
            f"{ctrl.name}'s override range times nominal_feed, [{wanted[0]:g}, {wanted[1]:g}] "
            'mm/s',
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
        Failure(
            'override_range',
            (
                Side(trajectory, 'feed_override.min, .max', mine),
                Side(ctrl.name, 'override.min, .max', theirs),
            ),
            f"scenario {c.scenario}: {trajectory}'s feed_override range [{mine[0]:g}, "
            f"{mine[1]:g}] differs from the force controller's override range "
            f"[{theirs[0]:g}, {theirs[1]:g}] ({ctrl.name}'s override.min, .max)",
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
        Failure(
            'override_period',
            (
                Side(trajectory, 'feed_override.period', given),
                Side(ctrl.name, 'spindle revolution 60/S_s', period),
            ),
            f"scenario {c.scenario}: {trajectory}'s feed_override.period {given!r} s is not "
            f"the force controller's control period ({ctrl.name}'s spindle revolution 60/S_s "
            f'= {period!r} s)',
        )
    ]
