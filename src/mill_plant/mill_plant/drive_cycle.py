"""When the drive steps: its `timing`, one strategy chosen at start.

The drive front end (mill_plant.drive_node) checks and holds the commands, publishes and
reports; its cycle says when a period runs and what counts as late:

The cycle owns the loop and reaches the machine through a narrow port (`DrivePort`:
publish a sample's states, write its efforts, let time pass), as a ros2_control hardware
interface offers read() and write(); what else it works with is handed to it at configure
(`Machine`: the command table, the reports, the parameters' values, the logger, and the few
things only the graph and the lifecycle know, as functions). Both cycles protect the axes
the same way (mill_plant.protection: the motion guard's travel, speed limit and hold
window, a latched stop, the same re-arm).

- `LockstepCycle` (simulation only): the plant is the clock. It publishes /clock and the
  states of step k (stamp kT), waits for the command stamped k of every active axis, then
  stops the axes its guard forbids to move on (braked, latched until re-armed: no sender
  moves an axis beyond the travel or faster than `speed_limit`) and integrates to k + 1
  with each command N steps late (`command_delay`), exactly as the offline simulator;
  with `spindle: reference` it waits for the spindle speed of step k on the reference too
  (mill_plant.spindle). A step that stays unanswered is offered again every second (a
  restarted node rejoins); a missing command is reported after
  `command_report_time`, naming the axis, the topic and the node that should send it,
  and when commands return, with the length of the silence; after `lockstep_timeout`
  the node ends with that message.
  With `recorder_window` W it also waits for the recorder: the states of step j go out only
  once step j − W has been acknowledged on mill/recorded, so that a busy recorder cannot
  lose samples (mill_bringup.bag_handshake).
- `RealtimeCycle`: every sample period of wall time it reads the positions, publishes them
  stamped with the acquisition time on the system clock, and applies the newest command of
  each axis (zero-order hold). A command must answer a state this drive published. A
  period without a fresh command counts as late, and the controller's silence is counted
  over the ticks this drive published (its own stall asked nothing of the controllers);
  when it would outlast the window H(v) of mill_common.hold_window (`max_hold` at rest,
  shorter at speed: the axis runs blind at most `excursion`), or when its motion leaves
  what the drive allows (mill_plant.motion_guard: a speed limit, and while commands are
  late a window around where they ended), the axis is stopped: braked, and released only
  by a re-arm (the owner's brake request then a valid command) or the operator
  (~/release), never by the first command that returns (mill_plant.command_table). Every
  state says whether the drive has stopped its axis (`effort` NaN). Ticks more than half a
  period late (the machine does not hold the rate) are counted and reported; a tick that
  wakes more than `stall_report` late on the monotonic clock is the drive's own stall,
  reported as such ("drive plant (pid …) stalled 112 ms (monotonic) at …"). A simulated
  machine keeps the wall clock as a real one does: after each tick it moves one period on,
  and a tick that comes late first moves it by what passed beyond that.
"""

from __future__ import annotations

import math
import os
import time
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import Rejected
from mill_common.hold_window import HoldWindow, Stall, StallWatch
from mill_common.lockstep import Action, LockstepWatchdog, RecorderGate
from mill_common.step_waits import StepWaits
from mill_common.timebase import seconds
from mill_common.timing import TIMINGS
from mill_common.travel import MachineTravel

from mill_common import topics
from mill_plant.command_delay import CommandDelay
from mill_plant.command_table import CommandTable
from mill_plant.drive_reports import DriveReports
from mill_plant.motion_guard import MotionGuard
from mill_plant.protection import Protection
from mill_plant.spindle import SpindleTrack
from mill_plant.topic_pair import sender_clock

# How a stopped axis is released, said with every stop.
REARM = "the controller's brake request, then a valid command; or ~/release"
RECENT_STAMPS = 200  # realtime: published state stamps a command may answer
# A tick later than a period / CATCH_UP moves the machine on first; less is left to the
# next period (the timer keeps its schedule on average).
CATCH_UP = 20


