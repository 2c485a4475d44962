"""An RS274/NGC (G-code) part program read into moves in machine coordinates [m]. ROS-free.

The words and their meaning follow LinuxCNC (docs/user-guide.md, "G-code programs", has the
table). Defaults at the start: G21 G90 G91.1 G17 G54 G40 G49 G64 G94 G98 G80, spindle and
coolant off, tool 0, no feed, no spindle speed.

Machine position = program position + work offset (G54..G59.3) + G92/G52 offset + tool
length offset (G43). G53 moves and G28/G30 land on machine positions.

The spindle is a signed speed [rev/min]: S for M3, -S for M4, 0 off. Where it changes (M3,
M4, M5, or a new S while it runs) the program has a `spindle` move: the axes come to rest,
and the spindle takes its new speed there (a CNC waits for its spindle as well). A tool
change (M6) is a `stop` with a message (the machine is taken to have a changer: the program
goes on). M0, and M1 with the optional stop switch on (Setup.optional_stop, LinuxCNC's
default), are a `stop` that pauses: the trajectory holds there until the operator resumes
(mill_trajectory.hold). "(MSG, text)", "(DEBUG, text)" and "(PRINT, text)" are `message`
moves (nothing moves). Coolant (M7 mist, M8 flood, M9 off)
and the path tolerance (G64 P) are carried by each move; G61/G61.1 mark moves that end at
rest. Between G41/G42 and G40 the moves are offset to the tool's centre
(mill_trajectory.gcode_comp).

Within a line the words act in LinuxCNC's order: messages, F (read in the units in force
before the line's G20/G21, kept in m/s), S, T, M6, M3/M4/M5, M7/M8/M9, G4, plane, units,
G40, G43/G49, coordinate system, path mode, distance modes, retract mode, G10/G28/G30/G52/
G92, the motion (G0..G3, canned cycles, as modified by G53), then M0/M1/M2/M30.

Nothing is half-read: the first problem raises GcodeError 'file:line:column: what', and no
move is returned.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mill_trajectory.gcode_comp import compensate
from mill_trajectory.gcode_words import (
    Block,
    GcodeError,
    Key,
    Move,
    OWord,
    Parameters,
    Point,
    Where,
    Word,
    read_block,
)

# G20 inch, G21 mm: length [m] = value / divisor; mm divides by 1000 so that X-105 is -0.105
# exactly as the float a YAML file gives for -0.105. Codes are ten times the G number.
UNIT = {200: 1.0 / 0.0254, 210: 1000.0}
# The plane's first and second axes and its normal (G18: Z-X, as RS274/NGC reads it).
PLANES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}
CYCLES = {730, 810, 820, 830, 850, 890}
GROUPS: dict[str, set[int]] = {
    'motion': {0, 10, 20, 30, 800} | CYCLES,
    'plane': {170, 180, 190},
    'distance': {900, 910},
    'arc distance': {901, 911},
    'feed mode': {940},
    'units': {200, 210},
    'cutter compensation': {400, 410, 411, 420, 421},
    'tool length': {430, 431, 490},
    'retract': {980, 990},
    'coordinate system': {540, 550, 560, 570, 580, 590, 591, 592, 593},
    'path': {610, 611, 640},
    'spindle mode': {970},
    'dwell': {40},
    'non-modal': {100, 280, 281, 300, 301, 520, 920, 921, 922, 923},
    'machine': {530},
}
GROUP_OF = {code: group for group, codes in GROUPS.items() for code in codes}
REFUSED = {
    930: 'G93 inverse-time feed is not supported: use G94 (units per minute)',
    950: 'G95 feed per revolution is not supported: use G94 (units per minute)',
    960: 'G96 constant surface speed is not supported: use G97 (rev/min)',
}
M_GROUP = {0: 'stop', 1: 'stop', 2: 'stop', 30: 'stop', 3: 'spindle', 4: 'spindle', 5: 'spindle'}
M_GROUP |= {6: 'tool change', 7: 'mist', 8: 'flood', 9: 'coolant off'}
SYSTEMS = (540, 550, 560, 570, 580, 590, 591, 592, 593)  # G54 .. G59.3
AXIS = {'X': 0, 'Y': 1, 'Z': 2}
# IJK arcs, LinuxCNC's defaults: the end's radius may differ from the start's by up to
# ARC_ABSOLUTE (in the program's units), or by more when that is within ARC_RELATIVE of the
# radius, but never by more than 100 ARC_ABSOLUTE; a radius below ZERO_RADIUS is refused.
ARC_ABSOLUTE = {200: 0.002 * math.sqrt(2.0), 210: 0.02 * math.sqrt(2.0)}
ARC_RELATIVE = 1e-3
ZERO_RADIUS = {200: 5e-5, 210: 5e-5 * 25.4}
ITERATIONS = 100_000  # loop passes (while, do, repeat) in one run of a program
CALL_DEPTH = 10  # subroutine calls nested at most (as LinuxCNC)
_COMMENTS = r'(?:\s*\([^)]*\))*\s*'
_OWORD_LINE = re.compile(rf'^{_COMMENTS}/?{_COMMENTS}(?:[nN][\s\d.]*)?{_COMMENTS}[oO]')


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
class _Frame:
    """A running subroutine (or the main program): its local parameters and loops."""

    sub: str
    back: int  # line index to go on at when it returns
    numbered: dict[int, float] = field(default_factory=dict)  # #1 .. #30
    named: dict[str, float] = field(default_factory=dict)  # names without a leading '_'
    repeats: dict[int, int] = field(default_factory=dict)  # repeat line -> passes left


@dataclass
class _State:
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


def read_tool_table(path: str | Path) -> dict[int, Tool]:
    """A LinuxCNC tool table (`T1 P1 Z+0.1 D6.0 ;comment`, lengths in mm) by tool number."""
    name = str(path)
    try:
        text = Path(path).read_text(encoding='utf-8-sig')
    except FileNotFoundError:
        raise GcodeError(Where(name, 0, 0), 'no such tool table file') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise GcodeError(Where(name, 0, 0), f'cannot read: {exc}') from None
    tools: dict[int, Tool] = {}
    for number, line in enumerate(text.splitlines(), 1):
        body, _, comment = line.partition(';')
        fields: dict[str, float] = {}
        for m in re.finditer(r'\S+', body):
            where = Where(name, number, m.start() + 1)
            word = m.group(0)
            letter, rest = word[0].upper(), word[1:]
            if letter not in 'TPXYZABCUVWDIJQ':
                raise GcodeError(where, f'unknown tool table field {word!r}')
            try:
                fields[letter] = float(rest)
            except ValueError:
                raise GcodeError(where, f'malformed number in {word!r}') from None
        if not fields:
            continue
        t = fields.get('T')
        where = Where(name, number, 1)
        if t is None or t != int(t) or t < 0:
            raise GcodeError(where, 'each tool table line needs T and a tool number >= 0')
        if int(t) in tools:
            raise GcodeError(where, f'tool T{int(t)} appears twice in the tool table')
        offset = tuple(fields.get(a, 0.0) / 1000.0 for a in 'XYZ')
        tools[int(t)] = Tool(int(t), offset, fields.get('D', 0.0) / 1000.0, comment.strip())  # type: ignore[arg-type]
    return tools


def read_program(
    path: str | Path,
    start: Point,
    work_offset: Point = (0.0, 0.0, 0.0),
    setup: Setup | None = None,
) -> list[Move]:
    """Read a G-code file; the tool stands at `start` (machine coordinates [m])."""
    name = str(path)
    try:
        text = Path(path).read_text(encoding='utf-8')
    except FileNotFoundError:
        raise GcodeError(Where(name, 0, 0), 'no such G-code file') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise GcodeError(Where(name, 0, 0), f'cannot read: {exc}') from None
    return parse_program(text, name, start, work_offset, setup)


def parse_program(
    text: str,
    file: str,
    start: Point,
    work_offset: Point = (0.0, 0.0, 0.0),
    setup: Setup | None = None,
) -> list[Move]:
    """The moves of a program's text (see the module doc). work_offset is G54's, and
    replaces setup's."""
    setup = setup or Setup()
    offsets = [list(p) for p in setup.work_offsets] + [[0.0, 0.0, 0.0]] * 9
    offsets[0] = [float(v) for v in work_offset]
    state = _State(here=tuple(map(float, start)), setup=setup)  # type: ignore[arg-type]
    state.systems = [list(map(float, p)) for p in offsets[:9]]
    return _Program(text.removeprefix('\ufeff'), file, state).run()


