"""Plant node: the simulated three-axis machine and the clock of the simulation.

Lockstep: it publishes /clock and the measured position of every axis for step
k, waits for the torque command stamped k from every active axis, then
integrates to k+1. The commands' arrival, not the wall clock, paces the run,
so results do not depend on DDS latency or machine load. A step whose
commands do not arrive within `lockstep_timeout` ends the node with a message
naming the missing topics and their publishers.

The cutting force of step k is a function of the state of step k (position, velocity,
time), not of its commands: it is published with the measured positions, so a force
controller can answer within the step (the adaptive-feed job sets the reference of step k
from the force of step k). Ground truth, which holds the disturbance the commands meet, is
published once the commands have arrived.
"""

from __future__ import annotations

import math
import time
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from mill_common.lockstep import Action, LockstepWatchdog
from mill_common.node_main import request_exit, run_node
from mill_common.ros import DATA_QOS, diagnostic_array, first, joint_state, to_stamp
from mill_common.ros_params import NodeParameters
from mill_common.signals import AXES
from mill_common.timebase import period_ns, seconds
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_plant.config import build_plant, parameter_specs
from mill_plant.sensor import quantize

STATUS_NAME = 'mill_plant: lockstep'


class PlantNode(Node):
    def __init__(self) -> None:
        super().__init__('plant')
        self._plant = None
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        self._active = [a in v['axes'] for a in AXES]
        self._dt_ns = period_ns(v['sample_period'])
        self._dt = seconds(self._dt_ns)
        self._clock_every = max(1, round(v['clock_period'] * 1e9 / self._dt_ns))
        self._k = 0
        self._commands: dict[str, float] = {}
        self._faults = dict.fromkeys(AXES, 0)
        self._saturations = dict.fromkeys(AXES, 0)
        self._wall_start = time.monotonic()
        self._last_publish_wall = self._wall_start
        self._wait_sum = 0.0
        self._wait_max = 0.0
        self._lockstep = LockstepWatchdog(
            self._wall_start,
            lambda: self.params.values['startup_timeout'],
            lambda: self.params.values['lockstep_timeout'],
        )

        self._clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, DATA_QOS)
        self._state_pubs = {
            a: self.create_publisher(JointState, topics.state(a), DATA_QOS) for a in AXES
        }
        self._truth_pub = self.create_publisher(JointState, topics.GROUND_TRUTH, DATA_QOS)
        self._force_pub = self.create_publisher(WrenchStamped, topics.CUTTING_FORCE, DATA_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self._command_subs = {
            a: self.create_subscription(
                JointState,
                topics.joint_command(a),
                lambda msg, axis=a: self._on_command(axis, msg),
                DATA_QOS,
            )
            for a, on in zip(AXES, self._active, strict=True)
            if on
        }
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(0.05, self._watchdog, clock=wall)
        self.get_logger().info(
            f'plant ready: axes {", ".join(v["axes"])}, T = {self._dt * 1e3:g} ms, '
            f'cutting model {v["cutting_model"]}; waiting for controllers and observers'
        )

    # -- configuration -------------------------------------------------------------------
    def _configure(self, values: dict[str, Any]) -> None:
        if self._plant is not None:
            return  # the model's parameters are read-only; the others are read where used
        self._plant = build_plant(values)
        self._resolution = values['sensor_resolution']

    # -- lockstep ----------------------------------------------------------------------------
    def _stamp_ns(self) -> int:
        return self._k * self._dt_ns

    def _publish_step(self) -> None:
        ns = self._stamp_ns()
        if self._k % self._clock_every == 0:
            self._clock_pub.publish(ClockMsg(clock=to_stamp(ns)))
        position = self._plant.position
        for i, axis in enumerate(AXES):
            if self._active[i]:
                y = quantize(position[i], self._resolution)
                self._state_pubs[axis].publish(joint_state(ns, (axis,), position=(y,)))
        self._publish_force(ns)
        self._last_publish_wall = time.monotonic()

    def _on_command(self, axis: str, msg: JointState) -> None:
        ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        if not self._lockstep.started or ns != self._stamp_ns():
            return  # a repeat of an answered step, or before the start
        try:
            value = first(msg.effort, 'effort')
        except ValueError:
            value = math.nan
        self._commands[axis] = value
        if len(self._commands) == len(self._command_subs):
            self._advance()

    def _advance(self) -> None:
        now = time.monotonic()
        wait = now - self._last_publish_wall
        self._wait_sum += wait
        self._wait_max = max(self._wait_max, wait)
        # An inactive axis gets a non-finite command: the plant brakes it.
        torque = tuple(self._commands.get(a, math.nan) for a in AXES)
        self._commands = {}
        ns = self._stamp_ns()
        if self.params.values['publish_ground_truth']:
            self._publish_truth(ns, torque)  # before the step: the state of sample k
        report = self._plant.step(torque, self._dt)
        for i, axis in enumerate(AXES):
            if not self._active[i]:
                continue
            if report.faulted[i]:
                self._faults[axis] += 1
                if self._faults[axis] == 1:
                    self.get_logger().error(
                        f'non-finite torque command on {topics.joint_command(axis)} at '
                        f't = {seconds(ns):.4f} s: axis {axis} braked'
                    )
                    self._publish_status(DiagnosticStatus.ERROR, f'axis {axis} braked')
            if report.saturated[i]:
                self._saturations[axis] += 1
        self._k += 1
        self._lockstep.progressed(now)
        if self._k % max(1, round(1.0 / self._dt)) == 0:
            self._publish_status(DiagnosticStatus.OK, 'running')
        self._publish_step()

    def _publish_truth(self, ns: int, torque: tuple[float, ...]) -> None:
        # Skipped without listeners: publishing costs more than the whole plant step.
        if self._truth_pub.get_subscription_count():
            xi = self._plant.disturbance(torque)
            self._truth_pub.publish(
                joint_state(ns, AXES, self._plant.position, self._plant.velocity, xi)
            )

    def _publish_force(self, ns: int) -> None:
        if not self._force_pub.get_subscription_count():
            return
        force = self._plant.cutting_force()
        msg = WrenchStamped()
        msg.header.stamp = to_stamp(ns)
        msg.header.frame_id = 'tool'
        msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = force
        self._force_pub.publish(msg)

    # -- start-up, retries, timeouts -------------------------------------------------------
    def _missing_peers(self) -> list[str]:
        missing = []
        for axis, sub in self._command_subs.items():
            if sub.get_publisher_count() < 1:
                missing.append(f'no publisher on {topics.joint_command(axis)}')
            need = self.params.values['min_subscribers']
            have = self._state_pubs[axis].get_subscription_count()
            if have < need:
                missing.append(f'{have}/{need} subscribers on {topics.state(axis)}')
        return missing

    def _watchdog(self) -> None:
        action = self._lockstep.tick(time.monotonic(), self._missing_peers, self._k == 0)
        if action is Action.START:
            self.get_logger().info('all peers matched: starting lockstep')
            self._publish_step()
        elif action is Action.OFFER_AGAIN:
            self._publish_step()
        elif action is Action.PEERS_MISSING:
            request_exit(self, 3, 'peers never appeared: ' + '; '.join(self._missing_peers()))
        elif action is Action.STALLED:
            request_exit(self, 3, self._timeout_message())

    def _timeout_message(self) -> str:
        waiting = [a for a in self._command_subs if a not in self._commands]
        parts = []
        for axis in waiting:
            topic = topics.joint_command(axis)
            nodes = sorted({i.node_name for i in self.get_publishers_info_by_topic(topic)})
            who = f'from {", ".join(nodes)}' if nodes else 'and no node publishes it'
            parts.append(f'{topic} ({who})')
        t = seconds(self._stamp_ns())
        return (
            f'lockstep timeout: no command for t = {t:.3f} s (step {self._k}) after '
            f'{self.params.values["lockstep_timeout"]:g} s on ' + ', '.join(parts)
        )

    def _publish_status(self, level: bytes, message: str) -> None:
        steps = max(self._k, 1)
        values = {
            'step': self._k,
            'time': seconds(self._stamp_ns()),
            'mean_wait_ms': 1e3 * self._wait_sum / steps,
            'max_wait_ms': 1e3 * self._wait_max,
            'wall_s': time.monotonic() - self._wall_start,
        }
        for axis in AXES:
            values[f'{axis}.faults'] = self._faults[axis]
            values[f'{axis}.saturations'] = self._saturations[axis]
        self._diag_pub.publish(
            diagnostic_array(self._stamp_ns(), level, STATUS_NAME, message, 'mill_plant', values)
        )


def main(argv: list[str] | None = None) -> int:
    return run_node(
        PlantNode,
        'plant_node',
        'Simulated three-axis milling machine (Beltrán 2013 eq. 1-4) and the /clock of the run.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
