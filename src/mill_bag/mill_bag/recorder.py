"""Recorder: writes a graph's topics into a rosbag2 bag in MCAP storage, as `ros2 bag record` does.

    recorder --ros-args -p output:=runs/bag1                       # every topic
    recorder --ros-args -p output:=bag1 -p "topics:=['/mill/x/state', '/clock']"
    recorder --ros-args -p output:=bag1 -p regex:='^/mill/' -p use_sim_time:=true
    ros2 run mill_bag recorder --ros-args -p output:=bag1          # with a full ROS install

`TopicRecorder` is the reusable part: it subscribes to topics of any node with
serialized (raw) subscriptions, so a message is never decoded, and writes each
message as it arrived (CDR) with its topic type and the publishers' offered QoS.
A node that has raw subscriptions of its own feeds them in with `tap` instead of
subscribing twice (mill's run monitor records a run that way, `run_scenario --record`).

Timestamps. Each message gets two: the MCAP log time (the one rosbag2 readers
use) and the publish time. When the graph runs on sim time (`use_sim_time`),
the log time is the message's own stamp for messages whose first field is a
std_msgs/Header (and Clock.clock for /clock), i.e. k T on a graph stepped in lockstep, and
the latest such stamp seen for other messages (/rosout, /parameter_events).
Without sim time it is the wall-clock receive time, as `ros2 bag record`
stores it. The publish time is always the wall-clock receive time (the
EventsExecutor does not expose the DDS source timestamp), so the loop timing can
be analysed from the bag.

Bad input. Any node of the domain may publish anything, so every message is checked before
it is written (mill_bag.intake): a negative, invalid or (on sim time) far-ahead stamp, more
than `max_message_bytes`, bytes that are no CDR, or a topic of an unknown type is dropped,
counted per kind and logged (one line per kind and second); the counts are in the summary
line and in metadata.yaml (custom_data `dropped_messages`). A header stamp reaches the MCAP
writer only once checked, and the writer refuses a time it cannot hold without touching the
file. Anything else that fails while writing closes the bag (at its last flush, if the MCAP
writer itself failed) and ends the recorder with one line saying so.

Losses. A recorder cannot make a publisher wait. Its subscriptions keep all (KEEP_ALL),
so that a recorder starved of CPU loses nothing of what reached it (a KEEP_LAST reader
dropped the oldest silently). It attaches no message_lost handler: with one on every
recorded topic, rclpy's EventsExecutor wedged in EventHandler.take_data once a runner
stopped for 3 s had lost messages, and took no data again (measured); a mill run's losses
are counted from the sequence of its samples instead (mill_analysis.realtime_record).

Durability. Messages are buffered in memory by the subscription callbacks and
written every `flush_period` (<= 1 s) of wall time: each write closes an MCAP
chunk, hands it to the OS and refreshes metadata.yaml. SIGINT or SIGTERM close
the bag (summary, footer, final metadata.yaml); a hard kill loses at most the
messages of the last `flush_period` and leaves a bag that `mill_bag.reader` reads
as it is and `python -m mill_bag recover` makes complete. A write the OS refuses (a
full disk) cuts the bag short at its last complete flush, says so in its metadata.yaml
and ends the recorder with one line and exit code 1.

Helpers used from mill_common, all generic (no topic, no run): node_main (run_node:
--help from the parameter specs, one-line start-up errors, SIGINT/SIGTERM, spin;
request_exit), parameters (ParamSpec and checks), ros_params (NodeParameters).
"""

from __future__ import annotations

import datetime as dt
import importlib
import re
import sys
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mill_common.declared import ParamSet, param
from mill_common.node_main import request_exit, run_node
from mill_common.parameters import ParamSpec, StringList, WholeAtLeast, in_range, one_of, text
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from mill_bag.errors import BagError
from mill_bag.intake import MAX_MESSAGE_BYTES, UNKNOWN_TYPE, Intake, Rejected
from mill_bag.types import message_definition, sim_stamped
from mill_bag.writer import COMPRESSIONS, BagCutShort, BagWriter, TopicInfo, counts_note

DROPPED = 'dropped_messages'  # custom_data note: messages dropped per kind (intake), JSON


def message_class(msgtype: str) -> type:
    """The Python message class of 'pkg/msg/Name'."""
    pkg, _, name = msgtype.partition('/msg/')
    try:
        return getattr(importlib.import_module(f'{pkg}.msg'), name)
    except (ImportError, AttributeError):
        raise BagError(f'message type {msgtype} is not installed') from None


