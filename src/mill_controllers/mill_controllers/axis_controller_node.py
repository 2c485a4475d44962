"""Axis controller node: one axis, one process.

For every sample it joins the measured position (/mill/<axis>/state), the
observer's estimate (/mill/<axis>/estimate) and the reference point of that
time (/mill/reference, several points per message) by stamp, runs the
selected control law and publishes the torque on /mill/<axis>/joint_command
with the same stamp. A law that designs with the observer's identified model
(adaptive_pi with model_source 'observer') also waits for that sample's
/mill/<axis>/observer_state.

Changing `controller` or any gain on the running node swaps the law without a bump
(mill_controllers.switching): the switch sample still outputs the old law's value and the
difference fades over `blend_time`; the switch is reported on /diagnostics. A law with
internal estimates (adaptive_pi) publishes them on /mill/<axis>/controller_state.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    diagnostic_array,
    first,
    from_duration,
    from_stamp,
    joint_state,
)
from mill_common.ros_params import NodeParameters
from mill_common.signals import AxisReference, Estimate, FopdtEstimate
from mill_common.stamp_join import StampJoin
from mill_common.timebase import seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_controllers.config import build_controller, parameter_specs
from mill_controllers.registry import CONTROLLERS
from mill_controllers.switching import BumplessSwitch, check_replacement

INPUTS = ('state', 'estimate', 'reference')


def needs_model(law: object) -> bool:
    """Whether the law designs with the observer's model estimate (Estimate.model)."""
    return bool(getattr(law, 'needs_model', False))


def required_inputs(law: object) -> tuple[str, ...]:
    return (*INPUTS, 'model') if needs_model(law) else INPUTS


class AxisControllerNode(Node):
    def __init__(self) -> None:
        super().__init__('axis_controller')
        self._law: BumplessSwitch | None = None
        self._reported_switch = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        axis = self.axis = self.params.values['axis']
        self._join = StampJoin(required_inputs(self._law.law))
        self._model_seen = False  # a model estimate has arrived on observer_state
        self._last_ns = -1
        self._last_command: JointState | None = None
        self._waiting_since: float | None = None
        self._pub = self.create_publisher(JointState, topics.joint_command(axis), DATA_QOS)
        self._state_pub = self.create_publisher(JointState, topics.controller_state(axis), DATA_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self.create_subscription(JointState, topics.state(axis), self._on_state, DATA_QOS)
        self.create_subscription(JointState, topics.estimate(axis), self._on_estimate, DATA_QOS)
        self.create_subscription(JointTrajectory, topics.REFERENCE, self._on_reference, DATA_QOS)
        self.create_subscription(
            JointState, topics.observer_state(axis), self._on_observer_state, DATA_QOS
        )
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: controller {self.params.values["controller"]}, '
            f'commands on {topics.joint_command(axis)}'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._law is None:
            law = build_controller(values)
            self._law = BumplessSwitch(law, values['sample_period'], values['blend_time'])
            self._law_name = values['controller']
            return
        if values['axis'] != self.axis:
            raise ValueError('axis is fixed for the life of the node')
        old = self.params.values
        reason = check_replacement(
            CONTROLLERS[old['controller']], CONTROLLERS[values['controller']]
        )
        if reason:
            raise ValueError(reason)
        law = build_controller(values)  # raises, with the reason, before anything changes
        if needs_model(law) and not self._model_seen:
            raise ValueError(
                f"{values['controller']} designs with the observer's model estimate, and none "
                f'has arrived on {topics.observer_state(self.axis)} (run the rls observer)'
            )
        self._law.set_blend_time(values['sample_period'], values['blend_time'])
        if any(values[k] != old[k] for k in values if k != 'blend_time'):
            self._law.replace(law)
            self._law_name = values['controller']  # params.values changes after we return
            ready = self._join.require(required_inputs(law))
            if ready is not None:  # a sample that waited only for the old law's extra input
                self._act(*ready)

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

    def _on_observer_state(self, msg: JointState) -> None:
        model = FopdtEstimate.from_status(dict(zip(msg.name, msg.position, strict=False)))
        if model is None:
            return  # another observer's state: no model in it
        self._model_seen = True
        ns = from_stamp(msg.header.stamp)
        if ns > self._last_ns:
            self._offer('model', ns, model)

    def _offer(self, slot: str, ns: int, value: Any) -> None:
        inputs = self._join.put(slot, ns, value)
        if inputs is None:
            if self._waiting_since is None:
                self._waiting_since = time.monotonic()
            return
        self._act(ns, inputs)

    def _act(self, ns: int, inputs: dict[str, Any]) -> None:
        self._waiting_since = None
        est = inputs['estimate']
        if 'model' in inputs:
            est = replace(est, model=inputs['model'])
        try:
            torque = self._law.compute(seconds(ns), inputs['state'], inputs['reference'], est)
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
        law = self._law.law
        if hasattr(law, 'status'):
            status = law.status()
            self._state_pub.publish(
                joint_state(ns, tuple(status), tuple(float(v) for v in status.values()))
            )
        if self._law.last_switch is not self._reported_switch:
            self._reported_switch = self._law.last_switch
            self._report_switch(ns)

    def _report_switch(self, ns: int) -> None:
        record = self._law.last_switch
        name = self._law_name
        self.get_logger().info(
            f'switched to {name} at t = {record.time:.4f} s: output {record.old_output:.6g} '
            f'(new law alone {record.new_output:.6g}), offset fades over '
            f'{self.params.values["blend_time"]:g} s'
        )
        values = {
            'controller': name,
            'time': repr(record.time),
            'old_output': repr(record.old_output),
            'new_output': repr(record.new_output),
        }
        self._diag_pub.publish(
            diagnostic_array(
                ns,
                DiagnosticStatus.OK,
                f'mill_controllers: {self.axis} switch',
                f'switched to {name}',
                topics.machine_id(self.get_namespace()),
                values,
            )
        )

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
            'model': topics.observer_state(self.axis),
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
