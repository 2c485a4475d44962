"""Simulated machines for the identification tests: the machines of issue 32, ROS-free.

One ball-screw axis, in force units at the table (N, kg, m): a motor side of mass m1 (the
motor and screw inertia seen through the lead) driven by the motor's force u/a, and a table
of mass m2 joined to it by the screw (stiffness k, damping c), possibly through a gap
(backlash). With m2 = 0 the axis is one rigid mass. Friction acts on the table (on the one
mass when rigid): Coulomb, static and Stribeck, viscous, with sticking; a constant load
pushes towards −x. The measured position is the motor's or the table's, quantised.

The axis is moved as the identify job moves it (mill_controllers/excitation.py, rewritten
here since a mill_models test cannot import a role package): a soft PD hold on a slow sine,
with an extended-state observer (velocity and lumped disturbance, so that friction and load
are carried), plus a random binary torque of ±acceleration/b_nominal whose bits last 1 to 4
bit periods (1 to 4 samples for short_share of the time), turned against the motion above
max_speed. The command is held over a period
and acts `delay` samples late.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PITCH = 0.003175  # Beltrán 2013 Table 1 [m/rev]
LEAD = PITCH / (2.0 * math.pi)  # [m/rad]


@dataclass(frozen=True)
class Machine:
    motor_mass: float = 94.4  # m1 [kg] (the whole mass when table_mass = 0)
    table_mass: float = 0.0  # m2 [kg]; 0: a rigid axis
    stiffness: float = 0.0  # k of the screw between m1 and m2 [N/m]
    damping: float = 0.0  # c [N·s/m]
    backlash: float = 0.0  # gap between motor side and table [m]
    coulomb: float = 0.3  # sliding friction Fc [N]
    static: float | None = None  # breakaway friction Fs [N] (None: = Fc)
    stribeck_speed: float = 2e-3  # vs [m/s]
    viscous: float = 5.0  # σ [N·s/m]
    load: float = 0.0  # constant force towards −x [N]
    delay: int = 1  # [samples]
    resolution: float = 1e-6  # encoder [m]
    measure: str = 'motor'  # 'motor' or 'table'
    friction_side: str = 'table'  # two masses: the friction on the 'table' (guides) or the
    # 'motor' side (screw bearings and nut); the table then has only its viscous guide_damping
    guide_damping: float = 0.0  # [N·s/m] on the table when the friction is on the motor side

    @property
    def mass(self) -> float:
        return self.motor_mass + self.table_mass

    @property
    def input_gain(self) -> float:
        """b of the whole axis [m/s² per N·m]: 1/(a·M) (Beltrán 2013 eq. (5))."""
        return 1.0 / (LEAD * self.mass)

    def friction(self, v: float) -> float:
        """Sliding friction force at speed v ≠ 0 [N]."""
        fs = self.coulomb if self.static is None else self.static
        # Stribeck curve, Olsson et al. 1998 §2 with δ = 2: F = Fc + (Fs − Fc)·e^(−(v/vs)²) + σv
        level = self.coulomb + (fs - self.coulomb) * math.exp(-((v / self.stribeck_speed) ** 2))
        return math.copysign(level, v) + self.viscous * v

    def resonance(self) -> float:
        """The two-mass axis's resonance [Hz] (motor held free): √(k/μ), μ = m1·m2/M."""
        mu = self.motor_mass * self.table_mass / self.mass
        return math.sqrt(self.stiffness / mu) / (2.0 * math.pi)


def stiffness_for(motor_mass: float, table_mass: float, hz: float) -> float:
    """k that puts the two-mass resonance at hz [N/m]."""
    mu = motor_mass * table_mass / (motor_mass + table_mass)
    return (2.0 * math.pi * hz) ** 2 * mu


@dataclass(frozen=True)
class Excitation:
    acceleration: float = 1.0  # binary torque amplitude as acceleration with nominal b [m/s²]
    bit_period: float = 0.01  # [s]
    short_share: float = 0.15  # of the time in bits of 1-4 samples (0: bit_period alone)
    max_speed: float = 0.05  # [m/s]
    omega_c: float = 30.0  # hold bandwidth [rad/s]
    omega_o: float = 150.0  # observer bandwidth [rad/s]
    sine: float = 0.002  # reference amplitude [m]
    sine_hz: float = 0.5


@dataclass
class Record:
    x: np.ndarray  # measured position (motor or table as the machine says) [m]
    u: np.ndarray  # command [N·m], u[k] answers x[k]
    T: float
    table: np.ndarray  # table position, quantised (a linear scale) [m]
    motor: np.ndarray  # motor-side position, quantised [m]
    excitation: np.ndarray  # the binary part of u [N·m]


