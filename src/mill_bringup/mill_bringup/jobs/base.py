"""What the job pipeline asks of a kind of job. ROS-free.

A scenario runs one kind of job: the three-axis motion job (`axis`: plant, trajectory,
observers, controllers) or the cutting-force job of Rubio 2013 (`force`: force process,
force controller, trajectory). The runner, the offline simulator and `--record` are written
once against this interface (and `report` against the kind of record a job names); what
differs between the kinds sits in one class per kind (mill_bringup.jobs.axis, .realtime,
.force):

- which node clocks the job (it starts last, once the others are heard), and its graph
  plan (`GraphPlan`: which topics must have a publisher before it starts, which the monitor
  keeps, records, times and subscribes to late, the recorder's handshake);
- when the job is complete and when its last messages have arrived;
- the record: from the messages of a run (or a bag), or from the offline simulation,
  sample by sample (`Simulation.step`), by the one loop in `simulate`;
- what happened to the machine (typed events, mill_analysis.events, parsed from the
  /diagnostics statuses heard until the job ended: `Ending`), and which of them fail the job
  (FAILING);
- the summary of a record (one value, mill_analysis.summary: the text and summary.json print
  from it);
- the kind of record a run gives (RECORD, the kind object of mill_analysis.report.kinds: its
  name goes in the bag, `report` reads the bag through the same object, and both summarise
  with it; it also says what a record left out and how two records differ), and what to
  note before the paper's verdicts (PAPER_NOTE).

The state of a run (what the runner heard when the job ended) is not kept by the job: the
runner takes it once, as an `Ending`, and hands it to `summary`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Generic, Protocol, TypeVar

from mill_analysis.events import Event, Status
from mill_analysis.report.kinds import RecordKind
from mill_analysis.summary import Summary

from mill_bringup.bag_handshake import RecordedSteps
from mill_bringup.job_config import JobConfig, build
from mill_bringup.scenario import LAYOUTS, NodeLaunch, Scenario
from mill_bringup.simulation import CoreTimer, Simulation, run_samples

R = TypeVar('R')


# Samples a recorded lockstep run's clock node may run ahead of its bag's file: far inside
# the writers' history (DATA_QOS, 2000 samples), and what a SIGKILL of the runner may cost at
# most. The runner acknowledges after each write (every monitor.FLUSH_PERIOD), so the clock
# node takes at most this many steps per write.
RECORDER_WINDOW = 400


class MessageSource(Protocol):
    """What a job reads of a running graph (the runner's monitor)."""

    def latest_stamp_ns(self, topic: str) -> int:
        """Stamp of the newest message on topic [ns], -1 if none."""
        ...

    def messages(self, topic: str) -> Sequence[bytes]:
        """Serialized messages heard on topic, in arrival order."""
        ...

    def status(self, name: str) -> dict[str, str] | None:
        """The newest /diagnostics status of this name: its values, 'message' and 'level'."""
        ...

    def problems(self) -> list[str]:
        """Every WARN or ERROR status heard so far, `name: message`, once each."""
        ...

    def arrival_ns(self, topic: str) -> Sequence[int]:
        """Wall-clock arrival [ns, system clock] of each message of a timed topic."""
        ...

    def statuses(self) -> Sequence[Status]:
        """Every /diagnostics status of the machine heard so far, in order (its values)."""
        ...


@dataclass(frozen=True)
class Ending:
    """How a run ended, as the runner took it once when the job was complete (or the run
    could not go on): the machine's statuses heard until then, the runner's own finding that
    ended it (a drive gone silent, a stall, a node that died; None: the job completed), and
    what the runner heard (for a job's figures of the messages' timing)."""

    statuses: tuple[Status, ...] = ()
    failure: Event | None = None
    source: MessageSource | None = None


@dataclass(frozen=True)
class GraphPlan:
    """What the runner starts and hears of a job's graph, as the job prepared it: the topics
    that must have a publisher before the clock node starts, those it keeps (to build the
    record) and those a bag records besides, whose arrival it times, those it subscribes to
    late (once each of `late_after` has a message), the recorder's handshake with the clock
    node, and whether the graph runs on sim time (Job.graph_plan)."""

    upstream: tuple[str, ...]
    kept: Mapping[str, str]  # topic -> message type
    recorded: Mapping[str, str]
    timed: frozenset[str]
    late: frozenset[str]
    late_after: tuple[str, ...]
    steps: RecordedSteps | None
    sim_time: bool


class Job(ABC, Generic[R]):
    """One scenario configuration, checked: its samples, its graph, its record."""

    KIND: ClassVar[str]
    # The kind of record a run gives (mill_analysis.report.kinds): named in its bag, read by
    # `report` through the same object, and summarised by it.
    RECORD: ClassVar[RecordKind[Any]]
    # The kinds of event (mill_analysis.events) that fail a run of this job (exit code 1);
    # what the runner finds itself (Ending.failure) always does.
    FAILING: ClassVar[tuple[str, ...]] = ()
    CLOCK: ClassVar[str]  # the role of the node that clocks the job (mill_bringup.catalogue)
    # How long to wait, after the job is complete, for its last messages [s].
    SETTLE_TIMEOUT: ClassVar[float] = 5.0
    # Whether the offline simulator reproduces a distributed run of this kind exactly.
    HAS_OFFLINE_TWIN: ClassVar[bool] = True
    # Whether the runner deactivates the clock node (lifecycle: brake) when the job is done.
    BRAKE_AT_END: ClassVar[bool] = False
    # What to say before the paper's verdicts on a run of this kind ('': nothing to add).
    PAPER_NOTE: ClassVar[str] = ''

    def __init__(self, scen: Scenario, config: JobConfig | None = None) -> None:
        """The job of scen, whose configuration (mill_bringup.job_config, built from scen
        if not given) is validated and checked once: the job reads its values from it."""
        self.scenario = scen
        self.config = config if config is not None else build(scen)

    @classmethod
    def runs(cls, config: JobConfig) -> bool:
        """Whether the scenario is a job of this kind (its clock node is in the launch list)."""
        return bool(config.of_role(cls.CLOCK))

    # -- what it is ------------------------------------------------------------------------
    @property
    @abstractmethod
    def samples(self) -> int:
        """Samples k = 0 .. samples − 1 make up the job."""

    @property
    @abstractmethod
    def sim_time(self) -> float:
        """Machine time from the first to the last sample [s]."""

    @property
    def max_samples(self) -> int:
        """The offline loop's bound: `samples`, or more for a job that ends when its path
        ends (the simulation then says when it has finished)."""
        return self.samples

    @property
    def clock_nodes(self) -> list[NodeLaunch]:
        return self.scenario.nodes_of(self.CLOCK)

    # -- the distributed run ---------------------------------------------------------------
    @abstractmethod
    def prepare_graph(
        self, monitored: bool, layout: str = LAYOUTS[0], recorded: bool = False
    ) -> None:
        """Adjust the scenario before launch in this layout (the clock node waits for the
        monitor too; if `recorded`, for the recorder where it can)."""

    @abstractmethod
    def graph_plan(self) -> GraphPlan:
        """What the runner starts and hears of the graph as prepare_graph left it."""

    def started_ns(self) -> int | None:
        """When the job started on the system clock, if the graph says so (realtime); else
        the runner counts from the first progress it hears."""
        return None

    @abstractmethod
    def progress(self, source: MessageSource) -> float:
        """Machine time the run has reached [s] (−inf before the first sample)."""

    @abstractmethod
    def complete(self, source: MessageSource) -> bool:
        """Every sample of the job has been produced."""

    def check(self, source: MessageSource) -> None:
        """While the run goes on: ScenarioError when the graph cannot make the job (a
        driver on another clock, a drive gone silent)."""

    def latched(self, source: MessageSource) -> dict[str, str] | None:
        """The axes the clock node (a drive that stays up across jobs) says it holds stopped,
        latched from an earlier job, with the reason of each; None: it has not said yet. The
        runner refuses to start the job on one unless told to re-arm (mill_bringup.runner.
        start.handshake). A job whose clock node latches nothing: {}."""
        return {}

    def warnings(self, statuses: Sequence[Status]) -> list[str]:
        """What the runner says once at the end about the statuses it heard (a drive's
        status named otherwise than the job reads it)."""
        return []

    def events(self, statuses: Sequence[Status]) -> list[Event]:
        """What the machine told of itself in these statuses (trips, stops, brakes)."""
        return []

    def settled(self, source: MessageSource) -> bool:
        """The last messages that follow a complete job have arrived."""
        return False

    @abstractmethod
    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[R, dict[str, int]]:
        """The record from a run's serialized messages, and samples missing per topic."""

    def summary_topics(self) -> frozenset[str]:
        """The topics whose messages `summary` reads besides the record (from the ending's
        source): the runner keeps them, and forgets the others' once the record is built."""
        return frozenset()

    # -- offline ---------------------------------------------------------------------------
    @abstractmethod
    def simulation(self, times: CoreTimer | None = None) -> Simulation[R]:
        """The job in one process, the same calls in the same order as the graph."""

    # -- results ---------------------------------------------------------------------------
    @abstractmethod
    def summary(self, rec: R, skip: float, ending: Ending | None = None) -> Summary:
        """The summary of a record (figures `skip` seconds after the job's path started), the
        events of its ending with it (None: an offline run, whose record has its events)."""

    def owners(self) -> dict[str, str]:
        """The node each per-sample topic must come from (header.frame_id)."""
        return {}


def simulate(
    job: Job[R],
    progress: Callable[[int, int], None] | None = None,
    times: CoreTimer | None = None,
) -> R:
    """The job offline: the record the distributed run of the same scenario gives."""
    return run_samples(job.simulation(times), job.max_samples, progress)
