"""Axis controller node: one axis, one process.

For every sample it joins the measured position (/mill/<axis>/state), the
observer's estimate (/mill/<axis>/estimate) and the reference point of that
time (/mill/reference, several points per message) by stamp, runs the
selected control law and publishes the torque on /mill/<axis>/joint_command
with the same stamp.
"""

from __future__ import annotations

import math
import time
from typing import Any

from mill_common.node_main import run_node
from mill_common.ros import DATA_QOS, first, from_duration, from_stamp, joint_state
from mill_common.ros_params import NodeParameters
from mill_common.signals import AxisReference, Estimate
from mill_common.stamp_join import StampJoin
from mill_common.timebase import seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_controllers.config import build_controller, parameter_specs

INPUT_TOPICS = {'state': topics.state, 'estimate': topics.estimate}


class AxisControllerNode(Node):
    def __init__(self) -> None:
        super().__init__('axis_controller')
        self._law = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        axis = self.axis = self.params.values['axis']
        self._join = StampJoin(('state', 'estimate', 'reference'))
        self._last_ns = -1
        self._last_command: JointState | None = None
        self._waiting_since: float | None = None
        self._pub = self.create_publisher(JointState, topics.joint_command(axis), DATA_QOS)
        self.create_subscription(JointState, topics.state(axis), self._on_state, DATA_QOS)
        self.create_subscription(JointState, topics.estimate(axis), self._on_estimate, DATA_QOS)
        self.create_subscription(JointTrajectory, topics.REFERENCE, self._on_reference, DATA_QOS)
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: controller {self.params.values["controller"]}, '
            f'commands on {topics.joint_command(axis)}'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._law is not None and values['axis'] != self.axis:
            raise ValueError('axis is fixed for the life of the node')
        self._law = build_controller(values)

    # -- inputs ----------------------------------------------------------------------------
    def _fresh(self, ns: int) -> bool:
        if ns == self._last_ns and self._last_command is not None:
            self._pub.publish(self._last_command)  # the plant offered this step again
        return ns > self._last_ns

    def _on_state(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._fresh(ns):
            self._offer('state', ns, first(msg.position, 'position'))

    def _on_estimate(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        if ns > self._last_ns:
            est = Estimate(
                first(msg.position, 'position'),
                first(msg.velocity, 'velocity'),
                first(msg.effort, 'effort'),
            )
            self._offer('estimate', ns, est)

    def _on_reference(self, msg: JointTrajectory) -> None:
        try:
            i = list(msg.joint_names).index(self.axis)
        except ValueError:
            return  # a reference for other axes only
        ns0 = from_stamp(msg.header.stamp)
        for p in msg.points:
            ns = ns0 + from_duration(p.time_from_start)
            if ns <= self._last_ns:
                continue
            ref = AxisReference(
                p.positions[i],
                p.velocities[i] if len(p.velocities) > i else 0.0,
                p.accelerations[i] if len(p.accelerations) > i else 0.0,
            )
            self._offer('reference', ns, ref)

    def _offer(self, slot: str, ns: int, value: Any) -> None:
        inputs = self._join.put(slot, ns, value)
        if inputs is None:
            if self._waiting_since is None:
                self._waiting_since = time.monotonic()
            return
        self._waiting_since = None
        try:
            torque = self._law.compute(
                seconds(ns), inputs['state'], inputs['reference'], inputs['estimate']
            )
        except ValueError as exc:
            # Never forward a non-finite command; the plant's lockstep timeout names us.
            self.get_logger().error(f'no command for t = {seconds(ns):.4f} s: {exc}')
            return
        if not math.isfinite(torque):
            self.get_logger().error(f'control law gave {torque} at t = {seconds(ns):.4f} s')
            return
        self._last_ns = ns
        self._last_command = joint_state(ns, (self.axis,), effort=(torque,))
        self._pub.publish(self._last_command)

    def _report_waiting(self) -> None:
        pending = self._join.oldest_incomplete()
        if pending is None or self._waiting_since is None:
            return
        if time.monotonic() - self._waiting_since < 2.0:
            return
        ns, missing = pending
        names = {
            'state': topics.state(self.axis),
            'estimate': topics.estimate(self.axis),
            'reference': topics.REFERENCE,
        }
        detail = ', '.join(
            f'{names[m]} ({self.count_publishers(names[m])} publishers)' for m in missing
        )
        self.get_logger().warning(f'waiting for t = {seconds(ns):.4f} s on {detail}')


def main(argv: list[str] | None = None) -> int:
    return run_node(
        AxisControllerNode,
        'axis_controller',
        'Motion controller of one axis: measured position + estimate + reference -> torque.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
