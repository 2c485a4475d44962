"""Interface of one machine-axis model, as integrated by mill_plant.axis_plant (ROS-free).

State layout (every model is mechanical): a flat list of floats
``[q_0, ..., q_{N-1}, q'_0, ..., q'_{N-1}]`` with N = N_DOF generalised coordinates
(rigid axis: [x, x']; flexible axis: [θ1, θ2, x, θ1', θ2', x']; ...). SI units.

What the plant calls:

- ``derivative(state, u, force, mode)``: d(state)/dt for the input u held in INPUT_UNIT
  (already delayed by ``dead_time`` by the plant), the cutting force [N] on this axis
  (sign of mill_plant.cutting: positive resists motion in +axis) and the friction mode.
- ``position(state)``, ``velocity(state)``: carriage/table position [m] and velocity
  [m/s]. Both must be LINEAR in the state: the plant gets the carriage acceleration as
  ``velocity(derivative(...))``.
- Coulomb stick-slip (the scheme of mill_plant.axis_plant): a model with FRICTION_DOF = j has a
  Coulomb force ``coulomb_friction`` [N] on coordinate j (the carriage). Per substep the
  plant freezes a mode: +1.0 / -1.0 = sliding in that direction (friction -mu·mode), 0.0 =
  stuck (coordinate j has zero velocity and zero acceleration). At rest (q'_j == 0.0) the
  mode comes from ``stick_force(state, u, force)``, the net non-friction force on j:
  stuck if |net| <= mu, else sliding along net. FRICTION_DOF = None: no Coulomb
  friction, mode is always 1.0 and ignored.
- ``dead_time`` [s]: input dead time; 0.0 for all but the transfer-function model.
- ``disturbance(state, u, force, mode, command)``: the lumped disturbance ξ = x'' - b·command
  [m/s²] that the plant reports (analysis only); by default from ``derivative``, a model
  may give it in closed form.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from mill_common.declared import Configured, ParamSet, param
from mill_common.parameters import UnknownParameterError, non_negative

State = list[float]

STANDARD_GRAVITY = 9.80665  # [m/s^2]

M = TypeVar('M', bound='AxisModel')


@dataclass(frozen=True)
class AxisModelParams(ParamSet):
    """Base of a model's parameters: g, which every model offers (it is used only on an axis
    built with gravity, the vertical z). A list field holds one entry per axis x, y, z."""

    gravity_acceleration: float = param(
        STANDARD_GRAVITY,
        'g [m/s^2], used on an axis built with gravity (Chávez-Conde eq. (3))',
        non_negative,
    )

    def at(self, axis: int) -> dict[str, Any]:
        """name → value on axis 0/1/2 (x/y/z): a list's entry for that axis, a number as is."""
        check_axis(axis)
        return {
            k: float(x[axis]) if isinstance(x, list | tuple) else x
            for k, x in self.values().items()
        }


class AxisModel(Configured, ABC):
    """One axis: input (torque or voltage) and cutting force in, carriage motion out.

    A model is built as `Model(params, axis, gravity)`, params its PARAMS set; INPUT_UNIT is
    the one declaration of the unit of its input, which the plant and the drive read.
    """

    PARAMS: ClassVar[type[AxisModelParams]] = AxisModelParams
    INPUT_UNIT: ClassVar[str]  # 'N·m' or 'V'
    N_DOF: ClassVar[int]  # generalised coordinates; the state has 2·N_DOF entries
    FRICTION_DOF: ClassVar[int | None] = None  # coordinate carrying Coulomb friction

    dead_time: float = 0.0  # input dead time [s]
    coulomb_friction: float = 0.0  # mu [N] on FRICTION_DOF

    @classmethod
    def from_parameters(
        cls: type[M], axis: int, values: Mapping[str, Any], gravity: bool = False
    ) -> M:
        """Model of axis 0/1/2 (x/y/z) from values named without prefix (missing: defaults).

        gravity: the weight of the carried mass acts along -axis (vertical z axis).
        Raises ParameterError naming the bad parameter (ValueError for a bad axis).
        """
        check_axis(axis)
        known = [s.name for s in cls.PARAMETERS]
        unknown = {f'{cls.PREFIX}.{n}': v for n, v in values.items() if n not in known}
        if unknown:
            full = [f'{cls.PREFIX}.{n}' for n in known]
            raise UnknownParameterError(unknown, full, f'the {cls.PREFIX} model')
        return cls(cls.PARAMS.from_values(values), axis, gravity)  # type: ignore[call-arg]

    @abstractmethod
    def initial_state(self, position: float) -> State:
        """At rest with the carriage at `position` [m] (elastic elements relaxed)."""

    @abstractmethod
    def position(self, state: Sequence[float]) -> float:
        """Carriage/table position [m]; linear in the state."""

    @abstractmethod
    def velocity(self, state: Sequence[float]) -> float:
        """Carriage/table velocity [m/s]; linear in the state."""

    @abstractmethod
    def add_load(self, mass: float) -> None:
        """The carried mass grows by `mass` [kg] from now on (ValueError if it would be <= 0)."""

    @abstractmethod
    def input_gain(self) -> float:
        """b of the nominal model x'' ≈ b·u [m/s² per input unit], for information."""

    @abstractmethod
    def derivative(self, state: Sequence[float], u: float, force: float, mode: float) -> State:
        """d(state)/dt for input u, cutting force [N] and friction mode (module docstring)."""

    def stick_force(self, state: Sequence[float], u: float, force: float) -> float:
        """Net non-friction force [N] on FRICTION_DOF when its velocity is zero."""
        return 0.0

    def disturbance(
        self, state: Sequence[float], u: float, force: float, mode: float, command: float
    ) -> float:
        """Lumped disturbance ξ = x'' - b·command [m/s²].

        x'' is the carriage acceleration with the input u acting (for a dead-time model the
        delayed input), b = input_gain() and command the input given now.
        """
        return self.velocity(self.derivative(state, u, force, mode)) - self.input_gain() * command


def check_axis(axis: int) -> int:
    """0, 1 or 2; ValueError names the bad value."""
    if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis <= 2:
        raise ValueError(f'axis must be 0, 1 or 2 (x, y, z), got {axis!r}')
    return axis


def check_mass_change(name: str, current: float, mass: float) -> float:
    """The new carried mass current + mass; ValueError if not finite or not > 0."""
    new = current + float(mass)
    if not math.isfinite(new) or new <= 0.0:
        raise ValueError(f'{name}: carried mass {current!r} + {mass!r} kg must stay > 0')
    return new
