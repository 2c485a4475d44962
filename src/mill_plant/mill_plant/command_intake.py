"""Which command messages a drive takes, per axis. ROS-free.

Every command must come from the axis's owner (header.frame_id, `command_owners`) and answer
a state of this drive; anything else — another sender, a stamp that answers no state, an
unknown joint, no effort for the joint — is `Dropped` with its reason, which the drive front
end (mill_plant.drive_node) counts and reports. A repeat of a step already answered (the
drive offered the step again) is ignored. A non-finite effort of the axis's joint from the
owner is `Accepted` as NaN: it is the controller saying it has no valid command, so the axis
brakes for that period. The start of such a brake request, and the first valid command after
it, are flagged once each: a tripped controller asks for it every sample.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from mill_common.checks import Rejected, StampCheck, joint_values, owner_check


@dataclass(frozen=True)
class Dropped:
    problem: Rejected
    foreign: bool  # sent by another node than the axis's owner


@dataclass(frozen=True)
class Accepted:
    effort: float  # NaN: the owner's brake request
    brake_request: str = ''  # why, when a brake request starts ('' otherwise)
    released: bool = False  # the first valid command after a brake request


class CommandIntake:
    def __init__(
        self,
        owners: Mapping[str, str],
        grid_ns: int | None,
        expected: Callable[[int], Rejected | None],
    ) -> None:
        """owners: axis -> the node its commands must come from ('' = anyone); grid_ns: the
        sample grid of command stamps (lockstep), None in real time; expected: whether a stamp
        answers a state of the drive (None: it does; the drive cycle's `expected`)."""
        self.owners = dict(owners)
        self._expected = expected
        self._stamps = {a: StampCheck(grid_ns) for a in self.owners}  # newest: its last answer
        self._brake_requested: set[str] = set()  # axes whose last command was not finite
        self.invalid_commands = dict.fromkeys(self.owners, 0)  # brake requests per axis

    def take(
        self, axis: str, ns: int, sender: str, names: Sequence[str], efforts: Sequence[float]
    ) -> Accepted | Dropped | None:
        """The verdict on a command for `axis` stamped ns from `sender` (header.frame_id);
        None: the repeat of a step it answered, ignored. An accepted command is newer than
        every other of its axis: the drive applies it."""
        stamps = self._stamps[axis]
        foreign = owner_check(sender, self.owners[axis])
        problem = foreign or stamps.check(ns) or self._expected(ns)
        if problem is not None:
            if stamps.is_repeat(ns) and problem.reason.startswith('stamp'):
                return None  # a repeat of an answered step (after a re-offer): harmless
            return Dropped(problem, foreign is not None)
        if stamps.is_repeat(ns):
            return None  # the owner answered this step again (a re-offered step)
        value = joint_values(names, {'effort': efforts}, axis, ('effort',))
        if isinstance(value, Rejected) and not value.non_finite:
            return Dropped(value, foreign=False)  # no joint, no effort: malformed
        stamps.accept(ns)
        if isinstance(value, Rejected):
            # From the owner, for the step it must answer: no valid command, so brake.
            self.invalid_commands[axis] += 1
            starts = axis not in self._brake_requested
            self._brake_requested.add(axis)
            return Accepted(math.nan, brake_request=value.reason if starts else '')
        released = axis in self._brake_requested
        self._brake_requested.discard(axis)
        return Accepted(value[0], released=released)
