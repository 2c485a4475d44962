"""The controller's inputs of one sample, joined as the node's timing says. ROS-free.

The state, the estimate (and the model, for a law that needs it) of a sample arrive on
different topics, in any order; the reference arrives as points ahead of time. A sample is
ready when every input it needs has the same stamp (mill_common.stamp_join) and the
reference reaches the stamp the command aims at. The timing (mill_common.timing) says what
happens to the others: lockstep waits for them and steps every sample in order; realtime
steps only the newest ready sample and drops one whose reference has not arrived.

An input whose owner's name two publishers claim (mill_common.graph_owner: CONTESTED) is
refused, but its sample is not waited for in vain: `contest` puts the `CONTESTED` marker in
its place (a contested state in the place of every input of its sample: the estimate of a
state nobody owns does not come), and the node answers that sample with a brake request
instead of stepping the law (`is_contested`), whose state stays as it was.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from mill_common.checks import CONTESTED as CONTESTED_SENDER
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AxisReference
from mill_common.stamp_join import StampJoin
from mill_common.timing import Timing


class Contested:
    """The marker of an input whose owner's name two publishers claim."""

    def __repr__(self) -> str:
        return 'CONTESTED'


CONTESTED = Contested()
# The inputs of a sample whose contested owner gets it answered by a brake request (the
# drive brakes: mill_plant.command_intake); the reference is not one of them.
BRAKE_ON_CONTEST = ('position', 'estimate', 'model')


def brakes_on_contest(slot: str, verdict: str) -> bool:
    """Whether a message of `slot` refused with `verdict` is contested (two publishers claim
    its owner's name) and its sample therefore answered by a brake request (`contest`), not
    waited for: the state's, the estimate's and the model's; a contested reference is only
    refused (the points it would give come again)."""
    return verdict == CONTESTED_SENDER and slot in BRAKE_ON_CONTEST


def is_contested(inputs: dict[str, Any]) -> bool:
    """Whether a joined sample holds a contested input (answered by a brake request)."""
    return any(v is CONTESTED for v in inputs.values())


class SampleJoin:
    def __init__(self, timing: Timing, slots: tuple[str, ...], lead_ns: int) -> None:
        self.timing = timing
        self.lead_ns = lead_ns  # the command aims this far ahead of its state
        self.references = ReferenceBuffer()
        self.late_references = 0  # realtime: samples dropped, the reference not there yet
        self._join = StampJoin(slots)
        self._ready: dict[int, dict[str, Any]] = {}  # joined, waiting for a reference
        self.last_ns = -1  # the last sample stepped

    def offer(self, slot: str, ns: int, value: Any) -> None:
        """One input of sample ns."""
        if ns <= self.last_ns:
            return  # a sample stepped already
        inputs = self._join.put(slot, ns, value)
        if inputs is not None:
            self._ready[ns] = inputs

    def contest(self, slot: str, ns: int, clock: bool) -> None:
        """Sample ns's `slot` input came from a publisher contesting its owner's name;
        clock: the input that paces the samples (the state), which stands in for every
        input of its sample not there yet."""
        slots = self._join.slots if clock else (slot,)
        for name in (slot, *slots):
            self.offer(name, ns, CONTESTED)
            if ns in self._ready:
                return

    def add_reference(self, ns: int, point: AxisReference) -> None:
        self.references.add(ns, point)

    def require(self, slots: tuple[str, ...]) -> None:
        """A new law needs these inputs (a sample that waited only for the old law's extra
        input is ready now)."""
        ready = self._join.require(slots)
        if ready is not None:
            self._ready[ready[0]] = ready[1]

    def due(self) -> Iterator[tuple[int, dict[str, Any]]]:
        """The samples to step now, in order; each is stepped before the next is offered."""
        for ns in self.timing.due(self._ready):
            if ns <= self.last_ns:
                del self._ready[ns]
                continue
            if self.references.at(ns + self.lead_ns) is None:
                if self.timing.WAITS_FOR_INPUTS or self.references.newest is None:
                    return  # the trajectory's next message brings it
                self.late_references += 1  # the reference does not reach this far yet
                del self._ready[ns]
                continue
            self.last_ns = ns
            yield ns, self._ready.pop(ns)
        self.references.forget_before(self.last_ns + self.lead_ns)

    def waiting_for(self) -> tuple[int, list[str]] | None:
        """The oldest sample waited for and the inputs it lacks (the reference, when it
        lacks nothing else), if any."""
        pending = self._join.oldest_incomplete()
        if pending is not None:
            return pending
        if self._ready:
            return min(self._ready), ['reference']
        return None
