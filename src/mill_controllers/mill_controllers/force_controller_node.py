"""Force controller node (Rubio 2013): cutting force in, feed override out.

Subscribes to /mill/cutting_force and acts once per control period T (one spindle
revolution of its process model): on the first force sample stamped at or after the next
control instant it runs the chosen law (`force_controller`: fixed β, scheme1, scheme2;
mill_controllers.force_control) on the peak force heard since the last instant
(`force_measure`: peak, or the sample at the instant). It publishes on /mill/feed_override
a JointState stamped like that force sample: position[0] = the override o_k (1 = programmed
feed), velocity[0] = its β-hold slope over the sample [1/s]. A trajectory in lockstep
answers each override with the reference of that sample; any other user of the
feed-override input may ignore the slope.

With `depth_source: position` the law is told the tool's depth below `workpiece_top` at the
control instant: the node also follows /mill/z/state and acts once the measured z of the
instant's stamp has arrived too.

A force sample stamped before the newest one, or so far ahead that it skips a control
instant, is dropped, counted and reported on /diagnostics (`<node>: inputs`); silence on
the force is reported and, on simulated time (in lockstep with the plant), ends the node
after input_timeout (mill_common.input_guard). A non-finite force sample is replaced by the
last finite one, and an override outside
[override.min, override.max] is clamped (a non-finite one holds the last): neither reaches the
trajectory, and both are reported on /diagnostics as a WARN. The force, reference, feed
command, override, active β and depth go to /mill/force_control/state every sample, with the
reference model's ξ and ω_n (so that J_c can be computed from a bag).
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from mill_common.checks import Rejected, StampCheck
from mill_common.codec import decode_joint_state, decode_wrench_stamped
from mill_common.input_guard import InputGuard
from mill_common.node_main import run_node
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    from_stamp,
    joint_state,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.timebase import sample_stamp_ns
from rclpy.node import Node
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_controllers.force_control import (
    ForceFeedLoop,
    ForceSampler,
    OverrideCommand,
    parameter_specs,
    tool_depth,
)

STATUS_PART = 'force control'  # the status `<node>: force control`
# the law's force, reference, feed command, override, active β and depth at the instant, then
# its reference model eq. (7) (ξ, ω_n): what J_c of eq. (14) compares the force with
STATE_NAMES = (
    'force',
    'reference',
    'feed_command',
    'override',
    'beta',
    'depth',
    'model_damping',
    'model_natural_frequency',
)


class ForceControllerNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('force_controller', **options)
        self._loop: ForceFeedLoop  # built once by _configure
        self._built = False
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        self._sampler = ForceSampler(self._loop.T, v['force_component'], v['force_measure'])
        self._last: tuple[int, JointState] | None = None  # last force stamp and its answer
        self._clamped = 0
        self._beta = self._loop.law.active_beta
        # depth_source position: measured z by stamp, and a control instant waiting for it
        self._z: dict[int, float] = {}
        self._waiting: tuple[int, int, float] | None = None  # (stamp, j, force)
        self._override_pub = data_publisher(self, JointState, topics.FEED_OVERRIDE, DATA_QOS)
        self._state_pub = data_publisher(self, JointState, topics.FORCE_CONTROL_STATE, DATA_QOS)
        self._stamps = StampCheck(None)  # the force samples' stamps (the sender's grid)
        self.guard = InputGuard(
            self,
            lambda: self.params.values['input_warn_time'],
            lambda: self.params.values['input_timeout'],
            # On simulated time the plant that sends the force is the clock (lockstep).
            exit_on_silence=bool(self.get_parameter('use_sim_time').value),
            stamp_ns=lambda: self._stamps.newest or 0,
        )
        self.guard.watch(topics.CUTTING_FORCE)
        force, z = topics.CUTTING_FORCE, topics.state('z')
        take_serialized(
            self,
            WrenchStamped,
            force,
            decode_wrench_stamped,
            self._on_force,
            DATA_QOS,
            partial(self.guard.drop, force),
        )
        if v['depth_source'] == 'position':
            z_dropped = partial(self.guard.drop, z)
            take_serialized(
                self, JointState, z, decode_joint_state, self._on_z, DATA_QOS, z_dropped
            )
        self.get_logger().info(
            f'force controller {v["force_controller"]} (β = {self._beta:g}), '
            f'F_r = {v["reference_force"]:g} N, T = {self._loop.T * 1e3:.4f} ms, override in '
            f'[{self._loop.lo:g}, {self._loop.hi:g}] of {v["nominal_feed"]:g} mm/s'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if values['override.min'] > values['override.max']:
            raise ValueError('override.min must not exceed override.max')
        if not self._built:
            self._loop = ForceFeedLoop.from_parameters(values)
            self._built = True
        # reference_force, the only changeable value, is read at every sample

    def _on_force(self, msg: Any) -> None:
        ns = from_stamp(msg.header.stamp)
        T = self._loop.T
        if self._last is not None and ns == self._last[0]:
            self.guard.heard(topics.CUTTING_FORCE)
            self._override_pub.publish(self._last[1])  # a repeated sample: the same answer
            return
        problem = self._stamps.check(ns)
        if problem is None and self._stamps.is_repeat(ns):
            return  # a sample seen already (between instants, or an instant waiting for z)
        next_j = self._sampler.next_instant
        if problem is None and self._last is not None and ns > sample_stamp_ns(next_j + 1, T):
            # The plant's sample period is shorter than T: the first sample at or after the
            # next instant comes before the one after it.
            problem = Rejected(f'stamp {ns / 1e9:.6f} s skips the control instant {next_j}')
        if problem is not None:
            self.guard.drop(topics.CUTTING_FORCE, problem, msg.header.frame_id)
            return
        self.guard.heard(topics.CUTTING_FORCE)
        self._stamps.accept(ns)
        f = msg.wrench.force
        hit = self._sampler.offer(ns, (f.x, f.y, f.z))
        if hit is None:
            return  # between control instants
        if self.params.values['depth_source'] == 'position':
            self._waiting = (ns, *hit)
            self._act_when_positioned()
        else:
            self._act(ns, *hit, None)

    def _on_z(self, msg: Any) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._last is not None and ns <= self._last[0]:
            return  # an instant already answered
        self._z[ns] = msg.position[0] if len(msg.position) else math.nan
        self._act_when_positioned()

    def _act_when_positioned(self) -> None:
        if self._waiting is None or self._waiting[0] not in self._z:
            return
        ns, j, measured = self._waiting
        self._waiting = None
        z = self._z[ns]
        self._z = {s: v for s, v in self._z.items() if s > ns}
        depth = tool_depth(self.params.values['workpiece_top'], z) if math.isfinite(z) else 0.0
        self._act(ns, j, measured, depth)

    def _act(self, ns: int, j: int, measured: float, depth: float | None) -> None:
        reference = self.params.values['reference_force']
        cmd = self._loop.step(j * self._loop.T, reference, measured, depth)
        out = joint_state(ns, ('override',), position=(cmd.override,), velocity=(cmd.slope,))
        self._override_pub.publish(out)
        self._last = (ns, out)
        model = self._loop.law.designer
        state = (
            *(cmd.force, reference, cmd.feed_command, cmd.override, cmd.beta, cmd.depth),
            *(model.damping, model.omega_n),
        )
        self._state_pub.publish(joint_state(ns, STATE_NAMES, position=state))
        self._report(ns, cmd, measured)

    def _report(self, ns: int, cmd: OverrideCommand, measured: float) -> None:
        problems = []
        if cmd.held:
            problems.append(f'non-finite force sample {measured}: holding {cmd.force:g} N')
        if cmd.clamped:
            self._clamped += 1
            wanted = cmd.feed_command / self._loop.nominal_feed
            problems.append(
                f'override {wanted:g} outside [{self._loop.lo:g}, {self._loop.hi:g}]: '
                f'sent {cmd.override:g}'
            )
        switched = cmd.beta != self._beta
        self._beta = cmd.beta
        if problems:
            for p in problems:
                self.get_logger().warning(p, throttle_duration_sec=1.0)
            self._publish_status(ns, DiagnosticStatus.WARN, '; '.join(problems), cmd)
        elif switched or ns == 0:
            self._publish_status(ns, DiagnosticStatus.OK, f'active β = {cmd.beta:g}', cmd)

    def _publish_status(self, ns: int, level: bytes, message: str, cmd: OverrideCommand) -> None:
        values = {
            'force_controller': self.params.values['force_controller'],
            'active_beta': cmd.beta,
            'override': cmd.override,
            'held_samples': self._loop.held_samples,
            'clamped_samples': self._clamped,
        }
        status = self.guard.diagnostics.status(level, STATUS_PART, message, values)
        self.guard.diagnostics.publish(ns, [status])


def main(argv: list[str] | None = None) -> int:
    return run_node(
        ForceControllerNode,
        'force_controller_node',
        'Cutting-force control by adaptive feed (Rubio 2013): /mill/cutting_force in, '
        '/mill/feed_override out.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
