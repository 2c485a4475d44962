"""Observer node: estimates velocity and lumped disturbance of one axis.

Sample k: the measured position y(k) corrects the estimate, which is
published on /mill/<axis>/estimate stamped k; when the controller's command
u(k) arrives (/mill/<axis>/joint_command), the observer predicts to k+1.
Messages are ordered by stamp, so a state that overtakes the previous
command waits for it.
"""

from __future__ import annotations

import time
from typing import Any

from mill_common.node_main import run_node
from mill_common.ros import DATA_QOS, first, from_stamp, joint_state
from mill_common.ros_params import NodeParameters
from mill_common.timebase import seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_observers.base import Observer
from mill_observers.config import build_observer, parameter_specs
from mill_observers.registry import OBSERVERS
from mill_observers.switching import EstimateBlend


class ObserverNode(Node):
    def __init__(self) -> None:
        super().__init__('observer')
        self._observer: Observer | None = None
        self._blend: EstimateBlend | None = None
        self._last_ns: int | None = None
        self._commands: dict[int, float] = {}
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        axis = self.axis = self.params.values['axis']
        self._states: dict[int, float] = {}
        self._last_estimate: JointState | None = None
        self._stalled_since: float | None = None
        self._pub = self.create_publisher(JointState, topics.estimate(axis), DATA_QOS)
        self._state_pub = self.create_publisher(JointState, topics.observer_state(axis), DATA_QOS)
        self.create_subscription(JointState, topics.state(axis), self._on_state, DATA_QOS)
        self.create_subscription(JointState, topics.joint_command(axis), self._on_command, DATA_QOS)
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: observer {self.params.values["observer"]}, '
            f'estimates on {topics.estimate(axis)}'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._observer is not None and values['axis'] != self.axis:
            raise ValueError('axis is fixed for the life of the node')
        # A rebuilt observer restarts from the next measurement; its estimate continues the
        # old one's and fades into its own over blend_time (mill_observers.switching).
        if self._observer is not None:
            old = self.params.values['observer']
            units = [OBSERVERS.get(n).DISTURBANCE_UNIT for n in (old, values['observer'])]
            if units[0] != units[1]:
                raise ValueError(
                    f'{values["observer"]} estimates the disturbance in {units[1]} but the running '
                    f'{old} in {units[0]}: the controller cannot use both'
                )
        self._observer = build_observer(values)
        blend = EstimateBlend(values['sample_period'], values['blend_time'])
        if self._last_ns is not None and self._blend is not None:
            blend.resumed(self._blend).switch()  # a switch while running: continue the estimate
        self._blend = blend
        if self._last_ns is not None:
            self._last_ns = None
            self._commands.clear()

    def _on_state(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._last_ns is not None and ns <= self._last_ns:
            if ns == self._last_ns and self._last_estimate is not None:
                self._pub.publish(self._last_estimate)  # the plant offered this step again
            return
        self._states[ns] = first(msg.position, 'position')
        self._advance()

    def _on_command(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._last_ns is None or ns >= self._last_ns:
            self._commands[ns] = first(msg.effort, 'effort')
            self._advance()

    def _advance(self) -> None:
        observer, blend = self._observer, self._blend
        assert observer is not None and blend is not None, 'configured in NodeParameters'
        while self._states:
            ns = min(self._states)
            if self._last_ns is not None:
                u = self._commands.pop(self._last_ns, None)
                if u is None:
                    self._stalled_since = self._stalled_since or time.monotonic()
                    return  # y(k) arrived before u(k-1): wait for it
                observer.predict(u)
            est = blend(observer.correct(self._states.pop(ns)))
            self._last_ns = ns
            self._stalled_since = None
            self._last_estimate = joint_state(
                ns, (self.axis,), (est.position,), (est.velocity,), (est.disturbance,)
            )
            self._pub.publish(self._last_estimate)
            status = observer.status()
            if status:
                values = tuple(float(v) for v in status.values())
                self._state_pub.publish(joint_state(ns, tuple(status), values))

    def _report_waiting(self) -> None:
        if self._last_ns is None or self._stalled_since is None:
            return
        if time.monotonic() - self._stalled_since > 2.0:
            topic = topics.joint_command(self.axis)
            self.get_logger().warning(
                f'waiting for the command of t = {seconds(self._last_ns):.4f} s on {topic} '
                f'({self.count_publishers(topic)} publishers)'
            )


def main(argv: list[str] | None = None) -> int:
    return run_node(
        ObserverNode,
        'observer_node',
        'Disturbance observer of one axis: position + torque -> velocity and disturbance.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
