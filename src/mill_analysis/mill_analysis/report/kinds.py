"""How `report` reads, summarises and plots a bag: one RecordKind per kind of record.

A bag of `run_scenario --record` names its kind of record (mill_analysis.bag_meta: the job
kind's); `kind_of` picks the RecordKind by that name. A bag that names none (the `recorder`
node's, `ros2 bag record`'s) is told by its topics: the force stream and the force
controller's state make a force job's bag; any other is an axis job's, lockstep or realtime
as its job status says.

Bags of kinds that share a REPORT go side by side in one report (lockstep and realtime axis
runs do); the presentation (table, report.md, plots) is that of the first bag's kind.

The kinds are the one registry of the kinds of record (`KINDS`): each job kind of
mill_bringup names its kind of record by the object (Job.RECORD), the runner writes its
NAME into the bag and summarises its record with its `summarize`, and `report` reads the bag
back through the same object and summarises with the same `summarize`
(mill_analysis.summary).
"""

from __future__ import annotations

import math
import os
import time
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, Generic, TypeVar

import numpy as np
from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_common.progress import Progress

from mill_analysis import bag_meta
from mill_analysis.bag_run import read_run
from mill_analysis.force_record import ForceBagRun, ForceRecord, is_force_bag, read_force_run
from mill_analysis.metrics import max_difference
from mill_analysis.record import FORCE_CONTROL, RunRecord
from mill_analysis.report.analysis import RunReport, analyse
from mill_analysis.report.force import force_figure, force_markdown, force_table
from mill_analysis.report.plots import plot_all
from mill_analysis.report.text import markdown, text_table
from mill_analysis.summary import AxisSummary, ForceSummary, axis_summary, force_summary

R = TypeVar('R')
Figures = list[tuple[str, str]]  # (file name, title) of each plot written


@dataclass(frozen=True)
class ReportOptions:
    """What `report`'s options ask of every bag."""

    skip: float  # metrics over t >= skip [s]
    window: float  # of the largest windowed RMS tracking error [s]
    freqs: list[float]  # of the error amplitudes [Hz]
    namespace: str | None  # the machine, in a bag of several
    quiet: bool  # no progress display


class RecordKind(ABC, Generic[R]):
    """How a bag of one kind of record is read and summarised (`read`, one bag) and shown
    (`table`, `markdown`, `plot`, every bag of the report)."""

    NAME: ClassVar[str]  # mill_analysis.bag_meta
    REPORT: ClassVar[str]  # kinds with the same REPORT share one (e.g. 'axis-job')

    @abstractmethod
    def summarize(self, record: Any, skip: float, **context: Any) -> AxisSummary | ForceSummary:
        """The summary of a record of this kind (mill_analysis.summary), what the runner and
        `report` print; context: what the kind's summary takes besides the record."""

    @abstractmethod
    def read(self, bag: Path, label: str, options: ReportOptions) -> R:
        """The bag's run, summarised; BagError (one line) when it cannot be."""

    @abstractmethod
    def table(self, runs: Sequence[R]) -> str:
        """What `report` prints."""

    @abstractmethod
    def markdown(self, runs: Sequence[R], figures: Figures, argv: list[str]) -> str:
        """report.md."""

    @abstractmethod
    def plot(self, runs: Sequence[R], out: Path) -> Figures:
        """The plots, written to `out`."""

    # -- what a record of this kind left out, and how two of them differ -----------------
    def foreign(self, record: Any) -> dict[str, int]:
        """Messages the record left out per topic: what the nodes drop (another sender, a
        stamp they refuse, malformed; mill_analysis.node_intake)."""
        return {}

    def dropped(self, record: Any) -> dict[str, list[tuple[int, str]]]:
        """The same per topic and reason: (messages, the first one's reason), most first."""
        return {}

    def gaps(self, record: Any) -> dict[str, list[tuple[int, int]]]:
        """Per topic with samples missing, the runs (first, last) of them."""
        return dict(record.gaps)

    @abstractmethod
    def differences(self, record: Any, other: Any) -> dict[str, float]:
        """Largest difference per signal between two records of this kind (inf: a gap): a
        distributed run against its offline twin."""


