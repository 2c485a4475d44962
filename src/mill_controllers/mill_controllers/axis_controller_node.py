"""Axis controller node: one axis, one process.

For every sample it joins the measured position (/mill/<axis>/state), the
observer's estimate (/mill/<axis>/estimate) and the reference point of that
time (/mill/reference, several points per message) by stamp, runs the
selected control law and publishes the torque on /mill/<axis>/joint_command
with the same stamp. A law that designs with the observer's identified model
(adaptive_pi with model_source 'observer') also waits for that sample's
/mill/<axis>/observer_state.

The inputs are the fields of mill_common.signals.ControlInputs; INPUTS below says which
topic each comes from and how a message becomes (stamp, value) pairs. The law says which
of them it needs (AxisController.required_inputs), and the stamp join waits for those.

Changing `controller` or any gain on the running node swaps the law without a bump
(mill_controllers.switching): the switch sample still outputs the old law's value and the
difference fades over `blend_time`; the switch is reported on /diagnostics. A law with
internal estimates (adaptive_pi) publishes them on /mill/<axis>/controller_state.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
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
from mill_common.signals import AxisReference, ControlInputs, Estimate, FopdtEstimate
from mill_common.stamp_join import StampJoin
from mill_common.timebase import seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_controllers.base import BASE_INPUTS
from mill_controllers.config import build_controller, parameter_specs
from mill_controllers.registry import CONTROLLERS
from mill_controllers.switching import BumplessSwitch, SwitchRecord, check_replacement

Samples = list[tuple[int, Any]]  # (stamp [ns], value) pairs read from one message


@dataclass(frozen=True)
class InputTopic:
    """Where one field of ControlInputs comes from."""

    message: type
    topic: Callable[[str], str]  # axis -> topic name
    read: Callable[[Any, str], Samples]  # (message, axis) -> the samples it holds
    hint: str = ''  # what to run when a law needs this input and none has arrived


def _position(msg: JointState, axis: str) -> Samples:
    return [(from_stamp(msg.header.stamp), first(msg.position, 'position'))]


def _estimate(msg: JointState, axis: str) -> Samples:
    est = Estimate(
        first(msg.position, 'position'),
        first(msg.velocity, 'velocity'),
        first(msg.effort, 'effort'),
    )
    return [(from_stamp(msg.header.stamp), est)]


def _reference(msg: JointTrajectory, axis: str) -> Samples:
    try:
        i = list(msg.joint_names).index(axis)
    except ValueError:
        return []  # a reference for other axes only
    ns0 = from_stamp(msg.header.stamp)
    return [
        (
            ns0 + from_duration(p.time_from_start),
            AxisReference(
                p.positions[i],
                p.velocities[i] if len(p.velocities) > i else 0.0,
                p.accelerations[i] if len(p.accelerations) > i else 0.0,
            ),
        )
        for p in msg.points
    ]


def _model(msg: JointState, axis: str) -> Samples:
    model = FopdtEstimate.from_status(dict(zip(msg.name, msg.position, strict=False)))
    if model is None:
        return []  # another observer's state: no model in it
    return [(from_stamp(msg.header.stamp), model)]


# Field of ControlInputs -> its topic. The plant's state paces the run (CLOCK_INPUT).
INPUTS: dict[str, InputTopic] = {
    'position': InputTopic(JointState, topics.state, _position),
    'estimate': InputTopic(JointState, topics.estimate, _estimate),
    'reference': InputTopic(JointTrajectory, lambda _axis: topics.REFERENCE, _reference),
    'model': InputTopic(JointState, topics.observer_state, _model, 'run the rls observer'),
}
CLOCK_INPUT = 'position'


class AxisControllerNode(Node):
    def __init__(self) -> None:
        super().__init__('axis_controller')
        self._law: BumplessSwitch | None = None
        self._reported_switch: SwitchRecord | None = None
        self._seen: set[str] = set()  # inputs of which a sample has arrived
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        axis = self.axis = self.params.values['axis']
        self._join = StampJoin(self._switch.law.required_inputs())
        self._last_ns = -1
        self._last_command: JointState | None = None
        self._waiting_since: float | None = None
        self._pub = self.create_publisher(JointState, topics.joint_command(axis), DATA_QOS)
        self._state_pub = self.create_publisher(JointState, topics.controller_state(axis), DATA_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        for slot, source in INPUTS.items():
            self.create_subscription(
                source.message,
                source.topic(axis),
                partial(self._on_input, slot),
                DATA_QOS,
            )
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: controller {self.params.values["controller"]}, '
            f'commands on {topics.joint_command(axis)}'
        )

    @property
    def _switch(self) -> BumplessSwitch:
        assert self._law is not None, 'configured in NodeParameters'
        return self._law

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
            CONTROLLERS.get(old['controller']), CONTROLLERS.get(values['controller'])
        )
        if reason:
            raise ValueError(reason)
        law = build_controller(values)  # raises, with the reason, before anything changes
        for slot in law.required_inputs():
            if slot not in BASE_INPUTS and slot not in self._seen:
                source = INPUTS[slot]
                raise ValueError(
                    f'{values["controller"]} needs the {slot} input each sample, and none '
                    f'has arrived on {source.topic(self.axis)} ({source.hint})'
                )
        self._law.set_blend_time(values['sample_period'], values['blend_time'])
        if any(values[k] != old[k] for k in values if k != 'blend_time'):
            self._law.replace(law)
            self._law_name = values['controller']  # params.values changes after we return
            ready = self._join.require(law.required_inputs())
            if ready is not None:  # a sample that waited only for the old law's extra input
                self._act(*ready)

    # -- inputs ----------------------------------------------------------------------------
    def _on_input(self, slot: str, msg: Any) -> None:
        for ns, value in INPUTS[slot].read(msg, self.axis):
            self._seen.add(slot)
            if slot == CLOCK_INPUT and ns == self._last_ns and self._last_command is not None:
                self._pub.publish(self._last_command)  # the plant offered this step again
            if ns > self._last_ns:
                self._offer(slot, ns, value)

    def _offer(self, slot: str, ns: int, value: Any) -> None:
        inputs = self._join.put(slot, ns, value)
        if inputs is None:
            if self._waiting_since is None:
                self._waiting_since = time.monotonic()
            return
        self._act(ns, inputs)

    def _act(self, ns: int, inputs: dict[str, Any]) -> None:
        self._waiting_since = None
        try:
            torque = self._switch.compute(ControlInputs(seconds(ns), **inputs))
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
        status = self._switch.law.status()
        if status:
            self._state_pub.publish(
                joint_state(ns, tuple(status), tuple(float(v) for v in status.values()))
            )
        record = self._switch.last_switch
        if record is not None and record is not self._reported_switch:
            self._reported_switch = record
            self._report_switch(ns, record)

    def _report_switch(self, ns: int, record: SwitchRecord) -> None:
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
                f'axis_{self.axis}',
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
        names = [INPUTS[m].topic(self.axis) for m in missing]
        detail = ', '.join(f'{n} ({self.count_publishers(n)} publishers)' for n in names)
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
