"""An RS274/NGC (G-code) part program read into moves in machine coordinates [m]. ROS-free.

The subset (docs/user-guide.md, "G-code programs"): G0, G1, G2/G3 with I J K centres or R
(helical with the third axis), G4 P dwell [s], G17/G18/G19 planes, G20/G21 units,
G90/G91 distance modes, G54 (the one work coordinate system, offset by `work_offset`),
G92 (shift it so the current point has the given coordinates), F in units per minute,
S [rev/min], M3/M4 (spindle on, clockwise / counter-clockwise), M5 (off), M0 (stop at
rest), M1 (optional stop: the switch is off, so ignored), M2/M30 (end: the rest of the
file is not read), N line numbers, comments.
Defaults at the start: G21 G90 G17 G54, spindle off, no feed, no spindle speed.

The spindle is a signed speed [rev/min]: S for M3, -S for M4, 0 off. Where it changes (M3,
M4, M5, or a new S while it runs) the program has a `spindle` move: the axes come to rest,
and the spindle takes its new speed there (a CNC waits for its spindle as well).

Within a line the words act in this order: plane, units and distance mode, F (read in the
units now in force, kept in m/s), S, M3/M4/M5, G4 or G92 or the motion, then M0/M1/M2/M30.
Nothing is half-read: the first problem raises GcodeError 'file:line:column: what', and no
move is returned.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from mill_trajectory.gcode_words import GcodeError, Where, Word, words_of

Point = tuple[float, float, float]

# G20 inch, G21 mm: length [m] = value / divisor; mm divides by 1000 so that X-105 is -0.105
# exactly as the float a YAML file gives for -0.105.
UNIT = {20: 1.0 / 0.0254, 21: 1000.0}
# The plane's first and second axes and its normal (G18: Z-X, as RS274/NGC reads it).
PLANES = {17: (0, 1, 2), 18: (2, 0, 1), 19: (1, 2, 0)}
MOTION = {0, 1, 2, 3}
G_KNOWN = MOTION | {4, 17, 18, 19, 20, 21, 54, 90, 91, 92}
M_KNOWN = {0, 1, 2, 3, 4, 5, 30}
AXIS = {'X': 0, 'Y': 1, 'Z': 2}
CENTRE = {'I': 0, 'J': 1, 'K': 2}
# IJK arcs: the end may miss the start's circle by this much (the larger) [m, -].
ARC_RADIUS_TOLERANCE = 5e-6
ARC_RADIUS_RELATIVE = 1e-3


@dataclass(frozen=True)
class Move:
    """One step of the program. kind: rapid, line, arc, dwell, stop (come to rest) or
    spindle (come to rest; the spindle changes to `spindle`)."""

    kind: str
    start: Point
    end: Point
    where: Where
    feed: float | None = None  # line, arc [m/s]
    center: Point | None = None  # arc, in the plane (the normal coordinate is start's)
    plane: tuple[int, int, int] = (0, 1, 2)
    sweep: float = 0.0  # arc: signed angle about the normal [rad], > 0 counter-clockwise
    duration: float = 0.0  # dwell [s]
    spindle: float = 0.0  # spindle speed during this move [rev/min], signed; 0 off


@dataclass
class _State:
    here: Point
    offset: Point
    unit: float = 1000.0  # divisor: value / unit = metres
    absolute: bool = True
    plane: int = 17
    motion: int | None = None
    feed: float | None = None
    speed: float | None = None  # S [rev/min], once given
    direction: int = 0  # 1 M3, -1 M4, 0 off
    spindle: float = 0.0
    moves: list[Move] = field(default_factory=list)


def read_program(
    path: str | Path, start: Point, work_offset: Point = (0.0, 0.0, 0.0)
) -> list[Move]:
    """Read a G-code file; the tool stands at `start` (machine coordinates [m])."""
    name = str(path)
    try:
        text = Path(path).read_text(encoding='utf-8')
    except FileNotFoundError:
        raise GcodeError(Where(name, 0, 0), 'no such G-code file') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise GcodeError(Where(name, 0, 0), f'cannot read: {exc}') from None
    return parse_program(text, name, start, work_offset)


def parse_program(
    text: str, file: str, start: Point, work_offset: Point = (0.0, 0.0, 0.0)
) -> list[Move]:
    """The moves of a program's text (see the module doc)."""
    state = _State(here=tuple(map(float, start)), offset=tuple(map(float, work_offset)))  # type: ignore[arg-type]
    for number, line in enumerate(text.splitlines(), 1):
        if _run_line(state, words_of(line, file, number), Where(file, number, 1)):
            break
    return state.moves


