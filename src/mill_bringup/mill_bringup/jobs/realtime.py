"""The three-axis job on the wall clock: the drive keeps its own time (timing realtime).

The same graph as the lockstep axis job (mill_bringup.jobs.axis: both hold its nodes and
topics, jobs.axis_nodes, and neither inherits from the other), with every node's
`timing` realtime and no sim time: the drive ticks every sample period, stamps its states
with the system clock and holds the newest command; the trajectory starts the job once it
hears every axis (first moving there from where the axes stand) and says so on /diagnostics
(`start_stamp_ns`); the job is complete when it reports done. A realtime run depends on the
machine's timing, so it has no offline twin; its summary adds, per axis, the drive's
fraction of periods without a fresh command and the state → command latency.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

from mill_analysis.events import BRAKED, DRIVE_SILENT, STOPPED, TRIP, Event, Status
from mill_analysis.realtime_record import command_timing, realtime_record
from mill_analysis.record import RunRecord
from mill_analysis.report import kinds
from mill_analysis.summary import DRIVE_FIGURES, AxisSummary, DriveFigures
from mill_common.signals import AXES
from mill_common.timebase import job_steps, seconds

from mill_analysis import drive_status as keys
from mill_bringup.bag_handshake import RecordedSteps
from mill_bringup.catalogue import PLANT
from mill_bringup.job_config import JobConfig
from mill_bringup.jobs.axis import WALL_CLOCK_NS
from mill_bringup.jobs.axis_nodes import WRENCH_STAMPED, AxisNodes, axis_summary
from mill_bringup.jobs.base import Ending, GraphPlan, Job, MessageSource
from mill_bringup.scenario import LAYOUTS, Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer
from mill_common import topics

# No state this long after the start: the drive is gone (the runner itself may go without
# the CPU for a second when the graph runs SCHED_FIFO on every core).
DRIVE_SILENCE_NS = 3_000_000_000
# The runner checks every 50 ms; a gap this long between two checks is the runner's own.
RUNNER_STALL_NS = 1_000_000_000


class DriveSilent(ScenarioError):
    """The drive sent no state for too long: the job cannot go on (its event)."""

    def __init__(self, event: Event) -> None:
        super().__init__(event.detail)
        self.event = event


class RealtimeAxisJob(Job[RunRecord]):
    KIND = 'axis-realtime'
    RECORD = kinds.REALTIME_AXIS
    CLOCK = PLANT
    SETTLE_TIMEOUT = 1.0  # the ground truth and force of the final step
    HAS_OFFLINE_TWIN = False
    BRAKE_AT_END = True  # the drive keeps running on its own clock: brake it first
    # On a machine an axis that tripped, or that the drive stopped or braked, did not
    # complete the job.
    FAILING = (TRIP, STOPPED, BRAKED)
    PAPER_NOTE = (
        "note: a realtime run: the paper's experiment is the lockstep run at its own sample "
        "rate; these figures also depend on how this machine kept the wall clock's rate, and "
        'the verdicts below are not a reproduction (run without --timing realtime for that)'
    )

    @classmethod
    def runs(cls, config: JobConfig) -> bool:
        return bool(config.of_role(cls.CLOCK)) and config.timing == 'realtime'

    def __init__(self, scen: Scenario, config: JobConfig | None = None) -> None:
        super().__init__(scen, config)  # every node's parameters valid, the rules kept
        self.nodes = AxisNodes(scen, self.config)  # shared with the lockstep job
        self.plant, self.trajectory = self.nodes.plant, self.nodes.trajectory
        self.dt_ns, self.axes = self.nodes.dt_ns, self.nodes.axes
        self.state_owner = self.nodes.state_owner
        # the path; once started, the approach move before it too (the trajectory says)
        self.end_time = self.config.trajectory_job().end_time
        lockstep = [
            n.name for n in self.config.nodes if n.values.get('timing', 'lockstep') != 'realtime'
        ]
        if lockstep:
            raise ScenarioError(
                f'the plant runs in realtime but {", ".join(lockstep)} in lockstep: '
                'set timing realtime on every node (run_scenario --timing realtime)'
            )
        waited = list(self.config.node(self.trajectory).values.get('axes', AXES))
        if sorted(waited) != sorted(self.axes):
            raise ScenarioError(
                f'the trajectory starts the job once axes {", ".join(waited)} report their '
                f'positions, the plant drives {", ".join(self.axes)}: set '
                f'{self.trajectory}.axes to the same axes'
            )
        # Following the run: the job's start and end as the trajectory reports them, and
        # the drive's silence as `check` counts it.
        self.start_ns: int | None = None
        self._checked_ns = -1  # when `check` last looked (system clock)
        self._quiet_ns: dict[str, int] = {}  # per axis: time awake without a state
        self.clock_ns = time.time_ns  # the system clock the arrivals are taken on

    @property
    def samples(self) -> int:
        return job_steps(self.end_time, self.dt_ns)

    @property
    def sim_time(self) -> float:
        return self.end_time

    # -- the distributed run ---------------------------------------------------------------
    def prepare_graph(
        self, monitored: bool, layout: str = LAYOUTS[0], recorded: bool = False
    ) -> None:
        # No lockstep start: the drive ticks from its activation on (nor does it wait for a
        # recorder: a bag of a realtime run counts what it lost instead). The trajectory starts the
        # job once the monitor hears it too, or the record would miss the job's first periods
        # (its participant may be discovered a second or more after the graph's).
        if monitored:
            readers = len(self.axes) + 1
            self.scenario.overrides.setdefault(self.trajectory, {}).setdefault(
                'min_subscribers', readers
            )

    def graph_plan(self) -> GraphPlan:
        late, after = self.late_topics()
        return GraphPlan(
            upstream=tuple(self.upstream_topics()),
            kept=self.monitor_topics(),
            recorded=self.recorded_topics(),
            timed=frozenset(self.timed_topics()),
            late=frozenset(late),
            late_after=tuple(after),
            steps=self.bag_handshake(),
            sim_time=False,
        )

    def bag_handshake(self) -> RecordedSteps | None:
        return self.nodes.bag_handshake(self.scenario)

    def upstream_topics(self) -> list[str]:
        return self.nodes.upstream_topics()

    def monitor_topics(self) -> dict[str, str]:
        return self.nodes.monitor_topics()

    def recorded_topics(self) -> dict[str, str]:
        return {topics.CUTTING_FORCE: WRENCH_STAMPED}

    def sim_time_stamps(self) -> bool:
        return False

    def started_ns(self) -> int | None:
        return self.start_ns

    def timed_topics(self) -> set[str]:
        # the commands for their latency; the states for the drive's silence (check)
        return {f(a) for a in self.axes for f in (topics.joint_command, topics.state)}

    def summary_topics(self) -> frozenset[str]:
        return frozenset(self.timed_topics())  # the commands' timing (summary)

    def late_topics(self) -> tuple[set[str], list[str]]:
        # The trajectory starts the job once the monitor reads the reference (prepare_graph);
        # the monitor reads it once it hears the drive, which may be on another host and
        # discovered later than the graph: else the record would miss the job's first
        # periods, and a drive never heard would look like one that went silent.
        return {topics.REFERENCE}, [topics.state(axis) for axis in self.axes]

    def _job(self, source: MessageSource) -> dict[str, str] | None:
        status = source.status(topics.status_name(self.trajectory, topics.JOB_STATUS))
        if status is not None and 'start_stamp_ns' in status:
            self.start_ns = int(status['start_stamp_ns'])
            self.end_time = float(status['end_time'])
        return status

    def progress(self, source: MessageSource) -> float:
        status = self._job(source)
        if status is None or 'start_stamp_ns' not in status:
            return -math.inf  # not started: the trajectory holds the axes until all answer
        return float(status['time'])

    def check(self, source: MessageSource) -> None:
        topic = topics.state(self.axes[0])
        ns = source.latest_stamp_ns(topic)
        if 0 <= ns < WALL_CLOCK_NS:
            raise ScenarioError(
                f'{self.state_owner} stamps its states on sim time (a lockstep plant, '
                f'{seconds(ns):.3f} s) but the job runs in realtime: run both in one timing'
            )
        if self.start_ns is None:
            return
        now = self.clock_ns()
        # Silence counts from when the runner last took a state, not from the state's stamp,
        # and only the time the runner was awake: of a gap between two checks longer than
        # RUNNER_STALL_NS (it went without the CPU, or was stopped) only that much counts, as
        # it takes the states queued meanwhile when it resumes. Stalls do not restart the
        # count either: a drive gone while the runner stalls again and again is still found.
        awake = min(now - self._checked_ns, RUNNER_STALL_NS) if self._checked_ns >= 0 else 0
        self._checked_ns = now
        for axis in self.axes:
            arrivals = source.arrival_ns(topics.state(axis))
            since = now - max(arrivals[-1] if arrivals else -1, self.start_ns)
            quiet = min(since, self._quiet_ns.get(axis, 0) + awake)
            self._quiet_ns[axis] = quiet
            if quiet > DRIVE_SILENCE_NS:
                detail = (
                    f'the drive went silent: nothing on {topics.state(axis)} from '
                    f'{self.state_owner} for {quiet / 1e9:.1f} s'
                )
                at = (now - quiet - self.start_ns) * 1e-9
                raise DriveSilent(Event(axis, DRIVE_SILENT, at, detail))

    def complete(self, source: MessageSource) -> bool:
        status = self._job(source)
        if status is None:
            return False
        if status.get('state') == 'refused':
            raise ScenarioError(f'the trajectory refused the job: {status["message"]}')
        return status.get('state') == 'done'

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[RunRecord, dict[str, int]]:
        if self.start_ns is None:  # the run stopped before the job started: no sample
            return RunRecord.empty(0, seconds(self.dt_ns)), {}
        rec, missing = realtime_record(raw, self.axes, self.start_ns, self.end_time, self.owners())
        return rec, {t: m for t, m in missing.items() if m}

    def owners(self) -> dict[str, str]:
        return self.nodes.owners()

    def events(self, statuses: Sequence[Status]) -> list[Event]:
        # the controllers' trips on the system clock, the drive's statuses stamped on it; what
        # the drive counted before the job started (a drive kept from an earlier job) is not
        # this job's, and a job that never started has no stop nor brake of its own
        start = self.start_ns
        counted_from = start if start is not None else 2**63
        return self.nodes.events(statuses, start or 0, counted_from)

    # -- offline ---------------------------------------------------------------------------
    def simulation(self, times: CoreTimer | None = None) -> Any:
        raise ScenarioError('a realtime run has no offline twin (it depends on the timing)')

    def latched(self, source: MessageSource) -> dict[str, str] | None:
        """The axes the drive says it holds stopped (latched), with the reason of each, from
        its newest status `<drive>: realtime` (None: none heard yet)."""
        status = source.status(self.drive_status)
        return None if status is None else keys.stopped(status, self.axes)

    def warnings(self, statuses: Sequence[Status]) -> list[str]:
        """A drive whose statuses are named otherwise than `<drive>: realtime`: said once."""
        text = keys.misnamed((s.name for s in statuses), self.state_owner)
        return [text] if text else []

    # -- results ---------------------------------------------------------------------------
    @property
    def drive_status(self) -> str:
        """The name of the drive's status with its figures (`plant: realtime`)."""
        return topics.status_name(self.state_owner, keys.PART)

    def summary(self, rec: RunRecord, skip: float, ending: Ending | None = None) -> AxisSummary:
        """Figures from `skip` s after the approach (the trajectory says how long it took),
        with the drive's figures from its last status before the job's end (as the runner
        received the commands, from a driver that does not report them)."""
        statuses = ending.statuses if ending is not None else ()
        drive = last_values(statuses, self.drive_status)
        received: dict[str, dict[str, float]] = {}
        source = ending.source if ending is not None else None
        if source is not None and self.start_ns is not None and len(rec.t):
            timed = self.timed_topics()
            raw = {t: source.messages(t) for t in timed}
            arrivals = {t: source.arrival_ns(t) for t in timed}
            timing = command_timing(rec, raw, arrivals, self.axes, self.start_ns)
            received = {axis: t.figures() for axis, t in timing.items()}
        job = last_values(statuses, topics.status_name(self.trajectory, topics.JOB_STATUS))
        return axis_summary(
            self.RECORD,
            self.scenario,
            rec,
            skip,
            self.FAILING,
            ending,
            approach=float(job.get('approach_s', 0.0)),
            # a job that never started has no figures of the drive (they are an earlier job's)
            drive=drive_figures(self.axes, drive, received) if self.start_ns is not None else None,
            start_stamp_ns=self.start_ns,
        )


