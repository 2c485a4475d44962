"""A transport delay of N periods between a command and the step it acts in. ROS-free.

The lockstep drive and the offline simulator both pass each step's commands through it:
the command answering step k acts from step k + N (zero input before the first one), so a
run with `command_delay` N equals its offline twin by construction.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence


class CommandDelay:
    def __init__(self, delay: int, axes: int) -> None:
        if delay < 0:
            raise ValueError(f'command_delay must be >= 0, got {delay}')
        self._line: deque[list[float]] = deque([[0.0] * axes for _ in range(delay)])

    def __call__(self, efforts: Sequence[float]) -> list[float]:
        """The commands that act now, given the ones that answer this step."""
        if not self._line:
            return list(efforts)
        self._line.append(list(efforts))
        return self._line.popleft()
