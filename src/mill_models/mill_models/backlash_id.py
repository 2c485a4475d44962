"""Backlash of an axis from its record (ROS-free).

Two cases:

- A second measurement, the table's (a linear scale) beside the motor's: the lost motion
  is direct. While the motor pushes the table one way, motor − table sits at one side of
  the gap; pushing the other way, at the other side. The backlash is the difference of the
  medians of motor − table over the two directions of steady motion (`lost_motion`), its
  interval from the spread over the stretches of motion (95 %, t quantile ≈ 2).

- Only the table's position: after each reversal of the motor's torque the motor crosses the
  gap alone while the table, no longer driven, runs on its own friction (the axis "does not
  move for a while then jumps" when it closes). `estimate_backlash` simulates every torque
  reversal of the record with the rigid fit's gain, delay, friction and load and a gap g
  between a motor side (mass share r of the whole) and the table, with the friction and the
  load on the table (the guides; a vertical axis's weight), plastic contact (the two sides
  move together once the gap closes); for a grid of (g, r) the simulated table positions are
  compared with the measured ones (least squares, each reversal's start position and speed
  free, as in the rigid fit). The best g with its interval (the reversals resampled, 95 %)
  is the estimate; "no backlash" when the interval reaches 0.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from mill_models.identification import AxisIdentification, Interval


@dataclass(frozen=True)
class BacklashSettings:
    before: int = 5  # samples simulated before the torque reverses
    after: float = 0.03  # simulated after it [s]
    settled: float = 0.01  # the torque kept its sign at least this long before [s]
    max_reversals: int = 80  # used (evenly spread over the record)
    min_reversals: int = 10
    sub: int = 10  # integration steps per sample
    gaps: tuple[float, ...] = tuple(np.arange(0.0, 40.5e-6, 1e-6))  # tried [m]
    shares: tuple[float, ...] = (0.5, 0.6, 0.7, 0.8, 0.9)  # motor side's share of the mass
    resamples: int = 200
    min_gap: float = 2.0  # × the encoder's resolution: smaller is not called backlash


@dataclass(frozen=True)
class Backlash:
    width: Interval  # the gap [m]
    reversals: int  # used
    present: bool
    reason: str  # one line
    motor_share: float = math.nan  # m1/M that fitted best (table-side estimate only)
    source: str = 'table'  # 'table' (one measurement) or 'two encoders'

    def as_dict(self) -> dict[str, float | int | bool | str]:
        return {
            'width': self.width.value,
            'width_ci': self.width.half_width,
            'reversals': self.reversals,
            'present': self.present,
            'source': self.source,
            'reason': self.reason,
        }


def lost_motion(
    motor: np.ndarray, table: np.ndarray, T: float, min_speed: float = 2e-3
) -> Backlash:
    """The gap from the motor's and the table's positions recorded together."""
    motor, table = np.asarray(motor, float), np.asarray(table, float)
    n_smooth = max(5, 2 * round(0.005 / T) + 1)
    kernel = np.ones(n_smooth) / n_smooth
    v = np.convolve(np.gradient(motor, T), kernel, mode='same')
    direction = np.where(np.abs(v) > min_speed, np.sign(v), 0.0)
    gap = motor - table
    # stretches of one direction, each giving its median of motor − table
    edges = np.flatnonzero(np.diff(direction)) + 1
    bounds = np.concatenate([[0], edges, [len(gap)]])
    levels: dict[float, list[float]] = {1.0: [], -1.0: []}
    for a, e in itertools.pairwise(bounds):
        if direction[a] != 0.0 and e - a >= n_smooth:
            levels[float(direction[a])].append(float(np.median(gap[a:e])))
    plus, minus = np.asarray(levels[1.0]), np.asarray(levels[-1.0])
    if len(plus) < 3 or len(minus) < 3:
        return Backlash(
            Interval(math.nan, math.nan),
            0,
            False,
            'too few stretches of motion each way to measure the lost motion',
            source='two encoders',
        )
    width = float(np.median(plus) - np.median(minus))
    # 95 % of the difference of two means (spread of the stretches), the medians' stand-in
    half = 2.0 * math.hypot(
        plus.std(ddof=1) / math.sqrt(len(plus)), minus.std(ddof=1) / math.sqrt(len(minus))
    )
    resolution = max(_resolution(table), _resolution(motor))
    half = max(half, resolution)  # the medians are of quantised differences
    present = bool(width - half > 2.0 * resolution)
    n = min(len(plus), len(minus))
    reason = (
        f'{1e6 * width:.3g} µm of backlash at reversals (motor − table, {n} reversals)'
        if present
        else f'no backlash: the lost motion {1e6 * width:.2g} ± {1e6 * half:.2g} µm is within '
        f"the encoders' resolution"
    )
    return Backlash(Interval(width, half), n, present, reason, source='two encoders')


def _resolution(x: np.ndarray) -> float:
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-12]
    return float(steps.min()) if steps.size else 0.0


def torque_reversals(u: np.ndarray, T: float, s: BacklashSettings) -> list[int]:
    """Samples where the command changes sign after keeping it at least `settled`."""
    sign = np.sign(u)
    changes = np.flatnonzero(sign[1:] * sign[:-1] < 0.0) + 1
    settled = max(1, round(s.settled / T))
    out, last = [], -settled
    for k in changes:
        if k - last >= settled:
            out.append(int(k))
        last = int(k)
    return out


def estimate_backlash(
    x: np.ndarray,
    u: np.ndarray,
    m: AxisIdentification,
    settings: BacklashSettings | None = None,
) -> Backlash:
    """The gap seen from the table's position alone, given the rigid fit m (module doc)."""
    s = settings or BacklashSettings()
    x, u = np.asarray(x, float), np.asarray(u, float)
    T, d = m.sample_period, m.delay
    post = round(s.after / T)
    b, gamma = m.b.value, m.gamma.value
    force = np.full(len(u), np.nan)
    force[d:] = b * u[: len(u) - d]  # the motor's push, as the acceleration of the whole axis
    found = [
        k
        for k in torque_reversals(force[d:], T, s)
        if k + d - s.before >= 2 and k + d + post <= len(x)
    ]
    found = [k + d for k in found]
    if len(found) < s.min_reversals:
        return Backlash(
            Interval(0.0, math.nan),
            len(found),
            False,
            f'too few torque reversals ({len(found)}) to look for backlash',
        )
    if len(found) > s.max_reversals:
        pick = np.linspace(0, len(found) - 1, s.max_reversals).round().astype(int)
        found = [found[i] for i in pick]
    n_seg, length = len(found), s.before + post
    meas = np.empty((n_seg, length))
    push = np.empty((n_seg, length))
    v0 = np.empty(n_seg)
    for i, k in enumerate(found):
        a = k - s.before
        meas[i] = x[a : a + length] - x[a]
        push[i] = force[a : a + length]
        v0[i] = (x[a + 1] - x[a - 2]) / (3.0 * T)  # moved on by the line projected out below
    t = np.arange(length) * T
    q, _ = np.linalg.qr(np.column_stack([np.ones(length), t]))
    gaps, shares = np.asarray(s.gaps), np.asarray(s.shares)
    grid_g, grid_r = (a.ravel() for a in np.meshgrid(gaps, shares, indexing='ij'))
    sim = _simulate(push, v0, T, s.sub, grid_g, grid_r, m.alpha.value, m.beta.value, gamma)
    r = meas[None] - sim
    r = r - (r @ q) @ q.T  # each reversal's own start position and speed
    cost = (r**2).sum(axis=2).reshape(len(gaps), len(shares), n_seg)
    per_gap = cost.min(axis=1)  # the best share at each gap, per reversal
    total = per_gap.sum(axis=1)
    best = int(np.argmin(total))
    rng = np.random.default_rng(0)
    picks = rng.integers(0, n_seg, size=(s.resamples, n_seg))
    boot = np.argmin(per_gap[:, picks].sum(axis=2), axis=0)
    lo, hi = np.quantile(gaps[boot], [0.025, 0.975])
    step = 0.5 * (gaps[1] - gaps[0])
    width = Interval(float(gaps[best]), float(max(step, gaps[best] - lo, hi - gaps[best])))
    share = float(shares[int(np.argmin(cost[best].sum(axis=1)))])
    small = s.min_gap * m.resolution
    present = bool(lo > 0.0 and width.value >= small)
    reason = (
        f'{1e6 * width.value:.3g} µm of backlash at reversals (± {1e6 * width.half_width:.2g} '
        f'µm, {n_seg} torque reversals)'
        if present
        else f'no backlash: the gap fitted to {n_seg} torque reversals is '
        f'{1e6 * width.value:.2g} ± {1e6 * width.half_width:.2g} µm'
    )
    return Backlash(width, n_seg, present, reason, share)


