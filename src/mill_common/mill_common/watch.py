"""Silence on a node's inputs, reported before it becomes a hang. ROS-free.

Each input a node needs has an `InputWatch`: `heard(now)` on every accepted message, and
`level(now)` says how long it has been quiet — OK, WARN after `warn_after` seconds, ERROR
after `error_after`. Before the first message an input is `waiting` (the graph is starting:
discovery can take a minute on a loaded machine); after it, silence counts. An outage that
ends is remembered with its length (`last_outage`), so it can be reported when it is over.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass


class Level(enum.IntEnum):
    OK = 0
    WARN = 1
    ERROR = 2


@dataclass
class InputWatch:
    topic: str
    publisher: str  # the node expected to publish it (for the message)
    warn_after: float
    error_after: float
    last: float | None = None  # when the last accepted message arrived
    last_outage: float = 0.0  # length of the last silence longer than warn_after [s]
    outages: int = 0

    def heard(self, now: float, counts: bool = True) -> float | None:
        """An accepted message; returns the length of the silence it ends, if it was one
        (counts False: a silence of the start-up, which is no outage)."""
        ended = None
        if counts and self.last is not None and now - self.last >= self.warn_after:
            ended = now - self.last
            self.last_outage = ended
            self.outages += 1
        self.last = now
        return ended

    def silence(self, now: float) -> float:
        return 0.0 if self.last is None else now - self.last

    def level(self, now: float) -> Level:
        quiet = self.silence(now)
        if quiet >= self.error_after:
            return Level.ERROR
        if quiet >= self.warn_after:
            return Level.WARN
        return Level.OK

    @property
    def waiting(self) -> bool:
        return self.last is None

    def describe(self, now: float) -> str:
        source = self.publisher or 'no publisher known'
        if self.waiting:
            return f'nothing yet on {self.topic} (from {source})'
        return f'nothing on {self.topic} for {self.silence(now):.1f} s (from {source})'
