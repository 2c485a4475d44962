"""Thin ROS helpers shared by the nodes: QoS, stamps, message construction, and the
serialized publish and take of the hot-path messages (mill_common.codec; in-process
delivery between the nodes of a container: mill_common.intra_process)."""

from __future__ import annotations

import weakref
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from mill_common import intra_process
from mill_common.checks import Rejected, Sender
from mill_common.codec import CodecError, encode_joint_state
from mill_common.graph_owner import GraphOwners
from mill_common.intra_process import DataInput as DataInput  # for the nodes
from mill_common.intra_process import data_mute as data_mute  # for the nodes
from mill_common.intra_process import data_publisher as data_publisher  # for the nodes
from mill_common.intra_process import data_subscription
from mill_common.intra_process import data_unsubscribe as data_unsubscribe  # for the nodes
from mill_common.timebase import time_ns

# Lockstep data must not be lost, and a slow listener (recorder, monitor) must
# not lose samples while it catches up: reliable, deep history.
DATA_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    history=HistoryPolicy.KEEP_LAST,
    depth=2000,
    durability=DurabilityPolicy.VOLATILE,
)

# A listener that must not lose what it fell behind on (the runner's monitor and recorder):
# DDS keeps every sample that reached it until it takes them. A KEEP_LAST reader dropped
# the oldest silently when its process took nothing for a while (no message_lost event);
# with KEEP_ALL only a writer whose own history overflows can lose one, and that is
# reported (mill_bag.recorder: Losses).
RECORD_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    history=HistoryPolicy.KEEP_ALL,
    durability=DurabilityPolicy.VOLATILE,
)

# The newest value only, kept for a reader that joins later (an acknowledgement, a status).
LATCHED_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


def to_stamp(ns: int) -> Time:
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


# builtin_interfaces/Time and Duration in nanoseconds: the one conversion, ROS-free
from_stamp = from_duration = time_ns


def joint_state(
    ns: int,
    names: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
    sender: str = '',
) -> JointState:
    """A stamped JointState; `sender` (header.frame_id) names the publishing node: a claim
    the receivers check agrees with the publisher GID (mill_common.graph_owner)."""
    msg = JointState()
    msg.header.stamp = to_stamp(ns)
    msg.header.frame_id = sender
    msg.name = list(names)
    msg.position = [float(v) for v in position]
    msg.velocity = [float(v) for v in velocity]
    msg.effort = [float(v) for v in effort]
    return msg


def joint_state_bytes(
    ns: int,
    names: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
    sender: str = '',
) -> bytes:
    """`joint_state` as the CDR bytes a publisher sends (`publish(bytes)`): the same message
    on the wire, without building the rclpy object (mill_common.codec)."""
    return encode_joint_state(ns, sender, names, position, velocity, effort)


# The bytes, decoder and decoded message of the last take: in-process delivery
# (mill_common.intra_process) hands the same bytes object to each reader of a message, and
# the readers only read what they are given.
_last_decoded: list[Any] = [None, None, None]


def take_serialized(
    node: Node,
    msg_type: Any,
    topic: str,
    decode: Callable[[bytes], Any],
    callback: Callable[[Any], None],
    qos: QoSProfile | int,
    malformed: Callable[[Rejected], None],
) -> DataInput:
    """Subscribe to `topic` taking the serialized bytes; `callback` gets them decoded by
    `decode` (a mill_common.codec reader: an object with the message's fields), and bytes
    that are not a `msg_type` go to `malformed` as one Rejected line instead."""

    bus = intra_process.bus()

    def take(data: bytes) -> None:
        bus.activity += 1
        last = _last_decoded
        if data is last[0] and decode is last[1]:
            callback(last[2])  # the same bytes handed to another reader in this process
            return
        try:
            msg = decode(data)
        except CodecError as exc:
            malformed(Rejected(f'malformed message: {exc}'))
            return
        last[:] = (data, decode, msg)
        callback(msg)

    return data_subscription(node, msg_type, topic, take, qos)


def graph_owners(
    node: Node, on_contested: Callable[[str, str, tuple[str, ...]], None] | None = None
) -> GraphOwners:
    """The senders of a node's owned inputs as the graph identifies them
    (mill_common.graph_owner), looked at again once a second."""
    from rclpy.clock import Clock, ClockType

    graph = GraphOwners(node, intra_process.bus().local_publishers, on_contested)
    node.create_timer(1.0, graph.look, clock=Clock(clock_type=ClockType.STEADY_TIME))
    return graph


def take_owned(
    node: Node,
    msg_type: Any,
    topic: str,
    decode: Callable[[bytes], Any],
    callback: Callable[[Any, Sender], None],
    qos: QoSProfile | int,
    malformed: Callable[[Rejected], None],
    graph: GraphOwners,
    owner: str,
) -> DataInput:
    """`take_serialized` of an input that belongs to `owner` (a node name, '' anyone):
    `callback` gets each message with its `Sender`, the graph's verdict on its publisher
    GID (mill_common.graph_owner). The message is decoded whoever sent it: a drop names what
    the sender says it is (frame_id) beside what the graph says."""
    bus = intra_process.bus()
    resolved = graph.watch(topic, owner)
    verdict = graph.verdict

    def take(data: bytes, gid: bytes) -> None:
        bus.activity += 1
        last = _last_decoded
        if data is last[0] and decode is last[1]:
            msg = last[2]  # the same bytes handed to another reader in this process
        else:
            try:
                msg = decode(data)
            except CodecError as exc:
                malformed(Rejected(f'malformed message: {exc}'))
                return
            last[:] = (data, decode, msg)
        callback(msg, verdict(resolved, gid))

    return data_subscription(node, msg_type, topic, None, qos, with_gid=take)


_readers_matched: weakref.WeakSet[Any] = weakref.WeakSet()


def readers_ready(node: Node, publisher: Any, need: int) -> bool:
    """Whether `publisher` has `need` subscribers; else log (once a second) that the node
    waits for them. A lockstep node started mid-job answers the plant's re-offered step only
    then, so that its first outputs are not lost to a reader that has not matched it yet."""
    if publisher in _readers_matched:
        return True
    have = publisher.get_subscription_count()
    if have >= need:
        _readers_matched.add(publisher)  # asked once: readers that matched stay for the job
        return True
    node.get_logger().info(
        f'waiting for {need} readers of {publisher.topic_name} ({have} so far)',
        throttle_duration_sec=1.0,
    )
    return False


def first(values: Sequence[float], what: str) -> float:
    """The single value of a one-joint message field; ValueError if it is missing."""
    if len(values) < 1:
        raise ValueError(f'message has no {what} value')
    return float(values[0])


def diagnostic_status(
    level: bytes,
    name: str,
    message: str,
    hardware_id: str,
    values: Mapping[str, object] | None = None,
) -> DiagnosticStatus:
    """One DiagnosticStatus; values as text (floats exact: str = repr)."""
    return DiagnosticStatus(
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[KeyValue(key=k, value=str(v)) for k, v in (values or {}).items()],
    )


def diagnostic_array(
    ns: int,
    level: bytes,
    name: str,
    message: str,
    hardware_id: str,
    values: Mapping[str, object],
) -> DiagnosticArray:
    """One DiagnosticStatus in an array stamped ns."""
    return diagnostics_of(ns, [diagnostic_status(level, name, message, hardware_id, values)])


def diagnostics_of(ns: int, statuses: Sequence[DiagnosticStatus]) -> DiagnosticArray:
    """Several statuses in one array stamped ns."""
    array = DiagnosticArray(status=list(statuses))
    array.header.stamp = to_stamp(ns)
    return array
