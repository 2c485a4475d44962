"""The trajectory role: a reference for all axes at any time. ROS-free.

Every path type subclasses Trajectory and is registered (mill_trajectory.registry): it
names its parameter namespace (PREFIX) and parameters (PARAMETERS) and builds itself with
from_parameters.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
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
