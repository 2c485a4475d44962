"""Checks every incoming message passes before a node uses it. ROS-free.

A node never lets a bad message reach its core: it takes the values it needs out of a
message with `joint_values` (the joint must be named, the arrays long enough, the values
finite), checks the stamp with a `StampCheck` (on the sample grid in lockstep, newer than
the last accepted) and `ahead` (not later than the plant can be) and the sender with
`owner_check`.
Each failure is a `Rejected` with a one-line reason; the node drops the message, counts it
(`DropCounter`) and reports it, rate-limited, on /diagnostics — it never crashes and never
waits for a message that can never come.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

# Lockstep: the most a reference message may lead the newest state a node has: the
# trajectory's preview_time (at most 10 s) plus the plant's clock_period (at most 10 s).
REFERENCE_LEAD_NS = 20_000_000_000


@dataclass(frozen=True)
class Rejected:
    """Why a message was dropped, in one line.

    non_finite: the joint and its entry are there but the value is not finite (a command's
    NaN is its sender's brake request, not a malformed message).
    """

    reason: str
    non_finite: bool = False


def joint_values(
    names: Sequence[str],
    arrays: Mapping[str, Sequence[float]],
    joint: str,
    fields: Sequence[str],
) -> tuple[float, ...] | Rejected:
    """The values of `joint` in the named arrays of a JointState-like message.

    The joint must appear in `names`, each array in `fields` must have an entry for it,
    and every entry must be finite.
    """
    names = list(names)
    if joint not in names:
        return Rejected(f'no joint {joint!r} in name {names}')
    i = names.index(joint)
    out = []
    for name in fields:
        values = arrays[name]
        if len(values) <= i:
            return Rejected(f'{name} has {len(values)} entries, joint {joint!r} needs {i + 1}')
        v = float(values[i])
        if not math.isfinite(v):
            return Rejected(f'{name} of joint {joint!r} is {v}', non_finite=True)
        out.append(v)
    return tuple(out)


def point_values(
    joint_names: Sequence[str],
    point: Mapping[str, Sequence[float]],
    joints: Sequence[str],
    required: Sequence[str],
    optional: Sequence[str] = (),
) -> dict[str, tuple[float, ...]] | Rejected:
    """Values of `joints` in one trajectory point (arrays in the order of `joint_names`).

    Every joint must be named; `required` arrays must hold all of them, finite;
    `optional` arrays may be empty (then zeros) but, if given, must be complete and finite.
    """
    names = list(joint_names)
    missing = [j for j in joints if j not in names]
    if missing:
        return Rejected(f'no joint {missing[0]!r} in joint_names {names}')
    index = [names.index(j) for j in joints]
    out: dict[str, tuple[float, ...]] = {}
    for name in (*required, *optional):
        values = point[name]
        if not len(values) and name in optional:
            out[name] = tuple(0.0 for _ in joints)
            continue
        if len(values) < len(names):
            return Rejected(f'{name} has {len(values)} entries for {len(names)} joint names')
        picked = tuple(float(values[i]) for i in index)
        bad = [v for v in picked if not math.isfinite(v)]
        if bad:
            return Rejected(f'{name} holds {bad[0]}')
        out[name] = picked
    return out


def axis_points(
    joint_names: Sequence[str], points: Sequence[Any], joint: str
) -> list[tuple[float, float, float]] | Rejected:
    """(position, velocity, acceleration) of `joint` in every point of a trajectory message,
    checked as `point_values` checks one point (positions required; velocities and
    accelerations may be empty: zeros). The joint is looked up once per message: a
    controller reads every point of every reference message."""
    names = list(joint_names)
    if joint not in names:
        return Rejected(f'no joint {joint!r} in joint_names {names}')
    i, n = names.index(joint), len(names)
    out = []
    isfinite = math.isfinite
    for p in points:
        values = []
        for name, array in (
            ('positions', p.positions),
            ('velocities', p.velocities),
            ('accelerations', p.accelerations),
        ):
            if not len(array) and name != 'positions':
                values.append(0.0)
                continue
            if len(array) < n:
                return Rejected(f'{name} has {len(array)} entries for {n} joint names')
            v = float(array[i])
            if not isfinite(v):
                return Rejected(f'{name} holds {v}')
            values.append(v)
        out.append((values[0], values[1], values[2]))
    return out


@dataclass
class StampCheck:
    """Sane stamps on one input.

    period_ns: the sample grid in lockstep (stamps must be whole multiples), None in real
    time. A stamp older than the newest accepted one is in the past; the same stamp again
    is a repeat (the caller decides whether a repeat of identical content is harmless).
    """

    period_ns: int | None
    newest: int | None = None

    def check(self, ns: int) -> Rejected | None:
        if ns < 0:
            return Rejected(f'negative stamp {ns} ns')
        problem = off_grid(ns, self.period_ns)
        if problem is not None:
            return problem
        if self.newest is not None and ns < self.newest:
            return Rejected(
                f'stamp {ns / 1e9:.6f} s is in the past (newest {self.newest / 1e9:.6f} s)'
            )
        return None

    def accept(self, ns: int) -> None:
        if self.newest is None or ns > self.newest:
            self.newest = ns

    def is_repeat(self, ns: int) -> bool:
        return self.newest is not None and ns == self.newest


def off_grid(ns: int, period_ns: int | None) -> Rejected | None:
    """A stamp that is not a whole multiple of the sample period (None: no grid)."""
    if period_ns is not None and ns % period_ns:
        return Rejected(f'stamp {ns / 1e9:.9f} s is off the sample grid of {period_ns / 1e6:g} ms')
    return None


def ahead(ns: int, newest_state: int | None, lead_ns: int) -> Rejected | None:
    """Lockstep: a stamp later than the plant can be.

    The plant publishes step k + 1 only after every node answered step k, so nothing a node
    receives can be stamped more than `lead_ns` after the newest state it has accepted (one
    period for states, estimates and commands; REFERENCE_LEAD_NS for the reference). Before
    the first state (a node that starts or restarts) anything goes.
    """
    if newest_state is None or ns <= newest_state + lead_ns:
        return None
    return Rejected(
        f'stamp {ns / 1e9:.6f} s is ahead of the plant (newest state {newest_state / 1e9:.6f} s)'
    )


def owner_check(frame_id: str, owner: str) -> Rejected | None:
    """The sender named in header.frame_id must be the input's owner ('' owner: anyone).

    frame_id is only what the sender says of itself (a bag's messages carry nothing else);
    a live node identifies the sender by its publisher GID (`Sender`, below)."""
    if not owner or frame_id == owner:
        return None
    return Rejected(f'sent by {frame_id or "an unnamed publisher"!r}, not by its owner {owner!r}')


# What the ROS graph says of a message's publisher (mill_common.graph_owner finds it from
# the publisher GID the message arrived with): the verdicts of `Sender`.
OWNER = 'owner'  # an endpoint of the expected node, the only node of that name
FOREIGN = 'foreign'  # an endpoint of another node
UNKNOWN = 'unknown'  # a GID the graph does not (yet) show
CONTESTED = 'contested'  # the expected node's name is claimed by two or more publishers


@dataclass(frozen=True)
class Sender:
    """Who sent a message, as the graph identifies its publisher.

    name: the publisher as the graph names it ('/ns/node', or its GID when it names no
    node); claimants (CONTESTED): every publisher of the topic whose node has the owner's
    name, each '/ns/node (gid …)'; (UNKNOWN) those the graph shows, while it does not name
    this publisher yet.
    """

    verdict: str
    name: str
    claimants: tuple[str, ...] = ()

    @property
    def foreign(self) -> bool:
        """Not the owner: another node, or a publisher the graph does not show."""
        return self.verdict in (FOREIGN, UNKNOWN)

    def called(self, frame_id: str) -> str:
        """How a report names who sent a message that wrote `frame_id`: the graph's name
        and the frame_id, or the frame_id alone where the graph names none."""
        return f'{self.name} (frame_id {frame_id!r})' if self.name else frame_id or '(unnamed)'


ANYONE = Sender(OWNER, '')  # an input without an owner: whoever sends it


def sender_check(sender: Sender, owner: str) -> Rejected | None:
    """The publisher must be the input's owner, and the only node of its name."""
    if sender.verdict == OWNER:
        return None
    if sender.verdict == CONTESTED:
        return Rejected(
            f'{len(sender.claimants)} publishers claim to be {owner!r}: '
            f'{"; ".join(sender.claimants)}: refused'
        )
    if sender.verdict == UNKNOWN:
        # a publisher discovery has not shown yet (the first commands of a drive's start):
        # its frame_id claim decides (owner_check) until the graph names it, at most
        # graph_owner.REFRESH_S later; but not while the graph shows the owner (claimants):
        # then it is refused until named (a second copy, or the owner started again)
        if sender.claimants:
            return Rejected(
                f'{sender.name}, not named by the graph yet, while it shows '
                f'{"; ".join(sender.claimants)}: refused until named'
            )
        return None
    return Rejected(f'sent by {sender.name}, not by its owner {owner!r}')


@dataclass
class DropCounter:
    """Rejected messages per input, with the last reason, and when to report them again."""

    interval: float = 1.0  # [s] between reports of one input
    counts: dict[str, int] = field(default_factory=dict)
    last_reason: dict[str, str] = field(default_factory=dict)
    _reported: dict[str, float] = field(default_factory=dict)

    def drop(self, topic: str, rejected: Rejected, now: float) -> bool:
        """Count one dropped message; True when it should be reported now (rate limit)."""
        self.counts[topic] = self.counts.get(topic, 0) + 1
        self.last_reason[topic] = rejected.reason
        last = self._reported.get(topic)
        if last is None or now - last >= self.interval:
            self._reported[topic] = now
            return True
        return False

    @property
    def total(self) -> int:
        return sum(self.counts.values())
