"""The record of one cutting-force job (Rubio 2013) and its continuous-time cost. ROS-free.

Samples k = 0..n−1 (t_k = kT, T one spindle revolution) and the force stream over the job.
The offline loop fills every field; a distributed run or a bag fills what travels on the
topics (no applied feed, no per-sample cost) and J_c comes from the recorded stream:

    J_c = Σ_j ∫ (F_p(τ) − F_pm(τ))² dτ [N²·s]        (Rubio 2013 eq. (14))

F_pm the continuous response of the reference model eq. (7) to the reference step at t = 0,
integrated by Simpson's rule on each smooth piece of the stream (the plant repeats a point
where the force jumps or kinks: a depth change, a clamp corner, a sample boundary).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_bag.types import DIAGNOSTIC_ARRAY, decode
from mill_common.timebase import sample_stamp_ns, time_ns
from mill_models.quadrature import simpson
from mill_models.reference_model import ContinuousReference

from mill_analysis.bag_meta import missing_ranges
from mill_analysis.events import Event
from mill_common import topics

# /mill/force_control/state: force used, reference, feed command, override, active β, depth
STATE_FIELDS = ('force', 'reference', 'feed_command', 'override', 'beta', 'depth')


def _nan(n: int) -> np.ndarray:
    return np.full(n, np.nan)


@dataclass
class ForceRecord:
    """One force job, sample by sample, and the force between samples."""

    t: np.ndarray
    reference: np.ndarray  # F_r [N]
    force: np.ndarray  # force the law used at t_k [N] (the last finite one)
    feed_command: np.ndarray  # the law's f_c,k [mm/s]
    override: np.ndarray  # applied override o_k [-]
    slope: np.ndarray  # its β-hold slope over [t_k, t_k+1) [1/s]
    beta: np.ndarray  # active β over [t_k, t_k+1)
    depth: np.ndarray  # a_dc(t_k) [mm]
    feed: np.ndarray | None = None  # applied feed [mm/s] (offline only)
    interval_cost: np.ndarray | None = None  # ∫ over [t_k, t_k+1) of (F_p − F_pm)² (offline)
    measured: np.ndarray | None = None  # F_p(t_k) as the plant measured it [N]
    trace_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    trace_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    fine: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)
    held_samples: int = 0
    j_c: float = math.nan
    gaps: dict[str, list[tuple[int, int]]] = field(default_factory=dict)  # missing, per topic
    events: list[Event] = field(default_factory=list)  # what the machine told (events)

    @classmethod
    def empty(cls, n: int, period: float) -> ForceRecord:
        arrays: dict[str, Any] = {name: _nan(n) for name in STATE_FIELDS}
        return cls(t=np.arange(n) * period, **arrays, slope=_nan(n))

    def fine_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, F_p, F_pm) on the J_c grid (offline, with keep_trace)."""
        if not self.fine:
            return np.zeros(0), np.zeros(0), np.zeros(0)
        t, f, fm = (np.concatenate([p[i] for p in self.fine]) for i in range(3))
        return t, f, fm