class _Program(Parameters):
    """The program's lines, their O-word structure, its parameters, and the run."""

    def __init__(self, text: str, file: str, state: _State) -> None:
        self.lines = text.splitlines()
        self.file = file
        self.state = state
        self.end = len(self.lines)
        first = next((i for i, t in enumerate(self.lines) if t.strip()), None)
        if first is not None and self.lines[first].strip() == '%':
            # A program opened by '%' ends at the next '%'.
            close = next(
                (i for i in range(first + 1, self.end) if self.lines[i].strip() == '%'), None
            )
            self.end = self.end if close is None else close
        self.globals: dict[Key, float] = {}
        self.frames = [_Frame('', self.end)]
        self.subs: dict[str, int] = {}
        self.passes = 0
        self._structure()

    # -- parameters
    def _home(self, key: Key) -> tuple[dict[Any, float], Key]:
        frame = self.frames[-1]
        if isinstance(key, int):
            return (frame.numbered, key) if key <= 30 else (self.globals, key)
        return (self.globals, key) if key.startswith('_') else (frame.named, key)

    def read(self, key: Key, where: Where) -> float:
        table, k = self._home(key)
        if k in table:
            return float(table[k])
        if isinstance(key, int):
            s = self.state
            if 5420 <= key <= 5422:  # the current position, program coordinates
                i = key - 5420
                return (s.here[i] - s.offset(i)) * s.unit
            if key == 5220:
                return float(s.system + 1)
            if key == 5400:
                return float(s.loaded)
            return 0.0  # numbered parameters start at 0 (LinuxCNC)
        raise GcodeError(where, f'parameter #<{key}> is used before it is set')

    def exists(self, key: Key) -> bool:
        table, k = self._home(key)
        return isinstance(key, int) or k in table

    # -- the O-word structure
    def _structure(self) -> None:
        """Match every O-word block; an unclosed or mismatched one is refused."""
        self.owords: dict[int, OWord] = {}
        self.link: dict[int, int] = {}  # opener <-> closer, branch -> next branch
        self.endif: dict[int, int] = {}  # if / elseif / else -> its endif
        self.loop: dict[int, int] = {}  # break / continue -> the loop's opener
        self.sub_of: dict[int, int] = {}  # return -> its sub
        stack: list[tuple[str, str, int]] = []  # name, keyword, line index
        branch: dict[int, int] = {}  # if -> its last branch so far
        for i in range(self.end):
            if not _OWORD_LINE.match(self.lines[i]):
                continue
            o = read_block(self.lines[i], self.file, i + 1).oword
            if o is None:
                continue
            self.owords[i] = o
            k, top = o.keyword, stack[-1] if stack else None
            named = f'{o.name} {k}'
            if k in ('sub', 'if', 'do', 'repeat') or (
                k == 'while' and not (top and top[:2] == (o.name, 'do'))
            ):
                if k == 'sub' and any(s[1] == 'sub' for s in stack):
                    raise GcodeError(o.where, f'{named}: a sub cannot be defined inside a sub')
                stack.append((o.name, k, i))
                if k == 'if':
                    branch[i] = i
            elif k == 'while':  # closes a do
                assert top is not None
                self.link[top[2]], self.link[i] = i, top[2]
                stack.pop()
            elif k in ('elseif', 'else', 'endif', 'endwhile', 'endrepeat', 'endsub'):
                want = {'elseif': 'if', 'else': 'if', 'endif': 'if', 'endwhile': 'while'}
                opener = want.get(k, k[3:])
                if not top or top[:2] != (o.name, opener):
                    raise GcodeError(o.where, f'{named} without an open {o.name} {opener}')
                start = top[2]
                if opener == 'if':
                    last = branch[start]
                    if k != 'endif' and last != start and self.owords[last].keyword == 'else':
                        raise GcodeError(o.where, f'{named} after {o.name} else')
                    self.link[last] = i
                    branch[start] = i
                    self.endif[start] = i
                    if k == 'endif':
                        stack.pop()
                        node = start
                        while node != i:
                            self.endif[node] = i
                            node = self.link[node]
                else:
                    self.link[start], self.link[i] = i, start
                    stack.pop()
            elif k in ('break', 'continue', 'return'):
                kinds = ('sub',) if k == 'return' else ('while', 'do', 'repeat')
                found = None
                for s in reversed(stack):
                    if s[0] == o.name and s[1] in kinds:
                        found = s
                        break
                    if s[1] == 'sub':
                        break
                if found is None:
                    what = 'sub' if k == 'return' else 'loop'
                    raise GcodeError(o.where, f'{named} outside its {o.name} {what}')
                (self.sub_of if k == 'return' else self.loop)[i] = found[2]
        if stack:
            name, k, i = stack[-1]
            closer = {'if': 'endif', 'do': 'while', 'sub': 'endsub'}.get(k, f'end{k}')
            raise GcodeError(self.owords[i].where, f'{name} {k} is not closed (no {name} {closer})')

    # -- the run
    def run(self) -> list[Move]:
        pc = 0
        while pc < self.end:
            o = self.owords.get(pc)
            if o is not None:
                pc = self._oword(pc, o)
                continue
            block = read_block(self.lines[pc], self.file, pc + 1, self)
            assert block.oword is None, 'an O-word line the structure pass did not see'
            if block.delete and self.state.setup.block_delete:
                pc += 1
                continue
            for key, value, _where in block.settings:
                table, k = self._home(key)
                table[k] = value
            if _run_line(self.state, block, Where(self.file, pc + 1, 1)):
                break
            pc += 1
        _comp_off(self.state)
        return self.state.moves

    def _value(self, pc: int) -> tuple[OWord, tuple[float, ...]]:
        """The O-word at line pc with its values read now."""
        block = read_block(self.lines[pc], self.file, pc + 1, self)
        assert block.oword is not None
        return block.oword, block.oword.values

    def _pass(self, o: OWord) -> None:
        self.passes += 1
        if self.passes > ITERATIONS:
            raise GcodeError(
                o.where, f'{o.name} {o.keyword}: more than {ITERATIONS} loop passes (runaway loop?)'
            )

    def _oword(self, pc: int, shape: OWord) -> int:
        """Run the O-word at line pc; the next line to run."""
        k = shape.keyword
        frame = self.frames[-1]
        if k == '':  # a program number (O1001): nothing to do
            return pc + 1
        if k == 'sub':
            self.subs[shape.name] = pc
            return self.link[pc] + 1
        if k in ('endsub', 'return'):
            o, values = self._value(pc)
            if len(self.frames) == 1:
                raise GcodeError(o.where, f'{o.name} {k} outside a call')
            if values:
                self.globals['_value'] = values[0]
                self.globals['_value_returned'] = 1.0
            self.frames.pop()
            return frame.back
        if k == 'call':
            o, values = self._value(pc)
            start = self.subs.get(o.name)
            if start is None:
                raise GcodeError(o.where, f'{o.name} call: no such subroutine defined before it')
            if len(self.frames) >= CALL_DEPTH + 1:
                raise GcodeError(o.where, f'{o.name} call: more than {CALL_DEPTH} nested calls')
            if len(values) > 30:
                raise GcodeError(o.where, f'{o.name} call: at most 30 arguments')
            numbered = dict(frame.numbered)
            numbered.update({n + 1: v for n, v in enumerate(values)})
            self.frames.append(_Frame(o.name, pc + 1, numbered))
            self.globals['_value_returned'] = 0.0
            return start + 1
        if k == 'if':
            node = pc
            while True:
                kind = self.owords[node].keyword
                if kind in ('if', 'elseif'):
                    _o, values = self._value(node)
                    if values[0] != 0.0:
                        return node + 1
                    node = self.link[node]
                else:  # else: run it; endif: past it
                    return node + 1
        if k in ('elseif', 'else'):  # the branch above ran: skip to past the endif
            return self.endif[pc] + 1
        if k == 'endif':
            return pc + 1
        if k == 'while' and self.link[pc] < pc:  # the end of a do .. while
            o, values = self._value(pc)
            if values[0] != 0.0:
                self._pass(o)
                return self.link[pc] + 1
            return pc + 1
        if k == 'while':
            o, values = self._value(pc)
            return pc + 1 if values[0] != 0.0 else self.link[pc] + 1
        if k == 'endwhile':
            self._pass(shape)
            return self.link[pc]
        if k == 'do':
            return pc + 1
        if k == 'repeat':
            o, values = self._value(pc)
            count = values[0]
            if count != int(count) or count < 0:
                raise GcodeError(o.where, f'{o.name} repeat [{count:g}]: not a whole number >= 0')
            if count == 0:
                return self.link[pc] + 1
            frame.repeats[pc] = int(count)
            return pc + 1
        if k == 'endrepeat':
            start = self.link[pc]
            left = frame.repeats.get(start, 1) - 1
            if left > 0:
                self._pass(shape)
                frame.repeats[start] = left
                return start + 1
            frame.repeats.pop(start, None)
            return pc + 1
        if k in ('break', 'continue'):
            start = self.loop[pc]
            kind, end = self.owords[start].keyword, self.link[start]
            if k == 'break':
                frame.repeats.pop(start, None)
                return end + 1
            if kind == 'while':
                self._pass(shape)
                return start
            return end  # do: its while tests; repeat: its endrepeat counts
        raise GcodeError(shape.where, f'{shape.name} {k}: not supported')  # pragma: no cover


