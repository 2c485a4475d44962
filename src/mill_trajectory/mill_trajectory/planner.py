"""Feed planner: straight pieces to a jerk-limited reference with blended corners. ROS-free.

The input is a chain of straight pieces (arcs come as chords, mill_trajectory.toolpath), each
with a speed cap (the programmed feed), and rests (dwell, stop). On the sharp timeline piece
k is travelled at a constant velocity V_k = u_k·d_k for τ_k = L_k/u_k; at each junction j
(the sharp path reaches corner C_j at t_j) the velocity changes by ΔV_j = V_b − V_a in a
transition of duration T_j centred on t_j. The planned velocity is the sum of the blended
steps, whether transitions overlap or not (a moving average of the sharp velocity with a
kernel of local length T, as FIR / "smoothed look-ahead" planners do):

    v(t) = V_0 + Σ_j ΔV_j s(x_j),  s(x) = 10x³ − 15x⁴ + 6x⁵,  x_j = (t − t_j)/T_j + 1/2 ∈ [0, 1]

s is symmetric, so each transition's position error ΔV_j·T_j·E(x_j) (E(x) = ∫₀ˣ s − max(0,
x − 1/2), at most 5/64 at x = 1/2) vanishes once it ends: the planned path takes the sharp
path's time. Per axis, then:

- velocity: if |T_a − T_b| ≤ 2τ_k around every piece k (enforced by shortening the longer
  transition toward the shorter, and where it may not, lengthening the shorter), the window
  starts and ends are in order and v(t) is a convex combination of the pieces' velocities,
  each within the axis limit and the feed: guaranteed, any program;
- acceleration Σ ΔV_j s'(x_j)/T_j and jerk Σ ΔV_j s''(x_j)/T_j² are continuous. A transition
  that overlaps no other peaks at 15/8·|ΔV_i|/T and (10/√3)·|ΔV_i|/T²: T ≥ the shortest
  transition for ΔV (transition_times) keeps it within the limits; it leaves the corner by
  (5/64)|ΔV|T at most, kept within the tolerance;
- where transitions overlap (on curves and fine polylines, longer transitions on purpose:
  T ≈ √(56·δ/κ)/u on a curvature κ leaves a circle by δ, and the corners' jerk averages out)
  the sums are polynomials between the windows' boundaries: they are evaluated between
  every two boundaries at points close enough that a bound on the next derivative
  (Σ 60|ΔV_i|/T³ for the acceleration, Σ 360|ΔV_i|/T⁴ for the jerk) adds at most 1 % of the
  limit. The distance to the pieces the sharp path runs on within the windows (the path
  tolerance, LinuxCNC G64 P) is measured at the same points, plus what the motion between
  two points can add: the acceleration bound·step²/8, and a chord cutting a corner of turn
  |Δd| by its length·|Δd|/4 (an estimate, not a bound, for chords longer than the pieces);
  a single transition in an interval counts as it does alone. A check that fails slows the
  pieces under it by the factor it asks for (acceleration ∝ u², jerk ∝ u³), or lengthens
  its transitions (if the tolerance has room: the sums fall as T grows), or shortens them
  (deviation); the checks are repeated until none fails.

Look-ahead: the whole chain is planned before it runs. Speeds start at their caps (the feed,
each axis's velocity limit along the piece's direction); a sharp corner's speed is computed
directly, the fastest at which its own transition meets the tolerance, and a curve's (a
junction turning by |d_b − d_a| < GENTLE, κ = |d_b − d_a| over the mean length of its
pieces) at CURVE_SHARE of min(√(A/κ), (J/κ²)^⅓). Speeds then ramp between these: u² changes
from piece to piece by at most 2·a·(the distance between their middles), running minima
forwards and backwards, with a the share of the acceleration a curve leaves (u²κ of the
acceleration and u³κ² of the jerk taken, and speeding up by a_t adding 3·u·a_t·κ to the
jerk). A straight piece slowed by a corner at one of its ends is cut there, if the rest
holds the ramps up to its cap: a short piece runs at the corner's speed and the rest at the
feed, so that the corner slows only its neighbourhood; a piece slow at one end only (an
arc's first chord after a sharp corner) is cut there too if the corner piece takes at most
half of it, so that the rest ramps on into the pieces after it. The start and end are junctions with
rest; an acceleration or jerk limit of inf is no limit (with both inf, the velocity steps at
each corner, as the straight cuts of Beltrán 2013 eq. (19)-(22), and pieces are not cut).

The spindle (signed speed [rev/min], None: not programmed) is a piece's; it changes only at
a rest (mill_trajectory.gcode), and rests of different spindles are not merged. A sample
takes the spindle of the segment it is in, and in a transition that of the segment it
leaves: the spindle changes when the axes have come to rest.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mill_trajectory.base import Trajectory, TrajectorySample

Point = tuple[float, float, float]


def xyz(values: Sequence[float]) -> Point:
    """Three numbers as a point."""
    return (float(values[0]), float(values[1]), float(values[2]))


_ZERO: Point = (0.0, 0.0, 0.0)
DEVIATION = 5.0 / 64.0  # max |∫ s − step| over a transition, per |ΔV|·T
PEAK_ACCELERATION = 15.0 / 8.0  # max s'
PEAK_JERK = 10.0 / math.sqrt(3.0)  # max |s''|
SNAP = 60.0  # max |s'''|
CRACKLE = 360.0  # max |s''''|
CURVE = 56.0  # a circle averaged over T shrinks by u²T²/(56 r): the kernel's variance T²/28
DEVIATION_SHARE = 0.8  # of the tolerance a curve's transitions are sized for
RAMP_SHARE = 0.5  # of the acceleration the look-ahead ramps speeds with
GENTLE = 0.2  # |d_b − d_a| below this: a junction of a curve
CURVE_SHARE = 0.97  # of a curve's limit speed it starts at
MARGIN = 0.01  # share of a limit the sampling margin may take
MAX_POINTS = 256  # per interval between window boundaries
SAFETY = 0.995  # a slowed piece goes this much below what its check asks
MAX_PASSES = 400
PATIENCE = 20  # slowings of a piece before its steps are at least STUBBORN
STUBBORN = 0.97
MAX_STRETCH = 8.0  # a transition lengthened at most this many times its shortest
LONE_CUT = 0.5  # a piece slow at one end is cut there if its corner piece takes at most this
PARALLEL = 1e-12  # |d_a − d_b| below this: the same direction
ZERO_LENGTH = 1e-12  # [m]: a shorter move is no move


@dataclass(frozen=True)
class Limits:
    """Per-axis limits (x, y, z) and the path tolerance at corners [m]."""

    velocity: Point  # [m/s], > 0
    acceleration: Point  # [m/s²], inf = no limit
    jerk: Point  # [m/s³], inf = no limit
    tolerance: float  # [m], > 0

    def scaled(self, override: float, reserve: float = 0.0) -> Limits:
        """Limits that a feed override up to `override` cannot push past (v·o, a·o², j·o³),
        with a share `reserve` of acceleration and jerk left for the override's changes."""
        o, keep = float(override), 1.0 - reserve
        return Limits(
            tuple(v / o for v in self.velocity),  # type: ignore[arg-type]
            tuple(keep * a / o**2 for a in self.acceleration),  # type: ignore[arg-type]
            tuple(keep * j / o**3 for j in self.jerk),  # type: ignore[arg-type]
            self.tolerance,
        )


