"""How long a drive may hold an axis's last command, and what a gap in its states means: one
declaration, one function, for the drive and the controllers alike. ROS-free.

When an axis's fresh commands stop, the drive holds the last one (zero-order hold) while the
axis keeps its course (mill_plant.motion_guard: within `hold_deviation` of where it would be
at the speed v it had at its last fresh command), and for at most

    H(v) = min(max_hold, (excursion - hold_deviation) / |v|)

of its own ticks; then it stops the axis (mill_plant.command_table). So an axis whose command
stream ends at speed v stops within |v|·H(v) + hold_deviation <= excursion of where it
stood at its last fresh command (plus what a change of its acceleration moves it in one
period beyond the guard's extrapolation, and the brake's own stopping distance): the window
is a time derived from what the machine can do in it, not a count of periods. At rest it
is `max_hold` (DESIGN: no fresh command, report within 0.5 s), at speed it is shorter: at
16 mm/s with the defaults 31 ms, at the 0.5 m/s speed limit 1 ms.

`excursion` defaults to 1 mm, the following-error limit of the scenarios (`slotting`): an
axis that ran blind further than that could have tripped unseen.

A drive of this contract says in every state whether it has stopped the axis (the state's
`effort`: NaN while stopped, see docs/hardware-driver.md). A controller therefore never
guesses: it trips on the drive's word; a gap in the states is reported with its length and
whose stall it was (`state_gap`). Only a driver that does not say (an empty `effort`, the
old contract) is judged by the window: a gap longer than H(v) (and than a period and a half)
means it has stopped the axis.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, in_range


@dataclass(frozen=True)
class HoldWindow(ParamSet):
    """The command watchdog's window (drive) and the gap rule (controllers), declared once."""

    PREFIX: ClassVar[str] = ''
    excursion: float = param(
        0.001,
        'realtime: how far an axis may run blind when its commands stop: the drive holds the '
        'last command for at most (excursion - hold_deviation) / |v| at the speed v of its '
        'last fresh command (max_hold at rest), then stops it (braked until re-armed); the '
        "default is the scenarios' following-error limit",
        in_range(1e-6, 1.0),
        unit='m',
    )
    max_hold: float = param(
        0.5,
        'realtime: the longest the drive holds the last command of an axis at rest before it '
        'stops the axis (braked until re-armed)',
        in_range(1e-3, 60.0),
        unit='s',
    )
    hold_deviation: float = param(
        0.0005,
        'realtime: while its commands are late, an axis holds the last one only within '
        'this distance of where it would be at the speed of its last fresh command, else '
        'it is stopped (braked until re-armed); less than excursion',
        in_range(1e-6, 0.1),
        unit='m',
    )
    stall_report: float = param(
        0.01,
        "realtime: a tick of the drive (or of a controller's own watch) that wakes this much "
        'later than its period, and a gap in the states this much longer than a period, is '
        'reported as a stall, with its length on the monotonic clock',
        in_range(1e-4, 10.0),
        unit='s',
        read_only=True,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.excursion > self.hold_deviation:
            raise ParameterError(
                'excursion',
                self.excursion,
                f'must exceed hold_deviation ({self.hold_deviation:g} m): the axis may run '
                'blind at most excursion, of which hold_deviation off its course',
            )

    def hold_time(self, speed: float) -> float:
        """H(v): the longest the drive holds the last command of an axis that had speed v
        [m/s] at its last fresh command [s]."""
        return hold_time(speed, self.excursion, self.hold_deviation, self.max_hold)


def hold_time(speed: float, excursion: float, hold_deviation: float, max_hold: float) -> float:
    """H(v) = min(max_hold, (excursion - hold_deviation) / |v|) [s]; NaN speed: max_hold."""
    room = max(excursion - hold_deviation, 0.0)
    v = abs(speed)
    if not v > 0.0 or math.isnan(v):
        return max_hold
    return min(max_hold, room / v)


# -- stalls on the monotonic clock ---------------------------------------------------------
@dataclass(frozen=True)
class Stall:
    """A wake that came late: due at `due_ns`, late by `length_ns` (monotonic clock)."""

    due_ns: int
    length_ns: int
    wall_ns: int  # the wall time it woke, to say when

    @property
    def end_ns(self) -> int:
        return self.due_ns + self.length_ns

    def describe(self, who: str) -> str:
        return f'{who} stalled {1e-6 * self.length_ns:.0f} ms (monotonic)'


class StallWatch:
    """A periodic wake's lateness on the monotonic clock: a wake later than `threshold_ns`
    after the previous one plus the period is a stall of the process (its thread did not
    run: the host, a longer callback, the garbage collector)."""

    def __init__(self, period_ns: int, threshold_ns: int, keep: int = 64) -> None:
        self.period_ns = period_ns
        self.threshold_ns = threshold_ns
        self.last_ns: int | None = None
        self.recent: deque[Stall] = deque(maxlen=keep)
        self.count = 0
        self.longest: Stall | None = None

    def wake(self, mono_ns: int, wall_ns: int = 0) -> Stall | None:
        """A wake at monotonic time mono_ns: the stall it ends, if it came that late."""
        last, self.last_ns = self.last_ns, mono_ns
        if last is None:
            return None
        late = mono_ns - last - self.period_ns
        if late <= self.threshold_ns:
            return None
        stall = Stall(last + self.period_ns, late, wall_ns)
        self.recent.append(stall)
        self.count += 1
        if self.longest is None or late > self.longest.length_ns:
            self.longest = stall
        return stall

    def within(self, start_ns: int, end_ns: int) -> int:
        """How long this process was stalled within [start_ns, end_ns] (monotonic) [ns]: its
        recorded stalls, and the one it is in if its next wake is overdue at end_ns (asked
        from a callback that ran before the late wake's own: the stall is not over yet)."""
        total = sum(max(0, min(end_ns, s.end_ns) - max(start_ns, s.due_ns)) for s in self.recent)
        if self.last_ns is not None:
            due = self.last_ns + self.period_ns
            if end_ns - due > self.threshold_ns:
                total += max(0, end_ns - max(start_ns, due))
        return total


def drive_word(effort: Sequence[float]) -> bool | None:
    """What a state's `effort` says of the drive: True it has stopped the axis (NaN), False it
    has not (a value), None it does not say (empty: a driver of the old contract)."""
    if not len(effort):
        return None
    return math.isnan(effort[0])


def effort_said(stopped: bool, applied: float) -> float:
    """The `effort` a drive of this contract puts in a state (what drive_word reads): NaN
    while it has stopped the axis, else the effort it applied over the period that ends now
    (0 while the brake holds the axis before its first command)."""
    if stopped:
        return math.nan
    return applied if math.isfinite(applied) else 0.0


def said_at(said: dict[int, bool | None], ns: int) -> bool | None:
    """What the drive said (drive_word) in the state ns, kept by stamp until stepped; the
    states before it are forgotten too (the timing dropped them)."""
    word = said.pop(ns, None)
    for old in [at for at in said if at < ns]:
        del said[old]
    return word


# -- a gap in the states a controller steps ------------------------------------------------
@dataclass(frozen=True)
class GapVerdict:
    trip: str = ''  # why the controller trips ('' it does not)
    report: str = ''  # a gap to report, not a trip ('' none)


_NO_GAP = GapVerdict()


def state_gap(
    gap_ns: int,
    period_ns: int,
    speed: float,
    window: HoldWindow,
    drive_stopped: bool | None,
    own_stall_ns: int = 0,
    mono_ns: int | None = None,
    reason: str = '',
) -> GapVerdict:
    """What a controller makes of the state it steps after a gap of gap_ns since the last.

    drive_stopped: the state's word (True: the drive has stopped the axis; False: it has
    not; None: the driver does not say, the old contract). speed: the axis's speed before
    the gap [m/s] (the controller's estimate). own_stall_ns: how long the controller's own
    process was stalled within the gap (StallWatch.within, monotonic); mono_ns: the time
    between its two steps on its monotonic clock, to report beside the stamps' gap; reason:
    the drive's own reason for its stop, where the controller knows it.
    """
    if 0 <= gap_ns <= period_ns and not drive_stopped:
        return _NO_GAP  # every state in time: the verdict the rules below give, at once
    if drive_stopped:
        said = 'the drive says it has stopped the axis (effort NaN in its state)'
        return GapVerdict(trip=f'{said}: {reason}' if reason else said)
    gap_ms = 1e-6 * gap_ns
    if drive_stopped is None and gap_ns > 0:
        # The drive holds while its silence plus a period stays within H: it has stopped the
        # axis by the state after a gap longer than H, and never within one period (a gap
        # of less than 1.5 periods is jitter, whatever the speed).
        held = window.hold_time(speed)
        if gap_ns > max(round(held * 1e9), 1.5 * period_ns):
            return GapVerdict(
                trip=(
                    f"no state for {gap_ms:.1f} ms, beyond the drive's window of "
                    f'{1e3 * held:.1f} ms at {1e3 * abs(speed):.1f} mm/s: a driver that does not '
                    'say when it stops has stopped the axis by then'
                )
            )
    if gap_ns - period_ns <= round(window.stall_report * 1e9):
        return GapVerdict()
    own_ms = 1e-6 * own_stall_ns
    if own_stall_ns * 2 >= gap_ns - period_ns:
        who = f"this controller's own process stalled {own_ms:.0f} ms (monotonic)"
    else:
        who = (
            f'the states stopped arriving (this process was awake; stalled {own_ms:.0f} ms '
            'of it): the drive or the link stalled'
        )
    here = f', {1e-6 * mono_ns:.1f} ms monotonic here' if mono_ns is not None else ''
    return GapVerdict(
        report=f'a gap of {gap_ms:.1f} ms between two states (their stamps{here}): {who}; no trip'
    )
