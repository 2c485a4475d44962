"""Drive front end: timing, topics, command watchdog, ownership, diagnostics, lifecycle.

The plant node is this front end over the simulated machine; a hardware driver is this
front end over a hardware backend (mill_plant.backend: read positions, write efforts,
report faults). It is a managed lifecycle node: `configure` builds the backend and the
topics, `activate` starts applying commands, `deactivate` brakes every axis; with
`autostart` (the default) it does both by itself.

timing `lockstep` (simulation only): the plant is the clock. It publishes /clock and the
measured position of every axis for step k (stamp kT), waits for the command stamped k of
every active axis, then integrates to k + 1. A step that stays unanswered is offered again
every second, so a restarted controller or observer rejoins; a missing command is reported
on /diagnostics after `command_report_time`, naming the axis, the topic and the node that
should send it, and when its commands arrive again, with the length of the silence; after
`lockstep_timeout` the node ends with that message.

timing `realtime`: every sample period of wall time it reads the positions, publishes them
stamped with the acquisition time on the system clock, and applies the newest command of
each axis (zero-order hold). A command answers a state: its stamp must be one this drive
published. A period without a fresh command counts as late; after `brake_after` late
periods in a row the axis is braked until fresh commands return, and /diagnostics says so.

Every command must come from the axis's owner (header.frame_id, `command_owners`); anything
else — another sender, a stamp that answers no state, an unknown joint, no effort for the
joint — is dropped, counted and reported (a rate-limited WARN `mill_plant: inputs` on
/diagnostics naming the topic and the sender). A non-finite effort of the axis's joint from
the owner brakes the axis for that period and is reported: it is the controller saying it
has no valid command.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Collection, Sequence
from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from mill_common.checks import DropCounter, Rejected, StampCheck, joint_values, owner_check
from mill_common.codec import decode_joint_state, encode_clock, encode_wrench_stamped
from mill_common.lockstep import Action, LockstepWatchdog
from mill_common.node_main import request_exit
from mill_common.parameters import ParamSpec
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    diagnostic_status,
    diagnostics_of,
    from_stamp,
    joint_state_bytes,
    take_serialized,
)
from mill_common.ros_params import NodeParameters
from mill_common.timebase import period_ns, seconds
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rosgraph_msgs.msg import Clock as ClockMsg
from sensor_msgs.msg import JointState

from mill_common import topics
from mill_plant.backend import DriveBackend
from mill_plant.command_table import CommandTable
from mill_plant.ownership import Ownership

LOCKSTEP_STATUS = 'mill_plant: lockstep'
REALTIME_STATUS = 'mill_plant: realtime'
INPUTS_STATUS = 'mill_plant: inputs'
AXIS_STATUS = 'mill_plant: {} axis'
MACHINE_AXES = ('x', 'y', 'z')
RECENT_STAMPS = 200  # realtime: published state stamps a command may answer


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
        self.timing = v['timing']
        self._dt_ns = period_ns(v['sample_period'])
        self._dt = seconds(self._dt_ns)
        self.active = False
        self._lockstep_allowed = False  # lockstep: activated (by autostart or the lifecycle)
        self._drops = DropCounter()
        self.ownership: Ownership | None = None  # set by configure, with the owners
        self._faults: dict[str, int] = {}
        self._nonfinite: dict[str, int] = {}
        self._brake_requested: set[str] = set()  # axes whose last command was not finite
        self._saturations: dict[str, int] = {}
        self._wall_start = time.monotonic()
        self._next_status = 0.0
        self._reported_missing: set[str] = set()
        self.get_logger().info(
            f'drive {name}: timing {self.timing}, T = {self._dt * 1e3:g} ms; '
            + ('configuring by itself' if v['autostart'] else 'waiting for configure')
        )
        if v['autostart']:
            self.trigger_configure()
            if self.timing == 'realtime':
                self.trigger_activate()
            # lockstep: activated by the watchdog once the peers are matched

    # -- lifecycle -----------------------------------------------------------------------------
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        v = self.params.values
        try:
            backend = self._make_backend(v)
        except (ValueError, OSError) as exc:
            self.get_logger().error(f'cannot configure the machine: {exc}')
            return TransitionCallbackReturn.FAILURE
        if self.timing == 'lockstep' and not backend.SIMULATED:
            self.get_logger().error('a real machine cannot run in lockstep: use timing realtime')
            return TransitionCallbackReturn.FAILURE
        self.backend = backend
        self.axes = list(backend.axes)
        owners = dict(zip(MACHINE_AXES, v['command_owners'], strict=True))
        self.owners = {a: owners[a] for a in self.axes}
        self.ownership = Ownership(self, self.owners)
        self.table = CommandTable(self.axes, v['brake_after'])
        self._stamps = {
            a: StampCheck(self._dt_ns if self.timing == 'lockstep' else None) for a in self.axes
        }
        self._recent: deque[int] = deque(maxlen=RECENT_STAMPS)
        self._k = 0
        # Realtime: ticks that came more than half a period late (the machine does not hold
        # the sample rate), in all and since the last report; ticks while active, their basis.
        self._overruns = 0
        self._active_ticks = 0
        self._overruns_reported = 0
        self._faults = dict.fromkeys(self.axes, 0)
        self._nonfinite = dict.fromkeys(self.axes, 0)
        self._saturations = dict.fromkeys(self.axes, 0)
        self._wait_sum = self._wait_max = 0.0
        self._last_publish_wall = time.monotonic()
        self._state_pubs = {
            a: data_publisher(self, JointState, topics.state(a), DATA_QOS) for a in self.axes
        }
        self._diag_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self._clock_pub = None
        if self.timing == 'lockstep':
            self._clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, DATA_QOS)
            self._clock_every = max(1, round(v['clock_period'] * 1e9 / self._dt_ns))
        self._truth_pub = self._force_pub = None
        if backend.SIMULATED:
            self._truth_pub = data_publisher(self, JointState, topics.GROUND_TRUTH, DATA_QOS)
            self._force_pub = data_publisher(self, WrenchStamped, topics.CUTTING_FORCE, DATA_QOS)
        self._command_subs = {
            a: take_serialized(
                self,
                JointState,
                topics.joint_command(a),
                decode_joint_state,
                partial(self._on_command, a),
                DATA_QOS,
                partial(self._drop, topics.joint_command(a)),
            )
            for a in self.axes
        }
        wall = Clock(clock_type=ClockType.STEADY_TIME)
        self._timers = [self.create_timer(0.05, self._watchdog, clock=wall)]
        if self.timing == 'lockstep':
            self._lockstep = LockstepWatchdog(
                time.monotonic(),
                lambda: self.params.values['startup_timeout'],
                lambda: self.params.values['lockstep_timeout'],
            )
        else:
            self._timers.append(self.create_timer(self._dt, self._tick, clock=wall))
        self.get_logger().info(
            f'configured: axes {", ".join(self.axes)}, commands from '
            + ', '.join(f'{a}: {o or "anyone"}' for a, o in self.owners.items())
        )
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        if self.timing == 'realtime':
            self.active = True
            self.get_logger().info('active: applying commands')
        # lockstep: stepping starts once the peers are matched (see _watchdog)
        self._lockstep_allowed = True
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = False
        self._lockstep_allowed = False
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
        for timer in getattr(self, '_timers', []):
            timer.cancel()
            self.destroy_timer(timer)
        self._timers = []
        self.backend = None

    # -- commands ------------------------------------------------------------------------------
    def _expected_stamp(self, ns: int) -> Rejected | None:
        if self.timing == 'lockstep':
            want = self._k * self._dt_ns
            if ns != want:
                return Rejected(
                    f'stamp {ns / 1e9:.6f} s is not the current step {want / 1e9:.6f} s'
                )
            return None
        if ns not in self._recent:
            return Rejected(f'stamp {ns / 1e9:.6f} s answers no state this drive published')
        return None

    def _on_command(self, axis: str, msg: JointState) -> None:
        if self.backend is None or (self.timing == 'lockstep' and not self.active):
            return
        topic = topics.joint_command(axis)
        ns = from_stamp(msg.header.stamp)
        problem = owner_check(msg.header.frame_id, self.owners[axis])
        sender = msg.header.frame_id or '(unnamed)'
        owned = self.ownership
        if problem is not None and owned is not None and owned.message_from(topic, sender):
            self._foreign_named(topic, sender)
        problem = problem or self._stamps[axis].check(ns) or self._expected_stamp(ns)
        if problem is not None:
            if self.table.by_axis[axis].stamp == ns and problem.reason.startswith('stamp'):
                return  # a repeat of an answered step (after a re-offer): harmless
            self._drop(topic, problem, msg.header.frame_id)
            return
        if self.table.by_axis[axis].stamp == ns:
            return  # the owner answered this step again (a re-offered step)
        value = joint_values(msg.name, {'effort': msg.effort}, axis, ('effort',))
        if isinstance(value, Rejected) and not value.non_finite:
            self._drop(topic, value, msg.header.frame_id)  # no joint, no effort: malformed
            return
        if isinstance(value, Rejected):
            # From the owner, for the step it must answer: no valid command, so brake. Said
            # once when it starts (a tripped controller asks for it every sample).
            self._nonfinite[axis] += 1
            if axis not in self._brake_requested:
                self._brake_requested.add(axis)
                self._report_axis(
                    axis, DiagnosticStatus.ERROR, f'invalid command ({value.reason}): braked'
                )
            effort = math.nan
        else:
            effort = value[0]
            if axis in self._brake_requested:
                self._brake_requested.discard(axis)
                self._report_axis(axis, DiagnosticStatus.OK, 'valid commands again: released')
        self._stamps[axis].accept(ns)
        self.table.offer(axis, ns, effort, time.time_ns() if self.timing == 'realtime' else None)
        if self.timing == 'lockstep' and self.table.complete(self._k * self._dt_ns):
            self._advance_lockstep()

    def _drop(self, topic: str, problem: Rejected, sender: str) -> None:
        if self._drops.drop(topic, problem, time.monotonic()):
            text = (
                f'dropped a message on {topic} from {sender or "an unnamed publisher"}: '
                f'{problem.reason} ({self._drops.counts[topic]} so far)'
            )
            self.get_logger().warning(text)
            status = diagnostic_status(
                DiagnosticStatus.WARN, INPUTS_STATUS, text, 'mill_plant', dict(self._drops.counts)
            )
            self._diag_pub.publish(diagnostics_of(self._stamp_now(), [status]))

    def _foreign_named(self, topic: str, who: str) -> None:
        self.get_logger().error(f'foreign publisher {who} on {topic}: its messages are ignored')
        self._publish_status(force=True)

    # -- lockstep ------------------------------------------------------------------------------
    def _publish_step(self) -> None:
        ns = self._k * self._dt_ns
        if self._clock_pub is not None and self._k % self._clock_every == 0:
            self._clock_pub.publish(encode_clock(ns))
        self._publish_states(ns)
        self._last_publish_wall = time.monotonic()

    def _reoffer(self) -> None:
        ns = self._k * self._dt_ns
        if self._clock_pub is not None:
            self._clock_pub.publish(encode_clock(ns))
        self._publish_states(ns)

    def _publish_states(self, ns: int) -> None:
        assert self.backend is not None
        name = self._name
        for axis, y in zip(self.axes, self.backend.read(), strict=True):
            self._state_pubs[axis].publish(
                joint_state_bytes(ns, (axis,), position=(y,), sender=name)
            )
        self._publish_force(ns)

    def _advance_lockstep(self) -> None:
        assert self.backend is not None
        now = time.monotonic()
        wait = now - self._last_publish_wall
        self._wait_sum += wait
        self._wait_max = max(self._wait_max, wait)
        ns = self._k * self._dt_ns
        self._apply(ns, self.table.values())
        self._k += 1
        if self._reported_missing:  # the step waited this long: the outage's length
            waited = self._lockstep.waited(now)
            for axis in self._reported_missing:
                message = f'commands arriving again after {waited:.2f} s of silence'
                self._report_axis(axis, DiagnosticStatus.OK, message)
            self._reported_missing.clear()
        self._lockstep.progressed(now)
        if self._k % max(1, round(1.0 / self._dt)) == 0:
            self._publish_status(force=True)
        self._publish_step()

    def _apply(self, ns: int, efforts: list[float], held: Collection[str] = ()) -> None:
        """Write the efforts, publish the analysis topics of sample ns, integrate one period.

        held: axes the drive holds braked before their first command (realtime): that is
        the state a job starts from, not a fault to report.
        """
        assert self.backend is not None
        backend = self.backend
        backend.write(efforts)
        self._publish_truth(ns)
        backend.advance(self._dt)
        report = backend.last_report
        if report is None:
            return
        for axis in self.axes:
            i = MACHINE_AXES.index(axis)
            if report.faulted[i] and axis not in held:
                self._faults[axis] += 1
                if self._faults[axis] == 1:
                    self.get_logger().error(
                        f'axis {axis} braked at t = {seconds(ns):.4f} s: no finite command '
                        f'on {topics.joint_command(axis)} to apply'
                    )
                    self._publish_status(force=True, message=f'axis {axis} braked')
            if report.saturated[i]:
                self._saturations[axis] += 1

    def _publish_truth(self, ns: int) -> None:
        # Skipped without listeners: publishing costs more than the whole plant step.
        assert self.backend is not None
        if self._truth_pub is not None and self._truth_pub.get_subscription_count():
            truth = self.backend.truth()
            if truth is not None:
                self._truth_pub.publish(joint_state_bytes(ns, MACHINE_AXES, *truth))

    def _publish_force(self, ns: int) -> None:
        # The cutting force of sample ns depends on its state (position, velocity, time),
        # not on its commands: sent with the states, a force controller can answer within
        # the sample (the adaptive-feed job sets the reference of sample k from its force),
        # and the re-offer of an unanswered step repeats it too.
        assert self.backend is not None
        if self._force_pub is not None and self._force_pub.get_subscription_count():
            force = self.backend.cutting_force()
            if force is not None:
                self._force_pub.publish(encode_wrench_stamped(ns, 'tool', force))

    # -- real time -----------------------------------------------------------------------------
    def _tick(self) -> None:
        if self.backend is None:
            return
        ns = time.time_ns()  # acquisition time on the system clock
        if self.active:
            self._active_ticks += 1
            if self._recent and ns - self._recent[-1] > 1.5 * self._dt_ns:
                self._overruns += 1
        self._publish_states(ns)
        self._recent.append(ns)
        held: Collection[str] = self.axes  # inactive: every axis held braked, as expected
        if self.active:
            tick = self.table.take()
            efforts = tick.efforts
            held = [a for a, c in self.table.by_axis.items() if c.stamp < 0]  # none came yet
            for axis in tick.newly_braked:
                owner = self.owners[axis] or 'its controller'
                self._report_axis(
                    axis,
                    DiagnosticStatus.ERROR,
                    f'braked: no fresh command for {self.params.values["brake_after"]} periods '
                    f'on {topics.joint_command(axis)} (from {owner})',
                )
            for axis in tick.resumed:
                self._report_axis(axis, DiagnosticStatus.OK, 'fresh commands: released')
        else:
            efforts = [math.nan] * len(self.axes)
        self._apply(ns, efforts, held)
        self._k += 1

    # -- watchdog, start-up, diagnostics -------------------------------------------------------
    def _missing_peers(self) -> list[str]:
        missing = []
        need = self.params.values['min_subscribers']
        for axis, sub in self._command_subs.items():
            if sub.get_publisher_count() < 1:
                missing.append(f'no publisher on {topics.joint_command(axis)}')
            have = self._state_pubs[axis].get_subscription_count()
            if have < need:
                missing.append(f'{have}/{need} subscribers on {topics.state(axis)}')
        return missing

    def _watchdog(self) -> None:
        if self.backend is None:
            return
        now = time.monotonic()
        if self.timing == 'lockstep':
            self._watch_lockstep(now)
        else:
            self._watch_realtime()
        if now >= self._next_status:
            self._check_owners()
            self._publish_status()

    def _watch_lockstep(self, now: float) -> None:
        if not self._lockstep_allowed and not self.params.values['autostart']:
            return  # waiting for the lifecycle transition activate
        action = self._lockstep.tick(now, self._missing_peers)
        if action is Action.START:
            if not self._lockstep_allowed:
                self.trigger_activate()  # autostart
            self.active = True
            self.get_logger().info('all peers matched: starting lockstep')
            self._publish_step()
        elif action is Action.OFFER_AGAIN:
            self._reoffer()
        elif action is Action.PEERS_MISSING:
            request_exit(self, 3, 'peers never appeared: ' + '; '.join(self._missing_peers()))
        elif action is Action.STALLED:
            request_exit(self, 3, self._timeout_message())
        if self._lockstep.started and self._lockstep.waited(now) >= self._report_time():
            for axis in self.table.missing(self._k * self._dt_ns):
                if axis not in self._reported_missing:
                    self._reported_missing.add(axis)
                    self._report_axis(axis, DiagnosticStatus.WARN, self._missing_text(axis, now))

    def _watch_realtime(self) -> None:
        if not self.active:
            return
        if self._overruns > self._overruns_reported and time.monotonic() >= self._next_status:
            late = self._overruns - self._overruns_reported
            self._overruns_reported = self._overruns
            text = (
                f'sample rate not held: {late} ticks came more than half a period '
                f'({0.5e-6 * self._dt_ns:g} ms) late in the last second; lower the rate or '
                'compose the nodes (run_scenario --layout single)'
            )
            self.get_logger().warning(text)
            self._publish_status(force=True, message=text, level=DiagnosticStatus.WARN)
        now_ns = time.time_ns()
        for axis, c in self.table.by_axis.items():
            quiet = (now_ns - c.stamp) * 1e-9 if c.stamp >= 0 else math.inf
            if quiet >= self._report_time() and axis not in self._reported_missing:
                self._reported_missing.add(axis)
                self._report_axis(axis, DiagnosticStatus.WARN, self._missing_text(axis, None))
            elif quiet < self._report_time() and axis in self._reported_missing:
                self._reported_missing.discard(axis)

    def _report_time(self) -> float:
        return self.params.values['command_report_time']

    def _missing_text(self, axis: str, now: float | None) -> str:
        topic = topics.joint_command(axis)
        owner = self.owners[axis] or 'its controller'
        if now is not None:
            waited = self._lockstep.waited(now)
            return f'no command for step {self._k} on {topic} from {owner} for {waited:.1f} s'
        return f'no fresh command on {topic} from {owner}'

    def _timeout_message(self) -> str:
        parts = []
        for axis in self.table.missing(self._k * self._dt_ns):
            topic = topics.joint_command(axis)
            nodes = sorted({i.node_name for i in self.get_publishers_info_by_topic(topic)})
            who = f'from {", ".join(nodes)}' if nodes else 'and no node publishes it'
            parts.append(f'{topic} ({who})')
        t = seconds(self._k * self._dt_ns)
        return (
            f'lockstep timeout: no command for t = {t:.3f} s (step {self._k}) after '
            f'{self.params.values["lockstep_timeout"]:g} s on ' + ', '.join(parts)
        )

    def _check_owners(self) -> None:
        """Publishers on a command or state topic other than its owner: say so, by name."""
        if self.ownership is not None:
            for topic, who in self.ownership.look():
                self._foreign_named(topic, who)

    def _report_axis(self, axis: str, level: bytes, message: str) -> None:
        # rclpy wants one severity per call site: one call each.
        if level == DiagnosticStatus.OK:
            self.get_logger().info(f'axis {axis}: {message}')
        elif level == DiagnosticStatus.WARN:
            self.get_logger().warning(f'axis {axis}: {message}')
        else:
            self.get_logger().error(f'axis {axis}: {message}')
        status = diagnostic_status(
            level, AXIS_STATUS.format(axis), message, self._machine(), {'step': self._k}
        )
        self._diag_pub.publish(diagnostics_of(self._stamp_now(), [status]))

    def _machine(self) -> str:
        """hardware_id of our statuses: the machine's namespace."""
        return topics.machine_id(self.get_namespace())

    def _stamp_now(self) -> int:
        if self.timing == 'lockstep':
            return self._k * self._dt_ns
        return time.time_ns()

    def _publish_status(
        self, force: bool = False, message: str | None = None, level: bytes | None = None
    ) -> None:
        """The drive's status; `message` (a fault, ERROR unless `level` says otherwise) is
        published at once, the running status once a second."""
        now = time.monotonic()
        if not force and now < self._next_status:
            return
        self._next_status = now + 1.0
        steps = max(self._k, 1)
        values: dict[str, object] = {
            'step': self._k,
            'time': seconds(self._k * self._dt_ns),
            'wall_s': now - self._wall_start,
            'active': self.active,
            'dropped': self._drops.total,
        }
        if self.timing == 'lockstep':
            values['mean_wait_ms'] = 1e3 * self._wait_sum / steps
            values['max_wait_ms'] = 1e3 * self._wait_max
        given, level = level, DiagnosticStatus.OK
        for axis in self.axes:
            values[f'{axis}.faults'] = self._faults[axis]
            values[f'{axis}.saturations'] = self._saturations[axis]
            values[f'{axis}.invalid_commands'] = self._nonfinite[axis]
            if self.timing == 'realtime':
                values['overruns'] = self._overruns
                values['active_ticks'] = self._active_ticks
                values[f'{axis}.late_fraction'] = self.table.late_fraction(axis)
                values[f'{axis}.longest_late_run'] = self.table.longest_late_run(axis)
                for key, v in self.table.latency_stats(axis).items():
                    values[f'{axis}.latency_{key}_ms'] = 1e3 * v
        faults = self.backend.faults() if self.backend is not None else {}
        for axis, text in faults.items():
            values[f'{axis}.fault'] = text
            level = DiagnosticStatus.ERROR
        name = LOCKSTEP_STATUS if self.timing == 'lockstep' else REALTIME_STATUS
        if message is not None:
            level = given if given is not None else DiagnosticStatus.ERROR
        statuses = [
            diagnostic_status(
                level,
                name,
                message or ('running' if self.active else 'waiting'),
                self._machine(),
                values,
            )
        ]
        foreign = self.ownership.status(self._machine()) if self.ownership is not None else None
        if foreign is not None:
            statuses.append(foreign)
        self._diag_pub.publish(diagnostics_of(self._stamp_now(), statuses))