def _simulate(
    push: np.ndarray,
    v0: np.ndarray,
    T: float,
    sub: int,
    gap: np.ndarray,
    share: np.ndarray,
    alpha: float,
    beta: float,
    gamma: float,
) -> np.ndarray:
    """Table positions (grid point, reversal, sample) of the axis with a gap, from contact
    on the side the motor pushed before (accelerations per unit of the whole mass)."""
    n_seg, length = push.shape
    shape = (len(gap), n_seg)
    g = np.broadcast_to(gap[:, None], shape)
    r = np.broadcast_to(share[:, None], shape)
    side = np.broadcast_to(np.sign(push[:, 0]), shape).copy()  # +1/−1 in contact, 0 apart
    x2 = np.zeros(shape)
    v2 = np.broadcast_to(v0, shape).copy()
    rel = side * 0.5 * g  # motor − table
    v_rel = np.zeros(shape)
    h = T / sub
    out = np.empty((len(gap), n_seg, length))
    for k in range(length):
        out[:, :, k] = x2
        f = push[:, k]
        for _ in range(sub):
            # in contact: one rigid axis, friction and load on the table
            moving = v2 != 0.0
            drive = f - gamma
            stuck = ~moving & (np.abs(drive) <= beta)
            a_common = np.where(
                stuck,
                0.0,
                drive - alpha * v2 - beta * np.where(moving, np.sign(v2), np.sign(drive)),
            )
            # the contact pushes the table while the motor's force exceeds what the motor
            # side needs for the common acceleration: N = f − r·a
            held = (side != 0.0) & (side * (f - r * a_common) > 0.0)
            # apart: the motor side under its force alone, the table under friction and load
            a_motor = f / r
            table_drive = -gamma
            t_stuck = ~moving & (abs(table_drive) <= beta)
            a_table = np.where(
                t_stuck,
                0.0,
                (
                    table_drive
                    - alpha * v2
                    - beta * np.where(moving, np.sign(v2), np.sign(table_drive))
                )
                / (1.0 - r),
            )
            a2 = np.where(held, a_common, a_table)
            v2_new = v2 + h * a2
            v2_new = np.where(moving & (v2_new * v2 < 0.0), 0.0, v2_new)
            x2 = x2 + 0.5 * h * (v2 + v2_new)
            v_rel = np.where(held, 0.0, v_rel + h * (a_motor - a2))
            rel = np.where(held, rel, rel + h * v_rel)
            side = np.where(held, side, 0.0)
            # the gap closes: plastic contact, both sides at the momentum-weighted speed
            closing = ~held & (np.abs(rel) >= 0.5 * g) & (v_rel * rel >= 0.0) & (v_rel != 0.0)
            v_common = v2_new + r * v_rel
            v2 = np.where(closing, v_common, v2_new)
            v_rel = np.where(closing, 0.0, v_rel)
            direction = np.where(rel != 0.0, np.sign(rel), np.sign(v_rel))
            rel = np.where(closing, direction * 0.5 * g, rel)
            side = np.where(closing, direction, side)
    return out