@dataclass(frozen=True)
class Piece:
    """A straight move start -> end at most at `speed` [m/s], or a rest of `dwell` [s].

    `sag` [m]: how far the piece itself may be from the programmed path (an arc's chord: its
    sagitta); its transitions keep within the tolerance less that."""

    start: Point
    end: Point
    speed: float = math.inf  # inf: as fast as the axes allow (a rapid)
    dwell: float = 0.0  # rest only
    rest: bool = False
    spindle: float | None = None  # [rev/min], signed; None: not programmed
    sag: float = 0.0


def transition_times(dv: np.ndarray, limits: Limits) -> np.ndarray:
    """Shortest transition T [s] for each velocity change ΔV (rows) within the limits."""
    adv = np.abs(dv)
    acc = np.asarray(limits.acceleration, dtype=float)
    jerk = np.asarray(limits.jerk, dtype=float)
    t_acc = PEAK_ACCELERATION * adv / acc
    t_jerk = np.sqrt(PEAK_JERK * adv / jerk)
    return np.maximum(t_acc, t_jerk).max(axis=1) if len(adv) else np.zeros(0)


# The kernel: s, its integral less the step (the position error), and its derivatives.
def _lag(x: np.ndarray) -> np.ndarray:
    return x**4 * (2.5 - 3.0 * x + x * x) - np.maximum(x - 0.5, 0.0)


def _step(x: np.ndarray) -> np.ndarray:
    return x**3 * (10.0 - 15.0 * x + 6.0 * x * x) - (x >= 0.5)


def _ds(x: np.ndarray) -> np.ndarray:
    return 30.0 * (x * (1.0 - x)) ** 2


def _dds(x: np.ndarray) -> np.ndarray:
    return 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)


