"""Tools in a G-code program: the tool table, T and M6, tool length offsets (G43, G43.1,
G49) and cutter compensation (G40, G41, G42; the offset path: mill_trajectory.gcode_comp).
ROS-free.
"""

from __future__ import annotations

import re
from pathlib import Path

from mill_trajectory.gcode_comp import compensate
from mill_trajectory.gcode_state import AXIS, State, Tool, whole
from mill_trajectory.gcode_words import GcodeError, Where, Word, read_file


def read_tool_table(path: str | Path) -> dict[int, Tool]:
    """A LinuxCNC tool table (`T1 P1 Z+0.1 D6.0 ;comment`, lengths in mm) by tool number."""
    name = str(path)
    text = read_file(path, 'utf-8-sig', 'tool table')
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


def tool_of(state: State, number: int, word: Word) -> Tool:
    tools = state.setup.tools
    if tools is None:
        return Tool(number)
    if number == 0:
        return tools.get(0, Tool(0))
    if number not in tools:
        table = state.setup.tool_table or 'the tool table'
        raise GcodeError(word.where, f'tool T{number} is not in {table}')
    return tools[number]


def tool_change(state: State, m6: Word) -> None:
    if state.selected is None:
        raise GcodeError(m6.where, 'M6 needs a tool: give T first')
    tool = tool_of(state, state.selected, m6)
    state.loaded = state.selected
    about = f', {tool.diameter * 1e3:g} mm diameter' if tool.diameter else ''
    about += f', {tool.comment}' if tool.comment else ''
    text = f'tool change: put in T{tool.number}{about}'
    state.move('stop', state.here, m6.where, message=text)


def cutter_comp(state: State, values: dict[str, Word], g: tuple[int, Word], used: set[str]) -> None:
    code, word = g
    if code == 400:
        comp_off(state)
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
        number = state.loaded if d is None else whole(d, 'tool number')
        diameter = tool_of(state, number or state.loaded, d or word).diameter
    state.comp = (1 if code in (410, 411) else -1, 0.5 * diameter, len(state.moves))


def comp_off(state: State) -> None:
    """G40 (or the program's end): the moves since G41/G42 offset to the tool's centre."""
    if state.comp is None:
        return
    side, radius, first = state.comp
    state.comp = None
    state.moves[first:] = compensate(state.moves[first:], side, radius)
    if state.moves[first:]:
        state.here = state.moves[-1].end


def tool_length(
    state: State, values: dict[str, Word], codes: dict[int, Word], used: set[str]
) -> None:
    if 490 in codes:
        state.tool_offset = [0.0, 0.0, 0.0]
    elif 430 in codes:
        h = values.get('H')
        number = state.loaded if h is None else whole(h, 'tool number')
        if h is not None and number == 0:
            number = state.loaded
        tool = tool_of(state, number, h or codes[430])
        state.tool_offset = list(tool.offset)
        used.add('H')
    else:
        given = [(AXIS[a], values[a]) for a in 'XYZ' if a in values]
        if not given:
            raise GcodeError(codes[431].where, 'G43.1 needs an offset: X, Y or Z')
        for i, w in given:
            state.tool_offset[i] = w.value / state.unit
            used.add(w.letter)
