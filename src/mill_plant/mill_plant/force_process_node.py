"""Force-process plant node (Rubio 2013 eq. (1)-(3)): the feed drive and the cut, and the clock.

Lockstep, one sample per spindle revolution (T = 60/S_s; stamps are the nearest ns to kT):

1. publish /clock and the force sample F_p(t_k) on /mill/cutting_force (the force along
   `feed_axis`);
2. wait for the reference stamped t_k on /mill/reference: its velocity along `feed_axis`
   is the feed command u(t_k) [m/s], its acceleration the slope of the reconstruction over
   the sample (a β-hold makes the command ramp within the sample, not a staircase);
3. apply u(t_k + τ) = u0 + slope·τ, clamped to `feed_limits`, for one T (exact
   integration), publish the force on a grid over the sample on /mill/cutting_force/trace
   and go on with k + 1. The trace is one trajectory_msgs/JointTrajectory per sample,
   stamped t_k, joint `force_<feed_axis>`: each point's positions[0] is the force [N] at
   t_k + time_from_start; a repeated time marks a jump or a kink (a depth change, a clamp
   corner), the left value first.

With `recorder_window` W (run_scenario --record) sample k goes out only once the recorder
has acknowledged sample k − W on mill/recorded (mill_common.lockstep.RecorderGate), so
that a bag misses nothing however busy the machine.

A non-finite reference never reaches the drive: the last feed is held and an ERROR goes to
/diagnostics. A reference stamped later than the current step is dropped, counted and
reported (WARN); an older one is a repeat of an answered sample and is ignored. A step
whose reference does not arrive within `lockstep_timeout` ends the node with a message
naming the topic and its publishers.
"""

from __future__ import annotations

import math
import time
from typing import Any

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from mill_common.checks import DropCounter, Rejected
from mill_common.codec import encode_clock
from mill_common.diagnostics import Diagnostics
from mill_common.lockstep import Action, LockstepWatchdog, RecorderGate
from mill_common.node_main import request_exit, run_node
from mill_common.parameters import algorithm_values
from mill_common.ros import DATA_QOS, LATCHED_QOS, data_publisher, from_stamp, to_stamp
from mill_common.ros_params import NodeParameters
from mill_common.signals import AXES
from mill_common.timebase import sample_stamp_ns
from mill_models.force_process import ForceProcessModel, ForceProcessPlant
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from mill_common import topics
from mill_plant.config import ForceProcessParams, force_process_specs
from mill_plant.force_drive import DrivenForceProcess

STATUS_PART = 'force process'  # the status `<node>: force process`
MM_PER_M = 1000.0


