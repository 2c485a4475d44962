"""The planner's checks of a candidate plan: acceleration, jerk and the path tolerance, for
transitions alone and where they overlap (sampled between window boundaries with a margin
for the next derivative), and the factors a failing check asks for: slower pieces, shorter
or longer transitions (mill_trajectory.planner's doc). ROS-free.
"""

from __future__ import annotations

import numpy as np

from mill_trajectory.planner_chain import PARALLEL, Chain, timeline
from mill_trajectory.planner_pieces import Limits
from mill_trajectory.planner_profile import CRACKLE, DEVIATION, PEAK_ACCELERATION, SNAP, Profile

MARGIN = 0.01  # share of a limit the sampling margin may take


MAX_POINTS = 256  # per interval between window boundaries


SAFETY = 0.995  # a slowed piece goes this much below what its check asks


STUBBORN = 0.97


def check(
    c: Chain,
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
    prof = timeline(c, u, T)
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
    prof: Profile,
    c: Chain,
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
