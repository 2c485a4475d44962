"""The record of a lockstep run: its messages -> RunRecord on the sample grid. ROS-free.

`build_record` is the one place where a lockstep run's messages become signals: the
runner's monitor (live, `record_from_raw` on the serialized messages it kept) and
mill_analysis.bag_run (a bag, for `report`) both call it, with the same `summarize` after it,
so the runner's summary and the report of its bag agree exactly. A realtime run's record:
mill_analysis.realtime_record.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from mill_bag.types import (
    JOINT_STATE,
    JOINT_TRAJECTORY,
    WRENCH_STAMPED,
    decode,
)
from mill_common.checks import Rejected, joint_values, point_values
from mill_common.signals import AXES
from mill_common.timebase import time_ns
from mill_common.timing import Lockstep

from mill_analysis.node_intake import Intake, arrival_order
from mill_analysis.record import RunRecord
from mill_common import topics as topic_names

# progress(phase, done, total): how far reading or decoding a bag has got (total None: unknown)
ProgressCallback = Callable[[str, int, int | None], None]


def record_topics(axes: Sequence[str]) -> dict[str, str]:
    """Topics (and types) a RunRecord is built from."""
    out = {}
    for axis in axes:
        out[topic_names.state(axis)] = JOINT_STATE
        out[topic_names.estimate(axis)] = JOINT_STATE
        out[topic_names.joint_command(axis)] = JOINT_STATE
    out[topic_names.REFERENCE] = JOINT_TRAJECTORY
    out[topic_names.GROUND_TRUTH] = JOINT_STATE
    out[topic_names.CUTTING_FORCE] = WRENCH_STAMPED
    return out


def build_record(
    messages: Iterable[tuple[str, Any]],
    axes: Sequence[str],
    n: int,
    dt_ns: int,
    listened: Iterable[str],
    owners: Mapping[str, str] | None = None,
) -> tuple[RunRecord, dict[str, int]]:
    """Decoded messages (topic, message), in the order one listener received them ->
    RunRecord of n samples at t = k T.

    The one place where messages become signals: the runner's monitor and the bag reader
    both call it. Each message goes through the nodes' checks (mill_analysis.node_intake:
    its sender against `owners` {topic: node}, its stamp as the lockstep timing takes it,
    its content as the node reading the topic takes it: the joint there, the arrays long
    enough, the values finite, the reference's points on the grid; a command's NaN is a
    brake request and kept); what a node would drop is left out, counted in the record's
    `foreign` and, with its reason, in `drops`. A message belongs to sample k when its stamp
    is k T (0 <= k < n); of a sample offered again the first message counts, as the nodes
    take the first. Also returns, per listened topic, how many of the n samples are missing
    (the reference: samples no point of it covers); the record's `gaps` say which.
    """
    owners = owners or {}
    listened = list(listened)
    ref_topic = topic_names.REFERENCE
    rec = RunRecord.empty(n, dt_ns / 1e9)
    s = rec.signals
    # The samples each topic gave, as flags (a set of ints costs ~60 bytes a sample)
    seen: dict[str, np.ndarray] = {t: np.zeros(n, dtype=bool) for t in listened}
    position, torque, force = s['position'], s['torque'], s['force']
    est_v, est_d = s['estimate_velocity'], s['estimate_disturbance']
    ref_p, ref_v = s['reference'], s['reference_velocity']
    true_v, true_d = s['true_velocity'], s['true_disturbance']

    def checked(msg, i, fields):  # what the node of the topic would take, or Rejected
        return joint_values(msg.name, {f: getattr(msg, f) for f in fields}, AXES[i], fields)

    # Each handler checks a message's content as the node reading the topic does: Rejected,
    # or how to put its values into sample k once its stamp is taken.
    def on_state(msg, i):
        got = checked(msg, i, ('position',))
        if isinstance(got, Rejected):
            return got

        def put(k):
            position[k, i] = got[0]

        return put

    def on_estimate(msg, i):
        got = checked(msg, i, ('position', 'velocity', 'effort'))
        if isinstance(got, Rejected):
            return got

        def put(k):
            est_v[k, i], est_d[k, i] = got[1], got[2]

        return put

    def on_command(msg, i):
        got = checked(msg, i, ('effort',))
        if isinstance(got, Rejected) and not got.non_finite:
            return got
        value = math.nan if isinstance(got, Rejected) else got[0]  # NaN: a brake request

        def put(k):
            torque[k, i] = value

        return put

    def on_truth(msg, _i):
        try:
            rows = [
                (AXES.index(name), msg.velocity[j], msg.effort[j])
                for j, name in enumerate(msg.name)
            ]
        except (IndexError, ValueError):
            return Rejected(f'ground truth of joints {list(msg.name)} without their values')

        def put(k):
            for i, v, d in rows:
                true_v[k, i], true_d[k, i] = v, d

        return put

    def on_force(msg, _i):
        f = msg.wrench.force

        def put(k):
            force[k] = (f.x, f.y, f.z)

        return put

    def on_reference(msg, _i):
        # all points checked before any is used, as the controllers do
        values = []
        for point in msg.points:
            offset = time_ns(point.time_from_start)
            if offset % dt_ns:
                return Rejected(f'a point at {offset} ns is off the grid')
            arrays = {
                'positions': point.positions,
                'velocities': point.velocities,
                'accelerations': point.accelerations,
            }
            got = point_values(
                msg.joint_names, arrays, axes, ['positions'], ['velocities', 'accelerations']
            )
            if isinstance(got, Rejected):
                return got
            values.append((offset // dt_ns, got['positions'], got['velocities']))
        covered = seen.get(ref_topic)

        def put(k):
            for offset, pos, vel in values:
                kp = k + offset
                if 0 <= kp < n:
                    for axis, p_i, v_i in zip(axes, pos, vel, strict=True):
                        i = AXES.index(axis)
                        ref_p[kp, i], ref_v[kp, i] = p_i, v_i
                    if covered is not None:
                        covered[kp] = True

        return put

    handlers: dict[str, tuple] = {
        topic_names.GROUND_TRUTH: (on_truth, None),
        topic_names.CUTTING_FORCE: (on_force, None),
        ref_topic: (on_reference, None),
    }
    for axis in axes:
        i = AXES.index(axis)
        handlers[topic_names.state(axis)] = (on_state, i)
        handlers[topic_names.estimate(axis)] = (on_estimate, i)
        handlers[topic_names.joint_command(axis)] = (on_command, i)
    intake = Intake(
        Lockstep(dt_ns), owners, [t for t in handlers if t != ref_topic], history=[ref_topic]
    )
    for topic, msg in messages:
        handler = handlers.get(topic)
        if handler is None:
            continue
        ns = time_ns(msg.header.stamp)
        problem = intake.problem(topic, ns, msg.header.frame_id)
        if problem is None:
            try:
                put = handler[0](msg, handler[1])
            except (IndexError, ValueError) as exc:
                put = Rejected(f'malformed: {exc}')
            problem = put if isinstance(put, Rejected) else None
        if problem is not None:
            intake.drop(topic, problem)
            continue
        if topic == ref_topic and not len(msg.points):
            continue  # nothing in it (the controllers take nothing from it either)
        if intake.again(topic, ns):
            continue  # the sample offered again: the first message counts
        intake.accept(topic, ns)
        k = ns // dt_ns
        if 0 <= k < n:
            put(k)
            if topic in seen and topic != ref_topic:
                seen[topic][k] = True
    rec.foreign = intake.drops.per_topic()
    rec.drops = intake.drops
    missing = {t: n - int(np.count_nonzero(ks)) for t, ks in seen.items()}
    rec.gaps = {t: missing_runs(ks) for t, ks in seen.items() if missing[t]}
    return rec, missing


def missing_runs(have: np.ndarray) -> list[tuple[int, int]]:
    """The samples whose flag is False, as (first, last) of each run of them (what
    bag_meta.missing_ranges says of the samples that are True)."""
    edges = np.diff(np.concatenate(([0], (~have).astype(np.int8), [0])))
    firsts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(int(a), int(b) - 1) for a, b in zip(firsts, ends, strict=True)]


def record_from_raw(
    raw: Mapping[str, Sequence[bytes]],
    types: Mapping[str, str],
    axes: Sequence[str],
    n: int,
    dt_ns: int,
    progress: ProgressCallback | None = None,
    owners: Mapping[str, str] | None = None,
) -> tuple[RunRecord, dict[str, int]]:
    """Serialized messages per topic -> decode -> build_record, in the order they arrived
    (`Received`; a plain mapping: each topic after the one before); what the monitor and the
    bag reader both call. `progress('decoding', done, total)` is called now and then with the
    number of messages decoded."""
    listened = list(raw)
    total = sum(len(raw[t]) for t in listened)
    messages: Iterable[tuple[str, Any]] = (
        (t, decode(types[t], d)) for t, d in arrival_order(raw, listened)
    )
    if progress is not None:
        messages = _counted(messages, lambda done: progress('decoding', done, total))
    return build_record(messages, axes, n, dt_ns, listened, owners)


def _counted(items: Iterable[Any], report: Callable[[int], None], every: int = 20_000):
    """The items, calling report(count so far) every `every` items and at the end."""
    count = 0
    for count, item in enumerate(items, 1):
        if count % every == 0:
            report(count)
        yield item
    report(count)