class BagProgress:
    """read_run's progress callback: one Progress per phase (reading, decoding) of a bag."""

    def __init__(self, label: str, quiet: bool) -> None:
        self.label = label
        self.quiet = quiet
        self.phase = ''
        self.bar: Progress | None = None

    def __call__(self, phase: str, done: int, total: int | None) -> None:
        if phase != self.phase:
            self.close()
            self.phase = phase
            self.bar = Progress(
                total,
                unit='messages',
                quiet=self.quiet,
                label=f'{self.label}: {phase}',
                decimals=0,
                delay=2.0,  # a short bag shows none (nor before a one-line error)
            )
        if self.bar is not None:
            self.bar.update(done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class AxisRecords(RecordKind[RunReport]):
    """The three-axis job's bags: per axis tracking and estimation errors, spectra, loop
    timing. This class reads a bag that does not say whether its run was lockstep or realtime
    (the job status tells); the two kinds below read a bag that says."""

    NAME = 'axis, lockstep or realtime'  # no bag names it: what a bag without a name is
    REPORT = 'axis-job'
    REALTIME: ClassVar[bool | None] = None  # None: told by the bag's job status

    def summarize(self, record: RunRecord, skip: float, **context: Any) -> AxisSummary:
        """mill_analysis.summary.axis_summary: approach, failing, predictions, force_control,
        drive, start_stamp_ns."""
        return axis_summary(record, skip, **context)

    def read(self, bag: Path, label: str, options: ReportOptions) -> RunReport:
        t0 = time.monotonic()
        progress = BagProgress(label, options.quiet)
        try:
            run = read_run(bag, options.namespace, progress, realtime=self.REALTIME)
        finally:
            progress.close()
        if run.n <= 1 or not (run.record.t >= options.skip).any():
            raise BagError(
                f'{bag}: no samples at t >= {options.skip:g} s '
                f'(the run lasts {run.record.t[-1]:g} s)'
            )
        summary = self.summarize(run.record, options.skip, approach=run.approach)
        report = analyse(run, label, summary, options.window, options.freqs)
        report.read_seconds = time.monotonic() - t0
        return report

    def table(self, runs: Sequence[RunReport]) -> str:
        return text_table(list(runs))

    def markdown(self, runs: Sequence[RunReport], figures: Figures, argv: list[str]) -> str:
        return markdown(list(runs), figures, argv)

    def plot(self, runs: Sequence[RunReport], out: Path) -> Figures:
        big = sum(r.run.n for r in runs) > 20_000
        workers = min(2, os.cpu_count() or 1) if big else 1  # long runs: two forked renderers
        return plot_all(list(runs), out, workers)

    def foreign(self, record: RunRecord) -> dict[str, int]:
        return dict(record.foreign)

    def dropped(self, record: RunRecord) -> dict[str, list[tuple[int, str]]]:
        return record.drops.reasons()

    def differences(self, record: RunRecord, other: RunRecord) -> dict[str, float]:
        out = {'tracking_error': max_difference(record.tracking_error, other.tracking_error)}
        if not np.isnan(record['force']).all():  # recorded (--record): the plant's force too
            out['cutting_force'] = max_difference(record['force'], other['force'])
        a, b = record.force_control, other.force_control
        if a is not None and b is not None:
            for i, name in enumerate(FORCE_CONTROL[1:], 1):
                out[f'force_control.{name}'] = (
                    max_difference(a[:, i], b[:, i]) if a.shape == b.shape else math.inf
                )
        return out


class LockstepAxisRecords(AxisRecords):
    """A lockstep run: samples on the grid t = k T."""

    NAME = bag_meta.AXIS
    REALTIME = False


class RealtimeAxisRecords(AxisRecords):
    """A realtime run: samples at the drive's stamps, with the commands' timing."""

    NAME = bag_meta.AXIS_REALTIME
    REALTIME = True

    def differences(self, record: RunRecord, other: RunRecord) -> dict[str, float]:
        raise ValueError('a realtime run has no offline twin (it depends on the timing)')


ForceRun = tuple[str, ForceBagRun]  # (label, run)
# What a distributed force job must equal its offline twin in (ForceRecord's fields).
FORCE_COMPARED = ('force', 'override', 'slope', 'beta', 'feed_command')


class ForceRecords(RecordKind[ForceRun]):
    """The cutting-force job's bags (Rubio 2013): J_c of eq. (14) and the override."""

    NAME = bag_meta.FORCE
    REPORT = 'force-job'

    def summarize(self, record: ForceRecord, skip: float, **context: Any) -> ForceSummary:
        """mill_analysis.summary.force_summary of the record's J_c, override and β; context:
        events."""
        return force_summary(record.j_c, record.override, record.beta, **context)

    def read(self, bag: Path, label: str, options: ReportOptions) -> ForceRun:
        return label, read_force_run(bag, options.namespace)

    def table(self, runs: Sequence[ForceRun]) -> str:
        return force_table(list(runs))

    def markdown(self, runs: Sequence[ForceRun], figures: Figures, argv: list[str]) -> str:
        return force_markdown(list(runs), figures, argv)

    def plot(self, runs: Sequence[ForceRun], out: Path) -> Figures:
        return force_figure(list(runs), out)

    def differences(self, record: ForceRecord, other: ForceRecord) -> dict[str, float]:
        out = {}
        for key in FORCE_COMPARED:
            a, b = getattr(record, key), getattr(other, key)
            out[key] = float(np.max(np.abs(a - b))) if a.shape == b.shape else math.inf
        out['j_c_relative'] = abs(record.j_c - other.j_c) / abs(other.j_c)
        return out


LOCKSTEP_AXIS = LockstepAxisRecords()
REALTIME_AXIS = RealtimeAxisRecords()
FORCE = ForceRecords()
KINDS: dict[str, RecordKind[Any]] = {
    kind.NAME: kind for kind in (LOCKSTEP_AXIS, REALTIME_AXIS, FORCE)
}


def kind_of(path: Path) -> RecordKind[Any]:
    """The kind of record a bag holds: the one it names, else told by its topics."""
    bag = open_bag(path)
    name = bag_meta.named(bag.custom_data)
    if name is not None:
        if name not in KINDS:
            raise BagError(
                f'{path} holds a record of kind {name!r}, which this report does not know '
                f'({", ".join(KINDS)})'
            )
        return KINDS[name]
    return FORCE if is_force_bag(bag_meta.bag_counts(bag)) else AxisRecords()
