"""The planner's chain of pieces as arrays, and what is read off it before the speeds are
settled: each junction's corner speed and curvature, the tolerance its transitions get,
straight pieces cut near slow corners, and the sharp timeline for given speeds and
transitions (mill_trajectory.planner's doc). ROS-free.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mill_trajectory.planner_pieces import Limits, Piece
from mill_trajectory.planner_profile import (
    DEVIATION,
    PEAK_ACCELERATION,
    PEAK_JERK,
    Profile,
    transition_times,
)

GENTLE = 0.2  # |d_b − d_a| below this: a junction of a curve


CURVE_SHARE = 0.97  # of a curve's limit speed it starts at


LONE_CUT = 0.5  # a piece slow at one end is cut there if its corner piece takes at most this


PARALLEL = 1e-12  # |d_a − d_b| below this: the same direction


@dataclass
class Chain:
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


def chain_of(pieces: Sequence[Piece], src: list[int], limits: Limits) -> Chain:
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
    return Chain(
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


def corner_speeds(c: Chain, limits: Limits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per junction: the fastest speed at which its corner meets the limits, the curvature
    κ there [1/m] (0 where the path goes straight on or stops), and the curve's own limit
    speed min(√(A/κ), (J/κ²)^⅓) (inf: none)."""
    acc = np.asarray(limits.acceleration, dtype=float)
    jerk = np.asarray(limits.jerk, dtype=float)
    tol = tolerances(c, limits)
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


def tolerances(c: Chain, limits: Limits) -> np.ndarray:
    """Per junction: what the tolerance leaves its transitions (less the pieces' sags)."""
    return limits.tolerance - np.maximum(c.sag[1:], c.sag[:-1])


def cut(c: Chain, limits: Limits) -> Chain:
    """Cut a straight piece near an end whose corner is slower than its cap: a short piece
    there at the corner's speed, long enough that the corner's transition and the one up to
    the cap need not overlap."""
    w, _, _ = corner_speeds(c, limits)
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
    return Chain(
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


def _durations(c: Chain, u: np.ndarray, T: np.ndarray) -> np.ndarray:
    corners = np.concatenate(([0.0], T, [0.0]))
    with np.errstate(divide='ignore', invalid='ignore'):
        moving = c.length / u
    # At rest: the dwell plus the halves of the transitions into and out of it.
    rest = c.dwell + 0.5 * corners[:-1] + 0.5 * corners[1:]
    return np.where(c.rest, rest, moving)


def timeline(c: Chain, u: np.ndarray, T: np.ndarray) -> Profile:
    duration = _durations(c, u, T)
    # As Beltrán 2013 eq. (19)-(22): duration = length/F, velocity (p_f − p_i)/duration.
    with np.errstate(divide='ignore', invalid='ignore'):
        velocity = np.where(c.rest[:, None], 0.0, (c.end - c.start) / duration[:, None])
    return Profile(c.start, c.end, velocity, duration, T, np.where(c.rest, 0.0, u))
