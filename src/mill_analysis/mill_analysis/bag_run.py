"""What a bag of a mill run means: its record (lockstep_record, realtime_record), and the
run's job and plant status.

The mill knowledge about bags lives here; the bag format itself is mill_bag (which
knows no mill topic).

`read_run` reads a bag by topic names and types only (the contract of
mill_common.topics): the sample period is the greatest common divisor of the state
stamps and the job length comes from the trajectory's job status on /diagnostics,
so a bag from `ros2 bag record` with these topics works as well as ours. The run may be
under a machine namespace (`/machine2/mill/x/state`): `read_run` finds it from the topic
names, or is told which one when a bag holds several machines; of the shared /diagnostics it
reads only that machine's statuses.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.errors import BagError
from mill_bag.reader import Bag, open_bag
from mill_bag.types import (
    DIAGNOSTIC_ARRAY,
    decode,
)
from mill_common.signals import AXES
from mill_common.timebase import job_steps

from mill_analysis import bag_meta
from mill_analysis.bag_status import job_approach, job_end, job_start, plant_status
from mill_analysis.events import events_of, statuses_of
from mill_analysis.lockstep_record import (
    ProgressCallback,
    record_from_raw,
    record_topics,
)
from mill_analysis.node_intake import ArrivalOrder, Received, drop_lines, subset
from mill_analysis.realtime_record import command_timing, realtime_record
from mill_analysis.record import RunRecord
from mill_common import topics as topic_names

# -- the run in a bag ------------------------------------------------------------------------


@dataclass
class BagRun:
    """What a bag holds of a mill run: its RunRecord and what the report needs besides."""

    bag: Bag
    axes: list[str]
    dt_ns: int
    n: int
    record: RunRecord
    missing: dict[str, int]
    end_time: float | None
    job_end_source: str
    state_wall_ns: np.ndarray | None  # wall time each sample of the first state arrived [ns]
    plant_status: dict[str, str]
    feed_override: list[tuple[int, float]] | None
    message_count: int
    size_bytes: int
    notes: list[str] = field(default_factory=list)
    # A realtime run (the drive's own clock): per axis, the state -> command latency of every
    # command as the recorder received it [ms], the share of states no command answered and
    # the most of them in a row.
    realtime: bool = False
    command_latency_ms: dict[str, np.ndarray] = field(default_factory=dict)
    unanswered: dict[str, float] = field(default_factory=dict)
    longest_unanswered: dict[str, int] = field(default_factory=dict)
    # A realtime job's move from where the axes stood to its path's start [s] (0: none)
    approach: float = 0.0

    @property
    def held(self) -> tuple[int, float]:
        """The samples of the job the bag holds (a state of every axis), and the time of the
        last of them [s] (NaN: none)."""
        pos = self.record['position'][:, [AXES.index(a) for a in self.axes]]
        have = np.flatnonzero(np.isfinite(pos).all(axis=1))
        return len(have), float(self.record.t[have[-1]]) if len(have) else math.nan

    def losses(self) -> list[str]:
        """What the bag lacks: a line per topic with samples missing (which ones, where
        known), and per topic with messages the nodes would drop, left out of the record."""
        return bag_meta.loss_lines(self.missing, self.record.gaps) + drop_lines(
            self.record.drops.reasons()
        )

    def extent(self) -> str:
        """What the bag holds of the job, as `report` says it: '6001 samples', or '2061 of the
        job's 6001 samples, the last at t = 2.060 s of 6.000 s' (a realtime run's samples are
        the drive's ticks the bag holds: '2061 samples, the last at ...')."""
        held, last = self.held
        end = float(self.record.t[-1]) if self.n else math.nan
        if self.realtime and self.end_time is not None:  # samples at the drive's ticks
            end = self.end_time
        if held == self.n and not last < end - 1.5 * self.dt_ns * 1e-9:
            return f'{self.n} samples'
        count = f'{held} samples' if held == self.n else f"{held} of the job's {self.n} samples"
        return f'{count}, the last at t = {last:.3f} s of {end:.3f} s'


def run_namespace(names: Iterable[str], where: str, namespace: str | None = None) -> str:
    """The machine namespace of the mill run among a bag's topic names (BagError if there is
    none, or several and `namespace` does not choose one)."""
    names = list(names)
    found = sorted(
        {ns for a in AXES for ns in topic_names.namespaces_with(names, topic_names.state(a))}
    )
    if namespace is not None:
        try:
            wanted = topic_names.namespace(namespace)
        except ValueError as exc:
            raise BagError(str(exc)) from None
        if wanted not in found:
            raise BagError(
                f'{where} holds no mill run in namespace {wanted} '
                f'(runs in: {", ".join(found) or "none"})'
            )
        return wanted
    if not found:
        present = ', '.join(sorted(names)) or 'none'
        raise BagError(
            f'{where} holds no mill run: no /mill/<axis>/state topic in any namespace '
            f'(sensor_msgs/msg/JointState); its topics: {present}'
        )
    if len(found) > 1:
        raise BagError(
            f'{where} holds runs in several namespaces ({", ".join(found)}); '
            'choose one with --namespace'
        )
    return found[0]


@dataclass
class _Stream:
    """The messages of one topic of a bag, as read."""

    msgtype: str
    data: list[bytes] = field(default_factory=list)
    log_times: list[int] = field(default_factory=list)
    publish_times: list[int | None] = field(default_factory=list)


def read_run(
    path: str | Path,
    namespace: str | None = None,
    progress: ProgressCallback | None = None,
    realtime: bool | None = None,
) -> BagRun:
    """Read a bag of a mill run into a RunRecord, by topic names and types only.

    The sample period is the greatest common divisor of the state stamps; the
    number of samples comes from the trajectory's job status on /diagnostics
    (end_time, as the runner computes it), or, without it, from the last sample
    every state topic has. The run may be in any namespace; `namespace` chooses the
    machine in a bag of several. `progress(phase, done, total)` is called now and then, while
    the bag is read ('reading', messages; total from metadata.yaml, None if it has none)
    and while its messages are decoded ('decoding'). realtime: whether the bag holds a
    realtime run, as it says (mill_analysis.bag_meta); None for a bag that does not say: a
    realtime job's status on /diagnostics tells its start stamp, a lockstep one's does not.
    """
    bag = open_bag(path)
    wanted_types = record_topics(AXES)
    contract = [*wanted_types, topic_names.FEED_OVERRIDE]
    # One pass over the bag: every topic that is a contract topic in some namespace is
    # kept by its absolute name; the namespace is chosen once every name is known.
    kept: dict[str, _Stream | None] = {}
    order: list[str] = []  # the kept topics' names in file order: the order they arrived
    info = (bag.metadata or {}).get('rosbag2_bagfile_information') or {}
    expected = info.get('message_count') if isinstance(info, dict) else None
    all_statuses: list[Any] = []
    read = 0
    for name, msgtype, log_time, publish_time, data in bag.read():
        read += 1
        if progress is not None and read % 20_000 == 0:
            progress('reading', read, expected)
        if name == topic_names.DIAGNOSTICS:
            if msgtype == DIAGNOSTIC_ARRAY:
                all_statuses.append(decode(msgtype, data))
            continue
        if name not in kept:
            ours = any(topic_names.namespaces_with([name], t) for t in contract)
            kept[name] = _Stream(msgtype) if ours else None
        stream = kept[name]
        if stream is not None:
            stream.data.append(data)
            stream.log_times.append(log_time)
            stream.publish_times.append(publish_time)
            order.append(name)
    if progress is not None:
        progress('reading', read, expected)
    total = sum(bag.counts.values())
    if total == 0:
        raise BagError(f'{bag.path} holds no messages')
    ns = run_namespace(bag.counts, str(bag.path), namespace)
    raw = Received()
    relative: dict[str, str] = {}
    walls: dict[str, list[int | None]] = {}  # publish times of the state messages
    for topic, msgtype in wanted_types.items():
        name = topic_names.qualify(topic, ns)
        stream = kept.get(name)
        if stream is None:
            continue
        if stream.msgtype != msgtype:
            raise BagError(
                f'{bag.path}: topic {name} has type {stream.msgtype}, expected {msgtype}'
            )
        raw[topic] = stream.data
        relative[name] = topic
        walls[topic] = stream.publish_times
    raw.order = ArrivalOrder(relative[name] for name in order if name in relative)
    feed_stream = kept.get(topic_names.qualify(topic_names.FEED_OVERRIDE, ns))
    feed = (
        []
        if feed_stream is None
        else list(zip(feed_stream.log_times, feed_stream.data, strict=True))
    )
    feed_type = '' if feed_stream is None else feed_stream.msgtype
    statuses = []
    for array in all_statuses:
        array.status = [s for s in array.status if topic_names.from_machine(s.hardware_id, ns)]
        statuses.append(array)
    axes = [a for a in AXES if topic_names.state(a) in raw]
    if not axes:
        raise BagError(f'{bag.path}: no message on the state topics of namespace {ns}')
    first = topic_names.state(axes[0])
    first_stamps = [cdr_stamp_ns(d) for d in raw[first]]
    stamps = np.array(sorted({s for s in first_stamps if s is not None}), dtype=np.int64)
    start_ns = job_start(statuses)
    if realtime is None:
        realtime = start_ns is not None
    if realtime:  # the drive's own clock: no sample grid
        if start_ns is None:
            raise BagError(
                f'{bag.path}: a realtime run without its start (no start_stamp_ns in the '
                'job status on /diagnostics)'
            )
        owners = bag_meta.owners(bag.custom_data, ns)
        run = _realtime_run(bag, axes, raw, walls, statuses, start_ns, stamps, total, owners)
        # What the machine told (trips, stops, brakes), as the runner takes it
        run.record.events = events_of(statuses_of(statuses), start_ns, counted_from=start_ns)
        run.approach = job_approach(statuses)
        return run
    diffs = np.diff(stamps)
    dt_ns = int(np.gcd.reduce(diffs[diffs > 0])) if (diffs > 0).any() else 0
    if dt_ns <= 0:
        raise BagError(f'{bag.path}: fewer than two samples on {first}')
    notes = []
    end_time, source = job_end(statuses)
    if end_time is not None:
        n = job_steps(end_time, dt_ns)
    else:
        last = min(max(cdr_stamp_ns(d) or 0 for d in raw[topic_names.state(a)]) for a in axes)
        n = last // dt_ns + 1
        source = 'last sample of every state topic (no job status on /diagnostics)'
        notes.append('no job status on /diagnostics: every sample up to the last state is used')
    listened = subset(raw, record_topics(axes))
    owners = bag_meta.owners(bag.custom_data, ns)
    record, missing = record_from_raw(listened, wanted_types, axes, n, dt_ns, progress, owners)
    record.events = events_of(statuses_of(statuses))  # as the runner takes them
    # Wall-clock arrival of each sample of the first axis, where the storage has
    # a wall time besides the (sim) stamp: our recorder's and rosbag2's publish_time.
    wall = None
    pairs = [(s, w) for s, w in zip(first_stamps, walls[first], strict=True) if s is not None]
    if pairs and any(w is not None and w != s for s, w in pairs):
        by_stamp = {s: w for s, w in pairs if w is not None}
        wall = np.array([by_stamp.get(k * dt_ns, -1) for k in range(n)], dtype=np.int64)
    if bag.cut_short:
        notes.append(
            f'the recording was cut short ({bag.cut_short}): the bag holds what was written '
            'up to its last complete flush'
        )
    elif bag.truncated:
        notes.append(
            'the bag was not closed (recorder killed?): read up to its last complete chunk'
        )
    feed_values = _feed_values(feed_type, feed, notes) if feed else None
    size = sum(f.stat().st_size for f in bag.files)
    return BagRun(
        bag=bag,
        axes=axes,
        dt_ns=dt_ns,
        n=n,
        record=record,
        missing={t: m for t, m in missing.items() if m},
        end_time=end_time,
        job_end_source=source,
        state_wall_ns=wall,
        plant_status=plant_status(statuses),
        feed_override=feed_values,
        message_count=total,
        size_bytes=size,
        notes=notes,
    )


def _realtime_run(
    bag: Bag,
    axes: list[str],
    raw: Mapping[str, Sequence[bytes]],
    walls: dict[str, list[int | None]],
    statuses: list[Any],
    start_ns: int,
    stamps: np.ndarray,
    total: int,
    owners: Mapping[str, str],
) -> BagRun:
    """A realtime run's record at the drive's stamps, and the commands' timing."""
    end_time, source = job_end(statuses)
    if end_time is None:
        end_time = (int(stamps[-1]) - start_ns) * 1e-9
    record, missing = realtime_record(raw, axes, start_ns, end_time, owners)
    timing = command_timing(record, raw, walls, axes, start_ns)
    latency = {axis: t.latency_ms for axis, t in timing.items()}
    unanswered = {axis: t.unanswered for axis, t in timing.items()}
    diffs = np.diff(stamps)
    dt_ns = int(np.median(diffs)) if diffs.size else 0
    notes = ["realtime run: samples at the drive's stamps, the reference interpolated there"]
    # A bag that ends before the job (a recorder killed): the drive's ticks after its last
    # state are in no topic, which `realtime_record` cannot see; counted at the drive's rate.
    last_ns = int(stamps[-1]) if stamps.size else start_ns
    tail = (start_ns + round(end_time * 1e9) - last_ns) // dt_ns if dt_ns else 0
    if tail > 1:
        missing = {t: m + tail for t, m in missing.items()}
        notes.append(
            f"the bag ends at t = {(last_ns - start_ns) * 1e-9:.3f} s of the job's "
            f'{end_time:.3f} s: about {tail} samples of every topic are not in it'
        )
    return BagRun(
        bag=bag,
        axes=axes,
        dt_ns=dt_ns,
        n=len(record.t),
        record=record,
        missing={t: m for t, m in missing.items() if m},
        end_time=end_time,
        job_end_source=source,
        state_wall_ns=None,
        plant_status=plant_status(statuses),
        feed_override=None,
        message_count=total,
        size_bytes=sum(f.stat().st_size for f in bag.files),
        notes=notes,
        realtime=True,
        command_latency_ms=latency,
        unanswered=unanswered,
        longest_unanswered={axis: t.longest_unanswered for axis, t in timing.items()},
    )


def _feed_values(msgtype: str, feed: list, notes: list[str]) -> list[tuple[int, float]]:
    """(log time, override) of each override sent; a stamped answer repeated for a
    re-offered sample (the force controller answers step 0 as often as the plant offers
    it) is one override, not several."""
    out = []
    last_stamp: int | None = None
    for log_time, data in feed:
        try:
            msg = decode(msgtype, data)
        except Exception:
            notes.append(f'{topic_names.FEED_OVERRIDE}: cannot decode type {msgtype}')
            return []
        stamp = cdr_stamp_ns(data) if hasattr(msg, 'header') else None
        if stamp is not None and stamp == last_stamp:
            continue
        last_stamp = stamp
        value = getattr(msg, 'data', None)
        if value is None and len(getattr(msg, 'position', ())):
            value = msg.position[0]  # sensor_msgs/JointState, the contract's type
        if value is None:
            notes.append(f'{topic_names.FEED_OVERRIDE}: type {msgtype} has no numeric data')
            return []
        out.append((log_time, float(value)))
    return out
