"""Process layouts: which nodes of a scenario share a process (a container). ROS-free.

- processes: every node in its own process (the default);
- per_axis: the observer and the controller of each axis in one process `AXIS_axis`;
- single: every node of the graph in one process `container`.

A layout is a deployment choice only: each node keeps its name, parameters and topics
wherever it runs (mill_bringup.container), so the same scenario can run split over hosts.
A node that runs elsewhere (`external`) is never put in a process here, and a node named
in `alone` keeps a process of its own in every layout. The runner (graph.py) and the
launch file (launch_plan.py) both take their processes from `processes()`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from mill_bringup.scenario import LAYOUTS, NodeLaunch, Scenario, ScenarioError, check_layout

if TYPE_CHECKING:
    from mill_bringup.job_config import JobConfig

__all__ = ['LAYOUTS', 'Process', 'check_layout', 'processes']

CONTAINER = 'container'  # the process of layout single


@dataclass(frozen=True)
class Process:
    """One process of a layout: a node alone, or a container of several nodes."""

    name: str
    nodes: tuple[NodeLaunch, ...]

    @property
    def container(self) -> bool:
        return len(self.nodes) > 1

    @property
    def node_names(self) -> list[str]:
        return [n.name for n in self.nodes]


def processes(
    scen: Scenario,
    layout: str,
    external: Iterable[str] = (),
    alone: Iterable[str] = (),
    config: JobConfig | None = None,
) -> list[Process]:
    """The processes that run the scenario's nodes in this layout, in the scenario's order
    (a process comes where its first node is listed). The axis of a per-axis node comes
    from the job's configuration if given (else the node's parameters are validated)."""
    check_layout(layout)
    left_out = set(external)
    apart = set(alone)
    groups: dict[str, list[NodeLaunch]] = {}
    for node in scen.nodes:
        if node.name in left_out:
            continue
        key = node.name
        if node.name not in apart:
            if layout == 'single':
                key = CONTAINER
            elif layout == 'per_axis' and node.kind.per_axis:
                values = config.node(node.name).values if config else scen.parameters(node.name)
                key = f'{values["axis"]}_axis'
        groups.setdefault(key, []).append(node)
    names = {n.name for n in scen.nodes}
    for key, members in groups.items():
        if len(members) > 1 and key in names:
            raise ScenarioError(
                f'layout {layout}: process name {key!r} is also a node of scenario {scen.name}'
            )
    out = []
    for key, members in groups.items():
        # A group of one is that node's own process, named after it.
        name = key if len(members) > 1 else members[0].name
        out.append(Process(name, tuple(members)))
    return out
