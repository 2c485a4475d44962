"""What the nodes would take of the messages a listener received: the record's intake. ROS-free.

A node drops a message sent by another node than its topic's owner (`owner_check`), with a
stamp its timing refuses (mill_common.timing: negative, off the sample grid, in the past,
ahead of the plant) or with content it cannot use (`joint_values`); of a sample offered
again the first message counts. A run's record (the runner's, and `report`'s of a bag) takes
the messages in the order the listener received them through the same checks (`Intake`), so
that it holds what the nodes acted on: a message they drop is left out of the record too,
and counted per topic with its reason (`Drops`).

How far the plant has got. A node checks `ahead` against the newest state it has accepted:
nothing it receives can be later than one sample after it, because the plant publishes step
k + 1 only after every node answered step k. A listener outside the loop (the runner, a
recorder) gets each writer's messages in order, but not two writers' in the order they were
sent: a step's estimate may reach it before that step's state. Every message it accepted
proves the plant had reached its step, so the newest step of any accepted per-sample message
(`stepped`: states, estimates, commands, cutting force, ground truth) stands in for the newest
state; not the reference, which may lead by its preview (REFERENCE_LEAD_NS).
"""

from __future__ import annotations

import bisect
import re
import zlib
from array import array
from collections.abc import Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import accumulate
from typing import overload

from mill_common.checks import REFERENCE_LEAD_NS, Rejected, StampCheck, owner_check
from mill_common.timing import Timing

# The numbers of a reason, so that reasons that differ only in them count together.
_NUMBER = re.compile(r'-?\d+(\.\d+)?')


@dataclass
class Drops:
    """Messages left out of a record, per topic and reason: how many, and the first one's
    reason as the check gave it (reasons that differ only in their numbers count together)."""

    counts: dict[str, dict[str, int]] = field(default_factory=dict)
    first: dict[str, dict[str, str]] = field(default_factory=dict)

    def add(self, topic: str, rejected: Rejected) -> None:
        kind = _NUMBER.sub('#', rejected.reason)
        counts = self.counts.setdefault(topic, {})
        counts[kind] = counts.get(kind, 0) + 1
        self.first.setdefault(topic, {}).setdefault(kind, rejected.reason)

    def per_topic(self) -> dict[str, int]:
        return {t: sum(kinds.values()) for t, kinds in self.counts.items()}

    def reasons(self) -> dict[str, list[tuple[int, str]]]:
        """Per topic: (messages, the first one's reason) of each reason, most first."""
        return {
            topic: sorted(((n, self.first[topic][k]) for k, n in kinds.items()), reverse=True)
            for topic, kinds in self.counts.items()
        }


def drop_lines(reasons: Mapping[str, Sequence[tuple[int, str]]]) -> list[str]:
    """One ERROR line per topic with messages left out of a record (`Drops.reasons`): what
    the runner's summary and `report` print."""
    out = []
    for topic, why in reasons.items():
        total = sum(n for n, _ in why)
        text = '; '.join(f'{n} like "{reason}"' for n, reason in why)
        out.append(f'ERROR: {topic}: {total} messages left out of the record: {text}')
    return out