def _code(word: Word) -> int:
    code = round(word.value * 10)
    if abs(word.value * 10 - code) > 1e-6 or code < 0:
        raise GcodeError(word.where, f'unsupported code {word.text}')
    if word.letter == 'G':
        if code in REFUSED:
            raise GcodeError(word.where, REFUSED[code])
        if code not in GROUP_OF:
            raise GcodeError(word.where, f'unsupported code {word.text}')
        return code
    if code % 10 or code // 10 not in M_GROUP:
        raise GcodeError(word.where, f'unsupported code {word.text}')
    return code // 10


def _whole(word: Word, what: str, low: int = 0) -> int:
    if word.value != int(word.value) or word.value < low:
        raise GcodeError(word.where, f'{what} {word.text} must be a whole number >= {low}')
    return int(word.value)


def _run_line(state: _State, block: Block, line: Where) -> bool:
    """Run one line; True at the program's end (M2/M30)."""
    gs: dict[str, tuple[int, Word]] = {}
    ms: dict[str, tuple[int, Word]] = {}
    values: dict[str, Word] = {}
    for w in block.words:
        if w.letter in 'GM':
            code = _code(w)
            group = GROUP_OF[code] if w.letter == 'G' else M_GROUP[code]
            table = gs if w.letter == 'G' else ms
            if group == 'motion' and 'motion' in table and 800 in (code, table[group][0]):
                # "G00 G80" (Haas, Fanuc posts): the cycle ends, the other motion holds
                if code != 800:
                    table[group] = (code, w)
                continue
            if group in table:
                raise GcodeError(w.where, f'{w.text} and {table[group][1].text} on one line')
            table[group] = (code, w)
        elif w.letter in values:
            raise GcodeError(w.where, f'word {w.letter} appears twice on this line')
        else:
            values[w.letter] = w
    used: set[str] = set()
    if 'N' in values:
        _whole(values['N'], 'line number')
        used.add('N')
    codes = {c: w for c, w in gs.values()}
    m_codes = {c: w for c, w in ms.values()}
    for channel, text, where in block.messages:
        state.move('message', state.here, where, message=text, channel=channel)
    if 'F' in values:
        f = values['F']
        if not f.value > 0.0:
            raise GcodeError(f.where, f'feed {f.text} must be > 0')
        state.feed = f.value / (60.0 * state.unit)  # units per minute -> m/s
        used.add('F')
    if 'S' in values:
        if values['S'].value < 0.0:
            raise GcodeError(values['S'].where, f'spindle speed {values["S"].text} must be >= 0')
        state.speed = values['S'].value
        used.add('S')
    if 'T' in values:
        t = _whole(values['T'], 'tool number')
        _tool(state, t, values['T'])
        state.selected = t
        used.add('T')
    if 6 in m_codes:
        _tool_change(state, m_codes[6])
    for code, w in m_codes.items():
        if code in (3, 4):
            if state.speed is None:
                raise GcodeError(w.where, f'{w.text} needs a spindle speed: give S first')
            state.direction = 1 if code == 3 else -1
        elif code == 5:
            state.direction = 0
    spindle = state.direction * (state.speed or 0.0)
    if spindle != state.spindle:
        state.spindle = spindle
        state.move('spindle', state.here, line, spindle=spindle)
    if 9 in m_codes:
        state.coolant = frozenset()
    for code, name in ((7, 'mist'), (8, 'flood')):
        if code in m_codes:
            state.coolant |= {name}
    if 40 in codes:
        _dwell(state, values, codes[40], used)
    for code in codes:
        if code in PLANES:
            if state.comp is not None and code != state.plane:
                raise GcodeError(codes[code].where, 'a plane change with cutter compensation on')
            state.plane = code
        elif code in UNIT:
            state.unit, state.units = UNIT[code], code
    if gs.get('cutter compensation'):
        _cutter(state, values, gs['cutter compensation'], used)
    if 430 in codes or 431 in codes or 490 in codes:
        _tool_length(state, values, codes, used)
    for i, code in enumerate(SYSTEMS):
        if code in codes:
            state.system = i
    _path_mode(state, values, codes, used)
    for code in codes:
        if code in (900, 910):
            state.absolute = code == 900
        elif code in (901, 911):
            state.arc_absolute = code == 901
        elif code in (980, 990):
            state.retract_old_z = code == 980
    non_modal = gs.get('non-modal')
    if non_modal is not None:
        _non_modal(state, values, non_modal, used)
    if non_modal is None or 'motion' in gs:
        _motion(state, values, gs, line, used, axis_words=non_modal is None)
    for letter, w in values.items():
        if letter not in used:
            raise GcodeError(w.where, f'word {w.text} is not used on this line')
    for code, w in m_codes.items():
        if code == 0 or (code == 1 and state.setup.optional_stop):
            what = 'M0: program stop' if code == 0 else 'M1: optional stop'
            state.move('stop', state.here, w.where, message=what, pause=True)
        elif code in (2, 30):
            return True
    return False


