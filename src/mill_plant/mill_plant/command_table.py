"""The commands a drive holds, per axis: which to apply, which are late, when to brake. ROS-free.

Every command names the state it answers by its stamp. The drive front end
(mill_plant.drive_node) offers each accepted command here and asks, per period:

- lockstep: `complete(stamp)` — has every axis answered the state of this step?
- real time: `take(now)` at each tick — the newest command of every axis (zero-order
  hold: a command stays applied until a newer one arrives). A command is fresh if it
  arrived since the last tick; a tick without a fresh command counts as late (from the
  axis's first command on: before it the job has not started), and after
  `brake_after` late ticks in a row the axis is braked (NaN) until fresh commands return.
  The longest such run is kept: scattered late ticks cost little, a long run brakes.

It also keeps, per axis, the state → command latency of every fresh command: the time the
command arrived minus the stamp of the state it answers (both on the drive's clock), in a
histogram (mill_plant.latency_histogram) whose report does not grow with the run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mill_plant.latency_histogram import LatencyHistogram


@dataclass
class AxisCommands:
    value: float = math.nan  # the newest accepted command
    stamp: int = -1  # stamp of the state it answers [ns]
    fresh: bool = False  # arrived since the last tick
    late_in_row: int = 0
    longest_late_run: int = 0  # most late ticks in a row (a brake comes at brake_after)
    ticks: int = 0
    late: int = 0
    braked: bool = True  # before the first command an axis is held braked
    latencies: LatencyHistogram = field(default_factory=LatencyHistogram)


@dataclass(frozen=True)
class Tick:
    efforts: list[float]  # what to apply now, NaN = brake
    newly_braked: list[str]  # axes braked at this tick
    resumed: list[str]  # axes that got fresh commands again after a brake


class CommandTable:
    def __init__(self, axes: list[str], brake_after: int) -> None:
        self.axes = list(axes)
        self.brake_after = brake_after
        self.by_axis = {a: AxisCommands() for a in self.axes}

    def offer(self, axis: str, stamp: int, value: float, arrived_ns: int | None = None) -> bool:
        """An accepted command; False if it is not newer than the one held (dropped)."""
        c = self.by_axis[axis]
        if stamp <= c.stamp:
            return False
        c.value, c.stamp, c.fresh = value, stamp, True
        if arrived_ns is not None:
            c.latencies.add(arrived_ns - stamp)
        return True

    # -- lockstep ------------------------------------------------------------------------------
    def complete(self, stamp: int) -> bool:
        return all(c.stamp == stamp for c in self.by_axis.values())

    def missing(self, stamp: int) -> list[str]:
        return [a for a, c in self.by_axis.items() if c.stamp != stamp]

    def values(self) -> list[float]:
        return [c.value for c in self.by_axis.values()]

    # -- real time -----------------------------------------------------------------------------
    def take(self) -> Tick:
        efforts, braked, resumed = [], [], []
        for axis, c in self.by_axis.items():
            if c.stamp < 0:
                efforts.append(math.nan)  # no command yet: the job has not started for it
                continue
            c.ticks += 1
            if c.fresh:
                c.fresh = False
                c.late_in_row = 0
                if c.braked and c.stamp >= 0:
                    c.braked = False
                    resumed.append(axis)
            else:
                c.late += 1
                c.late_in_row += 1
                c.longest_late_run = max(c.longest_late_run, c.late_in_row)
                if not c.braked and c.late_in_row >= self.brake_after:
                    c.braked = True
                    braked.append(axis)
            efforts.append(math.nan if c.braked else c.value)
        return Tick(efforts, braked, resumed)

    def brake_all(self) -> None:
        for c in self.by_axis.values():
            c.braked = True

    def late_fraction(self, axis: str) -> float:
        c = self.by_axis[axis]
        return c.late / c.ticks if c.ticks else math.nan

    def longest_late_run(self, axis: str) -> int:
        return self.by_axis[axis].longest_late_run

    def latency_stats(self, axis: str) -> dict[str, float]:
        """Median, p99 and max state → command latency [s] of an axis (to 1 µs)."""
        return self.by_axis[axis].latencies.stats()
