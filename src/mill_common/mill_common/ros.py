"""Thin ROS helpers shared by the nodes: QoS, stamps, message construction."""

from __future__ import annotations

from collections.abc import Sequence

from builtin_interfaces.msg import Time
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
) -> JointState:
    msg = JointState()
    msg.header.stamp = to_stamp(ns)
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
