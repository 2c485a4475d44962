"""The trajectory role: a reference for all axes at any time. ROS-free.

Every path type subclasses Trajectory and is registered (mill_trajectory.registry): it
names its parameter namespace (PREFIX) and parameters (PARAMETERS) and builds itself with
from_parameters.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.parameters import ParamSpec
from mill_common.signals import AxisReference


@dataclass(frozen=True)
class TrajectorySample:
    """Reference of the three axes (x, y, z) at one instant [m, m/s, m/s^2], and the
    programmed spindle speed [rev/min, signed; 0 off], None on a path that programs none."""

    position: tuple[float, float, float]
    velocity: tuple[float, float, float]
    acceleration: tuple[float, float, float]
    spindle: float | None = None

    def axis(self, i: int) -> AxisReference:
        return AxisReference(self.position[i], self.velocity[i], self.acceleration[i])


class Trajectory(ABC):
    """A path of the three axes; after end_time [s] it holds its last point at rest."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = ()
    end_time: float

    @classmethod
    @abstractmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> Trajectory:
        """Build from values named without the prefix; ParameterError names a bad one."""

    @abstractmethod
    def sample(self, t: float) -> TrajectorySample:
        """The reference at time t [s]."""

    def bounds(self, step: float) -> tuple[Point, Point]:
        """The smallest box (lowest, highest x, y, z) [m] holding the path from t = 0 to its
        end, here from samples every `step` [s]; a path type that knows its shape says so
        exactly and without sampling."""
        steps = math.ceil(self.end_time / step) if math.isfinite(self.end_time) else 0
        points = [self.sample(min(k * step, self.end_time)).position for k in range(steps + 1)]
        return box(points)


Point = tuple[float, float, float]


def box(points: Iterable[Sequence[float]]) -> tuple[Point, Point]:
    """Lowest and highest x, y, z of some points."""
    xs, ys, zs = zip(*points, strict=True)
    return (min(xs), min(ys), min(zs)), (max(xs), max(ys), max(zs))