def _duration(d: Any) -> dict[str, int]:
    sec, nsec = divmod(int(d.nanoseconds), 1_000_000_000)
    return {'sec': sec, 'nsec': nsec}


def qos_dicts(endpoints: Iterable[Any]) -> list[dict]:
    """Offered QoS profiles of a topic's publishers, as rosbag2 (version 9) stores them."""
    out = []
    for info in endpoints:
        p = info.qos_profile
        out.append(
            {
                'history': p.history.name.lower(),
                'depth': int(p.depth),
                'reliability': p.reliability.name.lower(),
                'durability': p.durability.name.lower(),
                'deadline': _duration(p.deadline),
                'lifespan': _duration(p.lifespan),
                'liveliness': p.liveliness.name.lower(),
                'liveliness_lease_duration': _duration(p.liveliness_lease_duration),
                'avoid_ros_namespace_conventions': bool(p.avoid_ros_namespace_conventions),
            }
        )
    return out


def subscription_qos(endpoints: list[Any]) -> QoSProfile:
    """A QoS that matches every publisher, as rosbag2 adapts it: reliable and transient-local
    only if all publishers offer it. KEEP_ALL: a recorder that falls behind (starved of CPU)
    loses nothing from its own history, where a KEEP_LAST one dropped the oldest silently
    (measured: 2321 of 8000 messages at 1 kHz, for a reader that took nothing for 5 s, and no
    message_lost event); see Losses above."""
    profiles = [e.qos_profile for e in endpoints]
    reliable = bool(profiles) and all(p.reliability == ReliabilityPolicy.RELIABLE for p in profiles)
    latched = bool(profiles) and all(
        p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in profiles
    )
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


@dataclass
class _Topic:
    name: str
    msgtype: str
    stamped: bool
    qos: list[dict] | None = None
    type_hash: str | None = None
    info: TopicInfo | None = None


