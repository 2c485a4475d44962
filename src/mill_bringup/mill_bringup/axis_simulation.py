"""The offline twin of the three-axis job: the same ROS-free steps, in one process.

`AxisSimulation` steps the plant, each axis's observer loop and control loop and the
trajectory's schedule (and, with a force controller, the adaptive feed: `AdaptiveFeed`) in
the order the messages of a lockstep run make them, so the distributed record equals the
offline one bit for bit (mill_bringup.jobs.axis, the job, runs both).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from mill_analysis.events import STOPPED, TRIP, Event, trip_detail
from mill_analysis.record import FORCE_CONTROL, RunRecord
from mill_common.hold_window import HoldWindow
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AXES, axis_index
from mill_common.timebase import seconds
from mill_common.travel import MachineTravel
from mill_controllers.config import build_loop
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.force_control import ForceFeedLoop, ForceSampler, tool_depth
from mill_observers.config import build_observer_loop
from mill_observers.observer_loop import ObserverLoop
from mill_plant.command_delay import CommandDelay
from mill_plant.command_table import CommandTable
from mill_plant.motion_guard import MotionGuard
from mill_plant.protection import Protection
from mill_plant.simulated_machine import SimulatedMachine
from mill_plant.spindle import SpindleTrack
from mill_trajectory.config import build_schedule
from mill_trajectory.feed_override import FeedOverride
from mill_trajectory.schedule import ClockedReference, OverrideReference, Points

from mill_bringup.catalogue import CONTROLLER
from mill_bringup.job_config import JobConfig
from mill_bringup.scenario import Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer, NoTimer


class SimulatedJob(Protocol):
    """What the simulation reads of its job (mill_bringup.jobs.axis.AxisJob)."""

    scenario: Scenario
    config: JobConfig
    plant: str
    trajectory: str
    force_controller: str  # '' without one
    dt_ns: int
    pauses: tuple[Any, ...]  # the program's M0/M1 (mill_trajectory.hold.ProgramEvent)

    @property
    def samples(self) -> int: ...
    @property
    def max_samples(self) -> int: ...
    def end_at(self, last_sample: int) -> None: ...
    def unattended_pause(self) -> str | None: ...


def build_axis_loops(
    config: JobConfig,
) -> tuple[dict[int, AxisControlLoop], dict[int, ObserverLoop]]:
    """The controller's and the observer's per-sample step of each axis, by axis index,
    built from the job's configuration as their nodes build them (that they fit together,
    and that every active axis has both, is the configuration's: mill_bringup.job_config)."""
    controllers: dict[int, AxisControlLoop] = {}
    observers: dict[int, ObserverLoop] = {}
    for node in config.nodes:
        if not node.kind.per_axis:
            continue  # a force controller, say: not an axis core
        values = dict(node.values)
        i = axis_index(values['axis'])
        if node.role == CONTROLLER:
            controllers[i] = build_loop(values)
        else:
            observers[i] = build_observer_loop(values)
    return controllers, observers


class AdaptiveFeed:
    """The force controller of an axis job and the trajectory's answer to its override."""

    def __init__(self, job: SimulatedJob, schedule: OverrideReference) -> None:
        cv = job.config.values(job.force_controller)
        self.loop = ForceFeedLoop.from_parameters(cv)
        self.sampler = ForceSampler(self.loop.T, cv['force_component'], cv['force_measure'])
        self.reference = cv['reference_force']
        self.top = cv['workpiece_top'] if cv['depth_source'] == 'position' else None
        self.schedule = schedule
        self.rows: list[tuple[float, ...]] = []

    def offer(self, ns: int, force: tuple[float, float, float], z: float) -> Points | None:
        """At a control instant, the override and the reference points it sets."""
        hit = self.sampler.offer(ns, force)
        if hit is None:
            return None
        j, measured = hit
        depth = None
        if self.top is not None:
            depth = tool_depth(self.top, z) if math.isfinite(z) else 0.0
        cmd = self.loop.step(j * self.loop.T, self.reference, measured, depth)
        self.rows.append(
            (
                seconds(ns),
                cmd.force,
                self.reference,
                cmd.feed_command,
                cmd.override,
                cmd.beta,
                cmd.depth,
            )
        )
        return self.schedule.answer(ns, cmd.override, cmd.slope)

    @property
    def last_sample(self) -> int | None:
        return self.schedule.scaled.last_sample


