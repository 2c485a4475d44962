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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import param
from mill_common.parameters import non_negative, number_list, positive

from mill_plant.models.base import AxisModel, AxisModelParams, State


@dataclass(frozen=True)
class VelocityDriveParams(AxisModelParams):
    """Hatwesh 2013 Table 1 per axis x, y, z (X, Y; Z = Y)."""

    PREFIX: ClassVar[str] = 'velocity_drive'
    amplifier_gain: list[float] = param(
        [15.7311] * 3, 'amplifier gain K_a per axis', number_list(3, positive), unit='A/V'
    )
    torque_constant: list[float] = param(
        [1.39] * 3, 'motor torque constant K_t per axis', number_list(3, positive), unit='N m/A'
    )
    damping: list[float] = param(
        [14e-4] * 3, 'viscous damping B per axis', number_list(3, non_negative), unit='kg m^2/s'
    )
    inertia: list[float] = param(
        [2.8828e-3, 3.8028e-3, 3.8028e-3],
        'inertia J reflected on the motor shaft per axis [kg m^2] (z = y, our choice)',
        number_list(3, positive),
    )
    pitch: list[float] = param(
        [0.012] * 3, 'ball-screw pitch h_p per axis', number_list(3, positive), unit='m/rev'
    )
    carried_mass: list[float] = param(
        [100.0] * 3,
        'table + workpiece mass whose weight loads an axis built with gravity [kg] '
        '(not in the paper)',
        number_list(3, non_negative),
    )


class VelocityDriveAxisModel(AxisModel):
    """Hatwesh 2013 feed drive, voltage input [V]; state [θ, ω] [rad, rad/s]."""

    PARAMS: ClassVar[type[VelocityDriveParams]] = VelocityDriveParams
    INPUT_UNIT: ClassVar[str] = 'V'
    N_DOF: ClassVar[int] = 1
    FRICTION_DOF: ClassVar[int | None] = None

    def __init__(
        self,
        params: VelocityDriveParams = VelocityDriveParams(),
        axis: int = 0,
        gravity: bool = False,
    ) -> None:
        v = params.at(axis)
        # Hatwesh eq. (2): torque per volt K_t K_a
        self.torque_per_volt = v['torque_constant'] * v['amplifier_gain']
        self.damping = v['damping']
        self.inertia = v['inertia']  # grows with add_load
        self.lead = v['pitch'] / (2.0 * math.pi)  # r_g = h_p/2π (eq. (1))
        self.carried_mass = v['carried_mass']  # grows with add_load
        self.gravity = bool(gravity)
        self.gravity_acceleration = params.gravity_acceleration
        self._update()

    def _update(self) -> None:
        self._inv_j = 1.0 / self.inertia
        weight = self.carried_mass * self.gravity_acceleration if self.gravity else 0.0
        self._load_torque = self.lead * weight  # r_g m g

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