def _tool(state: _State, number: int, word: Word) -> Tool:
    tools = state.setup.tools
    if tools is None:
        return Tool(number)
    if number == 0:
        return tools.get(0, Tool(0))
    if number not in tools:
        table = state.setup.tool_table or 'the tool table'
        raise GcodeError(word.where, f'tool T{number} is not in {table}')
    return tools[number]


def _tool_change(state: _State, m6: Word) -> None:
    if state.selected is None:
        raise GcodeError(m6.where, 'M6 needs a tool: give T first')
    tool = _tool(state, state.selected, m6)
    state.loaded = state.selected
    about = f', {tool.diameter * 1e3:g} mm diameter' if tool.diameter else ''
    about += f', {tool.comment}' if tool.comment else ''
    text = f'tool change: put in T{tool.number}{about}'
    state.move('stop', state.here, m6.where, message=text)


def _unused(values: dict[str, Word], letters: str, why: str) -> None:
    for letter in letters:
        if letter in values:
            raise GcodeError(values[letter].where, f'word {values[letter].text} {why}')


def _dwell(state: _State, values: dict[str, Word], g4: Word, used: set[str]) -> None:
    p = values.get('P')
    if p is None:
        raise GcodeError(g4.where, 'G4 needs P, the dwell time [s]')
    if p.value < 0.0:
        raise GcodeError(p.where, f'dwell {p.text} must be >= 0 s')
    used.add('P')
    state.move('dwell', state.here, p.where, duration=p.value)


