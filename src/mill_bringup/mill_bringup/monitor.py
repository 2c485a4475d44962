"""Monitor: the runner's node. Keeps the messages a job's record is built from, and records.

Subscriptions take the serialized bytes (no Python message per sample while the run goes
on), with the order they arrived in (mill_analysis.node_intake.Received: the record takes
them through the nodes' checks in that order); the job decodes them once at the end with the
same code that reads bags, so the runner's summary and the report of the run's bag are
computed by the same code. Every topic of the job it records it also keeps: what the bag
holds of the job, the record counts.

With `record=RecordOptions(...)` a TopicRecorder writes every topic of the graph to a
rosbag2 bag: the monitor's own subscriptions feed it too, and it subscribes only to the
rest (the job's other contract topics, /clock, /diagnostics, and whatever discovery finds).
In lockstep it also acknowledges, on mill/recorded, after each write of the bag, the newest
step whose stepped topics the bag's file holds whole, and the plant waits for that
(mill_bringup.bag_handshake): nothing is lost, and a SIGKILL of the runner costs at most the
plant's `recorder_window` steps.
Without a bag it acknowledges the steps it has heard whole, every ACK_PERIOD: a runner
short of CPU slows the job down instead of losing samples of its record.
In realtime nothing waits for it: its subscriptions keep all (RECORD_QOS), so that a runner
short of CPU loses nothing that reached it, and the job counts the samples missing from the
drive's sequence (the run's summary, the bag's notes).
/diagnostics is also kept, as the statuses of this machine (mill_analysis.events.Status: a
few hundred bytes each; the arrays as rclpy messages took 6 kB each, 7.6 MB in the main
job), for the faults the summary reports.

The monitor runs in the graph's namespace (and with its remappings), so the job's relative
topic names resolve as the nodes resolve them; of the shared /diagnostics it reports only
the statuses of its own machine.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_analysis.events import Status, statuses_of
from mill_analysis.node_intake import MessageLog, Received
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.recorder import TopicRecorder, message_class
from mill_bag.types import CLOCK, DIAGNOSTIC_ARRAY
from mill_common.checks import CONTESTED, FOREIGN, UNKNOWN
from mill_common.codec import encode_clock
from mill_common.graph_owner import GidSubscription
from mill_common.ros import LATCHED_QOS, RECORD_QOS, graph_owners
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg

from mill_bringup.bag_handshake import RecordedSteps
from mill_common import topics

# [s] between two writes of the runner's bag: the topics outside the lockstep handshake
# (/clock, the reference, /diagnostics, logs) a SIGKILL of the runner may lose; and, as the
# steps are acknowledged after each write, at most recorder_window steps per period go out
# (docs/reliability.md, "Recording through a crash").
FLUSH_PERIOD = 0.25
# [s] between two acknowledgements of a run without a bag: often enough that the clock node,
# recorder_window steps ahead at most, never waits on a runner that keeps up.
ACK_PERIOD = 0.05
# The levels of a status that is a problem (Status.level: the DiagnosticStatus byte's value)
WARN, ERROR = DiagnosticStatus.WARN[0], DiagnosticStatus.ERROR[0]


class _AcknowledgingRecorder(TopicRecorder):
    """A TopicRecorder that, after each write of its bag, acknowledges the steps it holds."""

    def __init__(self, *args: Any, written: Callable[[], None], **kwargs: Any) -> None:
        self._written = written
        super().__init__(*args, **kwargs)

    def flush(self) -> None:
        super().flush()
        if not (self.closed or self.writer.closed):  # a bag cut short holds nothing more
            self._written()


@dataclass(frozen=True)
class RecordOptions:
    path: Path
    sim_time: bool = True
    compression: str = 'zstd'
    flush_period: float = FLUSH_PERIOD
    notes: Mapping[str, str] = field(default_factory=dict)  # the bag's custom_data


def _own_topics(namespace: str) -> str:
    """What discovery adds to a run's bag: every topic in the root namespace; under a machine
    namespace its own topics and the global logs (not another machine's topics)."""
    if namespace == topics.ROOT:
        return ''
    return f'^{re.escape(namespace)}/|^/(rosout|parameter_events)$'


class Monitor(Node):
    def __init__(
        self,
        kept: Mapping[str, str],
        record: RecordOptions | None = None,
        recorded: Mapping[str, str] | None = None,
        name: str = 'mill_monitor',
        namespace: str = topics.ROOT,
        remappings: Sequence[str] = (),
        timed: Iterable[str] = (),
        late: Iterable[str] = (),
        late_after: Iterable[str] = (),
        steps: RecordedSteps | None = None,
        owners: Mapping[str, str] | None = None,
    ) -> None:
        """owners: the node each per-sample topic must come from (the job's owners): a
        message whose publisher the graph shows as another node (mill_common.graph_owner:
        its GID), or as one of two claiming the owner's name, is neither kept, recorded nor
        acknowledged, but counted in `refused` and named in `problems`."""
        rules = [
            arg for rule in remappings if not rule.startswith('__ns:=') for arg in ('-r', rule)
        ]
        super().__init__(
            name, namespace=namespace, cli_args=['--ros-args', *rules] if rules else None
        )
        self.ns = self.get_namespace()  # kept: read after the node is destroyed too
        self.raw = Received()
        self._owners = {t: o for t, o in (owners or {}).items() if o}
        self._graph = graph_owners(self) if self._owners else None
        self.refused: dict[str, dict[str, int]] = {}  # topic -> publisher -> messages left out
        self.arrivals: dict[str, list[int]] = {t: [] for t in timed}
        # Subscribed to only once a message arrived on each topic of `late_after`
        # (subscribe_late): a node that waits for its readers then waits for this monitor to
        # hear those topics (a realtime job's trajectory, for the drive's states).
        self._late = set(late)
        self._late_after = list(late_after)
        self._held: list[tuple[str, str, Callable[[bytes], None], Callable | None]] = []
        self._statuses: list[Status] = []  # of this machine, in the order they arrived
        self.recorder: TopicRecorder | None = None
        # A lockstep run's handshake: the steps heard whole (recording: written whole to the
        # bag) are acknowledged on mill/recorded, and the clock node waits for that.
        self.steps = steps if steps is None or record is not None else steps.only(kept)
        if self.steps is not None:
            self._ack_pub = self.create_publisher(ClockMsg, topics.RECORDED, LATCHED_QOS)
            if record is None:  # nothing to write first: what is heard is acknowledged
                self.create_timer(ACK_PERIOD, self._written)
        if record is not None:
            self.recorder = _AcknowledgingRecorder(
                self,
                record.path,
                written=self._written,
                regex=_own_topics(self.get_namespace()),
                sim_time=record.sim_time,
                compression=record.compression,
                flush_period=record.flush_period,
                custom_data=record.notes,
            )
        for topic, msgtype in kept.items():
            self._keep(topic, msgtype)
        # Every status kept, as every sample (RECORD_QOS): the job's events (a trip, a stop)
        # are parsed from them, and a KEEP_LAST reader drops the oldest while the runner is
        # short of CPU.
        self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self._heard, RECORD_QOS)
        if self.recorder is not None:
            # The rest of the contract, subscribed before the graph starts so that the
            # first step is recorded (and kept: the record counts it); discovery adds any
            # other topic.
            for topic, msgtype in (recorded or {}).items():
                if topic not in kept:
                    self._keep(topic, msgtype)
            self.recorder.subscribe(topics.CLOCK, CLOCK, RECORD_QOS)
            diag_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
            self.recorder.subscribe(topics.DIAGNOSTICS, DIAGNOSTIC_ARRAY, diag_qos)
        if self._held:
            self._late_timer = self.create_timer(0.05, self.subscribe_late)

    def _keep(self, topic: str, msgtype: str) -> None:
        store = self.raw.get(topic)
        if not isinstance(store, MessageLog):  # compact: a few bytes a message, not an object
            store = MessageLog()
            self.raw[topic] = store
        order = self.raw.order
        arrivals = self.arrivals.get(topic)
        if arrivals is None:

            def keep(data: bytes) -> None:
                store.append(data)
                order.append(topic)

        else:  # when each message came, on the system clock (latency)

            def keep(data: bytes) -> None:
                store.append(data)
                order.append(topic)
                arrivals.append(time.time_ns())

        self._listen(topic, msgtype, keep)

    def _listen(self, topic: str, msgtype: str, keep: Callable[[bytes], None] | None) -> None:
        """Subscribe to a topic of the job: keep its messages (if `keep`), record them (if
        recording), acknowledge the steps recorded whole (if the topic is stepped)."""
        actions = [keep] if keep is not None else []
        if self.recorder is not None:
            actions.append(self.recorder.tap(topic, msgtype))
        ack = None
        if self.steps is not None and self.steps.stepped(topic):
            actions.append(ack := self._acknowledger(topic))
        if len(actions) == 1:
            on_msg = actions[0]
        else:

            def on_msg(data: bytes) -> None:
                for action in actions:
                    action(data)

        if topic in self._late:
            self._held.append((topic, msgtype, on_msg, ack))
        else:
            self._subscribe(topic, msgtype, on_msg, ack)

    def _subscribe(
        self,
        topic: str,
        msgtype: str,
        on_msg: Callable[[bytes], None],
        ack: Callable[[bytes], None] | None = None,
    ) -> None:
        """A raw subscription; of an owned topic, with each message's publisher GID. A
        message of a contested owner's name (two publishers claim it) is left out, but still
        answers its step (`ack`, of a stepped topic): the drive took it as a brake request
        and stepped, and the plant waits for the runner to acknowledge the step."""
        owner, graph = self._owners.get(topic), self._graph
        if owner is None or graph is None:
            self.create_subscription(message_class(msgtype), topic, on_msg, RECORD_QOS, raw=True)
            return
        resolved = graph.watch(topic, owner)
        refused = self.refused

        def on_owned(data: bytes, gid: bytes) -> None:
            who = graph.verdict(resolved, gid)
            if who.verdict in (FOREIGN, CONTESTED):
                per = refused.setdefault(topic, {})
                per[who.name] = per.get(who.name, 0) + 1
                if who.verdict == CONTESTED and ack is not None:
                    ack(data)
                return
            if who.verdict == UNKNOWN and who.claimants:
                return  # not the owner's, whom the graph shows: its drive drops it too
            on_msg(data)

        GidSubscription(self, message_class(msgtype), topic, on_owned, RECORD_QOS)

    def subscribe_late(self) -> None:
        """Subscribe to the late topics once every `late_after` topic has a message."""
        if not self._held or not all(self.raw.get(t) for t in self._late_after):
            return
        for topic, msgtype, on_msg, ack in self._held:
            self._subscribe(topic, msgtype, on_msg, ack)
        self._held = []
        self.destroy_timer(self._late_timer)

    def finish_recording(self, samples: int) -> None:
        """The job's samples are done: the plant may take one more step, then waits for
        the runner (and its bag) to hold everything up to it (a lockstep run's handshake;
        else nothing)."""
        if self.steps is None:
            return
        if self.recorder is not None:
            self.recorder.flush()  # what it holds is written: the freeze may acknowledge it
        if (through := self.steps.freeze(samples)) is not None:
            self._ack_pub.publish(encode_clock(through))

    def _written(self) -> None:
        """The bag's file (without a bag: the monitor) holds what was heard so far:
        acknowledge the steps it holds whole."""
        if self.steps is not None and (through := self.steps.written()) is not None:
            self._ack_pub.publish(encode_clock(through))

    def _acknowledger(self, topic: str) -> Callable[[bytes], None]:
        assert self.steps is not None
        heard = self.steps.heard

        def note(data: bytes) -> None:
            ns = cdr_stamp_ns(data)
            if ns is not None:
                heard(topic, ns)

        return note

    # -- what a job reads (mill_bringup.jobs.base.MessageSource) ----------------------------
    def messages(self, topic: str) -> Sequence[bytes]:
        return self.raw.get(topic, ())

    def arrival_ns(self, topic: str) -> Sequence[int]:
        return self.arrivals.get(topic, ())

    def latest_stamp_ns(self, topic: str) -> int:
        """Stamp of the newest message of a topic (one writer delivers in order), -1 if none.

        Counting messages is not enough to know a topic is complete: a step offered twice
        at the start is answered twice.
        """
        store = self.raw.get(topic)
        stamp = cdr_stamp_ns(store[-1]) if store else None
        return -1 if stamp is None else stamp

    def _heard(self, array: DiagnosticArray) -> None:
        self._statuses += statuses_of([array], self.ns)

    def status(self, name: str) -> dict[str, str] | None:
        """The newest /diagnostics status of this machine with this name's node and part
        (topics.status_key: the name may leave out the namespace): its values, 'message'
        and 'level'."""
        key = topics.status_key(name)
        for s in reversed(self._statuses):
            if topics.status_key(s.name) == key:
                return dict(s.values) | {'message': s.message, 'level': str(s.level)}
        return None

    def statuses(self) -> list[Status]:
        """Every /diagnostics status of this machine heard so far, in order, with its values
        (mill_analysis.events reads them)."""
        return list(self._statuses)

    def problems(self) -> list[str]:
        """Every WARN or ERROR status heard on /diagnostics, once each, in order."""
        seen: dict[str, None] = {}
        for s in self._statuses:
            if s.level in (WARN, ERROR):
                seen.setdefault(f'{s.name}: {s.message}', None)
        for topic, per in self.refused.items():
            for who, n in per.items():
                seen.setdefault(
                    f'{self.get_name()}: left out {n} messages on {topic} from {who} '
                    f'(by its publisher GID, not the owner {self._owners[topic]})',
                    None,
                )
        return list(seen)

    def close_recording(self) -> None:
        """Write what is buffered and close the bag (idempotent)."""
        if self.recorder is None:
            return
        try:
            self.recorder.close()
        except ValueError:
            if self.recorder.error is None:
                raise  # a new failure; an earlier one has been reported already
