"""Feed override: the path's own time advances at `override` times the sample time (ROS-free).

A CNC's feed-override input scales the path speed without changing the path. With the path
p(τ) of any Trajectory and the override o(k) held over sample k:

    τ(k+1) = τ(k) + o(k)·T,
    x_ref(k) = p(τ(k)),  ẋ_ref(k) = o(k)·p'(τ(k)),  ẍ_ref(k) = o(k)²·p''(τ(k))

(o held constant within a sample, so no do/dt term; with a ramp ȯ over the sample, from a
β-hold, ẍ_ref gains ȯ·p'(τ(k)) and τ advances by ȯT²/2 more). o = 1 is the programmed feed, 0
stops on the path. Values outside [minimum, maximum] are clamped and a non-finite value
holds the last accepted override; `accept` says which happened so the node can report it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mill_trajectory.base import Trajectory, TrajectorySample


@dataclass(frozen=True)
class Accepted:
    """The override in effect and why it differs from the value offered (None: it does not)."""

    value: float
    problem: str | None = None


class FeedOverride:
    """Clamps offered overrides to a range and holds the last one over a non-finite value."""

    def __init__(self, minimum: float = 0.0, maximum: float = 1.5, initial: float = 1.0) -> None:
        if not (math.isfinite(minimum) and math.isfinite(maximum) and 0.0 <= minimum <= maximum):
            raise ValueError(f'need 0 <= minimum <= maximum, got [{minimum}, {maximum}]')
        self.minimum, self.maximum = float(minimum), float(maximum)
        self.value = min(max(float(initial), self.minimum), self.maximum)

    def accept(self, offered: float) -> Accepted:
        if not math.isfinite(offered):
            return Accepted(self.value, f'non-finite override {offered} ignored, holding')
        clamped = min(max(offered, self.minimum), self.maximum)
        self.value = clamped
        if clamped != offered:
            return Accepted(
                clamped, f'override {offered:g} outside [{self.minimum:g}, {self.maximum:g}]'
            )
        return Accepted(clamped)


class TimeScaledPath:
    """A path sampled on its own time τ, which runs at the override's rate."""

    def __init__(self, path: Trajectory, sample_period: float) -> None:
        self.path = path
        self._T = sample_period
        self._k = 0
        self._tau = 0.0

    @property
    def path_time(self) -> float:
        return self._tau

    @property
    def sample_index(self) -> int:
        return self._k

    def sample(self, override: float, slope: float = 0.0) -> TrajectorySample:
        """Reference of the current sample k with override o(k); then moves on to k+1.

        slope ȯ [1/s]: the override ramps as o(k) + ȯ·τ over the sample (a β-hold);
        the path time then advances by o·T + ȯ·T²/2 and ẍ_ref gains ȯ·p'.
        """
        s = self.path.sample(self._tau)
        o = override
        self._k += 1
        self._tau += o * self._T + 0.5 * slope * self._T * self._T
        v, a = s.velocity, s.acceleration
        return TrajectorySample(
            s.position,
            (o * v[0], o * v[1], o * v[2]),
            (o * o * a[0] + slope * v[0], o * o * a[1] + slope * v[1], o * o * a[2] + slope * v[2]),
        )