def _cutter(state: _State, values: dict[str, Word], g: tuple[int, Word], used: set[str]) -> None:
    code, word = g
    if code == 400:
        _comp_off(state)
        return
    if state.comp is not None:
        raise GcodeError(word.where, f'{word.text}: cutter compensation is already on (G40 first)')
    if state.plane != 170:
        raise GcodeError(word.where, f'{word.text}: cutter compensation only in the G17 plane')
    d = values.get('D')
    used.add('D')
    if code in (411, 421):  # G41.1 / G42.1 D: the diameter itself
        if d is None or d.value < 0.0:
            raise GcodeError(word.where, f'{word.text} needs D, the tool diameter (>= 0)')
        diameter = d.value / state.unit
    else:
        number = state.loaded if d is None else _whole(d, 'tool number')
        diameter = _tool(state, number or state.loaded, d or word).diameter
    state.comp = (1 if code in (410, 411) else -1, 0.5 * diameter, len(state.moves))


def _comp_off(state: _State) -> None:
    """G40 (or the program's end): the moves since G41/G42 offset to the tool's centre."""
    if state.comp is None:
        return
    side, radius, first = state.comp
    state.comp = None
    state.moves[first:] = compensate(state.moves[first:], side, radius)
    if state.moves[first:]:
        state.here = state.moves[-1].end


