"""The trajectory role: a reference for all axes at any time. ROS-free."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from mill_common.signals import AxisReference


@dataclass(frozen=True)
class TrajectorySample:
    """Reference of the three axes (x, y, z) at one instant [m, m/s, m/s^2]."""

    position: tuple[float, float, float]
    velocity: tuple[float, float, float]
    acceleration: tuple[float, float, float]

    def axis(self, i: int) -> AxisReference:
        return AxisReference(self.position[i], self.velocity[i], self.acceleration[i])


class Trajectory(Protocol):
    end_time: float

    def sample(self, t: float) -> TrajectorySample: ...
