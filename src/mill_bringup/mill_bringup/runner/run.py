"""One run of a job across processes: plan, start, follow, collect (one module each)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mill_bringup.graph import GraphError
from mill_bringup.jobs.base import Job
from mill_bringup.runner.collect import collect, result
from mill_bringup.runner.follow import follow
from mill_bringup.runner.options import RunError, RunOptions
from mill_bringup.runner.result import RunResult
from mill_bringup.runner.session import Session
from mill_bringup.runner.start import plan, start


def run(job: Job[Any], run_dir: Path, options: RunOptions | None = None) -> RunResult:
    """Run the job across processes; the record holds samples 0 .. job.samples − 1."""
    options = options or RunOptions()
    launch = plan(job, options)
    try:
        with Session(job, run_dir, options, launch.restartable) as session:
            start(session, job, launch, options)
            timing = follow(session, job, options)
            collected = collect(session, job, options)
    except GraphError as exc:
        raise RunError(str(exc)) from None
    finally:
        launch.restore(job)
    return result(job, options, session.domain_id, timing, collected)
