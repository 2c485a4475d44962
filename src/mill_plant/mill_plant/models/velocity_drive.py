"""Ball-screw feed drive of Hatwesh 2013 eq. (1)-(6): voltage → amplifier → torque → inertia.

    T_m = K_t K_a u                                     eq. (2)
    J ω' = T_m - B ω - T_d                              eq. (3)
    x' = r_g ω,  r_g = h_p/2π                           eq. (1)
    J += (m_t + m_w) r_g²  for a carried mass           eq. (4)

State [θ, ω] (motor = screw angle [rad] and speed [rad/s]); table position x = r_g θ.

Readings:

- eq. (1) writes X = r_g/s · ω; r_g is read as the lead h_p/2π (direct drive, gear
  ratio 1 in eq. (6)), as the suite's Hatwesh tests do.
- The disturbance torque T_d of eq. (3) is the cutting force on the table seen on the
  screw, T_d = r_g F_c (sign of mill_plant.cutting: positive F_c resists +x motion),
  plus, on a vertical axis, the weight r_g (m + Δm) g.
- Table 1 lists only the X and Y axes; Z takes the Y values (our choice).
- carried_mass (table + workpiece mass) is not in Table 1 (J already includes it); it is
  used only for the weight on an axis built with gravity. Default 100 kg (our choice; its
  reflected inertia 100 r_g² = 3.6e-4 kg·m² is ~10 % of J).
- No Coulomb friction (the paper's model has none; B is viscous).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import Check, ParamSpec, non_negative, number_list, positive

from mill_plant.models.base import GRAVITY_SPEC, STANDARD_GRAVITY, AxisModel, State, validated


def _three(name: str, default: list[float], description: str, check: Check) -> ParamSpec:
    return ParamSpec(name, default, description, number_list(3, check))


class VelocityDriveAxisModel(AxisModel):
    """Hatwesh 2013 feed drive, voltage input [V]; state [θ, ω] [rad, rad/s]."""

    INPUT_UNIT: ClassVar[str] = 'V'
    PREFIX: ClassVar[str] = 'velocity_drive'
    N_DOF: ClassVar[int] = 1
    FRICTION_DOF: ClassVar[int | None] = None
    # Hatwesh 2013 Table 1 (X, Y; Z = Y)
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        _three('amplifier_gain', [15.7311] * 3, 'amplifier gain K_a per axis [A/V]', positive),
        _three(
            'torque_constant', [1.39] * 3, 'motor torque constant K_t per axis [N m/A]', positive
        ),
        _three('damping', [14e-4] * 3, 'viscous damping B per axis [kg m^2/s]', non_negative),
        _three(
            'inertia',
            [2.8828e-3, 3.8028e-3, 3.8028e-3],
            'inertia J reflected on the motor shaft per axis [kg m^2] (z = y, our choice)',
            positive,
        ),
        _three('pitch', [0.012] * 3, 'ball-screw pitch h_p per axis [m/rev]', positive),
        _three(
            'carried_mass',
            [100.0] * 3,
            'table + workpiece mass whose weight loads an axis built with gravity [kg] '
            '(not in the paper)',
            non_negative,
        ),
        GRAVITY_SPEC,
    )

    def __init__(
        self,
        amplifier_gain: float = 15.7311,
        torque_constant: float = 1.39,
        damping: float = 14e-4,
        inertia: float = 2.8828e-3,
        pitch: float = 0.012,
        carried_mass: float = 100.0,
        gravity_acceleration: float = STANDARD_GRAVITY,
        gravity: bool = False,
    ) -> None:
        for name, value, positive_required in (
            ('amplifier_gain', amplifier_gain, True),
            ('torque_constant', torque_constant, True),
            ('damping', damping, False),
            ('inertia', inertia, True),
            ('pitch', pitch, True),
            ('carried_mass', carried_mass, False),
            ('gravity_acceleration', gravity_acceleration, False),
        ):
            reason = (positive if positive_required else non_negative)(value)
            if reason:
                raise ValueError(f'{name} {reason}, got {value!r}')
        # Hatwesh eq. (2): torque per volt K_t K_a
        self.torque_per_volt = float(torque_constant) * float(amplifier_gain)
        self.damping = float(damping)
        self.inertia = float(inertia)
        self.lead = float(pitch) / (2.0 * math.pi)  # r_g = h_p/2π (eq. (1))
        self.carried_mass = float(carried_mass)
        self.gravity = bool(gravity)
        self.gravity_acceleration = float(gravity_acceleration)
        self._update()

    def _update(self) -> None:
        self._inv_j = 1.0 / self.inertia
        weight = self.carried_mass * self.gravity_acceleration if self.gravity else 0.0
        self._load_torque = self.lead * weight  # r_g m g

    @classmethod
    def from_parameters(
        cls, axis: int, values: Mapping[str, Any], gravity: bool = False
    ) -> VelocityDriveAxisModel:
        return cls(**validated(cls, axis, values), gravity=gravity)

    def initial_state(self, position: float) -> State:
        return [float(position) / self.lead, 0.0]

    def position(self, state: Sequence[float]) -> float:
        return self.lead * state[0]  # Hatwesh eq. (1): x = r_g θ

    def velocity(self, state: Sequence[float]) -> float:
        return self.lead * state[1]

    def add_load(self, mass: float) -> None:
        carried = self.carried_mass + float(mass)
        # Hatwesh eq. (4): a mass Δm on the table adds Δm r_g² to J
        inertia = self.inertia + float(mass) * self.lead * self.lead
        if not (math.isfinite(carried) and carried >= 0.0 and inertia > 0.0):
            raise ValueError(
                f'velocity_drive.carried_mass: {self.carried_mass!r} + {mass!r} kg must stay >= 0'
            )
        self.carried_mass = carried
        self.inertia = inertia
        self._update()

    def input_gain(self) -> float:
        return self.lead * self.torque_per_volt / self.inertia  # r_g K_t K_a / J

    def steady_speed(self, u: float, force: float = 0.0) -> float:
        """Steady table speed [m/s] at constant voltage and force (eq. (3), ω' = 0, B > 0)."""
        return (
            self.lead
            * (self.torque_per_volt * u - self._load_torque - self.lead * force)
            / (self.damping)
        )

    def derivative(self, state: Sequence[float], u: float, force: float, mode: float) -> State:
        w = state[1]
        # Hatwesh eq. (2)-(3): J ω' = K_t K_a u - B ω - T_d,  T_d = r_g (F_c + m g)
        acc = self._inv_j * (
            self.torque_per_volt * u - self.damping * w - self.lead * force - self._load_torque
        )
        return [w, acc]