def _code(word: Word, known: set[int]) -> int:
    code = int(word.value)
    if code != word.value or code not in known:
        raise GcodeError(word.where, f'unsupported code {word.text}')
    return code


def _run_line(state: _State, words: list[Word], line: Where) -> bool:
    """Run one line; True at the program's end (M2/M30)."""
    gs: list[tuple[int, Word]] = []
    ms: list[tuple[int, Word]] = []
    values: dict[str, Word] = {}
    for w in words:
        if w.letter == 'G':
            gs.append((_code(w, G_KNOWN), w))
        elif w.letter == 'M':
            ms.append((_code(w, M_KNOWN), w))
        elif w.letter in values:
            raise GcodeError(w.where, f'word {w.letter} appears twice on this line')
        else:
            values[w.letter] = w
    if 'N' in values and (values['N'].value < 0 or values['N'].value != int(values['N'].value)):
        raise GcodeError(values['N'].where, f'line number {values["N"].text} is not a whole number')
    codes = {c for c, _ in gs}
    motions = [(c, w) for c, w in gs if c in MOTION or c in (4, 92)]
    if len(motions) > 1:
        raise GcodeError(
            motions[1][1].where, f'{motions[1][1].text} and {motions[0][1].text} on one line'
        )
    for code in codes:
        if code in PLANES:
            state.plane = code
        elif code in UNIT:
            state.unit = UNIT[code]
        elif code in (90, 91):
            state.absolute = code == 90
    if 'F' in values:
        f = values['F']
        if not f.value > 0.0:
            raise GcodeError(f.where, f'feed {f.text} must be > 0')
        state.feed = f.value / (60.0 * state.unit)  # units per minute -> m/s
    if 'S' in values:
        if values['S'].value < 0.0:
            raise GcodeError(values['S'].where, f'spindle speed {values["S"].text} must be >= 0')
        state.speed = values['S'].value
    for code, w in ms:
        if code in (3, 4):
            if state.speed is None:
                raise GcodeError(w.where, f'{w.text} needs a spindle speed: give S first')
            state.direction = 1 if code == 3 else -1
        elif code == 5:
            state.direction = 0
    spindle = state.direction * (state.speed or 0.0)
    if spindle != state.spindle:
        state.spindle = spindle
        state.moves.append(Move('spindle', state.here, state.here, line, spindle=spindle))
    if 4 in codes:
        _dwell(state, values, line)
    elif 92 in codes:
        _set_origin(state, values, dict(gs)[92])
    else:
        _motion(state, values, [(c, w) for c, w in gs if c in MOTION], line)
    for code, w in ms:
        if code == 0:
            state.moves.append(Move('stop', state.here, state.here, w.where, spindle=state.spindle))
        elif code in (2, 30):
            return True
    return False


def _unused(values: dict[str, Word], letters: str, why: str) -> None:
    for letter in letters:
        if letter in values:
            raise GcodeError(values[letter].where, f'word {values[letter].text} {why}')


