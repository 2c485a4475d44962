"""The operator's services as the trajectory node asks them (mill_trajectory.operator): which
call a request makes, the job time and state an answer is told at, and that an order taken in
realtime replaces the path the node publishes. ROS-free: a realtime schedule started by hand."""

from __future__ import annotations

from mill_trajectory.gcode import Setup
from mill_trajectory.gcode_program import DEFAULT_TOLERANCE
from mill_trajectory.hold import Holds
from mill_trajectory.manual import Machine, Manual
from mill_trajectory.operator import BOTH_GIVEN, ByHand, Job, feed
from mill_trajectory.planner import Limits
from mill_trajectory.program import ProgramParams, ProgramTrajectory
from mill_trajectory.schedule import WallClockReference
from mill_trajectory.toolpath import Travel

T = 1e-3  # the sample period [s]
T0 = 5_000_000_000  # the job's start on the system clock [ns]
START = (0.01, 0.0, 0.0)  # where the job (a dwell of 0.5 s) stands


def _by_hand(realtime: bool = True) -> ByHand:
    limits = Limits((0.05,) * 3, (0.5,) * 3, (10.0,) * 3, DEFAULT_TOLERANCE)  # type: ignore[arg-type]
    travel = Travel((-0.1, -0.1, -0.05), (0.1, 0.1, 0.05))
    return ByHand(Manual(Machine(limits, travel, T, 0.005, Setup()), realtime))


def _realtime(started: bool = True) -> tuple[WallClockReference, ProgramTrajectory]:
    path = ProgramTrajectory(ProgramParams(start=list(START), segments=['dwell 0.5']))
    schedule = WallClockReference(path, 1_000_000, 10)
    if started:
        schedule.hold(START, (0, 1, 2), T0, 0.01, 0.01)  # it stands at the path's start
        assert schedule.start(T0) == T0
    return schedule, path


def _job(schedule: object, time: float = 0.0, done: bool = False) -> Job:
    return Job(schedule, time, 0.5, done)


def test_a_jog_after_the_job_is_told_at_the_jobs_time_and_replaces_the_published_path() -> None:
    by_hand = _by_hand()
    schedule, _ = _realtime()
    approach = schedule.path
    answer = by_hand.jog(_job(schedule, done=True), 'x', 1e-3, 0.0, T0 + 1_500_000_000)
    assert answer.accepted, answer.message
    assert (answer.what, answer.t, answer.state) == ('jog', 1.5, 'done')
    assert by_hand.manual.job_end == 0.5  # the job's end taken with its path
    assert schedule.path is by_hand.manual.path and schedule.path is not approach
    later = schedule.path.sample(60.0).position  # the jog has come to rest
    assert abs(later[0] - (START[0] + 1e-3)) < 1e-9 and later[1:] == (0.0, 0.0)


def test_a_jog_before_the_job_has_started_is_refused_at_time_zero() -> None:
    by_hand = _by_hand()
    schedule, path = _realtime(started=False)
    answer = by_hand.jog(_job(schedule), 'x', 1e-3, 0.0, T0)
    assert not answer.accepted
    assert answer.message.startswith('the job has not started yet')
    assert (answer.t, answer.state) == (0.0, 'running')
    assert by_hand.manual.path is None and schedule.path is path  # nothing taken over


def test_a_jog_with_both_a_distance_and_a_velocity_is_refused_and_moves_nothing() -> None:
    by_hand = _by_hand()
    schedule, _ = _realtime()
    before = schedule.path
    answer = by_hand.jog(_job(schedule), 'x', 1e-3, 0.01, T0 + 1_000_000_000)
    assert (answer.accepted, answer.message, answer.t) == (False, BOTH_GIVEN, 1.0)
    assert schedule.path is before and by_hand.manual.motion is None


def test_a_velocity_jogs_until_jog_stop_and_home_waits_for_rest() -> None:
    by_hand = _by_hand()
    schedule, _ = _realtime()
    job = _job(schedule, done=True)
    moving = by_hand.jog(job, 'y', 0.0, 0.01, T0 + 1_000_000_000)
    assert moving.accepted, moving.message
    assert by_hand.manual.motion is not None and schedule.path is by_hand.manual.path
    refused = by_hand.order('home', job, T0 + 1_100_000_000)  # still under way
    assert not refused.accepted and 'under way' in refused.message
    assert (refused.what, refused.t) == ('home', 1.1)
    stop = by_hand.order('jog_stop', job, T0 + 1_200_000_000)
    assert stop.accepted, stop.message
    y = schedule.path.sample(60.0).position[1]
    assert 0.0 < y < 0.01 * 0.2 + 1e-9  # stopped after 0.2 s at 10 mm/s at most


def test_lockstep_answers_at_the_job_time_last_reported_and_refuses_by_hand() -> None:
    by_hand = _by_hand(realtime=False)
    schedule = object()  # any schedule not on the wall clock
    answer = by_hand.mdi(_job(schedule, time=0.25), 'G0 X0.001', T0)
    assert not answer.accepted and 'timing realtime' in answer.message
    assert (answer.what, answer.t, answer.state) == ('mdi', 0.25, 'running')
    assert by_hand.manual.path is None


def test_feed_hold_and_resume_go_to_the_jobs_holds_or_are_refused_without_them() -> None:
    job = _job(object(), time=0.75, done=False)
    none = feed('feed_hold', None, job)
    assert (none.accepted, none.t, none.state) == (False, 0.75, 'running')
    assert none.message == 'feed_hold: this job has no pause and cannot hold its feed'
    assert feed('resume', None, job).message.startswith('resume: this job has no pause')
    holds = Holds((), T)
    held = feed('feed_hold', holds, job)
    assert held.accepted and holds.state == 'held' and held.what == 'feed_hold'
    assert not feed('feed_hold', holds, job).accepted  # held already
    resumed = feed('resume', holds, job)
    assert resumed.accepted and holds.state == 'running'
    assert resumed.message == 'feed hold released: back to the feed'
