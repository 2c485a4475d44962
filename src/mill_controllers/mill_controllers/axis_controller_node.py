"""Axis controller node: one axis, one process.

For every sample it joins the measured position (mill/<axis>/state), the observer's
estimate (mill/<axis>/estimate) and, for a law that designs with the observer's model
(adaptive_pi with model_source 'observer'), that sample's mill/<axis>/observer_state, by
stamp; takes the reference at that stamp (plus command_delay samples) from the points of
mill/reference; runs the selected control law and publishes the torque on
mill/<axis>/joint_command with the same stamp and its own name in header.frame_id.

timing lockstep: every stamp is on the plant's grid and the node waits for all inputs of a
sample; a repeated state (the plant offering a step again) is answered with the same
command. timing realtime: the node acts on the newest state whose estimate has arrived,
drops anything older, and interpolates the reference at the state's stamp.

Every message is checked before use (mill_common.checks): sender, joint, array lengths,
finite values, stamp (lockstep: on the grid, every reference point too; not older than the
newest of its input; not later than the plant can be). A repeated stamp in lockstep is the
same sample offered again: the first message counts. A bad one is dropped, counted and
reported on /diagnostics; silence
on an input is reported and, in lockstep, ends the node after input_timeout
(mill_common.input_guard).

Following-error trip (mill_controllers.trip): |measured position − reference| above
`following_error_limit` latches a brake request (effort NaN, which the drive answers by
braking the axis) until the `~/reset_trip` service (std_srvs/Trigger) is called or the
limit is set again; the trip is an ERROR on /diagnostics naming the axis, the error and the
time. A law that cannot compute (non-finite result) also sends the brake request.

Changing `controller` or any gain on the running node swaps the law without a bump
(mill_controllers.switching). A law with internal estimates (adaptive_pi) publishes them on
mill/<axis>/controller_state.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timezone
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.checks import (
    REFERENCE_LEAD_NS,
    Rejected,
    StampCheck,
    ahead,
    axis_points,
    joint_values,
    owner_check,
)
from mill_common.codec import decode_joint_state, decode_joint_trajectory
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    diagnostic_array,
    from_duration,
    from_stamp,
    joint_state_bytes,
    readers_ready,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.signals import AxisReference, ControlInputs, Estimate, FopdtEstimate
from mill_common.stamp_join import StampJoin
from mill_common.timebase import period_ns, seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from mill_controllers.base import BASE_INPUTS, AxisController
from mill_controllers.config import build_controller, parameter_specs
from mill_controllers.registry import CONTROLLERS
from mill_controllers.switching import BumplessSwitch, SwitchRecord, check_replacement
from mill_controllers.trip import BRAKE, FollowingErrorTrip

Samples = list[tuple[int, Any]]  # (stamp [ns], value) pairs read from one message


def _position(msg: JointState, axis: str) -> Samples | Rejected:
    got = joint_values(msg.name, {'position': msg.position}, axis, ('position',))
    return got if isinstance(got, Rejected) else [(from_stamp(msg.header.stamp), got[0])]


def _estimate(msg: JointState, axis: str) -> Samples | Rejected:
    arrays = {'position': msg.position, 'velocity': msg.velocity, 'effort': msg.effort}
    got = joint_values(msg.name, arrays, axis, ('position', 'velocity', 'effort'))
    return got if isinstance(got, Rejected) else [(from_stamp(msg.header.stamp), Estimate(*got))]


def _reference(msg: JointTrajectory, axis: str) -> Samples | Rejected:
    got = axis_points(msg.joint_names, msg.points, axis)
    if isinstance(got, Rejected):
        return got  # the whole message: a partial reference is no reference
    ns0 = from_stamp(msg.header.stamp)
    return [
        (ns0 + from_duration(p.time_from_start), AxisReference(*values))
        for p, values in zip(msg.points, got, strict=True)
    ]


def _model(msg: JointState, axis: str) -> Samples | Rejected:
    model = FopdtEstimate.from_status(dict(zip(msg.name, msg.position, strict=False)))
    if model is None:
        return []  # another observer's state: no model in it
    if not all(math.isfinite(v) for v in model.as_status().values()):
        return Rejected('non-finite model estimate')
    return [(from_stamp(msg.header.stamp), model)]


@dataclass(frozen=True)
class InputTopic:
    """Where one field of ControlInputs comes from."""

    message: type
    topic: Callable[[str], str]  # axis -> topic name
    read: Callable[[Any, str], Samples | Rejected]  # (message, axis) -> its samples
    owner: str  # the parameter naming the node that must send it
    hint: str = ''  # what to run when a law needs this input and none has arrived
    decode: Callable[[bytes], Any] = decode_joint_state  # its CDR bytes -> its fields


# Field of ControlInputs -> its topic. The state paces the run (CLOCK_INPUT); the reference
# is taken at the state's stamp from the points the trajectory sent ahead (ReferenceBuffer).
INPUTS: dict[str, InputTopic] = {
    'position': InputTopic(JointState, topics.state, _position, 'plant_node'),
    'estimate': InputTopic(JointState, topics.estimate, _estimate, 'observer_node'),
    'reference': InputTopic(
        JointTrajectory,
        lambda _axis: topics.REFERENCE,
        _reference,
        'trajectory_node',
        decode=decode_joint_trajectory,
    ),
    'model': InputTopic(
        JointState, topics.observer_state, _model, 'observer_node', 'run the rls observer'
    ),
}
CLOCK_INPUT = 'position'
REFERENCE_INPUT = 'reference'


def joined(law: AxisController) -> tuple[str, ...]:
    """The inputs joined by stamp: every one the law needs but the reference."""
    return tuple(s for s in law.required_inputs() if s != REFERENCE_INPUT)


class AxisControllerNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('axis_controller', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._law: BumplessSwitch | None = None
        self._trip: FollowingErrorTrip | None = None
        self._reported_switch: SwitchRecord | None = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        axis = self.axis = v['axis']
        self.realtime = v['timing'] == 'realtime'
        self._dt_ns = period_ns(v['sample_period'])
        self._lead_ns = v['command_delay'] * self._dt_ns
        self._owners = {slot: v[source.owner] for slot, source in INPUTS.items()}
        for slot in ('estimate', 'model'):
            self._owners[slot] = self._owners[slot] or f'{axis}_observer'
        self._join = StampJoin(joined(self._switch.law))
        self._ready: dict[int, dict[str, Any]] = {}  # joined samples waiting for a reference
        self._reference = ReferenceBuffer()
        self._stamps = {
            slot: StampCheck(None if self.realtime else self._dt_ns) for slot in self._owners
        }
        self._seen: set[str] = set()  # inputs of which a sample has arrived
        self._last_ns = -1
        self._last_command: bytes | None = None
        self._waiting_since: float | None = None
        self._late_references = 0
        self._pub = data_publisher(self, JointState, topics.joint_command(axis), DATA_QOS)
        self._state_pub = data_publisher(self, JointState, topics.controller_state(axis), DATA_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=not self.realtime,
            stamp_ns=lambda: max(self._last_ns, 0),
            extra=self._trip_status,
        )
        # Real time keeps only the newest message of each input; lockstep must lose none. The
        # reference always keeps its history: its messages carry the points ahead.
        self._topics = {slot: source.topic(axis) for slot, source in INPUTS.items()}
        for slot in ('position', 'estimate', 'reference'):
            self.guard.watch(self._topics[slot], self._owners[slot])
        for slot, source in INPUTS.items():
            qos = 1 if self.realtime and slot != REFERENCE_INPUT else DATA_QOS
            topic = self._topics[slot]
            take_serialized(
                self,
                source.message,
                topic,
                source.decode,
                partial(self._on_input, slot),
                qos,
                partial(self.guard.drop, topic),
            )
        self.create_service(Trigger, '~/reset_trip', self._on_reset_trip)
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: controller {v["controller"]}, timing {v["timing"]}, commands on '
            f'{self.resolve_topic_name(topics.joint_command(axis))}, following-error limit '
            f'{1e3 * v["following_error_limit"]:g} mm'
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
            self._trip = FollowingErrorTrip(values['following_error_limit'])
            return
        # Setting following_error_limit (to any value, the same one too) clears a trip.
        limit = FollowingErrorTrip(values['following_error_limit'])
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
        if self._trip is not None and self._trip.trip is not None:
            self._log_reset(self._trip.reset(), 'parameter following_error_limit set')
        self._trip = limit
        unchanged = ('blend_time', 'following_error_limit', 'input_warn_time', 'input_timeout')
        if any(values[k] != old[k] for k in values if k not in unchanged):
            self._law.replace(law)
            self._law_name = values['controller']  # params.values changes after we return
            ready = self._join.require(joined(law))
            if ready is not None:  # a sample that waited only for the old law's extra input
                self._ready[ready[0]] = ready[1]
                self._try_pending()

    # -- inputs ----------------------------------------------------------------------------
    def _on_input(self, slot: str, msg: Any) -> None:
        """Check a message (sender, stamp, content) and hand its samples on."""
        topic, sender = self._topics[slot], msg.header.frame_id
        problem = owner_check(sender, self._owners[slot])
        if problem is not None:
            self.guard.drop(topic, problem, sender)
            return
        ns = from_stamp(msg.header.stamp)
        stamps = self._stamps[slot]
        if slot != REFERENCE_INPUT or not self.realtime:
            problem = stamps.check(ns)
            if problem is None and self.realtime and stamps.is_repeat(ns):
                problem = Rejected(f'repeated stamp {ns / 1e9:.6f} s')
            if problem is None and not self.realtime:
                lead = REFERENCE_LEAD_NS if slot == REFERENCE_INPUT else self._dt_ns
                problem = ahead(ns, self._stamps[CLOCK_INPUT].newest, lead)
            if problem is not None:
                if not (slot == CLOCK_INPUT and ns == self._last_ns):  # a re-offered step
                    self.guard.drop(topic, problem, sender)
                return
        samples = INPUTS[slot].read(msg, self.axis)
        if isinstance(samples, Rejected):
            self.guard.drop(topic, samples, sender)
            return
        if not self.realtime:
            off = next((at for at, _ in samples if at % self._dt_ns), None)
            if off is not None:
                self.guard.drop(topic, Rejected(f'a point at {off} ns is off the grid'), sender)
                return
        if topic in self.guard.watches:
            self.guard.heard(topic)
        if not samples:
            return
        if (
            slot == CLOCK_INPUT
            and not self.realtime
            and not readers_ready(self, self._pub, self.params.values['min_subscribers'])
        ):
            return  # the plant offers the step again
        self._seen.add(slot)
        repeat = not self.realtime and stamps.is_repeat(ns)
        stamps.accept(ns)
        if slot == REFERENCE_INPUT:
            if repeat:
                return  # lockstep: the trajectory answered a re-offered tick; the first counts
            for at, ref in samples:
                self._reference.add(at, ref)
            self._try_pending()
            return
        if slot == CLOCK_INPUT and ns == self._last_ns and self._last_command is not None:
            self._pub.publish(self._last_command)  # the plant offered this step again
            return
        if repeat:
            return  # lockstep: a sample offered again; the first one counts
        for at, value in samples:
            if at > self._last_ns:
                self._offer(slot, at, value)

    def _offer(self, slot: str, ns: int, value: Any) -> None:
        inputs = self._join.put(slot, ns, value)
        if inputs is None:
            if self._waiting_since is None:
                self._waiting_since = time.monotonic()
            return
        if self.realtime:
            self._ready.clear()  # only the newest sample is worth acting on
        self._ready[ns] = inputs
        self._try_pending()

    def _try_pending(self) -> None:
        """Act on joined samples whose reference is there, oldest first."""
        for ns in sorted(self._ready):
            if ns <= self._last_ns:
                del self._ready[ns]
                continue
            ref = self._reference.at(ns + self._lead_ns)
            if ref is None:
                if self.realtime and self._reference.newest is not None:
                    self._late_references += 1  # the reference does not reach this far yet
                    del self._ready[ns]
                    continue
                return  # lockstep: the trajectory's next message brings it
            inputs = self._ready.pop(ns)
            inputs['reference'] = ref
            if not self._ready:
                self._waiting_since = None
            self._act(ns, inputs)
        self._reference.forget_before(self._last_ns + self._lead_ns)

    def _act(self, ns: int, inputs: dict[str, Any]) -> None:
        self._waiting_since = None
        switch = self._switch
        est, y, ref = inputs['estimate'], inputs['position'], inputs['reference']
        t = seconds(ns)
        if self._lead_ns:  # the command acts N samples on: aim at the state there
            t, y = seconds(ns + self._lead_ns), est.position
        try:
            torque = switch.compute(ControlInputs(t, y, ref, est, inputs.get('model')))
        except ValueError as exc:
            self.get_logger().error(f'no valid command for t = {t:.4f} s: {exc}: braking')
            torque = BRAKE
        if not math.isfinite(torque):
            torque = BRAKE
        assert self._trip is not None
        error = inputs['position'] - self._reference_now(ns, ref)
        was = self._trip.tripped
        torque = self._trip.command(seconds(ns), error, torque)
        if self._trip.tripped and not was:
            self._report_trip(ns)
        self._last_ns = ns
        self._last_command = joint_state_bytes(
            ns, (self.axis,), effort=(torque,), sender=self._name
        )
        self._pub.publish(self._last_command)
        status = switch.law.status()
        if status:
            values = tuple(float(v) for v in status.values())
            self._state_pub.publish(joint_state_bytes(ns, tuple(status), values, sender=self._name))
        record = switch.last_switch
        if record is not None and record is not self._reported_switch:
            self._reported_switch = record
            self._report_switch(ns, record)

    def _reference_now(self, ns: int, aimed: AxisReference) -> float:
        """The reference position at the state's own stamp (the following error's)."""
        if not self._lead_ns:
            return aimed.position
        here = self._reference.at(ns)
        return aimed.position if here is None else here.position

    # -- following-error trip ------------------------------------------------------------
    def _trip_status(self) -> tuple[bytes, str, dict[str, object]]:
        assert self._trip is not None
        values: dict[str, object] = {
            'following_error_limit_m': self._trip.limit,
            'late_references': self._late_references,
        }
        trip = self._trip.trip
        if trip is None:
            return DiagnosticStatus.OK, f'axis {self.axis}: running', values
        values.update({'trip_time_s': trip.time, 'trip_error_m': trip.error})
        return DiagnosticStatus.ERROR, self._trip_text(), values

    def _trip_text(self) -> str:
        assert self._trip is not None and self._trip.trip is not None
        trip = self._trip.trip
        if self.realtime:  # a stamp on the system clock: the time of day says more
            when = datetime.fromtimestamp(trip.time, timezone.utc).strftime('%H:%M:%S.%f')[:-3]
            at = f'at {when} UTC'
        else:
            at = f'at t = {trip.time:.4f} s'
        return (
            f'axis {self.axis}: following-error trip {at}, '
            f'|e| = {1e3 * abs(trip.error):.3f} mm > {1e3 * trip.limit:g} mm: braked '
            '(reset: ~/reset_trip or set following_error_limit)'
        )

    def _report_trip(self, ns: int) -> None:
        self.get_logger().error(self._trip_text())
        level, message, values = self._trip_status()
        self._diag_pub.publish(
            diagnostic_array(
                ns,
                level,
                f'mill_controllers: {self.axis} trip',
                message,
                topics.machine_id(self.get_namespace()),
                values,
            )
        )

    def _on_reset_trip(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        assert self._trip is not None
        cleared = self._trip.reset()
        self._log_reset(cleared, 'service reset_trip')
        response.success = True
        response.message = 'trip cleared' if cleared else 'no trip to clear'
        return response

    def _log_reset(self, cleared: Any, how: str) -> None:
        if cleared is not None:
            self.get_logger().warning(
                f'axis {self.axis}: following-error trip of t = {cleared.time:.4f} s cleared '
                f'by {how}'
            )

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
                topics.machine_id(self.get_namespace()),
                values,
            )
        )

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
