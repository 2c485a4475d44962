"""How long the steps of a lockstep run waited, as counts over thresholds. ROS-free.

A lockstep plant waits, every step, for the commands of the step (and the recorder's
acknowledgement): on a quiet machine about a millisecond. A step that waits far longer is a
stall of the graph (a process without the CPU, a lost sample repaired at the writer's next
heartbeat). The plant counts its steps' waits over 10 ms, 100 ms and 1 s and reports them in
its status; the runner's summary and the repeat_runs benchmark print them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

THRESHOLDS_MS = (10, 100, 1000)  # a wait counts over each it exceeds


def status_key(threshold_ms: int) -> str:
    """The plant's status value with the count of waits over `threshold_ms`."""
    return f'waits_over_{threshold_ms}ms'


@dataclass
class StepWaits:
    """The waits of the steps so far: their sum, the longest, and counts over thresholds."""

    steps: int = 0
    total_s: float = 0.0
    longest_s: float = 0.0
    over: list[int] = field(default_factory=lambda: [0] * len(THRESHOLDS_MS))

    def add(self, wait_s: float) -> None:
        self.steps += 1
        self.total_s += wait_s
        self.longest_s = max(self.longest_s, wait_s)
        for i, limit in enumerate(THRESHOLDS_MS):
            if wait_s * 1e3 > limit:
                self.over[i] += 1

    def status_values(self) -> dict[str, float | int]:
        """mean_wait_ms, max_wait_ms and the counts over each threshold."""
        out: dict[str, float | int] = {
            'mean_wait_ms': 1e3 * self.total_s / max(self.steps, 1),
            'max_wait_ms': 1e3 * self.longest_s,
        }
        out.update({status_key(t): n for t, n in zip(THRESHOLDS_MS, self.over, strict=True)})
        return out


def from_status(values: Mapping[str, str]) -> dict[int, int] | None:
    """The counts over each threshold from a plant status's values (None: it has none)."""
    try:
        return {t: int(float(values[status_key(t)])) for t in THRESHOLDS_MS}
    except (KeyError, ValueError):
        return None
