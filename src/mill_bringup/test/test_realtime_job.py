"""How the commands of a realtime run answered the job's states (the runner's summary, the
report of a bag): realtime_record.command_timing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_bringup.cli import set_timing
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.jobs.registry import job_for
from mill_bringup.metrics import SIGNALS, RunRecord
from mill_bringup.realtime_record import command_timing, longest_run
from mill_common.ros import joint_state_bytes

from mill_bringup import scenario
from mill_common import topics

T0 = 1_800_000_000_000_000_000  # the job's start on the system clock [ns]
DT = 10_000_000


def test_late_fraction_and_latency_count_the_jobs_states_only() -> None:
    n = 4
    rec = RunRecord(np.arange(n) * DT * 1e-9, {s: np.full((n, 3), math.nan) for s in SIGNALS})
    # Answered: a state before the job (hold), job states 0, 1 and 3, and one after the job
    # that the runner took 3 s late while it ended the run.
    stamps = [T0 - DT, T0, T0 + DT, T0 + 3 * DT, T0 + 9 * DT]
    lags = [1_000_000, 2_000_000, 4_000_000, 3_000_000, 3_000_000_000]
    raw = {topics.joint_command('x'): [joint_state_bytes(s, ('x',), effort=(0.0,)) for s in stamps]}
    arrivals = {topics.joint_command('x'): [s + lag for s, lag in zip(stamps, lags, strict=True)]}
    got = command_timing(rec, raw, arrivals, ['x'], T0)['x']
    assert got.unanswered == 0.25  # job state 2 got no command
    assert list(got.latency_ms) == [2.0, 4.0, 3.0]  # not the hold's, not the 3 s after the job
    figures = got.figures()
    assert figures['late_fraction'] == 0.25
    assert figures['longest_late_run'] == 1
    assert (figures['latency_median_ms'], figures['latency_max_ms']) == (3.0, 4.0)


def test_the_longest_run_counts_consecutive_misses_only() -> None:
    assert longest_run([]) == 0
    assert longest_run([False, True, False, True, True, True, False, True]) == 3
    assert longest_run([True] * 5) == 5


def test_a_command_whose_arrival_is_unknown_counts_as_answer_but_not_in_latency() -> None:
    rec = RunRecord(np.array([0.0]), {s: np.full((1, 3), math.nan) for s in SIGNALS})
    raw = {topics.joint_command('y'): [joint_state_bytes(T0, ('y',), effort=(0.0,))]}
    got = command_timing(rec, raw, {topics.joint_command('y'): [None]}, ['y'], T0)['y']
    assert got.unanswered == 0.0 and got.latency_ms.size == 0 and got.longest_unanswered == 0
    assert math.isnan(got.figures()['latency_median_ms'])


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
