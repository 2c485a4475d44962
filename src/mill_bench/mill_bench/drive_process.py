"""The hardware case's pieces: the scenario at a rate, the drive in a process of its own, and
the realtime job as the benchmark follows it (hops timed, the drive's CPU over the job).

The drive is the scenario's simulated plant (`plant_node`, timing realtime), started as `ros2
run` would start it (mill_bringup.graph: `python -m mill_plant.plant_node --ros-args -r
__node:=plant --params-file SCENARIO --params-file PARAMETERS`), outside the graph's layout,
as a hardware driver runs: what crosses processes between drive and loop is what crosses a
real machine's. It waits to be activated (autostart false), by the runner once the graph is
up, or by the floor once its echo node is.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from mill_analysis.record import RunRecord
from mill_bringup.catalogue import PLANT
from mill_bringup.cli import set_duration, set_timing, set_tuning
from mill_bringup.graph import Graph, cpu_seconds
from mill_bringup.jobs.base import MessageSource
from mill_bringup.jobs.realtime import RealtimeAxisJob, drive_figures, drive_ticks
from mill_bringup.layout import Process
from mill_bringup.runner.options import RunError
from mill_bringup.scenario import Scenario

from mill_bench import hops
from mill_bench.realtime_figures import RatePoint
from mill_bringup import scenario as scenario_mod
from mill_common import topics

UP = 'waiting for configure'  # what the drive logs once it is up and waits to be activated


def realtime_scenario(name: str, rate: float, duration: float, priority: int = 0) -> Scenario:
    """The scenario on the wall clock at `rate` [Hz] for `duration` s of its path: one sample
    of delay, the gains of the tuning rule for the rate (run_scenario --tuning rule; the
    scenario's own gains are refused at another rate than theirs), the drive inactive until
    activated; with a priority, the drive and the axis nodes' processes on SCHED_FIFO.
    ScenarioError for a scenario the rule does not tune."""
    scen = scenario_mod.load(name)
    set_timing(scen, 'realtime')
    set_tuning(scen)
    set_duration(scen, duration)
    scen.add_override(f'*.sample_period={1.0 / rate!r}')
    scen.add_override(f'{drive_node(scen)}.autostart=false')
    if priority:
        scen.add_override(f'*.realtime_priority={priority}')
    return scen


def drive_node(scen: Scenario) -> str:
    return scen.nodes_of(PLANT)[0].name


@dataclass(frozen=True)
class Drive:
    """A drive running in its own process (`drive_process`)."""

    name: str
    graph: Graph  # of that one process

    def cpu(self) -> float:
        """CPU seconds the drive's process has used so far."""
        return cpu_seconds(self.graph.procs[self.name].pid)


@contextlib.contextmanager
def drive_process(
    scen: Scenario, run_dir: Path, env: dict[str, str], wait: float = 120.0
) -> Iterator[Drive]:
    """The scenario's drive in its own process while inside `with`: up and waiting to be
    activated on entering, stopped on leaving."""
    name = drive_node(scen)
    graph = Graph(scen, run_dir, env)
    try:
        graph.launch([Process(name, (scen.node(name),))])
        # Up before anything else starts: a participant of this machine that comes first
        # may not discover the drive's services (test_multi_host saw it).
        deadline = time.monotonic() + wait
        while UP not in graph.logs[name].read_text():
            graph.check('before it was up')
            if time.monotonic() > deadline:
                raise RunError(f'the drive {name} was not up within {wait:g} s')
            time.sleep(0.05)
        yield Drive(name, graph)
    finally:
        graph.stop()


class HopTimedJob(RealtimeAxisJob):
    """The realtime job whose monitor also times states and estimates (mill_bench.hops), which
    takes `drive_cpu` (CPU seconds of a drive in its own process) at the job's first step and
    at its end, the window in which the runner takes its graph's CPU, and the drive's
    figures from its first status after the job's end."""

    SETTLE_TIMEOUT = 1.5  # [s] after the job's end: the drive's next status comes in it

    def __init__(self, scen: Scenario, drive_cpu: Callable[[], float]) -> None:
        super().__init__(scen)
        self._drive_cpu = drive_cpu
        self._cpu_at: list[float] = []
        self._listener: MessageSource | None = None
        # The drive's status with its figures: its first after the job's end (settled)
        self.drive: dict[str, str] = {}
        self.hops: Mapping[str, Mapping[str, tuple[float, float]]] = {}

    def timed_topics(self) -> set[str]:
        return super().timed_topics() | hops.timed_topics(self.axes)

    def progress(self, source: MessageSource) -> float:
        t = super().progress(source)
        if t > -math.inf and not self._cpu_at:
            self._cpu_at.append(self._drive_cpu())
        return t

    def complete(self, source: MessageSource) -> bool:
        self._listener = source
        done = super().complete(source)
        if done and len(self._cpu_at) == 1:
            self._cpu_at.append(self._drive_cpu())
        if done and (status := source.status(self.drive_status)) is not None:
            self.drive = status  # at the job's end, until its first status after it
        return done

    @property
    def drive_status(self) -> str:
        """The name of the drive's status with its figures (`plant: realtime`)."""
        return topics.status_name(self.state_owner, topics.DRIVE_STATUSES[1])

    def settled(self, source: MessageSource) -> bool:
        # The drive reports once a second: its first status after the job's end has the
        # figures of the whole job (the one the job kept at its end may be a second old).
        status = source.status(self.drive_status)
        if status is not None:
            self.drive = status
        return super().settled(source)

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[RunRecord, dict[str, int]]:
        rec, gaps = super().record(raw)
        if self._listener is not None and self.start_ns is not None:
            window = (self.start_ns, self.start_ns + round(self.end_time * 1e9))
            timed = hops.timed_messages(self._listener, self.timed_topics())
            self.hops = hops.hop_latencies(timed, self.axes, window)
        return rec, gaps

    def drive_cpu_ms_per_tick(self) -> float:
        """The drive's CPU per step of the job [ms] (NaN if the job never ran)."""
        if len(self._cpu_at) < 2:
            return math.nan
        return 1e3 * (self._cpu_at[1] - self._cpu_at[0]) / max(self.samples - 1, 1)

    def point(
        self, case: str, rate: float, cpu_drive_ms: float, cpu_rest_ms: float, notes: Sequence[str]
    ) -> RatePoint:
        """The run's figures: the drive's from its status (`drive`, read as the job reads
        it), the hops, and the CPU per tick given."""
        overruns, ticks = drive_ticks(self.drive)
        return RatePoint(
            case,
            rate,
            drive_figures(self.axes, self.drive).axes,
            overruns,
            ticks,
            self.hops,
            cpu_drive_ms=cpu_drive_ms,
            cpu_rest_ms=cpu_rest_ms,
            notes=tuple(notes),
        )
