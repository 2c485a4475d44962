"""The commands a drive holds, per axis: which to apply, which are late, when to brake. ROS-free.

Every command names the state it answers by its stamp. The drive front end
(mill_plant.drive_node) offers each accepted command here and asks, per period:

- lockstep: `complete(stamp)` — has every axis answered the state of this step? — then
  `step()`: every command is fresh, and a stopped axis may be re-armed;
- real time: `take(ns, speeds)` at each tick — the newest command of every axis (zero-order
  hold: a command stays applied until a newer one arrives). A command is fresh if it
  arrived since the last tick; a tick without a fresh command counts as late (from the
  axis's first command on: before it the job has not started). The controller's silence is
  counted over the ticks the drive has actually published, each at most one period: a drive
  that itself slept 300 ms published no state in that time, so no answer is missing (the
  answer to its last state may wait unread in its queue), and its own stall is reported as
  such (mill_plant.drive_cycle), never as the controller's lateness. The drive holds the last
  command while that silence, one period more, stays within the window H(v) of
  mill_common.hold_window at the axis's speed v at its last fresh command (`max_hold` at
  rest, shorter at speed: the blind run stays within `excursion`); at the tick that would
  exceed it the axis is stopped: braked (NaN) and latched. The longest run of late ticks is
  kept: scattered late ticks cost little, a long silence stops the axis. The drive's motion
  guard (mill_plant.motion_guard) stops an axis the same way (`stop`).

A stopped axis stays braked when commands return: the first command that arrives after an
outage comes from a controller that knows nothing of it. It is released only by an explicit
handshake, as a servo amplifier's fault is: the owner acknowledges with a brake request (a
NaN command, what a tripped controller sends) and then re-arms with a valid command, or the
operator releases it (`release`, the drive's ~/release service). A released axis goes back to
where it stood before its first command: braked, and not watched — no tick counts late and no
silence stops it again — until its next fresh command, which a new job's controller sends once
it runs (a release between jobs, with no job running, is not undone by the window). A
deactivated drive (`brake_all`) does the same for every axis, but a latched stop stays latched
through it: the next job's start handshake releases it explicitly (docs/hardware-driver.md).

It also keeps, per axis, the state → command latency of every fresh command: the time the
command arrived minus the stamp of the state it answers (both on the drive's clock), in a
histogram (mill_plant.latency_histogram) whose report does not grow with the run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from mill_common.hold_window import HoldWindow

from mill_plant.latency_histogram import LatencyHistogram


@dataclass
class AxisCommands:
    value: float = math.nan  # the newest accepted command
    stamp: int = -1  # stamp of the state it answers [ns]; -1: none since the start or release
    floor: int = -1  # a command must be newer than this (the one held before a release)
    fresh: bool = False  # arrived since the last tick
    late_in_row: int = 0
    longest_late_run: int = 0  # most late ticks in a row
    waited_ns: int = 0  # the silence since the last fresh command, over the drive's ticks
    longest_wait_ns: int = 0
    ticks: int = 0
    late: int = 0
    braked: bool = True  # before the first command an axis is held braked
    stopped: str = ''  # why the axis is stopped (latched until released), '' if it is not
    acknowledged: bool = False  # the owner sent a brake request since the stop
    returned: bool = False  # fresh commands came while stopped (said once)
    latencies: LatencyHistogram = field(default_factory=LatencyHistogram)


@dataclass(frozen=True)
class Tick:
    efforts: list[float]  # what to apply now, NaN = brake
    resumed: list[str]  # axes released by a fresh command (their first, or after a release)
    stopped: list[str]  # axes stopped (latched) at this tick: no fresh command for too long
    returned: list[str]  # commands again on a stopped axis: it stays stopped until re-armed


class CommandTable:
    def __init__(self, axes: list[str], window: HoldWindow, period_ns: int) -> None:
        self.axes = list(axes)
        self.window = window
        self.period_ns = period_ns
        self.by_axis = {a: AxisCommands() for a in self.axes}
        self.last_tick_ns: int | None = None

    def offer(self, axis: str, stamp: int, value: float, arrived_ns: int | None = None) -> bool:
        """An accepted command; False if it is not newer than the one held (dropped)."""
        c = self.by_axis[axis]
        if stamp <= c.floor or stamp < c.stamp:
            return False  # older than the held one, or than the axis's release
        if stamp == c.stamp and not (math.isnan(value) and c.value == c.value):
            return False  # the same step again: only a brake replaces a valid one
        again, c.value, c.stamp, c.fresh = stamp == c.stamp, value, stamp, True
        if c.stopped and math.isnan(value):
            c.acknowledged = True  # the owner knows: its next valid command re-arms
        if arrived_ns is not None and not again:
            c.latencies.add(arrived_ns - stamp)
        return True

    # -- lockstep ------------------------------------------------------------------------------
    def complete(self, stamp: int) -> bool:
        return all(c.stamp == stamp for c in self.by_axis.values())

    def missing(self, stamp: int) -> list[str]:
        return [a for a, c in self.by_axis.items() if c.stamp != stamp]

    def values(self) -> list[float]:
        return [c.value for c in self.by_axis.values()]

    def step(self) -> list[str]:
        """The step every axis has answered: each command is fresh, none late. A stopped axis
        whose owner has acknowledged the stop is re-armed by a valid command; returns the
        axes re-armed."""
        rearmed = []
        for axis, c in self.by_axis.items():
            c.fresh = False
            if c.stopped and c.acknowledged and math.isfinite(c.value):
                self._release(c)
                rearmed.append(axis)
            c.braked = bool(c.stopped)
        return rearmed

    # -- real time -----------------------------------------------------------------------------
    def take(self, ns: int, speeds: Mapping[str, float] | None = None) -> Tick:
        """The tick at stamp ns: what to apply. speeds: per axis, its speed at its last
        fresh command [m/s] (mill_plant.motion_guard; left out: at rest)."""
        # The time this tick asked of the controllers: at most one period, whatever the drive
        # itself slept since its last tick (then it published nothing to answer).
        last, self.last_tick_ns = self.last_tick_ns, ns
        asked = self.period_ns if last is None else min(max(ns - last, 0), self.period_ns)
        efforts: list[float] = []
        resumed: list[str] = []
        stopped: list[str] = []
        returned: list[str] = []
        for axis, c in self.by_axis.items():
            if c.stamp < 0:
                # no command yet (or since a release): no job runs on it, it holds braked
                efforts.append(math.nan)
                continue
            c.ticks += 1
            if c.fresh:
                c.fresh = False
                c.late_in_row = c.waited_ns = 0
                if c.stopped and c.acknowledged and math.isfinite(c.value):
                    self._release(c)  # re-armed by its owner: brake request, then a command
                if c.stopped and not c.returned:
                    c.returned = True
                    returned.append(axis)
                elif not c.stopped and c.braked:
                    c.braked = False
                    resumed.append(axis)
            else:
                c.late += 1
                c.late_in_row += 1
                c.longest_late_run = max(c.longest_late_run, c.late_in_row)
                c.waited_ns += asked
                c.longest_wait_ns = max(c.longest_wait_ns, c.waited_ns)
                speed = (speeds or {}).get(axis, 0.0)
                hold_ns = round(self.window.hold_time(speed) * 1e9)
                # Holding on for one more period would exceed the window: stop now.
                if not c.stopped and c.waited_ns + self.period_ns > hold_ns:
                    at = f'{1e3 * abs(speed):.1f} mm/s' if speed else 'rest'
                    self.stop(
                        axis,
                        f'no fresh command for {1e-6 * c.waited_ns:.0f} ms of its ticks '
                        f'(the window at {at}: {1e-6 * hold_ns:.0f} ms)',
                    )
                    stopped.append(axis)
            efforts.append(math.nan if c.braked else c.value)
        return Tick(efforts, resumed, stopped, returned)

    def stop(self, axis: str, reason: str) -> bool:
        """Stop the axis (braked, latched until released) from now on; False if it was."""
        c = self.by_axis[axis]
        if c.stopped:
            return False
        c.stopped, c.braked, c.acknowledged, c.returned = reason, True, False, False
        return True

    def release(self, axis: str) -> bool:
        """The operator's release of a stopped axis (False if it was not stopped): it holds
        braked, unwatched, until its next fresh command (as before its first)."""
        c = self.by_axis[axis]
        if not c.stopped:
            return False
        self._release(c)
        self._idle(c)
        return True

    @staticmethod
    def _idle(c: AxisCommands) -> None:
        """Back to the state before the axis's first command: braked, no tick counted late
        until the next fresh command (newer than the one held)."""
        c.floor = max(c.floor, c.stamp)
        c.stamp, c.fresh, c.braked, c.late_in_row, c.waited_ns = -1, False, True, 0, 0

    @staticmethod
    def _release(c: AxisCommands) -> None:
        c.stopped, c.acknowledged, c.returned = '', False, False

    def brake_all(self) -> None:
        """Every axis braked and idle until its next fresh command (a deactivated drive:
        the next job starts afresh); a latched stop stays latched."""
        for c in self.by_axis.values():
            self._idle(c)

    def stop_reasons(self) -> dict[str, str]:
        """Why each stopped axis is stopped."""
        return {a: c.stopped for a, c in self.by_axis.items() if c.stopped}

    def late_fraction(self, axis: str) -> float:
        c = self.by_axis[axis]
        return c.late / c.ticks if c.ticks else math.nan

    def longest_late_run(self, axis: str) -> int:
        return self.by_axis[axis].longest_late_run

    def longest_wait(self, axis: str) -> float:
        """The longest silence of the axis's commands, over the drive's ticks [s]."""
        return 1e-9 * self.by_axis[axis].longest_wait_ns

    def latency_stats(self, axis: str) -> dict[str, float]:
        """Median, p99 and max state → command latency [s] of an axis (to 1 µs)."""
        return self.by_axis[axis].latencies.stats()
