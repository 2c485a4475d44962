"""What a drive checks of each axis's motion by itself, in real time, as a servo amplifier
does. ROS-free.

The drive reads every axis's position at each tick and asks `check` which axes to stop
(braked and latched, mill_plant.command_table), before it applies any command:

- speed: an axis that moved faster than `speed_limit` over the last period is stopped,
  whether its commands are fresh or not (a runaway);
- hold: while an axis has no fresh command, the drive holds the last one only while the
  axis stays within `hold_deviation` of where it stood at its last fresh command — at this
  tick and, extrapolated at constant acceleration from its last three positions, at the
  next one. It stops the axis before the extrapolation leaves that window.

So when the command stream ends, the axis stops within `hold_deviation` of where it was,
plus what a change of its acceleration moves it in one period beyond the extrapolation
(½·Δa·T²: 0.5 mm for Δa = 10 m/s² at T = 10 ms, 5 µm at 1 ms), plus the stopping
distance of the machine's brake (zero in the simulation). The stop after `brake_after`
late periods (mill_plant.command_table) bounds the hold in time.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field


@dataclass
class AxisMotion:
    recent: deque[tuple[int, float]] = field(default_factory=lambda: deque(maxlen=3))
    anchor: float = math.nan  # the position at the last tick with a fresh command


class MotionGuard:
    def __init__(self, axes: list[str], speed_limit: float, hold_deviation: float) -> None:
        self.speed_limit = speed_limit  # [m/s]
        self.hold_deviation = hold_deviation  # [m]
        self.by_axis = {a: AxisMotion() for a in axes}

    def check(
        self, ns: int, positions: dict[str, float], holding: dict[str, bool]
    ) -> dict[str, str]:
        """The axes to stop now and why, from the positions read at stamp ns; holding: per
        axis, whether its command is held (no fresh one this tick). Axes left out (not
        under way, stopped already) are not checked and start afresh when they come back."""
        out: dict[str, str] = {}
        for axis, m in self.by_axis.items():
            if axis not in positions:
                m.recent.clear()
                m.anchor = math.nan
                continue
            x = positions[axis]
            m.recent.append((ns, x))
            speed = self._speed(m)
            if speed > self.speed_limit:
                out[axis] = (
                    f'speed {1e3 * speed:.1f} mm/s above the limit {1e3 * self.speed_limit:g} mm/s'
                )
            elif not holding.get(axis, False) or math.isnan(m.anchor):
                m.anchor = x
            else:
                far = max(abs(x - m.anchor), abs(self._next(m) - m.anchor))
                if far > self.hold_deviation:
                    out[axis] = (
                        f'holding the last command it would leave {1e3 * self.hold_deviation:g}'
                        f' mm around where its commands ended (at {1e3 * abs(x - m.anchor):.3f}'
                        ' mm now)'
                    )
            if axis in out:
                m.recent.clear()
                m.anchor = math.nan
        return out

    @staticmethod
    def _speed(m: AxisMotion) -> float:
        """The mean speed over the last period [m/s] (0 before two positions)."""
        if len(m.recent) < 2:
            return 0.0
        (t0, x0), (t1, x1) = m.recent[-2], m.recent[-1]
        return abs(x1 - x0) / max(t1 - t0, 1) * 1e9

    @staticmethod
    def _next(m: AxisMotion) -> float:
        """The position at the next tick, at constant acceleration (ticks a period apart)."""
        xs = [x for _, x in m.recent]
        if len(xs) == 3:
            return 3 * xs[2] - 3 * xs[1] + xs[0]
        if len(xs) == 2:
            return 2 * xs[1] - xs[0]
        return xs[-1]

    def moved(self, axis: str) -> float:
        """How far the axis is from where it stood at its last fresh command [m] (NaN: not
        known)."""
        m = self.by_axis[axis]
        return abs(m.recent[-1][1] - m.anchor) if m.recent else math.nan
