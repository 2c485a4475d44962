"""Feed planner: straight pieces to a jerk-limited reference with blended corners. ROS-free.

The input is a chain of straight pieces (arcs come as chords, mill_trajectory.toolpath), each
with a speed cap (the programmed feed), and rests (dwell, stop). Each piece k is travelled
at a constant velocity V_k = u_k·d_k; at each junction the velocity changes from V_a to V_b
in a transition of duration T centred on the instant the sharp path reaches the corner C:

    v = V_a + ΔV s(x),  s(x) = 3x² − 2x³,  x = (t − t_C + T/2)/T ∈ [0, 1],  ΔV = V_b − V_a

so it leaves the first piece at C − V_a T/2 and joins the second at C + V_b T/2 (s is
symmetric). Per axis, then, by construction and for any program:

- velocity: v is a convex combination of V_a and V_b, each within the axis limit;
- acceleration ΔV·s'/T peaks at 1.5|ΔV|/T, jerk ΔV·s''/T² at 6|ΔV|/T², so T ≥ 1.5|ΔV_i|/A_i
  and T ≥ √(6|ΔV_i|/J_i) on every axis i keep both within the limits (acceleration is
  continuous, jerk bounded: a jerk-limited profile);
- the path leaves the sharp corner by at most (3/32)|ΔV|T (at x = 1/2), kept within the
  path tolerance (LinuxCNC G64 P); a junction of parallel pieces or with a rest stays on the
  line and has no deviation;
- transitions never overlap: the two half-transitions of a piece fit in its time L_k/u_k.

Look-ahead: the whole chain is planned before it runs. Speeds start at their caps (the
feed, and each axis's velocity limit along the piece's direction) and every piece whose
junction misses the tolerance or that cannot hold its two half-transitions is slowed by
SLOW_DOWN until none does; slowing a piece only shortens its transitions and lengthens its
time, so this ends. So that a slow corner slows only its neighbourhood, a straight piece
is first cut at distances tolerance·2^i from both of its ends: the speed can then rise
piece by piece along the line (a junction of parallel pieces has no deviation). The start
and end are junctions with rest; an acceleration or jerk limit of inf is no limit (with
both inf, the velocity steps at each corner, as the straight cuts of Beltrán 2013
eq. (19)-(22), and pieces are not cut).

The spindle (signed speed [rev/min], None: not programmed) is a piece's; it changes only at
a rest (mill_trajectory.gcode), and rests of different spindles are not merged. A sample
takes the spindle of the segment it is in, and in a transition that of the segment it
leaves: the spindle changes when the axes have come to rest.
"""

from __future__ import annotations

import bisect
import itertools
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
DEVIATION = 3.0 / 32.0  # max |∫ s − step| over a transition, per |ΔV|·T
SLOW_DOWN = 0.97  # factor a piece's speed falls by per planning pass
MAX_PASSES = 3000
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
    """A straight move start -> end at most at `speed` [m/s], or a rest of `dwell` [s]."""

    start: Point
    end: Point
    speed: float = math.inf  # inf: as fast as the axes allow (a rapid)
    dwell: float = 0.0  # rest only
    rest: bool = False
    spindle: float | None = None  # [rev/min], signed; None: not programmed


def transition_times(dv: np.ndarray, limits: Limits) -> np.ndarray:
    """Shortest transition T [s] for each velocity change ΔV (rows) within the limits."""
    adv = np.abs(dv)
    acc = np.asarray(limits.acceleration, dtype=float)
    jerk = np.asarray(limits.jerk, dtype=float)
    t_acc = 1.5 * adv / acc
    t_jerk = np.sqrt(6.0 * adv / jerk)
    return np.maximum(t_acc, t_jerk).max(axis=1) if len(adv) else np.zeros(0)


@dataclass
class _Segment:
    start: Point  # the sharp path's point when the segment starts
    velocity: Point
    duration: float  # on the sharp timeline [s]
    spindle: float | None = None