def _tool_length(
    state: _State, values: dict[str, Word], codes: dict[int, Word], used: set[str]
) -> None:
    if 490 in codes:
        state.tool_offset = [0.0, 0.0, 0.0]
    elif 430 in codes:
        h = values.get('H')
        number = state.loaded if h is None else _whole(h, 'tool number')
        if h is not None and number == 0:
            number = state.loaded
        tool = _tool(state, number, h or codes[430])
        state.tool_offset = list(tool.offset)
        used.add('H')
    else:
        given = [(AXIS[a], values[a]) for a in 'XYZ' if a in values]
        if not given:
            raise GcodeError(codes[431].where, 'G43.1 needs an offset: X, Y or Z')
        for i, w in given:
            state.tool_offset[i] = w.value / state.unit
            used.add(w.letter)


def _path_mode(
    state: _State, values: dict[str, Word], codes: dict[int, Word], used: set[str]
) -> None:
    if 610 in codes or 611 in codes:
        state.exact = True
    elif 640 in codes:
        state.exact = False
        p, q = values.get('P'), values.get('Q')
        for w in (p, q):
            if w is not None and w.value < 0.0:
                raise GcodeError(w.where, f'{w.text} must be >= 0')
        # P: how far the path may leave the programmed one; Q (CAM line merging): ignored.
        state.tolerance = p.value / state.unit if p is not None and p.value > 0 else None
        used.update('PQ')


def _axes(values: dict[str, Word], used: set[str]) -> list[tuple[int, Word]]:
    given = [(AXIS[a], values[a]) for a in 'XYZ' if a in values]
    used.update(a for a in 'XYZ' if a in values)
    return given


