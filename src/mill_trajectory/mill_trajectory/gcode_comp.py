"""Cutter radius compensation (G41/G42) of a run of moves in the XY plane. ROS-free.

The moves between G41/G42 and G40 are the programmed path (the part's edge); the tool's
centre runs `radius` to its left (G41) or right (G42), as LinuxCNC does it:

- The entry move (the first move with an XY component, a G0 or G1 longer than the radius)
  goes from the uncompensated point to its end point moved sideways by the radius,
  perpendicular to the entry move.
- Every later line or arc is offset by the radius (an arc's radius grows or shrinks).
- At an outside corner the tool goes round the programmed corner point on an arc of the
  tool radius; at an inside corner both offset moves end where they cross (the first is
  cut short, so the part is not gouged); tangent moves just join.
- Moves without XY motion (a plunge, a dwell, a spindle change) stay where the tool is.
- The last move ends at its offset end point; the move after G40 (the exit move) goes from
  there to its programmed end.

A move that the corners leave with no length (it would reverse), an arc whose radius is not
larger than the tool's on its inner side, an arc as the entry move, or an entry shorter than
the radius is refused with one line naming the move.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from mill_trajectory.gcode_words import GcodeError, Move, Where

Vec = tuple[float, float]
TINY = 1e-12  # [m]: shorter is no XY motion
PARALLEL = 1e-9  # |sin| of the turn below this: tangent (or reversing) moves


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1])


def _add(a: Vec, b: Vec, k: float = 1.0) -> Vec:
    return (a[0] + k * b[0], a[1] + k * b[1])


def _unit(v: Vec) -> Vec:
    n = math.hypot(*v)
    return (v[0] / n, v[1] / n)


def _left(v: Vec) -> Vec:
    return (-v[1], v[0])


def _cross(a: Vec, b: Vec) -> float:
    return a[0] * b[1] - a[1] * b[0]


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1]


@dataclass
class _Element:
    """A move with XY motion: the programmed geometry, and the tool's start and end."""

    index: int  # in the run
    start: Vec  # programmed
    end: Vec
    t_start: Vec  # unit tangents
    t_end: Vec
    center: Vec | None  # arcs
    radius: float  # arcs: the tool centre's radius
    ccw: bool
    tool_start: Vec = (0.0, 0.0)
    tool_end: Vec = (0.0, 0.0)


def compensate(moves: Sequence[Move], side: int, radius: float) -> list[Move]:
    """The run of moves with the tool's centre `radius` [m] to the left (side 1) or right
    (side -1) of the programmed path (see the module doc)."""
    moves = list(moves)
    if radius <= 0.0:
        return moves
    elements: list[_Element] = []
    for i, m in enumerate(moves):
        element = _element(i, m, side, radius)
        if element is not None:
            elements.append(element)
    if not elements:
        return moves
    first = elements[0]
    entry = moves[first.index]
    if entry.kind == 'arc':
        raise GcodeError(entry.where, 'cutter compensation: the entry move must be G0 or G1')
    length = math.dist(first.start, first.end)
    if length <= radius:
        raise GcodeError(
            entry.where,
            f'cutter compensation: the entry move ({length * 1e3:g} mm) must be longer than '
            f'the tool radius ({radius * 1e3:g} mm)',
        )
    first.tool_start = first.start
    for element in elements[1:]:
        element.tool_start = _add(element.start, _left(element.t_start), side * radius)
    for element in elements:
        element.tool_end = _add(element.end, _left(element.t_end), side * radius)
    corners: dict[int, tuple[Vec, float]] = {}  # element -> the corner arc after it
    for a, b in itertools.pairwise(elements):
        cross, dot = _cross(a.t_end, b.t_start), _dot(a.t_end, b.t_start)
        if abs(cross) < PARALLEL and dot > 0.0:
            b.tool_start = a.tool_end  # tangent
        elif side * cross < 0.0 or abs(cross) < PARALLEL:  # outside corner (or reversal)
            sweep = math.atan2(cross, dot) if abs(cross) >= PARALLEL else -side * math.pi
            corners[a.index] = (a.end, sweep)
        else:  # inside corner: both end where their offsets cross
            x = _crossing(a, b, moves[b.index].where)
            a.tool_end = b.tool_start = x
    for element in elements:
        _check(element, moves[element.index])
    out: list[Move] = []
    tool = first.start
    by_index = {e.index: e for e in elements}
    for i, m in enumerate(moves):
        e = by_index.get(i)
        if e is None:  # no XY motion: where the tool is
            out.append(replace(m, start=(*tool, m.start[2]), end=(*tool, m.end[2])))
            continue
        center = m.center if e.center is None else (*e.center, m.start[2])
        sweep = m.sweep
        if e.center is not None:
            sweep = _sweep(e.center, e.tool_start, e.tool_end, e.ccw, m.sweep)
        out.append(
            replace(m, start=(*e.tool_start, m.start[2]), end=(*e.tool_end, m.end[2]))
            if e.center is None
            else replace(
                m,
                start=(*e.tool_start, m.start[2]),
                end=(*e.tool_end, m.end[2]),
                center=center,
                sweep=sweep,
            )
        )
        tool = e.tool_end
        if i in corners:
            corner, turn = corners[i]
            after = next(f for f in elements if f.index > i)
            nxt = moves[after.index]
            z = m.end[2]
            out.append(
                replace(
                    nxt,
                    kind='arc',
                    start=(*tool, z),
                    end=(*after.tool_start, z),
                    center=(*corner, z),
                    plane=(0, 1, 2),
                    sweep=turn,
                    duration=0.0,
                    message='',
                )
            )
            tool = after.tool_start
    return out


