"""Join inputs that arrive on different topics by their stamp. ROS-free.

A lockstep node acts when every input of one sample has arrived, in whatever
order DDS delivered them.
"""

from __future__ import annotations

from typing import Any


class StampJoin:
    def __init__(self, slots: tuple[str, ...]) -> None:
        self.slots = slots
        self._pending: dict[int, dict[str, Any]] = {}

    def put(self, slot: str, ns: int, value: Any) -> dict[str, Any] | None:
        """Store one input; return all inputs of that stamp once complete (and forget them)."""
        entry = self._pending.setdefault(ns, {})
        entry[slot] = value
        if len(entry) < len(self.slots):
            return None
        del self._pending[ns]
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
