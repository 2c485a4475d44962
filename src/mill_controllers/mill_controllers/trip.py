"""Following-error trip of one axis, as a machine tool has it (LinuxCNC's FERROR). ROS-free.

Every sample the controller's following error e = measured position − reference is
compared with the axis's limit. The first |e| above it latches a trip: from then on the
controller sends no torque but the brake request (a non-finite effort, which the drive
answers by braking the axis: velocity 0, position held) until the trip is reset, by the
node's `reset_trip` service alone: a new `following_error_limit` changes the limit only, and
a tripped axis stays braked. The trip remembers when and with which error it happened, for
/diagnostics and the log.

The same latch takes a stop the loop decides on another ground (`stop`, with its cause): a
gap in the states long enough that the drive has stopped the axis (mill_controllers.
control_loop).

The same object runs in the controller node and in the offline simulator, so a run that
trips does so at the same sample in both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

BRAKE = math.nan  # the effort that asks the drive to brake the axis


RESET = '(reset: ~/reset_trip)'


@dataclass(frozen=True)
class Trip:
    time: float  # [s]
    error: float  # following error that tripped [m] (NaN: another cause)
    limit: float  # [m]
    cause: str = ''  # what tripped, if not the following error

    def describe(self, axis: str, when: str) -> str:
        """One line for the log and /diagnostics; `when` says the time as the node has it."""
        if self.cause:
            return f'axis {axis}: trip {when}: {self.cause}: braked {RESET}'
        return (
            f'axis {axis}: following-error trip {when}, |e| = {1e3 * abs(self.error):.3f} mm '
            f'> {1e3 * self.limit:g} mm: braked {RESET}'
        )


class FollowingErrorTrip:
    def __init__(self, limit: float) -> None:
        if not limit > 0.0:
            raise ValueError(f'following_error_limit must be > 0 (inf: no trip), got {limit!r}')
        self.limit = limit
        self.trip: Trip | None = None

    @property
    def tripped(self) -> bool:
        return self.trip is not None

    def check(self, t: float, error: float) -> bool:
        """True once |error| has exceeded the limit (latched); NaN errors do not trip."""
        if self.trip is None and abs(error) > self.limit:
            self.trip = Trip(t, error, self.limit)
        return self.trip is not None

    def stop(self, t: float, cause: str) -> None:
        """Latch a trip for another cause (kept if one is latched already)."""
        if self.trip is None:
            self.trip = Trip(t, math.nan, self.limit, cause)

    def command(self, t: float, error: float, effort: float) -> float:
        """The effort to send: the law's, or the brake request once tripped."""
        return BRAKE if self.check(t, error) else effort

    def reset(self) -> Trip | None:
        """Clear the trip; returns the one cleared, if any."""
        trip, self.trip = self.trip, None
        return trip

    def set_limit(self, limit: float) -> None:
        """A new limit for the samples to come; a latched trip stays latched (reset alone
        clears it)."""
        if not limit > 0.0:
            raise ValueError(f'following_error_limit must be > 0 (inf: no trip), got {limit!r}')
        self.limit = limit
