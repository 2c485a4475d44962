"""Cutting-force models seen by the three axes.

Sign convention (Beltrán 2013 eq. (1)): m_e x'' + c_e x' + mu sign(x') = tau/a - F_c,
so a force that resists motion in +x is a positive F_cx.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

Force3 = tuple[float, float, float]


class CuttingForceModel(Protocol):
    """Anything returning the cutting force (F_cx, F_cy, F_cz) [N] on the tool.

    A model whose force depends on the tool's past path (the Kline chip) also has
    `commit(t, position, velocity)`: the plant calls it with its initial state and with
    every state it accepts (after each RK4 substep), in increasing time.
    """

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        """Cutting force at time t [s], tool position (x, y, z) [m], velocity [m/s]."""
        ...


class NoCutting:
    """Air cutting: no force at all."""

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        return (0.0, 0.0, 0.0)


class StepForce:
    """Zero before start_time, then a constant force; a clean disturbance for observer tests."""

    def __init__(self, force: Sequence[float], start_time: float = 0.0) -> None:
        if len(force) != 3:
            raise ValueError(f'force must have 3 entries (x, y, z), got {len(force)}')
        values = tuple(float(f) for f in force)
        if not all(math.isfinite(f) for f in values):
            raise ValueError(f'force must be finite, got {force!r}')
        if not math.isfinite(start_time):
            raise ValueError(f'start_time must be finite, got {start_time!r}')
        self._force: Force3 = (values[0], values[1], values[2])
        self.start_time = float(start_time)

    @property
    def value(self) -> Force3:
        return self._force

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        if t < self.start_time:
            return (0.0, 0.0, 0.0)
        return self._force
