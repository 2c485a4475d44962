"""One line of a G-code program run on the modal state: its G and M codes checked and
grouped, then its words acting in LinuxCNC's order (mill_trajectory.gcode's doc lists it).
ROS-free.
"""

from __future__ import annotations

from mill_trajectory.gcode_motion import CYCLES, PLANES, run_motion
from mill_trajectory.gcode_offsets import run_non_modal
from mill_trajectory.gcode_state import State, whole
from mill_trajectory.gcode_tools import cutter_comp, tool_change, tool_length, tool_of
from mill_trajectory.gcode_words import Block, GcodeError, Where, Word

# G20 inch, G21 mm: length [m] = value / divisor; mm divides by 1000 so that X-105 is -0.105
# exactly as the float a YAML file gives for -0.105. Codes are ten times the G number.
UNIT = {200: 1.0 / 0.0254, 210: 1000.0}


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


def run_line(state: State, block: Block, line: Where) -> bool:
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
        whole(values['N'], 'line number')
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
        t = whole(values['T'], 'tool number')
        tool_of(state, t, values['T'])
        state.selected = t
        used.add('T')
    if 6 in m_codes:
        tool_change(state, m_codes[6])
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
        cutter_comp(state, values, gs['cutter compensation'], used)
    if 430 in codes or 431 in codes or 490 in codes:
        tool_length(state, values, codes, used)
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
        run_non_modal(state, values, non_modal, used)
    if non_modal is None or 'motion' in gs:
        run_motion(state, values, gs, line, used, axis_words=non_modal is None)
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


def _dwell(state: State, values: dict[str, Word], g4: Word, used: set[str]) -> None:
    p = values.get('P')
    if p is None:
        raise GcodeError(g4.where, 'G4 needs P, the dwell time [s]')
    if p.value < 0.0:
        raise GcodeError(p.where, f'dwell {p.text} must be >= 0 s')
    used.add('P')
    state.move('dwell', state.here, p.where, duration=p.value)


def _path_mode(
    state: State, values: dict[str, Word], codes: dict[int, Word], used: set[str]
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