def last_values(statuses: Sequence[Status], name: str) -> dict[str, str]:
    """The values of the newest status with this name's node and part ({}: none heard;
    the statuses are one machine's, so the namespace may be left out: topics.status_key)."""
    key = topics.status_key(name)
    for s in reversed(statuses):
        if topics.status_key(s.name) == key:
            return dict(s.values)
    return {}


def drive_figures(
    axes: Sequence[str],
    drive: Mapping[str, str],
    received: Mapping[str, Mapping[str, float]] | None = None,
) -> DriveFigures:
    """Per axis: late fraction, most late periods in a row and latency median/p99/max
    [ms], from the drive's status (NaN where it does not report one); a driver that does not
    report them: as the runner received the commands (`received`)."""
    received = received or {}
    out = {}
    said = {a: keys.axis_key(a, keys.LATE_FRACTION) in drive for a in axes}
    for axis in axes:
        if said[axis] or axis not in received:
            out[axis] = {f: float(drive.get(keys.axis_key(axis, f), 'nan')) for f in DRIVE_FIGURES}
        else:
            out[axis] = dict(received[axis])
    if any(said.values()) or not received:
        source = 'the drive'
    else:
        source = 'the commands as the runner received them'
    overruns, ticks = drive_ticks(drive)
    stalls, longest_ms, longest = drive_stalls(drive)
    return DriveFigures(
        source,
        out,
        overruns,
        ticks,
        stalls=stalls,
        longest_stall_ms=longest_ms,
        longest_stall=longest,
        stall_report_ms=drive.get(keys.STALL_REPORT_MS, '?'),
    )


def drive_ticks(drive: Mapping[str, str]) -> tuple[int, int]:
    """The drive's ticks more than half a period late, and its ticks while active (the
    approach and the hold included; 0 from a driver that does not report them), both from
    its last status."""
    overruns, ticks = drive.get(keys.OVERRUNS, '0'), drive.get(keys.ACTIVE_TICKS, '0')
    return int(float(overruns)), int(float(ticks))


def drive_stalls(drive: Mapping[str, str]) -> tuple[int, float, str]:
    """The drive's own stalls (ticks that woke more than its `stall_report` late, on the
    monotonic clock): how many, the longest [ms] and its line (which process, when), from its
    last status (0 from a driver that does not report them)."""
    return (
        int(float(drive.get(keys.STALLS, '0'))),
        float(drive.get(keys.LONGEST_STALL_MS, '0')),
        drive.get(keys.LONGEST_STALL, ''),
    )
