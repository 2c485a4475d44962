"""Identified x-axis transfer function of Maharof 2018 eq. (1), voltage input with dead time.

    G(s) = Z(s)/U(s) = A/(s² + B s + C) e^(-s T_d),   i.e.
    x'' = -B x' - C x + A (u(t - T_d) - F_c/k_f)        (time domain, x in m, A in m/(V·s²))

Units: A is a parameter in the paper's mm/(V·s²) and is converted to m/(V·s²) inside
(×1e-3); B [1/s], C [1/s²], T_d [s]; input u in volts. The dead time is exact: the plant
holds each step's voltage and, where the delayed voltage changes inside a step, splits the
integration at that instant (mill_plant.axis_plant). Before the plant's start the voltage
was 0.

Readings (not in the paper):

- Cutting force: the paper only says k_f is "the motor constant in [N]/[V]"; a cutting
  force F on the table enters as the input-equivalent voltage F/k_f (as in
  mill_observers.imbdo), with the eq. (1) sign convention of mill_plant.cutting (positive F
  resists motion in +x). Default k_f = 780.2 N/V = A·m0 with an assumed moving mass
  m0 = 10 kg of the XY table: then eq. (1) is Newton's law m0 x'' = k_f u - F - ...
- Load change (add_load Δm): eq. (1) is read as a force balance on the moving mass
  m0 = k_f/A: m0 x'' = k_f u(t-T_d) - F - m0 B x' - m0 C x. A carried mass Δm keeps the
  forces (k_f, m0 B, m0 C) and scales A, B and C by m0/(m0 + Δm); the DC gain A/C stays.
- Gravity (vertical use): the weight of the whole moving mass, x'' gets -g (independent
  of the load).
- No Coulomb friction (the identified model has none).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import param
from mill_common.parameters import non_negative, positive

from mill_plant.models.base import AxisModel, AxisModelParams, State, check_mass_change

M_PER_MM = 1e-3

# Maharof 2018 eq. (1), x axis
MAHAROF_A = 78020.0  # [mm/(V·s²)]
MAHAROF_B = 163.0  # [1/s]
MAHAROF_C = 193.3  # [1/s²]
MAHAROF_DEAD_TIME = 0.0012  # [s]
DEFAULT_MOVING_MASS = 10.0  # [kg], our reading (not published)
DEFAULT_FORCE_CONSTANT = 780.2  # k_f = A·m0 = 78.02 m/(V·s²) × 10 kg [N/V], our reading


@dataclass(frozen=True)
class TransferFunctionParams(AxisModelParams):
    """Maharof 2018 eq. (1) and our reading of the force constant; the same on every axis."""

    PREFIX: ClassVar[str] = 'transfer_function'
    gain: float = param(MAHAROF_A, 'A of A/(s^2 + B s + C), eq. (1)', positive, unit='mm/(V s^2)')
    damping: float = param(MAHAROF_B, 'B of eq. (1)', non_negative, unit='1/s')
    stiffness: float = param(MAHAROF_C, 'C of eq. (1)', non_negative, unit='1/s^2')
    dead_time: float = param(MAHAROF_DEAD_TIME, 'T_d of eq. (1)', non_negative, unit='s')
    force_constant: float = param(
        DEFAULT_FORCE_CONSTANT,
        'k_f: a cutting force F acts as the voltage F/k_f [N/V] (default A x 10 kg, our reading)',
        positive,
    )


class TransferFunctionAxisModel(AxisModel):
    """Maharof 2018 eq. (1), voltage input [V]; state [x, x'] [m, m/s]."""

    PARAMS: ClassVar[type[TransferFunctionParams]] = TransferFunctionParams
    INPUT_UNIT: ClassVar[str] = 'V'
    N_DOF: ClassVar[int] = 1
    FRICTION_DOF: ClassVar[int | None] = None

    def __init__(
        self,
        params: TransferFunctionParams = TransferFunctionParams(),
        axis: int = 0,
        gravity: bool = False,
    ) -> None:
        self.p = params  # the same on every axis
        self.gravity = bool(gravity)
        self.dead_time = params.dead_time
        self._k_f = params.force_constant
        # moving mass m0 = k_f / A [kg] (module docstring)
        self._m0 = self._k_f / (params.gain * M_PER_MM)
        self._mass = self._m0
        self._g = params.gravity_acceleration if self.gravity else 0.0
        self._update()

    def _update(self) -> None:
        r = self._m0 / self._mass
        self._a = self.p.gain * M_PER_MM * r
        self._b = self.p.damping * r
        self._c = self.p.stiffness * r
        self._inv_kf = 1.0 / self._k_f

    @property
    def moving_mass(self) -> float:
        """m0 + added load [kg]."""
        return self._mass

    @property
    def coefficients(self) -> tuple[float, float, float]:
        """Current (A [m/(V·s²)], B [1/s], C [1/s²])."""
        return self._a, self._b, self._c

    def initial_state(self, position: float) -> State:
        return [float(position), 0.0]

    def position(self, state: Sequence[float]) -> float:
        return state[0]

    def velocity(self, state: Sequence[float]) -> float:
        return state[1]

    def add_load(self, mass: float) -> None:
        self._mass = check_mass_change('transfer_function moving mass', self._mass, mass)
        self._update()

    def input_gain(self) -> float:
        return self._a  # A [m/(V·s²)]

    def derivative(self, state: Sequence[float], u: float, force: float, mode: float) -> State:
        x, v = state
        # Maharof 2018 eq. (1): x'' = -B x' - C x + A (u(t - T_d) - F/k_f)  [- g]
        acc = -self._b * v - self._c * x + self._a * (u - force * self._inv_kf) - self._g
        return [v, acc]
