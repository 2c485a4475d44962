"""The three-axis motion job: plant, trajectory, and an observer and a controller per axis.

Lockstep, sample k at t_k = k T: the plant publishes the measured positions y(k); each
observer corrects with y(k) and publishes its estimate; each controller joins state,
estimate and reference of t_k and publishes its command u(k); the plant integrates to k + 1
and each observer predicts with u(k). `AxisSimulation` (mill_bringup.axis_simulation)
makes exactly these calls in this order in one process, so the distributed record equals
the offline one bit for bit.

With a force controller (the adaptive feed of Rubio 2013 on the Kline job) the plant also
publishes the cutting force of sample k with its measured positions; at each control instant
(the first sample at or after each spindle revolution) the force controller turns the peak
force of the revolution, and the tool's depth from the measured z, into a feed override
stamped at that sample; the trajectory (`feed_override.lockstep`, `feed_override.period` = one
revolution) answers with the reference of the samples up to the next control instant, and
the controllers go on. The job ends when its path ends, whatever the override: the trajectory
finds the last sample and gives its time as end_time in its "done" status on /diagnostics,
which the runner waits for; the simulation finds the same sample.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from mill_analysis.metrics import (
    FORCE_CONTROL,
    RunRecord,
    summarize,
    summarize_contour,
    summary_text,
)
from mill_analysis.record_checks import subset
from mill_analysis.run_record import record_from_raw
from mill_bag.types import decode
from mill_common.signals import AXES, axis_index
from mill_common.timebase import job_steps, period_ns, seconds
from mill_controllers.force_control import ForceFeedLoop
from mill_trajectory.base import Trajectory
from mill_trajectory.config import build_job
from mill_trajectory.feed_override import JobEnd

from mill_analysis import records
from mill_bringup.axis_simulation import AxisSimulation, axis_delays, build_axis_loops, timing_of
from mill_bringup.catalogue import CONTROLLER, FORCE_CONTROLLER, PLANT, TRAJECTORY
from mill_bringup.jobs.base import RECORDER_WINDOW, Job, MessageSource
from mill_bringup.layout import processes
from mill_bringup.recorded_steps import RecordedSteps
from mill_bringup.scenario import LAYOUTS, Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer
from mill_bringup.tuning.prediction_file import against_prediction
from mill_common import topics

JOINT_STATE = 'sensor_msgs/msg/JointState'
# A stamp beyond this is a wall-clock time (2001 on), not a simulation's sim time [ns].
WALL_CLOCK_NS = 10**18
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'


def check_following_band(scen: Scenario, path: Trajectory, tv: Mapping[str, Any]) -> None:
    """ScenarioError if an axis, anywhere within its following-error limit of the path, could
    leave the machine's travel (the trajectory's travel.min / travel.max): a controller trips
    only beyond that limit, so the whole band must fit, as before an identify run."""
    band = [0.0, 0.0, 0.0]
    for node in scen.nodes_of(CONTROLLER):
        values = scen.parameters(node.name)
        band[axis_index(values['axis'])] = float(values['following_error_limit'])
    lo, hi = path.bounds(tv['sample_period'])
    for i, axis in enumerate(AXES):
        b = band[i] if math.isfinite(band[i]) else 0.0
        for edge, sign, end, side in (
            (lo[i], -1.0, tv['travel.min'][i], 'min'),
            (hi[i], 1.0, tv['travel.max'][i], 'max'),
        ):
            if sign * (edge + sign * b - end) > 0.0:
                raise ScenarioError(
                    f'scenario {scen.name}: axis {axis} may leave the machine travel before '
                    f'its controller trips: its path reaches {edge:.6g} m and its '
                    f'following-error limit is {1e3 * b:g} mm, beyond travel.{side} {end:g} m; '
                    'move the axis or lower the limit'
                )


class AxisJob(Job[RunRecord]):
    KIND = 'axis'
    RECORD = records.AXIS
    CLOCK = PLANT
    SETTLE_TIMEOUT = 1.0  # the ground truth and force of the final step

    @classmethod
    def runs(cls, scen: Scenario) -> bool:
        plants = scen.nodes_of(cls.CLOCK)
        return bool(plants) and timing_of(scen, plants[0].name) == 'lockstep'

    def __init__(self, scen: Scenario) -> None:
        super().__init__(scen)
        for node in scen.nodes:
            scen.parameters(node.name)  # every node's parameters are valid
        plants, trajectories = scen.nodes_of(PLANT), scen.nodes_of(TRAJECTORY)
        if len(plants) != 1 or len(trajectories) != 1:
            raise ScenarioError(
                f'scenario {scen.name}: an axis job has one plant and one trajectory'
            )
        self.plant, self.trajectory = plants[0].name, trajectories[0].name
        build_axis_loops(scen)  # the axes' cores fit together
        pv = scen.parameters(self.plant)
        tv = scen.parameters(self.trajectory)
        self.dt_ns = period_ns(pv['sample_period'])
        job = build_job(tv)
        self.end_time = job.end_time
        # A G-code program's planned feed, for the summary ('' for other paths).
        self.feed_summary = getattr(job.trajectory, 'feed_summary', '')
        check_following_band(scen, job.trajectory, tv)
        self._samples = job_steps(self.end_time, self.dt_ns)
        self.axes = list(pv['axes'])
        # Who publishes the states: the plant, or the driver the controllers are told of.
        controllers = [n for n in scen.nodes if n.kind.per_axis]
        self.state_owner = (
            scen.parameters(controllers[0].name)['plant_node'] if controllers else self.plant
        )
        forces = [n.name for n in scen.nodes_of(FORCE_CONTROLLER)]
        if len(forces) > 1:
            raise ScenarioError(f'scenario {scen.name}: more than one force controller')
        self.force_controller = forces[0] if forces else ''
        # With a feed override the job ends when its path ends: a length the run finds.
        self.override = bool(tv['feed_override.enabled'])
        self.lockstep = self.override and bool(tv['feed_override.lockstep'])
        self.end = JobEnd.of(
            build_job({**tv, 'settle_time': 0.0, 'duration': 0.0}).end_time,
            tv['settle_time'],
            tv['duration'],
            self.dt_ns,
        )
        self._bound = self._samples
        self._found: int | None = None  # the samples of a run whose end was found
        if self.override:
            self._check_override(tv)

    def _check_override(self, tv: dict[str, Any]) -> None:
        name = self.scenario.name
        if self.lockstep and not tv['feed_override.period'] > 0:
            raise ScenarioError(
                f'scenario {name}: an axis job in lockstep with its feed override needs the '
                "trajectory's feed_override.period (the override sender's control period)"
            )
        if self.lockstep and not self.force_controller:
            raise ScenarioError(
                f'scenario {name}: the trajectory waits for a lockstep feed override, but no '
                'force controller sends one'
            )
        if self.lockstep and any(axis_delays(self.scenario).values()):
            raise ScenarioError(
                f'scenario {name}: controllers with a command_delay aim at references beyond '
                'those a lockstep feed override has set; use command_delay 0'
            )
        lo = tv['feed_override.min']
        if lo <= 0 and not tv['duration'] > 0:
            raise ScenarioError(
                f'scenario {name}: with feed_override.min = 0 the path may never end; set '
                "feed_override.min > 0 or the trajectory's duration"
            )
        # The bound of the offline loop: the whole path at the lowest override, or duration.
        slowest = self.end.path_end / lo / seconds(self.dt_ns) if lo > 0 else math.inf
        bound = min(slowest + 2 + self.end.settle_samples, (self.end.cap or math.inf) + 1)
        self._bound = int(bound)
        if not self.force_controller:
            return
        cv = self.scenario.parameters(self.force_controller)
        loop = ForceFeedLoop.from_parameters(cv)
        if self.lockstep and abs(tv['feed_override.period'] - loop.T) > 1e-12 * loop.T:
            raise ScenarioError(
                f"scenario {name}: the trajectory's feed_override.period "
                f"{tv['feed_override.period']!r} s is not the force controller's control "
                f'period, one spindle revolution 60/S_s = {loop.T!r} s'
            )
        ranges = (tv['feed_override.min'], tv['feed_override.max'])
        if ranges != (cv['override.min'], cv['override.max']):
            raise ScenarioError(
                f"scenario {name}: the trajectory's feed_override range [{ranges[0]:g}, "
                f"{ranges[1]:g}] differs from the force controller's override range "
                f'[{cv["override.min"]:g}, {cv["override.max"]:g}]'
            )

    def end_at(self, last_sample: int) -> None:
        """The run found the job's last sample (a job with a feed override)."""
        self._found = last_sample + 1

    @property
    def samples(self) -> int:
        """The job's samples; with a feed override, at override 1 until a run found them."""
        return self._found if self._found is not None else self._samples

    @property
    def max_samples(self) -> int:
        return self._bound

    @property
    def sim_time(self) -> float:
        return seconds((self.samples - 1) * self.dt_ns)

    # -- the distributed run ---------------------------------------------------------------
    def prepare_graph(
        self, monitored: bool, layout: str = LAYOUTS[0], recorded: bool = False
    ) -> None:
        # The monitor listens to every state topic too: the plant waits for it (controller,
        # observer, monitor), so that the first samples reach the record. A controller that
        # shares its observer's process takes the states from it (a servo cycle).
        if monitored:
            readers = 2 if self._servo_cycles(layout) else 3
            self.scenario.overrides.setdefault(self.plant, {}).setdefault(
                'min_subscribers', readers
            )
            # An axis node answers only once the monitor hears it too (at the start, and when
            # --respawn starts it again mid-job): the estimate goes to the controller and the
            # monitor, the command to the plant, the observer and the monitor. A command sent
            # before the monitor matched its sender is lost to the record and the bag.
            for node in self.scenario.nodes:
                if node.kind.per_axis:
                    wanted = self.scenario.overrides.setdefault(node.name, {})
                    wanted.setdefault('min_subscribers', 3 if node.kind.role == CONTROLLER else 2)
        # The plant waits for the runner's acknowledgement of the steps it heard (of those
        # its bag holds, when it records): neither the record nor a bag misses a step. Without
        # it a runner short of CPU lost 7-41 states of an unrecorded run (eight processes and
        # six busy loops on two cores).
        if monitored:
            wanted = self.scenario.overrides.setdefault(self.plant, {})
            wanted.setdefault('recorder_window', RECORDER_WINDOW)

    def recorded_steps(self) -> RecordedSteps | None:
        window = self.scenario.parameters(self.plant)['recorder_window']
        if not window:
            return None
        # A step is whole with its states, estimates, commands and cutting force, and the
        # ground truth of the step before if the plant publishes it.
        stepped = {topics.state(a): 0 for a in self.axes}
        for axis in self.axes:
            stepped[topics.estimate(axis)] = 0
            stepped[topics.joint_command(axis)] = 0
        stepped[topics.CUTTING_FORCE] = 0
        if self.scenario.parameters(self.plant)['publish_ground_truth']:
            stepped[topics.GROUND_TRUTH] = 1
        return RecordedSteps(stepped, seconds(self.dt_ns), window)

    def _servo_cycles(self, layout: str) -> bool:
        """Whether an axis's observer and controller share a process in this layout."""
        for process in processes(self.scenario, layout):
            roles = [
                (self.scenario.parameters(n.name)['axis'], n.kind.role)
                for n in process.nodes
                if n.kind.per_axis
            ]
            axes = {axis for axis, role in roles if role == CONTROLLER}
            if any(axis in axes for axis, role in roles if role != CONTROLLER):
                return True
        return False

    def upstream_topics(self) -> list[str]:
        # The monitor cannot see from the plant whether an observer's estimates or a
        # controller's commands reach it: the plant starts once it has matched their publishers.
        out = [topics.estimate(a) for a in self.axes] + [topics.REFERENCE]
        out += [topics.joint_command(a) for a in self.axes]
        return out + ([topics.FEED_OVERRIDE] if self.force_controller else [])

    def monitor_topics(self) -> dict[str, str]:
        out = {}
        for axis in self.axes:
            out[topics.state(axis)] = JOINT_STATE
            out[topics.estimate(axis)] = JOINT_STATE
            out[topics.joint_command(axis)] = JOINT_STATE
        out[topics.REFERENCE] = JOINT_TRAJECTORY
        out[topics.GROUND_TRUTH] = JOINT_STATE
        if self.force_controller:
            out[topics.FORCE_CONTROL_STATE] = JOINT_STATE
        return out

    def recorded_topics(self) -> dict[str, str]:
        # Only when recorded: the plant publishes the force to a listener only (it costs).
        return {topics.CUTTING_FORCE: WRENCH_STAMPED}

    def sim_time_stamps(self) -> bool:
        return bool(self.scenario.raw_parameters(self.trajectory).get('use_sim_time', False))

    def progress(self, source: MessageSource) -> float:
        ns = source.latest_stamp_ns(topics.state(self.axes[0]))
        return seconds(ns) if ns >= 0 else -math.inf

    def check(self, source: MessageSource) -> None:
        ns = source.latest_stamp_ns(topics.state(self.axes[0]))
        if ns > WALL_CLOCK_NS:
            raise ScenarioError(
                f'{self.state_owner} stamps its states with the system clock (a realtime '
                f'driver, {seconds(ns):.0f} s) but the job runs in lockstep: run it with '
                '--timing realtime'
            )

    def complete(self, source: MessageSource) -> bool:
        if self.override and self._found is None:
            # The trajectory says where the job ends, once its path has ended.
            status = source.status(topics.status_name(self.trajectory, topics.JOB_STATUS))
            if status is None or status.get('state') != 'done':
                return False
            self._found = job_steps(float(status['end_time']), self.dt_ns)
        last_ns = (self.samples - 1) * self.dt_ns
        needed = [topics.state(a) for a in self.axes] + [topics.estimate(a) for a in self.axes]
        return all(source.latest_stamp_ns(t) >= last_ns for t in needed)

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[RunRecord, dict[str, int]]:
        aside = topics.FORCE_CONTROL_STATE
        types = {**self.monitor_topics(), **self.recorded_topics()}
        kept = subset(raw, [t for t in types if t != aside])  # every one the monitor kept
        rec, missing = record_from_raw(
            kept, types, self.axes, self.samples, self.dt_ns, owners=self.owners()
        )
        if self.force_controller:
            rows = force_control_rows(raw.get(aside, ()))
            rec.force_control = rows[rows[:, 0] <= rec.t[-1]]
        return rec, {t: m for t, m in missing.items() if m}

    def owners(self) -> dict[str, str]:
        """The node each per-axis topic must come from (header.frame_id)."""
        out = {}
        for node in self.scenario.nodes:
            if not node.kind.per_axis:
                continue
            axis = self.scenario.parameters(node.name)['axis']
            topic = topics.joint_command(axis) if node.kind.role == CONTROLLER else None
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
        text = '\n'.join(
            [
                summary_text(rec, skip),
                *([self.feed_summary] if self.feed_summary else []),
                *against_prediction(self.scenario, summarize(rec, skip), float(rec.t[-1])),
                *rec.events,
            ]
        )
        if rec.force_control is None or not len(rec.force_control):
            return text
        lines = [
            'force control, per constant depth of cut told (second half of each stretch, '
            'where the force has settled):',
            f'{"depth [mm]":>10} {"from [s]":>9} {"to [s]":>8} {"instants":>9} '
            f'{"force [N]":>10} {"reference [N]":>14} {"override":>9}',
        ]
        for s in depth_stretches(rec.force_control):
            lines.append(
                f'{s.depth:10.3f} {s.start:9.3f} {s.end:8.3f} {s.instants:9d} '
                f'{s.force:10.1f} {s.reference:14.1f} {s.override:9.4f}'
            )
        return text + '\n' + '\n'.join(lines)

    def summary_json(self, rec: RunRecord, skip: float) -> dict[str, Any]:
        out: dict[str, Any] = {
            'metrics': [vars(m) for m in summarize(rec, skip)],
            'contour_error': vars(c) if (c := summarize_contour(rec, skip)) else None,
            'events': rec.events,
        }
        if rec.force_control is not None:
            out['force_control'] = [vars(s) for s in depth_stretches(rec.force_control)]
            out['job_end_time'] = float(rec.t[-1])
        return out

    def foreign(self, rec: RunRecord) -> dict[str, int]:
        return dict(rec.foreign)

    def dropped(self, rec: RunRecord) -> dict[str, list[tuple[int, str]]]:
        return rec.drops.reasons()

    def gaps(self, rec: RunRecord) -> dict[str, list[tuple[int, int]]]:
        return dict(rec.gaps)

    def differences(self, rec: RunRecord, other: RunRecord) -> dict[str, float]:
        out = {'tracking_error': max_difference(rec.tracking_error, other.tracking_error)}
        if not np.isnan(rec['force']).all():  # recorded (--record): the plant's force too
            out['cutting_force'] = max_difference(rec['force'], other['force'])
        if rec.force_control is not None and other.force_control is not None:
            a, b = rec.force_control, other.force_control
            for i, name in enumerate(FORCE_CONTROL[1:], 1):
                out[f'force_control.{name}'] = (
                    max_difference(a[:, i], b[:, i]) if (a.shape == b.shape) else math.inf
                )
        return out


