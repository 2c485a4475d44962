"""Collecting a finished run: its last messages, the graph stopped, the bag closed, the record
built from the monitor's messages, and the RunResult with the job's summary."""

from __future__ import annotations

import resource
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mill_analysis.events import INTRUSIONS, events_of
from mill_bag.reader import open_bag
from mill_bag.writer import counts_note

from mill_analysis import bag_meta
from mill_bringup.jobs.base import Ending, Job, simulate
from mill_bringup.lifecycle_client import deactivate
from mill_bringup.lost_samples import split_lost
from mill_bringup.runner.follow import WallTime
from mill_bringup.runner.options import RunOptions
from mill_bringup.runner.result import RunResult
from mill_bringup.runner.session import Session
from mill_common import topics

QUIET = 2.0  # [s] without a newly recorded step that end the wait for the recorder


@dataclass(frozen=True)
class Collected:
    """What a finished run left: its record and what the runner saw of the graph."""

    record: Any
    missing: dict[str, int]  # samples missing per topic, not counting `lost`
    missing_ranges: dict[str, list[tuple[int, int]]]  # of the topics in `missing`
    lost: dict[str, int]  # samples a killed sender took with it (mill_bringup.lost_samples)
    problems: list[str]  # the graph's notes, WARN and ERROR statuses heard
    bag: dict[str, Any] | None  # path, messages and size of the bag, if one was written
    missing_from_bag: dict[str, int]  # per topic, received but not in the bag
    peak_rss_mb: dict[str, float]  # per process of the graph
    peak_pss_mb: float  # graph + runner
    foreign_publishers: list[str]  # what the drives said of foreign publishers they ignored
    warnings: list[str]  # what the job says once of the statuses heard (Job.warnings)
    rearmed: dict[str, str]  # axes the start handshake released (--rearm), and why stopped
    # messages the monitor left out per topic, their publisher GID another node's
    refused: dict[str, int] = field(default_factory=dict)


def collect(session: Session, job: Job[Any], options: RunOptions, ending: Ending) -> Collected:
    """Wait for the job's last messages (unless the run stopped), brake, stop the graph,
    close the bag; the record, with the events the machine told until the job ended."""
    monitor, graph = session.monitor, session.graph
    if ending.failure is not None:
        pass  # nothing more is coming: what arrived is the record
    elif monitor.steps is not None:  # the handshake says when the last messages are in
        monitor.finish_recording(job.samples)  # the plant stops where the bag can wait
        _catch_up(session)
    else:
        settle = time.monotonic() + job.SETTLE_TIMEOUT
        while time.monotonic() < settle and not job.settled(monitor):
            session.spin('after the job ended')
    if job.BRAKE_AT_END:
        for node in job.clock_nodes:
            deactivate(monitor, session.executor, node.name, session.progress)
    peak = graph.peak_rss()
    session.peak_pss_mb = max(session.peak_pss_mb, graph.pss())
    graph.stop()
    session.progress.close()
    recorder = monitor.recorder
    if recorder is not None:
        _drain(session)
    try:
        record, gaps = job.record(monitor.raw)
        # Built: the messages no figure reads are dropped (their counts stay for the bag's
        # check), 16 MB of the main job's.
        monitor.raw.forget(job.summary_topics())
        # What the machine told until the job ended (or the run stopped), in the record as
        # the offline simulator and a bag's reader put it there.
        record.events = job.events(ending.statuses)
        missing, lost = split_lost(gaps, job.owners(), graph.restarted_nodes())
        if recorder is not None:  # the bag says what its run lacks, as the summary does
            ns = monitor.get_namespace()
            absolute = {topics.qualify(t, ns): m for t, m in missing.items()}
            recorder.note(bag_meta.MISSING_SAMPLES, counts_note(absolute))
    finally:
        bag = _close_bag(session, options)
    ranges = {t: r for t, r in job.RECORD.gaps(record).items() if t in missing}
    short = _missing_from_bag(session, options) if bag is not None else {}
    problems = graph.notes + monitor.problems()
    # A foreign publisher on the drive's topics, or two claiming an owner's name, told at any
    # time: the record is not intact.
    heard = monitor.statuses()
    foreign = [e.text() for e in events_of(heard) if e.kind in INTRUSIONS]
    return Collected(
        record,
        missing,
        ranges,
        lost,
        problems,
        bag,
        short,
        peak,
        session.peak_pss_mb,
        foreign,
        job.warnings(heard),
        dict(session.rearmed),
        {t: sum(per.values()) for t, per in monitor.refused.items()},
    )


