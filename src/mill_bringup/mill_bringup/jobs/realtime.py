"""The three-axis job on the wall clock: the drive keeps its own time (timing realtime).

The same graph as the lockstep axis job (mill_bringup.jobs.axis), with every node's
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

from mill_analysis.metrics import summarize, summary_text
from mill_analysis.realtime_record import command_timing, realtime_record
from mill_analysis.record import RunRecord
from mill_common.signals import AXES
from mill_common.timebase import job_steps, seconds

from mill_analysis import records
from mill_bringup.job_config import JobConfig
from mill_bringup.jobs.axis import JOINT_STATE, WALL_CLOCK_NS, AxisJob
from mill_bringup.jobs.base import MessageSource
from mill_bringup.scenario import LAYOUTS, Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer
from mill_bringup.tuning.prediction_file import against_prediction
from mill_common import topics

# No state this long after the start: the drive is gone (the runner itself may go without
# the CPU for a second when the graph runs SCHED_FIFO on every core).
DRIVE_SILENCE_NS = 3_000_000_000
# The runner checks every 50 ms; a gap this long between two checks is the runner's own.
RUNNER_STALL_NS = 1_000_000_000
DRIVE_FIGURES = (
    'late_fraction',
    'longest_late_run',
    'latency_median_ms',
    'latency_p99_ms',
    'latency_max_ms',
)


class RealtimeAxisJob(AxisJob):
    KIND = 'axis-realtime'
    RECORD = records.AXIS_REALTIME
    HAS_OFFLINE_TWIN = False
    BRAKE_AT_END = True  # the drive keeps running on its own clock: brake it first
    PAPER_NOTE = (
        "note: a realtime run: the paper's experiment is the lockstep run at its own sample "
        "rate; these figures also depend on how this machine kept the wall clock's rate, and "
        'the verdicts below are not a reproduction (run without --timing realtime for that)'
    )

    @classmethod
    def runs(cls, config: JobConfig) -> bool:
        return bool(config.of_role(cls.CLOCK)) and config.timing == 'realtime'

    def __init__(self, scen: Scenario, config: JobConfig | None = None) -> None:
        super().__init__(scen, config)
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
        self.start_ns: int | None = None
        self._checked_ns = -1  # when `check` last looked (system clock)
        self._quiet_ns: dict[str, int] = {}  # per axis: time awake without a state
        self.clock_ns = time.time_ns  # the system clock the arrivals are taken on
        self.drive: dict[str, str] = {}
        self._source: MessageSource | None = None
        self.received: dict[str, dict[str, float]] = {}  # per axis, as the runner saw it
        self._problems_at_end: list[str] | None = None
        self._drive_at_end: dict[str, str] | None = None

    @property
    def sim_time(self) -> float:
        return self.end_time  # the path, and once started the approach move before it

    @property
    def samples(self) -> int:
        return job_steps(self.end_time, self.dt_ns)

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

    def monitor_topics(self) -> dict[str, str]:
        out = super().monitor_topics()
        for axis in self.axes:
            out[topics.joint_command(axis)] = JOINT_STATE
        return out

    def recorded_topics(self) -> dict[str, str]:
        return {
            k: v for k, v in super().recorded_topics().items() if k not in self.monitor_topics()
        }

    def sim_time_stamps(self) -> bool:
        return False

    def started_ns(self) -> int | None:
        return self.start_ns

    def timed_topics(self) -> set[str]:
        # the commands for their latency; the states for the drive's silence (check)
        return {f(a) for a in self.axes for f in (topics.joint_command, topics.state)}

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
                raise ScenarioError(
                    f'the drive went silent: nothing on {topics.state(axis)} from '
                    f'{self.state_owner} for {quiet / 1e9:.1f} s'
                )

    def failures(self, rec: RunRecord, problems: Sequence[str]) -> list[str]:
        """Every axis that tripped or was braked while the job ran (what happens after its
        end, as the graph stops, is not the job's): on a machine, the job did not complete."""
        parts = ('following error', *(f'{axis} axis' for axis in self.axes))
        heard = problems if self._problems_at_end is None else self._problems_at_end
        out = [
            p
            for p in heard
            if any(f': {part}: ' in p for part in parts) and ('trip' in p or 'braked' in p)
        ]
        # The drive's own count: its report of a stop may be lost with the link that failed.
        drive = self.drive if self._drive_at_end is None else self._drive_at_end
        for axis in self.axes:
            stops = int(float(drive.get(f'{axis}.stops', '0')))
            if stops and not any(f': {axis} axis: ' in p and 'stopped' in p for p in out):
                why = drive.get(f'{axis}.stopped') or 'released since'
                out.append(
                    f'{self.state_owner}: {axis} axis: stopped by the drive {stops} time(s) '
                    f'(now: {why})'
                )
        return out

    def complete(self, source: MessageSource) -> bool:
        status = self._job(source)
        if status is None:
            return False
        if status.get('state') == 'refused':
            raise ScenarioError(f'the trajectory refused the job: {status["message"]}')
        drive = source.status(topics.status_name(self.state_owner, topics.DRIVE_STATUSES[1]))
        if drive is not None:
            self.drive = drive
        self._source = source
        done = status.get('state') == 'done'
        if done:
            self._problems_at_end = source.problems()
            self._drive_at_end = dict(self.drive)
        return done

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[RunRecord, dict[str, int]]:
        if self.start_ns is None:
            raise ScenarioError('the job never started (no start_stamp_ns from the trajectory)')
        rec, missing = realtime_record(raw, self.axes, self.start_ns, self.end_time, self.owners())
        if self._source is not None:
            source = self._source
            arrivals = {t: source.arrival_ns(t) for t in self.timed_topics()}
            timing = command_timing(rec, raw, arrivals, self.axes, self.start_ns)
            self.received = {axis: t.figures() for axis, t in timing.items()}
        return rec, {t: m for t, m in missing.items() if m}

    def simulation(self, times: CoreTimer | None = None) -> Any:
        raise ScenarioError('a realtime run has no offline twin (it depends on the timing)')

    def drive_figures(self) -> dict[str, dict[str, float]]:
        """Per axis: late fraction, most late periods in a row and latency median/p99/max
        [ms], from the drive's status (NaN where it does not report one);
        a driver that does not report them: as the runner received the commands."""
        out = {}
        for axis in self.axes:
            if f'{axis}.late_fraction' in self.drive or axis not in self.received:
                out[axis] = {f: float(self.drive.get(f'{axis}.{f}', 'nan')) for f in DRIVE_FIGURES}
            else:
                out[axis] = dict(self.received[axis])
        return out

    def figures_source(self) -> str:
        """Where drive_figures come from, for the summary."""
        if any(f'{a}.late_fraction' in self.drive for a in self.axes) or not self.received:
            return 'the drive'
        return 'the commands as the runner received them'

    def overruns(self) -> tuple[int, int]:
        """The drive's ticks more than half a period late, and its ticks while active (the
        approach and the hold included; 0 from a driver that does not report them), both from
        its last status."""
        return (
            int(float(self.drive.get('overruns', '0'))),
            int(float(self.drive.get('active_ticks', '0'))),
        )

    def summary(self, rec: RunRecord, skip: float) -> str:
        lines = [
            summary_text(rec, skip),
        ]
        if len(rec.t):  # none: the drive's states never reached the runner
            lines += against_prediction(self.scenario, summarize(rec, skip), float(rec.t[-1]))
        lines.append(
            'axis   periods without a fresh command   in a row   state->command latency [ms]: '
            f'median    p99     max   (from {self.figures_source()})'
        )
        for axis, f in self.drive_figures().items():
            lines.append(
                f'{axis:>4}   {100 * f["late_fraction"]:30.2f} %   {f["longest_late_run"]:8.0f}   '
                f'{f["latency_median_ms"]:27.3f} {f["latency_p99_ms"]:7.3f} '
                f'{f["latency_max_ms"]:7.3f}'
            )
        overruns, ticks = self.overruns()
        if overruns:
            of = f' of {ticks} ({100 * overruns / ticks:.2f} %)' if ticks else ''
            lines.append(
                f'WARNING: the drive ticked more than half a period late {overruns} times{of}: '
                'this machine does not hold the sample rate in this layout'
            )
        return '\n'.join(lines)

    def summary_json(self, rec: RunRecord, skip: float) -> dict[str, Any]:
        out = super().summary_json(rec, skip)
        out['drive'] = self.drive_figures()
        out['drive_overruns'], out['drive_ticks'] = self.overruns()
        out['start_stamp_ns'] = self.start_ns
        return out
