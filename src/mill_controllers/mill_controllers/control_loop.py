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
3. shapes the command (mill_controllers.command_shaping: friction feed-forward, backlash
   offset of the reference, command filter), when the node was given any;
4. checks the following error e = y − r(t), at the state's own stamp, against the trip,
   which latches the brake request (mill_controllers.trip).

The drive says in every state whether it has stopped the axis (mill_common.hold_window:
the state's effort NaN). When it starts to say so (or the first state says so) the loop
trips, with the drive's reason where the node knows it, so that it sends the brake request
the drive waits for and its observer knows the axis is braked. It never claims a stop the
drive did not declare: a gap between two states it steps is reported (`Command.gap`: its
length, and whether this process or the states' arrival stalled), not tripped on. Only a
driver that does not say (an empty effort, the old contract) is judged by the window: a gap
of H(v) or more (v the estimated speed before it) means it has stopped the axis by then.
`window` None: no gap rule (a controller that knows nothing of the drive's stops). Reset
after such a trip it re-arms from where the axis stands: it holds the position it measures
then (the reference has moved on meanwhile; taking it up at once would throw the axis at
it), and takes the reference up again, without a bump, once that comes within half the
following-error limit of the held position (a new job's start, which begins where the axes
stand).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from mill_common.hold_window import HoldWindow, state_gap
from mill_common.signals import AxisReference, ControlInputs, Estimate, FopdtEstimate
from mill_common.timebase import period_ns, seconds

from mill_controllers.base import AxisController
from mill_controllers.command_shaping import CommandShaping
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
    gap: str = ''  # a gap before this state, to report (not a trip)


class AxisControlLoop:
    def __init__(
        self,
        law: AxisController,
        sample_period: float,
        following_error_limit: float,
        command_delay: int = 0,
        blend_time: float = 0.0,
        window: HoldWindow | None = None,
        min_following_error: float = 0.0,
        max_velocity: float = math.inf,
        shaping: CommandShaping | None = None,
    ) -> None:
        self.switch = BumplessSwitch(law, sample_period, blend_time)
        self.trip = FollowingErrorTrip(following_error_limit, min_following_error, max_velocity)
        self.lead_ns = command_delay * period_ns(sample_period)
        self.period_ns = period_ns(sample_period)
        self.window = window  # None: no gap rule
        self.last_ns = -1  # the stamp of the last state stepped
        self.last_speed = 0.0  # the estimated speed at it
        self.drive_said: bool | None = None  # what the drive said of the axis in it
        self.last_position = math.nan
        self.hold: float | None = None  # the position held after a re-arm
        # friction and backlash compensation, command filter (None: the law's command as is)
        self.shaping = shaping if shaping is not None and shaping.active else None

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
        *,
        drive_stopped: bool | None = None,
        drive_reason: str = '',
        own_stall_ns: int = 0,
        mono_ns: int | None = None,
    ) -> Command:
        """The command answering the state of stamp ns; references must know aim(ns).

        drive_stopped: what the state says (mill_common.hold_window.drive_word);
        drive_reason: the drive's reason, if known; own_stall_ns, mono_ns: this process's
        stall within the gap and the gap on its monotonic clock (for the report)."""
        aimed = references.at(ns + self.lead_ns)
        if aimed is None:
            raise ValueError(f'no reference for {seconds(ns + self.lead_ns):.6f} s')
        here = references.at(ns) if self.lead_ns else aimed
        was = self.trip.tripped
        gap = ns - self.last_ns if self.last_ns >= 0 else 0
        self.last_ns, self.last_position = ns, position
        reported = ''
        if self.window is not None:
            # News only: a stop it said before (and still says after a reset, until the
            # re-arm reaches it) trips no more.
            news = drive_stopped and not self.drive_said
            verdict = state_gap(
                gap,
                self.period_ns,
                self.last_speed,
                self.window,
                bool(news) if drive_stopped is not None else None,
                own_stall_ns,
                mono_ns,
                drive_reason,
            )
            if verdict.trip:
                self.trip.stop(seconds(ns), verdict.trip)
            reported = verdict.report
            self.drive_said = drive_stopped
        self.last_speed = estimate.velocity if math.isfinite(estimate.velocity) else 0.0
        if self.hold is not None:
            taken_up = here is not None and abs(here.position - self.hold) <= self.trip.limit / 2
            if taken_up:
                self.hold = None
            else:
                aimed = here = AxisReference(self.hold, 0.0, 0.0)
        offset = 0.0
        if self.shaping is not None:
            # backlash: half the gap on the side the reference moves towards (ramped)
            offset = self.shaping.offset(aimed.velocity)
            aimed = AxisReference(aimed.position + offset, aimed.velocity, aimed.acceleration)
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
        elif self.shaping is not None:
            effort = self.shaping.command(effort, aimed.velocity)
        now = aimed if here is None else here
        error = position - now.position - (offset if here is not None else 0.0)
        effort = self.trip.command(seconds(ns), error, effort, now.velocity)
        return Command(effort, problem, self.trip.tripped and not was, reported)
