"""Starting a run: which processes start first and which clock nodes wait (`plan`), then the
nodes, and, once the monitor hears them, the node that clocks the job (`start`).

Before any node starts, the start handshake with a drive that stays up across jobs (an
external clock node, `handshake`): the runner waits up to DRIVE_STATUS_WAIT for the drive's
status and reads the axes it holds stopped (`<axis>.stopped`, latched by an earlier job). On
such an axis the job does not start (StartRefused, one line naming the axis and the stop's
reason; run_scenario exits 2) unless the operator asked to re-arm (--rearm): the runner then
calls the drive's `~/release`, which logs it, and checks the drive's next status. No
controller of this job runs yet, so the first command a released axis takes comes from a
controller started at rest where the axis stands (the trajectory holds every axis there
until all of them command).

The clock node starts last, once the monitor has matched the others' publishers: it cannot
see whether their messages reach the monitor. A clock node in a container (a lifecycle
drive that shares a process) waits for `activate`, sent once the upstream is heard; so
does an external one (started elsewhere).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mill_analysis.events import REFUSED, Event

from mill_bringup.jobs.base import GraphPlan, Job
from mill_bringup.layout import Process, processes
from mill_bringup.lifecycle_client import activate, release
from mill_bringup.machine_model import VIEW_MODULE, VIEW_NODE, view_parameters
from mill_bringup.runner.options import RunError, RunOptions, StartRefused
from mill_bringup.scenario import NodeLaunch, check_layout
from mill_common import topics

if TYPE_CHECKING:
    from mill_bringup.runner.session import Session

# How long the start handshake waits for an external drive's status (it sends one a second;
# discovery may take as long again) and, after a release, for the next one [s].
DRIVE_STATUS_WAIT = 3.0


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
    """The start handshake, then every node, the clock node last; held and external clock
    nodes activated."""
    monitor, graph = session.monitor, session.graph
    # One budget from here to the first sample: the handshake, the graph's start, an
    # external drive's activation and the first step share it (runner.follow).
    deadline = session.startup_deadline = time.monotonic() + options.startup_timeout
    handshake(session, job, options)
    if options.view:  # first: a viewer of the whole job, its URDF latched before it starts
        graph.launch_beside(VIEW_NODE, VIEW_MODULE, view_parameters(job.config))
    graph.launch(launch.first)
    upstream = launch.graph.upstream
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
                wait=max(deadline - time.monotonic(), 0.0),
            )
    session.progress.note(
        f'started {len(graph.procs)} processes (ROS_DOMAIN_ID={session.domain_id}); '
        'waiting for discovery'
    )
    session.listen()


def handshake(session: Session, job: Job[Any], options: RunOptions) -> None:
    """Before any node starts: StartRefused on an axis an external drive holds stopped,
    unless options.rearm (the drive's ~/release, then its next status says it is free)."""
    drives = [n.name for n in job.clock_nodes if n.name in options.external]
    if not drives:
        return  # a drive the runner starts itself holds nothing from an earlier job
    drive = drives[0]
    latched = _wait_latched(session, job, time.monotonic() + DRIVE_STATUS_WAIT)
    if latched is None:
        session.progress.note(
            f'{drive}: no drive status within {DRIVE_STATUS_WAIT:g} s: whether it holds an '
            'axis stopped from an earlier job is not known before the start'
        )
        return
    if not latched:
        return
    if not options.rearm:
        raise StartRefused(refusal(drive, latched))
    monitor = session.monitor
    heard = len(monitor.statuses())
    answer = release(monitor, session.executor, drive, DRIVE_STATUS_WAIT)
    if answer is None:
        raise StartRefused(refusal(drive, latched, f'{drive} offers no ~/release'))
    session.progress.note(f'--rearm: {drive}/~release: {answer}')
    deadline = time.monotonic() + DRIVE_STATUS_WAIT
    while time.monotonic() < deadline and not _said_since(session, drive, heard):
        session.spin('while the drive released its axes')
    still = job.latched(monitor) if _said_since(session, drive, heard) else None
    if still:
        raise StartRefused(refusal(drive, still, 'still stopped after its ~/release'))
    session.rearmed = dict(latched)


def _wait_latched(session: Session, job: Job[Any], deadline: float) -> dict[str, str] | None:
    latched = job.latched(session.monitor)
    while latched is None and time.monotonic() < deadline:
        session.spin('before the job started')
        latched = job.latched(session.monitor)
    return latched


def _said_since(session: Session, drive: str, heard: int) -> bool:
    """Whether the drive's status (with its axes' stops) came after the first `heard`."""
    return any(
        s.node == drive and s.part in topics.DRIVE_STATUSES
        for s in session.monitor.statuses()[heard:]
    )


def refusal(drive: str, latched: Mapping[str, str], why: str = '') -> Event:
    """The one line of a start refused on axes the drive holds stopped (axis: reason)."""
    axes = sorted(latched)
    named = f'axis {axes[0]}' if len(axes) == 1 else f'axes {", ".join(axes)}'
    reasons = '; '.join(f'{a}: {latched[a]}' for a in axes) if len(axes) > 1 else latched[axes[0]]
    then = (
        f'{why}: release it on the drive'
        if why
        else 'once the machine is safe to move, run again with --rearm (the runner then '
        "calls the drive's ~/release before any node of the job starts)"
    )
    detail = f'{named} held stopped by the drive {drive} ({reasons}): job not started; {then}'
    return Event(axes[0] if len(axes) == 1 else '', REFUSED, math.nan, detail, drive)