def _dwell(state: _State, values: dict[str, Word], line: Where) -> None:
    _unused(values, 'XYZIJKR', 'is not used by G4')
    p = values.get('P')
    if p is None:
        raise GcodeError(line, 'G4 needs P, the dwell time [s]')
    if p.value < 0.0:
        raise GcodeError(p.where, f'dwell {p.text} must be >= 0 s')
    state.moves.append(
        Move('dwell', state.here, state.here, p.where, duration=p.value, spindle=state.spindle)
    )


def _set_origin(state: _State, values: dict[str, Word], g92: Word) -> None:
    _unused(values, 'IJKRP', 'is not used by G92')
    given = [(AXIS[a], values[a]) for a in 'XYZ' if a in values]
    if not given:
        raise GcodeError(g92.where, 'G92 needs at least one of X, Y, Z')
    offset = list(state.offset)
    for i, w in given:
        offset[i] = state.here[i] - w.value / state.unit
    state.offset = (offset[0], offset[1], offset[2])


def _target(state: _State, values: dict[str, Word]) -> Point:
    p = list(state.here)
    for letter, i in AXIS.items():
        if letter in values:
            v = values[letter].value / state.unit
            p[i] = v + state.offset[i] if state.absolute else p[i] + v
    return (p[0], p[1], p[2])


def _motion(
    state: _State, values: dict[str, Word], gs: list[tuple[int, Word]], line: Where
) -> None:
    if gs:
        state.motion = gs[0][0]
    has_axes = any(a in values for a in 'XYZ')
    _unused(values, 'P', 'is only used by G4')
    if not has_axes:
        if gs and gs[0][0] in MOTION:
            raise GcodeError(gs[0][1].where, f'{gs[0][1].text} needs an end point (X, Y or Z)')
        _unused(values, 'IJKR', 'needs G2 or G3 and an end point')
        return
    where = gs[0][1].where if gs else line
    if state.motion is None:
        raise GcodeError(where, 'an end point without a motion (G0, G1, G2 or G3)')
    end = _target(state, values)
    if state.motion == 0:
        _unused(values, 'IJKR', 'is not used by G0')
        move = Move('rapid', state.here, end, where, spindle=state.spindle)
    else:
        if state.feed is None:
            raise GcodeError(where, 'no feed: give F before the first G1, G2 or G3')
        if state.motion == 1:
            _unused(values, 'IJKR', 'is not used by G1')
            move = Move('line', state.here, end, where, state.feed, spindle=state.spindle)
        else:
            move = _arc(state, values, end, where)
    state.moves.append(move)
    state.here = end


def _arc(state: _State, values: dict[str, Word], end: Point, where: Where) -> Move:
    a, b, n = PLANES[state.plane]
    ccw = state.motion == 3
    s, e = state.here, end
    names = 'IJK'
    in_plane = {names[a], names[b]}
    _unused(values, ''.join(set(names) - in_plane), f'is not in the G{state.plane} plane')
    chord = math.hypot(e[a] - s[a], e[b] - s[b])
    if 'R' in values:
        r_word = values['R']
        _unused(values, 'IJK', 'cannot go with R')
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
        if not in_plane & values.keys():
            raise GcodeError(
                where, f'G{state.motion} needs a centre ({"/".join(sorted(in_plane))}) or R'
            )
        off = [values[c].value / state.unit if c in values else 0.0 for c in names]
        ca, cb = s[a] + off[a], s[b] + off[b]
        r0 = math.hypot(s[a] - ca, s[b] - cb)
        r1 = math.hypot(e[a] - ca, e[b] - cb)
        if r0 == 0.0:
            raise GcodeError(where, 'arc centre is its start point (radius 0)')
        if abs(r1 - r0) > max(ARC_RADIUS_TOLERANCE, ARC_RADIUS_RELATIVE * r0):
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
    center = [0.0, 0.0, 0.0]
    center[a], center[b], center[n] = ca, cb, s[n]
    return Move(
        'arc',
        s,
        e,
        where,
        state.feed,
        (center[0], center[1], center[2]),
        (a, b, n),
        sweep,
        spindle=state.spindle,
    )
