"""The feed planner's input: straight pieces and rests, the machine's limits, and its
failure (mill_trajectory.planner). ROS-free.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

Point = tuple[float, float, float]


def xyz(values: Sequence[float]) -> Point:
    """Three numbers as a point."""
    return (float(values[0]), float(values[1]), float(values[2]))


ORIGIN: Point = (0.0, 0.0, 0.0)


ZERO_LENGTH = 1e-12  # [m]: a shorter move is no move


@dataclass(frozen=True)
class Limits:
    """Per-axis limits (x, y, z) and the path tolerance at corners [m]."""

    velocity: Point  # [m/s], > 0
    acceleration: Point  # [m/s²], inf = no limit
    jerk: Point  # [m/s³], inf = no limit
    tolerance: float  # [m], > 0

    def scaled(self, override: float, reserve: float = 0.0) -> Limits:
        """Limits that a feed override up to `override` cannot push past (v·o, a·o², j·o³),
        with a share `reserve` of acceleration and jerk left for the override's changes."""
        o, keep = float(override), 1.0 - reserve
        return Limits(
            tuple(v / o for v in self.velocity),  # type: ignore[arg-type]
            tuple(keep * a / o**2 for a in self.acceleration),  # type: ignore[arg-type]
            tuple(keep * j / o**3 for j in self.jerk),  # type: ignore[arg-type]
            self.tolerance,
        )


@dataclass(frozen=True)
class Piece:
    """A straight move start -> end at most at `speed` [m/s], or a rest of `dwell` [s].

    `sag` [m]: how far the piece itself may be from the programmed path (an arc's chord: its
    sagitta); its transitions keep within the tolerance less that."""

    start: Point
    end: Point
    speed: float = math.inf  # inf: as fast as the axes allow (a rapid)
    dwell: float = 0.0  # rest only
    rest: bool = False
    spindle: float | None = None  # [rev/min], signed; None: not programmed
    sag: float = 0.0


class PlanError(ValueError):
    """The planner could not meet the limits; str() says where."""
