"""How the commands of a realtime run answered the job's states (the runner's summary, the
report of a bag): realtime_record.command_timing."""

from __future__ import annotations

import pytest
from mill_bringup.cli import set_timing
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

T0 = 1_800_000_000_000_000_000  # the job's start on the system clock [ns]
DT = 10_000_000


@pytest.mark.parametrize(
    'name', ['slotting', 'chavez_conde', 'hatwesh', 'hatwesh_velocity', 'maharof']
)
def test_every_axis_scenario_can_start_in_realtime(name: str) -> None:
    """The trajectory starts a realtime job once its `axes` report their positions: in a
    one-axis scenario they must be the plant's one axis, or the job never starts."""
    scen = scenario.load(name)
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)


def test_a_trajectory_waiting_for_other_axes_than_the_plant_drives_is_refused() -> None:
    scen = scenario.load('chavez_conde')
    set_timing(scen, 'realtime')
    scen.add_override('trajectory.axes=["x", "y"]')
    with pytest.raises(scenario.ScenarioError, match=r'set trajectory\.axes'):
        job_for(scen)


def test_the_drives_late_ticks_come_with_its_own_tick_count() -> None:
    """Late ticks are counted from the drive's activation on (approach and hold included):
    their share is taken of the drive's ticks over the same span, not of the job's samples."""
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    assert job.overruns() == (0, 0)  # a driver that reports neither
    job.drive = {'overruns': '3', 'active_ticks': '600'}
    assert job.overruns() == (3, 600)


def test_the_drives_own_stalls_are_said_as_what_they_were() -> None:
    """A drive that reports its stalls (ticks that woke late on the monotonic clock): their
    number and the longest, with which process and when, as the drive said it."""
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    assert job.stalls() == (0, 0.0, '')  # a driver that does not report them
    line = 'drive plant (pid 4242) stalled 112 ms (monotonic) at 22:31:07.015 UTC'
    job.drive = {'stalls': '2', 'longest_stall_ms': '112.0', 'longest_stall': line}
    assert job.stalls() == (2, 112.0, line)
