"""The topics a drive (mill_plant.drive_node) makes at configure, and which peers they lack.

Per axis it publishes the state and takes the command, each with the graph's word on its
publisher (mill_common.graph_owner); for the ROS tools it publishes every axis in one
message (`joint_states`, mill_plant.joint_states); over a simulated machine it also
publishes the ground truth and the cutting force; with `spindle: reference` it takes the
reference (mill_plant.spindle). Bytes that are no message go to `drop` with their topic.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Any

from geometry_msgs.msg import WrenchStamped
from mill_common.checks import Rejected, Sender
from mill_common.codec import decode_joint_state, decode_joint_trajectory
from mill_common.graph_owner import GraphOwners
from mill_common.intra_process import DataOutput
from mill_common.ros import DATA_QOS, DataInput, data_publisher, take_owned, take_serialized
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics


class DriveTopics:
    def __init__(
        self,
        node: Node,
        axes: Sequence[str],
        simulated: bool,
        on_command: Callable[[str, Any, Sender], None],
        on_reference: Callable[[Any], None] | None,  # None: no spindle: reference
        drop: Callable[[str, Rejected], None],
        graph: GraphOwners,
        owners: Mapping[str, str],
    ) -> None:
        """on_command(axis, msg, sender): sender is the graph's verdict on its publisher
        against owners[axis] (mill_common.graph_owner)."""
        self.states = {a: data_publisher(node, JointState, topics.state(a), DATA_QOS) for a in axes}
        self.joint_states = data_publisher(node, JointState, topics.JOINT_STATES, DATA_QOS)
        self.truth: DataOutput | None = None
        self.force: DataOutput | None = None
        if simulated:
            self.truth = data_publisher(node, JointState, topics.GROUND_TRUTH, DATA_QOS)
            self.force = data_publisher(node, WrenchStamped, topics.CUTTING_FORCE, DATA_QOS)
        self.commands = {
            a: take_owned(
                node,
                JointState,
                topics.joint_command(a),
                decode_joint_state,
                partial(on_command, a),
                DATA_QOS,
                partial(drop, topics.joint_command(a)),
                graph,
                owners[a],
            )
            for a in axes
        }
        self.reference: DataInput | None = None
        if on_reference is not None:
            self.reference = take_serialized(
                node,
                JointTrajectory,
                topics.REFERENCE,
                decode_joint_trajectory,
                on_reference,
                DATA_QOS,
                partial(drop, topics.REFERENCE),
            )

    def missing_peers(self, need: int) -> list[str]:
        """What the drive still waits for: a publisher on each input, `need` subscribers on
        each state topic."""
        missing = []
        if self.reference is not None and self.reference.get_publisher_count() < 1:
            missing.append(f'no publisher on {topics.REFERENCE} (spindle: reference)')
        for axis, sub in self.commands.items():
            if sub.get_publisher_count() < 1:
                missing.append(f'no publisher on {topics.joint_command(axis)}')
            have = self.states[axis].get_subscription_count()
            if have < need:
                missing.append(f'{have}/{need} subscribers on {topics.state(axis)}')
        return missing
