"""The record of a realtime run: samples at the drive's own stamps. ROS-free.

On the wall clock the drive stamps each state with its acquisition time, so samples are not
on a grid: sample i is the i-th state stamp at or after the job's start t0 (the trajectory
reports it on /diagnostics), t_i = stamp_i − t0. The reference is the trajectory's points
interpolated at each stamp (mill_common.reference_buffer, as the controllers take it), the
estimate and command are the ones stamped like the state they answer, the ground truth the
one the simulated drive published with it. Latency of a command: its arrival (the
recorder's receive time, where the bag has one) minus the stamp of the state it answers.

Samples missing. A realtime drive sends the state of every axis, and the ground truth, at each
tick with the tick's stamp, and no listener makes it wait: a topic that lacks a tick another of
these topics holds, between its own first and last, lost it on the way to the listener
(`missing_ticks`), as a lockstep record lacks a sample of its grid
(mill_analysis.lockstep_record.build_record). Ticks lost on every one of them at once cannot be
told from ticks the drive skipped (a late timer skips its periods) by the stamps alone.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from itertools import groupby
from math import nan
from typing import Any

import numpy as np
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.types import decode
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AXES, AxisReference
from mill_common.timebase import time_ns
from mill_common.timing import Realtime

from mill_analysis.node_intake import Drops, Intake, arrival_order, subset
from mill_analysis.record import SIGNALS, RunRecord
from mill_common import topics

JOINT_STATE = 'sensor_msgs/msg/JointState'
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'


def _by_stamp(messages: Sequence[Any]) -> dict[int, Any]:
    return {time_ns(msg.header.stamp): msg for msg in messages}


def _taken(
    raw: Mapping[str, Sequence[bytes]], owners: Mapping[str, str]
) -> tuple[dict[str, list[Any]], Drops]:
    """The decoded messages a realtime node would take, per topic, in the order they arrived
    (mill_analysis.node_intake: its sender, its stamp not repeated nor in the past), and
    what was left out."""
    intake = Intake(Realtime(1), owners, stepped=(), history=[topics.REFERENCE])
    out: dict[str, list[Any]] = {t: [] for t in raw}
    for topic, data in arrival_order(raw, list(raw)):
        msg = decode(JOINT_TRAJECTORY if topic == topics.REFERENCE else JOINT_STATE, data)
        ns = time_ns(msg.header.stamp)
        problem = intake.problem(topic, ns, msg.header.frame_id)
        if problem is not None:
            intake.drop(topic, problem)
            continue
        intake.accept(topic, ns)
        out[topic].append(msg)
    return out, intake.drops


def realtime_record(
    raw: Mapping[str, Sequence[bytes]],
    axes: Sequence[str],
    t0: int,
    end_time: float,
    owners: Mapping[str, str] | None = None,
) -> tuple[RunRecord, dict[str, int]]:
    """Samples of the job [t0, t0 + end_time] at the stamps of the first axis's states, and
    per topic the drive sends every tick, the ticks of the job it lacks (`missing_ticks`).

    owners: the node each topic must come from (the drive for the states); what a node would
    drop (another sender, a stamp repeated or in the past) is left out and counted in the
    record's `foreign` and `drops`.
    """
    wanted = [topics.REFERENCE, topics.GROUND_TRUTH]
    wanted += [f(a) for a in axes for f in (topics.state, topics.estimate, topics.joint_command)]
    taken, drops = _taken(subset(raw, wanted), owners or {})
    states = {a: _by_stamp(taken.get(topics.state(a), ())) for a in axes}
    end_ns = t0 + round(end_time * 1e9)
    stamps = sorted(ns for ns in states[axes[0]] if t0 <= ns <= end_ns)
    n = len(stamps)
    rec = RunRecord(
        np.array([(ns - t0) * 1e-9 for ns in stamps]),
        {s: np.full((n, len(AXES)), np.nan) for s in SIGNALS},
    )
    rec.foreign, rec.drops = drops.per_topic(), drops
    sig = rec.signals
    refs = {a: ReferenceBuffer() for a in axes}
    for msg in taken.get(topics.REFERENCE, ()):
        base = time_ns(msg.header.stamp)
        names = list(msg.joint_names)
        for p in msg.points:
            at = base + time_ns(p.time_from_start)
            for a in axes:
                if a in names:
                    j = names.index(a)
                    vel = p.velocities[j] if len(p.velocities) > j else 0.0
                    acc = p.accelerations[j] if len(p.accelerations) > j else 0.0
                    refs[a].add(at, AxisReference(p.positions[j], vel, acc))
    estimates = {a: _by_stamp(taken.get(topics.estimate(a), ())) for a in axes}
    commands = {a: _by_stamp(taken.get(topics.joint_command(a), ())) for a in axes}
    truth = _by_stamp(taken.get(topics.GROUND_TRUTH, ()))
    drive = {topics.state(a): states[a] for a in axes}
    if truth:  # a hardware driver has none
        drive[topics.GROUND_TRUTH] = truth
    missing = missing_ticks(
        {t: [ns for ns in sent if t0 <= ns <= end_ns] for t, sent in drive.items()}
    )
    for k, ns in enumerate(stamps):
        for a in axes:
            i = AXES.index(a)
            state = states[a].get(ns)
            if state is not None and len(state.position):
                sig['position'][k, i] = state.position[0]
            ref = refs[a].at(ns)
            if ref is not None:
                sig['reference'][k, i] = ref.position
                sig['reference_velocity'][k, i] = ref.velocity
            est = estimates[a].get(ns)
            if est is not None and len(est.velocity) and len(est.effort):
                sig['estimate_velocity'][k, i] = est.velocity[0]
                sig['estimate_disturbance'][k, i] = est.effort[0]
            cmd = commands[a].get(ns)
            if cmd is not None and len(cmd.effort):
                sig['torque'][k, i] = cmd.effort[0]
        gt = truth.get(ns)
        if gt is not None:
            for j, name in enumerate(gt.name):
                if name in AXES:
                    sig['true_velocity'][k, AXES.index(name)] = gt.velocity[j]
                    sig['true_disturbance'][k, AXES.index(name)] = gt.effort[j]
    return rec, missing


def missing_ticks(stamps: Mapping[str, Collection[int]]) -> dict[str, int]:
    """Per topic sent at every tick of one clock (topic -> the stamps received), how many
    of the ticks the topics hold together this one lacks between its own first and last:
    before and after them the listener may not have been subscribed yet, or any more (a
    recorder that joins a running graph matches its topics one after the other)."""
    ticks = sorted(set().union(*stamps.values()))
    out = {}
    for topic, got in stamps.items():
        own = set(got)
        if not own:
            out[topic] = 0  # never heard: not subscribed, or not sent at all
            continue
        first, last = bisect_left(ticks, min(own)), bisect_right(ticks, max(own))
        out[topic] = last - first - len(own)
    return out


@dataclass(frozen=True)
class CommandTiming:
    """How the commands of one axis answered the job's states, as one listener received them."""

    unanswered: float  # share of the job's states no command answered
    latency_ms: np.ndarray  # arrival − state stamp of each command answering a job state
    longest_unanswered: int = 0  # most job states in a row that no command answered

    def figures(self) -> dict[str, float]:
        lat = self.latency_ms
        return {
            'late_fraction': self.unanswered,
            'longest_late_run': float(self.longest_unanswered),
            'latency_median_ms': float(np.median(lat)) if lat.size else nan,
            'latency_p99_ms': float(np.percentile(lat, 99)) if lat.size else nan,
            'latency_max_ms': float(lat.max()) if lat.size else nan,
        }