def _non_modal(state: _State, values: dict[str, Word], g: tuple[int, Word], used: set[str]) -> None:
    code, word = g
    given = _axes(values, used)
    if code == 100:
        _set_system(state, values, word, given, used)
    elif code in (280, 300):
        if state.comp is not None:
            raise GcodeError(word.where, f'{word.text} with cutter compensation on (G40 first)')
        home = state.setup.home if code == 280 else state.setup.home2
        if given:
            middle = _target(state, values)
            state.move('rapid', middle, word.where)
            end = list(state.here)
            for i, _w in given:
                end[i] = home[i]
            state.move('rapid', (end[0], end[1], end[2]), word.where)
        else:
            state.move('rapid', home, word.where)
    elif code in (281, 301):
        _unused(values, 'XYZ', f'is not used by {word.text}')
        stored = state.here
        state.setup = _replace_home(state.setup, code == 281, stored)
    elif code == 520:
        if not given:
            raise GcodeError(word.where, 'G52 needs at least one of X, Y, Z')
        for i, w in given:
            state.g92[i] = w.value / state.unit
        state.g92_saved = list(state.g92)
    elif code == 920:
        if not given:
            raise GcodeError(word.where, 'G92 needs at least one of X, Y, Z')
        for i, w in given:
            state.g92[i] = (
                state.here[i]
                - state.systems[state.system][i]
                - state.tool_offset[i]
                - w.value / state.unit
            )
        state.g92_saved = list(state.g92)
    elif code in (921, 922):
        _unused(values, 'XYZ', f'is not used by {word.text}')
        state.g92 = [0.0, 0.0, 0.0]
        if code == 921:
            state.g92_saved = [0.0, 0.0, 0.0]
    elif code == 923:
        _unused(values, 'XYZ', f'is not used by {word.text}')
        state.g92 = list(state.g92_saved)


def _replace_home(setup: Setup, first: bool, point: Point) -> Setup:
    return replace(setup, home=point) if first else replace(setup, home2=point)


def _set_system(
    state: _State,
    values: dict[str, Word],
    g10: Word,
    given: list[tuple[int, Word]],
    used: set[str],
) -> None:
    lw, pw = values.get('L'), values.get('P')
    if lw is None or lw.value not in (2.0, 20.0):
        where = lw.where if lw else g10.where
        raise GcodeError(where, 'only G10 L2 and G10 L20 (coordinate systems) are supported')
    if pw is None:
        raise GcodeError(g10.where, f'G10 L{lw.value:g} needs P, the coordinate system 0..9')
    p = _whole(pw, 'coordinate system P')
    if p > 9:
        raise GcodeError(pw.where, f'coordinate system {pw.text} must be 0..9')
    r = values.get('R')
    if r is not None and r.value != 0.0:
        raise GcodeError(r.where, 'a rotated coordinate system (G10 R) is not supported')
    used.update('LPR')
    index = state.system if p == 0 else p - 1
    for i, w in given:
        v = w.value / state.unit
        if lw.value == 2.0:
            state.systems[index][i] = v
        else:  # L20: the current point gets coordinate v
            state.systems[index][i] = state.here[i] - state.g92[i] - state.tool_offset[i] - v


def _target(state: _State, values: dict[str, Word], machine: bool = False) -> Point:
    p = list(state.here)
    for letter, i in AXIS.items():
        if letter in values:
            v = values[letter].value / state.unit
            if machine:
                p[i] = v
            else:
                p[i] = v + state.offset(i) if state.absolute else p[i] + v
    return (p[0], p[1], p[2])


