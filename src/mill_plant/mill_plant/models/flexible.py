"""Flexible motor–coupling–screw–carriage axis, Chávez-Conde eq. (4)-(6).

Coordinates θ1 (motor), θ2 (coupling output = screw input end) and x (carriage); n = 2π/p:

    J_m θ1'' - k_c (θ2 - θ1) + f1 = tau                                   eq. (4)
    J_c θ2'' + k_c (θ2 - θ1) - k_To (n x - θ2) + f2 = 0                   eq. (5)
    (J_T n² + m_c) x'' + n k_To (n x - θ2) + f3 = -F_c [- m_c g]           eq. (6)
    f1 = c_m θ1',  f2 = c_To θ2',  f3 = [(c_Tu + c_b) n² + c_g] x' + mu sign(x')

Readings (the paper prints the equations but no parameter values for this model):

- Eq. (6) prints k_To (n x - θ2), a torque, in a force balance. From the potential
  ½ k_To (n x - θ2)² (Euler-Lagrange, as the paper says) the force on x is
  n k_To (n x - θ2): the factor n is restored here.
- f3 prints (c_To + C_b) n²; c_To already acts on θ2 in f2 and the nut damping C_Tu
  defined in the text appears nowhere, so f3 is read with C_Tu (nut) + C_b (end bearing).
  With the defaults (c_Tu = c_To) both readings coincide.
- μ1 = μ2 = 0: Coulomb friction only on the carriage (mu = μ3), where stick-slip is
  handled by the plant; the bearing Coulomb terms of f1, f2 are not given.
- Defaults: m_c = 5 kg, p = 10 mm (a = 0.01/2π), c_g = c_b = 2.5 N·s/m, mu = 0.3 N are the
  paper's x-axis simulation values (rigid model). The paper's screw inertia J = 0.005 kg·m²
  is split as J_m = 0.0025 (motor rotor), J_c = 0.0005 (coupling), J_T = 0.002 (screw),
  and its c_t = 2.5 N·s/m (translational reading) as rotational c_t a² = 6.33e-6 N·m·s/rad
  split equally over c_m, c_To, c_Tu, c_b. So in the stiff limit (k_c, k_To → ∞) the model
  is the paper's rigid x axis, m_e = m_c + (J_m + J_c + J_T) n², c_e = c_g + Σc n².
- Stiffnesses (not given): k_c = 2000 N·m/rad, k_To = 500 N·m/rad (torsion of the screw
  in series with its axial stiffness ~2e8 N/m seen through a²). Modes ≈ 94 Hz and 380 Hz,
  above the paper's control bandwidth (ω_n = 80 rad/s) and still RK4-stable at the
  paper's 1 ms step (ω_max h ≈ 2.4 < 2.8).
- Gravity (vertical use): the carriage weight (m_c + load) g acts on x towards -x.
  add_load adds to m_c (the text's m_p, workpiece mass, rides on the carriage).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import param
from mill_common.parameters import non_negative, positive

from mill_plant.models.base import AxisModel, AxisModelParams, State, check_mass_change

_A = 0.01 / (2.0 * math.pi)  # Chávez-Conde: a = 0.01 m / 2π
_C_ROT = 2.5 * _A * _A / 4.0  # a quarter of c_t a² [N·m·s/rad]


@dataclass(frozen=True)
class FlexibleModelParams(AxisModelParams):
    """Chávez-Conde eq. (4)-(6); the same values on every axis (module docstring)."""

    PREFIX: ClassVar[str] = 'flexible'
    motor_inertia: float = param(0.0025, 'motor rotor inertia J_m', positive, unit='kg m^2')
    coupling_inertia: float = param(0.0005, 'coupling inertia J_c', positive, unit='kg m^2')
    screw_inertia: float = param(0.002, 'ball-screw inertia J_To', non_negative, unit='kg m^2')
    carriage_mass: float = param(5.0, 'carriage (+ workpiece) mass m_c', positive, unit='kg')
    pitch: float = param(0.01, 'ball-screw pitch p', positive, unit='m/rev')
    coupling_stiffness: float = param(2000.0, 'coupling stiffness k_c', positive, unit='N m/rad')
    screw_stiffness: float = param(500.0, 'screw stiffness k_To', positive, unit='N m/rad')
    motor_damping: float = param(
        _C_ROT, 'motor bearing damping c_m', non_negative, unit='N m s/rad'
    )
    screw_damping: float = param(
        _C_ROT, 'bearing after the coupling, on θ2, c_To', non_negative, unit='N m s/rad'
    )
    nut_damping: float = param(
        _C_ROT, 'nut damping C_Tu, on x via n²', non_negative, unit='N m s/rad'
    )
    end_bearing_damping: float = param(
        _C_ROT, 'screw end bearing damping C_b, on x via n²', non_negative, unit='N m s/rad'
    )
    guide_damping: float = param(2.5, 'linear guide damping c_g', non_negative, unit='N s/m')
    coulomb_friction: float = param(
        0.3, 'Coulomb friction mu_3 on the carriage', non_negative, unit='N'
    )


class FlexibleAxisModel(AxisModel):
    """Three-inertia axis, torque input [N·m]; state [θ1, θ2, x, θ1', θ2', x']."""

    PARAMS: ClassVar[type[FlexibleModelParams]] = FlexibleModelParams
    INPUT_UNIT: ClassVar[str] = 'N·m'
    N_DOF: ClassVar[int] = 3
    FRICTION_DOF: ClassVar[int | None] = 2

    def __init__(
        self,
        params: FlexibleModelParams = FlexibleModelParams(),
        axis: int = 0,
        gravity: bool = False,
    ) -> None:
        self.p = params  # the same on every axis
        self.gravity = bool(gravity)
        self.n = 2.0 * math.pi / params.pitch
        self.coulomb_friction = params.coulomb_friction
        self._mc = params.carriage_mass
        self._update()

    def _update(self) -> None:
        p, n = self.p, self.n
        self._inv_jm = 1.0 / p.motor_inertia
        self._inv_jc = 1.0 / p.coupling_inertia
        # Chávez-Conde eq. (6): carriage-side inertia J_T n² + m_c
        self._inv_m = 1.0 / (p.screw_inertia * n * n + self._mc)
        self._c3 = (p.nut_damping + p.end_bearing_damping) * n * n + p.guide_damping
        self._weight = self._mc * p.gravity_acceleration if self.gravity else 0.0

    @property
    def carriage_mass(self) -> float:
        return self._mc

    def rigid_equivalent(self) -> tuple[float, float]:
        """(m_e [kg], c_e [N·s/m]) of the stiff limit (all coordinates locked, θ = n x)."""
        p, n = self.p, self.n
        m_e = self._mc + (p.motor_inertia + p.coupling_inertia + p.screw_inertia) * n * n
        c_rot = p.motor_damping + p.screw_damping + p.nut_damping
        c_e = p.guide_damping + (c_rot + p.end_bearing_damping) * n * n
        return m_e, c_e

    def initial_state(self, position: float) -> State:
        th = self.n * float(position)
        return [th, th, float(position), 0.0, 0.0, 0.0]

    def position(self, state: Sequence[float]) -> float:
        return state[2]

    def velocity(self, state: Sequence[float]) -> float:
        return state[5]

    def add_load(self, mass: float) -> None:
        self._mc = check_mass_change('flexible.carriage_mass', self._mc, mass)
        self._update()

    def input_gain(self) -> float:
        """Stiff-limit b = n / m_e [m/(N·m·s²)] (= 1/(a m_e) of the rigid axis)."""
        return self.n / self.rigid_equivalent()[0]

    def derivative(self, state: Sequence[float], u: float, force: float, mode: float) -> State:
        th1, th2, x, w1, w2, v = state
        p = self.p
        tc = p.coupling_stiffness * (th2 - th1)  # coupling torque k_c (θ2 - θ1)
        ts = p.screw_stiffness * (self.n * x - th2)  # screw torque k_To (n x - θ2)
        # Chávez-Conde eq. (4): J_m θ1'' = tau + k_c (θ2 - θ1) - c_m θ1'
        a1 = self._inv_jm * (u + tc - p.motor_damping * w1)
        # Chávez-Conde eq. (5): J_c θ2'' = -k_c (θ2 - θ1) + k_To (n x - θ2) - c_To θ2'
        a2 = self._inv_jc * (ts - tc - p.screw_damping * w2)
        if mode == 0.0:
            return [w1, w2, 0.0, a1, a2, 0.0]  # carriage stuck
        # Chávez-Conde eq. (6) (factor n restored): M x'' = -n k_To (n x - θ2) - f3 - F_c - m g
        a3 = self._inv_m * (
            -self.n * ts - self._c3 * v - self.coulomb_friction * mode - force - self._weight
        )
        return [w1, w2, v, a1, a2, a3]

    def stick_force(self, state: Sequence[float], u: float, force: float) -> float:
        ts = self.p.screw_stiffness * (self.n * state[2] - state[1])
        return -self.n * ts - force - self._weight
