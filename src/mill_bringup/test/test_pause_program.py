"""A program that pauses (M0) offline: it holds the programmed point for gcode.resume_after
and ends that much later; without resume_after nobody would resume it, and it is refused."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mill_bringup.cli import set_program, set_resume_after
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.scenario import ScenarioError
from mill_trajectory.config import build_job

from mill_bringup import scenario

# From the slot's start (x -75, y -105, z -5 mm): 1 mm in +y, pause, 1 mm more.
PART = """G21 G90 G17
G1 Y-104 F180
M0
G1 Y-103
M30
"""


def test_a_pause_holds_for_resume_after_and_the_job_ends_that_much_later(tmp_path: Path) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(PART)
    scen = scenario.load('slotting')
    set_program(scen, str(part))
    with pytest.raises(ScenarioError, match=r'part\.ngc:3:1: M0: program stop waits for'):
        simulate(job_for(scen))
    set_resume_after(scen, 0.3)
    path = build_job(scen.parameters('trajectory')).trajectory
    job = job_for(scen)
    assert job.unattended_pause() is None
    rec = simulate(job)
    # Planned samples, plus 300 at the pause (the path's end is found on its own time).
    planned = round(path.end_time * 1000)
    assert abs(len(rec.t) - (planned + 300)) <= 2
    ref = rec['reference']
    here = np.array(path.sample(path.pauses[0].time).position)
    still = np.flatnonzero(np.all(ref == here, axis=1))
    assert len(still) == 300 and np.all(np.diff(still) == 1)
    assert here == pytest.approx([-0.075, -0.104, -0.005], abs=1e-12)
    assert np.abs(rec['reference_velocity'][still]).max() == 0.0
    assert ref[-1] == pytest.approx([-0.075, -0.103, -0.005], abs=1e-12)
