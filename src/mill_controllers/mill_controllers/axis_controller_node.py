"""Axis controller node: one axis; take → check → step → publish.

Its inputs (mill_controllers.controller_inputs): the measured position mill/<axis>/state,
the observer's estimate mill/<axis>/estimate, the points of mill/reference and, for a law
that designs with the observer's model, mill/<axis>/observer_state. Every message is checked
(sender, joint, finite values, stamp: mill_common.checks) and a bad one is dropped, counted
and reported on /diagnostics (mill_common.input_guard). The node's `timing` strategy
(mill_common.timing) joins them: lockstep by exact stamp, waiting for every input of every
sample (a state offered again is answered with the same command); realtime on the newest
state whose estimate has arrived, the reference interpolated at its stamp, nothing stale.

Each joined sample goes to the ROS-free AxisControlLoop (mill_controllers.control_loop):
delay aim, law, following-error trip — the object the offline simulator steps too. The
command goes out on mill/<axis>/joint_command with the state's stamp and the node's name in
header.frame_id; effort NaN asks the drive to brake (a trip, or a law that cannot compute).

A trip latches until the `~/reset_trip` service (std_srvs/Trigger) is called or
`following_error_limit` is set; changing `controller` or a gain swaps the law without a bump
(mill_controllers.switching) and leaves a trip latched. A law with internal estimates
(adaptive_pi) publishes them on mill/<axis>/controller_state.
"""

from __future__ import annotations

import time
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import REFERENCE_LEAD_NS, Rejected, owner_check
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    diagnostic_array,
    from_stamp,
    joint_state_bytes,
    readers_ready,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.stamp_join import StampJoin
from mill_common.timebase import period_ns
from mill_common.timing import timing
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from mill_common import topics
from mill_controllers.base import BASE_INPUTS, AxisController
from mill_controllers.config import build_controller, build_loop, parameter_specs
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.controller_inputs import CLOCK_INPUT, INPUTS, REFERENCE_INPUT, owners
from mill_controllers.registry import CONTROLLERS
from mill_controllers.switching import SwitchRecord, check_replacement


def joined(law: AxisController) -> tuple[str, ...]:
    """The inputs joined by stamp: every one the law needs but the reference."""
    return tuple(s for s in law.required_inputs() if s != REFERENCE_INPUT)


class AxisControllerNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('axis_controller', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._loop: AxisControlLoop | None = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        axis = self.axis = v['axis']
        self.timing = timing(v['timing'], period_ns(v['sample_period']))
        self._owners = owners(v)
        self._join = StampJoin(joined(self.loop.law))
        self._ready: dict[int, dict[str, Any]] = {}  # joined samples waiting for a reference
        self._reference = ReferenceBuffer()
        self._stamps = {slot: self.timing.stamps() for slot in INPUTS}
        self._seen: set[str] = set()  # inputs of which a sample has arrived
        self._last_ns = -1
        self._last_command: bytes | None = None
        self._waiting_since: float | None = None
        self._late_references = 0
        self._reported_switch: SwitchRecord | None = None
        self._pub = data_publisher(self, JointState, topics.joint_command(axis), DATA_QOS)
        self._state_pub = data_publisher(self, JointState, topics.controller_state(axis), DATA_QOS)
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=self.timing.EXIT_ON_SILENCE,
            stamp_ns=lambda: max(self._last_ns, 0),
            extra=self._trip_status,
        )
        self._topics = {slot: source.topic(axis) for slot, source in INPUTS.items()}
        for slot in ('position', 'estimate', 'reference'):
            self.guard.watch(self._topics[slot], self._owners[slot])
        for slot, source in INPUTS.items():
            depth = self.timing.depth(history=slot == REFERENCE_INPUT)
            topic = self._topics[slot]
            on_bad = partial(self.guard.drop, topic)
            on_msg = partial(self._on_input, slot)
            qos = DATA_QOS if depth is None else depth
            take_serialized(self, source.message, topic, source.decode, on_msg, qos, on_bad)
        self.create_service(Trigger, '~/reset_trip', self._on_reset_trip)
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: controller {v["controller"]}, timing {v["timing"]}, commands on '
            f'{self.resolve_topic_name(topics.joint_command(axis))}, following-error limit '
            f'{1e3 * v["following_error_limit"]:g} mm'
        )

    @property
    def loop(self) -> AxisControlLoop:
        assert self._loop is not None, 'configured in NodeParameters'
        return self._loop

    def _configure(self, values: dict[str, Any]) -> None:
        if self._loop is None:
            self._law_name = values['controller']
            self._loop = build_loop(values)
            return
        law = build_controller(values)  # raises, with the reason, before anything changes
        old = self.params.values
        reason = check_replacement(
            CONTROLLERS.get(old['controller']), CONTROLLERS.get(values['controller'])
        )
        if reason:
            raise ValueError(reason)
        for slot in law.required_inputs():
            if slot not in BASE_INPUTS and slot not in self._seen:
                source = INPUTS[slot]
                raise ValueError(
                    f'{values["controller"]} needs the {slot} input each sample, and none '
                    f'has arrived on {source.topic(self.axis)} ({source.hint})'
                )
        loop = self.loop
        loop.switch.set_blend_time(values['sample_period'], values['blend_time'])
        if 'following_error_limit' in self.params.setting:  # the one way but the service
            cleared = loop.trip.set_limit(values['following_error_limit'])
            self._log_reset(cleared, 'setting following_error_limit')
        law_values = ('blend_time', 'following_error_limit', 'input_warn_time', 'input_timeout')
        if any(values[k] != old[k] for k in values if k not in law_values):
            loop.switch.replace(law)
            self._law_name = values['controller']  # params.values changes after we return
            ready = self._join.require(joined(law))
            if ready is not None:  # a sample that waited only for the old law's extra input
                self._ready[ready[0]] = ready[1]
                self._try_pending()

    # -- take and check ------------------------------------------------------------------
    def _on_input(self, slot: str, msg: Any) -> None:
        topic, sender = self._topics[slot], msg.header.frame_id
        problem = owner_check(sender, self._owners[slot])
        if problem is not None:
            self.guard.drop(topic, problem, sender)
            return
        ns = from_stamp(msg.header.stamp)
        stamps, history = self._stamps[slot], slot == REFERENCE_INPUT
        lead = REFERENCE_LEAD_NS if history else self.timing.period_ns
        newest_state = self._stamps[CLOCK_INPUT].newest
        problem = self.timing.problem(stamps, ns, newest_state, lead, history)
        if problem is not None:
            if not (slot == CLOCK_INPUT and ns == self._last_ns):  # not a re-offered step
                self.guard.drop(topic, problem, sender)
            return
        samples = INPUTS[slot].read(msg, self.axis)
        if not isinstance(samples, Rejected):
            off = self.timing.off_grid([at for at, _ in samples])
            if off is not None:
                samples = Rejected(f'a point at {off} ns is off the grid')
        if isinstance(samples, Rejected):
            self.guard.drop(topic, samples, sender)
            return
        if topic in self.guard.watches:
            self.guard.heard(topic)
        if not samples:
            return
        wait = slot == CLOCK_INPUT and self.timing.WAITS_FOR_READERS
        if wait and not readers_ready(self, self._pub, self.params.values['min_subscribers']):
            return  # the plant offers the step again
        self._seen.add(slot)
        again = self.timing.is_offered_again(stamps, ns)
        stamps.accept(ns)
        if slot == CLOCK_INPUT and ns == self._last_ns and self._last_command is not None:
            self._pub.publish(self._last_command)  # the plant offered this step again
            return
        if again:
            return  # the same sample offered again: the first one counts
        if not history:
            for at, value in samples:
                if at > self._last_ns:
                    self._offer(slot, at, value)
            return
        for at, ref in samples:
            self._reference.add(at, ref)
        self._try_pending()

    def _offer(self, slot: str, ns: int, value: Any) -> None:
        inputs = self._join.put(slot, ns, value)
        if inputs is None:
            self._waiting_since = self._waiting_since or time.monotonic()
            return
        self._ready[ns] = inputs
        self._try_pending()

    def _try_pending(self) -> None:
        """Step on joined samples whose reference is there, as the timing says."""
        for ns in self.timing.due(self._ready):
            if ns <= self._last_ns:
                del self._ready[ns]
                continue
            if self._reference.at(self.loop.aim(ns)) is None:
                if self.timing.WAITS_FOR_INPUTS or self._reference.newest is None:
                    return  # the trajectory's next message brings it
                self._late_references += 1  # the reference does not reach this far yet
                del self._ready[ns]
                continue
            self._step(ns, self._ready.pop(ns))
        self._reference.forget_before(self._last_ns + self.loop.lead_ns)

    # -- step and publish ----------------------------------------------------------------
    def _step(self, ns: int, inputs: dict[str, Any]) -> None:
        loop = self.loop
        self._waiting_since = None
        y, est = inputs['position'], inputs['estimate']
        cmd = loop.step(ns, y, est, self._reference, inputs.get('model'))
        self._last_ns = ns
        self._last_command = joint_state_bytes(
            ns, (self.axis,), effort=(cmd.effort,), sender=self._name
        )
        self._pub.publish(self._last_command)
        if cmd.problem:
            self.get_logger().error(
                f'no valid command {self.timing.when(ns)}: {cmd.problem}: braking',
                throttle_duration_sec=1.0,
            )
        if cmd.tripped:
            self._report_trip(ns)
        status = loop.law.status()
        if status:
            values = tuple(float(v) for v in status.values())
            self._state_pub.publish(joint_state_bytes(ns, tuple(status), values, sender=self._name))
        record = loop.switch.last_switch
        if record is not None and record is not self._reported_switch:
            self._reported_switch = record
            self._report_switch(ns, record)

    # -- trip, switch, waiting: the log and /diagnostics ---------------------------------
    def _trip_status(self) -> tuple[bytes, str, dict[str, object]]:
        trip = self.loop.trip
        values: dict[str, object] = {
            'following_error_limit_m': trip.limit,
            'late_references': self._late_references,
        }
        if trip.trip is None:
            return DiagnosticStatus.OK, f'axis {self.axis}: running', values
        values.update({'trip_time_s': trip.trip.time, 'trip_error_m': trip.trip.error})
        return DiagnosticStatus.ERROR, self._trip_text(), values

    def _trip_text(self) -> str:
        trip = self.loop.trip.trip
        assert trip is not None
        return trip.describe(self.axis, self.timing.when(round(trip.time * 1e9)))

    def _publish(self, ns: int, level: bytes, part: str, message: str, values: dict) -> None:
        machine = topics.machine_id(self.get_namespace())
        name = f'mill_controllers: {self.axis} {part}'
        self.guard.diagnostics.publish(diagnostic_array(ns, level, name, message, machine, values))

    def _report_trip(self, ns: int) -> None:
        self.get_logger().error(self._trip_text())
        level, message, values = self._trip_status()
        self._publish(ns, level, 'trip', message, values)

    def _on_reset_trip(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        cleared = self.loop.trip.reset()
        self._log_reset(cleared, 'the service reset_trip')
        response.success = True
        response.message = 'trip cleared' if cleared else 'no trip to clear'
        return response

    def _log_reset(self, cleared: Any, how: str) -> None:
        if cleared is not None:
            when = self.timing.when(round(cleared.time * 1e9))
            self.get_logger().warning(
                f'axis {self.axis}: following-error trip {when} cleared by {how}'
            )

    def _report_switch(self, ns: int, record: SwitchRecord) -> None:
        name = self._law_name
        self.get_logger().info(
            f'switched to {name} {self.timing.when(ns)}: output {record.old_output:.6g} '
            f'(new law alone {record.new_output:.6g}), offset fades over '
            f'{self.params.values["blend_time"]:g} s'
        )
        values = {
            'controller': name,
            'time': repr(record.time),
            'old_output': repr(record.old_output),
            'new_output': repr(record.new_output),
        }
        self._publish(ns, DiagnosticStatus.OK, 'switch', f'switched to {name}', values)

    def _report_waiting(self) -> None:
        if self._waiting_since is None or time.monotonic() - self._waiting_since < 2.0:
            return
        pending = self._join.oldest_incomplete()
        if pending is not None:
            ns, missing = pending
            names = [self._topics[m] for m in missing]
        elif self._ready:
            ns, names = min(self._ready), [self._topics['reference']]
        else:
            return
        detail = ', '.join(f'{n} ({self.count_publishers(n)} publishers)' for n in names)
        self.get_logger().warning(f'waiting for {self.timing.when(ns)} on {detail}')


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
