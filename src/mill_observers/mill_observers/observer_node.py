"""Observer node: estimates velocity and lumped disturbance of one axis.

Sample k: the command that acts over the period before it is fed to the observer (in
lockstep the command stamped k − 1, the controller's answer to y(k − 1); in real time the
newest command received, which the drive holds), then the measured position y(k) corrects
the estimate, which is published on mill/<axis>/estimate stamped like the state. Lockstep
takes messages in stamp order, so a state that overtakes the previous command waits for it;
real time never waits: a state always gets its estimate at once.

With command_delay N > 0 (real time: 1) the observer runs in the loop's delay
(mill_observers.delay): it predicts with the command that really acts, u(k − N), and
publishes the estimate of sample k + N, the period its controller's command will act in.

Every message is checked before use: sender (plant_node for states, controller_node for
commands), joint, finite values, stamp (mill_common.checks; lockstep: on the grid, not older
than the newest of its input, not later than the plant can be); a bad one is dropped,
counted and reported on /diagnostics. In lockstep a repeated stamp is the same sample offered
again: the first message counts. A non-finite effort of the axis's joint from the
controller is its brake request: the drive brakes the axis, the observer takes it as no
input. Silence on an input is
reported and, in lockstep, ends the node after input_timeout (mill_common.input_guard).
"""

from __future__ import annotations

import time
from functools import partial
from typing import Any

from mill_common.checks import Rejected, StampCheck, ahead, joint_values, owner_check
from mill_common.codec import decode_joint_state
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    from_stamp,
    joint_state_bytes,
    readers_ready,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.timebase import period_ns, seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_observers.config import build_observer, parameter_specs
from mill_observers.delay import DelayCompensation
from mill_observers.registry import OBSERVERS
from mill_observers.switching import EstimateBlend

MAX_COAST = 100  # periods the model runs on without a state before it just resumes


class ObserverNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('observer', **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._comp: DelayCompensation | None = None
        self._blend: EstimateBlend | None = None
        self._last_ns: int | None = None
        self._commands: dict[int, float] = {}
        self._newest_command: float | None = None  # real time: the newest command received
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        axis = self.axis = v['axis']
        self.realtime = v['timing'] == 'realtime'
        self._owners = {
            'state': v['plant_node'],
            'command': v['controller_node'] or f'{axis}_controller',
        }
        self._topics = {'state': topics.state(axis), 'command': topics.joint_command(axis)}
        self._dt_ns = period_ns(v['sample_period'])
        self._coasted = 0  # real time: periods run on without their state
        grid = None if self.realtime else self._dt_ns
        self._stamps = {'state': StampCheck(grid), 'command': StampCheck(grid)}
        self._states: dict[int, float] = {}
        self._last_estimate: bytes | None = None
        self._stalled_since: float | None = None
        self._braked_commands = 0
        self._pub = data_publisher(self, JointState, topics.estimate(axis), DATA_QOS)
        self._state_pub = data_publisher(self, JointState, topics.observer_state(axis), DATA_QOS)
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            exit_on_silence=not self.realtime,
            stamp_ns=lambda: self._last_ns or 0,
        )
        for slot, topic in self._topics.items():
            self.guard.watch(topic, self._owners[slot])
        qos = 1 if self.realtime else DATA_QOS
        for slot, callback in (('state', self._on_state), ('command', self._on_command)):
            topic = self._topics[slot]
            take_serialized(
                self,
                JointState,
                topic,
                decode_joint_state,
                callback,
                qos,
                partial(self.guard.drop, topic),
            )
        self.create_timer(2.0, self._report_waiting, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'axis {axis}: observer {v["observer"]}, timing {v["timing"]}, command_delay '
            f'{v["command_delay"]}, estimates on {self.resolve_topic_name(topics.estimate(axis))}'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._comp is not None and values['axis'] != self.axis:
            raise ValueError('axis is fixed for the life of the node')
        # A rebuilt observer restarts from the next measurement; its estimate continues the
        # old one's and fades into its own over blend_time (mill_observers.switching).
        if self._comp is not None:
            old = self.params.values['observer']
            units = [OBSERVERS.get(n).DISTURBANCE_UNIT for n in (old, values['observer'])]
            if units[0] != units[1]:
                raise ValueError(
                    f'{values["observer"]} estimates the disturbance in {units[1]} but the running '
                    f'{old} in {units[0]}: the controller cannot use both'
                )
        self._comp = DelayCompensation(
            build_observer(values), values['command_delay'], values['sample_period']
        )
        blend = EstimateBlend(values['sample_period'], values['blend_time'])
        if self._last_ns is not None and self._blend is not None:
            blend.resumed(self._blend).switch()  # a switch while running: continue the estimate
        self._blend = blend
        if self._last_ns is not None:
            self._last_ns = None
            self._commands.clear()

    def _accept(self, slot: str, msg: JointState, field: str) -> tuple[int, float] | None:
        """(stamp, value) of a message whose sender, stamp and value are fine, else None."""
        ns = from_stamp(msg.header.stamp)
        topic = self._topics[slot]
        stamps = self._stamps[slot]
        problem = owner_check(msg.header.frame_id, self._owners[slot]) or stamps.check(ns)
        if problem is None and not self.realtime:
            problem = ahead(ns, self._stamps['state'].newest, self._dt_ns)
        if problem is not None:
            if problem.reason.startswith('stamp') and ns == stamps.newest:
                return None
            if not (slot == 'state' and self._last_ns is not None and ns <= self._last_ns):
                self.guard.drop(topic, problem, msg.header.frame_id)
            return None
        value = joint_values(msg.name, {field: getattr(msg, field)}, self.axis, (field,))
        if isinstance(value, Rejected) and not (slot == 'command' and value.non_finite):
            self.guard.drop(topic, value, msg.header.frame_id)
            return None
        if not self.realtime and stamps.is_repeat(ns):
            return None  # lockstep: the same sample again (a re-offered step); the first counts
        if isinstance(value, Rejected):
            # The controller's brake request: the drive brakes, no input acts.
            self._braked_commands += 1
            return ns, float('nan')
        return ns, value[0]

    def _on_state(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._last_ns is not None and ns <= self._last_ns:
            if self.realtime:
                self.guard.drop(self._topics['state'], Rejected('stamp repeated or in the past'))
            elif ns == self._last_ns and self._last_estimate is not None:
                if msg.header.frame_id == self._owners['state']:
                    self.guard.heard(self._topics['state'])  # the plant is there, waiting
                self._pub.publish(self._last_estimate)  # the plant offered this step again
            return
        got = self._accept('state', msg, 'position')
        if got is None:
            return
        self.guard.heard(self._topics['state'])
        if not self.realtime and not readers_ready(
            self, self._pub, self.params.values['min_subscribers']
        ):
            return  # the plant offers the step again
        self._stamps['state'].accept(got[0])
        self._states[got[0]] = got[1]
        self._advance()

    def _on_command(self, msg: JointState) -> None:
        got = self._accept('command', msg, 'effort')
        if got is None:
            return
        ns, u = got
        self.guard.heard(self._topics['command'])
        self._stamps['command'].accept(ns)
        if self.realtime:
            self._newest_command = u
        elif self._last_ns is None or ns >= self._last_ns:
            self._commands[ns] = u
            self._advance()

    def _advance(self) -> None:
        comp, blend = self._comp, self._blend
        assert comp is not None and blend is not None, 'configured in NodeParameters'
        while self._states:
            ns = min(self._states)
            if self.realtime:
                ns = max(self._states)  # nothing stale: the newest state only
                self._states = {ns: self._states[ns]}
                if self._last_ns is not None:
                    held = 0.0 if self._newest_command is None else self._newest_command
                    # Periods whose state never reached us: the model runs on without one.
                    missed = min(round((ns - self._last_ns) / self._dt_ns) - 1, MAX_COAST)
                    for _ in range(max(missed, 0)):
                        comp.coast(held)
                    self._coasted += max(missed, 0)
                    comp.command(held)
            elif self._last_ns is not None:
                u = self._commands.pop(self._last_ns, None)
                if u is None:
                    self._stalled_since = self._stalled_since or time.monotonic()
                    return  # y(k) arrived before u(k-1): wait for it
                comp.command(u)
            est = blend(comp.correct(self._states.pop(ns)))
            self._last_ns = ns
            self._stalled_since = None
            self._last_estimate = joint_state_bytes(
                ns,
                (self.axis,),
                (est.position,),
                (est.velocity,),
                (est.disturbance,),
                sender=self._name,
            )
            self._pub.publish(self._last_estimate)
            status = comp.observer.status()
            if status:
                values = tuple(float(v) for v in status.values())
                self._state_pub.publish(
                    joint_state_bytes(ns, tuple(status), values, sender=self._name)
                )

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
