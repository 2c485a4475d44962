"""Realtime: the start of a job on the wall clock, for the trajectory node.

Once every axis of `axes` reports its position, every axis has an observer and as many
nodes listen to the reference, the axes are held where they stand (the reference is their
position, on the grid of the newest state's stamp) until a command has come from every axis:
only then has each controller its states, estimates and reference. The job then starts at
t0 on the system clock, first moving from where the axes stand to the path's start
(mill_trajectory.approach), or is refused, naming the distance; the refusal is said again
every second on /diagnostics. Which points go out is mill_trajectory.schedule's
WallClockReference; this is the part that listens to the graph.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from typing import Any, Protocol, cast

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import Rejected, joint_values
from mill_common.codec import decode_joint_state
from mill_common.ros import DataInput, data_unsubscribe, from_stamp, take_serialized
from mill_common.signals import AXES
from mill_common.timebase import seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_trajectory.approach import ApproachError
from mill_trajectory.schedule import JobProgress, Points, WallClockReference


class Publisher(Protocol):
    """What the start uses of the trajectory node."""

    params: Any  # NodeParameters: .values
    progress: JobProgress

    def publish(self, points: Points) -> None: ...
    def readers(self) -> int: ...
    def job_status(self, t: float) -> None: ...
    def report(
        self,
        t: float,
        state: str,
        problem: str | None = None,
        level: bytes | None = None,
        end_time: float | None = None,
    ) -> None: ...
    def count_publishers(self, topic: str) -> int: ...
    def get_logger(self) -> Any: ...
    def create_timer(self, *args: Any, **kwargs: Any) -> Any: ...


class WallClockStart:
    """Realtime: wait for the graph, hold the axes, start the job, publish on the wall clock."""

    def __init__(self, node: Publisher, schedule: WallClockReference) -> None:
        self.node, self.schedule = node, schedule
        self.ros = cast(Node, node)  # the trajectory node itself, for its subscriptions
        v = node.params.values
        self.axes = list(v['axes'])
        self.positions: dict[str, float] = {}  # the axes' latest positions
        self.newest_state_ns = 0
        self.answered: set[str] = set()  # axes whose controller has commanded
        self.refused = ''
        self.next_report = 0.0
        self.commands: dict[str, DataInput] = {}  # during the hold
        self.states = self._take_each_axis(topics.state, self._on_state, self._state_dropped)
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        node.create_timer(v['publish_period'], self._publish, clock=wall)
        node.get_logger().info(
            f'realtime: the job starts when {", ".join(self.axes)} report their positions'
        )

    def _take_each_axis(
        self,
        topic: Callable[[str], str],
        on_msg: Callable[[str, Any], None],
        on_malformed: Callable[[str, Rejected], None],
    ) -> dict[str, DataInput]:
        """A depth-1 subscription (the newest message only) to topic(axis) of each axis."""
        return {
            axis: take_serialized(
                self.ros,
                JointState,
                topic(axis),
                decode_joint_state,
                partial(on_msg, axis),
                1,
                partial(on_malformed, axis),
            )
            for axis in self.axes
        }

    def _state_dropped(self, axis: str, rejected: Rejected) -> None:
        self.node.get_logger().warning(
            f'dropped a state on {topics.state(axis)}: {rejected.reason}',
            throttle_duration_sec=1.0,
        )

    def _on_state(self, axis: str, msg: Any) -> None:
        value = joint_values(msg.name, {'position': msg.position}, axis, ('position',))
        if isinstance(value, Rejected):
            self._state_dropped(axis, value)
            return
        self.positions[axis] = value[0]
        self.newest_state_ns = max(self.newest_state_ns, from_stamp(msg.header.stamp))

    def _on_command(self, axis: str, msg: Any) -> None:
        self.answered.add(axis)  # its controller has states, an estimate and the reference

    def _publish(self) -> None:
        node, schedule = self.node, self.schedule
        now = time.time_ns()
        if schedule.t0 is None and not self._hold_or_start(now):
            return
        assert schedule.t0 is not None
        node.publish(schedule.running(now))
        node.job_status(seconds(now - schedule.t0))

    def _graph_ready(self) -> bool:
        node = self.node
        if set(self.positions) != set(self.axes):
            return False
        readers = max(len(self.axes), node.params.values['min_subscribers'])
        if node.readers() < readers:
            return False  # the controllers (one per axis) or a recorder are not listening yet
        # An observer that is not up yet: its controller could not act.
        return all(node.count_publishers(topics.estimate(a)) >= 1 for a in self.axes)

    def _hold_or_start(self, now: int) -> bool:
        """Before the job: wait for the graph, hold the axes, then start; True once started."""
        node, schedule, v = self.node, self.schedule, self.node.params.values
        if self.refused:
            if time.monotonic() >= self.next_report:  # said again: a listener may be late
                self.next_report = time.monotonic() + 1.0
                node.report(0.0, 'refused', self.refused, level=DiagnosticStatus.ERROR)
            return False
        if schedule.hold_ns is None:
            if not self._graph_ready():
                return False
            here = [self.positions.get(a, 0.0) for a in AXES]
            axes = [AXES.index(a) for a in self.axes]
            try:
                approach = schedule.hold(
                    here,
                    axes,
                    self.newest_state_ns,
                    v['approach.speed'],
                    v['approach.max_distance'],
                )
            except ApproachError as exc:
                self.refused = str(exc)
                node.get_logger().error(f'job refused: {exc}')
                return self._hold_or_start(now)
            node.progress.end_time += approach.duration
            self.commands = self._take_each_axis(
                topics.joint_command, self._on_command, lambda axis, rejected: None
            )  # a malformed command is the drive's to report
            node.get_logger().info(
                'holding the axes where they stand until every controller commands'
            )
        if self.answered != set(self.axes):
            node.publish(schedule.holding(now))
            if time.monotonic() >= self.next_report:  # seconds may pass: say who is missing
                self.next_report = time.monotonic() + 1.0
                missing = [topics.joint_command(a) for a in self.axes if a not in self.answered]
                message = f'holding the axes: no command yet on {", ".join(missing)}'
                node.report(0.0, 'waiting', message, level=DiagnosticStatus.OK)
            return False
        schedule.start(now)
        for sub in (*self.states.values(), *self.commands.values()):
            data_unsubscribe(self.ros, sub)  # where the axes stood and who answers: all it needed
        self.states.clear()
        self.commands.clear()
        node.progress.restart_reports()  # from here on: job time
        moved = schedule.approach
        assert moved is not None
        node.get_logger().info(
            f'job started; approach of {1e3 * moved.distance:.3f} mm in '
            f'{moved.duration:.2f} s, ends at t = {node.progress.end_time:.3f} s'
        )
        return True
