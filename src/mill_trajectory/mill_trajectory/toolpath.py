"""G-code moves to the planner's straight pieces, and the machine's travel. ROS-free.

An arc becomes chords that turn by at most CHORD_ANGLE and whose sagitta is at most a
quarter of the path tolerance; each chord carries its sagitta (Piece.sag), and the planner
keeps its blends within the tolerance less it, so that chords and blends stay within the
tolerance of the programmed arc (mill_trajectory.planner). Fine chords are what lets the
planner blend a curve at the speed its radius allows. A helix climbs linearly in its angle.
A move in exact stop mode (G61, G61.1, canned cycles) ends at rest; a message moves
nothing. The chords follow the program's G64 P where it is smaller than the machine's
tolerance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from mill_trajectory.gcode_words import GcodeError, Move, Point, Where
from mill_trajectory.planner import Piece

AXIS_NAMES = 'xyz'
SAG_SHARE = 0.25  # of the tolerance a chord may leave its arc by
CHORD_ANGLE = 0.02  # [rad] an arc's chords turn at most this much


@dataclass(frozen=True)
class Travel:
    """The machine's travel per axis [m]: minimum and maximum of x, y, z."""

    minimum: Point
    maximum: Point

    def outside(self, p: Sequence[float]) -> str | None:
        """Why p is outside the travel (None: inside)."""
        for i, name in enumerate(AXIS_NAMES):
            if p[i] < self.minimum[i]:
                return f'{name} = {p[i]:.6g} m is below travel.min {self.minimum[i]:g} m'
            if p[i] > self.maximum[i]:
                return f'{name} = {p[i]:.6g} m is above travel.max {self.maximum[i]:g} m'
        return None


def arc_points(move: Move, tolerance: float) -> list[Point]:
    """The chord ends of an arc, its end point last (its start not included)."""
    assert move.center is not None
    a, b, n = move.plane
    s, e, c = move.start, move.end, move.center
    r0 = math.hypot(s[a] - c[a], s[b] - c[b])
    r1 = math.hypot(e[a] - c[a], e[b] - c[b])
    # Chord angle whose sagitta r(1 − cos(θ/2)) is a quarter of the tolerance, and at most
    # CHORD_ANGLE: the planner blends many chords at once, and the finer they turn the less
    # their corners add to the jerk of the curve they make.
    cos_half = max(1.0 - SAG_SHARE * tolerance / max(r0, r1), -1.0)
    step = min(2.0 * math.acos(cos_half), CHORD_ANGLE)
    count = max(1, math.ceil(abs(move.sweep) / step)) if step > 0 else 1
    start_angle = math.atan2(s[b] - c[b], s[a] - c[a])
    points: list[Point] = []
    for i in range(1, count):
        f = i / count
        angle = start_angle + move.sweep * f
        r = r0 + (r1 - r0) * f  # an IJK end within tolerance of the circle: a slight spiral
        p = [0.0, 0.0, 0.0]
        p[a] = c[a] + r * math.cos(angle)
        p[b] = c[b] + r * math.sin(angle)
        p[n] = s[n] + (e[n] - s[n]) * f
        points.append((p[0], p[1], p[2]))
    points.append(e)
    return points


def chord_sag(move: Move, count: int) -> float:
    """How far `count` chords of an arc leave it [m], at most: the sagitta of the larger
    radius, plus the slight spiral of an end off the circle (mill_trajectory.gcode)."""
    assert move.center is not None
    a, b, _ = move.plane
    s, e, c = move.start, move.end, move.center
    r0 = math.hypot(s[a] - c[a], s[b] - c[b])
    r1 = math.hypot(e[a] - c[a], e[b] - c[b])
    half = 0.5 * abs(move.sweep) / count
    return max(r0, r1) * (1.0 - math.cos(half)) + abs(r1 - r0) / count


def pieces_of(moves: Sequence[Move], tolerance: float) -> tuple[list[Piece], list[Where]]:
    """The planner's pieces and, for each, the line of the move it comes from."""
    pieces: list[Piece] = []
    wheres: list[Where] = []
    for m in moves:
        if m.kind == 'message':  # nothing moves
            continue
        if m.kind in ('dwell', 'stop', 'spindle'):
            pieces.append(Piece(m.start, m.end, dwell=m.duration, rest=True, spindle=m.spindle))
            wheres.append(m.where)
            continue
        speed = math.inf if m.feed is None else m.feed
        here = m.start
        chord = min(tolerance, m.tolerance) if m.tolerance else tolerance  # G64 P
        ends = arc_points(m, chord) if m.kind == 'arc' else [m.end]
        sag = chord_sag(m, len(ends)) if m.kind == 'arc' else 0.0
        for p in ends:
            pieces.append(Piece(here, p, speed, spindle=m.spindle, sag=sag))
            wheres.append(m.where)
            here = p
        if m.exact_stop:  # G61, G61.1, canned cycles: at rest at the move's end
            pieces.append(Piece(m.end, m.end, rest=True, spindle=m.spindle))
            wheres.append(m.where)
    return pieces, wheres


def check_travel(pieces: Sequence[Piece], wheres: Sequence[Where], travel: Travel) -> None:
    """GcodeError at the first move whose piece leaves the travel.

    The planned path between two piece ends stays in the triangle of their corner, so the
    ends (inside a box) are all there is to check.
    """
    for piece, where in zip(pieces, wheres, strict=True):
        for p in (piece.start, piece.end):
            problem = travel.outside(p)
            if problem:
                raise GcodeError(where, f'move outside the machine travel: {problem}')
