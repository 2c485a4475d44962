"""Plain data exchanged between algorithm cores. ROS-free: cores import this, never rclpy."""

from __future__ import annotations

from dataclasses import dataclass

AXES: tuple[str, ...] = ('x', 'y', 'z')


def axis_index(axis: str) -> int:
    """Index of a machine axis name in AXES; ValueError names the bad value."""
    try:
        return AXES.index(axis)
    except ValueError:
        raise ValueError(f'axis must be one of {", ".join(AXES)}, got {axis!r}') from None


@dataclass(frozen=True)
class AxisReference:
    """Desired motion of one axis at one instant [m, m/s, m/s^2]."""

    position: float
    velocity: float
    acceleration: float


@dataclass(frozen=True)
class Estimate:
    """Observer output for one axis at one sample.

    position [m], velocity [m/s], disturbance: the lumped disturbance xi of
    Beltrán 2013 eq. (5)-(8), as an acceleration [m/s^2].
    """

    position: float
    velocity: float
    disturbance: float
