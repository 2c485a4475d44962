"""The three-axis motion job: plant, trajectory, and an observer and a controller per axis.

Lockstep, sample k at t_k = k T: the plant publishes the measured positions y(k); each
observer corrects with y(k) and publishes its estimate; each controller joins state,
estimate and reference of t_k and publishes its command u(k); the plant integrates to k + 1
and each observer predicts with u(k). `AxisSimulation` makes exactly these calls in this
order in one process, so the distributed record equals the offline one bit for bit.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from mill_common.signals import AXES, ControlInputs, axis_index
from mill_common.timebase import job_steps, period_ns, seconds
from mill_controllers.base import AxisController
from mill_controllers.config import build_controller
from mill_controllers.trip import FollowingErrorTrip
from mill_observers.base import Observer
from mill_observers.config import build_observer
from mill_observers.delay import DelayCompensation
from mill_plant.simulated_machine import SimulatedMachine
from mill_trajectory.config import build_job

from mill_bringup.jobs.base import Job, MessageSource
from mill_bringup.metrics import RunRecord, format_summary, summarize
from mill_bringup.run_record import record_from_raw
from mill_bringup.scenario import Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer, NoTimer
from mill_common import topics

JOINT_STATE = 'sensor_msgs/msg/JointState'
AXIS_NODES = {('mill_controllers', 'axis_controller'), ('mill_observers', 'observer_node')}
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'


def timing_of(scen: Scenario, node: str) -> str:
    """A node's `timing` parameter (lockstep for nodes that have none)."""
    return str(scen.parameters(node).get('timing', 'lockstep'))


def axis_delays(scen: Scenario) -> dict[int, int]:
    """command_delay of each axis's controller and observer, which must agree."""
    delays: dict[int, int] = {}
    for node in scen.nodes:
        if (node.package, node.executable) not in AXIS_NODES:
            continue
        values = scen.parameters(node.name)
        i = axis_index(values['axis'])
        if delays.setdefault(i, values['command_delay']) != values['command_delay']:
            raise ScenarioError(
                f'scenario {scen.name}: the {AXES[i]} controller and observer disagree on '
                'command_delay'
            )
    return delays


def following_error_trips(scen: Scenario) -> dict[int, FollowingErrorTrip]:
    """The following-error trip of each axis controller, by axis index."""
    trips = {}
    for node in scen.nodes:
        if (node.package, node.executable) == ('mill_controllers', 'axis_controller'):
            values = scen.parameters(node.name)
            trips[axis_index(values['axis'])] = FollowingErrorTrip(values['following_error_limit'])
    return trips


def build_axis_cores(scen: Scenario) -> tuple[dict[int, AxisController], dict[int, Observer]]:
    """Controller and observer cores by axis index, checked to fit together.

    ScenarioError if an active axis lacks one, or if a controller designs with the
    observer's model estimate and the observer of its axis estimates none.
    """
    pv = scen.parameters(scen.nodes_of('mill_plant')[0].name)
    controllers: dict[int, AxisController] = {}
    observers: dict[int, Observer] = {}
    names: dict[int, str] = {}
    for node in scen.nodes_of('mill_controllers'):
        if node.executable != 'axis_controller':
            continue  # a force controller, say: not an axis core
        values = scen.parameters(node.name)
        controllers[axis_index(values['axis'])] = build_controller(values)
    for node in scen.nodes_of('mill_observers'):
        if node.executable != 'observer_node':
            continue
        values = scen.parameters(node.name)
        i = axis_index(values['axis'])
        observers[i] = build_observer(values)
        names[i] = f'{node.name} (observer {values["observer"]})'
    active = [i for i, a in enumerate(AXES) if a in pv['axes']]
    missing = [AXES[i] for i in active if i not in controllers or i not in observers]
    if missing:
        raise ScenarioError(
            f'scenario {scen.name}: axes {missing} lack a controller or an observer'
        )
    for i in active:
        if controllers[i].needs_model and not observers[i].PROVIDES_MODEL:
            raise ScenarioError(
                f"scenario {scen.name}: the {AXES[i]} controller designs with the observer's "
                f'model estimate, but {names[i]} estimates none (use observer rls)'
            )
    return controllers, observers