def run(
    m: Machine,
    seconds: float = 20.0,
    seed: int = 1,
    T: float = 0.001,
    exc: Excitation | None = None,
    nominal_gain: float | None = None,
    sub: int = 20,
) -> Record:
    """Record the machine under the identify job's law for `seconds`."""
    e = exc or Excitation()
    rng = np.random.default_rng(seed)
    kinds = np.random.default_rng([seed, 1])  # short or long bits: a stream of their own
    b0 = nominal_gain or m.input_gain
    amplitude = e.acceleration / b0  # [N·m]
    n = round(seconds / T)
    h = T / sub
    q = m.resolution
    rigid = m.table_mass == 0.0
    m1 = m.mass if rigid else m.motor_mass
    m2 = m.table_mass
    fs = m.coulomb if m.static is None else m.static
    half_gap = 0.5 * m.backlash
    # state: motor side x1, v1; table x2, v2 (rigid: only x1, v1)
    x1 = v1 = x2 = v2 = 0.0
    if not rigid and m.backlash > 0.0:
        x1 = half_gap  # in contact, pushing +
    # ESO (position, velocity, disturbance), Euler, gains of a triple pole at -omega_o
    xh = vh = dh = 0.0
    wo = e.omega_o
    l1, l2, l3 = 3 * wo, 3 * wo * wo, wo**3
    wc = e.omega_c
    pending = [0.0] * m.delay
    xs, us = np.empty(n), np.empty(n)
    tables, motors, bits = np.empty(n), np.empty(n), np.empty(n)
    bit_len = max(1, round(e.bit_period / T))
    short = e.short_share * bit_len / (e.short_share * bit_len + (1.0 - e.short_share))
    sign, left = 1.0, 0
    u_prev = 0.0
    for k in range(n):
        y1 = round(x1 / q) * q
        y2 = round((x1 if rigid else x2) / q) * q
        y = y2 if m.measure == 'table' else y1
        # observer: correct with y, predict with the command that acted
        err = y - xh
        xh += T * (vh + l1 * err)
        vh += T * (dh + b0 * u_prev + l2 * err)
        dh += T * l3 * err
        t = k * T
        w = 2.0 * math.pi * e.sine_hz
        ref, dref = e.sine * math.sin(w * t), e.sine * w * math.cos(w * t)
        hold = (wc * wc * (ref - xh) + 2.0 * wc * (dref - vh) - dh) / b0
        if left == 0:
            sign = 1.0 if rng.random() < 0.5 else -1.0
            length = int(rng.integers(1, 5))
            left = length * (1 if kinds.random() < short else bit_len)
        left -= 1
        s = -math.copysign(1.0, vh) if abs(vh) > e.max_speed else sign
        u = hold + s * amplitude
        xs[k], us[k], tables[k], motors[k], bits[k] = y, u, y2, y1, s * amplitude
        u_prev = u
        pending.append(u)
        force = pending.pop(0) / LEAD
        for _ in range(sub):
            if rigid:
                x1, v1 = _slide(m, x1, v1, force - m.load, m1, h, fs)
                continue
            # screw between motor side and table, through the gap if there is one
            rel = x1 - x2
            if half_gap > 0.0:
                over = rel - math.copysign(half_gap, rel) if abs(rel) > half_gap else 0.0
                spring = m.stiffness * over + (m.damping * (v1 - v2) if over != 0.0 else 0.0)
            else:
                spring = m.stiffness * rel + m.damping * (v1 - v2)
            if m.friction_side == 'motor':
                x1, v1 = _slide(m, x1, v1, force - spring, m1, h, fs)
                v2 += h * (spring - m.load - m.guide_damping * v2) / m2  # semi-implicit Euler
                x2 += h * v2
            else:
                v1 += h * (force - spring) / m1  # semi-implicit Euler: speeds first
                x1 += h * v1
                x2, v2 = _slide(m, x2, v2, spring - m.load, m2, h, fs)
    return Record(xs, us, T, tables, motors, bits)


