"""The programmed path and the measured tool trace as point lists, for the viewers. ROS-free.

What RViz and Foxglove draw (nav_msgs/Path on mill/planned_path and mill/tool_trace) is
decided here, without ROS, so that it is tested as numbers; the nodes only turn the points
into messages:

- `planned_points`: the job's path sampled evenly in time from 0 to its end, at most
  `max_points` points (a path without an end: its first `PLANNED_HORIZON` s);
- `TraceDecimator`: the measured positions of the axes, which arrive one axis at a time
  (each its own `mill/<axis>/state`), kept as one x, y, z point, once every axis has
  reached its stamp, at most every `period_ns` of the states' own stamps (the job's time:
  simulated in lockstep, the drive's clock in realtime), the newest `length` points only;
  a stamp before the last point's (a new run on the same clock) starts the trace anew.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence

Point = tuple[float, float, float]

# What a path without an end shows of itself [s].
PLANNED_HORIZON = 600.0
# The planned path's points at most; the trace's rate [Hz] and its length in points.
PLANNED_POINTS = 5000
TRACE_RATE = 20.0
TRACE_LENGTH = 6000  # 5 min at 20 Hz


def planned_points(
    position: Callable[[float], Sequence[float]], end_time: float, max_points: int = PLANNED_POINTS
) -> list[Point]:
    """The path's x, y, z at `max_points` evenly spaced times from 0 to `end_time` [s]
    (both included; one point for a path that ends at 0); ValueError for max_points < 2."""
    if max_points < 2:
        raise ValueError(f'max_points must be at least 2, got {max_points}')
    end = end_time if math.isfinite(end_time) else PLANNED_HORIZON
    if end <= 0.0:
        x, y, z = position(0.0)
        return [(float(x), float(y), float(z))]
    out = []
    for k in range(max_points):
        x, y, z = position(end * k / (max_points - 1))
        out.append((float(x), float(y), float(z)))
    return out


class TraceDecimator:
    """The newest `length` x, y, z points of the measured positions, one per `period_ns`.

    `take(axis, stamp_ns, position)` gives each axis's newest position; once every axis has
    one, the point at the oldest of their stamps is kept when that stamp is at least
    `period_ns` after the last kept point's (the first at once). A position that is not
    finite (it would break the line) is not taken.
    """

    def __init__(self, axes: Sequence[str], period_ns: int, length: int) -> None:
        if period_ns <= 0 or length < 1:
            raise ValueError(f'period_ns and length must be positive, got {period_ns}, {length}')
        self.axes = tuple(axes)
        self.period_ns, self.length = period_ns, length
        self._newest: dict[str, tuple[int, float]] = {}  # axis -> (stamp, position)
        self._last_ns: int | None = None
        self.points: deque[tuple[int, Point]] = deque(maxlen=length)

    def take(self, axis: str, stamp_ns: int, position: float) -> bool:
        """Whether this position completed a new point of the trace."""
        if axis not in self.axes or not math.isfinite(position):
            return False
        self._newest[axis] = (stamp_ns, position)
        if len(self._newest) < len(self.axes):
            return False
        # The point of the sample every axis has reached: the oldest of the newest stamps
        # (a drive stamps the three states of a period alike: the last of them completes it).
        stamp = min(ns for ns, _ in self._newest.values())
        if self._last_ns is not None and stamp < self._last_ns:
            self.points.clear()  # the clock went back: a new run, a new trace
        elif self._last_ns is not None and stamp - self._last_ns < self.period_ns:
            return False
        xyz = [self._newest[a][1] if a in self._newest else 0.0 for a in ('x', 'y', 'z')]
        self.points.append((stamp, (xyz[0], xyz[1], xyz[2])))
        self._last_ns = stamp
        return True
