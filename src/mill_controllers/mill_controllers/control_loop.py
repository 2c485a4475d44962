"""One axis, one sample: what the controller does with its joined inputs. ROS-free.

The controller node and the offline simulator both call `AxisControlLoop.step` once per
sample, with the measured position of stamp ns, the observer's estimate of that sample and
the reference points the trajectory sent, so a distributed run equals the offline one by
construction. A step:

1. aims: with command_delay N the command acts N samples after the state it answers, so
   the law is evaluated at t + N·T with the observer's predicted position and the
   reference there (mill_observers.delay estimates that state);
2. evaluates the law (a BumplessSwitch: it can be replaced between samples); a law that
   cannot compute (ValueError, a non-finite result) gives the brake request;
3. checks the following error e = y − r(t), at the state's own stamp, against the trip,
   which latches the brake request (mill_controllers.trip).

A gap of `max_state_gap` periods or more between two states it steps (real time: the link
or the machine lost them) means the drive has had no command for as long, and has stopped
the axis (mill_plant.command_table): the loop trips too, so that it sends the brake request
the drive waits for and its observer knows the axis is braked. Reset after such a trip it
re-arms from where the axis stands: it holds the position it measures then (the reference
has moved on meanwhile; taking it up at once would throw the axis at it), and takes the
reference up again, without a bump, once that comes within half the following-error limit
of the held position (a new job's start, which begins where the axes stand).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from mill_common.signals import AxisReference, ControlInputs, Estimate, FopdtEstimate
from mill_common.timebase import period_ns, seconds

from mill_controllers.base import AxisController
from mill_controllers.switching import BumplessSwitch, check_replacement
from mill_controllers.trip import BRAKE, FollowingErrorTrip, Trip


class References(Protocol):
    """The reference of the axis at a stamp, None where it is not known (yet)."""

    def at(self, ns: int) -> AxisReference | None: ...


@dataclass(frozen=True)
class Command:
    effort: float  # in the law's OUTPUT_UNIT; NaN: the brake request
    problem: str = ''  # why the law gave no command (the effort is then the brake request)
    tripped: bool = False  # the following-error trip latched at this sample


class AxisControlLoop:
    def __init__(
        self,
        law: AxisController,
        sample_period: float,
        following_error_limit: float,
        command_delay: int = 0,
        blend_time: float = 0.0,
        max_state_gap: int = 0,
    ) -> None:
        self.switch = BumplessSwitch(law, sample_period, blend_time)
        self.trip = FollowingErrorTrip(following_error_limit)
        self.lead_ns = command_delay * period_ns(sample_period)
        self.period_ns = period_ns(sample_period)
        self.max_gap_ns = max_state_gap * self.period_ns  # 0: no gap trips
        self.last_ns = -1  # the stamp of the last state stepped
        self.last_position = math.nan
        self.hold: float | None = None  # the position held after a re-arm

    @property
    def law(self) -> AxisController:
        return self.switch.law

    def replace(self, law: AxisController) -> None:
        """Use `law` from the next sample on, without a bump; ValueError (before anything
        changes) if it cannot replace the running one on a running plant."""
        reason = check_replacement(type(self.switch.law), type(law))
        if reason:
            raise ValueError(reason)
        self.switch.replace(law)

    def reset_trip(self) -> Trip | None:
        """Clear the trip (the one cleared, if any); after a gap trip, re-arm holding the
        position last measured."""
        return self._rearm(self.trip.reset())

    def set_limit(self, limit: float) -> None:
        """A new following-error limit; a latched trip stays latched (reset_trip clears it)."""
        self.trip.set_limit(limit)

    def _rearm(self, cleared: Trip | None) -> Trip | None:
        if cleared is not None and cleared.cause and math.isfinite(self.last_position):
            self.hold = self.last_position
        return cleared

    def aim(self, ns: int) -> int:
        """The stamp of the reference the command for state ns needs."""
        return ns + self.lead_ns

    def step(
        self,
        ns: int,
        position: float,
        estimate: Estimate,
        references: References,
        model: FopdtEstimate | None = None,
    ) -> Command:
        """The command answering the state of stamp ns; references must know aim(ns)."""
        aimed = references.at(ns + self.lead_ns)
        if aimed is None:
            raise ValueError(f'no reference for {seconds(ns + self.lead_ns):.6f} s')
        here = references.at(ns) if self.lead_ns else aimed
        was = self.trip.tripped
        gap = ns - self.last_ns if self.last_ns >= 0 else 0
        self.last_ns, self.last_position = ns, position
        if self.max_gap_ns and gap >= self.max_gap_ns:
            self.trip.stop(
                seconds(ns),
                f'no state for {1e3 * seconds(gap):.1f} ms ({gap // self.period_ns} periods): '
                'the drive has stopped the axis',
            )
        if self.hold is not None:
            taken_up = here is not None and abs(here.position - self.hold) <= self.trip.limit / 2
            if taken_up:
                self.hold = None
            else:
                aimed = here = AxisReference(self.hold, 0.0, 0.0)
        t, y = seconds(ns), position
        if self.lead_ns:  # the command acts N samples on: aim at the state there
            t, y = seconds(ns + self.lead_ns), estimate.position
        problem = ''
        try:
            effort = self.switch.compute(ControlInputs(t, y, aimed, estimate, model))
        except ValueError as exc:
            effort, problem = BRAKE, str(exc)
        if not math.isfinite(effort):
            effort, problem = BRAKE, problem or f'the law gave {effort}'
        error = position - (aimed if here is None else here).position
        effort = self.trip.command(seconds(ns), error, effort)
        return Command(effort, problem, self.trip.tripped and not was)
