"""Observer node: velocity and lumped disturbance of one axis; take → check → step → publish.

Inputs: the measured position on mill/<axis>/state (from plant_node) and the controller's
command on mill/<axis>/joint_command (from controller_node). Every message is checked
(sender, joint, finite values, stamp: mill_common.checks); a bad one is dropped, counted
and reported on /diagnostics (mill_common.input_guard). A non-finite effort from the
controller is its brake request: the drive brakes, the observer takes it as no input.
While two publishers claim an input's owner's name (mill_common.graph_owner) both are
refused, but the step is not waited on: a contested command is taken as the brake the drive
makes of it, a contested state's step is passed without an estimate (the controller answers
it with a brake request). Which state is stepped when, with which command, and that contest
rule are mill_observers.observer_steps' (ROS-free).

Each state goes to the ROS-free ObserverLoop (mill_observers.observer_loop) with the command
that acted over the period before it, the object the offline simulator steps too, and the
estimate goes out on mill/<axis>/estimate stamped like the state (with command_delay N, the
estimate of the period the next command acts in). The `timing` strategy
(mill_common.timing) says which command that is: lockstep takes messages in stamp order
(y(k) waits for u(k − 1); a state offered again is answered with the same estimate); real
time never waits: the newest state gets its estimate at once, with the newest command
received (the one the drive holds) and the periods between two states run through.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from mill_common.checks import CONTESTED, Rejected, Sender, joint_values, owner_check, sender_check
from mill_common.codec import decode_joint_state
from mill_common.hold_window import drive_word, said_at
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

from mill_common import topics
from mill_observers.config import build_observer_loop, check_other_observers, parameter_specs
from mill_observers.observer_loop import ObserverLoop
from mill_observers.observer_steps import PASS, PAST, WAIT, ObserverSteps
from mill_observers.registry import OBSERVERS

# The controller of a servo cycle: (stamp, position, estimate, what the drive said, and
# whether the state came from a contested plant: then answered by a brake request).
Servo = Callable[[int, float, Estimate, bool | None, bool], None]
UNMEASURED = Estimate(math.nan, math.nan, math.nan)  # handed with a contested state


class ObserverNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('observer', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._loop: ObserverLoop | None = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        axis = self.axis = v['axis']
        self.timing = timing(v['timing'], period_ns(v['sample_period']))
        self.steps = ObserverSteps(self.timing)  # the states and commands, by stamp
        self._owners = {
            'state': v['plant_node'],
            'command': v['controller_node'] or f'{axis}_controller',
        }
        self._topics = {'state': topics.state(axis), 'command': topics.joint_command(axis)}
        self._fields = {'state': 'position', 'command': 'effort'}
        self._stamps = {slot: self.timing.stamps() for slot in self._topics}
        self._last_estimate: bytes | None = None
        self._stalled_since: float | None = None
        # Nothing waits for the estimate in a servo cycle: its controller has it already.
        self._pub = data_publisher(self, JointState, topics.estimate(axis), DATA_QOS, True)
        self._state_pub = data_publisher(
            self, JointState, topics.observer_state(axis), DATA_QOS, True
        )
        # A controller of this axis in this process, handed each sample at once (its servo
        # cycle: mill_bringup.container connects them): (stamp, position, estimate).
        self.servo: Servo | None = None
        self._served: tuple[int, float, Estimate, bool | None, bool] | None = None
        # What the drive said of the axis in each state not yet stepped (mill_common.
        # hold_window.drive_word), handed on to the controller of a servo cycle.
        self._said: dict[int, bool | None] = {}
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=self.timing.EXIT_ON_SILENCE,
            stamp_ns=lambda: self.steps.last_ns or 0,
        )
        depth = self.timing.depth()
        self._inputs: dict[str, DataInput] = {}
        self._advancing = False
        # Each input's sender as the graph identifies its publisher (mill_common.graph_owner).
        self._graph = graph_owners(self, self.guard.contested)  # both refused
        for slot, callback in (('state', self._on_state), ('command', self._on_command)):
            topic = self._topics[slot]
            self.guard.watch(topic, self._owners[slot])
            on_bad = partial(self.guard.drop, topic)
            qos = DATA_QOS if depth is None else depth
            self._inputs[slot] = take_owned(
                self,
                JointState,
                topic,
                decode_joint_state,
                callback,
                qos,
                on_bad,
                self._graph,
                self._owners[slot],
            )
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: observer {v["observer"]}, timing {v["timing"]}, command_delay '
            f'{v["command_delay"]}, estimates on {self.resolve_topic_name(topics.estimate(axis))}'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        first = self._loop is None
        if self._loop is not None:
            old = self.params.values['observer']
            units = [OBSERVERS.get(n).DISTURBANCE_UNIT for n in (old, values['observer'])]
            if units[0] != units[1]:
                raise ValueError(
                    f'{values["observer"]} estimates the disturbance in {units[1]} but the running '
                    f'{old} in {units[0]}: the controller cannot use both'
                )
        loop = build_observer_loop(values)  # raises, with the reason, before anything changes
        # to switch to later (at start-up: those given other gains than their defaults)
        check_other_observers(values, None if self._loop is None else self.params.values)
        # A rebuilt observer starts from the next measurement, its estimate continuing.
        self._loop = loop if self._loop is None else self._loop.replace(loop)
        if not first:
            self.steps.forget_commands()

    # -- take and check ------------------------------------------------------------------
    def _foreign(self, slot: str, msg: JointState, who: Sender) -> bool:
        """Whether a message is not its owner's (dropped and reported, then)."""
        owner = self._owners[slot]
        problem = sender_check(who, owner) if owner else None
        problem = problem or owner_check(msg.header.frame_id, owner)
        if problem is not None:
            self.guard.drop(self._topics[slot], problem, who.name or msg.header.frame_id)
        return problem is not None

    def _accept(self, slot: str, msg: JointState) -> tuple[int, float] | None:
        """(stamp, value) of a message whose stamp and value are fine (its sender is
        checked before), else None."""
        ns = from_stamp(msg.header.stamp)
        topic, sender, stamps = self._topics[slot], msg.header.frame_id, self._stamps[slot]
        newest_state = self._stamps['state'].newest
        problem = self.timing.problem(stamps, ns, newest_state, self.timing.period_ns)
        if problem is not None:
            if problem.reason.startswith('stamp') and ns == stamps.newest:
                return None
            if not (slot == 'state' and self.steps.behind(ns) is not None):
                self.guard.drop(topic, problem, sender)
            return None
        field = self._fields[slot]
        value = joint_values(msg.name, {field: getattr(msg, field)}, self.axis, (field,))
        brake = isinstance(value, Rejected) and slot == 'command' and value.non_finite
        if isinstance(value, Rejected) and not brake:
            self.guard.drop(topic, value, sender)
            return None
        if self.timing.is_offered_again(stamps, ns):
            return None  # the same sample again (a re-offered step); the first counts
        self.guard.heard(topic)
        return ns, float('nan') if isinstance(value, Rejected) else value[0]

    def _on_state(self, msg: JointState, who: Sender) -> None:
        contested = who.verdict == CONTESTED and bool(self._owners['state'])
        if contested:
            self._refuse_contested('state', who)
        elif self._foreign('state', msg, who):
            return
        ns = from_stamp(msg.header.stamp)
        behind = self.steps.behind(ns)
        if behind is not None:
            if behind == PAST:
                past = Rejected('stamp repeated or in the past')
                self.guard.drop(self._topics['state'], past, msg.header.frame_id)
            else:  # AGAIN
                self.guard.heard(self._topics['state'])  # the plant is there, waiting
                if self.servo is not None and self._served is not None:
                    self.servo(*self._served)
                if self._last_estimate is not None:  # (none of a contested state)
                    self._pub.publish(self._last_estimate)  # the plant offered this step again
            return
        got = self._accept('state', msg)
        if got is None:
            return
        if self.timing.WAITS_FOR_READERS and not readers_ready(
            self, self._pub, self.params.values['min_subscribers']
        ):
            return  # the plant offers the step again
        self._stamps['state'].accept(got[0])
        self.steps.state(*got, contested)
        if not contested and self.servo is not None:
            self._said[got[0]] = drive_word(msg.effort)
        self._advance()

    def _on_command(self, msg: JointState, who: Sender) -> None:
        if who.verdict == CONTESTED and self._owners['command']:
            self._contested_command(msg, who)
            return
        if self._foreign('command', msg, who):
            return
        got = self._accept('command', msg)
        if got is not None:
            self.commanded(*got)

    def _refuse_contested(self, slot: str, who: Sender) -> None:
        problem = sender_check(who, self._owners[slot])
        if problem is not None:
            self.guard.drop(self._topics[slot], problem, who.name)

    def _contested_command(self, msg: JointState, who: Sender) -> None:
        """A command of one of two publishers claiming the controller's name: refused as a
        command (dropped and named), and taken as a brake request for its step
        (ObserverSteps.brakes_pending). Refusing the step outright would stall the observer,
        and the real controller behind it, and the copy would then be the only claimant
        that speaks."""
        self._refuse_contested('command', who)
        if self.steps.brakes_pending(from_stamp(msg.header.stamp)):
            return
        got = self._accept('command', msg)
        if got is not None:
            self.commanded(got[0], math.nan)

    def serve(self, servo: Servo) -> None:
        """A servo cycle (mill_bringup.container): hand each estimated sample to this axis's
        controller in this process at once; its commands come back through `commanded`."""
        self.servo = servo
        data_mute(self._inputs['command'])  # still a reader of the topic, taking nothing

    def commanded(self, ns: int, u: float) -> None:
        """The controller's command answering the state of stamp ns (NaN: brake)."""
        if self.servo is not None:
            self.guard.heard(self._topics['command'])
        self._stamps['command'].accept(ns)
        if self.steps.commanded(ns, u) and not self._advancing:
            self._advance()  # (a servo cycle answers from inside _advance)

    # -- step and publish ----------------------------------------------------------------
    def _advance(self) -> None:
        self._advancing = True
        try:
            self._step_due()
        finally:
            self._advancing = False

    def _step_due(self) -> None:
        loop = self._loop
        assert loop is not None, 'configured in NodeParameters'
        for step in self.steps.due(lambda: loop.started):
            if step.kind == WAIT:
                self._stalled_since = self._stalled_since or time.monotonic()
                return
            self._stalled_since = None
            if step.kind == PASS:
                self._pass_contested(step.ns)
                continue
            ns, y = step.ns, step.y
            est = loop.step(y, step.acted, step.missed, step.late)
            if self.servo is not None:  # the command first; the estimate when idle
                said = said_at(self._said, ns)  # (and forgets the states the timing dropped)
                self._served = (ns, y, est, said, False)
                self.servo(*self._served)
            self._last_estimate = joint_state_bytes(
                ns,
                (self.axis,),
                (est.position,),
                (est.velocity,),
                (est.disturbance,),
                sender=self._name,
            )
            self._pub.publish(self._last_estimate)
            status = loop.status()
            if status:
                values = tuple(float(v) for v in status.values())
                self._state_pub.publish(
                    joint_state_bytes(ns, tuple(status), values, sender=self._name)
                )

    def _pass_contested(self, ns: int) -> None:
        """A state two publishers sent under the plant's name, passed (ObserverSteps): no
        estimate of it; in a servo cycle its controller is handed it to brake."""
        self._last_estimate = None
        self._said.pop(ns, None)
        if self.servo is not None:  # its controller takes no state of its own
            self._served = (ns, math.nan, UNMEASURED, None, True)
            self.servo(*self._served)

    def _report_waiting(self) -> None:
        last_ns = self.steps.last_ns
        if last_ns is None or self._stalled_since is None:
            return
        if time.monotonic() - self._stalled_since > 2.0:
            topic = topics.joint_command(self.axis)
            self.get_logger().warning(
                f'waiting for the command answering the state {self.timing.when(last_ns)} on '
                f'{topic} '
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
