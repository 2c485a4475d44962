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
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import Check, ParamSpec, non_negative, number_list, positive
from mill_models.axis_data import BELTRAN_TABLE1, RigidAxisParams

from mill_plant.models.base import (
    GRAVITY_SPEC,
    STANDARD_GRAVITY,
    AxisModel,
    State,
    check_mass_change,
    validated,
)


def _table(field: str) -> list[float]:
    return [float(getattr(BELTRAN_TABLE1[a], field)) for a in 'xyz']


def _three(name: str, field: str, description: str, check: Check) -> ParamSpec:
    return ParamSpec(name, _table(field), description, number_list(3, check))


class RigidAxisModel(AxisModel):
    """Rigid axis, torque input [N·m]; state [x, x'] [m, m/s]."""

    INPUT_UNIT: ClassVar[str] = 'N·m'
    PREFIX: ClassVar[str] = 'rigid'
    N_DOF: ClassVar[int] = 1
    FRICTION_DOF: ClassVar[int | None] = 0
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        _three('mass', 'mass', 'carriage mass m per axis x, y, z [kg]', positive),
        _three(
            'screw_inertia', 'screw_inertia', 'ball-screw inertia J per axis [kg m^2]', positive
        ),
        _three('pitch', 'pitch', 'ball-screw pitch p per axis [m/rev]', positive),
        _three(
            'cart_damping', 'cart_damping', 'guideway damping c_b per axis [N s/m]', non_negative
        ),
        _three(
            'screw_damping',
            'screw_damping',
            'screw-bearing damping c_t per axis, translational [N s/m]',
            non_negative,
        ),
        _three('coulomb_friction', 'coulomb_friction', 'Coulomb friction mu [N]', non_negative),
        GRAVITY_SPEC,
    )

    def __init__(
        self,
        params: RigidAxisParams,
        gravity: bool = False,
        gravity_acceleration: float = STANDARD_GRAVITY,
    ) -> None:
        params.validate()
        self.params = params
        self.gravity = bool(gravity)
        self.gravity_acceleration = float(gravity_acceleration)
        self.coulomb_friction = params.coulomb_friction
        self._update()

    def _update(self) -> None:
        p = self.params
        self._inv_lead = 1.0 / p.lead
        self._inv_me = 1.0 / p.effective_mass
        self._ce = p.effective_damping
        self._mu = p.coulomb_friction
        # Chávez-Conde eq. (3): weight m_3 g of the carriage
        self._weight = p.mass * self.gravity_acceleration if self.gravity else 0.0

    @classmethod
    def from_parameters(
        cls, axis: int, values: Mapping[str, Any], gravity: bool = False
    ) -> RigidAxisModel:
        v = validated(cls, axis, values)
        g = v.pop('gravity_acceleration')
        return cls(RigidAxisParams(**v), gravity, g)

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
