"""A job's configuration as the rules read it: its nodes with their validated values, its
axes, the sample period and where it comes from (JobConfig), and what a broken rule is
(Failure, its two Sides; JobConfigError). Built by mill_bringup.job_config. ROS-free.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from mill_controllers.base import AxisController
from mill_observers.base import Observer
from mill_plant.models.base import AxisModel
from mill_trajectory.config import JobPath, build_job

from mill_bringup.catalogue import PLANT, TRAJECTORY, NodeKind
from mill_bringup.scenario import ScenarioError

# Two sample periods closer than this (relative) are the same period.
PERIOD_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Side:
    """One side of a rule: a node, the value's name there, the value."""

    node: str
    name: str
    value: Any


@dataclass(frozen=True)
class Failure:
    """A rule the configuration breaks: its name, the two sides that disagree, and why."""

    rule: str
    sides: tuple[Side, Side]
    message: str  # one line naming both sides

    def __str__(self) -> str:
        return self.message


class JobConfigError(ScenarioError):
    """The configuration breaks rules; str() is the first failure's message (one line), or
    every failure's, joined, if built with all_failures."""

    def __init__(self, failures: list[Failure], all_failures: bool = False) -> None:
        self.failures = list(failures)
        shown = self.failures if all_failures else self.failures[:1]
        super().__init__('; '.join(f.message for f in shown))


@dataclass(frozen=True)
class NodeConfig:
    """One node: what it is and its validated parameter values (read-only)."""

    name: str
    kind: NodeKind
    values: Mapping[str, Any]

    @property
    def role(self) -> str:
        return self.kind.role

    def declares(self, name: str) -> bool:
        return name in self.values


@dataclass(frozen=True)
class AxisConfig:
    """An active axis: its controller and observer nodes, their classes, the plant's model."""

    axis: str
    controller: str  # node name
    observer: str  # node name
    law: type[AxisController]
    observer_class: type[Observer]
    plant_model: type[AxisModel]
    delay: int  # the controller's command_delay (the rule: every side's)

    @property
    def output_unit(self) -> str:
        return self.law.OUTPUT_UNIT

    @property
    def input_unit(self) -> str:
        return self.plant_model.INPUT_UNIT

    @property
    def disturbance_unit(self) -> str:
        return self.observer_class.DISTURBANCE_UNIT


@dataclass(frozen=True)
class JobConfig:
    """A scenario's nodes with their validated values, and what the jobs read of them."""

    scenario: str  # its name, for messages
    nodes: tuple[NodeConfig, ...]
    sample_period: float  # [s] the job's (the plant's, the force process's revolution, ...)
    period_source: Side  # where sample_period comes from
    timing: str  # the plant's timing ('lockstep' without a plant)
    axes: tuple[str, ...]  # the plant's active axes (none without a plant)
    axis_configs: Mapping[str, AxisConfig]  # per active axis
    _built: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def node(self, name: str) -> NodeConfig:
        for n in self.nodes:
            if n.name == name:
                return n
        raise ScenarioError(f'scenario {self.scenario} has no node {name!r}')

    def values(self, name: str) -> dict[str, Any]:
        """A node's validated values (a copy: the configuration does not change)."""
        return dict(self.node(name).values)

    def of_role(self, role: str) -> list[NodeConfig]:
        return [n for n in self.nodes if n.role == role]

    def names_of(self, role: str) -> list[str]:
        return [n.name for n in self.of_role(role)]

    def axis(self, axis: str) -> AxisConfig:
        return self.axis_configs[axis]

    def delays(self) -> dict[str, int]:
        """command_delay of each active axis."""
        return {a: c.delay for a, c in self.axis_configs.items()}

    @property
    def plant(self) -> str | None:
        names = self.names_of(PLANT)
        return names[0] if names else None

    @property
    def trajectory(self) -> str | None:
        names = self.names_of(TRAJECTORY)
        return names[0] if len(names) == 1 else None

    def trajectory_job(self) -> JobPath:
        """The trajectory node's job (path and end), built once."""
        if 'trajectory' not in self._built:
            name = self.trajectory
            if name is None:
                raise ScenarioError(f'scenario {self.scenario}: an axis job has one trajectory')
            try:
                self._built['trajectory'] = build_job(self.values(name))
            except ScenarioError:
                raise
            except ValueError as exc:  # the path leaves the travel, the job is too long
                raise ScenarioError(f'{name}: {exc}') from None
        job: JobPath = self._built['trajectory']
        return job


Rule = Callable[[JobConfig], list[Failure]]


def same_period(a: float, b: float) -> bool:
    return abs(a - b) <= PERIOD_TOLERANCE * max(abs(a), abs(b))
