"""The canned drilling cycles of a program (G73 G81 G82 G83 G85 G89) as rapids, feeds and
dwells, in the G17 plane, with G98/G99 retract. ROS-free.
"""

from __future__ import annotations

from mill_trajectory.gcode_state import State, axes, need_feed, unused, whole
from mill_trajectory.gcode_words import GcodeError, Where, Word


def run_cycle(state: State, values: dict[str, Word], where: Where, used: set[str]) -> None:
    """A canned cycle (G73 G81 G82 G83 G85 G89) at each position of this line."""
    motion = state.motion
    assert motion is not None
    name = f'G{motion // 10}'
    if state.plane != 170:
        raise GcodeError(where, f'{name}: canned cycles only in the G17 (XY) plane')
    need_feed(state, where)
    unused(values, 'IJK', f'is not used by {name}')
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
        repeat = whole(values['L'], 'repeat count L', 1)
        used.add('L')
    delta = state.setup.peck_clearance
    if 'D' in values:
        if values['D'].value < 0:
            raise GcodeError(values['D'].where, f'peck clearance {values["D"].text} must be >= 0')
        delta = values['D'].value / state.unit
        used.add('D')
    axes(values, used)
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
    state: State,
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
