"""The planner's look-ahead and passes: speeds ramped between corners and curves,
transition times kept in order, and the loop that slows, shortens and lengthens until every
check passes (mill_trajectory.planner's doc). ROS-free.
"""

from __future__ import annotations

import math

import numpy as np

from mill_trajectory.planner_chain import GENTLE, Chain, corner_speeds, tolerances
from mill_trajectory.planner_checks import STUBBORN, check
from mill_trajectory.planner_pieces import Limits, PlanError
from mill_trajectory.planner_profile import CURVE, DEVIATION, transition_times

DEVIATION_SHARE = 0.8  # of the tolerance a curve's transitions are sized for


RAMP_SHARE = 0.5  # of the acceleration the look-ahead ramps speeds with


MAX_PASSES = 400


PATIENCE = 20  # slowings of a piece before its steps are at least STUBBORN


MAX_STRETCH = 8.0  # a transition lengthened at most this many times its shortest


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


def settle(c: Chain, limits: Limits) -> tuple[np.ndarray, np.ndarray]:
    """Speeds and transition times that pass every check (see the module doc)."""
    w, kappa, curve = corner_speeds(c, limits)
    moving = ~c.rest
    u = c.cap.copy()
    u[1:] = np.minimum(u[1:], w)
    u[:-1] = np.minimum(u[:-1], w)
    u = np.where(moving, u, 0.0)
    tol = tolerances(c, limits)
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
        slow, shorter, longer = check(c, u, T, short, free, tol, limits)
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
