"""The reference of one axis at any stamp, from the trajectory's points. ROS-free.

The trajectory publishes points of its sample grid ahead of time. A controller stores them
here and asks for the reference at the stamp of the state it acts on:

- a stamp that is a point's own stamp gets that point exactly (lockstep: every state
  stamp is on the trajectory's grid, so no arithmetic touches the values);
- a stamp between two points gets the linear interpolation of position, velocity and
  acceleration (real time: the drive stamps its states with its own clock);
- a stamp after the newest point is not covered yet: `at` returns None (lockstep: wait for
  the next message; real time: the reference is late, which the node reports).

Points older than what the node has acted on are forgotten (`forget_before`).
"""

from __future__ import annotations

import bisect

from mill_common.signals import AxisReference


class ReferenceBuffer:
    def __init__(self) -> None:
        self._stamps: list[int] = []
        self._points: list[AxisReference] = []

    def add(self, ns: int, point: AxisReference) -> None:
        """A point at stamp ns; a newer message's point for the same stamp replaces it."""
        i = bisect.bisect_left(self._stamps, ns)
        if i < len(self._stamps) and self._stamps[i] == ns:
            self._points[i] = point
        else:
            self._stamps.insert(i, ns)
            self._points.insert(i, point)

    def at(self, ns: int) -> AxisReference | None:
        stamps = self._stamps
        i = bisect.bisect_left(stamps, ns)
        if i < len(stamps) and stamps[i] == ns:
            return self._points[i]
        if i == 0 or i == len(stamps):
            return None  # before the first point or after the newest one
        t0, t1 = stamps[i - 1], stamps[i]
        a, b = self._points[i - 1], self._points[i]
        w = (ns - t0) / (t1 - t0)
        return AxisReference(
            a.position + w * (b.position - a.position),
            a.velocity + w * (b.velocity - a.velocity),
            a.acceleration + w * (b.acceleration - a.acceleration),
        )

    def forget_before(self, ns: int) -> None:
        """Drop points no later stamp can need (keeps the one just before ns)."""
        i = bisect.bisect_left(self._stamps, ns)
        if i > 1:
            del self._stamps[: i - 1]
            del self._points[: i - 1]

    @property
    def newest(self) -> int | None:
        return self._stamps[-1] if self._stamps else None

    def __len__(self) -> int:
        return len(self._stamps)
