"""The non-modal G-codes of a program: coordinate systems (G10 L2/L20), the G92 and G52
offsets, and the G28/G30 home positions (going there, and G28.1/G30.1 storing them).
ROS-free.
"""

from __future__ import annotations

from dataclasses import replace

from mill_trajectory.gcode_state import Setup, State, axes, target, unused, whole
from mill_trajectory.gcode_words import GcodeError, Point, Word


def run_non_modal(
    state: State, values: dict[str, Word], g: tuple[int, Word], used: set[str]
) -> None:
    code, word = g
    given = axes(values, used)
    if code == 100:
        _set_system(state, values, word, given, used)
    elif code in (280, 300):
        if state.comp is not None:
            raise GcodeError(word.where, f'{word.text} with cutter compensation on (G40 first)')
        home = state.setup.home if code == 280 else state.setup.home2
        if given:
            middle = target(state, values)
            state.move('rapid', middle, word.where)
            end = list(state.here)
            for i, _w in given:
                end[i] = home[i]
            state.move('rapid', (end[0], end[1], end[2]), word.where)
        else:
            state.move('rapid', home, word.where)
    elif code in (281, 301):
        unused(values, 'XYZ', f'is not used by {word.text}')
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
        unused(values, 'XYZ', f'is not used by {word.text}')
        state.g92 = [0.0, 0.0, 0.0]
        if code == 921:
            state.g92_saved = [0.0, 0.0, 0.0]
    elif code == 923:
        unused(values, 'XYZ', f'is not used by {word.text}')
        state.g92 = list(state.g92_saved)


def _replace_home(setup: Setup, first: bool, point: Point) -> Setup:
    return replace(setup, home=point) if first else replace(setup, home2=point)


def _set_system(
    state: State,
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
    p = whole(pw, 'coordinate system P')
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
