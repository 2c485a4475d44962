"""Trajectory node: answers each /clock tick with the reference of all axes ahead of it.

Publishes /mill/reference (trajectory_msgs/JointTrajectory stamped with the
tick; point i holds positions, velocities and accelerations of x, y, z at
stamp + i T, time_from_start = i T, for `preview_time`), so the controllers
have the reference of every sample until the next tick. The job status goes
to /diagnostics ("running" with progress, then "done" at the job's end).

With feed_override.enabled the path speed follows /mill/feed_override (JointState,
position[0] = override, 1 = programmed feed), clamped to [feed_override.min,
feed_override.max]; a non-finite value is ignored and the last one held; both are reported
on /diagnostics as a WARN. Each sample's reference is then computed once, in order, with
the override in effect when its tick arrives (mill_trajectory.feed_override).

With timing realtime (a drive on the wall clock, no /clock) it waits until every axis of
`axes` has reported its position, every axis has an estimate publisher (its observer) and as
many nodes (the controllers) listen to the reference. It then holds the axes where they
stand (the reference is their position, on the grid of the newest state's stamp) until a
command has come from every axis: only then has each controller got states, estimates and
the reference (discovery between processes can take seconds after the graph is up). The
job starts at the grid point of that moment, t0 (the drive's system clock), first moving
from where the axes stand to the path's start at `approach.speed` (or refusing, with the
distance, beyond `approach.max_distance`), and publishes every `publish_period` the points
of the sample grid t0 + kT from one sample before now to `preview_time` ahead, stamped on
the system clock; the controllers interpolate them at their states' stamps. The job status
says when it started (`start_stamp_ns`).

With feed_override.lockstep the node answers overrides instead of ticks: an override stamped
t_k (from a force controller in lockstep with its plant) gets the reference of sample k, one
point stamped t_k, with the override's ramp velocity[0] (a β-hold) applied over the sample.
Each newer stamp gets the next sample, in order; a repeated override gets the same answer.
With feed_override.period T_c > 0 the sender acts once per control period on this node's
sample grid (a force controller on the 1 kHz axis job): the override stamped at control
instant j sets the reference from that sample up to the one before instant j + 1, sent as
one message (mill_trajectory.feed_override.PeriodicOverridePath).

With a feed override the job ends when the path ends, whatever the override: `settle_time`
after the first sample whose path time reaches the end of the path, or at `duration`. The
"done" status on /diagnostics then gives the time of that last sample as end_time.

In lockstep the input that paces the node (/clock, or the overrides) is watched
(mill_common.input_guard): a /clock tick off the sample grid or older than the newest is
dropped and counted; an override with another stamp than the next sample's is dropped and
counted; silence is reported on /diagnostics naming the topic and the node that published
it, and after input_timeout the node ends with that message (exit code 3).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.checks import Rejected, StampCheck, joint_values
from mill_common.codec import decode_joint_state, encode_joint_trajectory
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    DataInput,
    data_publisher,
    data_unsubscribe,
    diagnostic_array,
    from_stamp,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.signals import AXES
from mill_common.timebase import period_ns, sample_stamp_ns, seconds
from rclpy.clock import Clock as RosClock
from rclpy.clock import ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_trajectory.approach import Approach, ApproachError
from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.config import build_job, parameter_specs
from mill_trajectory.feed_override import (
    FeedOverride,
    JobEnd,
    PeriodicOverridePath,
    TimeScaledPath,
)

JOB_STATUS_NAME = 'mill_trajectory: job'
# A trajectory point as mill_common.codec writes it: positions, velocities, accelerations,
# effort and time_from_start [ns].
Point = tuple[Sequence[float], Sequence[float], Sequence[float], Sequence[float], int]
OVERRIDE_STAMP_TOLERANCE_NS = 1000


class TrajectoryNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('trajectory', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._path: Trajectory  # set by _configure
        self._scaled: TimeScaledPath | None = None
        self._periodic: PeriodicOverridePath | None = None
        self._override: FeedOverride  # set by _configure
        self._dt_ns = 0
        self._job_end = 0.0
        self._done_sent = False
        self._done_end = 0.0
        self._next_report = 0.0
        self._t0: int | None = None  # realtime: job start on the system clock [ns]
        self._newest_state_ns = 0
        self._hold_ns: int | None = None  # realtime: grid of the hold before the start [ns]
        self._approach: Approach  # realtime: set when the hold begins
        self._answered: set[str] = set()  # realtime: axes whose controller has commanded
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        self._ref_pub = data_publisher(self, JointTrajectory, topics.REFERENCE, DATA_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self._answer: tuple[int, bytes] | None = None
        self._positions: dict[str, float] = {}  # realtime: the axes' latest positions
        self._state_subs: dict[str, DataInput] = {}  # realtime: until the job has started
        self._command_subs: dict[str, DataInput] = {}  # realtime: during the hold
        self._refused = ''
        self._ticks = StampCheck(None)  # lockstep: the /clock ticks (or overrides) answered
        lockstep = self.params.values['timing'] == 'lockstep'
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=lockstep,
            stamp_ns=lambda: self._ticks.newest or 0,
        )
        if not lockstep:
            self._start_realtime()
        elif self._periodic is not None:
            self.guard.watch(topics.FEED_OVERRIDE)
            self._take_override(self._on_override_periodic, DATA_QOS)
        elif self.params.values['feed_override.lockstep']:
            self.guard.watch(topics.FEED_OVERRIDE)
            self._take_override(self._on_override_lockstep, DATA_QOS)
        else:
            self._ticks.period_ns = self._dt_ns
            self.guard.watch(topics.CLOCK)
            self.create_subscription(Clock, topics.CLOCK, self._on_clock, DATA_QOS)
        if self._scaled is not None and not self.params.values['feed_override.lockstep']:
            self._take_override(self._on_override, 10)
        self.get_logger().info(
            f'{self.params.values["trajectory"]} path, job ends at t = {self._job_end:.3f} s'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._t0 is not None:
            raise ValueError('the path cannot change while a realtime job runs')
        if values['feed_override.min'] > values['feed_override.max']:
            raise ValueError('feed_override.min must not exceed feed_override.max')
        if self._scaled is not None:
            # The path time has advanced under the overrides: only the range may change.
            self._override.minimum = values['feed_override.min']
            self._override.maximum = values['feed_override.max']
            return
        self._override = FeedOverride(values['feed_override.min'], values['feed_override.max'])
        job = build_job(values)
        self._path, self._job_end = job.trajectory, job.end_time
        self._done_sent = False
        self._scaled = None
        if values['feed_override.lockstep']:
            if not values['feed_override.enabled']:
                raise ValueError('feed_override.lockstep needs feed_override.enabled')
            if values['feed_override.period'] > 0:
                self._dt_ns = period_ns(values['sample_period'])
                self._periodic = PeriodicOverridePath(
                    self._path,
                    self._dt_ns,
                    values['feed_override.period'],
                    self._override,
                    self._end_rule(values),
                )
                self._scaled = self._periodic.scaled
                return
            # Samples are stamped by the override's sender: T need not be whole ns here.
            self._scaled = TimeScaledPath(self._path, values['sample_period'])
            return
        self._dt_ns = period_ns(values['sample_period'])
        self._points = max(1, math.ceil(values['preview_time'] * 1e9 / self._dt_ns))
        if values['timing'] == 'realtime':
            return
        if values['feed_override.enabled']:
            end = self._end_rule(values)
            self._scaled = TimeScaledPath(self._path, seconds(self._dt_ns), end)

    def _end_rule(self, values: dict[str, Any]) -> JobEnd:
        return JobEnd.of(
            self._path.end_time, values['settle_time'], values['duration'], self._dt_ns
        )

    # -- real time ---------------------------------------------------------------------------
    def _start_realtime(self) -> None:
        v = self.params.values
        if v['feed_override.enabled']:
            raise ValueError('feed_override is not available with timing realtime')
        self._state_subs = self._take_each_axis(topics.state, self._on_state, self._state_dropped)
        wall = RosClock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(v['publish_period'], self._publish_realtime, clock=wall)
        self.get_logger().info(
            f'realtime: the job starts when {", ".join(v["axes"])} report their positions'
        )

    def _take_each_axis(
        self,
        topic: Callable[[str], str],
        on_msg: Callable[[str, Any], None],
        on_malformed: Callable[[str, Rejected], None],
    ) -> dict[str, DataInput]:
        """Realtime: a depth-1 subscription (the newest message only) to topic(axis) of each
        axis of `axes`."""
        return {
            axis: take_serialized(
                self,
                JointState,
                topic(axis),
                decode_joint_state,
                partial(on_msg, axis),
                1,
                partial(on_malformed, axis),
            )
            for axis in self.params.values['axes']
        }

    def _take_override(self, callback: Callable[[Any], None], qos: QoSProfile | int) -> None:
        malformed = partial(self.guard.drop, topics.FEED_OVERRIDE)
        take_serialized(
            self, JointState, topics.FEED_OVERRIDE, decode_joint_state, callback, qos, malformed
        )

    def _state_dropped(self, axis: str, rejected: Rejected) -> None:
        self.get_logger().warning(
            f'dropped a state on {topics.state(axis)}: {rejected.reason}',
            throttle_duration_sec=1.0,
        )

    def _on_state(self, axis: str, msg: Any) -> None:
        value = joint_values(msg.name, {'position': msg.position}, axis, ('position',))
        if isinstance(value, Rejected):
            self._state_dropped(axis, value)
            return
        self._positions[axis] = value[0]
        self._newest_state_ns = max(self._newest_state_ns, from_stamp(msg.header.stamp))

    def _on_command(self, axis: str, msg: Any) -> None:
        self._answered.add(axis)  # its controller has states, an estimate and the reference

    def _publish_realtime(self) -> None:
        v = self.params.values
        if self._t0 is None and not self._hold_or_start(v):
            return
        assert self._t0 is not None
        dt_ns = self._dt_ns
        now = time.time_ns() - self._t0
        first = max(0, now // dt_ns - 1)
        count = self._points + math.ceil(v['publish_period'] * 1e9 / dt_ns) + 2
        points = []
        for i in range(count):
            sample = self._path.sample(seconds((first + i) * dt_ns))
            points.append(self._point(sample, i * dt_ns))
        self._ref_pub.publish(self._reference(self._t0 + first * dt_ns, points))
        self._job_status(seconds(now))

    def _hold_or_start(self, v: dict[str, Any]) -> bool:
        """Before the job: wait for the graph, hold the axes, then start; True once started."""
        if self._hold_ns is None:
            if self._refused or set(self._positions) != set(v['axes']):
                return False
            if self._ref_pub.get_subscription_count() < max(len(v['axes']), v['min_subscribers']):
                return False  # the controllers (one per axis) or a recorder are not listening yet
            if any(self.count_publishers(topics.estimate(a)) < 1 for a in v['axes']):
                return False  # an observer is not up yet: its controller could not act
            here = [self._positions.get(a, 0.0) for a in AXES]
            try:
                approach = Approach(
                    self._path,
                    here,
                    v['approach.speed'],
                    v['approach.max_distance'],
                    [AXES.index(a) for a in v['axes']],
                )
            except ApproachError as exc:
                self._refused = str(exc)
                self.get_logger().error(f'job refused: {exc}')
                self._report(0.0, 'refused', self._refused, level=DiagnosticStatus.ERROR)
                return False
            self._path = self._approach = approach
            self._job_end += approach.duration
            self._hold_ns = self._newest_state_ns
            self._command_subs = self._take_each_axis(
                topics.joint_command, self._on_command, lambda axis, rejected: None
            )  # a malformed command is the drive's to report
            self.get_logger().info(
                'holding the axes where they stand until every controller commands'
            )
        dt_ns = self._dt_ns
        k = (time.time_ns() - self._hold_ns) // dt_ns
        if self._answered != set(v['axes']):
            # Where the axes stand (the approach's first point), on the states' grid.
            here_sample = self._path.sample(0.0)
            first = max(0, k - 1)
            count = self._points + math.ceil(v['publish_period'] * 1e9 / dt_ns) + 2
            points = [self._point(here_sample, i * dt_ns) for i in range(count)]
            self._ref_pub.publish(self._reference(self._hold_ns + first * dt_ns, points))
            if time.monotonic() >= self._next_report:  # seconds may pass: say who is missing
                self._next_report = time.monotonic() + 1.0
                missing = [topics.joint_command(a) for a in v['axes'] if a not in self._answered]
                message = f'holding the axes: no command yet on {", ".join(missing)}'
                self._report(0.0, 'waiting', message, level=DiagnosticStatus.OK)
            return False
        # On the hold's grid: the job's first points replace the held ones stamp for stamp.
        self._t0 = self._hold_ns + max(k, 0) * dt_ns
        for sub in (*self._state_subs.values(), *self._command_subs.values()):
            data_unsubscribe(self, sub)  # where the axes stood and who answers: all it needed
        self._state_subs.clear()
        self._command_subs.clear()
        self._next_report = 0.0  # from here on: job time
        self.get_logger().info(
            f'job started; approach of {1e3 * self._approach.distance:.3f} mm in '
            f'{self._approach.duration:.2f} s, ends at t = {self._job_end:.3f} s'
        )
        return True

    def _on_override(self, msg: Any) -> None:
        offered = msg.position[0] if len(msg.position) else math.nan
        accepted = self._override.accept(float(offered))
        if accepted.problem:
            self.get_logger().warning(accepted.problem)
            self._report(self.get_clock().now().nanoseconds * 1e-9, 'running', accepted.problem)

    def _on_override_lockstep(self, msg: Any) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._answer is not None and ns == self._answer[0]:
            self.guard.heard(topics.FEED_OVERRIDE)
            self._ref_pub.publish(self._answer[1])  # a repeat: the same sample again
            return
        scaled = self._scaled
        assert scaled is not None, 'lockstep overrides always scale the path'
        # Each override asks for the next sample: t_k of k = the samples answered so far. The
        # sender's T may differ from ours in the last digits (the force job allows 1e-12 T):
        # 1 µs is far more than that makes over any job and far less than a period.
        want = sample_stamp_ns(scaled.sample_index, self.params.values['sample_period'])
        if abs(ns - want) > OVERRIDE_STAMP_TOLERANCE_NS:
            what = 'in the past' if ns < want else 'not the next sample'
            reason = f'stamp {ns / 1e9:.9f} s is {what} (t_k = {want / 1e9:.9f} s)'
            self.guard.drop(topics.FEED_OVERRIDE, Rejected(reason), msg.header.frame_id)
            return
        self.guard.heard(topics.FEED_OVERRIDE)
        offered = msg.position[0] if len(msg.position) else math.nan
        slope = msg.velocity[0] if len(msg.velocity) else 0.0
        accepted = self._override.accept(float(offered))
        problem = accepted.problem
        if not math.isfinite(slope):
            problem = f'non-finite override slope {slope} ignored'
            slope = 0.0
        if accepted.value != offered:
            slope = 0.0  # a clamped or held override does not ramp
        t = scaled.path_time
        if problem:
            self.get_logger().warning(problem)
            self._report(t, 'running', problem)
        out = self._reference(ns, [self._point(scaled.sample(accepted.value, slope), 0)])
        self._ref_pub.publish(out)
        self._answer = (ns, out)
        self._job_status(t)

    def _on_override_periodic(self, msg: Any) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._answer is not None and ns == self._answer[0]:
            self.guard.heard(topics.FEED_OVERRIDE)
            self._ref_pub.publish(self._answer[1])  # a repeat: the same samples again
            return
        periodic = self._periodic
        assert periodic is not None, 'periodic overrides come with feed_override.period'
        k, rem = divmod(ns, self._dt_ns)
        if rem or (self._answer is not None and ns < self._answer[0]):
            what = 'not a sample' if rem else 'in the past'
            reason = f'stamp {ns / 1e9:.9f} s is {what}'
            self.guard.drop(topics.FEED_OVERRIDE, Rejected(reason), msg.header.frame_id)
            return
        self.guard.heard(topics.FEED_OVERRIDE)
        offered = msg.position[0] if len(msg.position) else math.nan
        slope = msg.velocity[0] if len(msg.velocity) else 0.0
        answer = periodic.answer(k, float(offered), float(slope))
        if answer.problem:
            self.get_logger().warning(answer.problem)
            self._report(periodic.scaled.path_time, 'running', answer.problem)
        points = [self._point(sample, i * self._dt_ns) for i, sample in enumerate(answer.samples)]
        out = self._reference(answer.first * self._dt_ns, points)
        self._ref_pub.publish(out)
        self._answer = (ns, out)
        self._job_status(periodic.scaled.path_time)

    def _on_clock(self, msg: Clock) -> None:
        ns = from_stamp(msg.clock)
        problem = self._ticks.check(ns)
        if problem is not None:
            self.guard.drop(topics.CLOCK, problem)
            return
        self.guard.heard(topics.CLOCK)
        self._ticks.accept(ns)
        t = seconds(ns)
        if self._scaled is not None:
            self._publish_scaled(self._scaled, ns)
            t = self._scaled.path_time
        else:
            self._publish_chunk(ns)
        self._job_status(t)

    def _job_status(self, t: float) -> None:
        done, end = t >= self._job_end, self._job_end
        scaled = self._scaled
        if scaled is not None and self._dt_ns and self.params.values['feed_override.enabled']:
            # The job ends with its path, whatever the override: at a sample found on the way.
            last = scaled.last_sample
            done = last is not None and scaled.sample_index > last
            if last is not None and done:
                end = seconds(last * self._dt_ns)
        if done and not self._done_sent:
            self._done_end = end
        # Once done, the job stays done (a graph runs on until it is stopped).
        if (done and not self._done_sent) or t >= self._next_report:
            self._done_sent = self._done_sent or done
            self._next_report = t + 1.0
            if self._done_sent:
                self._report(t, 'done', end_time=self._done_end)
            else:
                self._report(t, 'running')

    def _publish_scaled(self, scaled: TimeScaledPath, ns: int) -> None:
        # Each sample once and in order: its path time depends on all earlier overrides.
        first = max(ns // self._dt_ns, scaled.sample_index)
        last = ns // self._dt_ns + self._points
        if first >= last:
            return
        points = []
        for k in range(first, last):
            sample = scaled.sample(self._override.value)
            points.append(self._point(sample, (k - first) * self._dt_ns))
        self._ref_pub.publish(self._reference(first * self._dt_ns, points))

    def _point(self, sample: TrajectorySample, offset_ns: int) -> Point:
        """One JointTrajectoryPoint: positions, velocities, accelerations of x, y, z."""
        return sample.position, sample.velocity, sample.acceleration, (), offset_ns

    def _reference(self, ns: int, points: list[Point]) -> bytes:
        """The JointTrajectory of these points stamped ns, serialized (mill_common.codec)."""
        return encode_joint_trajectory(ns, self._name, AXES, points)

    def _publish_chunk(self, ns: int) -> None:
        points = []
        for i in range(self._points):
            sample = self._path.sample(seconds(ns + i * self._dt_ns))
            points.append(self._point(sample, i * self._dt_ns))
        self._ref_pub.publish(self._reference(ns, points))

    def _report(
        self,
        t: float,
        state: str,
        problem: str | None = None,
        level: bytes | None = None,
        end_time: float | None = None,
    ) -> None:
        values: dict[str, object] = {
            'state': state,
            'time': t,
            'end_time': self._job_end if end_time is None else end_time,
            'feed_override': self._override.value,
        }
        if self._t0 is not None:
            values['start_stamp_ns'] = self._t0
        if level is None:
            level = DiagnosticStatus.WARN if problem else DiagnosticStatus.OK
        self._diag_pub.publish(
            diagnostic_array(
                self.get_clock().now().nanoseconds,
                level,
                JOB_STATUS_NAME,
                problem or f'job {state}',
                topics.machine_id(self.get_namespace()),
                values,
            )
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
