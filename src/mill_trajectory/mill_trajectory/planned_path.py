"""The job's programmed path on mill/planned_path (nav_msgs/Path, transient local).

The trajectory node publishes it once when its job is loaded (at start, and again when a
parameter change loads another path, once the change is over), so that RViz or Foxglove,
started before or after, draws the whole path beside the measured trace (mill/tool_trace,
mill_bringup.machine_view). The points are the path's own, sampled evenly in time
(mill_common.tool_path): the path the reference follows, before any feed override.
"""

from __future__ import annotations

from typing import Any

from mill_common.path_msgs import path_message
from mill_common.ros import LATCHED_QOS
from mill_common.tool_path import planned_points
from nav_msgs.msg import Path
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from mill_common import topics
from mill_trajectory.base import Trajectory
from mill_trajectory.schedule import OverrideReference


def job_path(schedule: object) -> Trajectory:
    """The path a schedule (mill_trajectory.config.Schedule) follows."""
    if isinstance(schedule, OverrideReference):
        return schedule.scaled.path
    path: Trajectory = schedule.path  # type: ignore[attr-defined]
    return path


class PlannedPath:
    """Publishes the job's path; a path loaded by a parameter change goes out once the change
    is over (`later`): `ros2 param load` sets one parameter at a time, each loading the job
    anew, and the path, thousands of poses, is published once for all of them."""

    DELAY = 0.2  # [s] of steady time after the last change

    def __init__(self, node: Node) -> None:
        self.node = node
        self.publisher = node.create_publisher(Path, topics.PLANNED_PATH, LATCHED_QOS)
        self._pending: tuple[Trajectory, float] | None = None
        self._timer: Any = None
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)

    def publish(self, path: Trajectory, end_time: float) -> int:
        """Publish the path from 0 to end_time [s]; returns how many points it holds."""
        points = planned_points(lambda t: path.sample(t).position, min(end_time, path.end_time))
        stamp = self.node.get_clock().now().nanoseconds
        self.publisher.publish(path_message(stamp, points, ns=self.node.get_namespace()))
        return len(points)

    def later(self, path: Trajectory, end_time: float) -> None:
        """Publish this path DELAY s after the last call (a newer path replaces it)."""
        self._pending = (path, end_time)
        if self._timer is not None:
            self._timer.reset()
            return
        self._timer = self.node.create_timer(self.DELAY, self._due, clock=self._steady)

    def _due(self) -> None:
        if self._timer is not None:
            self.node.destroy_timer(self._timer)
            self._timer = None
        if self._pending is not None:
            path, end_time = self._pending
            self._pending = None
            self.publish(path, end_time)