class DrivePort(Protocol):
    """The machine as a cycle reaches it through the drive front end
    (mill_plant.drive_node.DriveNode), the way a ros2_control hardware interface offers
    read() and write(): publish a sample's states, write its efforts, let time pass."""

    def publish(self, ns: int, say_stops: bool = False) -> list[float]:
        """Read the positions of sample ns, publish them (and what goes with them); return
        them in the order of the cycle's axes."""
        ...

    def write(self, ns: int, efforts: list[float]) -> None:
        """Apply these efforts from sample ns on (NaN: brake that axis)."""
        ...

    def advance(self, ns: int, dt: float, held: Collection[str] = ()) -> None:
        """Let dt seconds pass from ns with the efforts written."""
        ...


@dataclass(frozen=True)
class Machine:
    """What the drive hands its cycle at configure: the port, and the explicit collaborators
    a cycle works with (none of them the node)."""

    port: DrivePort
    axes: list[str]
    table: CommandTable  # the commands held (mill_plant.command_table)
    reports: DriveReports  # its axis events and its status
    values: Callable[[], Mapping[str, Any]]  # the parameters' values now
    owners: Mapping[str, str]  # axis -> the node its commands come from ('' anyone)
    spindle: SpindleTrack | None  # spindle: reference
    log: Any  # the node's logger
    # What only the graph and the lifecycle know, as functions:
    missing_peers: Callable[[], list[str]]
    publishers_of: Callable[[str], list[str]]  # node names publishing on a topic
    activate: Callable[[], object]  # the lifecycle transition activate
    end: Callable[[int, str], None]  # end the node with this code and message
    clock: Callable[[int], None] | None = None  # publish /clock (lockstep)
    # the topic an axis's commands come on (ros2_control: the pair's, mill_plant.topic_pair)
    command_topic: Callable[[str], str] = topics.joint_command

    def owner_of(self, axis: str) -> str:
        return self.owners[axis] or 'its controller'


class DriveCycle(ABC):
    TIMING: ClassVar[str]  # the `timing` it is
    STATUS: ClassVar[str]  # the part of the drive's status `<node>: <part>` on /diagnostics
    GRID: ClassVar[bool]  # command stamps lie on the sample grid
    TICKS: ClassVar[bool]  # the drive calls `tick` every sample period of wall time
    m: Machine  # by configure

    def __init__(self, dt_ns: int, name: str) -> None:
        self.dt_ns = dt_ns
        self.dt = seconds(dt_ns)
        self.name = name  # the drive's node name
        self.k = 0  # steps (lockstep) or ticks (realtime) so far
        self.active = False  # applying commands
        # how a stamp reads in the log: job time, or the time of day (mill_common.timing)
        self.when = TIMINGS[self.TIMING](dt_ns).when

    def configure(self, machine: Machine) -> None:
        """Take the machine, and build what the cycle needs once it exists."""
        self.m = machine
        v = machine.values()
        travel = MachineTravel.from_node_values(v).limits(''.join(machine.axes))
        guard = MotionGuard(machine.axes, v['speed_limit'], v['hold_deviation'], travel)
        self._protection = Protection(machine.table, guard)
        self.stops = dict.fromkeys(machine.axes, 0)  # times each axis was stopped

    def activate(self) -> None:  # noqa: B027 (nothing to do by default)
        """The lifecycle transition activate."""

    def deactivate(self) -> None:
        """The lifecycle transition deactivate (the drive brakes every axis)."""
        self.active = False

    @abstractmethod
    def expected(self, ns: int) -> Rejected | None:
        """Whether a command stamped ns answers a state of this drive (None: it does)."""

    def arrival_ns(self) -> int | None:
        """When a command arrived, if the cycle keeps its latency."""
        return None

    def sender_stamped(self, ns: int) -> Rejected | None:
        """Whether a command stamped on its sender's own clock, not with the state it
        answers (ros2_control's, mill_plant.topic_pair), is recent (None: it is)."""
        return Rejected(f'{self.TIMING} takes only commands that answer its states')

    def command_taken(self) -> None:  # noqa: B027 (nothing to do by default)
        """A command (or the spindle speed) was taken: a step may be whole."""

    def tick(self) -> None:  # noqa: B027 (lockstep: no tick)
        """Every sample period of wall time (TICKS)."""

    def recorded(self, ns: int) -> None:  # noqa: B027 (realtime: no recorder handshake)
        """The recorder acknowledged the step stamped ns."""

    def _refresh_guard(self) -> None:
        """The guard's limits as the parameters are now (they may be set at run time)."""
        v = self.m.values()
        guard = self._protection.guard
        guard.speed_limit, guard.hold_deviation = v['speed_limit'], v['hold_deviation']

    def _stopped(self, axis: str, reason: str) -> None:
        self.stops[axis] += 1
        self.m.reports.axis(
            axis, DiagnosticStatus.ERROR, f'stopped: {reason}; braked until re-armed ({REARM})'
        )
        self.m.reports.status(force=True)

    def release(self) -> list[str]:
        """The operator's release (~/release): the stopped axes, now released."""
        m = self.m
        released = [a for a in m.axes if m.table.release(a)]
        for axis in released:
            m.reports.axis(
                axis,
                DiagnosticStatus.OK,
                'released by ~/release: braked until its next fresh command',
            )
        return released

    @abstractmethod
    def watch(self, now: float) -> None:
        """From the drive's watchdog timer (steady time now)."""

    @abstractmethod
    def stamp_now(self) -> int:
        """The stamp of a status published now."""

    def status_values(self) -> dict[str, object]:
        """The cycle's figures for the drive's status: per axis, its stops."""
        stopped = self.m.table.stop_reasons()
        values: dict[str, object] = {}
        for axis in self.m.axes:
            values[f'{axis}.stops'] = self.stops[axis]
            values[f'{axis}.stopped'] = stopped.get(axis, '')
        return values


