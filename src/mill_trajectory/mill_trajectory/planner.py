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

import math
from collections.abc import Sequence

import numpy as np

from mill_trajectory.planner_chain import chain_of, cut, timeline
from mill_trajectory.planner_pieces import ORIGIN, ZERO_LENGTH, Limits, Piece, PlanError, Point, xyz
from mill_trajectory.planner_profile import PlannedPath
from mill_trajectory.planner_settle import settle

# The planner's public names: plan() here, its input, limits, failure and result.
__all__ = [
    'ZERO_LENGTH',
    'Limits',
    'Piece',
    'PlanError',
    'PlannedPath',
    'Point',
    'plan',
    'xyz',
]


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
        start = pieces[0].start if pieces else ORIGIN
        return PlannedPath(None, [], start)
    first, last = chain[0].start, chain[-1].end
    # Rest before and after the program: the start and end are junctions with rest.
    s0, s1 = chain[0].spindle, chain[-1].spindle
    chain = [
        Piece(first, first, rest=True, spindle=s0),
        *chain,
        Piece(last, last, rest=True, spindle=s1),
    ]
    c = chain_of(chain, [-1, *src, -1], limits)
    smooth = not all(math.isinf(x) for x in (*limits.acceleration, *limits.jerk))
    if smooth:
        c = cut(c, limits)
    u, T = settle(c, limits) if smooth else (c.cap, np.zeros(len(c.cap) - 1))
    profile = timeline(c, u, T)
    return PlannedPath(profile, c.spindle, last, c.src)
