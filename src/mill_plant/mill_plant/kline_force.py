"""Quasi-static Kline end-milling force model, Beltrán 2013 eq. (4).

Readings (see also /work/shared/papers/README.md):

- Specific cutting energy u_s: the paper prints "0.5 kW/cm³/min" for soft
  steel. Read literally (0.5 kW·min/cm³) that is 3.0e10 J/m³, about ten times
  a realistic value; 0.5 hp·min/in³ = 1.37e9 J/m³ is the realistic reading and
  the default here. It is a constructor parameter (specific_energy).
- Feed per tooth (the chip): the paper gives f = 0.001 m in the force section
  and 0.05 mm/tooth at 3 mm/s, 1800 rpm, 2 teeth in the trajectory section; we
  take 0.05 mm/tooth, the set that is mutually consistent. The chip a tooth
  removes is the material the previous tooth left: the feed-per-tooth vector
  is the x-y path since the previous tooth passed the same angle,
  Δ = p_xy(t) − p_xy(t − T_z) with the tooth period T_z = 60/(N n_t)
  (1/60 s here), f = |Δ|, and Δ/|Δ| is the feed direction. Whose path, is
  the parameter chip:
  * 'programmed' (the paper's quasi-static assumption): the programmed path
    (`program`, straight segments at `program_feed_rate` from t = 0, as the
    linear trajectory of eq. (19)-(22)), so f = 0.05 mm along the programmed
    direction at 3 mm/s whatever the tool does;
  * 'tool': the tool's own path, from the states the plant accepted
    (`commit`), interpolated by a cubic Hermite polynomial in position and
    velocity; before the first committed state the tool was at rest there.
    This adds to the programmed chip the tool's displacement since the
    previous tooth, the regenerative effect: a force F ∝ p(t) − p(t − T_z),
    whose stiffness u_s d_a/2 ≈ 3.4e6 N/m dwarfs the PD law's m_e ω_c² ≈ 1e4
    N/m, so eq. (9) without compensation chatters and diverges, while with
    the observer's compensation the tool follows the program and the force is
    the programmed one.
  Either way the chip is set by a path between tooth passes, not by the
  instantaneous speed |v_xy|: the tool's velocity ripple at the tooth-passing
  frequency and its harmonics (60, 120, ... Hz) integrates to zero over T_z.
  A path that has not moved for T_z removes no chip: no force.
- Depth of cut d_a: the paper holds it constant ("the cutting depth in z axis
  direction is a constant value", 5 mm). depth 'programmed' (the paper's
  assumption) takes d_a = workpiece_top − z of the program; 'tool' takes the
  tool's depth d_a = workpiece_top − z, so that F_z, which pushes the tool in,
  deepens the cut that makes it (a loop the paper does not have; with eq. (9)
  without compensation its gain dF_z/dd_a over the PD stiffness m_e ω_c² is
  about 1.05 and the depth runs away).
- Frame: eq. (4) gives the forces in the cutter's frame whose local y is the
  feed direction. With d = Δ / |Δ| the unit feed direction and
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
  v_0 < v_i < v_m. No force when the tool centre is outside the workpiece x-y
  box or not below its top.

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

import bisect
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParameterError,
    in_range,
    number,
    number_list,
    one_of,
    positive,
    whole_in,
)

from mill_plant.cutting import CuttingForceModel, Force3

_TWO_PI = 2.0 * math.pi
PATHS = ('programmed', 'tool')  # whose path sets the chip and the depth (module docstring)
# The paper's job (the linear trajectory's default): x = -0.075 m, 80 mm in +y, 80 mm in +x,
# 5 mm below the top, at 3 mm/s.
BELTRAN_PROGRAM = ((-0.075, -0.105, -0.005), (-0.075, -0.025, -0.005), (0.005, -0.025, -0.005))
BELTRAN_FEED_RATE = 0.003
# Instants whose time-only parts of the force are kept (a handful are asked again).
_CACHED_TIMES = 16


class ProgrammedPath:
    """Straight segments between waypoints at a constant feed rate from t = 0 (eq. (19)-(22))."""

    def __init__(self, waypoints: Sequence[Sequence[float]], feed_rate: float) -> None:
        if len(waypoints) < 2 or any(len(p) != 3 for p in waypoints):
            raise ValueError('program must hold at least two finite points (x, y, z)')
        points = [(float(p[0]), float(p[1]), float(p[2])) for p in waypoints]
        if not all(math.isfinite(v) for p in points for v in p):
            raise ValueError('program must hold at least two finite points (x, y, z)')
        if isinstance(feed_rate, bool) or not (
            isinstance(feed_rate, int | float) and math.isfinite(feed_rate) and feed_rate > 0.0
        ):
            raise ValueError(f'program_feed_rate must be > 0, got {feed_rate!r}')
        self.points = points
        self._starts = [0.0]
        for a, b in itertools.pairwise(points):
            length = math.dist(a, b)
            if length == 0.0:
                raise ValueError('program must not repeat a point (zero-length segment)')
            self._starts.append(self._starts[-1] + length / float(feed_rate))

    def position(self, t: float) -> tuple[float, float, float]:
        """The programmed tool position at time t [s]: first point before 0, last after the end."""
        if t <= 0.0:
            return self.points[0]
        if t >= self._starts[-1]:
            return self.points[-1]
        i = bisect.bisect_right(self._starts, t) - 1
        a, b = self.points[i], self.points[i + 1]
        s = (t - self._starts[i]) / (self._starts[i + 1] - self._starts[i])
        return (a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]))


def _program(value: Any) -> str | None:
    reason = number_list()(value)
    if reason:
        return reason
    if len(value) < 6 or len(value) % 3:
        return 'must list at least two points x, y, z (a multiple of 3 numbers)'
    return None


@dataclass(frozen=True)
class KlineParams(ParamSet):
    """Beltrán 2013 eq. (4) and the workpiece; the spindle speed in rpm, the angle in degrees."""

    PREFIX: ClassVar[str] = 'kline'
    specific_energy: float = param(
        1.37e9, 'u_s, energy per removed volume [J/m^3] (0.5 hp min/in^3)', positive
    )
    spindle_speed: float = param(1800.0, 'spindle speed N', positive, unit='rpm')
    teeth: int = param(2, 'cutter teeth n_t', whole_in(1, 100))
    tool_diameter: float = param(0.010, 'cutter diameter D', positive, unit='m')
    radial_depth: float = param(0.010, 'radial depth of cut b [m] (b = D: slot)', positive)
    helix_angle: float = param(45.0, 'cutting-edge angle lambda', in_range(0, 89), unit='deg')
    workpiece_min: list[float] = param(
        [-0.1, -0.12], 'workpiece corner x, y', number_list(2), unit='m'
    )
    workpiece_max: list[float] = param(
        [0.03, 0.0], 'workpiece corner x, y', number_list(2), unit='m'
    )
    workpiece_top: float = param(0.0, 'z of the workpiece top surface', number, unit='m')
    chip: str = param(
        'tool',
        "whose x-y path since the previous tooth is the chip: 'programmed' = "
        "kline.program's (Beltrán 2013's quasi-static assumption), 'tool' = the tool's",
        one_of(*PATHS),
    )
    depth: str = param(
        'tool',
        "depth of cut d_a = workpiece_top - z: 'programmed' = z of kline.program "
        "(Beltrán 2013's constant depth), 'tool' = the tool's z",
        one_of(*PATHS),
    )
    program: list[float] = param(
        [v for p in BELTRAN_PROGRAM for v in p],
        "the programmed path for 'programmed' chip or depth: corners x0, y0, z0, x1, "
        '... [m], straight segments from t = 0 (as trajectory linear.waypoints)',
        _program,
    )
    program_feed_rate: float = param(
        BELTRAN_FEED_RATE,
        'speed along kline.program [m/s] (as trajectory linear.feed_rate)',
        positive,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.radial_depth <= self.tool_diameter:
            raise ParameterError(
                'kline.radial_depth',
                self.radial_depth,
                f'must be in (0, tool_diameter={self.tool_diameter}]',
            )
        low, high = self.workpiece_min, self.workpiece_max
        if not (low[0] < high[0] and low[1] < high[1]):
            raise ParameterError(
                'kline.workpiece_min', low, f'must be below workpiece_max {high!r}'
            )


class KlineCuttingForce(CuttingForceModel):
    """Kline quasi-static cutting force (Beltrán 2013 eq. (4)) on a box-shaped workpiece.

    With chip 'tool' the chip depends on the tool's path: the plant that integrates the tool
    tells the model every state it accepts (`commit`, in increasing time; PATH_DEPENDENT is
    then True on the instance). One model belongs to one plant.
    """

    PARAMS: ClassVar[type[KlineParams]] = KlineParams
    PATH_DEPENDENT: ClassVar[bool] = True
    # k_r of the radial and axial forces (Beltrán 2013 eq. (4)), not a parameter
    RADIAL_RATIO: ClassVar[float] = 0.3

    def __init__(self, params: KlineParams = KlineParams()) -> None:
        self.specific_energy = params.specific_energy
        self.spindle_speed_rpm = params.spindle_speed
        teeth = self.teeth = params.teeth
        self.tool_diameter = params.tool_diameter
        self.radial_depth = params.radial_depth
        self.helix_angle = math.radians(params.helix_angle)  # degrees on the node
        self.radial_ratio = self.RADIAL_RATIO
        self.workpiece_min = (params.workpiece_min[0], params.workpiece_min[1])
        self.workpiece_max = (params.workpiece_max[0], params.workpiece_max[1])
        self.workpiece_top = params.workpiece_top
        chip = self.chip = params.chip
        depth = self.depth = params.depth
        flat = params.program
        program = [flat[i : i + 3] for i in range(0, len(flat), 3)]
        try:
            self.program = ProgrammedPath(program, params.program_feed_rate)
        except ValueError as e:
            raise ParameterError('kline.program', flat, str(e)) from None

        # Beltrán 2013 eq. (4): v_m = acos(1 - 2b/D), the exit angle; entry v_0 = 0
        self.exit_angle = math.acos(1.0 - 2.0 * self.radial_depth / self.tool_diameter)
        self._omega = _TWO_PI * self.spindle_speed_rpm / 60.0  # spindle speed [rad/s]
        self._offsets = tuple(_TWO_PI * i / teeth for i in range(teeth))
        # The previous tooth passed the same angle one tooth period T_z = 60/(N n_t) ago.
        self.tooth_period = 60.0 / (teeth * self.spindle_speed_rpm)
        self._axial = self.radial_ratio * math.tan(self.helix_angle)
        self._programmed_chip = chip == 'programmed'
        self._programmed_depth = depth == 'programmed'
        # Only the tool's chip reads the tool's past path: with the programmed chip the plant
        # need not tell this model its states (4 commits a sample saved; nothing else reads
        # them).
        self.PATH_DEPENDENT = not self._programmed_chip  # type: ignore[misc]
        # The accepted tool states (t, x, y, v_x, v_y), oldest first, back to 2 T_z ago.
        self._t: list[float] = []
        self._path: list[tuple[float, float, float, float]] = []
        # What depends on t alone, by t (the plant asks the same instant several times: RK4's
        # two midpoint stages, a substep's end and the next one's start, the measurement):
        # the teeth's sums (s1, s2, sc), and with the programmed chip and depth, the feed and
        # the depth. Computed once per t by the same expressions: the same bits.
        self._sums: dict[float, tuple[float, float, float]] = {}
        self._programmed: dict[float, tuple[float, float, float]] = {}

    def feed_per_tooth(self, feed_speed: float) -> float:
        """f [m/tooth] at a steady x-y feed speed [m/s]: the path of one tooth period."""
        return abs(feed_speed) * self.tooth_period

    def tooth_angles(self, t: float) -> tuple[float, ...]:
        """Rotation angle v_i in [0, 2π) of each tooth at time t [s]."""
        base = self._omega * t
        return tuple((base + off) % _TWO_PI for off in self._offsets)

    # ---- the tool's path ---------------------------------------------------------

    def commit(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> None:
        """The plant accepted this tool state at time t [s]; times must not decrease.

        A second state at the time of the last one replaces it (a plant that sets its
        initial state again). ValueError if time goes backwards: one model per plant.
        """
        times = self._t
        entry = (float(position[0]), float(position[1]), float(velocity[0]), float(velocity[1]))
        if times and t <= times[-1]:
            if t < times[-1]:
                raise ValueError(
                    f'KlineCuttingForce.commit: time went backwards ({times[-1]} -> {t}); '
                    'a path-dependent force model belongs to one plant'
                )
            self._path[-1] = entry
            return
        times.append(float(t))
        self._path.append(entry)
        # Forces are asked for at t or later, so the past before t - T_z is no longer needed:
        # keep one state before t - 2 T_z.
        horizon = t - 2.0 * self.tooth_period
        if len(times) > 2 and times[1] < horizon:
            drop = bisect.bisect_left(times, horizon) - 1
            del times[:drop]
            del self._path[:drop]

    def past_position(self, t: float) -> tuple[float, float]:
        """The tool's x-y position at time t [s] from the committed states.

        Cubic Hermite between the two states around t; before the first state, that
        state's position (the tool was at rest there); after the last, the last one.
        """
        times, path = self._t, self._path
        if not times:
            raise ValueError('KlineCuttingForce: no committed tool state (call commit first)')
        j = bisect.bisect_right(times, t)
        if j == 0:
            return path[0][0], path[0][1]
        if j == len(times):
            return path[-1][0], path[-1][1]
        t0, t1 = times[j - 1], times[j]
        x0, y0, u0, w0 = path[j - 1]
        x1, y1, u1, w1 = path[j]
        h = t1 - t0
        s = (t - t0) / h
        s2 = s * s
        s3 = s2 * s
        h00 = 2.0 * s3 - 3.0 * s2 + 1.0
        h10 = (s3 - 2.0 * s2 + s) * h
        h01 = 3.0 * s2 - 2.0 * s3
        h11 = (s3 - s2) * h
        return (
            h00 * x0 + h10 * u0 + h01 * x1 + h11 * u1,
            h00 * y0 + h10 * w0 + h01 * y1 + h11 * w1,
        )

    # ---- the force -------------------------------------------------------------------

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        """Eq. (4) at time t [s] for the tool at `position`; the chip and the depth come from
        the programmed or the tool's path (module docstring). velocity is not used."""
        if self._programmed_chip and self._programmed_depth:
            # _outside written out (the plant asks 18 times a sample)
            x = position[0]
            y = position[1]
            top = self.workpiece_top
            lo = self.workpiece_min
            hi = self.workpiece_max
            if position[2] >= top or x < lo[0] or x > hi[0] or y < lo[1] or y > hi[1]:
                return (0.0, 0.0, 0.0)
            known = self._programmed.get(t)
            if known is None:
                if len(self._programmed) > _CACHED_TIMES:
                    self._programmed.clear()
                now = self.program.position(t)
                past = self.program.position(t - self.tooth_period)
                known = self._programmed[t] = self._local_force(
                    t, now[0] - past[0], now[1] - past[1], top - now[2]
                )
            return known
        if self._programmed_chip:
            now = self.program.position(t)
            past = self.program.position(t - self.tooth_period)
            feed = (now[0] - past[0], now[1] - past[1])
        else:
            px, py = self.past_position(t - self.tooth_period)
            feed = (position[0] - px, position[1] - py)
        if self._programmed_depth:
            depth = self.workpiece_top - self.program.position(t)[2]
        else:
            depth = self.workpiece_top - position[2]
        return self.chip_force(t, position, feed, depth)

    def _teeth(self, t: float) -> tuple[float, float, float]:
        """(sum sin v_i, sum sin^2 v_i, sum sin v_i cos v_i) over the teeth in cut at t."""
        sums = self._sums.get(t)
        if sums is not None:
            return sums
        if len(self._sums) > _CACHED_TIMES:
            self._sums.clear()
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
        sums = self._sums[t] = (s1, s2, sc)
        return sums

    def chip_force(
        self, t: float, position: Sequence[float], feed: Sequence[float], depth: float
    ) -> Force3:
        """Eq. (4) with the feed-per-tooth vector `feed` (x, y) [m] (f = |feed|, along it)
        and the depth of cut d_a = depth [m], for the tool at `position` (no force outside
        the workpiece box, above its top, or for d_a <= 0)."""
        if self._outside(position):
            return (0.0, 0.0, 0.0)
        return self._local_force(t, feed[0], feed[1], depth)

    def _outside(self, position: Sequence[float]) -> bool:
        """The tool centre outside the workpiece's x-y box or not below its top."""
        x = position[0]
        y = position[1]
        lo = self.workpiece_min
        hi = self.workpiece_max
        return position[2] >= self.workpiece_top or x < lo[0] or x > hi[0] or y < lo[1] or y > hi[1]

    def _local_force(self, t: float, fx: float, fy: float, depth: float) -> Force3:
        """Eq. (4) in the machine frame for the tool inside the workpiece (chip_force)."""
        if depth <= 0.0 or (fx == 0.0 and fy == 0.0):
            return (0.0, 0.0, 0.0)
        s1, s2, sc = self._teeth(t)
        if s1 == 0.0:
            return (0.0, 0.0, 0.0)
        f = math.hypot(fx, fy)
        # Beltrán 2013 eq. (4): u_s d_a f, common factor of all components
        k = self.specific_energy * depth * f
        r = self.radial_ratio
        # Beltrán 2013 eq. (4): F_x = u_s d_a f sum(0.3 sin^2 v + sin v cos v) (local x)
        f_lx = k * (r * s2 + sc)
        # Beltrán 2013 eq. (4): F_y = u_s d_a f sum(sin^2 v - 0.3 sin v cos v) (local y = feed)
        f_ly = k * (s2 - r * sc)
        # Beltrán 2013 eq. (4): F_z = 0.3 sum(F_t,i) tan(lambda), F_t,i = u_s d_a f sin v_i
        f_z = self._axial * k * s1
        # Rotate local (x, y) = (n, d) into the machine frame, n = (d_y, -d_x).
        dx = fx / f
        dy = fy / f
        return (f_lx * dy + f_ly * dx, f_ly * dy - f_lx * dx, f_z)
