"""One run of a job across processes: plan, start, follow, collect (one module each).

However the run ends once its graph was planned, it ends with a RunResult: the job complete,
or the run stopped by what the runner found (a drive gone silent, a node that died, a stall, a
graph that cannot make the job, a start refused on a latched axis, an interrupt: Ctrl-C or
SIGTERM), which is the result's failure (mill_analysis.events), with the record of what
arrived until then. The runner takes the run's `Ending` once, there: the
statuses the machine sent until then, and what ended it.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

from mill_analysis.events import INTERRUPTED, NODE_DIED, RUN_ERROR, Event

from mill_bringup.graph import GraphError
from mill_bringup.jobs.base import Ending, Job
from mill_bringup.runner.collect import collect, result
from mill_bringup.runner.follow import WallTime, follow, stopped
from mill_bringup.runner.options import RunError, RunFailed, RunOptions
from mill_bringup.runner.result import RunResult
from mill_bringup.runner.session import Session
from mill_bringup.runner.start import plan, start
from mill_bringup.scenario import ScenarioError


def run(job: Job[Any], run_dir: Path, options: RunOptions | None = None) -> RunResult:
    """Run the job across processes; the record holds samples 0 .. job.samples − 1 (those
    that arrived, if the run stopped: RunResult.error says why)."""
    options = options or RunOptions()
    launch = plan(job, options)
    try:
        with Session(job, run_dir, options, launch.restartable, launch.graph) as session:
            began = time.monotonic()
            failure = None
            timing: WallTime
            try:
                start(session, job, launch, options)
                timing = follow(session, job, options)
            except (RunError, ScenarioError, GraphError) as exc:
                failure = failure_of(exc, job, session)
                timing = stopped(began)
            except KeyboardInterrupt:
                failure = interrupted(job, session)
                timing = stopped(began)
            monitor = session.monitor
            ending = Ending(tuple(monitor.statuses()), failure, monitor)
            collected = collect(session, job, options, ending)
    except GraphError as exc:
        raise RunError(str(exc)) from None
    finally:
        launch.restore(job)
    return result(job, options, session.domain_id, timing, collected, ending)


def failure_of(exc: Exception, job: Job[Any], session: Session) -> Event:
    """What ended the run, as an event: the job's own (a drive gone silent), a node that
    died, a stall; else the error that stopped it."""
    event = getattr(exc, 'event', None)
    if isinstance(event, Event):
        return event
    if isinstance(exc, GraphError):
        kind = NODE_DIED
    elif isinstance(exc, RunFailed):
        kind = exc.kind
    else:
        kind = RUN_ERROR
    try:
        reached = job.progress(session.monitor)
    except ScenarioError:
        reached = -math.inf
    return Event('', kind, reached if reached > -math.inf else math.nan, str(exc))


def interrupted(job: Job[Any], session: Session) -> Event:
    """The run interrupted (Ctrl-C, SIGTERM), as its failure event: when, in the job."""
    try:
        reached = job.progress(session.monitor)
    except ScenarioError:
        reached = -math.inf
    at = reached if reached > -math.inf else math.nan
    return Event('', INTERRUPTED, at, 'interrupted (Ctrl-C or SIGTERM): the graph was stopped')
