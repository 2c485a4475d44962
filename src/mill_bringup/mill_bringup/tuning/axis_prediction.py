"""One axis of a job run again on its identified structure (ROS-free): what `tune` predicts
for an axis the simulated plant cannot be (a two-mass axis, Stribeck friction, backlash).

The job is first run offline on the rigid machine (mill_bringup.tuning.predict); its record
gives, per axis, the reference (position and speed; the acceleration from the speed) and
the cutting force. The axis is then stepped here with the same controller and observer
loops the nodes build from the tuned parameters, around the identified axis in force units
at the table (lead a, whole mass M = 1/(a·b)):

- a motor side m1 driven by u/a and, for a two-mass axis, a table m2 on the screw
  (stiffness k, damping c; mill_models.frequency_response: m1 = M/(1 + r), m2 = M·r/(1 + r),
  ωr² = k/μ, μ = m1·m2/M), through a gap when identify found backlash;
- an axis with backlash: a motor side and a table (the motor side's share of the mass as
  identify fitted it) in contact through the gap (stiff: CONTACT_HZ, ζ CONTACT_ZETA), the
  friction on the table (the guides), measured where identify measured it (the table when
  it saw the gap from the table alone);
- friction on the motor side (the screw's bearings and nut) for a two-mass axis, on the one
  mass of a rigid one: the Stribeck curve F(v) = sign(v)·(Fc + (Fs − Fc)·e^(−(v/vs)²)) + σ·v
  with sticking (at rest the axis stays while the force on it is within ±Fs);
- the cutting force and the load on the table; the motor side measured, quantised to the
  encoder's resolution; the command held over a period and applied `delay` samples late.

Integration: `SUBSTEPS` semi-implicit Euler steps per period (speeds first), a sliding mass
whose speed changes sign stopped at rest for friction to decide what follows.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from mill_common.signals import AxisReference
from mill_controllers.control_loop import AxisControlLoop
from mill_models.axis_model import TWO_MASS, AxisModel
from mill_models.identification import AxisIdentification
from mill_observers.observer_loop import ObserverLoop

SUBSTEPS = 20
CONTACT_HZ = 300.0  # the closed gap's contact mode
CONTACT_ZETA = 0.5
MOTOR_SHARE = 0.8  # of the mass on the motor side, when identify did not fit it


@dataclass(frozen=True)
class AxisPlant:
    """The identified axis in force units at the table."""

    m1: float  # motor side [kg] (the whole mass when m2 = 0)
    m2: float  # table [kg]; 0: rigid
    k: float  # screw stiffness [N/m]
    c: float  # screw damping [N·s/m]
    coulomb: float  # sliding friction Fc [N]
    static: float  # breakaway friction Fs [N]
    stribeck_speed: float  # vs [m/s]
    viscous: float  # σ [N·s/m]
    load: float  # towards −x [N]
    gap: float  # backlash [m]
    lead: float  # [m/rad]
    resolution: float  # encoder [m]
    delay: int  # [samples]
    friction_on_table: bool = False  # else on the motor side
    measure_table: bool = False  # else the motor side is measured

    @property
    def mass(self) -> float:
        return self.m1 + self.m2

    def friction(self, v: float) -> float:
        """F(v) for v ≠ 0 [N]."""
        level = self.coulomb + (self.static - self.coulomb) * math.exp(
            -((v / self.stribeck_speed) ** 2)
        )
        # Stribeck curve, Olsson et al. 1998 §2 (δ = 2): sign(v)·(Fc + (Fs − Fc)e^(−(v/vs)²)) + σv
        return math.copysign(level, v) + self.viscous * v


def axis_plant(
    structure: AxisModel | None, fit: AxisIdentification, lead: float, delay: int
) -> AxisPlant:
    """The plant for an identified axis: its rigid (or slow) fit with what identify saw."""
    M = 1.0 / (lead * fit.b.value)  # Beltrán 2013 eq. (5): b = 1/(a·M)
    fc = max(0.0, fit.beta.value) * M
    fs, vs = fc, 1e-3
    fr = structure.friction if structure is not None else None
    if fr is not None and fr.present and fr.speed is not None:
        fs, vs = max(fc, fr.static.value * M), fr.speed.value
    m1, m2, k, c = M, 0.0, 0.0, 0.0
    tm = structure.two_mass if structure is not None else None
    if structure is not None and structure.model == TWO_MASS and tm is not None:
        r = tm.mass_ratio.value
        m1, m2 = M / (1.0 + r), M * r / (1.0 + r)
        mu = m1 * m2 / M
        k = tm.omega_r.value**2 * mu  # ωr² = k/μ
        c = 2.0 * tm.zeta.value * tm.omega_r.value * mu  # ζ = c/(2√(kμ))
    bl = structure.backlash if structure is not None else None
    gap = bl.width.value if bl is not None and bl.present else 0.0
    on_table = False
    if gap > 0.0 and m2 == 0.0:
        share = bl.motor_share if bl is not None and math.isfinite(bl.motor_share) else MOTOR_SHARE
        m1, m2 = share * M, (1.0 - share) * M
        mu = m1 * m2 / M
        k = (2.0 * math.pi * CONTACT_HZ) ** 2 * mu  # ω² = k/μ
        c = 2.0 * CONTACT_ZETA * math.sqrt(k * mu)
        on_table = True
    return AxisPlant(
        m1,
        m2,
        k,
        c,
        fc,
        fs,
        vs,
        max(0.0, fit.alpha.value) * M,
        fit.gamma.value * M,
        gap,
        lead,
        fit.resolution,
        delay,
        friction_on_table=on_table,
        measure_table=on_table and bl is not None and bl.source == 'table',
    )


class _References:
    """The recorded reference by sample (the last one after the end)."""

    def __init__(self, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray, period_ns: int):
        self.pos, self.vel, self.acc, self.period_ns = pos, vel, acc, period_ns

    def at(self, ns: int) -> AxisReference:
        k = min(len(self.pos) - 1, max(0, round(ns / self.period_ns)))
        return AxisReference(float(self.pos[k]), float(self.vel[k]), float(self.acc[k]))


@dataclass(frozen=True)
class AxisRun:
    error: np.ndarray  # measured position − reference [m] (NaN after a trip)
    tripped_at: float | None  # [s]
    trip_error: float  # [m]
    trip_limit: float  # [m]


def run_axis(
    plant: AxisPlant,
    observer: ObserverLoop,
    loop: AxisControlLoop,
    reference: np.ndarray,
    reference_velocity: np.ndarray,
    force: np.ndarray,
    T: float,
) -> AxisRun:
    """Step the loop around the plant over the recorded reference and cutting force."""
    n = len(reference)
    acc = np.gradient(reference_velocity, T) if n > 1 else np.zeros(n)
    period_ns = round(T * 1e9)
    refs = _References(reference, reference_velocity, acc, period_ns)
    h = T / SUBSTEPS
    rigid = plant.m2 == 0.0
    half_gap = 0.5 * plant.gap
    x1 = float(reference[0])
    x2 = x1 - (half_gap if not rigid else 0.0)  # the table behind the nut, in contact
    v1 = v2 = 0.0
    q = plant.resolution
    queue: deque[float] = deque([0.0] * plant.delay)
    acted: float | None = None
    error = np.full(n, np.nan)
    if plant.measure_table:
        x1, x2 = x1 + half_gap, x1  # the table at the reference, the nut pushing it +
    for k in range(n):
        seen = x2 if plant.measure_table else x1
        y = round(seen / q) * q if q > 0.0 else seen
        est = observer.step(y, acted)
        cmd = loop.step(k * period_ns, y, est, refs)
        error[k] = y - reference[k]
        if cmd.tripped or not math.isfinite(cmd.effort):
            trip = loop.trip.trip
            return AxisRun(
                error,
                k * T,
                trip.error if trip is not None else math.nan,
                trip.limit if trip is not None else loop.trip.limit,
            )
        acted = cmd.effort
        queue.append(cmd.effort)
        drive = queue.popleft() / plant.lead
        cut = float(force[k]) if math.isfinite(force[k]) else 0.0
        for _ in range(SUBSTEPS):
            if rigid:
                x1, v1 = _slide(plant, x1, v1, drive - cut - plant.load, plant.m1, h)
                continue
            stretch = x1 - x2
            if half_gap > 0.0:
                # the nut pushes the table only once the gap is closed
                over = (
                    stretch - math.copysign(half_gap, stretch) if abs(stretch) > half_gap else 0.0
                )
                spring = plant.k * over + (plant.c * (v1 - v2) if over else 0.0)
            else:
                spring = plant.k * stretch + plant.c * (v1 - v2)
            if plant.friction_on_table:
                v1 += h * (drive - spring) / plant.m1
                x1 += h * v1
                x2, v2 = _slide(plant, x2, v2, spring - cut - plant.load, plant.m2, h)
                continue
            x1, v1 = _slide(plant, x1, v1, drive - spring, plant.m1, h)
            # m2·x2'' = spring − cutting force − load
            v2 += h * (spring - cut - plant.load) / plant.m2
            x2 += h * v2
    return AxisRun(error, None, math.nan, math.nan)


def _slide(p: AxisPlant, x: float, v: float, net: float, m: float, h: float) -> tuple[float, float]:
    """One substep of a mass with friction and sticking under the force `net` [N]."""
    if v == 0.0:
        if abs(net) <= p.static:
            return x, 0.0  # stuck: static friction holds it
        v_new = h * (net - math.copysign(p.static, net)) / m
        return x + h * v_new, v_new
    v_new = v + h * (net - p.friction(v)) / m
    if v_new * v < 0.0:
        v_new = 0.0  # stopped: friction decides at the next substep
    return x + h * v_new, v_new