def _motion(
    state: _State,
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
        _cycle(state, values, where, used)
        return
    if g is not None and g[0] in CYCLES:
        raise GcodeError(g[1].where, f'{g[1].text} needs a hole position (X, Y or Z)')
    if not has_axes or not axis_words:
        ijk = [c for c in 'IJK' if c in values]
        if state.motion in (20, 30) and ijk and axis_words:
            _axes(values, used)
            _arc_move(state, values, state.here, where, used)  # a full circle: end = start
            return
        _unused(values, 'IJKR', 'needs G2 or G3 and an end point')
        return
    if state.motion is None and g53 is None:
        raise GcodeError(where, 'an end point without a motion (G0, G1, G2 or G3)')
    _axes(values, used)
    end = _target(state, values, machine=g53 is not None)
    if state.motion == 0 or state.motion is None:  # G53 after G80: a rapid (Haas posts)
        _unused(values, 'IJKR', 'is not used by G0')
        state.move('rapid', end, where)
    elif state.motion == 10:
        _need_feed(state, where)
        _unused(values, 'IJKR', 'is not used by G1')
        state.move('line', end, where, feed=state.feed)
    else:
        _arc_move(state, values, end, where, used)


def _need_feed(state: _State, where: Where) -> None:
    if state.feed is None:
        raise GcodeError(where, 'no feed: give F before the first G1, G2 or G3')


def _arc_move(
    state: _State, values: dict[str, Word], end: Point, where: Where, used: set[str]
) -> None:
    _need_feed(state, where)
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
        turns = _whole(values['P'], 'arc turns', 1)
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


def _cycle(state: _State, values: dict[str, Word], where: Where, used: set[str]) -> None:
    """A canned cycle (G73 G81 G82 G83 G85 G89) at each position of this line."""
    motion = state.motion
    assert motion is not None
    name = f'G{motion // 10}'
    if state.plane != 170:
        raise GcodeError(where, f'{name}: canned cycles only in the G17 (XY) plane')
    _need_feed(state, where)
    _unused(values, 'IJK', f'is not used by {name}')
    sticky = state.cycle
    for letter in 'RZPQ':
        if letter in values:
            sticky[letter] = values[letter].value
            used.add(letter)
    if 'R' not in sticky:
        raise GcodeError(where, f'{name} needs R, the retract height')
    if 'Z' not in sticky:
        raise GcodeError(where, f'{name} needs Z, the hole bottom')
    if motion in (820, 890) and 'P' not in sticky:
        raise GcodeError(where, f'{name} needs P, the dwell at the bottom [s]')
    if motion in (820, 890) and sticky['P'] < 0:
        p_where = values['P'].where if 'P' in values else where
        raise GcodeError(p_where, f'{name} dwell P must be >= 0 s')
    if motion in (730, 830):
        if 'Q' not in sticky:
            raise GcodeError(where, f'{name} needs Q, the peck depth')
        if not sticky['Q'] > 0:
            q_where = values['Q'].where if 'Q' in values else where
            raise GcodeError(q_where, f'{name} peck depth Q must be > 0')
    repeat = 1
    if 'L' in values:
        repeat = _whole(values['L'], 'repeat count L', 1)
        used.add('L')
    delta = state.setup.peck_clearance
    if 'D' in values:
        if values['D'].value < 0:
            raise GcodeError(values['D'].where, f'peck clearance {values["D"].text} must be >= 0')
        delta = values['D'].value / state.unit
        used.add('D')
    _axes(values, used)
    u, z_off = state.unit, state.offset(2)
    current = state.here[2]
    if state.cycle_initial is None:
        state.cycle_initial = current
    old = state.cycle_initial
    if state.absolute:
        r, bottom = sticky['R'] / u + z_off, sticky['Z'] / u + z_off
        x = values['X'].value / u + state.offset(0) if 'X' in values else state.here[0]
        y = values['Y'].value / u + state.offset(1) if 'Y' in values else state.here[1]
        dx = dy = 0.0
    else:
        r = sticky['R'] / u + old
        bottom = r + sticky['Z'] / u
        x, y = state.here[0], state.here[1]
        dx = values['X'].value / u if 'X' in values else 0.0
        dy = values['Y'].value / u if 'Y' in values else 0.0
    if r < bottom:
        raise GcodeError(where, f'{name}: the retract height R is below the hole bottom Z')
    exact = state.exact
    state.exact = True  # canned cycles run in exact path mode (as LinuxCNC)
    if old < r:
        state.move('rapid', (state.here[0], state.here[1], r), where)
        old = current = r
    clear = old if state.retract_old_z else r
    for k in range(repeat):
        x, y = x + dx, y + dy
        if k == 0 and current > r:
            state.move('rapid', (x, y, current), where)
            state.move('rapid', (x, y, r), where)
        else:
            state.move('rapid', (x, y, clear), where)
            if clear > r:
                state.move('rapid', (x, y, r), where)
        _drill(state, motion, x, y, r, bottom, clear, delta, where)
    state.exact = exact


def _drill(
    state: _State,
    motion: int,
    x: float,
    y: float,
    r: float,
    bottom: float,
    clear: float,
    delta: float,
    where: Where,
) -> None:
    feed = state.feed
    sticky = state.cycle
    if motion in (730, 830):
        q = sticky['Q'] / state.unit
        depth = r - q
        while depth > bottom:
            state.move('line', (x, y, depth), where, feed=feed)
            if motion == 830:
                state.move('rapid', (x, y, r), where)
            state.move('rapid', (x, y, depth + delta), where)
            depth -= q
    state.move('line', (x, y, bottom), where, feed=feed)
    if motion in (820, 890):
        state.move('dwell', (x, y, bottom), where, duration=sticky['P'])
    if motion == 850:
        state.move('line', (x, y, r), where, feed=feed)
    if motion == 890:
        state.move('line', (x, y, clear), where, feed=feed)
    else:
        state.move('rapid', (x, y, clear), where)
