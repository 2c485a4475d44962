"""Rigid ball-screw axis: Beltrán 2013 eq. (1)-(2), Chávez-Conde eq. (1)-(3) with gravity.

    m_e x'' + c_e x' + m g [vertical axis] + mu sign(x') = tau/a - F_c

with m_e = m + J/a², a = p/2π and c_e = c_b + c_t (c_t read as translational, see
mill_models.axis_data, which holds eq. (2) and the Beltrán Table 1 defaults).

Gravity (Chávez-Conde eq. (3)): the weight m_3 g of the CARRIAGE mass (not m_e: the screw
rotates, it is not lifted) acts on the z axis towards -z (z up; the tool plunges to -z).
The holding torque is tau = m g a. A load added by add_load is carried by the carriage:
it adds to m (so to m_e) and to the weight.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import param
from mill_common.parameters import non_negative, number_list, positive
from mill_models.axis_data import BELTRAN_TABLE1, RigidAxisParams

from mill_plant.models.base import AxisModel, AxisModelParams, State, check_mass_change


def _table(field: str) -> list[float]:
    return [float(getattr(BELTRAN_TABLE1[a], field)) for a in 'xyz']


@dataclass(frozen=True)
class RigidModelParams(AxisModelParams):
    """Beltrán 2013 Table 1 per axis x, y, z (on the plant node under their plain names)."""

    PREFIX: ClassVar[str] = 'rigid'
    mass: list[float] = param(
        _table('mass'), 'carriage mass m per axis x, y, z', number_list(3, positive), unit='kg'
    )
    screw_inertia: list[float] = param(
        _table('screw_inertia'),
        'ball-screw inertia J per axis',
        number_list(3, positive),
        unit='kg m^2',
    )
    pitch: list[float] = param(
        _table('pitch'), 'ball-screw pitch p per axis', number_list(3, positive), unit='m/rev'
    )
    cart_damping: list[float] = param(
        _table('cart_damping'),
        'guideway damping c_b per axis',
        number_list(3, non_negative),
        unit='N s/m',
    )
    screw_damping: list[float] = param(
        _table('screw_damping'),
        'screw-bearing damping c_t per axis, translational',
        number_list(3, non_negative),
        unit='N s/m',
    )
    coulomb_friction: list[float] = param(
        _table('coulomb_friction'),
        'Coulomb friction mu',
        number_list(3, non_negative),
        unit='N',
    )

    def axis_params(self, axis: int) -> RigidAxisParams:
        """The physical parameters of axis 0/1/2 (x/y/z)."""
        v = self.at(axis)
        return RigidAxisParams(**{f.name: v[f.name] for f in dataclasses.fields(RigidAxisParams)})


class RigidAxisModel(AxisModel):
    """Rigid axis, torque input [N·m]; state [x, x'] [m, m/s]."""

    PARAMS: ClassVar[type[RigidModelParams]] = RigidModelParams
    INPUT_UNIT: ClassVar[str] = 'N·m'
    N_DOF: ClassVar[int] = 1
    FRICTION_DOF: ClassVar[int | None] = 0

    def __init__(
        self, params: RigidModelParams = RigidModelParams(), axis: int = 0, gravity: bool = False
    ) -> None:
        self.params = params.axis_params(axis)
        self.gravity = bool(gravity)
        self.gravity_acceleration = params.gravity_acceleration
        self.coulomb_friction = self.params.coulomb_friction
        self._update()

    def _update(self) -> None:
        p = self.params
        self._inv_lead = 1.0 / p.lead
        self._inv_me = 1.0 / p.effective_mass
        self._ce = p.effective_damping
        self._mu = p.coulomb_friction
        # Chávez-Conde eq. (3): weight m_3 g of the carriage
        self._weight = p.mass * self.gravity_acceleration if self.gravity else 0.0

    def initial_state(self, position: float) -> State:
        return [float(position), 0.0]

    def position(self, state: Sequence[float]) -> float:
        return state[0]

    def velocity(self, state: Sequence[float]) -> float:
        return state[1]

    def add_load(self, mass: float) -> None:
        new = check_mass_change('rigid.mass', self.params.mass, mass)
        self.params = dataclasses.replace(self.params, mass=new)
        self._update()

    def input_gain(self) -> float:
        return self.params.input_gain  # Beltrán 2013 eq. (5): b = 1/(a m_e)

    @property
    def weight(self) -> float:
        """Weight of the carriage along -axis [N] (0 without gravity)."""
        return self._weight

    def derivative(self, state: Sequence[float], u: float, force: float, mode: float) -> State:
        if mode == 0.0:
            return [0.0, 0.0]  # stuck: static friction balances the net force
        v = state[1]
        return [v, self.acceleration(v, self.drive_force(u, mode), force)]

    # The two halves of x'' for a plant that integrates rigid axes on scalars (AxisPlant).
    def drive_force(self, u: float, mode: float) -> float:
        """tau/a - m g - mu·mode [N]: what drives a sliding carriage, constant in a substep."""
        return u * self._inv_lead - self._weight - self._mu * mode

    def acceleration(self, v: float, drive: float, force: float) -> float:
        """x'' [m/s²] of a sliding carriage at velocity v, given drive_force() and F_c."""
        # Chávez-Conde eq. (1)-(3): x'' = (tau/a - m g - mu sign(x') - F_c - c_e x') / m_e
        return self._inv_me * (drive - force - self._ce * v)

    def scalar_terms(self) -> tuple[float, float, float, float, float]:
        """(1/a, m g, mu, 1/m_e, c_e): drive_force = u/a - m g - mu·mode and acceleration =
        (drive - F_c - c_e v)/m_e written out by a plant that integrates on scalars."""
        return (self._inv_lead, self._weight, self._mu, self._inv_me, self._ce)

    def stick_force(self, state: Sequence[float], u: float, force: float) -> float:
        return u * self._inv_lead - self._weight - force

    def disturbance(
        self, state: Sequence[float], u: float, force: float, mode: float, command: float
    ) -> float:
        """Closed form, free of the cancellation in x'' - b·u when b·u is much larger than ξ."""
        if mode == 0.0:
            return -self.input_gain() * command  # stuck: x'' = 0
        # Beltrán 2013 eqs. (6)-(8): ξ = -(c_e x' + mu sign(x') + F_c) / m_e (and -m g / m_e)
        xi = -(self._ce * state[1] + self._mu * mode + force) * self._inv_me
        return xi - self._weight * self._inv_me
