"""Straight cutting segments at a programmed feed rate, Beltrán 2013 eq. (19)-(22).

Each segment is travelled at constant speed `feed_rate` along the line
between consecutive waypoints, so the reference velocity is piecewise
constant and the acceleration zero, exactly as in eq. (19)-(22). Before the
start the tool holds the first waypoint, after the end the last one.
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, non_negative, number_list, positive

from mill_trajectory.base import Point, Trajectory, TrajectorySample, box

# The paper's job: x = -0.075 m on the first cut (the reading that makes the
# path continuous; eq. (19) prints +0.075), 80 mm in +y, then 80 mm in +x,
# tool 5 mm below the top surface, 3 mm/s.
BELTRAN_WAYPOINTS = (
    (-0.075, -0.105, -0.005),
    (-0.075, -0.025, -0.005),
    (0.005, -0.025, -0.005),
)
BELTRAN_FEED_RATE = 0.003


def _flat(points: Sequence[Sequence[float]]) -> list[float]:
    return [float(v) for p in points for v in p]


@dataclass(frozen=True)
class LinearParams(ParamSet):
    """Beltrán 2013 eq. (19)-(22): straight segments at a constant feed rate."""

    PREFIX: ClassVar[str] = 'linear'
    waypoints: list[float] = param(
        _flat(BELTRAN_WAYPOINTS),
        'path corners as a flat list x0, y0, z0, x1, y1, z1, ... [m] (at least 2 points)',
        number_list(),
    )
    feed_rate: float = param(BELTRAN_FEED_RATE, 'programmed path speed', positive, unit='m/s')
    start_time: float = param(
        0.0, 'time the tool leaves the first waypoint', non_negative, unit='s'
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if len(self.waypoints) % 3:
            raise ParameterError(
                'linear.waypoints', self.waypoints, 'must hold a multiple of 3 numbers'
            )
        if len(self.waypoints) < 6:
            raise ParameterError(
                'linear.waypoints',
                self.waypoints,
                'must hold at least two points of three coordinates',
            )

    @property
    def points(self) -> list[tuple[float, float, float]]:
        w = self.waypoints
        return [(w[i], w[i + 1], w[i + 2]) for i in range(0, len(w), 3)]


class LinearPath(Trajectory):
    PARAMS: ClassVar[type[LinearParams]] = LinearParams

    def __init__(self, params: LinearParams = LinearParams()) -> None:
        points = params.points
        self.points = points
        self.feed_rate = params.feed_rate
        self.start_time = params.start_time
        self._starts = [self.start_time]  # segment start times
        self._velocities: list[tuple[float, float, float]] = []
        for a, b in itertools.pairwise(points):
            length = math.dist(a, b)
            if length == 0.0:
                raise ParameterError(
                    'linear.waypoints',
                    params.waypoints,
                    'must not repeat a point (zero-length segment)',
                )
            duration = length / self.feed_rate
            # Beltrán 2013 eq. (19)-(22): velocity (p_f - p_i)/(t_f - t_i) on each segment.
            velocity = (
                (b[0] - a[0]) / duration,
                (b[1] - a[1]) / duration,
                (b[2] - a[2]) / duration,
            )
            self._velocities.append(velocity)
            self._starts.append(self._starts[-1] + duration)
        self.end_time = self._starts[-1]

    def sample(self, t: float) -> TrajectorySample:
        zero = (0.0, 0.0, 0.0)
        if t <= self.start_time:
            return TrajectorySample(self.points[0], zero, zero)
        if t >= self.end_time:
            return TrajectorySample(self.points[-1], zero, zero)
        i = bisect.bisect_right(self._starts, t) - 1
        tau = t - self._starts[i]
        v = self._velocities[i]
        p0 = self.points[i]
        # Beltrán 2013 eq. (19)-(22): p(t) = (p_f - p_i)/(t_f - t_i) (t - t_i) + p_i.
        pos = (p0[0] + v[0] * tau, p0[1] + v[1] * tau, p0[2] + v[2] * tau)
        return TrajectorySample(pos, v, zero)

    def bounds(self, step: float) -> tuple[Point, Point]:
        return box(self.points)  # straight segments between the waypoints