class PlannedPath(Trajectory):
    """The planned reference (see the module doc): sample(t) for any t."""

    PREFIX = 'planned'

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> PlannedPath:
        raise NotImplementedError('a planned path is built by plan()')

    def __init__(
        self,
        segments: list[_Segment],
        corners: list[float],
        end: Point,
        sources: list[int] | None = None,
    ) -> None:
        self._segments = segments
        # Per segment: the index of the input piece it comes from (-1: the rest before the
        # start or after the end).
        self.sources = sources if sources is not None else [-1] * len(segments)
        self._corners = corners  # transition time before segment i (0 for the first)
        starts, t = [], 0.0
        for seg in segments:
            starts.append(t)
            t += seg.duration
        self._starts = starts
        self.end_time = t
        self.end_point = end
        self.start_point = segments[0].start if segments else end

    def piece_times(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """For each of the `count` input pieces: its time on the sharp timeline [s] (the
        blended path takes the same time: each transition is centred on its corner) and its
        planned speed [m/s], which the blended path reaches (transitions never overlap);
        0 and 0 for a dropped (zero-length) piece, a rest's time is its dwell."""
        time, speed = np.zeros(count), np.zeros(count)
        for seg, k in zip(self._segments, self.sources, strict=True):
            if k < 0:
                continue
            v = math.hypot(*seg.velocity)
            if v > 0.0:
                time[k] += seg.duration
                speed[k] = max(speed[k], v)
        return time, speed

    @property
    def transitions(self) -> list[float]:
        """Duration of each junction's transition [s], the start's and the end's included."""
        return list(self._corners)

    def sample(self, t: float) -> TrajectorySample:
        if not self._segments:
            return TrajectorySample(self.end_point, _ZERO, _ZERO)
        if t <= 0.0:
            return TrajectorySample(self.start_point, _ZERO, _ZERO, self._segments[0].spindle)
        if t >= self.end_time:
            return TrajectorySample(self.end_point, _ZERO, _ZERO, self._segments[-1].spindle)
        i = bisect.bisect_right(self._starts, t) - 1
        seg, t0 = self._segments[i], self._starts[i]
        before = self._corners[i]
        after = self._corners[i + 1] if i + 1 < len(self._corners) else 0.0
        if t < t0 + 0.5 * before and i > 0:
            return self._blend(i, t - (t0 - 0.5 * before), before)
        if t > t0 + seg.duration - 0.5 * after and i + 1 < len(self._segments):
            return self._blend(i + 1, t - (t0 + seg.duration - 0.5 * after), after)
        tau = t - t0
        p, v = seg.start, seg.velocity
        # Beltrán 2013 eq. (19)-(22) between transitions: p(t) = p_i + v (t − t_i)
        return TrajectorySample(
            (p[0] + v[0] * tau, p[1] + v[1] * tau, p[2] + v[2] * tau), v, _ZERO, seg.spindle
        )

    def _blend(self, i: int, tau: float, T: float) -> TrajectorySample:
        """The transition into segment i, tau [s] after it began."""
        va, vb, c = (
            self._segments[i - 1].velocity,
            self._segments[i].velocity,
            self._segments[i].start,
        )
        x = tau / T
        s, big_s, ds = 3 * x * x - 2 * x**3, x**3 - 0.5 * x**4, (6 * x - 6 * x * x) / T
        pos = tuple(
            c[k] - va[k] * 0.5 * T + va[k] * tau + (vb[k] - va[k]) * T * big_s for k in range(3)
        )
        vel = tuple(va[k] + (vb[k] - va[k]) * s for k in range(3))
        acc = tuple((vb[k] - va[k]) * ds for k in range(3))
        spindle = self._segments[i - 1].spindle  # of the segment it leaves
        return TrajectorySample(pos, vel, acc, spindle)  # type: ignore[arg-type]


class PlanError(ValueError):
    """The planner could not meet the limits; str() says where."""


def _caps(pieces: Sequence[Piece], dirs: np.ndarray, limits: Limits) -> np.ndarray:
    vmax = np.asarray(limits.velocity, dtype=float)
    with np.errstate(divide='ignore', over='ignore'):  # a tiny direction component: no cap
        along = np.where(np.abs(dirs) > 0.0, vmax / np.abs(dirs), np.inf).min(axis=1)
    return np.minimum(np.array([p.speed for p in pieces]), along)


def _split(p: Piece, base: float) -> list[Piece]:
    """A straight piece cut at base·2^i from both ends (a rest as it is)."""
    length = math.dist(p.start, p.end)
    if p.rest or length <= 4 * base:
        return [p]
    cuts, d = [], base
    while d < 0.5 * length:
        cuts += [d, length - d]
        d *= 2.0
    points = [p.start]
    for f in sorted(cuts):
        point = tuple(a + (b - a) * f / length for a, b in zip(p.start, p.end, strict=True))
        points.append(point)  # type: ignore[arg-type]
    points.append(p.end)
    return [Piece(a, b, p.speed, spindle=p.spindle) for a, b in itertools.pairwise(points)]


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
        return PlannedPath([], [], start)
    if not all(math.isinf(x) for x in (*limits.acceleration, *limits.jerk)):
        cut = [_split(p, limits.tolerance) for p in chain]
        src = [i for i, parts in zip(src, cut, strict=True) for _ in parts]
        chain = [q for parts in cut for q in parts]
    src = [-1, *src, -1]
    first, last = chain[0].start, chain[-1].end
    # Rest before and after the program: the start and end are junctions with rest.
    s0, s1 = chain[0].spindle, chain[-1].spindle
    chain = [
        Piece(first, first, rest=True, spindle=s0),
        *chain,
        Piece(last, last, rest=True, spindle=s1),
    ]
    moving = np.array([not p.rest for p in chain])
    length = np.array([math.dist(p.start, p.end) for p in chain])
    delta = np.array([np.subtract(p.end, p.start) for p in chain])
    dirs = np.divide(delta, length[:, None], out=np.zeros_like(delta), where=length[:, None] > 0)
    caps = np.where(moving, _caps(chain, dirs, limits), 0.0)
    u, T = _settle(caps.copy(), dirs, moving, length, limits)
    return _timeline(chain, u, T, src)


def _settle(
    u: np.ndarray, dirs: np.ndarray, moving: np.ndarray, length: np.ndarray, limits: Limits
) -> tuple[np.ndarray, np.ndarray]:
    """Slow pieces by SLOW_DOWN until no junction misses the tolerance and every piece holds
    its two half-transitions; the speeds and the junctions' transition times.

    A pass slows every piece that misses, as if all were checked anew, but only the
    junctions and pieces next to a slowed piece are: nothing else changed, so every number
    is the one a full pass gives (the same operations on the same values), and a pass costs
    what it slows, not the whole program (most pieces settle in the first few passes)."""
    n = len(u)
    bent = moving[1:] & moving[:-1] & (np.abs(dirs[1:] - dirs[:-1]).max(axis=1) > PARALLEL)
    T = np.zeros(n - 1)
    off = np.zeros(n - 1, dtype=bool)
    slow = np.zeros(n, dtype=bool)

    def junctions(j: np.ndarray) -> None:  # junction j: from piece j to piece j + 1
        dv = u[j + 1, None] * dirs[j + 1] - u[j, None] * dirs[j]
        T[j] = transition_times(dv, limits)
        off[j] = bent[j] & (DEVIATION * np.linalg.norm(dv, axis=1) * T[j] > limits.tolerance)

    def pieces(k: np.ndarray) -> None:
        first, last = k > 0, k < n - 1
        before, after = np.maximum(k - 1, 0), np.minimum(k, n - 2)
        half = 0.5 * np.where(first, T[before], 0.0) + 0.5 * np.where(last, T[after], 0.0)
        with np.errstate(divide='ignore'):
            long = moving[k] & (half > length[k] / np.where(moving[k], u[k], 1.0))
        slow[k] = long | (first & off[before]) | (last & off[after])

    junctions(np.arange(n - 1))
    pieces(np.arange(n))
    for _ in range(MAX_PASSES):
        changed = np.flatnonzero(slow)
        if not len(changed):
            return u, T
        u[changed] = u[changed] * SLOW_DOWN
        j = np.flatnonzero(slow[:-1] | slow[1:])  # a junction next to a slowed piece
        junctions(j)
        near = np.zeros(n, dtype=bool)
        near[j] = near[j + 1] = True
        pieces(np.flatnonzero(near))
    raise PlanError(f'no feed meets the limits after {MAX_PASSES} passes')


def _timeline(chain: list[Piece], u: np.ndarray, T: np.ndarray, src: list[int]) -> PlannedPath:
    segments: list[_Segment] = []
    corners = [0.0, *(float(x) for x in T)]
    for k, p in enumerate(chain):
        if p.rest:
            # At rest: the dwell plus the halves of the transitions into and out of it.
            after = corners[k + 1] if k + 1 < len(corners) else 0.0
            duration = p.dwell + 0.5 * corners[k] + 0.5 * after
            segments.append(_Segment(p.start, _ZERO, duration, p.spindle))
            continue
        # As Beltrán 2013 eq. (19)-(22): duration = length/F, velocity (p_f − p_i)/duration.
        duration = math.dist(p.start, p.end) / float(u[k])
        v = tuple((b - a) / duration for a, b in zip(p.start, p.end, strict=True))
        segments.append(_Segment(p.start, v, duration, p.spindle))  # type: ignore[arg-type]
    return PlannedPath(segments, corners, chain[-1].end, src)
