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
from collections.abc import Mapping, Sequence
from typing import Any

from mill_common.parameters import ParamSpec, non_negative, number_list, positive

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


class LinearPath(Trajectory):
    PREFIX = 'linear'
    PARAMETERS = (
        ParamSpec(
            'waypoints',
            _flat(BELTRAN_WAYPOINTS),
            'path corners as a flat list x0, y0, z0, x1, y1, z1, ... [m] (at least 2 points)',
            number_list(),
        ),
        ParamSpec('feed_rate', BELTRAN_FEED_RATE, 'programmed path speed [m/s]', positive),
        ParamSpec('start_time', 0.0, 'time the tool leaves the first waypoint [s]', non_negative),
    )

    def __init__(
        self,
        waypoints: Sequence[Sequence[float]] = BELTRAN_WAYPOINTS,
        feed_rate: float = BELTRAN_FEED_RATE,
        start_time: float = 0.0,
    ) -> None:
        if len(waypoints) < 2 or any(len(p) != 3 for p in waypoints):
            raise ValueError('waypoints must hold at least two points of three coordinates')
        points = [(float(p[0]), float(p[1]), float(p[2])) for p in waypoints]
        if not (feed_rate > 0 and math.isfinite(feed_rate)):
            raise ValueError(f'feed_rate must be > 0, got {feed_rate!r}')
        self.points = points
        self.feed_rate = float(feed_rate)
        self.start_time = float(start_time)
        self._starts = [self.start_time]  # segment start times
        self._velocities: list[tuple[float, float, float]] = []
        for a, b in itertools.pairwise(points):
            length = math.dist(a, b)
            if length == 0.0:
                raise ValueError('waypoints must not repeat a point (zero-length segment)')
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

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> LinearPath:
        flat = values['waypoints']
        if len(flat) % 3:
            raise ValueError('linear.waypoints must hold a multiple of 3 numbers')
        points = [flat[i : i + 3] for i in range(0, len(flat), 3)]
        return cls(points, values['feed_rate'], values['start_time'])

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
