"""What a drive checks of each axis's motion by itself, as a servo amplifier does, in real
time and in lockstep alike. ROS-free.

The drive reads every axis's position at each tick (each step in lockstep) and asks `check`
which axes to stop (braked and latched, mill_plant.command_table, through
mill_plant.protection), before it applies any command:

- travel: an axis that is outside the machine's travel (`travel.min`, `travel.max`, the
  declaration mill_common.travel that the trajectory reads too), or would be at the next
  tick extrapolated at constant acceleration from its last three positions, and moves
  outwards, is stopped, whatever its commands: it stops inside the travel but for what a
  change of its acceleration moves it in the one period beyond the extrapolation
  (½·Δa·T², 21 µm for a 10 N·m jump on Beltrán's x axis at T = 1 ms) plus the brake's
  stopping distance (zero in the simulation). An axis outside may move back in;
- speed: an axis that moved faster than `speed_limit` over the last period is stopped,
  whether its commands are fresh or not (a runaway);
- hold: while an axis has no fresh command, the drive holds the last one only while the
  axis stays within `hold_deviation` of where it would be had it kept the speed it had at
  its last fresh command — at this tick and, extrapolated at constant acceleration from its
  last three positions, at the next one. A held command that keeps the axis on its course
  goes on; one that accelerates it away is stopped before the extrapolation leaves the
  window.

So when the command stream ends at speed v, the axis stops within v·H + `hold_deviation`
of where it was (H: the hold, at most H(v) = min(max_hold, (excursion − hold_deviation)/|v|)
of mill_common.hold_window, after which mill_plant.command_table stops the axis: so within
`excursion`; v is `speed(axis)`, the speed at its last fresh command), plus what a change
of its acceleration moves it in one period beyond the extrapolation (½·Δa·T²: 0.5 mm for
Δa = 10 m/s² at T = 10 ms, 5 µm at 1 ms), plus the stopping distance of the machine's
brake (zero in the simulation), plus how far it moves while the drive itself does not run
(a stall of the drive's own process: the amplifier holds what it was given).
The extrapolation takes the ticks a period apart.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass
class AxisMotion:
    recent: deque[tuple[int, float]] = field(default_factory=lambda: deque(maxlen=3))
    # At the last tick with a fresh command: its stamp [ns], the position and the speed.
    anchor: tuple[int, float, float] | None = None

    def course(self, ns: int) -> float:
        """Where the axis would be at ns had it kept the speed of its last fresh command."""
        assert self.anchor is not None
        t, x, v = self.anchor
        return x + v * (ns - t) * 1e-9


class MotionGuard:
    def __init__(
        self,
        axes: list[str],
        speed_limit: float,
        hold_deviation: float,
        travel: Mapping[str, tuple[float, float]] | None = None,
    ) -> None:
        self.speed_limit = speed_limit  # [m/s]
        self.hold_deviation = hold_deviation  # [m]
        # axis -> (lowest, highest) position [m]; an axis left out has no travel limit
        self.travel = dict(travel or {})
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
                m.anchor = None
                continue
            x = positions[axis]
            m.recent.append((ns, x))
            speed = self._speed(m)
            leaves = self._leaves(axis, m)
            if leaves:
                out[axis] = leaves
            elif abs(speed) > self.speed_limit:
                out[axis] = (
                    f'speed {1e3 * abs(speed):.1f} mm/s above the limit '
                    f'{1e3 * self.speed_limit:g} mm/s'
                )
            elif not holding.get(axis, False) or m.anchor is None:
                m.anchor = (ns, x, speed)
            else:
                step = ns - m.recent[-2][0] if len(m.recent) > 1 else 0
                off = max(abs(x - m.course(ns)), abs(self._next(m) - m.course(ns + step)))
                if off > self.hold_deviation:
                    moved = 1e3 * self.moved(axis)
                    out[axis] = (
                        f'holding the last command it would leave {1e3 * self.hold_deviation:g}'
                        f' mm around its course when its commands ended ({moved:.3f} mm from '
                        'where they ended)'
                    )
            if axis in out:
                m.recent.clear()
                m.anchor = None
        return out

    def _leaves(self, axis: str, m: AxisMotion) -> str:
        """Why the axis is leaving the travel ('' if it is not): outside it now or at the
        next tick, and moving outwards."""
        if axis not in self.travel:
            return ''
        lo, hi = self.travel[axis]
        x, ahead = m.recent[-1][1], self._next(m)
        moving = ahead - x
        if ahead > hi and moving > 0.0:
            return f'at {x:.6f} m it would leave the travel (travel.max {hi:g} m)'
        if ahead < lo and moving < 0.0:
            return f'at {x:.6f} m it would leave the travel (travel.min {lo:g} m)'
        return ''

    @staticmethod
    def _speed(m: AxisMotion) -> float:
        """The mean velocity over the last period [m/s] (0 before two positions)."""
        if len(m.recent) < 2:
            return 0.0
        (t0, x0), (t1, x1) = m.recent[-2], m.recent[-1]
        return (x1 - x0) / max(t1 - t0, 1) * 1e9

    @staticmethod
    def _next(m: AxisMotion) -> float:
        """The position at the next tick, at constant acceleration (ticks a period apart)."""
        xs = [x for _, x in m.recent]
        if len(xs) == 3:
            return 3 * xs[2] - 3 * xs[1] + xs[0]
        if len(xs) == 2:
            return 2 * xs[1] - xs[0]
        return xs[-1]

    def speed(self, axis: str) -> float:
        """The axis's speed at its last fresh command [m/s] (0 when not known)."""
        anchor = self.by_axis[axis].anchor
        return anchor[2] if anchor is not None else 0.0

    def moved(self, axis: str) -> float:
        """How far the axis is from where it stood at its last fresh command [m] (NaN: not
        known)."""
        m = self.by_axis[axis]
        if not m.recent or m.anchor is None:
            return math.nan
        return abs(m.recent[-1][1] - m.anchor[1])
