"""Cutting-force models seen by the three axes: the interface, and the two simple ones.

Sign convention (Beltrán 2013 eq. (1)): m_e x'' + c_e x' + mu sign(x') = tau/a - F_c,
so a force that resists motion in +x is a positive F_cx.

Every model subclasses CuttingForceModel and is registered by name in
mill_plant.registry (the plant's `cutting_model` parameter); its parameters are
`<PREFIX>.<name>` on the plant node. The models with a paper behind them have a file of
their own (kline_force.py, harmonic_force.py).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import ParamSpec, non_negative, number_list, validate_all

Force3 = tuple[float, float, float]


class CuttingForceModel(ABC):
    """Anything returning the cutting force (F_cx, F_cy, F_cz) [N] on the tool.

    A model whose force depends on the tool's past path (the Kline chip) says so with
    PATH_DEPENDENT: the plant then calls `commit(t, position, velocity)` with its initial
    state and with every state it accepts (after each RK4 substep), in increasing time.
    """

    PATH_DEPENDENT: ClassVar[bool] = False

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = ()

    @classmethod
    @abstractmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> CuttingForceModel:
        """Build from values named without the prefix (missing names take defaults).

        Raises ParameterError naming a bad parameter ('<PREFIX>.<name>').
        """

    @abstractmethod
    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        """Cutting force at time t [s], tool position (x, y, z) [m], velocity [m/s]."""

    def commit(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> None:  # noqa: B027
        """An accepted tool state (PATH_DEPENDENT models keep the path)."""


class NoCutting(CuttingForceModel):
    """Air cutting: no force at all."""

    PREFIX: ClassVar[str] = 'none'

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> NoCutting:
        return cls()

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        return (0.0, 0.0, 0.0)


class StepForce(CuttingForceModel):
    """Zero before start_time, then a constant force; a clean disturbance for observer tests."""

    PREFIX: ClassVar[str] = 'step'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            'force',
            [0.0, 100.0, 0.0],
            'constant force Fx, Fy, Fz after the step [N]',
            number_list(3),
        ),
        ParamSpec('start_time', 1.0, 'time the step force starts [s]', non_negative),
    )

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

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> StepForce:
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        return cls(tuple(v['force']), v['start_time'])

    @property
    def value(self) -> Force3:
        return self._force

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        if t < self.start_time:
            return (0.0, 0.0, 0.0)
        return self._force