def track(
    m: Machine,
    command,  # (k, y) -> u [N·m]: the controller answering the measurement y of sample k
    samples: int,
    T: float,
    cut: np.ndarray | None = None,  # force on the table against +x per sample [N]
    start: float = 0.0,
    sub: int = 20,
) -> np.ndarray:
    """The machine closed by `command` for `samples` periods (a controller of a role package
    is passed in as a function: this module cannot import one); the measured positions.
    The same physics as `run`, with a cutting force on the table (on the one mass when
    rigid)."""
    h = T / sub
    q = m.resolution
    rigid = m.table_mass == 0.0
    m1 = m.mass if rigid else m.motor_mass
    m2 = m.table_mass
    fs = m.coulomb if m.static is None else m.static
    half_gap = 0.5 * m.backlash
    x1 = x2 = start
    v1 = v2 = 0.0
    if not rigid and m.backlash > 0.0:
        x1 = start + half_gap
    pending = [0.0] * m.delay
    ys = np.empty(samples)
    for k in range(samples):
        y1 = round(x1 / q) * q
        y2 = round((x1 if rigid else x2) / q) * q
        y = y2 if m.measure == 'table' else y1
        ys[k] = y
        u = command(k, y)
        if not math.isfinite(u):
            ys[k + 1 :] = math.nan
            break
        pending.append(u)
        force = pending.pop(0) / LEAD
        f_cut = float(cut[k]) if cut is not None and math.isfinite(cut[k]) else 0.0
        for _ in range(sub):
            if rigid:
                x1, v1 = _slide(m, x1, v1, force - f_cut - m.load, m1, h, fs)
                continue
            rel = x1 - x2
            if half_gap > 0.0:
                over = rel - math.copysign(half_gap, rel) if abs(rel) > half_gap else 0.0
                spring = m.stiffness * over + (m.damping * (v1 - v2) if over != 0.0 else 0.0)
            else:
                spring = m.stiffness * rel + m.damping * (v1 - v2)
            table = spring - f_cut - m.load
            if m.friction_side == 'motor':
                x1, v1 = _slide(m, x1, v1, force - spring, m1, h, fs)
                v2 += h * (table - m.guide_damping * v2) / m2
                x2 += h * v2
            else:
                v1 += h * (force - spring) / m1
                x1 += h * v1
                x2, v2 = _slide(m, x2, v2, table, m2, h, fs)
    return ys


def _slide(
    m: Machine, x: float, v: float, drive: float, mass: float, h: float, fs: float
) -> tuple[float, float]:
    """One step h of a mass with friction and sticking under the force `drive` [N]."""
    if v == 0.0:
        if abs(drive) <= fs:
            return x, 0.0  # stuck
        a = (drive - math.copysign(fs, drive)) / mass
        v_new = h * a
        return x + 0.5 * h * v_new, v_new
    a = (drive - m.friction(v)) / mass
    v_new = v + h * a
    if v_new * v < 0.0:
        v_new = 0.0  # stops at the reversal; friction decides what follows
    return x + 0.5 * h * (v + v_new), v_new


# The machines of issue 32 and a rigid one like Beltrán's (Table 1's x, with the existing
# tests' friction scaled up so that it shows).
BELTRAN_X = Machine(motor_mass=94.4, coulomb=20.0, viscous=10.0)
M1 = Machine(motor_mass=94.4, coulomb=70.0, static=120.0, stribeck_speed=2e-3, viscous=25.0)
# the screw's nut with a 15 µm gap to the table, a stiff damped contact (2e8 N/m, ζ ≈ 0.5),
# the guides' friction on the table, measured on the table (a linear scale)
M3_X = Machine(
    motor_mass=76.9,
    table_mass=17.5,
    stiffness=2e8,
    damping=2.0 * 0.5 * math.sqrt(2e8 * 76.9 * 17.5 / 94.4),
    backlash=15e-6,
    coulomb=30.0,
    viscous=10.0,
    measure='table',
)


def two_mass(hz: float, zeta: float = 0.03, **kw: object) -> Machine:
    """M2's axis with its resonance at hz and damping ratio zeta (of the screw alone), the
    friction in the screw's bearings and nut, on the motor side."""
    m1, m2 = float(kw.pop('motor_mass', 76.9)), float(kw.pop('table_mass', 17.5))
    k = stiffness_for(m1, m2, hz)
    mu = m1 * m2 / (m1 + m2)
    c = 2.0 * zeta * math.sqrt(k * mu)  # ζ = c / (2√(k μ))
    args: dict = {'coulomb': 30.0, 'viscous': 10.0, 'friction_side': 'motor', **kw}
    return Machine(motor_mass=m1, table_mass=m2, stiffness=k, damping=c, **args)


# motor and screw (76.9 kg seen at the table) joined to the table (17.5 kg) by the screw
M2_X = two_mass(45.0)
M2_Y = two_mass(70.0, motor_mass=47.0, table_mass=23.9)
