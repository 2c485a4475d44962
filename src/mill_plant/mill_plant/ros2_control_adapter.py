"""The drive's ROS side of topic_based_ros2_control's topic pair (mill_plant.topic_pair).

Made by the drive front end (mill_plant.drive_node) at its first configure when
`ros2_control.commands_topic` is set: it takes the hardware interface's commands (one
sensor_msgs/JointState for every joint, with the graph's word on its publisher,
mill_common.graph_owner) and publishes the states it reads, every sample: the measured
position, the velocity (the difference of the last two positions over their stamps, NaN
at the first) and the effort applied over the period that ends at the stamp (NaN: braked)
of each axis, `header.frame_id` empty.

A command of the right shape goes to the drive axis by axis, through the same intake,
ownership, table and protection as a mill controller's (`take`); the first axis whose
command is dropped as foreign ends the message, so that a foreign message is counted and
named once, not once per joint.

QoS: the commands are taken as mill's are (DATA_QOS: RELIABLE, KEEP_LAST 2000): a reader's
history is shared by every writer of a topic, so at depth 1 a foreign publisher's flood
would replace the owner's commands before the drive took them (the axes would brake on the
owner's silence, seen in the test). The states go out RELIABLE, KEEP_LAST 1, VOLATILE (only
the newest matters). The hardware interface publishes its commands RELIABLE (depth 1) and
reads its states BEST_EFFORT (rclcpp's SensorDataQoS), which a reliable writer serves.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from mill_common.checks import FOREIGN, Rejected, Sender
from mill_common.codec import decode_joint_state
from mill_common.graph_owner import GraphOwners
from mill_common.ros import DATA_QOS, data_publisher, joint_state_bytes, take_owned
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from mill_plant.command_intake import Accepted, Dropped
from mill_plant.joint_states import JointStates
from mill_plant.topic_pair import Ros2ControlParams, command_shape

STATES_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    durability=DurabilityPolicy.VOLATILE,
)

# take(axis, topic, msg, sender): the drive's verdict on the axis's command in msg
Take = Callable[[str, str, Any, Sender], Accepted | Dropped | None]


class Ros2ControlPair:
    def __init__(
        self,
        node: Node,
        axes: Sequence[str],
        params: Ros2ControlParams,
        period: float,
        graph: GraphOwners,
        take: Take,
        drop: Callable[[str, Rejected, str], None],
        foreign: Callable[[str, str], None],
    ) -> None:
        """drop(topic, problem, sender): a message refused before any axis saw it;
        foreign(topic, sender): it came from a node the graph says is not the owner."""
        self.axes = tuple(axes)
        self.commands_topic = params.commands_topic
        self.states_topic = params.states_topic
        self.owner = params.owner
        self._take = take
        self._drop = drop
        self._foreign = foreign
        self._joints = JointStates(self.axes, 1.0 / period, period)  # every sample
        self.states = data_publisher(node, JointState, self.states_topic, STATES_QOS)
        self.commands = take_owned(
            node,
            JointState,
            self.commands_topic,
            decode_joint_state,
            self._on_message,
            DATA_QOS,
            lambda problem: drop(self.commands_topic, problem, ''),
            graph,
            self.owner,
        )
        self.messages = 0  # commands heard, taken or not

    def _on_message(self, msg: Any, who: Sender) -> None:
        self.messages += 1
        topic = self.commands_topic
        problem = command_shape(msg.name, msg.position, msg.velocity, msg.effort, self.axes)
        if problem is not None:
            named = who.called(msg.header.frame_id)
            if who.verdict == FOREIGN:
                self._foreign(topic, named)
            self._drop(topic, problem, named)
            return
        for axis in msg.name:
            got = self._take(axis, topic, msg, who)
            if isinstance(got, Dropped) and got.foreign:
                return  # the same sender for every joint: said once

    def publish(self, ns: int, positions: Sequence[float], efforts: Sequence[float]) -> None:
        """The states of sample ns for the hardware interface's read()."""
        joints = self._joints.sample(ns, positions, efforts)  # every sample: the velocity
        if joints is not None and self.states.get_subscription_count():
            self.states.publish(
                joint_state_bytes(ns, joints.names, joints.position, joints.velocity, joints.effort)
            )
