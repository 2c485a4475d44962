"""Cutting-force models seen by the three axes: the interface, and the two simple ones.

Sign convention (Beltrán 2013 eq. (1)): m_e x'' + c_e x' + mu sign(x') = tau/a - F_c,
so a force that resists motion in +x is a positive F_cx.

Every model subclasses CuttingForceModel and is registered by name in
mill_plant.registry (the plant's `cutting_model` parameter); its parameters are
`<PREFIX>.<name>` on the plant node. The models with a paper behind them have a file of
their own (kline_force.py, harmonic_force.py).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from mill_common.declared import Configured, ParamSet, param
from mill_common.parameters import non_negative, number_list

Force3 = tuple[float, float, float]

F = TypeVar('F', bound='CuttingForceModel')


class CuttingForceModel(Configured, ABC):
    """Anything returning the cutting force (F_cx, F_cy, F_cz) [N] on the tool.

    A model is built as `Model(params)`, params its PARAMS set. A model whose force depends
    on the tool's past path (the Kline chip) says so with PATH_DEPENDENT: the plant then
    calls `commit(t, position, velocity)` with its initial state and with every state it
    accepts (after each RK4 substep), in increasing time.
    """

    PATH_DEPENDENT: ClassVar[bool] = False

    @classmethod
    def from_parameters(cls: type[F], values: Mapping[str, Any]) -> F:
        """Build from values named without the prefix (missing names take defaults).

        Raises ParameterError naming a bad parameter ('<PREFIX>.<name>').
        """
        return cls(cls.PARAMS.from_values(values))  # type: ignore[call-arg]

    @abstractmethod
    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        """Cutting force at time t [s], tool position (x, y, z) [m], velocity [m/s]."""

    def commit(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> None:
        """An accepted tool state (PATH_DEPENDENT models keep the path)."""


@dataclass(frozen=True)
class NoParams(ParamSet):
    """Air cutting has no parameters."""

    PREFIX: ClassVar[str] = 'none'


class NoCutting(CuttingForceModel):
    """Air cutting: no force at all."""

    PARAMS: ClassVar[type[NoParams]] = NoParams

    def __init__(self, params: NoParams = NoParams()) -> None:
        pass

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        return (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class StepParams(ParamSet):
    PREFIX: ClassVar[str] = 'step'
    force: list[float] = param(
        [0.0, 100.0, 0.0], 'constant force Fx, Fy, Fz after the step', number_list(3), unit='N'
    )
    start_time: float = param(1.0, 'time the step force starts', non_negative, unit='s')


class StepForce(CuttingForceModel):
    """Zero before start_time, then a constant force; a clean disturbance for observer tests."""

    PARAMS: ClassVar[type[StepParams]] = StepParams

    def __init__(self, params: StepParams = StepParams()) -> None:
        f = params.force
        self._force: Force3 = (f[0], f[1], f[2])
        self.start_time = params.start_time

    @property
    def value(self) -> Force3:
        return self._force

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        if t < self.start_time:
            return (0.0, 0.0, 0.0)
        return self._force
