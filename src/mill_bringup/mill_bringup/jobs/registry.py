"""Kinds of job a scenario can run, told apart by the node that clocks it (see jobs.base)."""

from __future__ import annotations

from mill_bringup.catalogue import of_role
from mill_bringup.job_config import build
from mill_bringup.jobs.axis import AxisJob
from mill_bringup.jobs.base import Job
from mill_bringup.jobs.force import ForceJob
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.scenario import Scenario, ScenarioError

JOB_KINDS: tuple[type[Job], ...] = (AxisJob, RealtimeAxisJob, ForceJob)


def job_for(scen: Scenario) -> Job:
    """The scenario's job, checked; ScenarioError names what does not fit.

    Its configuration (mill_bringup.job_config) is built once, here, and the job reads it.
    """
    config = build(scen)
    kinds = [kind for kind in JOB_KINDS if kind.runs(config)]
    if len(kinds) != 1:
        clocks = ', '.join(
            sorted({f'{k.package} {k.executable}' for j in JOB_KINDS for k in of_role(j.CLOCK)})
        )
        raise ScenarioError(
            f'scenario {scen.name} must launch exactly one clock node ({clocks}); '
            f'it launches {len(kinds) or "none"}'
        )
    return kinds[0](scen, config)
