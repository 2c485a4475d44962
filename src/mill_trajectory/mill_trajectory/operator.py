"""What the trajectory node's operator services decide, ROS-free: feed hold and resume of a
job (mill_trajectory.hold), and the moves by hand between jobs (mill_trajectory.manual).

The node (mill_trajectory.trajectory_node) turns a request into one call here and the
`Answer` into its response, its log line and its /diagnostics status: which job time the
answer is told at, the job's state then, and that an order taken in realtime replaces the
path the node publishes, are decided here.
"""

from __future__ import annotations

from dataclasses import dataclass

from mill_common.timebase import seconds

from mill_trajectory.hold import Holds
from mill_trajectory.manual import Manual, Order
from mill_trajectory.schedule import WallClockReference

BOTH_GIVEN = 'give a distance (by increment) or a velocity (continuous), not both'
BY_HAND = ('jog_stop', 'home', 'set_home')  # the manual services that take no argument


@dataclass(frozen=True)
class Answer:
    """A service's answer: taken or not, one line on it, and the job's time [s] and state
    ('running' or 'done') to report it at."""

    what: str  # the service: feed_hold, resume, jog, mdi, jog_stop, home, set_home
    accepted: bool
    message: str
    t: float
    state: str


@dataclass(frozen=True)
class Job:
    """What the node knows of its job when a service is called."""

    schedule: object  # the node's schedule (mill_trajectory.config.Schedule)
    time: float  # the job time last reported [s] (lockstep)
    end_time: float  # the job's end [s]
    done: bool  # the job has ended


def feed(what: str, holds: Holds | None, job: Job) -> Answer:
    """feed_hold or resume: the job's holds decide (refused if it has none)."""
    if holds is None:
        accepted, message = False, f'{what}: this job has no pause and cannot hold its feed'
    else:
        command = holds.feed_hold() if what == 'feed_hold' else holds.resume()
        accepted, message = command.accepted, command.message
    return Answer(what, accepted, message, job.time, 'running')


class ByHand:
    """The manual commands of one trajectory node, on its job's schedule."""

    def __init__(self, manual: Manual) -> None:
        self.manual = manual

    def jog(self, job: Job, axis: str, distance: float, velocity: float, now_ns: int) -> Answer:
        """By increment (distance), or continuously (velocity) until jog_stop: not both."""
        t = self._time(job, now_ns)
        if distance != 0.0 and velocity != 0.0:
            order = Order(False, BOTH_GIVEN)
        elif velocity != 0.0:
            order = self.manual.jog_continuous(axis, velocity, t)
        else:
            order = self.manual.jog(axis, distance, t)
        return self._answer('jog', order, t, job)

    def mdi(self, job: Job, line: str, now_ns: int) -> Answer:
        """One G-code line."""
        t = self._time(job, now_ns)
        return self._answer('mdi', self.manual.mdi(line, t), t, job)

    def order(self, what: str, job: Job, now_ns: int) -> Answer:
        """One of BY_HAND."""
        t = self._time(job, now_ns)
        manual = self.manual
        command = {'jog_stop': manual.jog_stop, 'home': manual.go_home, 'set_home': manual.set_home}
        return self._answer(what, command[what](t), t, job)

    def _time(self, job: Job, now_ns: int) -> float | None:
        """The job's time at now_ns (None: not started); the manual commands take over the
        job's path once it has started."""
        schedule = job.schedule
        if not isinstance(schedule, WallClockReference):
            return job.time
        if schedule.t0 is None:
            return None
        if self.manual.path is None:
            self.manual.job_started(schedule.path, job.end_time)
        return seconds(now_ns - schedule.t0)

    def _answer(self, what: str, order: Order, t: float | None, job: Job) -> Answer:
        """An order taken in realtime: its path published from the next sample on."""
        schedule = job.schedule
        if order.accepted and isinstance(schedule, WallClockReference):
            assert self.manual.path is not None
            schedule.path = self.manual.path
        state = 'done' if job.done else 'running'
        return Answer(what, order.accepted, order.message, t or 0.0, state)