def _missing_from_bag(session: Session, options: RunOptions) -> dict[str, int]:
    """Per topic the runner kept, the messages it received that the closed bag does not hold
    (its metadata.yaml's counts): a bag that lacks a sample fails the run as the record
    does. Each message reaches the bag and the record by the same callback; this checks what
    was written."""
    ns = session.monitor.get_namespace()
    written = bag_meta.bag_counts(open_bag(Path(str(options.record_bag))))
    out = {}
    for topic, kept in session.monitor.raw.items():
        short = len(kept) - written.get(topics.qualify(topic, ns), 0)
        if short > 0:
            out[topic] = short
    return out


def _catch_up(session: Session) -> None:
    """Wait until the bag holds every step the plant took (nothing is in flight when the
    graph stops), unless no step comes for QUIET seconds."""
    steps = session.monitor.steps
    assert steps is not None, 'a run with the handshake'
    through, since = steps.through, time.monotonic()
    while not steps.drained and time.monotonic() - since < QUIET:
        session.spin('while the recorder caught up')
        if steps.through != through:
            through, since = steps.through, time.monotonic()


def _drain(session: Session) -> None:
    """Take what the nodes sent before they stopped."""
    drain = time.monotonic() + 0.3
    while time.monotonic() < drain:
        session.executor.spin_once(timeout_sec=0.05)


def _close_bag(session: Session, options: RunOptions) -> dict[str, Any] | None:
    """Close the bag; its figures."""
    recorder = session.monitor.recorder
    if recorder is None:
        return None
    session.monitor.close_recording()
    return {
        'path': str(options.record_bag),
        'messages': recorder.message_count,
        'size_bytes': recorder.writer.size_bytes,
        'dropped': dict(recorder.intake.counts),  # bad messages per kind (mill_bag.intake)
    }


def result(
    job: Job[Any],
    options: RunOptions,
    domain_id: str,
    timing: WallTime,
    collected: Collected,
    ending: Ending,
) -> RunResult:
    """The run's figures and the job's summary of its record (and the offline comparison)."""
    peak = dict(collected.peak_rss_mb)
    peak['runner'] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    record, wall = collected.record, timing.wall
    out = RunResult(
        scenario=job.scenario.name,
        kind=job.KIND,
        samples=job.samples,
        sim_time=job.sim_time,
        wall_time=wall,
        real_time_factor=job.sim_time / wall,
        steps_per_second=job.samples / wall,
        cpu_ms_per_step=sum(timing.cpu_ms_per_step.values()),
        cpu_ms_per_step_by_process=timing.cpu_ms_per_step,
        peak_pss_mb=collected.peak_pss_mb,
        peak_rss_mb=peak,
        domain_id=domain_id,
        missing_samples=collected.missing,
        missing_ranges=collected.missing_ranges,
        missing_from_bag=collected.missing_from_bag,
        summary=job.summary(record, options.skip, ending),
        problems=collected.problems,
        foreign=_added(job.RECORD.foreign(record), collected.refused),
        dropped=job.RECORD.dropped(record),
        lost_with_restarts=collected.lost,
        foreign_publishers=collected.foreign_publishers,
        warnings=collected.warnings,
        rearmed=collected.rearmed,
        error=None if ending.failure is None else ending.failure.detail,
        bag=collected.bag,
        record=record,
    )
    if out.bag is not None:
        sim = job.sim_time
        out.bag['bytes_per_sim_second'] = out.bag['size_bytes'] / sim if sim > 0 else None
    if options.compare_offline and ending.failure is None:
        out.differences = job.RECORD.differences(record, simulate(job))
    return out


def _added(a: dict[str, int], b: dict[str, int]) -> dict[str, int]:
    """Counts per topic of both."""
    return {t: a.get(t, 0) + b.get(t, 0) for t in {**a, **b}}