class LockstepCycle(DriveCycle):
    TIMING = 'lockstep'
    STATUS = topics.DRIVE_STATUSES[0]
    GRID = True
    TICKS = False

    def configure(self, machine: Machine) -> None:
        super().configure(machine)
        v = machine.values()
        self._delay = CommandDelay(v['command_delay'], len(machine.axes))
        self._clock_every = max(1, round(v['clock_period'] * 1e9 / self.dt_ns))
        self._watchdog = LockstepWatchdog(
            time.monotonic(),
            lambda: machine.values()['startup_timeout'],
            lambda: machine.values()['lockstep_timeout'],
        )
        self.allowed = False  # activated (by autostart or the lifecycle)
        self._waits = StepWaits()  # how long each step waited (mill_common.step_waits)
        self._last_publish = time.monotonic()
        self._missing: set[str] = set()  # axes reported missing
        self._recorder = RecorderGate(v['recorder_window'], self.dt)
        self._positions: list[float] = []  # read at the step's publish

    def activate(self) -> None:
        self.allowed = True  # stepping starts once the peers are matched (see watch)

    def deactivate(self) -> None:
        super().deactivate()
        self.allowed = False

    @property
    def stamp(self) -> int:
        return self.k * self.dt_ns

    def expected(self, ns: int) -> Rejected | None:
        if ns != self.stamp:
            return Rejected(
                f'stamp {ns / 1e9:.6f} s is not the current step {self.stamp / 1e9:.6f} s'
            )
        return None

    def _whole(self) -> bool:
        """Whether the step has all it needs: every command, and the spindle's speed."""
        m = self.m
        spindle = m.spindle is None or m.spindle.known(self.stamp)
        return m.table.complete(self.stamp) and spindle

    def command_taken(self) -> None:
        if self.active and self._whole() and self._recorder_caught_up():
            self._advance()

    def _recorder_caught_up(self) -> bool:
        """Whether the next step may go out: the recorder is at most the window behind it."""
        return self._recorder.allows(self.k + 1)

    def recorded(self, ns: int) -> None:
        self._recorder.acknowledged(ns)
        started = self.active and self._watchdog.started
        if started and self._whole() and self._recorder_caught_up():
            self._advance()

    def _publish_step(self, again: bool = False) -> None:
        clock = self.m.clock
        if clock is not None and (again or self.k % self._clock_every == 0):
            clock(self.stamp)
        self._positions = self.m.port.publish(self.stamp)
        if not again:
            self._last_publish = time.monotonic()

    def _advance(self) -> None:
        m = self.m
        now = time.monotonic()
        self._waits.add(now - self._last_publish)
        # The drive's protection (mill_plant.protection), as in real time and offline.
        self._refresh_guard()
        step = self._protection.lockstep_step(self.stamp, self._positions, self._delay)
        for axis, reason in step.stopped.items():
            self._stopped(axis, reason)
        for axis in step.rearmed:
            m.reports.axis(axis, DiagnosticStatus.OK, f're-armed by {m.owner_of(axis)}: released')
        m.port.write(self.stamp, step.efforts)
        m.port.advance(self.stamp, self.dt)
        self.k += 1
        if self._missing:  # the step waited this long: the outage's length
            waited = self._watchdog.waited(now)
            for axis in self._missing if self.k > 1 else ():  # not the start-up's wait
                m.reports.axis(
                    axis,
                    DiagnosticStatus.OK,
                    f'commands arriving again after {waited:.2f} s of silence',
                )
            self._missing.clear()
        self._watchdog.progressed(now)
        if self.k % max(1, round(1.0 / self.dt)) == 0:
            m.reports.status(force=True)
        self._publish_step()

    def watch(self, now: float) -> None:
        m = self.m
        v = m.values()
        if not self.allowed and not v['autostart']:
            return  # waiting for the lifecycle transition activate
        action = self._watchdog.tick(now, m.missing_peers)
        if action is Action.START:
            if not self.allowed:
                m.activate()  # autostart
            self.active = True
            m.log.info('all peers matched: starting lockstep')
            self._publish_step()
        elif action is Action.OFFER_AGAIN and not self._whole():
            self._publish_step(again=True)  # (a step waiting only for the recorder is whole)
        elif action is Action.PEERS_MISSING:
            m.end(3, 'peers never appeared: ' + '; '.join(m.missing_peers()))
        elif action is Action.STALLED:
            m.end(3, self._timeout_message())
        report_time = v['command_report_time']
        if self._watchdog.started and self._watchdog.waited(now) >= report_time:
            for axis in m.table.missing(self.stamp):
                if axis not in self._missing:
                    self._missing.add(axis)
                    waited = self._watchdog.waited(now)
                    message = (
                        f'no command for step {self.k} on {topics.joint_command(axis)} from '
                        f'{m.owner_of(axis)} for {waited:.1f} s'
                    )
                    if self.k == 0:
                        # Start-up: the route of the first command may still be settling
                        # (discovery); the lockstep timeout ends a start that never comes.
                        m.log.info(message + ' (start-up)')
                    else:
                        m.reports.axis(axis, DiagnosticStatus.WARN, message)

    def _timeout_message(self) -> str:
        m = self.m
        timeout = m.values()['lockstep_timeout']
        if m.table.complete(self.stamp) and not self._whole():
            return (
                f'lockstep timeout: no spindle speed for t = {seconds(self.stamp):.3f} s '
                f'(step {self.k}) on {topics.REFERENCE} after '
                f'{timeout:g} s (spindle: reference)'
            )
        if m.table.complete(self.stamp):
            return (
                f'lockstep timeout: step {self.k} waited '
                f'{timeout:g} s for the recorder (its newest '
                f'acknowledgement on {topics.RECORDED}: {self._recorder.describe()})'
            )
        parts = []
        for axis in m.table.missing(self.stamp):
            topic = topics.joint_command(axis)
            nodes = m.publishers_of(topic)
            who = f'from {", ".join(nodes)}' if nodes else 'and no node publishes it'
            parts.append(f'{topic} ({who})')
        return (
            f'lockstep timeout: no command for t = {seconds(self.stamp):.3f} s (step {self.k}) '
            f'after {timeout:g} s on ' + ', '.join(parts)
        )

    def stamp_now(self) -> int:
        return self.stamp

    def status_values(self) -> dict[str, object]:
        out: dict[str, object] = dict(self._waits.status_values())
        if self._recorder.window:
            out['recorded_s'] = seconds(max(self._recorder.recorded, 0) * self.dt_ns)
        out.update(super().status_values())
        return out


