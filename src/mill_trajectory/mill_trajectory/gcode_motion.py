"""The motion words of a program: G0 rapids, G1 lines, G2/G3 arcs (IJK or R, full circles,
P turns), G53 machine moves, and where a canned cycle runs (mill_trajectory.gcode_cycles).
ROS-free.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from mill_trajectory.gcode_cycles import run_cycle
from mill_trajectory.gcode_state import State, axes, need_feed, target, unused, whole
from mill_trajectory.gcode_words import GcodeError, Point, Where, Word

# The plane's first and second axes and its normal (G18: Z-X, as RS274/NGC reads it).
PLANES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}


CYCLES = {730, 810, 820, 830, 850, 890}


# IJK arcs, LinuxCNC's defaults: the end's radius may differ from the start's by up to
# ARC_ABSOLUTE (in the program's units), or by more when that is within ARC_RELATIVE of the
# radius, but never by more than 100 ARC_ABSOLUTE; a radius below ZERO_RADIUS is refused.
ARC_ABSOLUTE = {200: 0.002 * math.sqrt(2.0), 210: 0.02 * math.sqrt(2.0)}


ARC_RELATIVE = 1e-3


ZERO_RADIUS = {200: 5e-5, 210: 5e-5 * 25.4}


def run_motion(
    state: State,
    values: dict[str, Word],
    gs: Mapping[str, tuple[int, Word]],
    line: Where,
    used: set[str],
    axis_words: bool = True,
) -> None:
    g = gs.get('motion')
    if g is not None:
        if g[0] != state.motion:  # R, Z, P, Q are sticky within one cycle only
            state.cycle = {}
        if g[0] not in CYCLES:  # the initial level lasts while cycles follow cycles
            state.cycle_initial = None
        state.motion = None if g[0] == 800 else g[0]
    g53 = gs.get('machine')
    has_axes = any(a in values for a in 'XYZ')
    where = g[1].where if g else line
    if g53 is not None:
        if state.motion not in (0, 10, None):
            raise GcodeError(g53[1].where, 'G53 needs G0 or G1')
        if not has_axes:
            raise GcodeError(g53[1].where, 'G53 needs an end point (X, Y or Z)')
    if g is not None and g[0] == 800 and has_axes and axis_words:
        raise GcodeError(where, 'axis words with G80 (no motion)')
    if state.comp is not None and (g53 is not None or (state.motion in CYCLES and has_axes)):
        raise GcodeError(where, 'not with cutter compensation on (G40 first)')
    if state.motion in CYCLES and axis_words and has_axes:
        run_cycle(state, values, where, used)
        return
    if g is not None and g[0] in CYCLES:
        raise GcodeError(g[1].where, f'{g[1].text} needs a hole position (X, Y or Z)')
    if not has_axes or not axis_words:
        ijk = [c for c in 'IJK' if c in values]
        if state.motion in (20, 30) and ijk and axis_words:
            axes(values, used)
            _arc_move(state, values, state.here, where, used)  # a full circle: end = start
            return
        unused(values, 'IJKR', 'needs G2 or G3 and an end point')
        return
    if state.motion is None and g53 is None:
        raise GcodeError(where, 'an end point without a motion (G0, G1, G2 or G3)')
    axes(values, used)
    end = target(state, values, machine=g53 is not None)
    if state.motion == 0 or state.motion is None:  # G53 after G80: a rapid (Haas posts)
        unused(values, 'IJKR', 'is not used by G0')
        state.move('rapid', end, where)
    elif state.motion == 10:
        need_feed(state, where)
        unused(values, 'IJKR', 'is not used by G1')
        state.move('line', end, where, feed=state.feed)
    else:
        _arc_move(state, values, end, where, used)


def _arc_move(
    state: State, values: dict[str, Word], end: Point, where: Where, used: set[str]
) -> None:
    need_feed(state, where)
    a, b, n = PLANES[state.plane]
    ccw = state.motion == 30
    s, e = state.here, end
    names = 'IJK'
    in_plane = {names[a], names[b]}
    for c in set(names) - in_plane:  # the normal's word: allowed as 0 (CAM posts write K0)
        if c in values and values[c].value != 0.0:
            raise GcodeError(
                values[c].where, f'word {values[c].text} is not in the G{state.plane // 10} plane'
            )
    used.update(names)
    turns = 1
    if 'P' in values:
        turns = whole(values['P'], 'arc turns', 1)
        used.add('P')
    chord = math.hypot(e[a] - s[a], e[b] - s[b])
    g = f'G{(state.motion or 0) // 10}'
    if 'R' in values:
        r_word = values['R']
        used.add('R')
        if in_plane & values.keys():
            raise GcodeError(r_word.where, 'R cannot go with I, J or K')
        r = r_word.value / state.unit
        if chord == 0.0:
            raise GcodeError(r_word.where, 'an R arc needs an end point away from its start')
        if abs(r) < 0.5 * chord * (1.0 - 1e-9):
            raise GcodeError(
                r_word.where,
                f'arc radius {abs(r) * 1e3:g} mm does not reach its end point '
                f'({chord * 1e3:g} mm away, at most twice the radius)',
            )
        h = math.sqrt(max(r * r - 0.25 * chord * chord, 0.0))
        side = 1.0 if ccw != (r < 0.0) else -1.0  # centre left of start->end for a short G3
        ua, ub = (e[a] - s[a]) / chord, (e[b] - s[b]) / chord
        ca = 0.5 * (s[a] + e[a]) - side * h * ub
        cb = 0.5 * (s[b] + e[b]) + side * h * ua
    else:
        given = in_plane & values.keys()
        if not given:
            raise GcodeError(where, f'{g} needs a centre ({"/".join(sorted(in_plane))}) or R')
        if state.arc_absolute and len(given) < 2:
            missing = sorted(in_plane - given)[0]
            raise GcodeError(where, f'{g} with G90.1 needs both centre words: {missing} missing')
        off = [values[c].value / state.unit if c in values else 0.0 for c in names]
        if state.arc_absolute:
            ca, cb = off[a] + state.offset(a), off[b] + state.offset(b)
        else:
            ca, cb = s[a] + off[a], s[b] + off[b]
        r0 = math.hypot(s[a] - ca, s[b] - cb)
        r1 = math.hypot(e[a] - ca, e[b] - cb)
        zero = ZERO_RADIUS[state.units] / state.unit
        if r0 < zero or r1 < zero:
            raise GcodeError(where, 'arc of zero radius (its centre is its start or end)')
        err = abs(r1 - r0)
        tol = ARC_ABSOLUTE[state.units] / state.unit
        if err > 100.0 * tol or (err > tol and err > ARC_RELATIVE * max(r0, r1)):
            raise GcodeError(
                where,
                f'arc end point is not on its circle: {r1 * 1e3:g} mm from the centre, '
                f'the start {r0 * 1e3:g} mm',
            )
    start_angle = math.atan2(s[b] - cb, s[a] - ca)
    sweep = math.atan2(e[b] - cb, e[a] - ca) - start_angle
    if ccw:
        sweep = sweep % (2 * math.pi) or (2 * math.pi if chord == 0.0 else 0.0)
    else:
        sweep = -((-sweep) % (2 * math.pi) or (2 * math.pi if chord == 0.0 else 0.0))
    sweep += math.copysign(2 * math.pi * (turns - 1), sweep)
    center = [0.0, 0.0, 0.0]
    center[a], center[b], center[n] = ca, cb, s[n]
    state.move(
        'arc',
        e,
        where,
        feed=state.feed,
        center=(center[0], center[1], center[2]),
        plane=(a, b, n),
        sweep=sweep,
    )
