"""How a drive protects its axes, one implementation for real time, lockstep and the offline
simulator. ROS-free.

At each tick (each step in lockstep) the drive reads the positions and, before it applies
any command, asks its motion guard (mill_plant.motion_guard: the travel, the speed limit
and, while commands are late, the hold window) which axes to stop; each is stopped in the
command table (mill_plant.command_table): braked and latched, released only by the owner's
re-arm (a brake request, then a valid command) or the operator's release.

- real time: the table's `take` then applies the newest command of each axis (zero-order
  hold) and stops the axes whose commands stay away too long;
- lockstep (`lockstep_step`): every axis has answered the step, so none is late; the
  commands pass the transport delay (mill_plant.command_delay) and a stopped axis gets NaN,
  at once, whatever the delay. The lockstep drive (mill_plant.drive_cycle) and the offline
  simulator (mill_bringup.axis_simulation) both step through here, so a run stays equal to
  its offline twin, stops included.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from mill_plant.command_delay import CommandDelay
from mill_plant.command_table import CommandTable
from mill_plant.motion_guard import MotionGuard


@dataclass(frozen=True)
class Step:
    efforts: list[float]  # what to apply over the step, NaN = brake
    stopped: dict[str, str]  # axes stopped at this step, and why
    rearmed: list[str]  # axes released by their owner's re-arm at this step


class Protection:
    def __init__(self, table: CommandTable, guard: MotionGuard) -> None:
        self.table = table
        self.guard = guard

    def check(self, ns: int, positions: Sequence[float]) -> dict[str, str]:
        """Stop the axes whose motion the drive does not allow, from the positions read at
        stamp ns (in the table's axis order); the axes stopped now, and why. Only the axes
        under way (a command came, not stopped) are checked."""
        table = self.table.by_axis
        under_way = {
            a: x
            for a, x in zip(self.table.axes, positions, strict=True)
            if table[a].stamp >= 0 and not table[a].stopped
        }
        holding = {a: not table[a].fresh for a in under_way}
        stops = self.guard.check(ns, under_way, holding)
        for axis, reason in stops.items():
            self.table.stop(axis, reason)
        return stops

    def lockstep_step(self, ns: int, positions: Sequence[float], delay: CommandDelay) -> Step:
        """Lockstep, once every axis has answered step ns: the efforts to write."""
        stopped = self.check(ns, positions)
        rearmed = self.table.step()
        efforts = delay(self.table.values())
        stops = self.table.by_axis
        efforts = [
            math.nan if stops[a].stopped else u
            for a, u in zip(self.table.axes, efforts, strict=True)
        ]
        return Step(efforts, stopped, rearmed)