class TopicRecorder:
    """Records topics of `node` into a rosbag2 MCAP bag at `output`.

    topics / regex select what discovery subscribes to (neither: every topic;
    both: either); `tap(topic, type)` gives a callback for a raw subscription the
    node has already, `subscribe(topic, type, qos)` subscribes before the topic
    is discovered (so the first message is not missed). Relative names are resolved
    as the node resolves them (its namespace and remappings), as `ros2 bag record`
    does; the bag holds absolute names. custom_data: notes for the bag's readers
    (metadata.yaml), e.g. what kind of run it holds; `note` adds one before the bag is
    closed.
    """

    def __init__(
        self,
        node: Node,
        output: Path,
        *,
        topics: Iterable[str] = (),
        regex: str = '',
        sim_time: bool = False,
        compression: str = 'zstd',
        flush_period: float = 0.5,
        discovery_period: float = 0.5,
        discover: bool = True,
        custom_data: Mapping[str, str] | None = None,
        max_message_bytes: int = MAX_MESSAGE_BYTES,
    ) -> None:
        self.node = node
        self.sim_time = sim_time
        self.names = {self.resolve(t) for t in topics}
        try:
            self.regex = re.compile(regex) if regex else None
        except re.error as exc:
            raise BagError(f'regex {regex!r} is not a valid regular expression: {exc}') from None
        self.writer = BagWriter(output, compression, custom_data=custom_data)
        self._buf: list[tuple[_Topic, int, bytes]] = []
        self._topics: dict[str, _Topic] = {}
        self._subs: list[Any] = []
        self._skipped: set[str] = set()
        self.intake = Intake(sim_time, max_message_bytes)
        self.closed = False
        self.error: str | None = None  # why writing failed, if it did
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._timers = [node.create_timer(flush_period, self._on_flush_timer, clock=steady)]
        if discover:
            self._timers.append(node.create_timer(discovery_period, self.discover, clock=steady))

    # -- what to record ------------------------------------------------------------------------
    def resolve(self, topic: str) -> str:
        """The absolute name of `topic` for this node; BagError for an invalid name."""
        try:
            return self.node.resolve_topic_name(topic)
        except (ValueError, RuntimeError) as exc:
            raise BagError(f'topic name {topic!r} is not valid: {exc}') from None

    def matches(self, topic: str) -> bool:
        if not self.names and self.regex is None:
            return not any(part.startswith('_') for part in topic.split('/'))  # no hidden topics
        return topic in self.names or bool(self.regex and self.regex.search(topic))

    def _entry(self, topic: str, msgtype: str) -> _Topic:
        topic = self.resolve(topic)
        if topic in self._topics:
            raise BagError(f'topic {topic} is recorded twice')
        message_definition(msgtype)  # fails early for a type without definition
        entry = _Topic(topic, msgtype, sim_stamped(msgtype))
        self._topics[topic] = entry
        return entry

    def tap(self, topic: str, msgtype: str) -> Callable[[bytes], None]:
        """Callback that records a serialized message of `topic` (for a subscription you own)."""
        entry = self._entry(topic, msgtype)
        append = self._buf.append
        now = time.time_ns

        def on_message(data: bytes) -> None:
            append((entry, now(), data))

        return on_message

    def subscribe(self, topic: str, msgtype: str, qos: QoSProfile) -> None:
        callback = self.tap(topic, msgtype)
        self._subs.append(
            self.node.create_subscription(message_class(msgtype), topic, callback, qos, raw=True)
        )

    def note(self, key: str, value: str) -> None:
        """A note for the bag's readers (metadata.yaml's custom_data), written at the next
        flush or at close."""
        self.writer.custom_data[key] = value

    def discover(self) -> None:
        """Subscribe to new matching topics that have publishers; note the publishers' QoS."""
        if self.closed:
            return
        for name, types in self.node.get_topic_names_and_types():
            entry = self._topics.get(name)
            if entry is not None:
                if entry.info is None and entry.qos is None:
                    self._note_publishers(entry)
                continue
            if name in self._skipped or not self.matches(name):
                continue
            endpoints = self.node.get_publishers_info_by_topic(name)
            if not endpoints:
                continue  # no publisher yet: its QoS is unknown
            msgtype = types[0]
            try:
                self.subscribe(name, msgtype, subscription_qos(endpoints))
            except BagError as exc:
                self._skipped.add(name)
                self._drop(name, Rejected(UNKNOWN_TYPE, str(exc)))
                continue
            self._note_publishers(self._topics[name], endpoints)

    def _note_publishers(self, entry: _Topic, endpoints: list[Any] | None = None) -> None:
        if endpoints is None:
            try:
                endpoints = self.node.get_publishers_info_by_topic(entry.name)
            except Exception:  # the context may be shut down already (Ctrl-C)
                return
        if endpoints:
            entry.qos = qos_dicts(endpoints)
            entry.type_hash = str(endpoints[0].topic_type_hash) or None

    # -- writing -----------------------------------------------------------------------------
    def _drop(self, topic: str, rejected: Rejected) -> None:
        line = self.intake.drop(topic, rejected, time.monotonic())
        if line is not None:
            self.node.get_logger().warning(line)

    def _on_flush_timer(self) -> None:
        # Nothing may be thrown through the executor: a failed write ends the node instead.
        if self.error is not None:
            return
        # The node's exit prints the error once (run_node), so it is not logged here too.
        try:
            self.flush()
        except BagCutShort as exc:  # a full disk: the bag ends at its last complete flush
            self.error = str(exc)
            request_exit(self.node, 1, self.error)
        except Exception as exc:  # not bad input (intake drops that): the bag is closed
            self.error = self._close_after(exc)
            request_exit(self.node, 1, self.error)

    def _close_after(self, exc: Exception) -> str:
        """Close the bag after a write failed unexpectedly; what happened, in one line."""
        why = f'{type(exc).__name__}: {exc}' if str(exc) else type(exc).__name__
        self.closed = True
        writer = self.writer
        try:
            writer.close()
            end = ''
        except Exception:  # the MCAP writer is broken: end at the last complete flush
            writer.abort(why)
            end = ' at its last flush (`python -m mill_bag recover` completes it)'
        n = writer.message_count
        return f'cannot write the bag {writer.path} ({why}); closed it{end} with {n} messages'

    def flush(self) -> None:
        """Write what arrived since the last flush as one chunk; refresh metadata.yaml."""
        if self.writer.closed:
            return
        buf = self._buf
        n = len(buf)
        batch = buf[:n]
        del buf[:n]
        writer = self.writer
        intake = self.intake
        for entry, received, data in batch:
            log_time = intake.log_time(data, entry.stamped, received)
            if isinstance(log_time, Rejected):
                self._drop(entry.name, log_time)
                continue
            info = entry.info
            if info is None:
                if entry.qos is None and not self.closed:
                    self._note_publishers(entry)
                info = entry.info = writer.add_topic(
                    entry.name, entry.msgtype, entry.qos or [], entry.type_hash
                )
            writer.write(info, log_time, received, data)
        if intake.dropped:  # discovery counts too: noted at every flush
            self.note(DROPPED, counts_note(intake.counts))
        writer.flush()

    def close(self) -> None:
        """Write the rest and close the bag (idempotent). BagCutShort if the disk is full;
        any other failure closes the bag as `_close_after` can and raises BagError saying so."""
        for timer in self._timers:
            timer.cancel()
        if self.writer.closed:
            return
        try:
            self.flush()
            self.closed = True
            self.writer.close()
        except BagCutShort:
            raise
        except Exception as exc:
            raise BagError(self._close_after(exc)) from None

    @property
    def message_count(self) -> int:
        return self.writer.message_count

    def summary(self) -> str:
        size = self.writer.size_bytes / 1e6
        dropped = self.intake.describe()
        return (
            f'bag {self.writer.path}: {self.writer.message_count} messages on '
            f'{len(self.writer.topics)} topics, {size:.1f} MB' + (f'; {dropped}' if dropped else '')
        )


