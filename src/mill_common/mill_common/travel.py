"""The machine's travel, declared once for every node that needs it. ROS-free.

The trajectory refuses a path that leaves it before anything moves
(mill_trajectory.config); the drive stops an axis about to leave it, whatever commands it
(mill_plant.motion_guard). Per axis x, y, z [m].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, number_list


@dataclass(frozen=True)
class MachineTravel(ParamSet):
    """The machine's travel."""

    PREFIX: ClassVar[str] = 'travel'
    min: list[float] = param(
        [-1.0, -1.0, -1.0],
        "the machine's travel: lowest x, y, z; the trajectory refuses a path that leaves "
        'it before anything moves, the drive stops an axis about to leave it',
        number_list(3),
        unit='m',
    )
    max: list[float] = param(
        [1.0, 1.0, 1.0], "the machine's travel: highest x, y, z", number_list(3), unit='m'
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if any(lo > hi for lo, hi in zip(self.min, self.max, strict=True)):
            raise ParameterError(
                'travel.min', self.min, 'travel.min must not exceed travel.max on any axis'
            )

    def limits(self, axes: str = 'xyz') -> dict[str, tuple[float, float]]:
        """axis -> (lowest, highest) [m]."""
        return {a: (self.min[i], self.max[i]) for i, a in enumerate('xyz') if a in axes}
