"""The planned motion as a function of time: the blending kernel s(x) = 10x³ − 15x⁴ + 6x⁵
and its peaks, the shortest transition for a velocity change, the sharp segments plus their
transitions (Profile, vectorised), and the reference sampled from them (PlannedPath). The
equations are derived in mill_trajectory.planner's doc. ROS-free.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.planner_pieces import ORIGIN, ZERO_LENGTH, Limits, Piece, Point, xyz

DEVIATION = 5.0 / 64.0  # max |∫ s − step| over a transition, per |ΔV|·T


PEAK_ACCELERATION = 15.0 / 8.0  # max s'


PEAK_JERK = 10.0 / math.sqrt(3.0)  # max |s''|


SNAP = 60.0  # max |s'''|


CRACKLE = 360.0  # max |s''''|


CURVE = 56.0  # a circle averaged over T shrinks by u²T²/(56 r): the kernel's variance T²/28


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


class Profile:
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
        profile: Profile | None,
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
            return TrajectorySample(self.end_point, ORIGIN, ORIGIN)
        if t <= 0.0:
            return TrajectorySample(self.start_point, ORIGIN, ORIGIN, self._spindles[0])
        if t >= self.end_time:
            return TrajectorySample(self.end_point, ORIGIN, ORIGIN, self._spindles[-1])
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
            ORIGIN,
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