class ForceProcessNode(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('force_process', **options)
        self._drive: DrivenForceProcess  # built once by _configure
        self._built = False
        self.params = NodeParameters(self, force_process_specs(), self._configure)
        v = self.params.values
        self._axis = AXES.index(v['feed_axis'])
        self._k = 0
        self._feed = (0.0, 0.0)  # last applied (u0, slope) [mm/s, mm/s²]
        self._faults = 0
        self._drops = DropCounter()
        self._wall_start = time.monotonic()
        self._lockstep = LockstepWatchdog(
            self._wall_start,
            lambda: self.params.values['startup_timeout'],
            lambda: self.params.values['lockstep_timeout'],
        )

        self._clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, DATA_QOS)
        self._force_pub = data_publisher(self, WrenchStamped, topics.CUTTING_FORCE, DATA_QOS)
        self._trace_pub = data_publisher(
            self, JointTrajectory, topics.CUTTING_FORCE_TRACE, DATA_QOS
        )
        self._diagnostics = Diagnostics(self)
        self._ref_sub = self.create_subscription(
            JointTrajectory, topics.REFERENCE, self._on_reference, DATA_QOS
        )
        self._recorder = RecorderGate(v['recorder_window'], self._T)
        self._held = False  # sample k waits for the recorder
        if self._recorder.window:
            self.create_subscription(ClockMsg, topics.RECORDED, self._on_recorded, LATCHED_QOS)
        self.create_timer(0.05, self._watchdog, clock=Clock(clock_type=ClockType.STEADY_TIME))
        m = self._drive.plant.model
        self.get_logger().info(
            f'force process ready: {m.spindle_speed_rpm:g} rpm, T = {self._T * 1e3:.4f} ms, '
            f'feed along {v["feed_axis"]} in [{self._drive.lo:g}, {self._drive.hi:g}] mm/s; '
            'waiting for the force controller and the trajectory'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        if self._built:
            return  # the model is read-only; the others are read where used
        model = ForceProcessModel.from_parameters(algorithm_values(ForceProcessModel, values))
        self._T = model.sample_period
        own = ForceProcessParams.from_node_values(values)
        lo, hi = own.feed_limits
        self._drive = DrivenForceProcess(
            ForceProcessPlant(model), lo, hi, self._T / own.trace_intervals
        )
        self._built = True

    # -- lockstep ----------------------------------------------------------------------------
    def _stamp_ns(self) -> int:
        return sample_stamp_ns(self._k, self._T)

    def _wrench(self, ns: int, force: float) -> WrenchStamped:
        msg = WrenchStamped()
        msg.header.stamp = to_stamp(ns)
        msg.header.frame_id = 'tool'
        setattr(msg.wrench.force, AXES[self._axis], float(force))
        return msg

    def _publish_sample(self) -> None:
        self._held = not self._recorder.allows(self._k)
        if self._held:
            return  # _on_recorded sends it
        ns = self._stamp_ns()
        self._clock_pub.publish(encode_clock(ns))
        self._force_pub.publish(self._wrench(ns, self._drive.plant.force))

    def _on_recorded(self, msg: ClockMsg) -> None:
        self._recorder.acknowledged(from_stamp(msg.clock))
        if self._held:
            self._publish_sample()

    def _on_reference(self, msg: JointTrajectory) -> None:
        ns = from_stamp(msg.header.stamp)
        if self._held or not self._lockstep.started or ns < self._stamp_ns():
            return  # a repeat of an answered sample, or before the start
        if ns != self._stamp_ns():
            reason = (
                f'stamp {ns / 1e9:.9f} s is not the current step {self._stamp_ns() / 1e9:.9f} s'
            )
            if self._drops.drop(topics.REFERENCE, Rejected(reason), time.monotonic()):
                text = (
                    f'dropped a message on {topics.REFERENCE} from '
                    f'{msg.header.frame_id or "an unnamed publisher"}: {reason} '
                    f'({self._drops.total} so far)'
                )
                self.get_logger().warning(text)
                self._publish_status(DiagnosticStatus.WARN, text)
            return
        u0, slope = self._command(msg)
        self._publish_trace(self._drive.apply(u0, slope, self._T))
        self._k += 1
        self._lockstep.progressed(time.monotonic())
        if self._k % max(1, round(1.0 / self._T)) == 0:
            self._publish_status(DiagnosticStatus.OK, 'running')
        self._publish_sample()

    def _publish_trace(self, pieces: list) -> None:
        ns = self._stamp_ns()
        msg = JointTrajectory()
        msg.header.stamp = to_stamp(ns)
        msg.joint_names = [f'force_{AXES[self._axis]}']
        for times, forces in pieces:
            for t, f in zip(times.tolist(), forces.tolist(), strict=True):
                point = JointTrajectoryPoint(positions=[f])
                offset = round(t * 1e9) - ns  # absolute ns as round(t), like the samples
                point.time_from_start = Duration(
                    sec=offset // 1_000_000_000, nanosec=offset % 1_000_000_000
                )
                msg.points.append(point)
        self._trace_pub.publish(msg)

    def _command(self, msg: JointTrajectory) -> tuple[float, float]:
        try:
            point = msg.points[0]
            u0 = MM_PER_M * float(point.velocities[self._axis])
            slope = MM_PER_M * float(point.accelerations[self._axis])
        except (IndexError, TypeError):
            u0 = slope = math.nan
        if math.isfinite(u0) and math.isfinite(slope):
            self._feed = (u0, slope)
            return u0, slope
        self._faults += 1
        if self._faults == 1:
            self.get_logger().error(
                f'non-finite or missing feed command on {topics.REFERENCE} at step {self._k}: '
                'holding the last feed'
            )
        self._publish_status(DiagnosticStatus.ERROR, 'feed command not finite: last feed held')
        held = self._feed[0] + self._feed[1] * self._T  # where the last ramp ended
        self._feed = (self._drive.clamp(held), 0.0)
        return self._feed

    # -- start-up, retries, timeouts -------------------------------------------------------
    def _missing_peers(self) -> list[str]:
        missing = []
        if self._ref_sub.get_publisher_count() < 1:
            missing.append(f'no publisher on {topics.REFERENCE}')
        need = self.params.values['min_subscribers']
        have = self._force_pub.get_subscription_count()
        if have < need:
            missing.append(f'{have}/{need} subscribers on {topics.CUTTING_FORCE}')
        return missing

    def _watchdog(self) -> None:
        action = self._lockstep.tick(time.monotonic(), self._missing_peers)
        if action is Action.START:
            self.get_logger().info('all peers matched: starting lockstep')
            self._publish_sample()
        elif action is Action.OFFER_AGAIN and not self._held:
            self._publish_sample()
        elif action is Action.PEERS_MISSING:
            request_exit(self, 3, 'peers never appeared: ' + '; '.join(self._missing_peers()))
        elif action is Action.STALLED and self._held:
            request_exit(
                self,
                3,
                f'lockstep timeout: step {self._k} waited '
                f'{self.params.values["lockstep_timeout"]:g} s for the recorder (its newest '
                f'acknowledgement on {topics.RECORDED}: {self._recorder.describe()})',
            )
        elif action is Action.STALLED:
            infos = self.get_publishers_info_by_topic(topics.REFERENCE)
            nodes = sorted({i.node_name for i in infos})
            who = f'from {", ".join(nodes)}' if nodes else 'and no node publishes it'
            request_exit(
                self,
                3,
                f'lockstep timeout: no reference for t = {self._stamp_ns() / 1e9:.4f} s '
                f'(step {self._k}) after {self.params.values["lockstep_timeout"]:g} s on '
                f'{topics.REFERENCE} ({who})',
            )

    def _publish_status(self, level: bytes, message: str) -> None:
        plant = self._drive.plant
        values = {
            'step': self._k,
            'time': plant.time,
            'force': plant.force,
            'feed_actual': plant.feed_actual,
            'depth': plant.model.depth_at(plant.time),
            'faults': self._faults,
            'dropped': self._drops.total,
            'wall_s': time.monotonic() - self._wall_start,
        }
        status = self._diagnostics.status(level, STATUS_PART, message, values)
        self._diagnostics.publish(self._stamp_ns(), [status])


def main(argv: list[str] | None = None) -> int:
    return run_node(
        ForceProcessNode,
        'force_process_node',
        'Cutting-force process of Rubio 2013 (feed drive + cut, eq. 1-3) and the /clock of '
        'the run.',
        force_process_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