class Intake:
    """The checks of the nodes, on one listener's messages in the order it received them.

    timing: the graph's (mill_common.timing); owners: the node each topic must come from
    (header.frame_id; a topic without one: anyone); stepped: the per-sample topics whose
    accepted stamps tell how far the plant has got; history: topics that carry points ahead
    (the reference: it may lead by REFERENCE_LEAD_NS).
    """

    def __init__(
        self,
        timing: Timing,
        owners: Mapping[str, str],
        stepped: Collection[str],
        history: Collection[str] = (),
    ) -> None:
        self.timing = timing
        self.owners = dict(owners)
        self.stepped = set(stepped)
        self.history = set(history)
        self.reached: int | None = None  # the newest step an accepted message proves
        self.drops = Drops()
        self._stamps: dict[str, StampCheck] = {}

    def _stamp_check(self, topic: str) -> StampCheck:
        stamps = self._stamps.get(topic)
        if stamps is None:
            stamps = self._stamps[topic] = self.timing.stamps()
        return stamps

    def problem(self, topic: str, ns: int, sender: str) -> Rejected | None:
        """What a node would drop this message for, by its sender and stamp (None: nothing)."""
        problem = owner_check(sender, self.owners.get(topic, ''))
        if problem is not None:
            return problem
        history = topic in self.history
        lead = REFERENCE_LEAD_NS if history else self.timing.period_ns
        return self.timing.problem(self._stamp_check(topic), ns, self.reached, lead, history)

    def again(self, topic: str, ns: int) -> bool:
        """A sample offered again (its first message counts)."""
        return self.timing.is_offered_again(self._stamp_check(topic), ns)

    def accept(self, topic: str, ns: int) -> None:
        self._stamp_check(topic).accept(ns)
        if topic in self.stepped and (self.reached is None or ns > self.reached):
            self.reached = ns

    def drop(self, topic: str, rejected: Rejected) -> None:
        self.drops.add(topic, rejected)


class Forgotten(LookupError):
    """A message of a MessageLog that forgot it (`MessageLog.forget`)."""


class MessageLog(Sequence[bytes]):
    """A topic's serialized messages, kept compact: appended to a buffer that is compressed
    (zlib, fastest level) every CHUNK bytes, so that a long run's record costs its runner a
    few bytes a message instead of a Python object each (the CDR of a sample compresses
    about fivefold; zstd's one-shot compress compressed more but kept ~50 kB of the
    runner's heap per chunk, 46 MB in 900 chunks, and a reused zstd context costs more than
    it saves), and each message's length, two bytes (four once one is 64 kB or more).
    Reading a message gives its bytes back; reading them in order decompresses each chunk
    once.

    Once a record is built from them, `forget` drops all of them but the newest: the log
    still counts them all (a bag is checked against the count), and reading an older one
    raises Forgotten.
    """

    CHUNK = 1 << 16

    def __init__(self, messages: Iterable[bytes] = ()) -> None:
        self._chunks: list[bytes] = []  # compressed, oldest first
        self._first: list[int] = []  # the index of each chunk's first message
        self._sizes = array('H')  # each message's length
        self._tail = bytearray()  # the messages since the last chunk
        self._tail_first = 0
        self._tail_ends = array('I', [0])  # where each of them ends in the tail
        self._cached: tuple[int, bytes, array[int]] = (-1, b'', array('I'))  # chunk read last
        self._forgotten = 0  # the messages before the first held (`forget`)
        for data in messages:
            self.append(data)

    def forget(self) -> None:
        """Drop every message but the newest; the count stays."""
        n = len(self._sizes)
        if n <= 1:
            return
        newest = self[-1]
        self._forgotten += n - 1
        self._chunks, self._first, self._cached = [], [], (-1, b'', array('I'))
        self._sizes = array(self._sizes.typecode, [len(newest)])
        self._tail, self._tail_first = bytearray(newest), 0
        self._tail_ends = array('I', [0, len(newest)])

    def append(self, data: bytes) -> None:
        size = len(data)
        if size > 0xFFFF and self._sizes.typecode == 'H':
            self._sizes = array('I', self._sizes)
        self._sizes.append(size)
        self._tail += data
        self._tail_ends.append(len(self._tail))
        if len(self._tail) >= self.CHUNK:
            self._chunks.append(zlib.compress(self._tail, 1))
            self._first.append(self._tail_first)
            self._tail = bytearray()
            self._tail_first = len(self._sizes)
            self._tail_ends = array('I', [0])

    def __len__(self) -> int:
        return self._forgotten + len(self._sizes)

    @overload
    def __getitem__(self, i: int) -> bytes: ...
    @overload
    def __getitem__(self, i: slice) -> list[bytes]: ...
    def __getitem__(self, i: int | slice) -> bytes | list[bytes]:
        n = len(self)
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(n))]
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError('message index out of range')
        if i < self._forgotten:
            raise Forgotten(f'message {i} of {n} was forgotten (only the newest is kept)')
        i -= self._forgotten
        if i >= self._tail_first:
            ends, k = self._tail_ends, i - self._tail_first
            return bytes(self._tail[ends[k] : ends[k + 1]])
        c = bisect.bisect_right(self._first, i) - 1
        if self._cached[0] != c:
            first = self._first[c]
            last = self._first[c + 1] if c + 1 < len(self._first) else self._tail_first
            ends = array('I', accumulate(self._sizes[first:last], initial=0))
            self._cached = (c, zlib.decompress(self._chunks[c]), ends)
        _, data, ends = self._cached
        k = i - self._first[c]
        return data[ends[k] : ends[k + 1]]

    def __iter__(self) -> Iterator[bytes]:
        for i in range(len(self)):
            yield self[i]

    def nbytes(self) -> int:
        """What it holds [bytes]: the compressed chunks, the buffer and the index."""
        return (
            sum(len(c) for c in self._chunks)
            + len(self._tail)
            + self._sizes.itemsize * len(self._sizes)
            + self._tail_ends.itemsize * len(self._tail_ends)
        )


