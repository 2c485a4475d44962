"""The spindle: the cutting-force model cuts only while it runs. ROS-free.

A path that programs the spindle (G-code M3/M4/M5 and S) carries its speed in the
reference, as the joint `spindle` (mill_common.signals.SPINDLE; signed rev/min, 0 off). A
drive with `spindle: reference` reads it (`spindle_values`) into a `SpindleTrack`, and the
speed of sample k is what the machine's spindle does over the step k -> k + 1, as the
efforts of sample k are: in lockstep the step waits until it is known (the trajectory has
sent it before any controller could answer sample k), in real time the newest one at or
before the tick holds. The simulated machine puts a `SpindleGate` between the plant and its
cutting-force model: no force while the spindle stands. The force published with the
states of sample k + 1 is then that of the spindle of sample k.

With `spindle: on` (the default, for paths that program no spindle) the model always cuts,
as it always did.
"""

from __future__ import annotations

import bisect
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.signals import SPINDLE

from mill_plant.cutting import CuttingForceModel, Force3

SPINDLE_MODES = ('on', 'reference')
_NONE: Force3 = (0.0, 0.0, 0.0)


class SpindleGate(CuttingForceModel):
    """A cutting-force model that applies its force only while the spindle runs."""

    PREFIX: ClassVar[str] = 'spindle_gate'

    def __init__(self, model: CuttingForceModel, running: bool = True) -> None:
        self.model = model
        self.running = running
        # A path-dependent model keeps learning the tool's path while the spindle stands.
        self.PATH_DEPENDENT = model.PATH_DEPENDENT  # type: ignore[misc]

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> SpindleGate:
        raise NotImplementedError('a spindle gate wraps a built model')

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        return self.model.force(t, position, velocity) if self.running else _NONE

    def commit(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> None:
        self.model.commit(t, position, velocity)


def spindle_values(joint_names: Sequence[str], points: Sequence[Any]) -> list[float] | None:
    """The spindle speed of every point of a reference message (None: it carries none, or
    a point lacks it or holds a non-finite value)."""
    names = list(joint_names)
    if SPINDLE not in names:
        return None
    i = names.index(SPINDLE)
    out = []
    for p in points:
        if len(p.positions) <= i or not abs(float(p.positions[i])) < float('inf'):
            return None
        out.append(float(p.positions[i]))
    return out


class SpindleTrack:
    """The programmed spindle speed by sample stamp [ns], as the reference sent it."""

    def __init__(self, initial: float = 0.0) -> None:
        self._stamps: list[int] = []
        self._speeds: list[float] = []
        self._before = initial  # the speed before the first stamp kept

    def offer(self, stamps: Sequence[int], speeds: Sequence[float]) -> None:
        """Speeds at these stamps (increasing); a later message replaces what it covers."""
        if not stamps:
            return
        cut = bisect.bisect_left(self._stamps, stamps[0])
        del self._stamps[cut:], self._speeds[cut:]
        self._stamps += stamps
        self._speeds += speeds

    def known(self, ns: int) -> bool:
        """Whether the reference has said what the spindle does at sample ns."""
        return bool(self._stamps) and self._stamps[-1] >= ns

    def at(self, ns: int) -> float:
        """The newest speed at or before ns (the initial one before any)."""
        i = bisect.bisect_right(self._stamps, ns)
        return self._speeds[i - 1] if i else self._before

    def forget_before(self, ns: int) -> None:
        """Drop what no later sample needs (the speed at ns is kept)."""
        i = bisect.bisect_right(self._stamps, ns) - 1
        if i > 0:
            self._before = self._speeds[i - 1]
            del self._stamps[:i], self._speeds[:i]
