"""Axis controller node: one axis; take → check → step → publish.

Its inputs (mill_controllers.controller_inputs): the measured position mill/<axis>/state,
the observer's estimate mill/<axis>/estimate, the points of mill/reference and, for a law
that designs with the observer's model, mill/<axis>/observer_state. Every message is checked
(sender, joint, finite values, stamp: mill_common.checks) and a bad one is dropped, counted
and reported on /diagnostics (mill_common.input_guard); a state or estimate two publishers
sent under its owner's name (contested) is refused too, and its sample answered by a brake
request without stepping the law (mill_controllers.sample_join). The node's `timing` strategy
(mill_common.timing) joins them: lockstep by exact stamp, waiting for every input of every
sample (a state offered again is answered with the same command); realtime on the newest
state whose estimate has arrived, the reference interpolated at its stamp, nothing stale.

Each joined sample goes to the ROS-free AxisControlLoop (mill_controllers.control_loop):
delay aim, law, following-error trip — the object the offline simulator steps too. The
command goes out on mill/<axis>/joint_command (effort NaN: brake); a trip latches until
`~/reset_trip` (std_srvs/Trigger), whatever parameter is set meanwhile (a new
`following_error_limit` changes the limit only); `controller` and gains switch without a
bump, and a change whose law cannot be built (that of a law that does not run too) is
refused while the old law runs on; a law's internal estimates go to
mill/<axis>/controller_state. In a composed process the axis's observer hands over each
sample at once (a servo cycle).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.checks import (
    REFERENCE_LEAD_NS,
    Rejected,
    Sender,
    owner_check,
    sender_check,
)
from mill_common.hold_window import StallWatch, drive_word, said_at
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    DataInput,
    data_mute,
    data_publisher,
    from_stamp,
    graph_owners,
    joint_state_bytes,
    readers_ready,
    take_owned,
)
from mill_common.ros_params import NodeParameters
from mill_common.signals import Estimate
from mill_common.timebase import period_ns
from mill_common.timing import timing
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from mill_common import topics
from mill_controllers.axis_reports import AxisReports
from mill_controllers.base import AxisController
from mill_controllers.config import (
    build_controller,
    build_loop,
    check_other_laws,
    parameter_specs,
    rebuilds_law,
    unseen_input,
)
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.controller_inputs import CLOCK_INPUT, INPUTS, REFERENCE_INPUT, owners
from mill_controllers.sample_join import (
    BRAKE_ON_CONTEST,
    SampleJoin,
    brakes_on_contest,
    is_contested,
)
from mill_controllers.switching import SwitchRecord
from mill_controllers.trip import BRAKE, Trip

WATCH_NS = 20_000_000  # the period of the process's own stall watch (realtime)


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
        self._join = SampleJoin(self.timing, joined(self.loop.law), self.loop.lead_ns)
        self._stamps = {slot: self.timing.stamps() for slot in INPUTS}
        self._seen: set[str] = set()  # inputs of which a sample has arrived
        self._last_command: bytes | None = None
        self._waiting_since: float | None = None
        self._reported_switch: SwitchRecord | None = None
        self._commanded: Callable[[int, float], None] | None = None  # the observer's, in a cycle
        # What the drive said of the axis in each state not yet stepped (its effort: NaN
        # stopped), and this process's own stalls (a steady watch timer, realtime only).
        self._said: dict[int, bool | None] = {}
        self._stalls = StallWatch(WATCH_NS, round(v['stall_report'] * 1e9))
        self._stepped_mono: int | None = None
        self._gaps = 0
        self._gap_reported = 0.0
        self._drive_reason = ''  # the drive's last stop of this axis, as it said it
        self._pub = data_publisher(self, JointState, topics.joint_command(axis), DATA_QOS)
        self._state_pub = data_publisher(
            self, JointState, topics.controller_state(axis), DATA_QOS, True
        )
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=self.timing.EXIT_ON_SILENCE,
            stamp_ns=lambda: max(self._join.last_ns, 0),
            extra=self._trip_status,
        )
        self.reports = AxisReports(self.guard.diagnostics, axis, self.timing)
        self._topics = {slot: source.topic(axis) for slot, source in INPUTS.items()}
        for slot in ('position', 'estimate', 'reference'):
            self.guard.watch(self._topics[slot], self._owners[slot])
        self._inputs: dict[str, DataInput] = {}
        # Each input's sender as the graph identifies its publisher (mill_common.graph_owner).
        self._graph = graph_owners(self, self._contested)
        for slot, source in INPUTS.items():
            depth = self.timing.depth(history=slot == REFERENCE_INPUT)
            topic = self._topics[slot]
            on_bad = partial(self.guard.drop, topic)
            on_msg = partial(self._on_input, slot)
            qos = DATA_QOS if depth is None else depth
            self._inputs[slot] = take_owned(
                self,
                source.message,
                topic,
                source.decode,
                on_msg,
                qos,
                on_bad,
                self._graph,
                self._owners[slot],
            )
        self.create_service(Trigger, '~/reset_trip', self._on_reset_trip)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(2.0, self._report_waiting, clock=steady)
        if not self.timing.WAITS_FOR_INPUTS:  # realtime: who stalled, when a gap comes
            self.create_timer(WATCH_NS * 1e-9, self._watch_self, clock=steady)
            # The drive's reason for a stop it declares (its axis status), for the trip.
            self._drive_status = topics.status_name(
                self._owners[CLOCK_INPUT], f'{axis} axis', self.get_namespace()
            )
            self._machine = topics.machine_id(self.get_namespace())
            self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self._on_diagnostics, 20)
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
            check_other_laws(values)  # those given other gains than their defaults build too
            return
        law = build_controller(values)  # raises, with the reason, before anything changes
        check_other_laws(values, self.params.values)  # a law to switch to later builds too
        slot = unseen_input(law, self._seen)
        if slot is not None:
            source = INPUTS[slot]
            raise ValueError(
                f'{values["controller"]} needs the {slot} input each sample, and none '
                f'has arrived on {source.topic(self.axis)} ({source.hint})'
            )
        loop = self.loop
        if rebuilds_law(values, self.params.values):
            loop.replace(law)
            self._law_name = values['controller']  # params.values changes after we return
            self._join.require(joined(law))
        loop.switch.set_blend_time(values['sample_period'], values['blend_time'])
        loop.set_limit(values['following_error_limit'])  # a trip stays: ~/reset_trip alone
        self._step_due()

    # -- take and check ------------------------------------------------------------------
    def _contested(self, topic: str, owner: str, claimants: tuple[str, ...]) -> None:
        """Two or more publishers of an input claim its owner's name: both refused (the
        state's or the estimate's: each of their samples answered by a brake request)."""
        slot = next((s for s, t in self._topics.items() if t == topic), '')  # as watched
        brakes = ', the axis brakes' if slot in BRAKE_ON_CONTEST else ''
        self.guard.contested(topic, owner, claimants, brakes)

    def _on_input(self, slot: str, msg: Any, who: Sender) -> None:
        topic, owner = self._topics[slot], self._owners[slot]
        sender = who.name or msg.header.frame_id
        problem = sender_check(who, owner) if owner else None
        # Refused, but answered with a brake request: waiting for it would stall the graph.
        contested = problem is not None and brakes_on_contest(slot, who.verdict)
        if problem is not None and contested:
            self.guard.drop(topic, problem, sender)
            problem = None
        problem = problem or owner_check(msg.header.frame_id, owner)
        if problem is not None:
            self.guard.drop(topic, problem, sender)
            return
        ns = from_stamp(msg.header.stamp)
        stamps, history = self._stamps[slot], slot == REFERENCE_INPUT
        lead = REFERENCE_LEAD_NS if history else self.timing.period_ns
        newest_state = self._stamps[CLOCK_INPUT].newest
        problem = self.timing.problem(stamps, ns, newest_state, lead, history)
        if problem is not None:
            if not (slot == CLOCK_INPUT and ns == self._join.last_ns):  # not a re-offered step
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
        if slot == CLOCK_INPUT and not self._readers_ready():
            return  # the plant offers the step again
        if slot == CLOCK_INPUT and not contested:
            self._said[ns] = drive_word(msg.effort)
        self._seen.add(slot)
        again = self.timing.is_offered_again(stamps, ns)
        stamps.accept(ns)
        if slot == CLOCK_INPUT and ns == self._join.last_ns and self._last_command is not None:
            self._pub.publish(self._last_command)  # the plant offered this step again
            return
        if again:
            return  # the same sample offered again: the first one counts
        for at, value in samples:
            if contested:
                self._join.contest(slot, at, clock=slot == CLOCK_INPUT)
            elif history:
                self._join.add_reference(at, value)
            else:
                self._join.offer(slot, at, value)
        self._step_due()

    # -- the servo cycle: the observer of this axis in this process hands each sample --------
    def attach(
        self, plant_node: str, commanded: Callable[[int, float], None]
    ) -> Callable[[int, float, Estimate, bool | None, bool], None] | None:
        """Take state and estimate from this axis's observer in this process, at once, as
        it steps, and hand it each command (mill_bringup.container); None if it listens to
        another plant."""
        if plant_node != self._owners[CLOCK_INPUT]:
            return None
        for slot in (CLOCK_INPUT, 'estimate'):
            data_mute(self._inputs[slot])  # still a reader of the topic, taking nothing
        self._commanded = commanded
        return self.serve

    def serve(
        self,
        ns: int,
        position: float,
        estimate: Estimate,
        said: bool | None = None,
        contested: bool = False,
    ) -> None:
        """A sample the observer took (its sender and stamp checked) and estimated; said:
        what the drive said of the axis in that state (mill_common.hold_window.drive_word);
        contested: a state two publishers sent under the plant's name, not estimated (its
        sample is answered by a brake request)."""
        join = self._join
        for slot in (CLOCK_INPUT, 'estimate'):
            self.guard.heard(self._topics[slot])
        if ns == join.last_ns and self._last_command is not None:
            self._pub.publish(self._last_command)  # the plant offered this step again
            return
        if ns < join.last_ns or not self._readers_ready():
            return  # a sample stepped already; or (lockstep) the plant offers it again
        self._seen.update((CLOCK_INPUT, 'estimate'))
        for slot in (CLOCK_INPUT, 'estimate'):
            self._stamps[slot].accept(ns)
        self._said[ns] = said
        if contested:
            join.contest(CLOCK_INPUT, ns, clock=True)
        else:
            join.offer(CLOCK_INPUT, ns, position)
            join.offer('estimate', ns, estimate)
        self._step_due()

    def _readers_ready(self) -> bool:
        """Lockstep: every reader of the command is matched (else the plant offers again)."""
        if not self.timing.WAITS_FOR_READERS:
            return True
        return readers_ready(self, self._pub, self.params.values['min_subscribers'])

    def _step_due(self) -> None:
        for ns, inputs in self._join.due():
            self._step(ns, inputs)
        if self._waiting_since is None and self._join.waiting_for() is not None:
            self._waiting_since = time.monotonic()  # the first input of a sample still open

    # -- step and publish ----------------------------------------------------------------
    def _step(self, ns: int, inputs: dict[str, Any]) -> None:
        loop = self.loop
        self._waiting_since = None
        if is_contested(inputs):
            self._said.pop(ns, None)
            self._answer(ns, BRAKE)  # the law is not stepped: its state stays finite
            return
        y, est = inputs['position'], inputs['estimate']
        said = said_at(self._said, ns)  # (and forgets the states the timing dropped)
        if said is False:
            self._drive_reason = ''  # running: a later stop comes with its own reason
        mono, last = time.monotonic_ns(), self._stepped_mono
        self._stepped_mono = mono
        cmd = loop.step(
            ns,
            y,
            est,
            self._join.references,
            inputs.get('model'),
            drive_stopped=said,
            drive_reason=self._drive_reason if said else '',
            own_stall_ns=self._stalls.within(last, mono) if last is not None else 0,
            mono_ns=mono - last if last is not None else None,
        )
        if cmd.gap:
            self._gap(ns, cmd.gap)
        self._answer(ns, cmd.effort)
        if cmd.problem:
            self.get_logger().error(
                f'no valid command {self.timing.when(ns)}: {cmd.problem}: braking',
                throttle_duration_sec=1.0,
            )
        if cmd.tripped:
            self.reports.tripped(ns, loop.trip, self._join.late_references)
        status = loop.law.status()
        if status:
            values = tuple(float(v) for v in status.values())
            self._state_pub.publish(joint_state_bytes(ns, tuple(status), values, sender=self._name))
        record = loop.switch.last_switch
        if record is not None and record is not self._reported_switch:
            self._reported_switch = record
            blend = self.params.values['blend_time']
            self.reports.switched(ns, self._law_name, record, blend)

    def _answer(self, ns: int, effort: float) -> None:
        """Publish the command answering the state ns (NaN: the brake request)."""
        self._last_command = joint_state_bytes(
            ns, (self.axis,), effort=(effort,), sender=self._name
        )
        self._pub.publish(self._last_command)
        if self._commanded is not None:
            self._commanded(ns, effort)

    # -- gaps and this process's own stalls ---------------------------------------------
    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            ours = status.name == self._drive_status and status.hardware_id == self._machine
            if ours and ': stopped: ' in status.message:
                self._drive_reason = status.message.split(': stopped: ', 1)[1]

    def _watch_self(self) -> None:
        self._stalls.wake(time.monotonic_ns(), time.time_ns())

    def _gap(self, ns: int, text: str) -> None:
        """A gap between two states (not a trip): WARN at most once a second, with the count."""
        self._gaps += 1
        now = time.monotonic()
        if now - self._gap_reported < 1.0:
            return
        self._gap_reported = now
        message = (
            f'axis {self.axis} {self.timing.when(ns)}: {text} ({self._name}, pid {os.getpid()}; '
            f'{self._gaps} gaps so far)'
        )
        values = {'gaps': self._gaps, 'own_stalls': self._stalls.count}
        self.guard.diagnostics.report(ns, DiagnosticStatus.WARN, 'state gaps', message, values)

    # -- trip, switch, waiting: the log and /diagnostics ---------------------------------
    def _trip_status(self) -> tuple[bytes, str, str, dict[str, object]]:
        return self.reports.status(self.loop.trip, self._join.late_references)

    def _on_reset_trip(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        cleared = self.loop.reset_trip()
        self._log_reset(cleared, 'the service reset_trip')
        response.success = True
        response.message = 'trip cleared' if cleared else 'no trip to clear'
        return response

    def _log_reset(self, cleared: Trip | None, how: str) -> None:
        self.reports.cleared(max(self._join.last_ns, 0), cleared, how, self.loop.trip)

    def _report_waiting(self) -> None:
        waiting = self._join.waiting_for()
        if waiting is None or self._waiting_since is None:
            return
        if time.monotonic() - self._waiting_since >= 2.0:
            ns, missing = waiting
            names = [self._topics[m] for m in missing]
            detail = ', '.join(f'{n} ({self.count_publishers(n)} publishers)' for n in names)
            when = self.timing.when(ns)
            self.get_logger().warning(f'waiting for the inputs of the state {when} on {detail}')


def main(argv: list[str] | None = None) -> int:
    return run_node(
        AxisControllerNode,
        'axis_controller_node',
        'Motion controller of one axis: measured position + estimate + reference -> torque.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
