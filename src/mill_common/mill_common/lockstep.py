"""Start-up and liveness of the node that clocks a lockstep run (ROS-free).

The clock node (the plant, the force process) calls `tick` from a steady-time timer:

- before the start it waits until no peer is missing, then another `settle` seconds so
  that discovery settles on the subscribers' side too (a writer that has matched a reader
  does not mean the reader has matched the writer), then says START;
- while a step stays unanswered it says OFFER_AGAIN every `retry` seconds: a peer may have
  matched just after step 0 went out, or a restarted controller or observer may have missed
  the step it is needed for — a repeated step lets it rejoin (the others answer a repeat
  with what they sent before);
- PEERS_MISSING when peers are still missing after `startup_timeout`, STALLED when no step
  has completed (`progressed`) for `lockstep_timeout`: the node ends with a message.

`RecorderGate` holds a recorded run's clock node within a window of the recorder's
acknowledgements, so that a bag misses nothing.
"""

from __future__ import annotations

import enum
from collections.abc import Callable

from mill_common.timebase import sample_index, sample_stamp_ns


class Action(enum.Enum):
    WAIT = 'wait'
    START = 'start'
    OFFER_AGAIN = 'offer again'
    PEERS_MISSING = 'peers missing'
    STALLED = 'stalled'


class LockstepWatchdog:
    def __init__(
        self,
        now: float,
        startup_timeout: Callable[[], float],
        lockstep_timeout: Callable[[], float],
        settle: float = 0.5,
        retry: float = 1.0,
    ) -> None:
        # Timeouts are read at each tick: they are run-time parameters of the node.
        self._startup_timeout = startup_timeout
        self._lockstep_timeout = lockstep_timeout
        self._settle = settle
        self._retry = retry
        self._created = now
        self._ready_since: float | None = None
        self._retry_at = 0.0
        self._last_progress = now
        self.started = False

    def progressed(self, now: float) -> None:
        """A step has completed."""
        self._last_progress = now
        self._retry_at = now + self._retry

    def waited(self, now: float) -> float:
        """Wall time since the last step completed (or since the start) [s]."""
        return now - self._last_progress if self.started else 0.0

    def tick(self, now: float, missing_peers: Callable[[], list[str]]) -> Action:
        if not self.started:
            if missing_peers():
                self._ready_since = None
                if now - self._created > self._startup_timeout():
                    return Action.PEERS_MISSING
                return Action.WAIT
            if self._ready_since is None:
                self._ready_since = now
            if now - self._ready_since < self._settle:
                return Action.WAIT
            self.started = True
            self._last_progress = now
            self._retry_at = now + self._retry
            return Action.START
        if now - self._last_progress > self._lockstep_timeout():
            return Action.STALLED
        if now - self._last_progress > self._retry and now > self._retry_at:
            self._retry_at = now + self._retry
            return Action.OFFER_AGAIN
        return Action.WAIT


class RecorderGate:
    """The clock node's side of the recorder handshake (mill_bringup.bag_handshake).

    With a window of W samples, sample j goes out only once the recorder has acknowledged
    (on mill/recorded) sample j − W: however busy the machine, the clock node never runs
    more than W samples ahead of the bag. Window 0: there is no recorder to wait for.
    """

    def __init__(self, window: int, period_s: float) -> None:
        self.window = window
        self._period_s = period_s
        self.recorded = -1  # the newest sample acknowledged (-1: none yet)

    def acknowledged(self, ns: int) -> None:
        self.recorded = max(self.recorded, sample_index(ns, self._period_s))

    def allows(self, k: int) -> bool:
        """Whether sample k may go out now."""
        return not self.window or k <= self.recorded + self.window

    def describe(self) -> str:
        """The newest acknowledgement, for a timeout's message."""
        if self.recorded < 0:
            return 'none'
        return f't = {sample_stamp_ns(self.recorded, self._period_s) / 1e9:.3f} s'
