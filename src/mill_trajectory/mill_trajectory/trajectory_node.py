"""Trajectory node: the reference of all axes, ahead of the controllers.

Publishes /mill/reference (trajectory_msgs/JointTrajectory: point i holds positions,
velocities and accelerations of x, y, z at stamp + time_from_start; a path that
programs the spindle, G-code, adds the joint `spindle`, its position the speed [rev/min]),
the job's status on /diagnostics ("running" with progress, then "done" with its end_time)
and the job's path, once loaded, on mill/planned_path (mill_trajectory.planned_path). Which
points go out, and when, is decided by the ROS-free schedules of mill_trajectory.schedule, the ones
the offline simulator uses too; this node takes what paces it, checks it and publishes:

- lockstep, /clock: each tick is answered with `preview_time` of points ahead. With
  feed_override.enabled the path speed follows /mill/feed_override (position[0], 1 = the
  programmed feed), clamped to [feed_override.min, feed_override.max]; a non-finite value
  holds the last one; both are reported on /diagnostics as a WARN.
- lockstep, feed_override.lockstep: the overrides of a force controller pace the job; an
  override stamped t_k gets the reference of sample k (feed_override.period 0) or of the
  samples up to the next control instant (period T_c > 0), with the override's β-hold ramp.
  With a feed override the job ends where its path ends, `settle_time` later (or at
  `duration`).
- realtime: once every axis of `axes` reports its position, every axis has an observer and
  as many nodes listen to the reference, the axes are held where they stand until every axis
  has sent a command; then the job starts at t0 (system clock), first moving to the path's
  start at `approach.speed` (refused, naming the distance, beyond `approach.max_distance`),
  and every `publish_period` the points of the grid t0 + kT from one sample before now to
  `preview_time` ahead go out. The job status says when it started (`start_stamp_ns`).

Realtime, once the job has ended and its path has come to rest: jog an axis (~/jog, by
increment or continuously until ~/jog_stop), go home (~/home), set home (~/set_home), run one
G-code line (~/mdi); what moves and why a command is refused is mill_trajectory.manual's,
and the node publishes its moves from the next sample on.

In lockstep the input that paces the node is watched (mill_common.input_guard): a tick off
the grid or in the past, an override for another sample, are dropped and counted; silence is
reported and after input_timeout ends the node (exit code 3).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import Rejected, StampCheck
from mill_common.codec import decode_joint_state, encode_joint_trajectory
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    from_stamp,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.signals import AXES, SPINDLE
from mill_common.timebase import period_ns
from mill_interfaces.srv import Jog, Mdi
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_trajectory.config import (
    FeedOverrideParams,
    Schedule,
    build_schedule,
    manual_machine,
    parameter_specs,
)
from mill_trajectory.feed_override import FeedOverride
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.hold import PAUSE, EventClock, Holds
from mill_trajectory.manual import Manual
from mill_trajectory.operator import BY_HAND, Answer, ByHand, Job, feed
from mill_trajectory.planned_path import PlannedPath, job_path
from mill_trajectory.schedule import (
    ClockedReference,
    OverrideReference,
    Points,
    WallClockReference,
)
from mill_trajectory.wall_clock_start import WallClockStart


def _now() -> int:
    """The system clock [ns], what a realtime job's time is counted on."""
    return time.time_ns()


class TrajectoryNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('trajectory', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._schedule: Schedule | None = None
        self._override: FeedOverride  # set by _configure
        self._planned: PlannedPath | None = None  # the path on mill/planned_path, once made
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        self._ref_pub = data_publisher(self, JointTrajectory, topics.REFERENCE, DATA_QOS)
        self._planned = PlannedPath(self)
        self._planned.publish(job_path(self._schedule), self.progress.end_time)
        self._answer: tuple[int, bytes] | None = None  # lockstep overrides: the last answer
        self._job_time = 0.0  # the job time last reported
        self._held_report_ns = 0  # lockstep: the next tick to report a pause or hold at
        self._ticks = StampCheck(None)  # lockstep: the /clock ticks (or overrides) answered
        schedule = self._schedule
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=not isinstance(schedule, WallClockReference),
            stamp_ns=lambda: self._ticks.newest or 0,
        )
        if isinstance(schedule, WallClockReference):
            self._realtime = WallClockStart(self, schedule)
        elif isinstance(schedule, OverrideReference):
            self.guard.watch(topics.FEED_OVERRIDE)
            self._take_override(self._on_paced_override, DATA_QOS)
        else:
            self._ticks.period_ns = period_ns(v['sample_period'])
            self.guard.watch(topics.CLOCK)
            self.create_subscription(Clock, topics.CLOCK, self._on_clock, DATA_QOS)
            if v['feed_override.enabled']:
                self._take_override(self._on_user_override, 10)
        self.create_service(Trigger, '~/feed_hold', self._on_feed_hold)
        self.create_service(Trigger, '~/resume', self._on_resume)
        # Between jobs, timing realtime: moving the machine by hand (mill_trajectory.manual).
        manual = Manual(manual_machine(v), isinstance(schedule, WallClockReference))
        self._by_hand = ByHand(manual)
        self.create_service(Jog, '~/jog', self._on_jog)
        for what in BY_HAND:
            self.create_service(Trigger, f'~/{what}', partial(self._on_manual, what))
        self.create_service(Mdi, '~/mdi', self._on_mdi)
        self.get_logger().info(
            f'{v["trajectory"]} path, job ends at t = {self.progress.end_time:.3f} s'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        feed = FeedOverrideParams.from_node_values(values)  # min <= max, or ParameterError
        schedule = self._schedule
        if isinstance(schedule, WallClockReference) and schedule.hold_ns is not None:
            raise ValueError('the path cannot change while a realtime job runs')
        if schedule is not None and self._override_scales():
            # The path time has advanced under the overrides: only the range may change.
            self._override.minimum = feed.min
            self._override.maximum = feed.max
            return
        self._override = FeedOverride(feed.min, feed.max)
        self._schedule, self.progress = build_schedule(values, self._override)
        path = self._path()
        self._events = EventClock(path.events if isinstance(path, GcodeTrajectory) else ())
        self._publish_planned()

    def _publish_planned(self) -> None:
        """The job's path on mill/planned_path, once a parameter change has loaded it."""
        if self._planned is not None and self._schedule is not None:
            self._planned.later(job_path(self._schedule), self.progress.end_time)

    def _path(self) -> Any:
        s = self._schedule
        return s.scaled.path if isinstance(s, OverrideReference) else s.path if s else None

    @property
    def holds(self) -> Holds | None:
        """The job's pauses and feed hold (None: a path that cannot pause nor hold)."""
        s = self._schedule
        scaled = s.scaled if isinstance(s, ClockedReference | OverrideReference) else None
        return None if scaled is None else scaled.holds

    # -- the operator: the decisions are mill_trajectory.operator's ----------------------
    def _job(self) -> Job:
        done = self.progress.done_at is not None
        return Job(self._schedule, self._job_time, self.progress.end_time, done)

    def _on_feed_hold(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        return self._respond(feed('feed_hold', self.holds, self._job()), response)

    def _on_resume(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        return self._respond(feed('resume', self.holds, self._job()), response)

    # By hand, between jobs (realtime).
    def _on_jog(self, request: Any, response: Any) -> Any:
        jog = self._by_hand.jog
        answer = jog(self._job(), str(request.axis), request.distance, request.velocity, _now())
        return self._respond(answer, response)

    def _on_mdi(self, request: Any, response: Any) -> Any:
        return self._respond(self._by_hand.mdi(self._job(), str(request.line), _now()), response)

    def _on_manual(self, what: str, request: Any, response: Any) -> Any:
        return self._respond(self._by_hand.order(what, self._job(), _now()), response)

    def _respond(self, answer: Answer, response: Any) -> Any:
        """The answer in the response, the log and the job's status on /diagnostics."""
        response.success, response.message = answer.accepted, answer.message
        if answer.accepted:  # rclpy wants one severity per call site
            self.get_logger().info(f'{answer.what}: {answer.message}')
        else:
            self.get_logger().warning(f'{answer.what} refused: {answer.message}')
        self.report(
            answer.t,
            answer.state,
            answer.message,
            level=DiagnosticStatus.OK if answer.accepted else DiagnosticStatus.WARN,
            event=(answer.what, answer.message, ''),
        )
        return response

    def _tell(self, t: float) -> None:
        """The program's messages and the pauses reached by path time t, logged and on
        /diagnostics."""
        for e in self._events.due(t):
            if e.kind == PAUSE:
                continue  # the holds say it, with how to go on
            self.get_logger().info(str(e))
            said = (e.kind, e.text, e.where, e.channel)
            self.report(t, 'running', str(e), level=DiagnosticStatus.OK, event=said)
        holds = self.holds
        for n in holds.drain() if holds is not None else ():
            level = DiagnosticStatus.OK
            if n.kind == 'paused':
                self.get_logger().warning(n.text)
                level = DiagnosticStatus.WARN
            else:
                self.get_logger().info(n.text)
            said = (n.kind, n.event.text, n.event.where, '')
            self.report(t, 'running', n.text, level=level, event=said)

    def _override_scales(self) -> bool:
        s = self._schedule
        return isinstance(s, OverrideReference) or (
            isinstance(s, ClockedReference) and s.scaled is not None
        )

    def _take_override(self, callback: Callable[[Any], None], qos: Any) -> None:
        malformed = partial(self.guard.drop, topics.FEED_OVERRIDE)
        take_serialized(
            self, JointState, topics.FEED_OVERRIDE, decode_joint_state, callback, qos, malformed
        )

    # -- lockstep ------------------------------------------------------------------------
    def _on_clock(self, msg: Clock) -> None:
        ns = from_stamp(msg.clock)
        problem = self._ticks.check(ns)
        if problem is not None:
            self.guard.drop(topics.CLOCK, problem)
            return
        self.guard.heard(topics.CLOCK)
        self._ticks.accept(ns)
        schedule = self._schedule
        assert isinstance(schedule, ClockedReference)
        points = schedule.answer(ns)
        if points is not None:
            self.publish(points)
        t = schedule.job_time(ns)
        self._job_time = t
        self._tell(t)
        self.job_status(t)
        holds = self.holds
        if holds is not None and holds.state != 'running' and ns >= self._held_report_ns:
            # The path time stands still while paused or held: say so once a second of clock.
            self._held_report_ns = ns + 1_000_000_000
            self.report(t, 'running', f'job {holds.state}')

    def _on_user_override(self, msg: Any) -> None:
        offered = msg.position[0] if len(msg.position) else math.nan
        accepted = self._override.accept(float(offered))
        if accepted.problem:
            self.get_logger().warning(accepted.problem)
            self.report(self.get_clock().now().nanoseconds * 1e-9, 'running', accepted.problem)

    def _on_paced_override(self, msg: Any) -> None:
        ns = from_stamp(msg.header.stamp)
        schedule = self._schedule
        assert isinstance(schedule, OverrideReference)
        if self._answer is not None and ns == self._answer[0]:
            self.guard.heard(topics.FEED_OVERRIDE)
            self._ref_pub.publish(self._answer[1])  # a repeat: the same answer again
            return
        problem = schedule.problem(ns, None if self._answer is None else self._answer[0])
        if problem is not None:
            self.guard.drop(topics.FEED_OVERRIDE, Rejected(problem), msg.header.frame_id)
            return
        self.guard.heard(topics.FEED_OVERRIDE)
        offered = msg.position[0] if len(msg.position) else math.nan
        slope = msg.velocity[0] if len(msg.velocity) else 0.0
        points = schedule.answer(ns, float(offered), float(slope))
        t = schedule.job_time
        if points.problem:
            self.get_logger().warning(points.problem)
            self.report(t, 'running', points.problem)
        out = self._message(points)
        self._ref_pub.publish(out)
        self._answer = (ns, out)
        self._job_time = t
        self._tell(t)
        self.job_status(t)

    # -- what goes out -------------------------------------------------------------------
    def publish(self, points: Points) -> None:
        self._ref_pub.publish(self._message(points))

    def readers(self) -> int:
        """Subscribers of the reference."""
        return self._ref_pub.get_subscription_count()

    def _message(self, points: Points) -> bytes:
        """The JointTrajectory of these points, serialized (mill_common.codec)."""
        p = points.period_ns
        samples = points.samples
        if samples and samples[0].spindle is not None:
            # A path that programs the spindle: its speed is the joint `spindle`'s position.
            rows = [
                (
                    (*s.position, s.spindle or 0.0),
                    (*s.velocity, 0.0),
                    (*s.acceleration, 0.0),
                    (),
                    i * p,
                )
                for i, s in enumerate(samples)
            ]
            return encode_joint_trajectory(points.stamp_ns, self._name, (*AXES, SPINDLE), rows)
        plain = [(s.position, s.velocity, s.acceleration, (), i * p) for i, s in enumerate(samples)]
        return encode_joint_trajectory(points.stamp_ns, self._name, AXES, plain)

    def job_status(self, t: float) -> None:
        state = self.progress.update(t)
        if state is not None:
            self.report(t, state, end_time=self.progress.done_at)

    def report(
        self,
        t: float,
        state: str,
        problem: str | None = None,
        level: bytes | None = None,
        end_time: float | None = None,
        event: tuple[str, ...] | None = None,
    ) -> None:
        values: dict[str, object] = {
            'state': state,
            'time': t,
            'end_time': self.progress.end_time if end_time is None else end_time,
            'feed_override': self._override.value,
        }
        holds = self.holds
        if holds is not None:
            values['hold'] = holds.state  # running, paused or held
        if event is not None:  # what the program or the operator did (mill_analysis.events)
            keys = ('event', 'event_text', 'event_where', 'event_channel')
            values.update(zip(keys, event, strict=False))
            values['event_time_s'] = t
        schedule = self._schedule
        if isinstance(schedule, WallClockReference) and schedule.t0 is not None:
            values['start_stamp_ns'] = schedule.t0
            if schedule.approach is not None:  # the move to the path's start, before it
                values['approach_s'] = schedule.approach.duration
        if level is None:
            level = DiagnosticStatus.WARN if problem else DiagnosticStatus.OK
        message = problem or f'job {state}'
        self.guard.diagnostics.report(
            self.get_clock().now().nanoseconds, level, topics.JOB_STATUS, message, values, log=False
        )


def main(argv: list[str] | None = None) -> int:
    return run_node(
        TrajectoryNode,
        'trajectory_node',
        'Publishes the reference of all axes on /mill/reference for every /clock tick.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
