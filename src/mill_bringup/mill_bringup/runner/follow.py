"""Following a started job to its end: progress, stalls, and the time and CPU it took.

The job is followed with a progress bar until it is complete (jobs.base.Job.complete). The
run ends with RunError when no step comes within the start-up timeout, or no new sample
for --stall-timeout (for a process --respawn just started again, at least as long as a
start-up may take). A node that exits ends it too (Session.spin). With --stay (timing
realtime) the graph then stays up, the job's checks still made (a drive gone silent, a node
that exits), until Ctrl-C or SIGTERM ends the run as that of a complete job: between jobs the
trajectory takes the manual commands (jog, home, MDI) and the axes follow them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from mill_analysis.events import STALL

from mill_bringup.jobs.base import Job
from mill_bringup.runner.options import RunError, RunFailed, RunOptions
from mill_bringup.runner.session import Session


@dataclass(frozen=True)
class WallTime:
    """How long the job took on the wall clock and what each process spent on it."""

    wall: float  # from the job's first step (or its own start) to its end [s]
    cpu_ms_per_step: dict[str, float]  # per process, the runner included


def stopped(began: float) -> WallTime:
    """The timing of a run that could not go on: its wall time since it began, no CPU."""
    return WallTime(max(time.monotonic() - began, 1e-9), {})


def follow(session: Session, job: Job[Any], options: RunOptions) -> WallTime:
    """Spin until the job is complete; its wall time and CPU per step."""
    graph = session.graph
    t_start = time.monotonic()
    t_first: float | None = None
    cpu_first: dict[str, float] = {}
    reached, last_change = -float('inf'), t_start
    while not job.complete(session.monitor):
        session.spin('before the job ended')
        job.check(session.monitor)
        now = time.monotonic()
        t = job.progress(session.monitor)
        if t > reached:
            reached, last_change = t, now
            if t_first is None:
                t_first, cpu_first = now, graph.cpu_by_process()
        if t_first is None:
            if now > session.startup_deadline:
                raise RunError(
                    f'no step within {options.startup_timeout:g} s of the start'
                    f'{_silent_external(session, job, options)}'
                )
            continue
        limit = _stall_limit(session, options, now)
        if now - last_change > limit:
            raise RunFailed(
                STALL, f'the run stalled: no new sample for {limit:g} s{_waiting(session)}'
            )
        # Over the first half second the factor means nothing (one step in a microsecond).
        elapsed = now - t_first
        rtf = f'real-time factor {reached / elapsed:.2f}' if elapsed >= 0.5 else ''
        session.progress.update(max(reached, 0.0), rtf)
    t_first = t_first if t_first is not None else t_start
    wall = max(time.monotonic() - t_first, 1e-9)
    started = job.started_ns()
    if started is not None:  # the job's own start (progress reports come once a second)
        wall = max((time.time_ns() - started) * 1e-9, 1e-9)
    steps = max(job.samples - 1, 1)
    cpu = {
        name: 1e3 * (used - cpu_first.get(name, 0.0)) / steps
        for name, used in graph.cpu_by_process().items()
    }
    if options.stay:
        stay(session, job)
    return WallTime(wall, cpu)


def stay(session: Session, job: Job[Any]) -> None:
    """--stay: the job is complete; the graph stays up until Ctrl-C or SIGTERM."""
    session.progress.note(
        'the job is done; the graph stays up for manual commands (--stay) until Ctrl-C'
    )
    try:
        while True:
            session.spin('after the job (--stay)')
            job.check(session.monitor)
    except KeyboardInterrupt:
        session.take_stop()


def _silent_external(session: Session, job: Job[Any], options: RunOptions) -> str:
    """What an external node (a driver started elsewhere) never published, if anything."""
    silent = sorted(
        topic
        for topic, owner in job.owners().items()
        if owner in options.external and session.monitor.count_publishers(topic) < 1
    )
    if not silent:
        return ''
    owners = sorted({job.owners()[t] for t in silent})
    return (
        f': nothing from {", ".join(owners)} (--external: it runs elsewhere) on '
        f'{", ".join(silent)}; is it running, in ROS_DOMAIN_ID={session.domain_id}?'
    )


def _waiting(session: Session) -> str:
    """What a recorded lockstep run's plant may be waiting for: the topics the bag lacks."""
    steps = session.monitor.steps
    if steps is None:
        return ''
    whole = f't = {steps.through / 1e9:.3f} s' if steps.through >= 0 else 'no step yet'
    return f' (the bag holds every topic up to {whole}; it waits for {", ".join(steps.behind())})'


def _stall_limit(session: Session, options: RunOptions, now: float) -> float:
    """How long without a new sample ends the run [s]: a restarted process has as long to
    come back as any start-up takes."""
    restart = session.graph.last_restart
    if restart is not None and now - restart < options.startup_timeout:
        return max(options.stall_timeout, options.startup_timeout)
    return options.stall_timeout