class AxisSimulation:
    """Sample by sample, the steps the graph makes (plant -> observer -> controller -> plant):
    the same ROS-free objects the nodes step, fed as the messages feed them."""

    def __init__(self, job: SimulatedJob, times: CoreTimer | None) -> None:
        scen, config = job.scenario, job.config
        pv = config.values(job.plant)
        # The machine behind the plant node's front end: the same backend, the same calls.
        self.machine = SimulatedMachine(pv)
        self.active = [AXES.index(a) for a in self.machine.axes]
        self.dt_ns = job.dt_ns
        self.dt = seconds(job.dt_ns)
        controllers, observers = build_axis_loops(config)
        self.controllers = {i: controllers[i] for i in self.active}
        self.observers = {i: observers[i] for i in self.active}
        self.acted: dict[int, float | None] = dict.fromkeys(self.active)
        # The reference points each controller holds, from the trajectory's schedule.
        tv = config.values(job.trajectory)
        override = FeedOverride(tv['feed_override.min'], tv['feed_override.max'])
        self.schedule, _ = build_schedule(tv, override)
        self.clock_every = max(1, round(pv['clock_period'] * 1e9 / self.dt_ns))
        self.buffers = {i: ReferenceBuffer() for i in self.active}
        self.delay = CommandDelay(pv['command_delay'], len(self.active))
        # The drive's protection of the axes, as the lockstep plant node steps it: the same
        # command table, motion guard and latched stop (mill_plant.protection).
        axes = list(self.machine.axes)
        self.table = CommandTable(axes, HoldWindow.from_node_values(pv), self.dt_ns)
        travel = MachineTravel.from_node_values(pv).limits(''.join(axes))
        guard = MotionGuard(axes, pv['speed_limit'], pv['hold_deviation'], travel)
        self.protection = Protection(self.table, guard)
        self.stops: list[Event] = []  # as the plant's status tells them
        # spindle: reference: the speeds the plant node reads off the reference.
        self.spindle = SpindleTrack() if pv['spindle'] == 'reference' else None
        self.job = job
        unattended = job.unattended_pause()
        if unattended is not None:
            raise ScenarioError(f'scenario {scen.name}: offline: {unattended}')
        self.feed: AdaptiveFeed | None = None
        if job.force_controller:
            if not isinstance(self.schedule, OverrideReference):
                raise ScenarioError(
                    f'scenario {scen.name}: the feed override reaches the trajectory '
                    "asynchronously, so the job has no offline twin (set the trajectory's "
                    'feed_override.lockstep and feed_override.period)'
                )
            self.feed = AdaptiveFeed(job, self.schedule)
        self.rec = RunRecord.empty(min(job.samples, job.max_samples), self.dt)
        self.k = -1
        self.clock = times or NoTimer()

    def _reference_points(
        self, k: int, ns: int, force: tuple[float, float, float], measured: list[float]
    ) -> None:
        """The points the trajectory sends at this sample, into each controller's buffer."""
        points: Points | None = None
        if self.feed is not None:
            z = measured[self.active.index(2)] if 2 in self.active else math.nan
            points = self.feed.offer(ns, force, z)
        elif isinstance(self.schedule, ClockedReference) and k % self.clock_every == 0:
            points = self.schedule.answer(ns)  # the plant's /clock tick
        if points is None:
            return
        speeds = [s.spindle for s in points.samples]
        if self.spindle is not None and None not in speeds:
            self.spindle.offer(points.stamps(), speeds)  # type: ignore[arg-type]
        for at, sample in zip(points.stamps(), points.samples, strict=True):
            for i in self.active:
                self.buffers[i].add(at, sample.axis(i))

    def step(self, k: int) -> None:
        if k >= len(self.rec.t):
            self.rec = self.rec.grown(2 * len(self.rec.t), self.dt)
        s = self.rec.signals
        ns = k * self.dt_ns
        clock, machine = self.clock, self.machine
        clock.start()
        measured = machine.read()
        force = machine.cutting_force()  # of this sample's state, sent with the states
        self._reference_points(k, ns, force, measured)
        clock.lap('trajectory')
        efforts = []
        for i, y in zip(self.active, measured, strict=True):
            clock.start()
            observer = self.observers[i]
            est = observer.step(y, self.acted[i])
            model = observer.model_estimate()
            clock.lap('observer')
            loop = self.controllers[i]
            u = loop.step(ns, y, est, self.buffers[i], model).effort
            clock.lap('controller')
            self.acted[i] = u
            efforts.append(u)
            ref = self.buffers[i].at(ns)
            assert ref is not None, 'the controller stepped on it'
            s['position'][k, i] = y
            s['reference'][k, i] = ref.position
            s['reference_velocity'][k, i] = ref.velocity
            s['estimate_velocity'][k, i] = est.velocity
            s['estimate_disturbance'][k, i] = est.disturbance
            s['torque'][k, i] = u
            self.buffers[i].forget_before(ns)
        for axis, u in zip(self.table.axes, efforts, strict=True):
            # What the plant node's intake offers: a non-finite effort is a brake request.
            self.table.offer(axis, ns, u if math.isfinite(u) else math.nan)
        protected = self.protection.lockstep_step(ns, measured, self.delay)
        for axis, reason in protected.stopped.items():
            self.stops.append(Event(axis, STOPPED, seconds(ns), reason))
        machine.write(protected.efforts)
        if self.spindle is not None:  # as the plant node's write: the step k -> k + 1
            machine.spindle(self.spindle.at(ns))
            self.spindle.forget_before(ns)
        _, s['true_velocity'][k], s['true_disturbance'][k] = machine.truth()
        s['force'][k] = force
        clock.start()
        machine.advance(self.dt)
        clock.lap('plant')
        self.k = k

    def finished(self) -> bool:
        last = None if self.feed is None else self.feed.last_sample
        schedule = self.schedule
        if self.job.pauses and isinstance(schedule, ClockedReference) and schedule.scaled:
            last = schedule.scaled.last_sample  # a program that paused ends where its path does
        if last is not None and self.k >= last:
            self.job.end_at(last)
            return True
        return False

    def record(self) -> RunRecord:
        self.rec = self.rec.trimmed(self.k + 1)
        if self.feed is not None:
            rows = np.array(self.feed.rows, dtype=float)
            self.rec.force_control = rows.reshape(-1, len(FORCE_CONTROL))
        # Each controller's trip, as its status on /diagnostics tells it (mill_analysis.events)
        self.rec.events = [
            Event(AXES[i], TRIP, trip.time, trip_detail(trip.error, trip.limit, trip.cause))
            for i, loop in sorted(self.controllers.items())
            if (trip := loop.trip.trip) is not None
        ] + self.stops
        return self.rec
