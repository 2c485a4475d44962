"""What a recorder lets into its bag: every message is checked before it is written. ROS-free.

A recorder hears every node of its domain, so it cannot trust what it records: one JointState
with a negative header stamp, on any topic, once ended a recording (on sim time the stamp is
the bag time, and MCAP times are unsigned). `Intake.log_time` checks a message without
decoding it and gives its bag time, or a `Rejected` that says why it is dropped;
`Intake.drop` counts the drop by kind and says when to log it (one line per kind and
second). The kinds:

    too large       more serialized bytes than `max_bytes` (default MAX_MESSAGE_BYTES, 16 MiB):
                    a huge array, held in the recorder's memory until the next flush
    not CDR         no CDR encapsulation header, or too short for the stamp its type leads with
    negative stamp  a header (or /clock) stamp before 1970, sec < 0: no ROS time (rclpy
                    refuses it) and no MCAP time (unsigned)
    invalid stamp   nanosec >= 10^9: not a builtin_interfaces/Time
    stamp ahead     sim time only: more than MAX_LEAD_NS after the newest stamp accepted
                    before it. A sim graph's clock steps on; a stamp an hour ahead of it is no
                    time of that graph, and as the newest bag time it would move every later
                    unstamped message (rosout, a Float64) an hour on. The first stamp a
                    recording accepts sets its time: there is nothing to compare it with.
    unknown type    a topic whose type has no definition here: not subscribed, so it counts
                    once per topic (the recorder's discovery reports it)

Bag times. On sim time a message whose first field is a std_msgs/Header (or a Clock) is
logged at its own stamp, every other one at the newest stamp accepted so far; on wall time
every message is logged at its receive time, as `ros2 bag record` does. The stamp checks
apply on wall time too (a negative stamp is no ROS time), the lead check does not.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

from mill_common.timebase import stamp_ns

MAX_MESSAGE_BYTES = 16 << 20
MAX_LEAD_NS = 3600 * 1_000_000_000
UNKNOWN_TYPE = 'unknown type'
_STAMP = {0: struct.Struct('>iI'), 1: struct.Struct('<iI')}  # CDR big / little endian


class Rejected(NamedTuple):
    kind: str  # one of the kinds above
    detail: str  # the message's own figures, for the log line


@dataclass
class Intake:
    """Checks and bag times of one recording's messages; drops counted per kind."""

    sim_time: bool
    max_bytes: int = MAX_MESSAGE_BYTES
    interval: float = 1.0  # [s] between two log lines of one kind
    counts: dict[str, int] = field(default_factory=dict)
    latest_ns: int | None = None  # the newest stamp accepted (sim time)
    _logged: dict[str, float] = field(default_factory=dict)

    def log_time(self, data: bytes, stamped: bool, received_ns: int) -> int | Rejected:
        """The bag time of a message (CDR as received), or why it is dropped.

        stamped: its type leads with a std_msgs/Header or is a Clock (mill_bag.types.sim_stamped).
        """
        if len(data) > self.max_bytes:
            return Rejected('too large', f'{len(data)} bytes, the limit is {self.max_bytes}')
        if len(data) < 4 or data[0] != 0 or data[1] > 1:
            return Rejected('not CDR', f'{len(data)} bytes without a CDR header')
        if not stamped:
            return received_ns if not self.sim_time else self.latest_ns or 0
        if len(data) < 12:
            return Rejected('not CDR', f'{len(data)} bytes, too short for a stamp')
        sec, nanosec = _STAMP[data[1]].unpack_from(data, 4)
        if sec < 0:
            return Rejected('negative stamp', f'sec {sec}')
        if nanosec >= 1_000_000_000:
            return Rejected('invalid stamp', f'nanosec {nanosec}')
        if not self.sim_time:
            return received_ns
        ns = stamp_ns(sec, nanosec)
        latest = self.latest_ns
        if latest is not None and ns > latest + MAX_LEAD_NS:
            return Rejected('stamp ahead', f'{ns / 1e9:.9f} s, newest {latest / 1e9:.9f} s')
        if latest is None or ns > latest:
            self.latest_ns = ns
        return ns

    def drop(self, topic: str, rejected: Rejected, now: float) -> str | None:
        """Count one dropped message; the line to log now, None within `interval` of the
        last line of its kind."""
        n = self.counts[rejected.kind] = self.counts.get(rejected.kind, 0) + 1
        last = self._logged.get(rejected.kind)
        if last is not None and now - last < self.interval:
            return None
        self._logged[rejected.kind] = now
        what = 'not recording' if rejected.kind == UNKNOWN_TYPE else 'dropped a message on'
        return f'{what} {topic}: {rejected.kind} ({rejected.detail}); {n} so far'

    @property
    def dropped(self) -> int:
        return sum(self.counts.values())

    def describe(self) -> str:
        return describe(self.counts)


def describe(counts: Mapping[str, int]) -> str:
    """Drops per kind as '3 dropped (negative stamp 2, too large 1)'; '' for none."""
    total = sum(counts.values())
    if not total:
        return ''
    return f'{total} dropped ({", ".join(f"{k} {n}" for k, n in sorted(counts.items()) if n)})'
