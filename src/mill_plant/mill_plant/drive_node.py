"""Drive front end: topics, command checks, watchdog, ownership, diagnostics, lifecycle.

The plant node is this front end over the simulated machine; a hardware driver is this
front end over a hardware backend (mill_plant.backend: read positions, write efforts,
report faults). It is a managed lifecycle node: `configure` builds the backend and the
topics, `activate` starts applying commands, `deactivate` brakes every axis; with
`autostart` (the default) it does both by itself. When it steps is its `timing`
(mill_plant.drive_cycle): lockstep (the plant is the clock of a simulation) or realtime
(the wall clock, zero-order hold; an axis is stopped when its commands stay away longer
than the window H(v) of mill_common.hold_window, or on a motion the drive does not allow,
and released only by a re-arm or `~/release`; every state it publishes says whether it has
stopped the axis: `effort` NaN).

What command it takes, from whom, is its intake's decision (mill_plant.command_intake); a
command it drops is counted and reported (a rate-limited WARN `<node>: inputs` on
/diagnostics naming the topic and the sender), a brake request (a non-finite effort from the
owner) once when it starts, and once when valid commands return. What it says on
/diagnostics and in its log is its reports' (mill_plant.drive_reports); the topics it
makes at configure are mill_plant.drive_topics.

With `ros2_control.commands_topic` set (realtime only) the axes take their efforts from
topic_based_ros2_control's topic pair instead of mill/<axis>/joint_command
(mill_plant.topic_pair; its ROS side mill_plant.ros2_control_adapter): the same intake,
ownership, table and protection, with the pair's owner; mill/<axis>/joint_command is then
refused.

With `spindle: reference` the drive also reads the spindle speed the reference carries
(mill_plant.spindle) and gives it to the backend with the efforts of each sample; in
lockstep a step then waits for it as for its commands.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Collection, Sequence
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import Rejected, Sender
from mill_common.codec import encode_clock, encode_wrench_stamped
from mill_common.diagnostics import Diagnostics
from mill_common.hold_window import HoldWindow, effort_said
from mill_common.node_main import request_exit
from mill_common.parameters import ParameterError, ParamSpec
from mill_common.ros import DATA_QOS, LATCHED_QOS, from_stamp, graph_owners, joint_state_bytes
from mill_common.ros_params import NodeParameters
from mill_common.timebase import period_ns, seconds
from mill_common.travel import MachineTravel
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.service import Service
from rclpy.timer import Timer
from rosgraph_msgs.msg import Clock as ClockMsg
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from mill_common import topics
from mill_plant.backend import DriveBackend
from mill_plant.command_intake import Accepted, CommandIntake, Dropped
from mill_plant.command_table import CommandTable
from mill_plant.drive_counts import DriveCounts
from mill_plant.drive_cycle import CYCLES, DriveCycle, Machine
from mill_plant.drive_reports import DriveReports
from mill_plant.drive_setup import MACHINE_AXES, command_owners, configure_refusal
from mill_plant.drive_topics import DriveTopics
from mill_plant.joint_states import JointStates
from mill_plant.ownership import Ownership
from mill_plant.ros2_control_adapter import Ros2ControlPair
from mill_plant.spindle import SpindleTrack, spindle_values
from mill_plant.topic_pair import Ros2ControlParams


class DriveNode(LifecycleNode):
    def __init__(
        self,
        make_backend: Callable[[dict[str, Any]], DriveBackend],
        specs: Sequence[tuple[str, ParamSpec]],
        name: str = 'plant',
        **options: Any,
    ) -> None:
        super().__init__(name, **options)
        self._name = self.get_name()  # the sender of every message; asked once
        self._make_backend = make_backend
        self.backend: DriveBackend | None = None
        # Read-only values cannot change; the others are read where they are used.
        self.params = NodeParameters(self, specs, lambda values: None)
        v = self.params.values
        self.dt_ns = period_ns(v['sample_period'])
        self.dt = seconds(self.dt_ns)
        self.cycle: DriveCycle = CYCLES[v['timing']](self.dt_ns, self._name)
        self.reports = DriveReports(self)
        self.ownership: Ownership | None = None  # set by configure, with the owners
        self._timers: list[Timer] = []
        self._release_service: Service | None = None
        self._made: tuple[Diagnostics, DriveTopics, Ros2ControlPair | None] | None = None
        self.pair: Ros2ControlPair | None = None  # ros2_control.commands_topic
        self._clock_pub: Any = None  # lockstep: /clock, by the first configure
        self._recorded_sub: Any = None  # lockstep with a recorder window
        self.get_logger().info(
            f'drive {name}: timing {v["timing"]}, T = {self.dt * 1e3:g} ms; '
            + ('configuring by itself' if v['autostart'] else 'waiting for configure')
        )
        if v['autostart']:
            self.trigger_configure()
            if v['timing'] == 'realtime':
                self.trigger_activate()
            # lockstep: activated by the cycle once the peers are matched

    # -- lifecycle -------------------------------------------------------------------------
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        v = self.params.values
        try:
            backend = self._make_backend(v)
        except (ValueError, OSError) as exc:
            self.get_logger().error(f'cannot configure the machine: {exc}')
            return TransitionCallbackReturn.FAILURE
        pair = Ros2ControlParams.from_node_values(v)
        refusal = configure_refusal(self.cycle.GRID, backend.SIMULATED, pair)
        if refusal is not None:
            self.get_logger().error(refusal)
            return TransitionCallbackReturn.FAILURE
        self.backend = backend
        self.axes = list(backend.axes)
        owned = command_owners(self.axes, v['command_owners'], pair, self._name)
        axis_owners = owned.axis_topics
        self.owners = owned.axes
        self.ownership = Ownership(self, axis_owners, owned.pair_topics)
        try:
            window = HoldWindow.from_node_values(v)
            MachineTravel.from_node_values(v)  # the guard's travel (refused here, in one line)
        except ParameterError as exc:
            self.get_logger().error(f'cannot configure the machine: {exc}')
            return TransitionCallbackReturn.FAILURE
        self.table = CommandTable(self.axes, window, self.dt_ns)
        self._written: list[float] = [math.nan] * len(self.axes)
        grid = self.dt_ns if self.cycle.GRID else None
        if pair.commands_topic:  # stamped with the sender's write time, frame_id empty
            self.intake = CommandIntake(self.owners, None, self.cycle.sender_stamped, False)
        else:
            self.intake = CommandIntake(self.owners, grid, self.cycle.expected)
        self.counts = DriveCounts(self.axes)
        self.joint_states = JointStates(self.axes, v['joint_states_rate'], self.dt)
        # spindle: reference
        self.spindle = SpindleTrack() if v['spindle'] == 'reference' else None
        if self._made is None:  # once: a configure after a cleanup takes the same topics again
            on_reference = self._on_reference if self.spindle is not None else None
            self.graph = graph_owners(self, self._on_contested)
            io = DriveTopics(
                self,
                self.axes,
                backend.SIMULATED,
                self._on_command,
                on_reference,
                self.reports.drop,
                self.graph,
                axis_owners,
            )
            pair_io = None
            if pair.commands_topic:
                pair_io = Ros2ControlPair(
                    self,
                    self.axes,
                    pair,
                    self.dt,
                    self.graph,
                    self.take_command,
                    self.reports.drop,
                    self._foreign,
                )
            self._made = (Diagnostics(self), io, pair_io)
        self.diagnostics, self.io, self.pair = self._made
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        self.add_timer(self.create_timer(0.05, self._watchdog, clock=wall))
        if self._release_service is None:
            self._release_service = self.create_service(Trigger, '~/release', self._on_release)
        self.cycle.configure(self._machine())
        if self.cycle.TICKS:
            self.add_timer(self.create_timer(self.dt, self._tick, clock=wall))
        self.get_logger().info(
            f'configured: axes {", ".join(self.axes)}, commands from '
            + ', '.join(f'{a}: {o or "anyone"}' for a, o in self.owners.items())
            + (
                f' on {pair.commands_topic} (ros2_control), states on {pair.states_topic}'
                if pair.commands_topic
                else ''
            )
        )
        return TransitionCallbackReturn.SUCCESS

    def _machine(self) -> Machine:
        """What the cycle is handed: this node as its port, and its collaborators."""
        v = self.params.values
        clock = None
        if self.cycle.GRID:  # once: a configure after a cleanup takes the same topics again
            if self._clock_pub is None:
                self._clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, DATA_QOS)
            if v['recorder_window'] and self._recorded_sub is None:
                self._recorded_sub = self.create_subscription(
                    ClockMsg,
                    topics.RECORDED,
                    self._on_recorded,
                    LATCHED_QOS,
                )
            pub = self._clock_pub
            clock = lambda ns: pub.publish(encode_clock(ns))  # noqa: E731
        return Machine(
            port=self,
            axes=self.axes,
            table=self.table,
            reports=self.reports,
            values=lambda: self.params.values,
            owners=self.owners,
            spindle=self.spindle,
            log=self.get_logger(),
            missing_peers=self.missing_peers,
            publishers_of=self._publishers_of,
            activate=self.trigger_activate,
            end=self.end,
            clock=clock,
            command_topic=self.command_topic,
        )

    def _on_recorded(self, msg: ClockMsg) -> None:
        self.cycle.recorded(from_stamp(msg.clock))

    def _publishers_of(self, topic: str) -> list[str]:
        return sorted({i.node_name for i in self.get_publishers_info_by_topic(topic)})

    def _tick(self) -> None:
        if self.backend is not None:
            self.cycle.tick()

    def add_timer(self, timer: Timer) -> None:
        """A timer that lives until cleanup."""
        self._timers.append(timer)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.cycle.activate()
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.cycle.deactivate()
        if self.backend is not None:
            self.table.brake_all()
            self.backend.write([math.nan] * len(self.axes))
        self.get_logger().info('inactive: every axis braked')
        return TransitionCallbackReturn.SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        if self.backend is not None:
            self.backend.write([math.nan] * len(self.axes))
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def _release(self) -> None:
        for timer in self._timers:
            timer.cancel()
            self.destroy_timer(timer)
        self._timers = []
        self.backend = None

    # -- commands ----------------------------------------------------------------------------
    def command_topic(self, axis: str) -> str:
        """The topic the axis's commands come on."""
        return self.pair.commands_topic if self.pair is not None else topics.joint_command(axis)

    def _on_command(self, axis: str, msg: JointState, who: Sender) -> None:
        if self.pair is not None:
            topic, named = topics.joint_command(axis), who.called(msg.header.frame_id)
            problem = Rejected(
                f'axis {axis} takes its commands on {self.pair.commands_topic} only '
                '(ros2_control.commands_topic)'
            )
            self.reports.drop(topic, problem, named)
            return
        self.take_command(axis, topics.joint_command(axis), msg, who)

    def _foreign(self, topic: str, named: str) -> None:
        """A message on `topic` from a node the graph says is not its owner."""
        owned = self.ownership
        if owned is not None and owned.message_from(topic, named):
            self.reports.foreign(topic, named)

    def take_command(
        self, axis: str, topic: str, msg: JointState, who: Sender
    ) -> Accepted | Dropped | None:
        """The axis's effort in the command msg that came on `topic` from `who`: taken into
        the table, or dropped and reported; returns the intake's verdict."""
        if self.backend is None or (self.cycle.GRID and not self.cycle.active):
            return None
        sender = msg.header.frame_id
        ns = from_stamp(msg.header.stamp)
        got = self.intake.take(axis, ns, sender, msg.name, msg.effort, who)
        if got is None:
            return None  # a repeat of an answered step: harmless
        if not isinstance(got, Accepted):
            named = who.called(sender)
            if got.foreign:
                self._foreign(topic, named)
            self.reports.drop(topic, got.problem, named)
            return got
        if got.brake_request:
            self.reports.axis(
                axis, DiagnosticStatus.ERROR, f'invalid command ({got.brake_request}): braked'
            )
        elif got.released:
            self.reports.axis(axis, DiagnosticStatus.OK, 'valid commands again: released')
        self.table.offer(axis, ns, got.effort, self.cycle.arrival_ns())
        self.cycle.command_taken()
        return got

    def _on_contested(self, topic: str, owner: str, claimants: tuple[str, ...]) -> None:
        """Two or more live publishers of `topic` claim the owner's name:
        neither drives the axis (mill_plant.command_intake); said once per set."""
        if self.ownership is not None:
            self.ownership.contested(topic, owner, claimants)
        self.reports.contested(topic, owner, claimants)

    def _on_reference(self, msg: Any) -> None:
        """The spindle speeds of a reference message (spindle: reference)."""
        if self.spindle is None:
            return
        speeds = spindle_values(msg.joint_names, msg.points)
        if speeds is None:
            problem = Rejected("no finite speed of the joint 'spindle' in every point")
            self.reports.drop(topics.REFERENCE, problem, msg.header.frame_id)
            return
        ns = from_stamp(msg.header.stamp)
        stamps = [ns + from_stamp(p.time_from_start) for p in msg.points]
        self.spindle.offer(stamps, speeds)
        if self.cycle.GRID and self.cycle.active:
            self.cycle.command_taken()  # the step may have waited only for this

    def _on_release(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        """The operator's release of the stopped axes (mill_plant.command_table)."""
        released = self.cycle.release() if self.backend is not None else []
        response.success = bool(released)
        response.message = (
            f'released {", ".join(released)}: braked until the next fresh command'
            if released
            else 'no axis is stopped'
        )
        self.get_logger().info(f'~/release: {response.message}')
        return response

    def end(self, code: int, message: str) -> None:
        """End the node after this callback (run_node exits with code and message)."""
        request_exit(self, code, message)

    # -- one period: states out, efforts in ------------------------------------------------
    def publish(self, ns: int, say_stops: bool = False) -> list[float]:
        """Read and publish the positions of sample ns; returns them.

        say_stops (realtime): each state's `effort` says whether the drive has stopped the
        axis (NaN: stopped, braked until re-armed) or else the effort it applied over the
        period that ends now (0 while the brake holds the axis before its first command):
        a controller trips on the drive's word, never on a guess from a gap.
        """
        assert self.backend is not None
        name = self._name
        positions = self.backend.read()
        publishers = self.io.states
        if say_stops:
            table = self.table.by_axis
            for axis, y, u in zip(self.axes, positions, self._written, strict=True):
                said = effort_said(bool(table[axis].stopped), u)
                publishers[axis].publish(
                    joint_state_bytes(ns, (axis,), position=(y,), effort=(said,), sender=name)
                )
        else:
            for axis, y in zip(self.axes, positions, strict=True):
                publishers[axis].publish(joint_state_bytes(ns, (axis,), position=(y,), sender=name))
        joints = self.joint_states.sample(ns, positions, self._written)
        if joints is not None and self.io.joint_states.get_subscription_count():
            self.io.joint_states.publish(
                joint_state_bytes(ns, joints.names, joints.position, joints.velocity, joints.effort)
            )
        # The cutting force of sample ns depends on its state, not on its commands: sent
        # with the states, a force controller can answer within the sample.
        if self.pair is not None:
            self.pair.publish(ns, positions, self._written)
        force_pub = self.io.force
        if force_pub is not None and force_pub.get_subscription_count():
            force = self.backend.cutting_force()
            if force is not None:
                force_pub.publish(encode_wrench_stamped(ns, 'tool', force))
        return positions

    def write(self, ns: int, efforts: list[float]) -> None:
        """Write the efforts and publish the ground truth of sample ns."""
        assert self.backend is not None
        backend = self.backend
        backend.write(efforts)
        self._written = efforts
        if self.spindle is not None:  # with the efforts: what the step ns -> ns + T does
            backend.spindle(self.spindle.at(ns))
            self.spindle.forget_before(ns)
        # Skipped without listeners: publishing costs more than the whole plant step.
        truth_pub = self.io.truth
        if truth_pub is not None and truth_pub.get_subscription_count():
            truth = backend.truth()
            if truth is not None:
                truth_pub.publish(joint_state_bytes(ns, MACHINE_AXES, *truth))

    def advance(self, ns: int, dt: float, held: Collection[str] = ()) -> None:
        """Let dt seconds pass with the efforts written (a simulated machine integrates;
        a real one has moved by itself) and report what the step did to them.

        held: axes the drive holds braked before their first command (realtime): that is
        the state a job starts from, not a fault to report.
        """
        assert self.backend is not None
        backend = self.backend
        backend.advance(dt)
        report = backend.last_report
        first = self.counts.step(report, MACHINE_AXES, held) if report is not None else []
        for axis in first:  # braked for the first time
            self.get_logger().error(
                f'axis {axis} braked {self.cycle.when(ns)}: no finite command '
                f'on {self.command_topic(axis)} to apply'
            )
            self.reports.status(force=True, message=f'axis {axis} braked')

    # -- watchdog, start-up ------------------------------------------------------------------
    def missing_peers(self) -> list[str]:
        return self.io.missing_peers(self.params.values['min_subscribers'])

    def _watchdog(self) -> None:
        if self.backend is None:
            return
        now = time.monotonic()
        self.cycle.watch(now)
        self.reports.periodic(now)
