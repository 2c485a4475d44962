"""Intra-process delivery: nodes that share a process hand each other the serialized bytes.

rclpy has no intra-process communication (rclcpp's `use_intra_process_comms`): a message
between two nodes of one container still goes through DDS, an executor event and a take
for every reader. This module is that shortcut for the hot-path topics of a container
(`mill_container`, the `per_axis` and `single` layouts):

- a publisher made with `data_publisher` publishes to DDS as always (the runner, a
  recorder, a tool, a node on another host hear it) and puts the same bytes in a queue
  for each subscriber of the topic in this process;
- a subscription made with `data_subscription` takes from DDS only while no node of this
  process publishes its topic; once one does, its DDS subscription is destroyed and it
  gets that publisher's bytes from the queue instead;
- the spin loop (`mill_common.node_main.run_nodes`) drains the queue between executor
  events, so callbacks never run inside one another and each sees the bytes a DDS take
  would have given it, in the order they were published;
- a publisher made `deferred` (what no loop waits for: estimates, internal states) hands
  its bytes to this process's subscribers at once but to DDS only once the process has
  nothing more urgent to do: when the spin loop finds no data callback ready, so the
  commands of a servo cycle go out first (`flush_later`).

A topic has one legitimate publisher (docs/reliability.md, "one owner per axis"); when it
is in this process, messages of any other publisher on the topic are not taken here at
all. A check once a second names such publishers in the subscribing node's log.

Off unless `enable()` is called (a process of one node gains nothing); the environment
variable MILL_INTRA_PROCESS=0 keeps it off in a container too (to measure the difference).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import QoSProfile
from rclpy.serialization import serialize_message
from rclpy.subscription import Subscription

from mill_common.graph_owner import LOCAL, GidSubscription

ENV = 'MILL_INTRA_PROCESS'
CHECK_PERIOD = 1.0  # s between looks for publishers outside the process on a local topic


class DataOutput(Protocol):
    """What a node uses of a publisher (rclpy's Publisher has it too)."""

    @property
    def topic_name(self) -> str: ...

    def publish(self, msg: Any) -> None: ...

    def get_subscription_count(self) -> int: ...


class DataInput(Protocol):
    """What a node uses of a subscription (rclpy's Subscription has it too)."""

    def get_publisher_count(self) -> int: ...


@dataclass(eq=False)
class _Input:
    node: Node
    msg_type: Any
    topic: str  # resolved name
    callback: Callable[[bytes], None]
    qos: QoSProfile | int
    dds: Subscription | GidSubscription | None = None
    with_gid: Callable[[bytes, bytes], None] | None = None  # the callback wants the GID

    def take_dds(self) -> Subscription | GidSubscription:
        if self.with_gid is not None:
            return GidSubscription(self.node, self.msg_type, self.topic, self.with_gid, self.qos)
        return self.node.create_subscription(
            self.msg_type, self.topic, self.callback, self.qos, raw=True
        )

    def get_publisher_count(self) -> int:
        if self.dds is not None:
            return self.dds.get_publisher_count()
        return self.node.count_publishers(self.topic)


class _Output:
    """A publisher whose bytes also go straight to this process's subscribers."""

    def __init__(
        self, bus: IntraProcess, publisher: Publisher, topic: str, deferred: bool = False
    ) -> None:
        self._bus = bus
        self._publisher = publisher
        self._topic = topic
        self._inputs = bus.inputs(topic)  # the list itself: later subscribers join it
        self._deferred = deferred

    @property
    def topic_name(self) -> str:
        return self._topic

    def publish(self, msg: Any) -> None:
        if self._deferred:
            self._bus.later.append((self._publisher, msg))
        else:
            self._publisher.publish(msg)
        if self._inputs:
            data = msg if isinstance(msg, bytes) else serialize_message(msg)
            queue = self._bus.queue
            for listener in self._inputs:
                queue.append((listener.callback, data))

    def get_subscription_count(self) -> int:
        """Readers over DDS and in this process."""
        return self._publisher.get_subscription_count() + len(self._inputs)


class IntraProcess:
    """The delivery of one process: its local publishers, subscribers and the queue."""

    def __init__(self) -> None:
        self.enabled = False
        self.queue: deque[tuple[Callable[[bytes], None], bytes]] = deque()
        self.later: list[tuple[Publisher, Any]] = []  # DDS publishes that wait (deferred)
        self.activity = 0  # data callbacks run: the spin loop tells busy from idle by it
        self._inputs: dict[str, list[_Input]] = {}
        self._outputs: dict[str, int] = {}  # resolved topic -> local publishers
        self._reported: dict[str, frozenset[str]] = {}
        self._checking = False
        self._local_nodes: dict[str, list[str]] = {}  # resolved topic -> its local publishers

    def enable(self) -> None:
        self.enabled = os.environ.get(ENV, '1') != '0'

    def inputs(self, topic: str) -> list[_Input]:
        return self._inputs.setdefault(topic, [])

    def local(self, topic: str) -> bool:
        """Whether a node of this process publishes `topic` (resolved)."""
        return self._outputs.get(topic, 0) > 0

    def local_publishers(self, topic: str) -> list[str]:
        """The nodes of this process ('/ns/name') that publish `topic` (resolved)."""
        return self._local_nodes.get(topic, [])

    # -- what nodes call ---------------------------------------------------------------------
    def publisher(
        self,
        node: Node,
        msg_type: Any,
        topic: str,
        qos: QoSProfile | int,
        deferred: bool = False,
    ) -> Any:
        """A publisher of a hot-path topic; delivers in-process too when enabled. deferred:
        nothing waits for it, its DDS publish comes when the process is idle."""
        publisher = node.create_publisher(msg_type, topic, qos)
        if not self.enabled:
            return publisher
        resolved = publisher.topic_name
        self._outputs[resolved] = self._outputs.get(resolved, 0) + 1
        name = f'{node.get_namespace().rstrip("/")}/{node.get_name()}'
        self._local_nodes.setdefault(resolved, []).append(name)
        for listener in self.inputs(resolved):
            self._drop_dds(listener)
        self._watch(node)
        return _Output(self, publisher, resolved, deferred)

    def subscribe(
        self,
        node: Node,
        msg_type: Any,
        topic: str,
        callback: Callable[[bytes], None] | None,
        qos: QoSProfile | int,
        with_gid: Callable[[bytes, bytes], None] | None = None,
    ) -> DataInput:
        """A raw (bytes) subscription; takes from this process's publisher when there is one.

        with_gid (instead of callback): the callback gets each message's publisher GID too
        (mill_common.graph_owner; LOCAL for a message of this process's publisher)."""
        if with_gid is not None:
            gid_callback = with_gid

            def callback(data: bytes) -> None:
                gid_callback(data, LOCAL)

        assert callback is not None, 'a callback, or with_gid'
        resolved = node.resolve_topic_name(topic)
        listener = _Input(node, msg_type, resolved, callback, qos, with_gid=with_gid)
        if not self.enabled:
            return listener.take_dds()
        self.inputs(resolved).append(listener)
        if not self.local(resolved):
            listener.dds = listener.take_dds()
        self._watch(node)
        return listener

    def mute(self, handle: DataInput) -> None:
        """A subscription whose messages reach its node another way (a servo cycle): it
        takes nothing any more, from DDS or this process, yet still counts as a reader of
        its topic for a publisher in this process."""
        if isinstance(handle, _Input):
            self._drop_dds(handle)
            handle.callback = _ignore

    def unsubscribe(self, node: Node, handle: DataInput) -> None:
        """End a subscription made by `subscribe`: no more messages reach its callback."""
        if isinstance(handle, _Input):
            listeners = self.inputs(handle.topic)
            if handle in listeners:
                listeners.remove(handle)
            self._drop_dds(handle)
            for i, (callback, _data) in reversed(list(enumerate(self.queue))):
                if callback is handle.callback:
                    del self.queue[i]  # queued for it already: not delivered either
        elif isinstance(handle, Subscription):
            node.destroy_subscription(handle)
        elif isinstance(handle, GidSubscription):
            handle.destroy()

    # -- what the spin loop calls ------------------------------------------------------------
    def pending(self) -> bool:
        return bool(self.queue)

    def flush_later(self) -> None:
        """Publish to DDS what deferred publishers sent, in order."""
        later, self.later = self.later, []
        for publisher, msg in later:
            publisher.publish(msg)

    def drain(self, budget: int) -> None:
        """Deliver queued messages, at most `budget` (callbacks may queue more)."""
        queue = self.queue
        for _ in range(budget):
            if not queue:
                return
            callback, data = queue.popleft()
            callback(data)

    # -- internals ---------------------------------------------------------------------------
    @staticmethod
    def _drop_dds(listener: _Input) -> None:
        if isinstance(listener.dds, GidSubscription):
            listener.dds.destroy()
        elif listener.dds is not None:
            listener.node.destroy_subscription(listener.dds)
        listener.dds = None

    def _watch(self, node: Node) -> None:
        if self._checking:
            return
        self._checking = True
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        node.create_timer(CHECK_PERIOD, self._check_outsiders, clock=steady)

    def _check_outsiders(self) -> None:
        """Name, once per change, publishers outside this process on a topic taken here."""
        for topic, listeners in self._inputs.items():
            if not listeners or not self.local(topic):
                continue
            node = listeners[0].node
            if node.count_publishers(topic) <= self._outputs[topic]:
                continue  # the usual case, and 10x cheaper to ask than the publishers' names
            infos = node.get_publishers_info_by_topic(topic)
            outside = len(infos) - self._outputs[topic]
            names = frozenset(f'{i.node_namespace.rstrip("/")}/{i.node_name}' for i in infos)
            if outside > 0 and self._reported.get(topic) != names:
                self._reported[topic] = names
                node.get_logger().warning(
                    f'{topic}: {outside} publisher(s) besides the one in this process '
                    f'({", ".join(sorted(names))}); their messages are not taken here'
                )


def _ignore(data: bytes) -> None:
    pass


_BUS = IntraProcess()


def bus() -> IntraProcess:
    """This process's delivery."""
    return _BUS


# What the nodes call: publishers and raw (bytes) subscriptions of the hot-path topics.
data_publisher = _BUS.publisher
data_subscription = _BUS.subscribe
data_unsubscribe = _BUS.unsubscribe
data_mute = _BUS.mute
