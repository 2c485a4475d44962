"""How a job runs across processes: what run_scenario's options set. ROS-free."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


class RunError(RuntimeError):
    """The run could not complete; str() says why."""


class RunFailed(RunError):
    """The run could not go on for a reason the runner found itself (mill_analysis.events:
    a stall); `kind` says which."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


class StartRefused(RunError):
    """The runner refused to start the job (an axis the drive holds stopped): nothing moved.
    `event` is the refusal (mill_analysis.events.REFUSED); str() the one line said."""

    def __init__(self, event: Any) -> None:
        super().__init__(event.detail)
        self.event = event


@dataclass(frozen=True)
class RunOptions:
    """The options of one run of a job (mill_bringup.runner.run.run).

    respawn: a node other than the clock node that dies is started again (at most 3 times)
    and rejoins the job, instead of ending the run.
    external: nodes of the scenario that run elsewhere (a hardware driver, a plant on
    another host): neither launched nor supervised here; an external clock node with the
    lifecycle services is activated where it would have been launched.
    layout: which nodes share a process (mill_bringup.layout; None: the scenario's). A
    clock node that is a lifecycle node (the drive) can share one: it then waits for the
    runner to activate it where it would have been launched. Another clock node keeps a
    process of its own, started last, so that it cannot start before the monitor hears the
    nodes upstream. Respawn starts a process again whose nodes are none of the clocks.
    runner_priority: SCHED_FIFO priority of the runner's own threads (its monitor, which
    takes every message of the record, and the middleware's), 0: the normal scheduler.
    rearm: an axis an external drive holds stopped (latched by an earlier job) is released
    through the drive's ~/release before the job starts, instead of refusing the start.
    view: machine_view runs beside the graph (mill_bringup.graph.Graph.launch_beside).
    stay: once the job is complete the graph stays up until Ctrl-C or SIGTERM, which end the
    run as a complete one (runner.follow.stay).
    """

    skip: float = 1.0  # the summary's metrics over t >= skip [s]
    stall_timeout: float = 30.0  # no new sample for this long ends the run [s]
    startup_timeout: float = 120.0  # until the first sample, or a restarted node is back [s]
    quiet: bool = False  # no progress display
    domain_id: str | None = None  # ROS_DOMAIN_ID (None: the caller's, else a private one)
    compare_offline: bool = False  # also simulate the job and compare the records
    record_bag: Path | None = None  # write every topic to a rosbag2 bag there
    respawn: bool = False
    external: frozenset[str] = frozenset()
    layout: str | None = None
    rearm: bool = False
    runner_priority: int = 0
    view: bool = False
    stay: bool = False