class AxisSimulation:
    """Sample by sample, the calls the graph makes (plant -> observer -> controller -> plant)."""

    def __init__(self, job: AxisJob, times: CoreTimer | None) -> None:
        scen = job.scenario
        pv = scen.parameters(job.plant)
        # The machine behind the plant node's front end: the same backend, the same calls.
        self.machine = SimulatedMachine(pv)
        self.path = build_job(scen.parameters(job.trajectory)).trajectory
        controllers, observers = build_axis_cores(scen)
        self.active = [AXES.index(a) for a in self.machine.axes]
        self.dt_ns = job.dt_ns
        self.dt = seconds(job.dt_ns)
        delays = axis_delays(scen)
        self.controllers = controllers
        self.lead = {i: delays[i] for i in self.active}  # the controllers' aim ahead
        self.trips = following_error_trips(scen)
        self.observers = {
            i: DelayCompensation(observers[i], delays[i], self.dt) for i in self.active
        }
        # Commands the plant applies N steps after the step they answer (zero before).
        self.in_flight: deque[list[float]] = deque([[0.0] * len(self.active)] * pv['command_delay'])
        self.rec = RunRecord.empty(job.samples, self.dt)
        self.clock = times or NoTimer()

    def step(self, k: int) -> None:
        s = self.rec.signals
        t = seconds(k * self.dt_ns)
        clock, machine = self.clock, self.machine
        clock.start()
        ref = self.path.sample(t)
        clock.lap('trajectory')
        efforts = []
        for i, y in zip(self.active, machine.read(), strict=True):
            clock.start()
            observer = self.observers[i]
            est = observer.correct(y)
            model = observer.observer.model_estimate()
            clock.lap('observer')
            lead = self.lead[i]
            if lead:  # the command acts N samples on: aim at the state and reference there
                t_c = seconds((k + lead) * self.dt_ns)
                inputs = ControlInputs(t_c, est.position, self.path.sample(t_c).axis(i), est, model)
            else:
                inputs = ControlInputs(t, y, ref.axis(i), est, model)
            u = self.controllers[i].compute(inputs)
            clock.lap('controller')
            u = self.trips[i].command(t, y - ref.position[i], u)
            efforts.append(u)
            s['position'][k, i] = y
            s['reference'][k, i] = ref.position[i]
            s['reference_velocity'][k, i] = ref.velocity[i]
            s['estimate_velocity'][k, i] = est.velocity
            s['estimate_disturbance'][k, i] = est.disturbance
            s['torque'][k, i] = u
        applied = efforts
        if self.in_flight:
            self.in_flight.append(efforts)
            applied = self.in_flight.popleft()
        machine.write(applied)
        _, s['true_velocity'][k], s['true_disturbance'][k] = machine.truth()
        s['force'][k] = machine.cutting_force()
        clock.start()
        machine.advance(self.dt)
        clock.lap('plant')
        for i, u in zip(self.active, efforts, strict=True):
            self.observers[i].command(u)
            clock.lap('observer', call=False)  # the second half of the correct call's sample

    def record(self) -> RunRecord:
        self.rec.events = [
            f'{AXES[i]} axis: following-error trip at t = {trip.trip.time:.4f} s, '
            f'|e| = {1e3 * abs(trip.trip.error):.3f} mm > {1e3 * trip.limit:g} mm: braked'
            for i, trip in sorted(self.trips.items())
            if trip.trip is not None
        ]
        return self.rec


