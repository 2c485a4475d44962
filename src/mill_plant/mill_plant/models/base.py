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
from typing import Any, ClassVar

from mill_common.parameters import ParameterError, ParamSpec, non_negative, validate_all

State = list[float]

STANDARD_GRAVITY = 9.80665  # [m/s^2]

# Every model offers g; it is used only on an axis built with gravity (the vertical z).
GRAVITY_SPEC = ParamSpec(
    'gravity_acceleration',
    STANDARD_GRAVITY,
    'g [m/s^2], used on an axis built with gravity (Chávez-Conde eq. (3))',
    non_negative,
)


class AxisModel(ABC):
    """One axis: input (torque or voltage) and cutting force in, carriage motion out."""

    INPUT_UNIT: ClassVar[str]  # 'N·m' or 'V'
    PREFIX: ClassVar[str]  # parameter namespace
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]
    N_DOF: ClassVar[int]  # generalised coordinates; the state has 2·N_DOF entries
    FRICTION_DOF: ClassVar[int | None] = None  # coordinate carrying Coulomb friction

    dead_time: float = 0.0  # input dead time [s]
    coulomb_friction: float = 0.0  # mu [N] on FRICTION_DOF

    @classmethod
    @abstractmethod
    def from_parameters(
        cls, axis: int, values: Mapping[str, Any], gravity: bool = False
    ) -> AxisModel:
        """Model of axis 0/1/2 (x/y/z) from values named without prefix (missing: defaults).

        gravity: the weight of the carried mass acts along -axis (vertical z axis).
        Raises ParameterError naming the bad parameter.
        """

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


def validated(cls: type[AxisModel], axis: int, values: Mapping[str, Any]) -> dict[str, float]:
    """Validate `values` against cls.PARAMETERS and pick this axis's entry of every list."""
    check_axis(axis)
    unknown = sorted(set(values) - {s.name for s in cls.PARAMETERS})
    if unknown:
        name = unknown[0]
        raise ParameterError(f'{cls.PREFIX}.{name}', values[name], 'unknown parameter')
    v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
    return {k: float(x[axis]) if isinstance(x, list | tuple) else x for k, x in v.items()}


def check_mass_change(name: str, current: float, mass: float) -> float:
    """The new carried mass current + mass; ValueError if not finite or not > 0."""
    new = current + float(mass)
    if not math.isfinite(new) or new <= 0.0:
        raise ValueError(f'{name}: carried mass {current!r} + {mass!r} kg must stay > 0')
    return new