class _Profile:
    """Sharp segments and the transitions between them: the planned motion at any times."""

    def __init__(
        self,
        start: np.ndarray,  # (n, 3) the sharp path's point when segment i starts
        end: np.ndarray,  # (n, 3) and ends
        velocity: np.ndarray,  # (n, 3)
        duration: np.ndarray,  # (n,)
        T: np.ndarray,  # (n − 1,) transition into segment i + 1
        speed: np.ndarray | None = None,  # (n,) planned [m/s]
    ) -> None:
        self.start, self.end, self.velocity, self.duration = start, end, velocity, duration
        self.speed = np.linalg.norm(velocity, axis=1) if speed is None else speed
        self.T = T
        ends = np.cumsum(duration)
        self.starts = np.concatenate(([0.0], ends[:-1]))
        self.end_time = float(ends[-1]) if len(ends) else 0.0
        self.tj = self.starts[1:]
        self.dv = velocity[1:] - velocity[:-1]
        self.ws = self.tj - 0.5 * T
        self.we = self.tj + 0.5 * T

    def active(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Transitions lo..hi − 1 under way at each time (windows are in order)."""
        lo = np.searchsorted(self.we, ts, side='right')
        hi = np.searchsorted(self.ws, ts, side='right')
        return lo, np.maximum(hi, lo)

    def at(self, ts: np.ndarray, jerks: bool = True) -> tuple[np.ndarray, ...]:
        """Position, velocity, acceleration, jerk (m, 3) at times ts; and lo, hi."""
        n = len(self.duration)
        i = np.clip(np.searchsorted(self.starts, ts, side='right') - 1, 0, n - 1)
        tau = ts - self.starts[i]
        pos = self.start[i] + self.velocity[i] * tau[:, None]
        vel = self.velocity[i].copy()
        acc = np.zeros_like(pos)
        jerk = np.zeros_like(pos)
        lo, hi = self.active(ts)
        count = hi - lo
        total = int(count.sum())
        if total:
            which = np.repeat(np.arange(len(ts)), count)
            first = np.repeat(np.cumsum(count) - count, count)
            j = np.repeat(lo, count) + np.arange(total) - first
            T = self.T[j]
            x = (ts[which] - self.tj[j]) / T + 0.5
            dv = self.dv[j]
            m = len(ts)
            terms = [(pos, T * _lag(x)), (vel, _step(x)), (acc, _ds(x) / T)]
            if jerks:
                terms.append((jerk, _dds(x) / (T * T)))
            for out, f in terms:
                for k in range(3):
                    out[:, k] += np.bincount(which, weights=dv[:, k] * f, minlength=m)
        return pos, vel, acc, jerk, lo, hi


class PlannedPath(Trajectory):
    """The planned reference (see the module doc): sample(t) for any t."""

    PREFIX = 'planned'

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> PlannedPath:
        raise NotImplementedError('a planned path is built by plan()')

    def __init__(
        self,
        profile: _Profile | None,
        spindles: list[float | None],
        end: Point,
        sources: list[int] | None = None,
    ) -> None:
        self._profile = profile
        self._spindles = spindles
        n = len(spindles)
        # Per segment: the index of the input piece it comes from (-1: the rest before the
        # start or after the end).
        self.sources = sources if sources is not None else [-1] * n
        self.end_point = end
        if profile is None or n == 0:
            self._starts: list[float] = []
            self._corners: list[float] = []
            self.end_time = 0.0
            self.start_point = end
            return
        self._starts = profile.starts.tolist()
        self._p = profile.start.tolist()
        self._v = profile.velocity.tolist()
        self._corners = [0.0, *profile.T.tolist()]
        self._ws = profile.ws.tolist()
        self._we = profile.we.tolist()
        self.end_time = profile.end_time
        self.start_point = xyz(self._p[0])

    def piece_times(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """For each of the `count` input pieces: its time on the sharp timeline [s] (the
        blended path takes the same time: each transition is centred on its corner) and its
        planned speed [m/s] (the blended path reaches it where the piece's transitions do
        not overlap; on a curve of short pieces it runs a little below); 0 and 0 for a
        dropped (zero-length) piece, a rest's time is its dwell."""
        time, speed = np.zeros(count), np.zeros(count)
        if self._profile is None:
            return time, speed
        src = np.asarray(self.sources, dtype=int)
        v = self._profile.speed
        keep = (src >= 0) & (v > 0.0)
        np.add.at(time, src[keep], self._profile.duration[keep])
        np.maximum.at(speed, src[keep], v[keep])
        return time, speed

    def piece_starts(self, pieces: Sequence[Piece]) -> list[float]:
        """For each of the planned input pieces, when it begins [s]: a move, where the sharp
        path begins it; a rest, the instant the reference has come to rest for it (after
        the dwells of the rests before it that it was merged with, which the reference
        keeps exactly still through); a dropped (zero-length) move, where the next begins."""
        n = len(pieces)
        out = [self.end_time] * n
        if self._profile is None:
            return out
        speed = self._profile.speed.tolist()
        src = self.sources
        for s, j in enumerate(src):
            if j < 0 or (s > 0 and src[s - 1] == j):  # the path's own rests; a cut's rest
                continue
            if speed[s] > 0.0:
                out[j] = self._starts[s]
                continue
            t = self._starts[s] + 0.5 * self._corners[s]
            following = next((k for k in src[s + 1 :] if k >= 0), n)
            for i in range(j, following):  # the rests merged into this one
                out[i] = t
                t += pieces[i].dwell if pieces[i].rest else 0.0
        for i in range(n - 2, -1, -1):  # dropped moves: where the next piece begins
            if not pieces[i].rest and math.dist(pieces[i].start, pieces[i].end) <= ZERO_LENGTH:
                out[i] = out[i + 1]
        return out

    @property
    def transitions(self) -> list[float]:
        """Duration of each junction's transition [s], the start's and the end's included."""
        return list(self._corners)

    def sample(self, t: float) -> TrajectorySample:
        if self._profile is None:
            return TrajectorySample(self.end_point, _ZERO, _ZERO)
        if t <= 0.0:
            return TrajectorySample(self.start_point, _ZERO, _ZERO, self._spindles[0])
        if t >= self.end_time:
            return TrajectorySample(self.end_point, _ZERO, _ZERO, self._spindles[-1])
        lo = bisect.bisect_right(self._we, t)
        hi = bisect.bisect_right(self._ws, t)
        i = bisect.bisect_right(self._starts, t) - 1
        if hi > lo:  # transitions under way: the one begun first sets the spindle
            if hi - lo > 8:
                p, v, a, _, _, _ = self._profile.at(np.array([t]), jerks=False)
                return TrajectorySample(xyz(p[0]), xyz(v[0]), xyz(a[0]), self._spindles[lo])
            return self._blend(i, t, lo, hi)
        tau = t - self._starts[i]
        p, v = self._p[i], self._v[i]
        # Beltrán 2013 eq. (19)-(22) between transitions: p(t) = p_i + v (t − t_i)
        return TrajectorySample(
            (p[0] + v[0] * tau, p[1] + v[1] * tau, p[2] + v[2] * tau),
            (v[0], v[1], v[2]),
            _ZERO,
            self._spindles[i],
        )

    def _blend(self, i: int, t: float, lo: int, hi: int) -> TrajectorySample:
        """The sharp segment i plus transitions lo..hi − 1 (into segments lo + 1..hi)."""
        tau = t - self._starts[i]
        p0, v0 = self._p[i], self._v[i]
        pos = [p0[k] + v0[k] * tau for k in range(3)]
        vel = list(v0)
        acc = [0.0, 0.0, 0.0]
        for j in range(lo, hi):
            T = self._corners[j + 1]
            x = (t - self._starts[j + 1]) / T + 0.5
            va, vb = self._v[j], self._v[j + 1]
            lag = x**4 * (2.5 - 3.0 * x + x * x) - max(x - 0.5, 0.0)
            step = x**3 * (10.0 - 15.0 * x + 6.0 * x * x) - (1.0 if x >= 0.5 else 0.0)
            ds = 30.0 * (x * (1.0 - x)) ** 2 / T
            for k in range(3):
                dv = vb[k] - va[k]
                pos[k] += dv * T * lag
                vel[k] += dv * step
                acc[k] += dv * ds
        return TrajectorySample(xyz(pos), xyz(vel), xyz(acc), self._spindles[lo])


class PlanError(ValueError):
    """The planner could not meet the limits; str() says where."""


@dataclass
class _Chain:
    """The pieces as arrays: rest or move, ends, length, direction, cap, sag, dwell."""

    rest: np.ndarray
    start: np.ndarray
    end: np.ndarray
    length: np.ndarray
    dirs: np.ndarray
    cap: np.ndarray
    sag: np.ndarray
    dwell: np.ndarray
    spindle: list[float | None]
    src: list[int]


def _chain(pieces: Sequence[Piece], src: list[int], limits: Limits) -> _Chain:
    rest = np.array([p.rest for p in pieces])
    start = np.array([p.start for p in pieces], dtype=float).reshape(-1, 3)
    end = np.array([p.end for p in pieces], dtype=float).reshape(-1, 3)
    length = np.array([math.dist(p.start, p.end) for p in pieces])
    delta = end - start
    dirs = np.divide(delta, length[:, None], out=np.zeros_like(delta), where=length[:, None] > 0)
    vmax = np.asarray(limits.velocity, dtype=float)
    with np.errstate(divide='ignore', over='ignore'):  # a tiny direction component: no cap
        along = np.where(np.abs(dirs) > 0.0, vmax / np.abs(dirs), np.inf).min(axis=1)
    cap = np.minimum(np.array([p.speed for p in pieces]), along)
    return _Chain(
        rest,
        start,
        end,
        length,
        dirs,
        np.where(rest, 0.0, cap),
        np.array([p.sag for p in pieces]),
        np.array([p.dwell for p in pieces]),
        [p.spindle for p in pieces],
        src,
    )


def plan(pieces: Sequence[Piece], limits: Limits) -> PlannedPath:
    """Plan the chain (see the module doc). Zero-length moves are dropped, rests merged."""
    chain: list[Piece] = []
    src: list[int] = []  # the input piece each chain piece comes from
    for i, p in enumerate(pieces):
        if not p.rest and math.dist(p.start, p.end) <= ZERO_LENGTH:
            continue
        if p.rest and chain and chain[-1].rest and chain[-1].spindle == p.spindle:
            chain[-1] = Piece(
                p.start, p.end, dwell=chain[-1].dwell + p.dwell, rest=True, spindle=p.spindle
            )
            continue
        chain.append(p)
        src.append(i)
    if not chain:
        start = pieces[0].start if pieces else _ZERO
        return PlannedPath(None, [], start)
    first, last = chain[0].start, chain[-1].end
    # Rest before and after the program: the start and end are junctions with rest.
    s0, s1 = chain[0].spindle, chain[-1].spindle
    chain = [
        Piece(first, first, rest=True, spindle=s0),
        *chain,
        Piece(last, last, rest=True, spindle=s1),
    ]
    c = _chain(chain, [-1, *src, -1], limits)
    smooth = not all(math.isinf(x) for x in (*limits.acceleration, *limits.jerk))
    if smooth:
        c = _cut(c, limits)
    u, T = _settle(c, limits) if smooth else (c.cap, np.zeros(len(c.cap) - 1))
    profile = _timeline(c, u, T)
    return PlannedPath(profile, c.spindle, last, c.src)


def _corner_speeds(c: _Chain, limits: Limits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per junction: the fastest speed at which its corner meets the limits, the curvature
    κ there [1/m] (0 where the path goes straight on or stops), and the curve's own limit
    speed min(√(A/κ), (J/κ²)^⅓) (inf: none)."""
    acc = np.asarray(limits.acceleration, dtype=float)
    jerk = np.asarray(limits.jerk, dtype=float)
    tol = _tolerances(c, limits)
    dd = c.dirs[1:] - c.dirs[:-1]
    nd = np.linalg.norm(dd, axis=1)
    bent = ~c.rest[1:] & ~c.rest[:-1] & (np.abs(dd).max(axis=1) > PARALLEL)
    ad = np.abs(dd)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        # Its own transition alone: (5/64)·u·|Δd|·T(u) ≤ tolerance, T(u) from u·|Δd_i|.
        budget = 0.9 * tol / (DEVIATION * nd)
        by_acc = np.sqrt(budget[:, None] / (PEAK_ACCELERATION * ad / acc)).min(axis=1)
        by_jerk = (budget[:, None] / np.sqrt(PEAK_JERK * ad / jerk)) ** (2.0 / 3.0)
        alone = np.minimum(by_acc, by_jerk.min(axis=1))
        # A curve: u²κ and u³κ² on the axes it turns in.
        kappa = np.where(bent, nd / (0.5 * (c.length[1:] + c.length[:-1])), 0.0)
        plane = (np.abs(c.dirs[1:]) + np.abs(c.dirs[:-1])) > 1e-9
        a_c = np.where(plane, acc, np.inf).min(axis=1)
        j_c = np.where(plane, jerk, np.inf).min(axis=1)
        curve = np.minimum(np.sqrt(a_c / kappa), np.cbrt(j_c / kappa**2))
        curve = np.where(bent & (nd < GENTLE), curve, np.inf)
        w = np.where(bent, np.minimum(alone, CURVE_SHARE * curve), np.inf)
    w = np.nan_to_num(w, nan=np.inf, posinf=np.inf)
    return w, kappa, np.nan_to_num(curve, nan=np.inf, posinf=np.inf)


def _tolerances(c: _Chain, limits: Limits) -> np.ndarray:
    """Per junction: what the tolerance leaves its transitions (less the pieces' sags)."""
    return limits.tolerance - np.maximum(c.sag[1:], c.sag[:-1])


def _cut(c: _Chain, limits: Limits) -> _Chain:
    """Cut a straight piece near an end whose corner is slower than its cap: a short piece
    there at the corner's speed, long enough that the corner's transition and the one up to
    the cap need not overlap."""
    w, _, _ = _corner_speeds(c, limits)
    n = len(c.cap)
    moving = ~c.rest
    corner_in = np.concatenate(([np.inf], w))  # the corner at a piece's start
    corner_out = np.concatenate((w, [np.inf]))
    tol = limits.tolerance

    def room(speed: np.ndarray, turn: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The corner piece's length and the time of the ramp to the cap after it."""
        with np.errstate(divide='ignore', invalid='ignore'):
            ramp = transition_times((c.cap - speed)[:, None] * c.dirs, limits)
            corner = tol / (DEVIATION * speed * np.maximum(turn, 1e-300))
            out = 1.25 * speed * (0.5 * (np.minimum(corner, ramp * 4) + ramp))
        return np.nan_to_num(out, nan=0.0, posinf=0.0), ramp

    turn = np.linalg.norm(c.dirs[1:] - c.dirs[:-1], axis=1)
    turn_in = np.concatenate(([0.0], turn))
    turn_out = np.concatenate((turn, [0.0]))
    slow_in = moving & (corner_in < 0.98 * c.cap)
    slow_out = moving & (corner_out < 0.98 * c.cap)
    a, ramp_a = room(np.minimum(corner_in, c.cap), turn_in)
    b, ramp_b = room(np.minimum(corner_out, c.cap), turn_out)
    a, b = np.where(slow_in, a, 0.0), np.where(slow_out, b, 0.0)
    ramps = np.where(slow_in, ramp_a, 0.0) + np.where(slow_out, ramp_b, 0.0)
    # The rest must hold its ramps up to the cap and down again (else no cut: the whole
    # piece at its corners' speed costs little more than ramps that never reach the cap).
    with np.errstate(invalid='ignore'):
        middle = np.nan_to_num(0.5 * c.cap * ramps, nan=np.inf)
    fits = (a + b + middle <= c.length) & (a + b > 0.0)
    # A piece slow at one end only (an arc's first chord after a sharp corner, a short line
    # into a curve): its corner piece alone, so that the rest ramps on into the pieces after
    # it instead of crawling at the corner's speed from end to end.
    fits |= (slow_in != slow_out) & (a + b > 0.0) & (a + b <= LONE_CUT * c.length)
    a, b = np.where(fits, a, 0.0), np.where(fits, b, 0.0)
    if not fits.any():
        return c
    # Up to three parts a piece: [0, a], [a, L − b], [L − b, L].
    d = c.dirs
    mid_start = np.where((a > 0)[:, None], c.start + a[:, None] * d, c.start)
    mid_end = np.where((b > 0)[:, None], c.end - b[:, None] * d, c.end)
    keep = np.stack([a > 0, np.ones(n, dtype=bool), b > 0], axis=1).ravel()
    start = np.stack([c.start, mid_start, mid_end], axis=1).reshape(-1, 3)[keep]
    end = np.stack([mid_start, mid_end, c.end], axis=1).reshape(-1, 3)[keep]
    length = np.stack([a, c.length - a - b, b], axis=1).ravel()[keep]
    parts = keep.reshape(n, 3).sum(axis=1)
    rep = np.repeat(np.arange(n), parts)
    src = np.asarray(c.src)[rep].tolist()
    spindle = [c.spindle[k] for k in rep.tolist()]
    return _Chain(
        c.rest[rep],
        start,
        end,
        length,
        d[rep],
        c.cap[rep],
        c.sag[rep],
        c.dwell[rep],
        spindle,
        src,
    )


def _running_max(x: np.ndarray, group: np.ndarray) -> np.ndarray:
    """Running maximum of x that starts again where group (nondecreasing) changes."""
    if not len(x):
        return x
    first = np.flatnonzero(np.concatenate(([True], group[1:] != group[:-1])))
    low = np.minimum.reduceat(x, first)
    span = np.maximum.reduceat(x, first) - low + 1.0
    offset = np.concatenate(([0.0], np.cumsum(span)[:-1])) - low
    off = np.repeat(offset, np.diff(np.concatenate((first, [len(x)]))))
    return np.maximum.accumulate(x + off) - off


def _in_order(T: np.ndarray, t_min: np.ndarray, tau: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Transitions with |T_a − T_b| ≤ 2τ around every moving piece (the windows then start
    and end in order); a rest parts the chain. A longer transition is first shortened toward
    its neighbour's (down to its shortest, t_min), and where its shortest still differs too
    much, the neighbour lengthened."""
    group = np.cumsum(rest)[:-1]  # junction j follows piece j
    clock = np.cumsum(np.where(rest, 0.0, tau))[:-1]  # junction times within a group
    back_group = (group[-1] - group)[::-1]
    # Lower envelope: T_j ≤ T_k + 2|c_j − c_k|.
    T = np.minimum(T, -_running_max(-(T - 2.0 * clock), group) + 2.0 * clock)
    T = np.minimum(T, -_running_max(-(T + 2.0 * clock)[::-1], back_group)[::-1] - 2.0 * clock)
    T = np.maximum(T, t_min)
    # Upper envelope: T_j ≥ T_k − 2|c_j − c_k|.
    T = np.maximum(T, _running_max(T + 2.0 * clock, group) - 2.0 * clock)
    back = _running_max((T - 2.0 * clock)[::-1], back_group)[::-1]
    return np.maximum(T, back + 2.0 * clock)


def _settle(c: _Chain, limits: Limits) -> tuple[np.ndarray, np.ndarray]:
    """Speeds and transition times that pass every check (see the module doc)."""
    w, kappa, curve = _corner_speeds(c, limits)
    moving = ~c.rest
    u = c.cap.copy()
    u[1:] = np.minimum(u[1:], w)
    u[:-1] = np.minimum(u[:-1], w)
    u = np.where(moving, u, 0.0)
    tol = _tolerances(c, limits)
    # Junctions of a curve (small turns): transitions as long as the tolerance allows, which
    # average their corners out; a sharper corner blends as fast as the limits allow.
    gentle = np.isfinite(w) & (np.linalg.norm(c.dirs[1:] - c.dirs[:-1], axis=1) < GENTLE)
    scale = np.ones(len(w))  # a transition's length over what it started at
    shrunk = np.zeros(len(w), dtype=bool)  # shortened once: not lengthened again
    times = np.zeros(len(u), dtype=int)  # how often each piece has been slowed
    u, step = _ramp_rates(u, c.length, kappa, curve, limits)
    centre = np.concatenate(([0.0], np.cumsum(step)))
    for _ in range(MAX_PASSES):
        u = _ramps(u, centre)
        V = u[:, None] * c.dirs
        dv = V[1:] - V[:-1]
        t_min = transition_times(dv, limits)
        ndv = np.linalg.norm(dv, axis=1)
        fast = np.maximum(u[1:], u[:-1])
        with np.errstate(divide='ignore', invalid='ignore'):
            alone = DEVIATION_SHARE * tol / (DEVIATION * ndv)
            curve = np.sqrt(CURVE * DEVIATION_SHARE * tol / kappa) / fast
            pref = np.where(gentle, np.minimum(alone, curve), 0.0)
        target = np.maximum(t_min, np.nan_to_num(pref, nan=0.0, posinf=0.0))
        own = np.maximum(t_min, target * scale)
        with np.errstate(divide='ignore'):
            tau = np.where(moving, c.length / np.where(moving, u, 1.0), 0.0)
        T = _in_order(own, t_min, tau, c.rest)
        # May be shortened: longer than its shortest, and not held up by a neighbour's
        # (_in_order; a piece between them slowed parts them).
        short = (t_min < T) & (own >= T)
        free = np.where(shrunk, 1.0, MAX_STRETCH / scale)  # how much longer it may get
        slow, shorter, longer = _check(c, u, T, short, free, tol, limits)
        if slow is None:
            return u, T
        # A piece slowed many times steps at least by STUBBORN: every pass then makes
        # progress however little its check asks (the last few per cent of a curve's
        # speed are settled in the first passes, as its checks ask).
        times += slow < 1.0
        u = u * np.where(times > PATIENCE, np.minimum(slow, STUBBORN), slow)
        scale = scale * shorter * np.minimum(longer, free)
        shrunk |= shorter < 1.0
    raise PlanError(f'no feed meets the limits after {MAX_PASSES} passes')


def _ramp_rates(
    u: np.ndarray, length: np.ndarray, kappa: np.ndarray, curve: np.ndarray, limits: Limits
) -> tuple[np.ndarray, np.ndarray]:
    """The look-ahead's steps: per junction 2·a·(the distance between the pieces' middles),
    a a share of what the curvature leaves the tangential acceleration. On a curve u²κ of
    the acceleration and u³κ² of the jerk are taken, and speeding up by a_t adds 3·u·a_t·κ
    to the jerk: a_t falls as u nears the curve's limit. Where a curve is that fast, the
    speeds are first ramped piece by piece with a_t at each piece's speed; the steps then
    hold a_t at the speeds reached (lower speeds leave more: the steps stay safe)."""
    acc = float(np.min(limits.acceleration))
    jerk = float(np.min(limits.jerk))
    ds = 0.5 * (length[1:] + length[:-1])
    k = np.zeros(len(u))
    k[1:] = kappa
    k[:-1] = np.maximum(k[:-1], kappa)  # a piece's curvature: its sharper junction's
    fastest = np.full(len(u), np.inf)
    fastest[1:] = curve
    fastest[:-1] = np.minimum(fastest[:-1], curve)

    def rate(v: np.ndarray, kk: np.ndarray) -> np.ndarray:
        with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
            by_acc = acc * np.sqrt(np.maximum(1.0 - (v * v * kk / acc) ** 2, 0.0))
            by_jerk = np.maximum(jerk - v**3 * kk * kk, 0.0) / (3.0 * v * kk)
        a = np.where(kk > 0.0, np.minimum(by_acc, np.nan_to_num(by_jerk, nan=np.inf)), acc)
        return RAMP_SHARE * np.maximum(a, 1e-3 * acc)

    curvy = (k > 0.0) & (u > 0.3 * fastest)
    if curvy.any() and math.isfinite(acc):
        q = (u * u).tolist()
        kl = k.tolist()
        dl = ds.tolist()

        def one(v: float, kk: float) -> float:  # rate() of one piece, without numpy
            if kk <= 0.0:
                return RAMP_SHARE * acc
            by_acc = acc * math.sqrt(max(1.0 - (v * v * kk / acc) ** 2, 0.0))
            room = max(jerk - v**3 * kk * kk, 0.0)
            by_jerk = room / (3.0 * v * kk) if v > 0.0 else math.inf
            return RAMP_SHARE * max(min(by_acc, by_jerk), 1e-3 * acc)

        for i in range(len(q) - 1):  # speeding up
            lim = q[i] + 2.0 * one(math.sqrt(q[i]), max(kl[i], kl[i + 1])) * dl[i]
            if q[i + 1] > lim:
                q[i + 1] = lim
        for i in range(len(q) - 1, 0, -1):  # slowing down
            lim = q[i] + 2.0 * one(math.sqrt(q[i]), max(kl[i], kl[i - 1])) * dl[i - 1]
            if q[i - 1] > lim:
                q[i - 1] = lim
        u = np.minimum(u, np.sqrt(np.array(q)))
    a = rate(u, k)
    return u, 2.0 * ds * np.minimum(a[1:], a[:-1])


def _ramps(u: np.ndarray, ramp: np.ndarray) -> np.ndarray:
    """Speeds that change from piece to piece at most as u² changes by 2·a·(the distance
    between the pieces' middles), `ramp` its running sum: the look-ahead that starts
    slowing down before a slow corner or curve, and speeds up after it, piece by piece."""
    if not np.isfinite(ramp[-1]):
        return u
    q = u * u
    q = np.minimum(q, np.minimum.accumulate(q - ramp) + ramp)
    q = np.minimum(q, np.minimum.accumulate((q + ramp)[::-1])[::-1] - ramp)
    return np.minimum(u, np.sqrt(np.maximum(q, 0.0)))


def _durations(c: _Chain, u: np.ndarray, T: np.ndarray) -> np.ndarray:
    corners = np.concatenate(([0.0], T, [0.0]))
    with np.errstate(divide='ignore', invalid='ignore'):
        moving = c.length / u
    # At rest: the dwell plus the halves of the transitions into and out of it.
    rest = c.dwell + 0.5 * corners[:-1] + 0.5 * corners[1:]
    return np.where(c.rest, rest, moving)


def _timeline(c: _Chain, u: np.ndarray, T: np.ndarray) -> _Profile:
    duration = _durations(c, u, T)
    # As Beltrán 2013 eq. (19)-(22): duration = length/F, velocity (p_f − p_i)/duration.
    with np.errstate(divide='ignore', invalid='ignore'):
        velocity = np.where(c.rest[:, None], 0.0, (c.end - c.start) / duration[:, None])
    return _Profile(c.start, c.end, velocity, duration, T, np.where(c.rest, 0.0, u))


def _check(
    c: _Chain,
    u: np.ndarray,
    T: np.ndarray,
    short: np.ndarray,
    free: np.ndarray,
    tol: np.ndarray,
    limits: Limits,
) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
    """Per piece the factor its speed must fall by, per junction those its transition must
    shorten and lengthen by (None: every check passes)."""
    n = len(u)
    slow = np.ones(n)
    shorter = np.ones(n - 1)
    longer = np.ones(n - 1)
    prof = _timeline(c, u, T)
    ws, we = prof.ws, prof.we
    overlap = np.zeros(n - 1, dtype=bool)
    if n > 2:
        meet = (we[:-1] > ws[1:]) & (T[:-1] > 0) & (T[1:] > 0)
        overlap[:-1] |= meet
        overlap[1:] |= meet
    # Alone: acceleration and jerk within the limits by T ≥ t_min; the deviation exactly.
    alone = ~overlap
    dev = DEVIATION * np.linalg.norm(prof.dv, axis=1) * T
    turn = np.abs(c.dirs[1:] - c.dirs[:-1]).max(axis=1) > PARALLEL
    bad = alone & turn & ~c.rest[1:] & ~c.rest[:-1] & (dev > tol)
    if bad.any():
        ratio = dev[bad] / tol[bad]
        j = np.flatnonzero(bad)
        own = short[j]  # a transition longer than it must be: shorten it
        f = SAFETY * ratio**-0.5
        shorter[j[own]] = np.minimum(shorter[j[own]], f[own])
        f_slow = np.where(own, 1.0, SAFETY * ratio ** (-2.0 / 3.0))
        np.minimum.at(slow, j, f_slow)
        np.minimum.at(slow, j + 1, f_slow)
    if overlap.any():
        _check_overlaps(
            prof, c, np.flatnonzero(overlap), short, free, tol, limits, slow, shorter, longer
        )
    if (slow < 1.0).any() or (shorter < 1.0).any() or (longer > 1.0).any():
        return slow, shorter, longer
    return None, shorter, longer


def _check_overlaps(
    prof: _Profile,
    c: _Chain,
    js: np.ndarray,
    short: np.ndarray,
    free: np.ndarray,
    tol: np.ndarray,
    limits: Limits,
    slow: np.ndarray,
    shorter: np.ndarray,
    longer: np.ndarray,
) -> None:
    """Acceleration, jerk and deviation where transitions overlap: between every two window
    boundaries, at points close enough that the margin from the next derivative is small."""
    acc = np.asarray(limits.acceleration, dtype=float)
    jerk = np.asarray(limits.jerk, dtype=float)
    bounds = np.unique(np.concatenate((prof.ws[js], prof.we[js], prof.tj[js])))
    a0, a1 = bounds[:-1], bounds[1:]
    h = a1 - a0
    mid = 0.5 * (a0 + a1)
    lo, hi = prof.active(mid)
    live = (hi > lo) & (h > 0)
    a0, h, lo, hi = a0[live], h[live], lo[live], hi[live]
    if not len(h):
        return
    adv = np.abs(prof.dv)
    T = prof.T
    with np.errstate(divide='ignore', invalid='ignore'):
        k2 = np.nan_to_num(adv * (PEAK_ACCELERATION / T)[:, None])
        k3 = np.nan_to_num(adv * (SNAP / T**3)[:, None])
        k4 = np.nan_to_num(adv * (CRACKLE / T**4)[:, None])

    def span(k: np.ndarray) -> np.ndarray:
        s = np.vstack((np.zeros((1, 3)), np.cumsum(k, axis=0)))
        return s[hi] - s[lo]

    m2, m3, m4 = span(k2), span(k3), span(k4)
    with np.errstate(divide='ignore', invalid='ignore'):
        need = np.maximum(
            np.nanmax(np.sqrt(m3 / (8.0 * MARGIN * acc)), axis=1),
            np.nanmax(np.sqrt(m4 / (8.0 * MARGIN * jerk)), axis=1),
        )
        need = np.maximum(need, np.sqrt(np.linalg.norm(m2, axis=1) / (8.0 * 0.05 * tol[lo])))
    # Two points either side of a corner are a chord that cuts it by about their distance
    # apart times the turn: close enough that it is a small share of the tolerance.
    active = np.repeat(lo, hi - lo) + _ranks(hi - lo)
    starts = _firsts(hi - lo)
    speed = np.linalg.norm(prof.velocity, axis=1)
    fast = np.maximum.reduceat(np.maximum(speed[active], speed[active + 1]), starts)
    turn = np.linalg.norm(c.dirs[1:] - c.dirs[:-1], axis=1)
    bend = np.maximum.reduceat(turn[active], starts)
    with np.errstate(divide='ignore', invalid='ignore'):
        need = np.maximum(need, fast * bend / (4.0 * 0.05 * tol[lo]))
    points = np.clip(np.ceil(np.nan_to_num(h * need, posinf=MAX_POINTS)), 1, MAX_POINTS)
    points = points.astype(int)
    step = h / points
    count = points + 1
    which = np.repeat(np.arange(len(h)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    ts = a0[which] + step[which] * k
    pos, _, a, j, _, _ = prof.at(ts)
    first = np.cumsum(count) - count
    a_max = np.maximum.reduceat(np.abs(a), first, axis=0) + m3 * (step * step / 8.0)[:, None]
    j_max = np.maximum.reduceat(np.abs(j), first, axis=0) + m4 * (step * step / 8.0)[:, None]
    with np.errstate(divide='ignore', invalid='ignore'):
        r_acc = np.nan_to_num(a_max / acc).max(axis=1)
        r_jerk = np.nan_to_num(j_max / jerk).max(axis=1)
    # Distance to the pieces the sharp path runs on within the active windows (the planned
    # point is a weighted mean of the sharp path's points there), at each point.
    last_seg = len(prof.starts) - 1
    first_seg = np.clip(np.searchsorted(prof.starts, prof.ws[lo], side='right') - 1, 0, last_seg)
    end_seg = np.clip(np.searchsorted(prof.starts, prof.we[hi - 1], side='right') - 1, 0, last_seg)
    seg_lo = np.minimum(first_seg, lo)[which]
    seg_hi = np.maximum(end_seg, hi)[which] + 1
    nseg = seg_hi - seg_lo
    own = np.repeat(np.arange(len(ts)), nseg)
    s = (
        np.repeat(seg_lo, nseg)
        + np.arange(int(nseg.sum()))
        - np.repeat(np.cumsum(nseg) - nseg, nseg)
    )
    pa, pb = c.start[s], c.end[s]
    ab = pb - pa
    ap = pos[own] - pa
    nn = np.einsum('ij,ij->i', ab, ab)
    with np.errstate(divide='ignore', invalid='ignore'):
        f = np.clip(np.nan_to_num(np.einsum('ij,ij->i', ap, ab) / nn), 0.0, 1.0)
    dist = np.linalg.norm(ap - f[:, None] * ab, axis=1)
    near = np.full(len(ts), np.inf)
    np.minimum.at(near, own, dist)
    # Between two points the motion is their chord within m2·step²/8, and a chord between
    # two points near the path cuts a corner of turn |Δd| by at most its length·|Δd|/4.
    off = (
        np.maximum.reduceat(near, first)
        + np.linalg.norm(m2, axis=1) * step * step / 8.0
        + fast * step * bend / 4.0
    )
    budget = np.minimum.reduceat(tol[np.repeat(lo, hi - lo) + _ranks(hi - lo)], _firsts(hi - lo))
    r_dev = off / budget
    # One transition alone in an interval: within the limits by T ≥ its shortest (exactly,
    # where the samples' margin could only add), and as far from the path as its own lag.
    alone = hi - lo == 1
    r_acc[alone] = r_jerk[alone] = 0.0
    lag = DEVIATION * np.linalg.norm(prof.dv[lo], axis=1) * T[lo] / budget
    r_dev[alone] = np.minimum(r_dev[alone], lag[alone])
    fail = (r_acc > 1.0) | (r_jerk > 1.0) | (r_dev > 1.0)
    for q in np.flatnonzero(fail):
        jj = slice(lo[q], hi[q])
        if r_dev[q] < 0.7 and (r_acc[q] > 1.0 or r_jerk[q] > 1.0) and (free[jj] > 1.0).all():
            # Room to blend over longer: the sums fall as the transitions lengthen.
            f_long = max(r_acc[q], r_jerk[q] ** 0.5, 1.0 / STUBBORN) / SAFETY
            longer[jj] = np.maximum(longer[jj], f_long)
            continue
        f_speed = SAFETY * min(1.0, max(r_acc[q], 1.0) ** -0.5, max(r_jerk[q], 1.0) ** -(1 / 3))
        if r_dev[q] > 1.0:
            f_dev = SAFETY * r_dev[q] ** -0.5
            own_t = short[jj]
            shorter[jj] = np.minimum(shorter[jj], np.where(own_t, f_dev, 1.0))
            if not own_t.any():  # none can shorten: slower, they shorten and part
                f_speed = min(f_speed, f_dev)
        if f_speed < 1.0:
            slow[lo[q] : hi[q] + 1] = np.minimum(slow[lo[q] : hi[q] + 1], f_speed)


def _ranks(count: np.ndarray) -> np.ndarray:
    return np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)


def _firsts(count: np.ndarray) -> np.ndarray:
    return np.cumsum(count) - count