def smooth_pieces(stamps_ns: np.ndarray, values: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split a force stream where a point is repeated (stamps at most 1 ns apart)."""
    stamps_ns = np.asarray(stamps_ns, dtype=np.int64)
    values = np.asarray(values, dtype=float)
    cuts = np.flatnonzero(np.diff(stamps_ns) <= 1) + 1
    pieces = []
    for s, v in zip(np.split(stamps_ns, cuts), np.split(values, cuts), strict=True):
        if len(s) >= 2:
            pieces.append((s / 1e9, v))
    return pieces


def continuous_cost(
    stamps_ns: np.ndarray,
    forces: np.ndarray,
    reference_force: float,
    damping: float,
    omega_n: float,
) -> float:
    """Rubio 2013 eq. (14) from a recorded force stream [N²·s] (see the module doc)."""
    # Rubio 2013 eq. (14): J_c = Σ_j ∫_{(j−1)T}^{jT} (F_p(τ) − F_pm(τ))² dτ
    f_ref = ContinuousReference(damping, omega_n)
    f_ref.reset(0.0, 0.0)
    f_ref.begin(reference_force)
    total = 0.0
    for times, force in smooth_pieces(stamps_ns, forces):
        total += simpson(times, (force - f_ref.values(times)) ** 2)
    return total


JOINT_STATE_TYPE = 'sensor_msgs/msg/JointState'
FORCE_TOPICS = {
    topics.CUTTING_FORCE: 'geometry_msgs/msg/WrenchStamped',
    topics.CUTTING_FORCE_TRACE: 'trajectory_msgs/msg/JointTrajectory',
    topics.FEED_OVERRIDE: 'sensor_msgs/msg/JointState',
    topics.FORCE_CONTROL_STATE: 'sensor_msgs/msg/JointState',
}


def record_from_messages(
    raw: Mapping[str, Sequence[bytes]],
    n: int,
    period: float,
    feed_axis: str,
    tolerance_ns: int = 0,
) -> tuple[ForceRecord, dict[str, int]]:
    """Serialized force-job messages -> record of samples 0..n−1 and its force stream.

    A message belongs to sample k when its stamp is sample_stamp_ns(k, T) (to tolerance_ns,
    for a period estimated from a bag's stamps); the stream keeps the trace points up to
    the end of the last sample. Also returns, per topic, how many samples are missing.
    """
    rec = ForceRecord.empty(n, period)
    index = {}
    for d in sorted(range(-tolerance_ns, tolerance_ns + 1), key=abs, reverse=True):
        index.update({sample_stamp_ns(k, period) + d: k for k in range(n)})
    seen: dict[str, set[int]] = {t: set() for t in FORCE_TOPICS}
    measured = _nan(n)
    end_ns = sample_stamp_ns(n, period) + tolerance_ns
    trace: list[tuple[int, float]] = []
    for topic, msgtype in FORCE_TOPICS.items():
        for data in raw.get(topic, ()):
            msg = decode(msgtype, data)
            ns = time_ns(msg.header.stamp)
            k = index.get(ns)
            if topic == topics.CUTTING_FORCE_TRACE:
                if k is not None:
                    seen[topic].add(k)
                for p in msg.points:
                    at = ns + time_ns(p.time_from_start)
                    if at <= end_ns:
                        trace.append((at, float(p.positions[0])))
                continue
            if k is None:
                continue
            seen[topic].add(k)
            if topic == topics.CUTTING_FORCE:
                measured[k] = float(getattr(msg.wrench.force, feed_axis))
            elif topic == topics.FEED_OVERRIDE:
                rec.override[k] = msg.position[0]
                rec.slope[k] = msg.velocity[0] if len(msg.velocity) else 0.0
            else:
                values = dict(zip(STATE_FIELDS, msg.position, strict=False))
                for name in ('force', 'reference', 'feed_command', 'beta', 'depth'):
                    getattr(rec, name)[k] = values.get(name, math.nan)
    trace.sort(key=lambda p: p[0])  # stable: a repeated time keeps its left value first
    rec.measured = measured
    rec.trace_ns = np.array([p[0] for p in trace], dtype=np.int64)
    rec.trace_force = np.array([p[1] for p in trace])
    missing = {t: n - len(ks) for t, ks in seen.items()}
    rec.gaps = {t: missing_ranges(ks, n) for t, ks in seen.items() if len(ks) < n}
    return rec, {t: m for t, m in missing.items() if m}


# -- a force job in a bag (`report`) ----------------------------------------------------------


@dataclass
class ForceBagRun:
    """What a bag holds of a force job: its record, J_c and how they were found."""

    path: str
    record: ForceRecord
    period: float  # one sample, from the force stamps [s]
    samples: int
    reference_force: float  # [N]
    damping: float  # ξ of the reference model eq. (7)
    omega_n: float  # its ω_n [rad/s]
    missing: dict[str, int]
    message_count: int
    notes: list[str] = field(default_factory=list)

    @property
    def held(self) -> int:
        """The samples of the job the bag holds (a force sample each)."""
        measured = self.record.measured
        return 0 if measured is None else int(np.isfinite(measured).sum())


def is_force_bag(counts: Mapping[str, int]) -> bool:
    """A force job's bag: the force stream and the force controller's state, in a namespace."""
    return bool(
        set(topics.namespaces_with(counts, topics.CUTTING_FORCE_TRACE))
        & set(topics.namespaces_with(counts, topics.FORCE_CONTROL_STATE))
    )


def read_force_run(path: str | Path, namespace: str | None = None) -> ForceBagRun:
    """J_c and the record of a force job from its bag, by topic names and types only.

    The sample period is estimated from the force stamps (sample k stamped at the ns nearest
    k T); the number of samples comes from the trajectory's job status on /diagnostics (its
    end_time, the job's duration), or, without it, from the last override; the reference
    force and the reference model (ξ, ω_n) from mill/force_control/state. The job may run in
    any namespace; `namespace` chooses one where the bag holds several.
    """
    bag = open_bag(path)
    by_name: dict[str, list[tuple[str, bytes]]] = {}
    statuses: list[Any] = []
    for topic, msgtype, _log, _pub, data in bag.read():
        if topic == topics.DIAGNOSTICS and msgtype == DIAGNOSTIC_ARRAY:
            statuses.append(decode(msgtype, data))
        else:
            by_name.setdefault(topic, []).append((msgtype, data))
    found = topics.namespaces_with(by_name, topics.CUTTING_FORCE_TRACE)
    if namespace is not None:
        found = [ns for ns in found if ns == topics.namespace(namespace)]
    if len(found) != 1:
        where = ', '.join(found) or 'none'
        raise BagError(
            f'{bag.path}: one force job wanted, found it in namespaces: {where} '
            '(choose one with --namespace)'
        )
    ns = found[0]
    raw: dict[str, list[bytes]] = {t: [] for t in FORCE_TOPICS}
    for topic, msgtype in FORCE_TOPICS.items():
        for got, data in by_name.get(topics.qualify(topic, ns), ()):
            if got != msgtype:
                raise BagError(
                    f'{bag.path}: topic {topics.qualify(topic, ns)} has type {got}, '
                    f'expected {msgtype}'
                )
            raw[topic].append(data)
    end_time = None
    for array in statuses:
        for status in array.status:
            values = {kv.key: kv.value for kv in status.values}
            if (
                end_time is None
                and topics.part_of(status.name) == topics.JOB_STATUS
                and 'end_time' in values
                and topics.from_machine(status.hardware_id, ns)
            ):
                end_time = float(values['end_time'])
    if not raw[topics.CUTTING_FORCE] or not raw[topics.CUTTING_FORCE_TRACE]:
        raise BagError(f'{bag.path} holds no force job: no force samples or force stream')
    stamps = np.array(sorted({cdr_stamp_ns(d) or 0 for d in raw[topics.CUTTING_FORCE]}))
    if stamps.size < 3:
        raise BagError(f'{bag.path}: fewer than three force samples')
    # k T to the nearest ns: k from a first guess, then the least-squares T through 0.
    k = np.rint(stamps / np.median(np.diff(stamps))).astype(float)
    period = float(np.sum(k * stamps) / np.sum(k * k)) / 1e9
    notes = []
    if end_time is not None:
        n = max(1, math.ceil(end_time / period - 1e-9))
    else:
        n = len({cdr_stamp_ns(d) for d in raw[topics.FEED_OVERRIDE]})
        notes.append('no job status on /diagnostics: the samples are those with an override')
    forces = [
        decode(FORCE_TOPICS[topics.CUTTING_FORCE], d).wrench.force
        for d in raw[topics.CUTTING_FORCE]
    ]
    feed_axis = max('xyz', key=lambda a: sum(abs(getattr(f, a)) for f in forces))
    rec, missing = record_from_messages(raw, n, period, feed_axis, tolerance_ns=1)
    state = decode(JOINT_STATE_TYPE, raw[topics.FORCE_CONTROL_STATE][0])
    values = dict(zip(state.name, state.position, strict=False))
    reference = float(values.get('reference', math.nan))
    if 'model_damping' in values and 'model_natural_frequency' in values:
        damping, omega_n = values['model_damping'], values['model_natural_frequency']
    else:
        # Rubio 2013 §2.3 defaults: ξ = 0.7, rise time of three samples, ω_n = 2.5/T_r
        damping, omega_n = 0.7, 2.5 / (3.0 * period)
        notes.append(
            'the force controller did not publish its reference model: J_c uses the '
            'defaults ξ = 0.7, ω_n = 2.5/(3T)'
        )
    rec.j_c = continuous_cost(rec.trace_ns, rec.trace_force, reference, damping, omega_n)
    if bag.truncated:
        notes.append('the bag was not closed: read up to its last complete chunk')
    return ForceBagRun(
        str(bag.path),
        rec,
        period,
        n,
        reference,
        float(damping),
        float(omega_n),
        missing,
        sum(bag.counts.values()),
        notes,
    )
