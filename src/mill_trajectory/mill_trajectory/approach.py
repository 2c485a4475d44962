"""The move from where the axes stand to the start of a job, then the job's path. ROS-free.

A real machine starts a job wherever its axes stand. On the wall clock (timing realtime)
the trajectory therefore begins with a rest-to-rest move (the Bézier blend of
mill_trajectory.bezier) from the measured position to the path's first point, at a peak
speed of `speed`, and then runs the path; an axis further than `max_distance` from the
start point is refused with a message naming the distance, rather than moved blindly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.bezier import BezierParams, BezierRestToRest

# Peak of dψ/dΔ of the Bézier blend (at Δ = 7/15): a move of length d in time D peaks at
# 3.249·d/D, so D = 3.249·d/speed keeps the peak at `speed`.
PEAK_BLEND_SLOPE = 3.2490


class ApproachError(ValueError):
    """The axes stand too far from the start point; str() names the distance."""


class Approach(Trajectory):
    """From `position` to path.sample(0) at a limited speed, then the path, shifted.

    Not a registered path type: the trajectory node puts it in front of the job's path.
    """

    PREFIX = 'approach'

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> Approach:
        raise NotImplementedError('an approach is built from the measured position')

    def __init__(
        self,
        path: Trajectory,
        position: Sequence[float],
        speed: float,
        max_distance: float,
        axes: Sequence[int] = (0, 1, 2),
    ) -> None:
        first = path.sample(0.0)
        start = first.position
        # A path that programs the spindle starts it at its first point (at rest): off before.
        self._spindle = None if first.spindle is None else 0.0
        here = list(start)
        for i in axes:
            here[i] = float(position[i])
        distance = max(abs(here[i] - start[i]) for i in axes)
        if distance > max_distance:
            far = max(axes, key=lambda i: abs(here[i] - start[i]))
            raise ApproachError(
                f'axis {"xyz"[far]} stands {1e3 * (here[far] - start[far]):+.3f} mm from the '
                f'start point of the job, more than approach.max_distance = '
                f'{1e3 * max_distance:g} mm: move it closer first'
            )
        self.path = path
        self.distance = distance
        self.duration = PEAK_BLEND_SLOPE * distance / speed if distance > 0.0 else 0.0
        self.move = (
            BezierRestToRest(BezierParams(start=here, end=list(start), t1=0.0, t2=self.duration))
            if self.duration > 0.0
            else None
        )
        self.end_time = self.duration + path.end_time

    def sample(self, t: float) -> TrajectorySample:
        if self.move is not None and t < self.duration:
            return replace(self.move.sample(t), spindle=self._spindle)
        return self.path.sample(t - self.duration)
