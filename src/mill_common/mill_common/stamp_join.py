"""Join inputs that arrive on different topics by their stamp. ROS-free.

A lockstep node acts when every required input of one sample has arrived, in whatever
order DDS delivered them. Inputs of other slots that arrived in time are handed over too;
the required set can change between samples (a new control law that needs one more input).
"""

from __future__ import annotations

from typing import Any


class StampJoin:
    def __init__(self, slots: tuple[str, ...]) -> None:
        self.slots = tuple(slots)
        self._pending: dict[int, dict[str, Any]] = {}

    def require(self, slots: tuple[str, ...]) -> tuple[int, dict[str, Any]] | None:
        """Change the required slots; returns (stamp, inputs) of the oldest sample this
        completes, if any."""
        self.slots = tuple(slots)
        for ns in sorted(self._pending):
            if self._complete(self._pending[ns]):
                return ns, self._take(ns)
        return None

    def put(self, slot: str, ns: int, value: Any) -> dict[str, Any] | None:
        """Store one input; return all inputs of that stamp once complete (and forget them)."""
        entry = self._pending.setdefault(ns, {})
        entry[slot] = value
        return self._take(ns) if self._complete(entry) else None

    def _complete(self, entry: dict[str, Any]) -> bool:
        return all(s in entry for s in self.slots)

    def _take(self, ns: int) -> dict[str, Any]:
        entry = self._pending.pop(ns)
        # Anything older than a completed sample can never complete: drop it.
        for old in [s for s in self._pending if s < ns]:
            del self._pending[old]
        return entry

    def oldest_incomplete(self) -> tuple[int, list[str]] | None:
        """The oldest waiting stamp and the slots it still lacks, if any."""
        if not self._pending:
            return None
        ns = min(self._pending)
        return ns, [s for s in self.slots if s not in self._pending[ns]]