def max_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| over all entries; 0 where both are NaN, inf where only one is."""
    if a.shape != b.shape:
        return math.inf
    diff = np.abs(a - b)
    diff[np.isnan(a) & np.isnan(b)] = 0.0
    diff[np.isnan(diff)] = np.inf
    return float(diff.max()) if diff.size else 0.0


@dataclass(frozen=True)
class DepthStretch:
    """Control instants at one depth of cut, averaged over the second half of the stretch."""

    depth: float  # [mm]
    start: float  # first instant at this depth [s]
    end: float  # last instant [s]
    instants: int
    force: float  # mean force the law used [N]
    reference: float  # mean reference [N]
    override: float  # mean override [-]


def depth_stretches(rows: np.ndarray, min_instants: int = 10) -> list[DepthStretch]:
    """Stretches of at least min_instants control instants told the same depth (to 1 µm)."""
    col = {name: i for i, name in enumerate(FORCE_CONTROL)}
    depth = np.round(rows[:, col['depth']], 3)
    out = []
    edges = [0, *(np.flatnonzero(np.diff(depth)) + 1).tolist(), len(depth)]
    for a, b in itertools.pairwise(edges):
        if b - a < min_instants:
            continue
        half = rows[a + (b - a) // 2 : b]
        out.append(
            DepthStretch(
                float(depth[a]),
                float(rows[a, 0]),
                float(rows[b - 1, 0]),
                b - a,
                float(np.mean(half[:, col['force']])),
                float(np.mean(half[:, col['reference']])),
                float(np.mean(half[:, col['override']])),
            )
        )
    return out


def force_control_rows(messages: Sequence[bytes]) -> np.ndarray:
    """/mill/force_control/state messages -> rows (t, force, ..., depth), one per instant."""
    rows: dict[int, list[float]] = {}
    for data in messages:
        msg = decode(JOINT_STATE, data)
        ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        rows[ns] = [seconds(ns), *list(msg.position)[: len(FORCE_CONTROL) - 1]]
    out = np.array([rows[ns] for ns in sorted(rows)], dtype=float)
    return out.reshape(-1, len(FORCE_CONTROL))
