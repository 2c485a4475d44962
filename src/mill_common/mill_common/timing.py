"""How a node's inputs are joined and when its step runs: the `timing` parameter. ROS-free.

Every node of the graph reads `timing` once and keeps one of these strategies; the node's
callbacks ask it instead of testing the name:

- `Lockstep` (the plant is the clock): every stamp is on the sample grid; a node waits for
  all inputs of a sample and acts on every sample, oldest first; a stamp it has seen is the
  same sample offered again (the first message counts; the node answers it again); nothing
  can be later than the plant (`ahead`); a silent input ends the node (it would wait forever).
- `Realtime` (a drive on the wall clock): stamps are the drive's acquisition times, on no
  grid; a node keeps only the newest message of each input and acts on the newest sample;
  a repeated stamp is an error; an input that is late is dropped, never waited for; silence
  is reported while the node runs on.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, MutableMapping
from datetime import datetime, timezone
from typing import ClassVar, TypeVar

from mill_common.checks import Rejected, StampCheck, ahead

T = TypeVar('T')


class Timing(ABC):
    NAME: ClassVar[str]
    # An input silent for input_timeout ends the node (lockstep: it would wait forever).
    EXIT_ON_SILENCE: ClassVar[bool]
    # A node answers a sample only once every reader of its output is matched (lockstep: a
    # reader that misses the answer would stall the plant; the plant offers the step again).
    WAITS_FOR_READERS: ClassVar[bool]
    # A sample whose inputs are not all there yet is waited for (else dropped: too late).
    WAITS_FOR_INPUTS: ClassVar[bool]

    def __init__(self, period_ns: int) -> None:
        self.period_ns = period_ns

    @abstractmethod
    def stamps(self) -> StampCheck:
        """A fresh stamp check for one input."""

    @abstractmethod
    def depth(self, history: bool = False) -> int | None:
        """Queue depth of an input; None: the graph's data QoS (keep every sample).
        history: the input carries points ahead (the reference), keep them."""

    @abstractmethod
    def problem(
        self,
        stamps: StampCheck,
        ns: int,
        newest_state: int | None,
        lead_ns: int,
        history: bool = False,
    ) -> Rejected | None:
        """What is wrong with an input's stamp ns (None: fine). newest_state: the newest
        state stamp the node accepted; lead_ns: the most this input may be ahead of it;
        history: the input carries points ahead (the reference)."""

    @abstractmethod
    def is_offered_again(self, stamps: StampCheck, ns: int) -> bool:
        """Whether an accepted stamp is the same sample offered again (the first counts)."""

    @abstractmethod
    def due(self, pending: MutableMapping[int, T]) -> list[int]:
        """The stamps of pending samples to act on now, in order; the rest are dropped."""

    @abstractmethod
    def when(self, ns: int) -> str:
        """A stamp as a log says it ('at ...'): job time, or the time of day of a wall-clock
        stamp."""

    def off_grid(self, stamps_ns: list[int]) -> int | None:
        """The first of these stamps off the sample grid, if the timing has one."""
        return None


class Lockstep(Timing):
    NAME = 'lockstep'
    EXIT_ON_SILENCE = True
    WAITS_FOR_READERS = True
    WAITS_FOR_INPUTS = True

    def stamps(self) -> StampCheck:
        return StampCheck(self.period_ns)

    def depth(self, history: bool = False) -> int | None:
        return None

    def problem(
        self,
        stamps: StampCheck,
        ns: int,
        newest_state: int | None,
        lead_ns: int,
        history: bool = False,
    ) -> Rejected | None:
        return stamps.check(ns) or ahead(ns, newest_state, lead_ns)

    def is_offered_again(self, stamps: StampCheck, ns: int) -> bool:
        return stamps.is_repeat(ns)

    def due(self, pending: MutableMapping[int, T]) -> list[int]:
        return sorted(pending)

    def when(self, ns: int) -> str:
        return f'at t = {ns / 1e9:.4f} s'

    def off_grid(self, stamps_ns: list[int]) -> int | None:
        return next((ns for ns in stamps_ns if ns % self.period_ns), None)


class Realtime(Timing):
    NAME = 'realtime'
    EXIT_ON_SILENCE = False
    WAITS_FOR_READERS = False
    WAITS_FOR_INPUTS = False

    def stamps(self) -> StampCheck:
        return StampCheck(None)

    def depth(self, history: bool = False) -> int | None:
        return None if history else 1  # nothing stale queues

    def problem(
        self,
        stamps: StampCheck,
        ns: int,
        newest_state: int | None,
        lead_ns: int,
        history: bool = False,
    ) -> Rejected | None:
        if history:
            return None  # each message's points are merged by stamp; any order will do
        problem = stamps.check(ns)
        if problem is None and stamps.is_repeat(ns):
            problem = Rejected(f'repeated stamp {ns / 1e9:.6f} s')
        return problem

    def is_offered_again(self, stamps: StampCheck, ns: int) -> bool:
        return False

    def due(self, pending: MutableMapping[int, T]) -> list[int]:
        if not pending:
            return []
        newest = max(pending)
        for ns in [s for s in pending if s != newest]:
            del pending[ns]  # only the newest sample is worth acting on
        return [newest]

    def when(self, ns: int) -> str:
        clock = datetime.fromtimestamp(ns / 1e9, timezone.utc).strftime('%H:%M:%S.%f')[:-3]
        return f'at {clock} UTC'


TIMINGS: dict[str, Callable[[int], Timing]] = {t.NAME: t for t in (Lockstep, Realtime)}


def timing(name: str, period_ns: int) -> Timing:
    """The strategy a `timing` parameter names; ValueError names a bad one."""
    try:
        return TIMINGS[name](period_ns)
    except KeyError:
        raise ValueError(f'timing must be one of {", ".join(TIMINGS)}, got {name!r}') from None