def _element(i: int, m: Move, side: int, radius: float) -> _Element | None:
    if m.kind not in ('rapid', 'line', 'arc'):
        return None
    s, e = (m.start[0], m.start[1]), (m.end[0], m.end[1])
    if m.kind != 'arc':
        if math.dist(s, e) <= TINY:
            return None
        d = _unit(_sub(e, s))
        return _Element(i, s, e, d, d, None, 0.0, True)
    assert m.center is not None
    c = (m.center[0], m.center[1])
    ccw = m.sweep > 0.0
    sign = 1.0 if ccw else -1.0
    t_s = _unit(_left(_sub(s, c)))
    t_e = _unit(_left(_sub(e, c)))
    t_s, t_e = (sign * t_s[0], sign * t_s[1]), (sign * t_e[0], sign * t_e[1])
    r = math.dist(s, c)
    # The left of a counter-clockwise arc is its inside.
    tool_r = r - side * sign * radius
    if tool_r <= TINY:
        raise GcodeError(
            m.where,
            f'cutter compensation: the arc radius {r * 1e3:g} mm is not larger than the tool '
            f'radius {radius * 1e3:g} mm on its inner side',
        )
    return _Element(i, s, e, t_s, t_e, c, tool_r, ccw)


def _crossing(a: _Element, b: _Element, where: Where) -> Vec:
    """Where the offset paths of a and b cross, nearest the programmed corner."""
    points: list[Vec]
    if a.center is None and b.center is None:
        points = _line_line(a.tool_end, a.t_end, b.tool_start, b.t_start)
    elif a.center is None:
        assert b.center is not None
        points = _line_circle(a.tool_end, a.t_end, b.center, b.radius)
    elif b.center is None:
        points = _line_circle(b.tool_start, b.t_start, a.center, a.radius)
    else:
        points = _circle_circle(a.center, a.radius, b.center, b.radius)
    if not points:
        raise GcodeError(where, 'cutter compensation: the offset moves do not meet at this corner')
    return min(points, key=lambda p: math.dist(p, a.end))


def _line_line(p: Vec, u: Vec, q: Vec, v: Vec) -> list[Vec]:
    den = _cross(u, v)
    if abs(den) < PARALLEL:
        return []
    t = _cross(_sub(q, p), v) / den
    return [_add(p, u, t)]


def _line_circle(p: Vec, u: Vec, c: Vec, r: float) -> list[Vec]:
    f = _sub(p, c)
    b = _dot(f, u)
    disc = b * b - (_dot(f, f) - r * r)
    if disc < 0.0:
        return []
    root = math.sqrt(disc)
    return [_add(p, u, -b - root), _add(p, u, -b + root)]


def _circle_circle(c1: Vec, r1: float, c2: Vec, r2: float) -> list[Vec]:
    d = math.dist(c1, c2)
    if d < TINY or d > r1 + r2 or d < abs(r1 - r2):
        return []
    a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    h = math.sqrt(max(r1 * r1 - a * a, 0.0))
    u = _unit(_sub(c2, c1))
    mid = _add(c1, u, a)
    return [_add(mid, _left(u), h), _add(mid, _left(u), -h)]


def _sweep(c: Vec, s: Vec, e: Vec, ccw: bool, programmed: float) -> float:
    """The tool's sweep from s to e about c, the programmed direction; a full circle stays."""
    turn = math.atan2(e[1] - c[1], e[0] - c[0]) - math.atan2(s[1] - c[1], s[0] - c[0])
    if ccw:
        turn %= 2 * math.pi
    else:
        turn = -((-turn) % (2 * math.pi))
    extra = abs(programmed) - abs(turn)
    if extra > math.pi:  # full circles and turns: the whole turns stay
        turn += math.copysign(2 * math.pi * round(extra / (2 * math.pi)), programmed)
    return turn


def _check(e: _Element, m: Move) -> None:
    """A move the corners cut to nothing, or turned round, would gouge the part."""
    if e.center is None:
        if _dot(_sub(e.tool_end, e.tool_start), e.t_start) > TINY:
            return
    else:
        turn = _sweep(e.center, e.tool_start, e.tool_end, e.ccw, m.sweep)
        if abs(turn) <= abs(m.sweep) + 1e-9 and (
            abs(turn) > TINY or math.dist(e.tool_start, e.tool_end) <= TINY
        ):
            return
    raise GcodeError(
        m.where, 'cutter compensation: this move is too short for the tool radius (it would gouge)'
    )