class RealtimeCycle(DriveCycle):
    TIMING = 'realtime'
    STATUS = topics.DRIVE_STATUSES[1]
    GRID = False
    TICKS = True

    def configure(self, machine: Machine) -> None:
        super().configure(machine)
        self._recent: deque[int] = deque(maxlen=RECENT_STAMPS)
        self._held: Collection[str] = ()  # axes held braked before their first command
        self._moved_to = 0  # the wall time [ns] up to which the machine has moved
        # Ticks that came more than half a period late (the machine does not hold the
        # sample rate), in all and since the last report; ticks while active, their basis.
        self.overruns = self._overruns_reported = self.active_ticks = 0
        self._missing: set[str] = set()
        v = machine.values()
        # The drive's own stalls: ticks that woke late on the monotonic clock.
        self._stalls = StallWatch(self.dt_ns, round(v['stall_report'] * 1e9))
        self._stalls_reported = 0
        self._worst_new: Stall | None = None  # the longest since the last report
        self._window_values = self._window_key()

    def activate(self) -> None:
        self.active = True
        self.m.log.info('active: applying commands')

    def expected(self, ns: int) -> Rejected | None:
        if ns not in self._recent:
            return Rejected(f'stamp {ns / 1e9:.6f} s answers no state this drive published')
        return None

    def arrival_ns(self) -> int | None:
        return time.time_ns()

    def sender_stamped(self, ns: int) -> Rejected | None:
        oldest = self._recent[0] if self._recent else None
        return sender_clock(ns, oldest, time.time_ns(), self.dt_ns)

    def tick(self) -> None:
        m = self.m
        port, table, axes, dt_ns = m.port, m.table, m.axes, self.dt_ns
        ns = time.time_ns()  # acquisition time on the system clock
        if self.active:  # its own stalls while it drives (the watch starts afresh when active)
            stall = self._stalls.wake(time.monotonic_ns(), ns)
            if stall is not None and (
                self._worst_new is None or stall.length_ns > self._worst_new.length_ns
            ):
                self._worst_new = stall
        else:
            self._stalls.last_ns = None
        behind = ns - self._moved_to
        if self._moved_to and behind > dt_ns // CATCH_UP:  # a late tick: it moved on
            port.advance(self._moved_to, behind * 1e-9, self._held)
            self._moved_to = ns
        if self.active:
            self.active_ticks += 1
            if self._recent and ns - self._recent[-1] > 1.5 * dt_ns:
                self.overruns += 1
        positions = port.publish(ns, say_stops=True)
        self._recent.append(ns)
        held: Collection[str] = axes  # inactive: every axis held braked, as expected
        if self.active:
            self._guard_motion(ns, positions)
            guard = self._protection.guard
            tick = table.take(ns, {a: guard.speed(a) for a in axes})
            efforts = tick.efforts
            held = [a for a, c in table.by_axis.items() if c.stamp < 0]  # none came yet
            for axis in tick.stopped:
                reason = table.by_axis[axis].stopped
                moved = guard.moved(axis)
                self._stopped(
                    axis,
                    f'{reason} on {m.command_topic(axis)} (from {m.owner_of(axis)}); '
                    f'{1e3 * moved:.3f} mm from where it stood at the last one',
                )
            for axis in tick.returned:
                m.reports.axis(
                    axis,
                    DiagnosticStatus.ERROR,
                    f'commands arriving, but stopped ({table.by_axis[axis].stopped}): '
                    f'braked until re-armed ({REARM})',
                )
            for axis in tick.resumed:
                m.reports.axis(axis, DiagnosticStatus.OK, 'fresh commands: released')
        else:
            efforts = [math.nan] * len(axes)
        port.write(ns, efforts)
        self._held = held
        # The period that starts now, at once, so that the next tick reads without waiting;
        # a late tick adds what passed beyond it (above): the machine keeps the wall clock.
        start = max(ns, self._moved_to)
        port.advance(start, self.dt, held)
        self._moved_to = start + dt_ns
        self.k += 1

    def _guard_motion(self, ns: int, positions: list[float]) -> None:
        """Stop the axes whose motion the drive does not allow (before any command applies)."""
        self._refresh_guard()
        for axis, reason in self._protection.check(ns, positions).items():
            self._stopped(axis, reason)

    def watch(self, now: float) -> None:
        m = self.m
        if not self.active:
            return
        reports = m.reports
        if self.overruns > self._overruns_reported and now >= reports.next_status:
            late = self.overruns - self._overruns_reported
            self._overruns_reported = self.overruns
            text = (
                f'sample rate not held: {late} ticks came more than half a period '
                f'({0.5e-6 * self.dt_ns:g} ms) late in the last second; lower the rate or '
                'compose the nodes (run_scenario --layout single)'
            )
            m.log.warning(text)
            reports.status(force=True, message=text, level=DiagnosticStatus.WARN)
        if self._worst_new is not None and now >= reports.next_status:
            new = self._stalls.count - self._stalls_reported
            self._stalls_reported = self._stalls.count
            stall, self._worst_new = self._worst_new, None
            more = f' (longest of {new} in the last second)' if new > 1 else ''
            text = (
                f'{self.stalled(stall)}{more}: the drive did not run, so no state went out and '
                'no command was missing for it'
            )
            m.log.warning(text)
            reports.status(force=True, message=text, level=DiagnosticStatus.WARN)
        self._refresh_window()
        now_ns = time.time_ns()
        report_time = m.values()['command_report_time']
        for axis, c in m.table.by_axis.items():
            quiet = (now_ns - c.stamp) * 1e-9 if c.stamp >= 0 else math.inf
            if quiet >= report_time and axis not in self._missing:
                self._missing.add(axis)
                message = f'no fresh command on {m.command_topic(axis)} from {m.owner_of(axis)}'
                if c.stamp < 0:
                    # Start-up: no command yet (discovery); the axis holds until one comes.
                    m.log.info(message + ' yet (start-up)')
                else:
                    reports.axis(axis, DiagnosticStatus.WARN, message)
            elif quiet < report_time and axis in self._missing:
                self._missing.discard(axis)

    def stalled(self, stall: Stall) -> str:
        """'drive plant (pid 123) stalled 112 ms (monotonic) at 12:00:01.234 UTC'."""
        who = f'drive {self.name} (pid {os.getpid()})'
        return f'{stall.describe(who)} {self.when(stall.wall_ns)}'

    def _window_key(self) -> tuple[float, ...]:
        v = self.m.values()
        return tuple(v[s.name] for s in HoldWindow.specs())

    def _refresh_window(self) -> None:
        """Parameters of the window set at run time take effect (a pair that contradicts
        itself is refused in the log, the window kept)."""
        key = self._window_key()
        if key == self._window_values:
            return
        self._window_values = key
        try:
            self.m.table.window = HoldWindow.from_node_values(self.m.values())
        except ValueError as exc:
            self.m.log.error(f'hold window kept as it was: {exc}')

    def stamp_now(self) -> int:
        return time.time_ns()

    def status_values(self) -> dict[str, object]:
        table = self.m.table
        values: dict[str, object] = {'overruns': self.overruns, 'active_ticks': self.active_ticks}
        longest = self._stalls.longest
        values['pid'] = os.getpid()
        values['stalls'] = self._stalls.count
        values['longest_stall_ms'] = 1e-6 * longest.length_ns if longest else 0.0
        values['longest_stall'] = self.stalled(longest) if longest else ''
        values['stall_report_ms'] = 1e-6 * self._stalls.threshold_ns
        stopped = table.stop_reasons()
        for axis in self.m.axes:
            values[f'{axis}.stops'] = self.stops[axis]
            values[f'{axis}.stopped'] = stopped.get(axis, '')
            values[f'{axis}.late_fraction'] = table.late_fraction(axis)
            values[f'{axis}.longest_late_run'] = table.longest_late_run(axis)
            values[f'{axis}.longest_wait_ms'] = 1e3 * table.longest_wait(axis)
            for key, v in table.latency_stats(axis).items():
                values[f'{axis}.latency_{key}_ms'] = 1e3 * v
        return values


CYCLES: dict[str, type[DriveCycle]] = {'lockstep': LockstepCycle, 'realtime': RealtimeCycle}
