"""Quasi-static Kline end-milling force model, Beltrán 2013 eq. (4).

Readings (see also /work/shared/papers/README.md):

- Specific cutting energy u_s: the paper prints "0.5 kW/cm³/min" for soft
  steel. Read literally (0.5 kW·min/cm³) that is 3.0e10 J/m³, about ten times
  a realistic value; 0.5 hp·min/in³ = 1.37e9 J/m³ is the realistic reading and
  the default here. It is a constructor parameter (specific_energy).
- Feed per tooth: the paper gives f = 0.001 m in the force section and
  0.05 mm/tooth at 3 mm/s, 1800 rpm, 2 teeth in the trajectory section. Here f
  follows the actual x-y feed velocity of the tool, f = |v_xy| / (n_t N / 60),
  so 3 mm/s gives the consistent 0.05 mm, there is no force at rest, and the
  force is continuous in the velocity.
- Frame: eq. (4) gives the forces in the cutter's frame whose local y is the
  feed direction. With d = v_xy / |v_xy| the unit feed direction and
  n = (d_y, -d_x), the machine-frame force is F_lx n + F_ly d (a proper
  rotation: feed +y gives (F_lx, F_ly); feed +x gives (F_ly, -F_lx)). The mean
  feed-direction force is then positive along the feed, i.e. it resists the
  motion under the eq. (1) convention tau/a - F_c.
- The single ratio 0.3 of eq. (4) (radial_ratio) is used in all three places
  where eq. (4) prints it, including F_z = 0.3 sum(F_t,i) tan(lambda); F_z is
  summed over the teeth in cut and is positive, so under eq. (1) it pushes the
  z axis towards -z (into the workpiece).
- Engagement: entry angle v_0 = 0, exit angle v_m = acos(1 - 2b/D) (eq. 4);
  tooth i is at v_i = (2π N/60 t + 2π i/n_t) mod 2π and cuts while
  v_0 < v_i < v_m. Depth of cut d_a = max(0, workpiece_top - z); no force when
  the tool centre is outside the workpiece x-y box or above its top.

Numbers with the defaults (slotting b = D = 10 mm, 2 teeth, 1800 rpm,
lambda = 45°, u_s = 1.37e9 J/m³) at a 3 mm/s feed (f = 0.05 mm) and
d_a = 5 mm, so u_s d_a f = 342.5 N. For 2-tooth slotting exactly one tooth is
in cut, and since sin²v and sin v cos v have period π, F_lx and F_ly are
smooth in time; F_z ∝ |sin| has a kink at each tooth entry (120 Hz).
  feed-direction force F_ly: mean 171.25 N (0.5 K), peak 350.0 N, min -7.5 N
  normal force F_lx:         mean  51.38 N (0.15 K), peak 230.2 N, min -127.4 N
  axial force F_z:           mean  65.42 N (0.6 K/π), peak 102.75 N, min 0 N
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import (
    ParamSpec,
    in_range,
    number,
    number_list,
    positive,
    positive_int,
    validate_all,
)

from mill_plant.cutting import CuttingForceModel, Force3

_TWO_PI = 2.0 * math.pi


class KlineCuttingForce(CuttingForceModel):
    """Kline quasi-static cutting force (Beltrán 2013 eq. (4)) on a box-shaped workpiece."""

    PREFIX: ClassVar[str] = 'kline'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            'specific_energy',
            1.37e9,
            'u_s, energy per removed volume [J/m^3] (0.5 hp min/in^3)',
            positive,
        ),
        ParamSpec('spindle_speed', 1800.0, 'spindle speed N [rpm]', positive),
        ParamSpec('teeth', 2, 'cutter teeth n_t', positive_int),
        ParamSpec('tool_diameter', 0.010, 'cutter diameter D [m]', positive),
        ParamSpec('radial_depth', 0.010, 'radial depth of cut b [m] (b = D: slot)', positive),
        ParamSpec('helix_angle', 45.0, 'cutting-edge angle lambda [deg]', in_range(0, 89)),
        ParamSpec('workpiece_min', [-0.1, -0.12], 'workpiece corner x, y [m]', number_list(2)),
        ParamSpec('workpiece_max', [0.03, 0.0], 'workpiece corner x, y [m]', number_list(2)),
        ParamSpec('workpiece_top', 0.0, 'z of the workpiece top surface [m]', number),
    )

    def __init__(
        self,
        *,
        specific_energy: float = 1.37e9,
        spindle_speed_rpm: float = 1800.0,
        teeth: int = 2,
        tool_diameter: float = 0.010,
        radial_depth: float = 0.010,
        helix_angle: float = math.radians(45.0),
        radial_ratio: float = 0.3,
        workpiece_min: Sequence[float] = (-0.1, -0.12),
        workpiece_max: Sequence[float] = (0.03, 0.0),
        workpiece_top: float = 0.0,
    ) -> None:
        def finite(name: str, value: float) -> float:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f'{name} must be a number, got {value!r}')
            if not math.isfinite(value):
                raise ValueError(f'{name} must be finite, got {value!r}')
            return float(value)

        self.specific_energy = finite('specific_energy', specific_energy)
        if self.specific_energy < 0.0:
            raise ValueError(f'specific_energy must be >= 0, got {specific_energy!r}')
        self.spindle_speed_rpm = finite('spindle_speed_rpm', spindle_speed_rpm)
        if self.spindle_speed_rpm <= 0.0:
            raise ValueError(f'spindle_speed_rpm must be > 0, got {spindle_speed_rpm!r}')
        if isinstance(teeth, bool) or not isinstance(teeth, int) or teeth < 1:
            raise ValueError(f'teeth must be a whole number >= 1, got {teeth!r}')
        self.teeth = teeth
        self.tool_diameter = finite('tool_diameter', tool_diameter)
        if self.tool_diameter <= 0.0:
            raise ValueError(f'tool_diameter must be > 0, got {tool_diameter!r}')
        self.radial_depth = finite('radial_depth', radial_depth)
        if not 0.0 < self.radial_depth <= self.tool_diameter:
            raise ValueError(
                f'radial_depth must be in (0, tool_diameter={self.tool_diameter}], '
                f'got {radial_depth!r}'
            )
        self.helix_angle = finite('helix_angle', helix_angle)
        if not 0.0 <= self.helix_angle < 0.5 * math.pi:
            raise ValueError(f'helix_angle must be in [0, pi/2) rad, got {helix_angle!r}')
        self.radial_ratio = finite('radial_ratio', radial_ratio)
        if self.radial_ratio < 0.0:
            raise ValueError(f'radial_ratio must be >= 0, got {radial_ratio!r}')
        for name, corner in (('workpiece_min', workpiece_min), ('workpiece_max', workpiece_max)):
            if len(corner) != 2:
                raise ValueError(f'{name} must be (x, y), got {corner!r}')
            for value in corner:
                finite(name, value)
        self.workpiece_min = (float(workpiece_min[0]), float(workpiece_min[1]))
        self.workpiece_max = (float(workpiece_max[0]), float(workpiece_max[1]))
        if not (
            self.workpiece_min[0] < self.workpiece_max[0]
            and self.workpiece_min[1] < self.workpiece_max[1]
        ):
            raise ValueError(
                f'workpiece_min {workpiece_min!r} must be below workpiece_max {workpiece_max!r}'
            )
        self.workpiece_top = finite('workpiece_top', workpiece_top)

        # Beltrán 2013 eq. (4): v_m = acos(1 - 2b/D), the exit angle; entry v_0 = 0
        self.exit_angle = math.acos(1.0 - 2.0 * self.radial_depth / self.tool_diameter)
        self._omega = _TWO_PI * self.spindle_speed_rpm / 60.0  # spindle speed [rad/s]
        self._offsets = tuple(_TWO_PI * i / teeth for i in range(teeth))
        # f = |v_xy| / (n_t N/60), so u_s f = u_s |v_xy| * 60/(n_t N): fold the constants once
        self._energy_per_speed = self.specific_energy * 60.0 / (teeth * self.spindle_speed_rpm)
        self._axial = self.radial_ratio * math.tan(self.helix_angle)

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> KlineCuttingForce:
        """From PARAMETERS (spindle speed in rpm, helix angle in degrees)."""
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        return cls(
            specific_energy=v['specific_energy'],
            spindle_speed_rpm=v['spindle_speed'],
            teeth=v['teeth'],
            tool_diameter=v['tool_diameter'],
            radial_depth=v['radial_depth'],
            helix_angle=math.radians(v['helix_angle']),
            workpiece_min=tuple(v['workpiece_min']),
            workpiece_max=tuple(v['workpiece_max']),
            workpiece_top=v['workpiece_top'],
        )

    def feed_per_tooth(self, feed_speed: float) -> float:
        """f [m/tooth] at an x-y feed speed [m/s]."""
        return abs(feed_speed) * 60.0 / (self.teeth * self.spindle_speed_rpm)

    def tooth_angles(self, t: float) -> tuple[float, ...]:
        """Rotation angle v_i in [0, 2π) of each tooth at time t [s]."""
        base = self._omega * t
        return tuple((base + off) % _TWO_PI for off in self._offsets)

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        x = position[0]
        y = position[1]
        depth = self.workpiece_top - position[2]
        vx = velocity[0]
        vy = velocity[1]
        lo = self.workpiece_min
        hi = self.workpiece_max
        if (
            depth <= 0.0
            or x < lo[0]
            or x > hi[0]
            or y < lo[1]
            or y > hi[1]
            or (vx == 0.0 and vy == 0.0)
        ):
            return (0.0, 0.0, 0.0)
        speed = math.hypot(vx, vy)
        # Beltrán 2013 eq. (4): u_s d_a f, common factor of all components
        k = self._energy_per_speed * depth * speed
        exit_angle = self.exit_angle
        base = self._omega * t
        s2 = 0.0  # sum of sin^2 v_i over teeth in cut
        sc = 0.0  # sum of sin v_i cos v_i
        s1 = 0.0  # sum of sin v_i
        for off in self._offsets:
            v = (base + off) % _TWO_PI
            if 0.0 < v < exit_angle:
                s = math.sin(v)
                s1 += s
                s2 += s * s
                sc += s * math.cos(v)
        if s1 == 0.0:
            return (0.0, 0.0, 0.0)
        r = self.radial_ratio
        # Beltrán 2013 eq. (4): F_x = u_s d_a f sum(0.3 sin^2 v + sin v cos v) (local x)
        f_lx = k * (r * s2 + sc)
        # Beltrán 2013 eq. (4): F_y = u_s d_a f sum(sin^2 v - 0.3 sin v cos v) (local y = feed)
        f_ly = k * (s2 - r * sc)
        # Beltrán 2013 eq. (4): F_z = 0.3 sum(F_t,i) tan(lambda), F_t,i = u_s d_a f sin v_i
        f_z = self._axial * k * s1
        # Rotate local (x, y) = (n, d) into the machine frame, n = (d_y, -d_x).
        dx = vx / speed
        dy = vy / speed
        return (f_lx * dy + f_ly * dx, f_ly * dy - f_lx * dx, f_z)