# -- the recorder node -------------------------------------------------------------------------


def _regex(value: Any) -> str | None:
    if not isinstance(value, str):
        return 'must be a string'
    try:
        re.compile(value)
    except re.error as exc:
        return f'not a valid regular expression ({exc})'
    return None


@dataclass(frozen=True)
class RecorderParams(ParamSet):
    """The recorder node's parameters (all read-only: a bag is opened once)."""

    output: str = param(
        '',
        'bag directory to create (default rosbag2_YYYY_MM_DD-HH_MM_SS); never overwritten',
        text,
        read_only=True,
    )
    topics: list[str] = param(
        [],
        'topics to record (empty and no regex: all topics)',
        StringList('topic names'),
        read_only=True,
    )
    regex: str = param(
        '', 'also record topics matching this regular expression', _regex, read_only=True
    )
    compression: str = param(
        'zstd', 'MCAP chunk compression', one_of(*COMPRESSIONS), read_only=True
    )
    flush_period: float = param(
        0.5,
        'write buffered messages to the file this often [s]; a hard kill loses at most this',
        in_range(0.05, 1.0),
        read_only=True,
    )
    max_message_bytes: int = param(
        MAX_MESSAGE_BYTES,
        'a message with more serialized bytes is dropped and counted (mill_bag.intake)',
        WholeAtLeast(1024),
        read_only=True,
    )


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return RecorderParams.named_specs()


class RecorderNode(Node):
    def __init__(self) -> None:
        super().__init__('recorder')
        from mill_common.ros_params import NodeParameters

        self.recorder: TopicRecorder | None = None
        self.params = NodeParameters(self, parameter_specs(), lambda _values: None)
        v = RecorderParams.from_node_values(self.params.values)
        output = v.output or dt.datetime.now().strftime('rosbag2_%Y_%m_%d-%H_%M_%S')
        sim_time = bool(self.get_parameter('use_sim_time').value)
        self.recorder = TopicRecorder(
            self,
            Path(output),
            topics=v.topics,
            regex=v.regex,
            sim_time=sim_time,
            compression=v.compression,
            flush_period=v.flush_period,
            max_message_bytes=v.max_message_bytes,
        )
        what = sorted(self.recorder.names)
        if v.regex:
            what.append(f'topics matching {v.regex!r}')
        self.get_logger().info(
            f'recording {", ".join(what) or "all topics"} to {output} '
            f'({"sim time" if sim_time else "wall time"} stamps)'
        )

    def destroy_node(self) -> None:
        """Close the bag. A failure to (a full disk) propagates as a BagError, which run_node
        prints as one line; a failure while recording (the bag closed or cut short then) has
        been reported already, so no summary follows it."""
        recorder, self.recorder = self.recorder, None
        try:
            if recorder is not None:
                failed_before = recorder.error is not None
                recorder.close()
                if not failed_before:
                    print(f'recorder: {recorder.summary()}', file=sys.stderr)
        finally:
            super().destroy_node()


def main(argv: list[str] | None = None) -> int:
    # run_node ends the node on SIGINT and SIGTERM alike; destroy_node closes the bag.
    return run_node(
        RecorderNode,
        'recorder',
        'Records topics into a rosbag2 bag in MCAP storage (as `ros2 bag record -s mcap`). '
        'With use_sim_time:=true a message is stamped with its header stamp (sim time); '
        'SIGINT/SIGTERM close the bag.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
