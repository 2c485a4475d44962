"""Pauses at M0/M1, feed hold and resume, and the program's messages in time. ROS-free.

A G-code program's path is planned whole (mill_trajectory.planner); what the operator does
to it happens on the path's own time τ, which the trajectory advances sample by sample
(mill_trajectory.feed_override.TimeScaledPath), in the trajectory node and in the offline
simulator alike:

- **Pause** (M0; M1 with `gcode.optional_stop` on): the path is exactly at rest at the
  pause's instant t_p (the planner's rest, `PlannedPath.piece_starts`). The first sample whose
  τ reaches t_p is taken at t_p, and τ stays there: the reference holds the programmed
  point with zero velocity and acceleration while the clock runs on, so the job's end moves
  later by the time paused. `resume` lets τ run on from the next sample not yet sent; with
  `gcode.resume_after` > 0 a pause also ends by itself after that long at rest (an
  unattended run, the offline simulator): counted in samples, so both agree sample for
  sample.
- **Feed hold**: the override the path follows goes to 0 at the rate and change of rate the
  plan leaves room for (mill_trajectory.override_limit), so the reference decelerates along
  the path within the limits and comes to rest on it; resume ramps back to the offered
  override the same way. It needs that room: a path planned for a feed override
  (`feed_override.enabled`); otherwise `feed_hold` is refused and says why.
- **Messages** ((MSG, …), (DEBUG, …), (PRINT, …)), pauses and tool changes are
  `ProgramEvent`s at the path time their line runs; `due(τ)` gives those reached.

Commands answer with a `Command`: accepted or not, and one line that says what happened or
why not (a hold while held, a resume with nothing to resume).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

MESSAGE = 'message'
PAUSE = 'pause'
TOOL_CHANGE = 'tool change'


@dataclass(frozen=True)
class ProgramEvent:
    """What a program line says to the operator, at the path time the line runs [s]."""

    time: float
    kind: str  # MESSAGE, PAUSE or TOOL_CHANGE
    where: str  # 'file:line:column'
    text: str
    channel: str = ''  # a message's: MSG, DEBUG or PRINT

    def __str__(self) -> str:
        label = self.channel or self.kind
        return f'{self.where}: {label}: {self.text}'


@dataclass(frozen=True)
class Command:
    """The answer to feed_hold or resume: whether it was taken, and one line on it."""

    accepted: bool
    message: str


@dataclass(frozen=True)
class Notice:
    """A change the holds made by themselves (a pause reached, an automatic resume)."""

    kind: str  # 'paused' or 'resumed'
    event: ProgramEvent
    text: str


class Holds:
    """The pauses and the feed hold of one job (see the module doc)."""

    def __init__(
        self,
        pauses: Sequence[ProgramEvent],
        sample_period: float,
        resume_after: float = 0.0,
        hold_refusal: str | None = None,
    ) -> None:
        self.pauses = tuple(sorted(pauses, key=lambda e: e.time))
        self._pending = self.pauses
        self._next = 0
        self.paused: ProgramEvent | None = None
        self.held = False  # a feed hold is asked for (until resume)
        self.hold_refusal = hold_refusal  # why this job cannot hold its feed (None: it can)
        # Samples at the pause's point before it ends by itself (None: only resume ends it).
        self.resume_samples = (
            max(2, math.ceil(resume_after / sample_period - 1e-9)) if resume_after > 0 else None
        )
        self._rested = 0  # samples held in the current pause
        self.notices: list[Notice] = []  # drained by whoever reports them

    @property
    def state(self) -> str:
        """'paused', 'held' (a feed hold, decelerating or at rest) or 'running'."""
        return 'paused' if self.paused is not None else 'held' if self.held else 'running'

    def feed_hold(self) -> Command:
        if self.paused is not None:
            p = self.paused
            return Command(False, f'paused at {p.where} ({p.text}): at rest already; resume it')
        if self.hold_refusal is not None:
            return Command(False, self.hold_refusal)
        if self.held:
            return Command(False, 'the feed is held already: call resume to go on')
        self.held = True
        return Command(True, 'feed hold: decelerating to rest along the path')

    def resume(self) -> Command:
        if self.paused is not None:
            p, self.paused = self.paused, None
            return Command(True, f'resumed after the pause at {p.where} ({p.text})')
        if self.held:
            self.held = False
            return Command(True, 'feed hold released: back to the feed')
        return Command(False, 'nothing to resume: no pause and no feed hold')

    def target(self, override: float) -> float:
        """The override the path follows: 0 while the feed is held."""
        return 0.0 if self.held else override

    def hold_at(self, tau: float) -> float | None:
        """Before a sample at path time tau: the path time to hold (None: run on)."""
        if self.paused is not None:
            self._rested += 1
            # This sample, the first after the pause, is still at the pause's point too.
            if self.resume_samples is not None and self._rested >= self.resume_samples:
                p, self.paused = self.paused, None
                said = f'resumed by itself after {self.resume_samples} samples at {p.where}'
                self.notices.append(Notice('resumed', p, said))
                return None
            return self.paused.time
        if self._next < len(self._pending) and tau >= self._pending[self._next].time:
            p = self._pending[self._next]
            self._next += 1
            self.paused, self._rested = p, 1
            how = (
                "call the trajectory's ~/resume (std_srvs/Trigger) to go on"
                if self.resume_samples is None
                else f'resuming by itself after {self.resume_samples} samples (gcode.resume_after)'
            )
            self.notices.append(Notice('paused', p, f'paused at {p.where}: {p.text}; {how}'))
            return p.time
        return None

    def drain(self) -> list[Notice]:
        out, self.notices = self.notices, []
        return out


class EventClock:
    """The program's events in order of time: which ones the path has reached."""

    def __init__(self, events: Sequence[ProgramEvent]) -> None:
        self.events = sorted(events, key=lambda e: e.time)
        self._next = 0

    def due(self, tau: float) -> list[ProgramEvent]:
        """The events at or before path time tau not given yet."""
        start = self._next
        while self._next < len(self.events) and self.events[self._next].time <= tau:
            self._next += 1
        return self.events[start : self._next]
