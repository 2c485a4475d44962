"""What happened to a run besides its signals, as typed events. ROS-free.

An event is parsed once, from the values (KeyValues) of the /diagnostics status it arrives
in, never from the status's prose:

- a controller's following-error status (`<node>: following error`) carries `trip_time_s`
  and `trip_error_m` once the axis tripped, and its `axis`: a `trip`;
- a drive's status (`<node>: lockstep` / `realtime`) counts per axis the stops it made
  (`<axis>.stops`, why in `<axis>.stopped`): each new one a `stopped`; the brake requests it
  took (`<axis>.invalid_commands`, a NaN command: a tripped controller sends one every
  period): the first a `braked`; and what the machine reports wrong (`<axis>.fault`): a `fault`;
- a drive's ownership status (`<node>: ownership`, with `foreign_messages`): a
  `foreign_publisher`, once per drive (what it said in the detail).

- the trajectory's job status (`<node>: job`) with an `event` value: a `program_message`
  ((MSG, …), (DEBUG, …), (PRINT, …), a tool change) or a `pause` (M0/M1 reached, a feed
  hold, a resume), at the job time of its line (`program_events_of`; not among the machine's
  events, which a run and its offline twin must share).

The runner adds what it found itself: a drive that went silent (`drive_silent`), a run
that stalled (`stall`), a node that died (`node_died`), a run it could not complete
(`run_error`). The offline simulator makes its trips as the controllers report them.

An event's time is the job's [s]: the trip's own time, else the stamp of the status that
first told it, less the job's start (the realtime job's start stamp; 0 in lockstep).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mill_common import topics

TRIP = 'trip'  # the controller's following-error trip latched: it sends brake requests
STOPPED = 'stopped'  # the drive stopped the axis (no fresh command, a motion it forbids)
BRAKED = 'braked'  # the drive braked the axis on a brake request (an invalid command)
FAULT = 'fault'  # the machine reports the axis at fault
DRIVE_SILENT = 'drive_silent'  # the runner heard no state of the drive for too long
STALL = 'stall'  # the run made no progress for --stall-timeout
NODE_DIED = 'node_died'  # a node's process ended while the job ran
RUN_ERROR = 'run_error'  # the run could not go on (the graph refused it)
FOREIGN = 'foreign_publisher'  # the drive saw another publisher on its topics (ignored)
PROGRAM_MESSAGE = 'program_message'  # a G-code (MSG, …), (DEBUG, …), (PRINT, …) or tool change
PAUSE = 'pause'  # the program paused (M0/M1) or the operator held the feed, or resumed
KINDS = (
    TRIP,
    STOPPED,
    BRAKED,
    FAULT,
    FOREIGN,
    DRIVE_SILENT,
    STALL,
    NODE_DIED,
    RUN_ERROR,
    PROGRAM_MESSAGE,
    PAUSE,
)
# The trajectory's job status (`<node>: job`) says what the program and the operator did in
# its values `event` (EVENT_KINDS: the value -> the kind), `event_text`, `event_where`
# (file:line:column), `event_channel` and `event_time_s` (the job time of the line).
EVENT_KINDS = {
    'message': PROGRAM_MESSAGE,
    'tool change': PROGRAM_MESSAGE,
    'paused': PAUSE,
    'resumed': PAUSE,
    'feed_hold': PAUSE,
    'resume': PAUSE,
}
# The events of a status on the machine (the others are the runner's own findings).
MACHINE_KINDS = (TRIP, STOPPED, BRAKED, FAULT, FOREIGN)

TRIP_PART = 'following error'  # mill_controllers.axis_reports.TRIP_PART
OWNERSHIP_PART = 'ownership'  # mill_plant.ownership.OWNERSHIP_PART


@dataclass(frozen=True)
class Event:
    """One thing that happened to a run: to an axis ('' for the whole run), of a kind
    (KINDS), at a time of the job [s] (NaN where unknown), with what else is known."""

    axis: str
    kind: str
    time: float
    detail: str = ''
    source: str = ''  # the node that told it ('' the runner's own)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f'no kind of event {self.kind!r} (known: {", ".join(KINDS)})')

    def text(self) -> str:
        """One line: 'y axis: trip at t = 1.2345 s (y_controller): following error |e| =
        2.001 mm > 2 mm: braked'."""
        who = f'{self.axis} axis: ' if self.axis else ''
        when = f' at t = {self.time:.4f} s' if math.isfinite(self.time) else ''
        name = self.kind.replace('_', ' ')
        by = f' ({self.source})' if self.source else ''
        return f'{who}{name}{when}{by}' + (f': {self.detail}' if self.detail else '')

    def to_json(self) -> dict[str, Any]:
        return {
            'axis': self.axis,
            'kind': self.kind,
            'time': self.time if math.isfinite(self.time) else None,
            'detail': self.detail,
            'source': self.source,
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Event:
        time = d.get('time')
        return cls(
            str(d['axis']),
            str(d['kind']),
            math.nan if time is None else float(time),
            str(d.get('detail', '')),
            str(d.get('source', '')),
        )


@dataclass(frozen=True)
class Status:
    """One /diagnostics status as it arrived: the stamp of its array [ns], its name
    (`[<namespace>/]<node>: <part>`, topics.status_name), level (0 OK, 1 WARN, 2 ERROR),
    message and values."""

    stamp_ns: int
    name: str
    level: int
    message: str
    values: Mapping[str, str]

    @property
    def node(self) -> str:
        return topics.parse_status_name(self.name).node

    @property
    def part(self) -> str:
        return topics.part_of(self.name)


def statuses_of(arrays: Iterable[Any], namespace: str | None = None) -> list[Status]:
    """The statuses of DiagnosticArray messages (rclpy's or decoded from a bag), in order;
    those of the machine in `namespace` only, if given."""
    out = []
    for array in arrays:
        stamp = array.header.stamp
        ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        for s in array.status:
            if namespace is not None and not topics.from_machine(s.hardware_id, namespace):
                continue
            level = s.level[0] if isinstance(s.level, bytes) else int(s.level)
            values = {kv.key: kv.value for kv in s.values}
            out.append(Status(ns, s.name, level, s.message, values))
    return out


def trip_detail(error: float, limit: float, cause: str = '') -> str:
    """What a trip event says besides its time: the error and the limit, or its cause."""
    if cause:
        return f'{cause}: braked'
    return f'following error |e| = {1e3 * abs(error):.3f} mm > {1e3 * limit:g} mm: braked'


def _number(text: str | None) -> float:
    try:
        return float(text) if text is not None else math.nan
    except ValueError:
        return math.nan


def _count(text: str | None) -> int:
    n = _number(text)
    return int(n) if math.isfinite(n) else 0


def events_of(
    statuses: Sequence[Status], start_ns: int = 0, axis_of: Mapping[str, str] | None = None
) -> list[Event]:
    """The machine's events (MACHINE_KINDS) told by these statuses, once each, in the order
    they were told. start_ns: the job's start on the statuses' clock (time 0 of the events);
    axis_of: the axis of each controller node, for one whose status does not name it."""
    axis_of = axis_of or {}
    start = start_ns * 1e-9
    out: list[Event] = []
    trips: set[tuple[str, float]] = set()
    counted: dict[tuple[str, str], int] = {}  # (node, key) -> the count told so far
    faults: dict[tuple[str, str], str] = {}
    foreign: set[str] = set()  # drives that told of a foreign publisher
    for s in statuses:
        at = (s.stamp_ns - start_ns) * 1e-9
        values = s.values
        if s.part == TRIP_PART and 'trip_time_s' in values:
            axis = values.get('axis') or axis_of.get(s.node, '')
            t = _number(values['trip_time_s'])
            if (axis, t) in trips:
                continue
            trips.add((axis, t))
            detail = trip_detail(
                _number(values.get('trip_error_m')),
                _number(values.get('following_error_limit_m')),
                values.get('trip_cause', ''),
            )
            out.append(Event(axis, TRIP, t - start, detail, s.node))
            continue
        if s.part == OWNERSHIP_PART and 'foreign_messages' in values:
            if s.node not in foreign:
                foreign.add(s.node)
                out.append(Event('', FOREIGN, at, s.message, s.node))
            continue
        if s.part not in topics.DRIVE_STATUSES:
            continue
        for key, value in values.items():
            axis, _, field = key.partition('.')
            if field == 'stops':
                n, was = _count(value), counted.get((s.node, key), 0)
                why = values.get(f'{axis}.stopped') or 'released since'
                out += [Event(axis, STOPPED, at, why, s.node) for _ in range(n - was)]
                counted[(s.node, key)] = max(n, was)
            elif field == 'invalid_commands':
                # The first brake request of the axis: a tripped controller sends one every
                # period, and a status (once a second, and at each stop) cannot tell one
                # series of them from the next.
                n = _count(value)
                if n > 0 and (s.node, key) not in counted:
                    counted[(s.node, key)] = n
                    out.append(Event(axis, BRAKED, at, 'brake request (invalid command)', s.node))
            elif field == 'fault' and value and faults.get((s.node, axis)) != value:
                faults[(s.node, axis)] = value
                out.append(Event(axis, FAULT, at, value, s.node))
    return out


def first_stop(events: Iterable[Event], axis: str) -> float | None:
    """When the axis was first tripped, stopped or braked [s], None if it never was."""
    times = [
        e.time
        for e in events
        if e.axis == axis and e.kind in (TRIP, STOPPED, BRAKED) and math.isfinite(e.time)
    ]
    return min(times) if times else None


def program_events_of(statuses: Sequence[Status]) -> list[Event]:
    """What the program said and the operator did (PROGRAM_MESSAGE, PAUSE), once each, in
    order: from the trajectory's job statuses with an `event` value (EVENT_KINDS), at the
    job time they carry. The detail is 'file:line:column: CHANNEL: text' (a message) or
    the event and what it said (a pause, a hold, a resume: refused ones included)."""
    out: list[Event] = []
    seen: set[tuple[str, str, str, str]] = set()
    for s in statuses:
        values = s.values
        event = values.get('event')
        if s.part != topics.JOB_STATUS or event not in EVENT_KINDS:
            continue
        t = values.get('event_time_s', '')
        key = (event, values.get('event_where', ''), values.get('event_text', ''), t)
        if key in seen:
            continue
        seen.add(key)
        out.append(Event('', EVENT_KINDS[event], _number(t), s.message, s.node))
    return out
