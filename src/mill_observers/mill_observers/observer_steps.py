"""Which state an observer node steps next, with which command, and what it makes of a
contested input: the bookkeeping of mill_observers.observer_node, ROS-free.

The node has checked each message (sender, joint, stamp) before it comes here. States and
commands are kept by stamp; the `timing` strategy (mill_common.timing) says which states are
due: lockstep a state waits for the command answering the one before it (y(k) waits for
u(k − 1)); realtime the newest state is stepped at once with the newest command (the one the
drive holds) and the periods between two states run through.

The contest rule (two publishers claim an input's owner's name, mill_common.graph_owner):
both are refused, but no step waits on them. A contested command is taken as what the drive
makes of it, a brake request for its step (mill_plant.command_intake: it wins over a valid
command of that step not used yet), so the observer predicts the braked axis; a contested
state's step is passed without an estimate (the controller answers it with a brake request,
the command the next state is estimated with).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from mill_common.timing import Timing

MAX_COAST = 100  # periods the model runs on without a state before it just resumes

# What a state stamped at or before the last one stepped is (`ObserverSteps.behind`).
PAST = 'past'  # refused: a stamp repeated or in the past
AGAIN = 'again'  # lockstep: the plant offers the last step again (answered again)

# The kinds of `Step`.
STEP = 'step'  # estimate this state
PASS = 'pass'  # a contested state: passed, not estimated
WAIT = 'wait'  # the state due waits for the command before it (nothing more is due now)


@dataclass(frozen=True)
class Step:
    """What to do with the state of stamp ns: STEP it with the command that acted before it
    (None: none, at the start), the periods missed since the last state and the time beyond
    whole periods (in periods); PASS it; or WAIT for its command."""

    kind: str
    ns: int
    y: float = math.nan
    acted: float | None = None
    missed: int = 0
    late: float = 0.0


class ObserverSteps:
    """The states and commands of one observer node, by stamp (see the module doc)."""

    def __init__(self, timing: Timing) -> None:
        self.timing = timing
        self.last_ns: int | None = None  # the last state stepped or passed
        self.states: dict[int, float] = {}
        self.contested_states: set[int] = set()  # of those, sent by a contested plant
        self.commands: dict[int, float] = {}  # lockstep: by stamp
        self.newest_command: float | None = None  # real time: the newest received

    def behind(self, ns: int) -> str | None:
        """PAST or AGAIN for a state not after the last one stepped; None for a new one."""
        if self.last_ns is None or ns > self.last_ns:
            return None
        if not self.timing.WAITS_FOR_INPUTS or ns < self.last_ns:
            return PAST
        return AGAIN

    def state(self, ns: int, y: float, contested: bool) -> None:
        """A state taken; contested: sent by one of two publishers claiming the plant's name."""
        self.states[ns] = y
        if contested:
            self.contested_states.add(ns)

    def commanded(self, ns: int, u: float) -> bool:
        """The command answering the state ns (NaN: brake); whether a state may be due now."""
        self.newest_command = u
        if self.timing.WAITS_FOR_INPUTS and (self.last_ns is None or ns >= self.last_ns):
            self.commands[ns] = u
            return True
        return False

    def brakes_pending(self, ns: int) -> bool:
        """A contested command for step ns: True if it has made the step's valid command, come
        first and not used yet, a brake (nothing more to take); False: take it as a brake
        request (`commanded(ns, NaN)`) once its stamp is checked."""
        if ns in self.commands:
            self.commands[ns] = math.nan
            return True
        return False

    def forget_commands(self) -> None:
        """A rebuilt observer starts from the next measurement."""
        self.commands.clear()

    def due(self, started: Callable[[], bool]) -> Iterator[Step]:
        """The steps due now, oldest first; started(): whether the model has stepped yet (a
        lockstep state before it does not wait for a command). A WAIT ends them."""
        for ns in self.timing.due(self.states):
            if ns in self.contested_states:
                self._pass(ns)
                yield Step(PASS, ns)
                continue
            acted, missed, late = self._acted(ns)
            if self.timing.WAITS_FOR_INPUTS and started() and acted is None:
                yield Step(WAIT, ns)
                return  # y(k) arrived before u(k − 1): wait for it
            y = self.states.pop(ns)
            self.last_ns = ns
            yield Step(STEP, ns, y, acted, missed, late)

    def _pass(self, ns: int) -> None:
        self.contested_states.discard(ns)
        del self.states[ns]
        if self.last_ns is not None:
            self.commands.pop(self.last_ns, None)  # it acted before a state not taken
        self.last_ns = ns

    def _acted(self, ns: int) -> tuple[float | None, int, float]:
        """The command that acted before the state ns, the periods missed since the last
        state and the time beyond whole periods (in periods): lockstep the command stamped
        like that state, on the grid; real time the newest, and the drive's stamps."""
        if self.last_ns is None:
            return None, 0, 0.0
        if self.timing.WAITS_FOR_INPUTS:
            return self.commands.pop(self.last_ns, None), 0, 0.0
        periods = (ns - self.last_ns) / self.timing.period_ns
        whole = max(round(periods), 1)
        # Before its first command the drive holds the axis braked (the contract).
        held = math.nan if self.newest_command is None else self.newest_command
        return held, min(whole - 1, MAX_COAST), periods - whole
