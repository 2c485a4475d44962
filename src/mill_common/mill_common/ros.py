"""Thin ROS helpers shared by the nodes: QoS, stamps, message construction."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

# Lockstep data must not be lost, and a slow listener (recorder, monitor) must
# not lose samples while it catches up: reliable, deep history.
DATA_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    history=HistoryPolicy.KEEP_LAST,
    depth=2000,
    durability=DurabilityPolicy.VOLATILE,
)


def to_stamp(ns: int) -> Time:
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def from_stamp(stamp: Time) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def from_duration(duration) -> int:
    """builtin_interfaces/Duration in nanoseconds."""
    return duration.sec * 1_000_000_000 + duration.nanosec


def joint_state(
    ns: int,
    names: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
    sender: str = '',
) -> JointState:
    """A stamped JointState; `sender` (header.frame_id) names the publishing node, which
    the receivers check against the owner of the topic."""
    msg = JointState()
    msg.header.stamp = to_stamp(ns)
    msg.header.frame_id = sender
    msg.name = list(names)
    msg.position = [float(v) for v in position]
    msg.velocity = [float(v) for v in velocity]
    msg.effort = [float(v) for v in effort]
    return msg


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