def command_timing(
    rec: RunRecord,
    raw: Mapping[str, Sequence[bytes]],
    arrivals: Mapping[str, Sequence[int | None]],
    axes: Sequence[str],
    t0: int,
) -> dict[str, CommandTiming]:
    """Per axis, from the commands (`raw`) and when each arrived (`arrivals`, system clock
    [ns], None where unknown): the share of the record's states no command answered, and
    the latency of the commands that answer them. Commands outside the job (the hold before
    it, the time a listener took nothing while it ended the run) do not count."""
    states = (t0 + np.round(rec.t * 1e9).astype(np.int64)).tolist()
    job = set(states)
    out = {}
    for axis in axes:
        topic = topics.joint_command(axis)
        stamps = [cdr_stamp_ns(d) for d in raw.get(topic, ())]
        pairs = zip(stamps, arrivals.get(topic, ()), strict=False)
        latency = [(a - s) * 1e-6 for s, a in pairs if s is not None and s in job and a is not None]
        answered = set(stamps)
        missed = [s not in answered for s in states]
        unanswered = float(np.mean(missed)) if states else nan
        out[axis] = CommandTiming(unanswered, np.array(latency), longest_run(missed))
    return out


def longest_run(flags: Sequence[bool]) -> int:
    """The most True values in a row."""
    return max((sum(1 for _ in group) for flag, group in groupby(flags) if flag), default=0)
