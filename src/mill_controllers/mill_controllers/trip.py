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

The limit may grow with speed, as LinuxCNC's does (FERROR at the axis's top speed,
MIN_FERROR at rest): with `min_limit` > 0 the limit at a reference speed v is
min_limit + (limit − min_limit)·min(1, |v|/max_speed); `min_limit` 0 keeps it fixed.

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
    def __init__(self, limit: float, min_limit: float = 0.0, max_speed: float = math.inf) -> None:
        if not limit > 0.0:
            raise ValueError(f'following_error_limit must be > 0 (inf: no trip), got {limit!r}')
        if not 0.0 <= min_limit <= limit:
            raise ValueError(
                f'min_following_error must be within 0 and following_error_limit ({limit!r}), '
                f'got {min_limit!r}'
            )
        if not max_speed > 0.0:
            raise ValueError(f'max_velocity must be > 0, got {max_speed!r}')
        self.limit = limit
        self.min_limit = min_limit
        self.max_speed = max_speed
        self.trip: Trip | None = None

    def limit_at(self, speed: float) -> float:
        """The limit at the reference speed `speed` [m/s]."""
        if self.min_limit == 0.0 or math.isinf(self.limit):
            return self.limit
        share = min(1.0, abs(speed) / self.max_speed) if math.isfinite(speed) else 1.0
        # LinuxCNC: limit = MIN_FERROR + (FERROR − MIN_FERROR)·|v|/v_max
        return self.min_limit + (self.limit - self.min_limit) * share

    @property
    def tripped(self) -> bool:
        return self.trip is not None

    def check(self, t: float, error: float, speed: float = 0.0) -> bool:
        """True once |error| has exceeded the limit at the reference speed (latched); NaN
        errors do not trip."""
        if self.trip is None:
            limit = self.limit_at(speed)
            if abs(error) > limit:
                self.trip = Trip(t, error, limit)
        return self.trip is not None

    def stop(self, t: float, cause: str) -> None:
        """Latch a trip for another cause (kept if one is latched already)."""
        if self.trip is None:
            self.trip = Trip(t, math.nan, self.limit, cause)

    def command(self, t: float, error: float, effort: float, speed: float = 0.0) -> float:
        """The effort to send: the law's, or the brake request once tripped."""
        return BRAKE if self.check(t, error, speed) else effort

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
        self.min_limit = min(self.min_limit, limit)
