"""Which command messages a drive takes, per axis. ROS-free.

Every command must come from the axis's owner (`command_owners`) and answer a state of this
drive. The owner is who the ROS graph says published it (its publisher GID: a
mill_common.checks.Sender, from mill_common.graph_owner); what the message says of itself
(header.frame_id) must agree, but cannot stand in for it. While two publishers claim the
owner's name (the graph shows both), neither drives the axis: each command of either for a
step the drive expects is taken as a brake request. A brake request from the owner wins over
a valid command of the same step that arrived before it (the step applies the brake if it
has not been applied yet, and in real time the held command is replaced). Anything else —
another sender, a stamp that answers no state, an unknown joint, no effort for the joint —
is `Dropped` with its reason, which the drive front
end (mill_plant.drive_node) counts and reports. A repeat of a step already answered (the
drive offered the step again) is ignored. A non-finite effort of the axis's joint from the
owner is `Accepted` as NaN: it is the controller saying it has no valid command, so the axis
brakes for that period. The start of such a brake request, and the first valid command after
it, are flagged once each: a tripped controller asks for it every sample.

Commands that do not name their sender (`frame_id_says=False`: topic_based_ros2_control
leaves header.frame_id empty, mill_plant.topic_pair) are judged by the graph alone: a
publisher the graph does not show yet is refused until it does (at most
mill_common.graph_owner.REFRESH_S later), and a frame_id, if one is given, must agree.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from mill_common.checks import (
    CONTESTED,
    UNKNOWN,
    Rejected,
    Sender,
    StampCheck,
    joint_values,
    owner_check,
    sender_check,
)


@dataclass(frozen=True)
class Dropped:
    problem: Rejected
    foreign: bool  # sent by another node than the axis's owner


@dataclass(frozen=True)
class Accepted:
    effort: float  # NaN: the owner's brake request
    brake_request: str = ''  # why, when a brake request starts ('' otherwise)
    released: bool = False  # the first valid command after a brake request
    contested: bool = False  # a brake: two publishers claim the owner's name


class CommandIntake:
    def __init__(
        self,
        owners: Mapping[str, str],
        grid_ns: int | None,
        expected: Callable[[int], Rejected | None],
        frame_id_says: bool = True,
    ) -> None:
        """owners: axis -> the node its commands must come from ('' = anyone); grid_ns: the
        sample grid of command stamps (lockstep), None in real time; expected: whether a stamp
        answers a state of the drive (None: it does; the drive cycle's `expected`);
        frame_id_says: the commands name their sender in header.frame_id (mill's
        controllers), or not (ros2_control): then the graph's word alone decides."""
        self.owners = dict(owners)
        self._frame_id_says = frame_id_says
        self._expected = expected
        self._stamps = {a: StampCheck(grid_ns) for a in self.owners}  # newest: its last answer
        self._brake_requested: set[str] = set()  # axes whose last command was not finite
        self._finite = dict.fromkeys(self.owners, False)  # the last accepted was a valid one
        self.invalid_commands = dict.fromkeys(self.owners, 0)  # brake requests per axis

    def take(
        self,
        axis: str,
        ns: int,
        sender: str,
        names: Sequence[str],
        efforts: Sequence[float],
        graph: Sender | None = None,
    ) -> Accepted | Dropped | None:
        """The verdict on a command for `axis` stamped ns, whose header.frame_id is
        `sender` and whose publisher the graph identified as `graph` (None: not asked);
        None: the repeat of a step it answered, ignored. An accepted command is newer than
        every other of its axis, or the owner's brake request for the step just answered:
        the drive applies it."""
        stamps, owner = self._stamps[axis], self.owners[axis]
        who = sender_check(graph, owner) if graph is not None and owner else None
        if graph is not None and graph.verdict == CONTESTED and owner:
            return self._contested(axis, ns, who)
        foreign = who or self._claim_check(sender, owner, graph)
        problem = foreign or stamps.check(ns) or self._expected(ns)
        repeat = stamps.is_repeat(ns)
        if problem is not None:
            if repeat and problem.reason.startswith('stamp'):
                return None  # a repeat of an answered step (after a re-offer): harmless
            # a publisher the graph does not name yet is not known to be foreign
            unnamed = graph is not None and graph.verdict == UNKNOWN
            return Dropped(problem, foreign is not None and not (unnamed and who is not None))
        value = joint_values(names, {'effort': efforts}, axis, ('effort',))
        if isinstance(value, Rejected) and not value.non_finite:
            return None if repeat else Dropped(value, foreign=False)  # malformed
        if repeat:
            if isinstance(value, Rejected) and self._finite[axis]:
                return self._brake(axis, value.reason)  # the owner's brake wins the step
            return None  # the owner answered this step again (a re-offered step)
        stamps.accept(ns)
        if isinstance(value, Rejected):
            # From the owner, for the step it must answer: no valid command, so brake.
            return self._brake(axis, value.reason)
        released = axis in self._brake_requested
        self._brake_requested.discard(axis)
        self._finite[axis] = True
        return Accepted(value[0], released=released)

    def _claim_check(self, sender: str, owner: str, graph: Sender | None) -> Rejected | None:
        """What frame_id says against the owner, where the graph has not refused it."""
        if self._frame_id_says or not owner:
            return owner_check(sender, owner)
        if graph is None or graph.verdict == UNKNOWN:
            return Rejected(
                'sent by a publisher the graph does not show yet (and frame_id names none): '
                'refused until it does'
            )
        return owner_check(sender, owner) if sender else None

    def _brake(self, axis: str, reason: str, contested: bool = False) -> Accepted:
        self.invalid_commands[axis] += 1
        self._finite[axis] = False
        starts = axis not in self._brake_requested
        self._brake_requested.add(axis)
        return Accepted(math.nan, brake_request=reason if starts else '', contested=contested)

    def _contested(self, axis: str, ns: int, refused: Rejected | None) -> Accepted | Dropped | None:
        """A command of one of two publishers that claim the owner's name: for the step the
        drive expects, a brake request; anything else dropped as from any sender."""
        stamps = self._stamps[axis]
        problem = stamps.check(ns) or self._expected(ns)
        if stamps.is_repeat(ns):
            if self._finite[axis]:  # a valid command of the step came before the claim
                return self._brake(axis, refused.reason if refused else '', contested=True)
            return None
        if problem is not None:
            return Dropped(problem, foreign=False)
        stamps.accept(ns)
        return self._brake(axis, refused.reason if refused else '', contested=True)