class ArrivalOrder(Sequence[str]):
    """Topic names in the order their messages arrived, two bytes a message (the index of
    the name among those seen), not a list slot each."""

    def __init__(self, names: Iterable[str] = ()) -> None:
        self._names: list[str] = []
        self._index: dict[str, int] = {}
        self._seq = array('H')
        for name in names:
            self.append(name)

    def clear(self) -> None:
        del self._seq[:]

    def append(self, name: str) -> None:
        i = self._index.get(name)
        if i is None:
            i = self._index[name] = len(self._names)
            self._names.append(name)
        self._seq.append(i)

    def __len__(self) -> int:
        return len(self._seq)

    @overload
    def __getitem__(self, i: int) -> str: ...
    @overload
    def __getitem__(self, i: slice) -> list[str]: ...
    def __getitem__(self, i: int | slice) -> str | list[str]:
        if isinstance(i, slice):
            return [self._names[j] for j in self._seq[i]]
        return self._names[self._seq[i]]

    def __iter__(self) -> Iterator[str]:
        names = self._names
        for i in self._seq:
            yield names[i]


class Received(dict[str, Sequence[bytes]]):
    """Serialized messages per topic, and the topic of each message in the order they arrived
    (what `Intake` needs: the order of one listener)."""

    def __init__(self) -> None:
        super().__init__()
        self.order = ArrivalOrder()

    def forget(self, keep: Collection[str] = ()) -> None:
        """Forget the messages of every topic but `keep` (MessageLog.forget: their counts
        and newest stay); with nothing kept, the order of arrival too."""
        for topic, messages in self.items():
            if topic not in keep and isinstance(messages, MessageLog):
                messages.forget()
        if not keep:
            self.order.clear()


def subset(raw: Mapping[str, Sequence[bytes]], topics: Collection[str]) -> Received:
    """The messages of these topics in `raw`, in the order they arrived where it knows it
    (the same sequences, not copies)."""
    out = Received()
    out.update({t: raw[t] for t in topics if t in raw})
    order = getattr(raw, 'order', None)
    out.order = ArrivalOrder(
        (t for t in order if t in out) if order is not None else (t for t in out for _ in out[t])
    )
    return out


def arrival_order(
    raw: Mapping[str, Sequence[bytes]], topics: Collection[str]
) -> Iterator[tuple[str, bytes]]:
    """(topic, message) of `topics` in the order they arrived (`Received`); from a mapping
    that does not know it, each topic's messages after the topic before."""
    order = getattr(raw, 'order', None)
    if order is None:
        for topic in topics:
            for data in raw.get(topic, ()):
                yield topic, data
        return
    cursor = dict.fromkeys(topics, 0)
    for topic in order:
        i = cursor.get(topic)
        if i is not None:
            cursor[topic] = i + 1
            yield topic, raw[topic][i]
