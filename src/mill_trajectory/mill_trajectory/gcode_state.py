"""The G-code interpreter's modal state, the machine's setup and the helpers every word uses.

`State` is what a running program carries from line to line (mill_trajectory.gcode: units,
distance modes, plane, motion, feed, spindle, coolant, offsets, tool, path mode, canned
cycle, cutter compensation) and the moves so far; `Setup` is the machine side (work
offsets, G28/G30 positions, tool table, switches). ROS-free.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from mill_trajectory.gcode_words import GcodeError, Move, Point, Where, Word

AXIS = {'X': 0, 'Y': 1, 'Z': 2}


@dataclass(frozen=True)
class Tool:
    """A tool table entry: offsets x, y, z [m] (z: the length) and diameter [m]."""

    number: int
    offset: Point = (0.0, 0.0, 0.0)
    diameter: float = 0.0
    comment: str = ''


@dataclass(frozen=True)
class Setup:
    """The machine side of a program: work offsets G54..G59.3 (machine position of each
    program zero [m]), the G28 and G30 positions [m], the tool table (None: no table, every
    tool has zero offsets), the block delete switch, the G73/G83 peck clearance [m]."""

    work_offsets: tuple[Point, ...] = ((0.0, 0.0, 0.0),) * 9
    home: Point = (0.0, 0.0, 0.0)
    home2: Point = (0.0, 0.0, 0.0)
    tools: Mapping[int, Tool] | None = None
    tool_table: str = ''
    block_delete: bool = False
    peck_clearance: float = 0.001  # LinuxCNC's default on a metric machine: 1 mm
    optional_stop: bool = True  # M1 pauses as M0 (LinuxCNC's optional-stop switch on)


@dataclass
class State:
    here: Point
    setup: Setup
    unit: float = 1000.0  # divisor: value / unit = metres
    units: int = 210
    absolute: bool = True
    arc_absolute: bool = False
    plane: int = 170
    motion: int | None = None
    feed: float | None = None
    speed: float | None = None  # S [rev/min], once given
    direction: int = 0  # 1 M3, -1 M4, 0 off
    spindle: float = 0.0
    coolant: frozenset[str] = frozenset()
    system: int = 0  # G54 .. G59.3 as 0 .. 8
    systems: list[list[float]] = field(default_factory=list)
    g92: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    g92_saved: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    tool_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    selected: int | None = None
    loaded: int = 0
    tolerance: float | None = None
    exact: bool = False
    retract_old_z: bool = True  # G98
    cycle_initial: float | None = None  # machine z where the canned cycles began
    cycle: dict[str, float] = field(default_factory=dict)  # sticky R, Z, P, Q
    comp: tuple[int, float, int] | None = None  # G41/G42: side (1 left), radius [m], first move
    moves: list[Move] = field(default_factory=list)

    def offset(self, i: int) -> float:
        return self.systems[self.system][i] + self.g92[i] + self.tool_offset[i]

    def move(self, kind: str, end: Point, where: Where, **more: Any) -> None:
        given: dict[str, Any] = {
            'spindle': self.spindle,
            'coolant': '+'.join(sorted(self.coolant)),
            'tolerance': self.tolerance,
            'exact_stop': self.exact,
        }
        self.moves.append(Move(kind, self.here, end, where, **(given | more)))
        self.here = end


def whole(word: Word, what: str, low: int = 0) -> int:
    if word.value != int(word.value) or word.value < low:
        raise GcodeError(word.where, f'{what} {word.text} must be a whole number >= {low}')
    return int(word.value)


def unused(values: dict[str, Word], letters: str, why: str) -> None:
    for letter in letters:
        if letter in values:
            raise GcodeError(values[letter].where, f'word {values[letter].text} {why}')


def axes(values: dict[str, Word], used: set[str]) -> list[tuple[int, Word]]:
    given = [(AXIS[a], values[a]) for a in 'XYZ' if a in values]
    used.update(a for a in 'XYZ' if a in values)
    return given


def target(state: State, values: dict[str, Word], machine: bool = False) -> Point:
    p = list(state.here)
    for letter, i in AXIS.items():
        if letter in values:
            v = values[letter].value / state.unit
            if machine:
                p[i] = v
            else:
                p[i] = v + state.offset(i) if state.absolute else p[i] + v
    return (p[0], p[1], p[2])


def need_feed(state: State, where: Where) -> None:
    if state.feed is None:
        raise GcodeError(where, 'no feed: give F before the first G1, G2 or G3')
