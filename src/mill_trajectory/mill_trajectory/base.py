"""The trajectory role: a reference for all axes at any time. ROS-free.

Every path type subclasses Trajectory and is registered (mill_trajectory.registry): it
declares its parameters once as a ParamSet (PARAMS; PREFIX and PARAMETERS derive from it) and
is built as `Path(params)`, or from a mapping by the one generic from_parameters.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from mill_common.declared import Configured
from mill_common.signals import AxisReference

P = TypeVar('P', bound='Trajectory')


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


class Trajectory(Configured, ABC):
    """A path of the three axes; after end_time [s] it holds its last point at rest."""

    end_time: float

    @classmethod
    def from_parameters(cls: type[P], values: Mapping[str, Any]) -> P:
        """Build from values named without the prefix; ParameterError names a bad one."""
        return cls(cls.PARAMS.from_values(values))  # type: ignore[call-arg]

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
