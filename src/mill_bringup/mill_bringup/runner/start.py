"""Starting a run: which processes start first and which clock nodes wait (`plan`), then the
nodes, and, once the monitor hears them, the node that clocks the job (`start`).

The clock node starts last, once the monitor has matched the others' publishers: it cannot
see whether their messages reach the monitor. A clock node in a container (a lifecycle
drive that shares a process) waits for `activate`, sent once the upstream is heard; so
does an external one (started elsewhere).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mill_bringup.jobs.base import GraphPlan, Job
from mill_bringup.layout import Process, processes
from mill_bringup.lifecycle_client import activate
from mill_bringup.runner.options import RunError, RunOptions
from mill_bringup.scenario import NodeLaunch, check_layout

if TYPE_CHECKING:
    from mill_bringup.runner.session import Session


@dataclass
class Launch:
    """The processes of a run in the order they start, and the scenario changes made for it."""

    first: list[Process]  # every process but a clock node's own
    last: list[Process]  # the clock node's own process, started once the others are heard
    held: list[NodeLaunch]  # clock nodes in a container: they wait for `activate`
    restartable: list[str]  # processes --respawn may start again (none holds a clock)
    given: dict[str, dict[str, Any]]  # overrides of the nodes this run changes, as they were
    graph: GraphPlan  # what the runner starts and hears of the graph, as prepared for the run

    def restore(self, job: Job[Any]) -> None:
        """Put the overrides back: the next run of the scenario may differ."""
        for name, overrides in self.given.items():
            job.scenario.overrides[name] = overrides


def plan(job: Job[Any], options: RunOptions) -> Launch:
    """The run's processes; the scenario's overrides adjusted for it (Launch.restore undoes)."""
    scen = job.scenario
    unknown = sorted(options.external - {n.name for n in scen.nodes})
    if unknown:
        raise RunError(f'--external: scenario {scen.name} has no node {unknown[0]!r}')
    layout = check_layout(scen.layout if options.layout is None else options.layout)
    # Every node's overrides as they were: the next run of the scenario (another layout,
    # another variant) starts from them again (Launch.restore).
    given = {n.name: dict(scen.overrides.get(n.name, {})) for n in scen.nodes}
    job.prepare_graph(monitored=True, layout=layout, recorded=options.record_bag is not None)
    clock_names = {n.name for n in job.clock_nodes}
    managed = {n.name for n in job.clock_nodes if n.kind.lifecycle}
    planned = processes(
        scen, layout, options.external, alone=clock_names - managed, config=job.config
    )
    held = [n for p in planned if p.container for n in p.nodes if n.name in clock_names]
    for node in held:
        scen.overrides.setdefault(node.name, {})['autostart'] = False
    if options.respawn:
        # A restarted node takes as long to start as any node: the plant must not give up on
        # its commands, nor its peers on its messages, before it can be back.
        for node in scen.nodes:
            name = 'lockstep_timeout' if node.name in clock_names else None
            if node.kind.per_axis:
                name = 'input_timeout'
            if name is not None:
                scen.overrides.setdefault(node.name, {}).setdefault(name, options.startup_timeout)
    first = [p for p in planned if p.container or not clock_names & set(p.node_names)]
    return Launch(
        first=first,
        last=[p for p in planned if p not in first],
        held=held,
        restartable=[p.name for p in planned if not clock_names & set(p.node_names)],
        given=given,
        graph=job.graph_plan(),
    )


def start(session: Session, job: Job[Any], launch: Launch, options: RunOptions) -> None:
    """Every node, the clock node last; held and external clock nodes activated."""
    monitor, graph = session.monitor, session.graph
    graph.launch(launch.first)
    upstream = launch.graph.upstream
    deadline = time.monotonic() + options.startup_timeout
    while any(monitor.count_publishers(t) < 1 for t in upstream):
        if time.monotonic() > deadline:
            silent = [t for t in upstream if monitor.count_publishers(t) < 1]
            raise RunError(f'no publisher appeared on {", ".join(silent)}')
        session.spin('before the job started')
    graph.launch(launch.last)
    for node in job.clock_nodes:
        # started elsewhere, perhaps waiting to be activated; or held in a container
        if node.name in options.external or node in launch.held:
            activate(
                monitor,
                session.executor,
                node.name,
                session.progress,
                started=lambda: job.progress(monitor) > -math.inf,
                wait=options.startup_timeout,
            )
    session.progress.note(
        f'started {len(graph.procs)} processes (ROS_DOMAIN_ID={session.domain_id}); '
        'waiting for discovery'
    )
    session.listen()
