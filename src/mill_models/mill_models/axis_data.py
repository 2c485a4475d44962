"""Nominal data of the rigid ball-screw axis, Beltrán 2013 eq. (1)-(3) and (5), Table 1.

The plant integrates this axis (mill_plant.models.rigid, mill_plant.axis_plant); the
controllers and observers take their nominal input gain b from it (nominal_input_gain),
so it lives in the model layer that every role package imports.

One axis is a cart of mass m driven through a ball screw of inertia J and
pitch p by a torque tau:

    m_e x'' + c_e x' + mu sign(x') = tau / a - F_c        (Beltrán 2013 eq. (1))

Readings of Table 1 (see /work/shared/papers/README.md):

- Table 1 prints the row ``c_b1 = c_b2 = c_b3 = 2.5 N s/m`` twice; the second
  row is the screw-bearing damping c_t.
- J is printed in kg·mm² and is converted here to kg·m² (factor 1e-6).
- mu = 0.3 is a Coulomb friction force in N.
- Eq. (2) reads c_e = c_b + c_t / a². Taken literally with c_t = 2.5 N·m·s/rad
  and a = p / 2π = 5.053e-4 m/rad, c_t / a² = 9.79e6 N·s/m. The plant pole
  c_e / m_e is then at -1.04e5 s⁻¹ (x), -1.39e5 s⁻¹ (y), -1.14e5 s⁻¹ (z), and
  the paper's loop (PD law eq. (9) with w_c = 12 rad/s, zeta_c = 0.7071, plus
  the GPI observer eq. (15) with w_o = p_o = 700 rad/s) has an eigenvalue with
  real part +74 (x), +70 (y), +72 (z) s⁻¹: unstable, unlike the paper's
  figures. We therefore take c_t = 2.5 N·s/m as already translational:
  c_e = c_b + c_t = 5 N·s/m, pole c_e / m_e = -0.053 (x), -0.071 (y),
  -0.058 (z) s⁻¹, and the same closed loop has its slowest eigenvalue at
  -8.49 s⁻¹ (= -zeta_c w_c, the controller poles). Checked with the continuous
  9-state linearisation (plant without friction, observer, controller).

Resulting values: m_e = 94.400 / 70.390 / 86.140 kg and b = 1 / (a m_e) =
20.964 / 28.114 / 22.974 m/(N·m·s²) for x / y / z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class RigidAxisParams:
    """Physical parameters of one rigid ball-screw axis (SI units).

    mass: cart mass m [kg]; screw_inertia: J [kg·m²]; pitch: p [m/rev];
    cart_damping: c_b [N·s/m]; screw_damping: c_t [N·s/m], translational
    (see the module docstring); coulomb_friction: mu [N].
    """

    mass: float
    screw_inertia: float
    pitch: float
    cart_damping: float
    screw_damping: float
    coulomb_friction: float

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ValueError naming the first field that is not physically valid."""
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f'{f.name} must be a number, got {value!r}')
            if not math.isfinite(value):
                raise ValueError(f'{f.name} must be finite, got {value!r}')
        for name in ('mass', 'screw_inertia', 'pitch'):
            if getattr(self, name) <= 0.0:
                raise ValueError(f'{name} must be > 0, got {getattr(self, name)!r}')
        for name in ('cart_damping', 'screw_damping', 'coulomb_friction'):
            if getattr(self, name) < 0.0:
                raise ValueError(f'{name} must be >= 0, got {getattr(self, name)!r}')

    @property
    def lead(self) -> float:
        """a [m/rad]."""
        # Beltrán 2013, text after eq. (2): a = p / 2π, x = a θ
        return self.pitch / (2.0 * math.pi)

    @property
    def effective_mass(self) -> float:
        """m_e [kg]."""
        # Beltrán 2013 eq. (2): m_e = m + J/a^2
        return self.mass + self.screw_inertia / self.lead**2

    @property
    def effective_damping(self) -> float:
        """c_e [N·s/m], with c_t read as translational (module docstring)."""
        # Beltrán 2013 eq. (2): c_e = c_b + c_t/a^2, here c_e = c_b + c_t (c_t already in N·s/m)
        return self.cart_damping + self.screw_damping

    @property
    def input_gain(self) -> float:
        """b [m/(N·m·s²)]: acceleration per unit torque."""
        # Beltrán 2013 eq. (5): b = 1/(a m_e)
        return 1.0 / (self.lead * self.effective_mass)


def _table1_axis(mass: float, inertia_kg_mm2: float) -> RigidAxisParams:
    return RigidAxisParams(
        mass=mass,
        screw_inertia=inertia_kg_mm2 / 1e6,  # exact decimal: 16.249 / 1e6 = 1.6249e-05
        pitch=0.003175,
        cart_damping=2.5,
        screw_damping=2.5,
        coulomb_friction=0.3,
    )


# Beltrán 2013 Table 1: m = 17.551/23.896/22.505 kg, J = 19.623/11.872/16.249 kg·mm²,
# c_b = c_t = 2.5 N·s/m, mu = 0.3 N, p = 0.003175 m.
BELTRAN_TABLE1: dict[str, RigidAxisParams] = {
    'x': _table1_axis(17.551, 19.623),
    'y': _table1_axis(23.896, 11.872),
    'z': _table1_axis(22.505, 16.249),
}


def nominal_input_gain(axis: str) -> float:
    """Input gain b of the Table 1 axis 'x', 'y' or 'z'; ValueError names a bad axis."""
    try:
        return BELTRAN_TABLE1[axis].input_gain
    except KeyError:
        raise ValueError(f'axis must be one of x, y, z, got {axis!r}') from None
