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
from dataclasses import replace
from typing import Any

import numpy as np
from mill_analysis.events import Event, Status
from mill_analysis.lockstep_record import record_from_raw
from mill_analysis.node_intake import subset
from mill_analysis.record import FORCE_CONTROL, RunRecord
from mill_analysis.report import kinds
from mill_analysis.summary import AxisSummary, DepthStretch
from mill_bag.types import decode
from mill_common.step_waits import from_status
from mill_common.timebase import job_steps, seconds
from mill_trajectory.config import build_job
from mill_trajectory.feed_override import JobEnd

from mill_bringup.axis_simulation import AxisSimulation
from mill_bringup.bag_handshake import RecordedSteps
from mill_bringup.catalogue import CONTROLLER, PLANT
from mill_bringup.job_config import JobConfig
from mill_bringup.jobs.axis_nodes import JOINT_STATE, WRENCH_STAMPED, AxisNodes, axis_summary
from mill_bringup.jobs.base import RECORDER_WINDOW, Ending, GraphPlan, Job, MessageSource
from mill_bringup.layout import processes
from mill_bringup.scenario import LAYOUTS, Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer
from mill_common import topics

# A stamp beyond this is a wall-clock time (2001 on), not a simulation's sim time [ns].
WALL_CLOCK_NS = 10**18


class AxisJob(Job[RunRecord]):
    KIND = 'axis'
    RECORD = kinds.LOCKSTEP_AXIS
    CLOCK = PLANT
    SETTLE_TIMEOUT = 1.0  # the ground truth and force of the final step
    # A lockstep trip is a result (the offline twin trips alike), not a failure of the run.
    FAILING = ()

    @classmethod
    def runs(cls, config: JobConfig) -> bool:
        return bool(config.of_role(cls.CLOCK)) and config.timing == 'lockstep'

    def __init__(self, scen: Scenario, config: JobConfig | None = None) -> None:
        super().__init__(scen, config)  # every node's parameters valid, the rules kept
        c = self.config
        self.nodes = AxisNodes(scen, c)  # shared with the realtime job
        self.plant, self.trajectory = self.nodes.plant, self.nodes.trajectory
        self.dt_ns, self.axes = self.nodes.dt_ns, self.nodes.axes
        self.state_owner, self.force_controller = (
            self.nodes.state_owner,
            self.nodes.force_controller,
        )
        tv = c.values(self.trajectory)
        self.end_time = c.trajectory_job().end_time
        # A G-code program's planned feed, for the summary ('' for other paths).
        self.feed_summary: str = getattr(c.trajectory_job().trajectory, 'feed_summary', '')
        self._samples = job_steps(self.end_time, self.dt_ns)
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
        # A program that pauses (M0/M1) ends later than planned: a length the run finds too.
        path = c.trajectory_job().trajectory
        self.pauses: tuple[Any, ...] = getattr(path, 'pauses', ())
        self.resume_after: float = getattr(path, 'resume_after', 0.0)
        self.open_end = self.override or bool(self.pauses)
        if self.override:
            self._check_override(tv)
        if self.pauses and self.resume_after > 0:
            # The bound of the offline loop: each pause at rest for resume_after, and more.
            each = math.ceil(self.resume_after / seconds(self.dt_ns)) + 2
            self._bound = max(self._bound, self._samples) + len(self.pauses) * each

    def unattended_pause(self) -> str | None:
        """Why nobody would end this job's first pause (None: it has none, or they end by
        themselves after gcode.resume_after)."""
        if not self.pauses or self.resume_after > 0:
            return None
        first = self.pauses[0]
        return (
            f"{first.where}: {first.text} waits for the trajectory's ~/resume, which nobody "
            'calls in this run: give --resume-after SECONDS (gcode.resume_after), or run the '
            'launch file and resume by hand'
        )

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
        if self.lockstep and any(self.config.delays().values()):
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
        # The override's period and range are the force controller's: job_config's rules
        # override_period and override_range.

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
        # shares its observer's process takes the states from it (a servo cycle), and the
        # plant counts the two as one reader: without a monitor (the launch file) that one
        # is all it gets, and waiting for its default 2 it never started.
        servo = self._servo_cycles(layout)
        if monitored or servo:
            readers = (2 if servo else 3) if monitored else 1
            self.scenario.overrides.setdefault(self.plant, {}).setdefault(
                'min_subscribers', readers
            )
        if monitored:
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

    def graph_plan(self) -> GraphPlan:
        return GraphPlan(
            upstream=tuple(self.upstream_topics()),
            kept=self.monitor_topics(),
            recorded=self.recorded_topics(),
            timed=frozenset(),
            late=frozenset(),
            late_after=(),
            steps=self.bag_handshake(),
            sim_time=self.sim_time_stamps(),
        )

    def bag_handshake(self) -> RecordedSteps | None:
        """The recorder's handshake with the plant, if the graph as prepared has one."""
        return self.nodes.bag_handshake(self.scenario)

    def _servo_cycles(self, layout: str) -> bool:
        """Whether an axis's observer and controller share a process in this layout."""
        for process in processes(self.scenario, layout, config=self.config):
            roles = [
                (self.config.node(n.name).values['axis'], n.kind.role)
                for n in process.nodes
                if n.kind.per_axis
            ]
            axes = {axis for axis, role in roles if role == CONTROLLER}
            if any(axis in axes for axis, role in roles if role != CONTROLLER):
                return True
        return False

    def upstream_topics(self) -> list[str]:
        return self.nodes.upstream_topics()

    def monitor_topics(self) -> dict[str, str]:
        return self.nodes.monitor_topics()

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
        if self.open_end and self._found is None:
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
        return self.nodes.owners()

    def events(self, statuses: Sequence[Status]) -> list[Event]:
        return self.nodes.events(statuses)  # sim time: the job's own

    # -- offline ---------------------------------------------------------------------------
    def simulation(self, times: CoreTimer | None = None) -> AxisSimulation:
        return AxisSimulation(self, times)

    # -- results ---------------------------------------------------------------------------
    def summary(self, rec: RunRecord, skip: float, ending: Ending | None = None) -> AxisSummary:
        stretches = None if rec.force_control is None else depth_stretches(rec.force_control)
        summary = axis_summary(
            self.RECORD, self.scenario, rec, skip, self.FAILING, ending, force_control=stretches
        )
        summary = replace(summary, planned_feed=self.feed_summary)
        source = ending.source if ending is not None else None
        status = None
        if source is not None:  # the plant's steps' waits, as its last status told them
            status = source.status(topics.status_name(self.state_owner, topics.DRIVE_STATUSES[0]))
        over = from_status(status) if status is not None else None
        if status is None or over is None:
            return summary
        longest = float(status.get('max_wait_ms', 'nan'))
        return replace(summary, step_waits=over, longest_wait_ms=longest)


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