class AxisJob(Job[RunRecord]):
    KIND = 'axis'
    CLOCK = ('mill_plant', 'plant_node')
    SETTLE_TIMEOUT = 1.0  # the ground truth and force of the final step

    @classmethod
    def runs(cls, scen: Scenario) -> bool:
        plants = [n for n in scen.nodes if (n.package, n.executable) == cls.CLOCK]
        return bool(plants) and timing_of(scen, plants[0].name) == 'lockstep'

    def __init__(self, scen: Scenario) -> None:
        super().__init__(scen)
        for node in scen.nodes:
            scen.parameters(node.name)  # every node's parameters are valid
        plants, trajectories = scen.nodes_of('mill_plant'), scen.nodes_of('mill_trajectory')
        if len(plants) != 1 or len(trajectories) != 1:
            raise ScenarioError(
                f'scenario {scen.name}: an axis job has one plant and one trajectory'
            )
        self.plant, self.trajectory = plants[0].name, trajectories[0].name
        build_axis_cores(scen)  # the axes' cores fit together
        pv = scen.parameters(self.plant)
        self.dt_ns = period_ns(pv['sample_period'])
        self.end_time = build_job(scen.parameters(self.trajectory)).end_time
        self._samples = job_steps(self.end_time, self.dt_ns)
        self.axes = list(pv['axes'])
        # Who publishes the states: the plant, or the driver the controllers are told of.
        controllers = [n for n in scen.nodes if (n.package, n.executable) in AXIS_NODES]
        self.state_owner = (
            scen.parameters(controllers[0].name)['plant_node'] if controllers else self.plant
        )

    @property
    def samples(self) -> int:
        return self._samples

    @property
    def sim_time(self) -> float:
        return seconds((self._samples - 1) * self.dt_ns)

    # -- the distributed run ---------------------------------------------------------------
    def prepare_graph(self, monitored: bool) -> None:
        # The monitor listens to every state topic too: the plant waits for it (controller,
        # observer, monitor), so that the first samples reach the record.
        if monitored:
            self.scenario.overrides.setdefault(self.plant, {}).setdefault('min_subscribers', 3)

    def upstream_topics(self) -> list[str]:
        # The monitor cannot see from the plant whether an observer's estimates reach it:
        # the plant starts once the monitor has matched their publishers.
        return [topics.estimate(a) for a in self.axes] + [topics.REFERENCE]

    def monitor_topics(self) -> dict[str, str]:
        out = {}
        for axis in self.axes:
            out[topics.state(axis)] = JOINT_STATE
            out[topics.estimate(axis)] = JOINT_STATE
        out[topics.REFERENCE] = JOINT_TRAJECTORY
        out[topics.GROUND_TRUTH] = JOINT_STATE
        return out

    def recorded_topics(self) -> dict[str, str]:
        out = {topics.joint_command(a): JOINT_STATE for a in self.axes}
        out[topics.CUTTING_FORCE] = WRENCH_STAMPED
        return out

    def sim_time_stamps(self) -> bool:
        return bool(self.scenario.raw_parameters(self.trajectory).get('use_sim_time', False))

    def progress(self, source: MessageSource) -> float:
        ns = source.latest_stamp_ns(topics.state(self.axes[0]))
        return seconds(ns) if ns >= 0 else -math.inf

    def complete(self, source: MessageSource) -> bool:
        last_ns = (self._samples - 1) * self.dt_ns
        needed = [topics.state(a) for a in self.axes] + [topics.estimate(a) for a in self.axes]
        return all(source.latest_stamp_ns(t) >= last_ns for t in needed)

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[RunRecord, dict[str, int]]:
        kept = {t: list(raw[t]) for t in self.monitor_topics() if t in raw}
        types = {**self.monitor_topics(), **self.recorded_topics()}
        rec, missing = record_from_raw(
            kept, types, self.axes, self._samples, self.dt_ns, owners=self.owners()
        )
        return rec, {t: m for t, m in missing.items() if m}

    def owners(self) -> dict[str, str]:
        """The node each per-axis topic must come from (header.frame_id)."""
        out = {}
        for node in self.scenario.nodes:
            key = (node.package, node.executable)
            if key not in AXIS_NODES:
                continue
            axis = self.scenario.parameters(node.name)['axis']
            topic = topics.joint_command(axis) if key[0] == 'mill_controllers' else None
            out[topic or topics.estimate(axis)] = node.name
        for axis in self.axes:
            out[topics.state(axis)] = self.state_owner
        out[topics.REFERENCE] = self.trajectory
        return out

    # -- offline ---------------------------------------------------------------------------
    def simulation(self, times: CoreTimer | None = None) -> AxisSimulation:
        return AxisSimulation(self, times)

    # -- results ---------------------------------------------------------------------------
    def summary(self, rec: RunRecord, skip: float) -> str:
        return '\n'.join([format_summary(summarize(rec, skip), skip), *rec.events])

    def summary_json(self, rec: RunRecord, skip: float) -> dict[str, Any]:
        return {'metrics': [vars(m) for m in summarize(rec, skip)], 'events': rec.events}

    def foreign(self, rec: RunRecord) -> dict[str, int]:
        return dict(rec.foreign)

    def differences(self, rec: RunRecord, other: RunRecord) -> dict[str, float]:
        return {'tracking_error': max_difference(rec.tracking_error, other.tracking_error)}


def max_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| over all entries; 0 where both are NaN, inf where only one is."""
    if a.shape != b.shape:
        return math.inf
    diff = np.abs(a - b)
    diff[np.isnan(a) & np.isnan(b)] = 0.0
    diff[np.isnan(diff)] = np.inf
    return float(diff.max()) if diff.size else 0.0
