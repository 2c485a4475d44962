"""A ros2_control stack drives the simulated machine over topic_based_ros2_control's topic
pair (issue 34 item 6; docs/hardware-driver.md, "ros2_control"): the real plant node in
realtime with `ros2_control.commands_topic`, and a real rclpy node in a private domain that
does what the TopicBasedSystem hardware interface does at each cycle of the controller
manager: read the newest JointState of the states topic, write one JointState of efforts for
x, y, z, stamped with its clock's now and no frame_id, from a node named
topic_based_ros2_control_<block name>. The effort law here is a PID position loop per joint, what a
ros2_control effort controller would close."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from mill_common.in_process import Graph

COMMANDS = 'robot_joint_commands'
STATES = 'robot_joint_states'
OWNER = 'topic_based_ros2_control_mill'
AXES = ('x', 'y', 'z')
# A PID per joint for the plant's b ≈ 21-28 m/s² per N·m: about 12 rad/s, critically damped
# (slow enough for the 10-50 ms this one test process's executor takes to answer a state on a
# loaded machine), the integral against the guides' friction [N·m/m], [N·m/(m·s)],
# [N·m·s/m], [N·m].
KP, KI, KD, LIMIT = 7.0, 15.0, 1.1, 0.2


class Side:
    """The hardware interface's node: its states in, its commands out."""

    def __init__(self, graph: Graph, name: str) -> None:
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import JointState

        self.node = graph.node(name)
        # As TopicBasedSystem makes them: commands QoS(1), states SensorDataQoS.
        self.pub = self.node.create_publisher(JointState, COMMANDS, 1)
        self.node.create_subscription(JointState, STATES, self._on_state, qos_profile_sensor_data)
        self.latest: Any = None
        self.history: list[Any] = []
        self.states = 0
        self.law: Callable[[Any], list[float]] | None = None  # None: silent
        self.sent: list[float] = []

    def _on_state(self, msg: Any) -> None:
        self.latest, self.states = msg, self.states + 1
        self.history.append(msg)
        if self.law is not None:  # read(), update(), write()
            self.send(effort=self.law(msg))

    def send(self, names: tuple[str, ...] = AXES, **fields: list[float]) -> None:
        from sensor_msgs.msg import JointState

        msg = JointState()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.name = list(names)
        for field, values in fields.items():
            setattr(msg, field, [float(v) for v in values])
        if 'effort' in fields:
            self.sent = list(fields['effort'])
        self.pub.publish(msg)

    def position(self, axis: str) -> float:
        return float(self.latest.position[list(self.latest.name).index(axis)])


class Pair(Graph):
    """The plant node with the pair's commands topic, and what /diagnostics said."""

    drive: Any = None
    said: list[str]

    def side(self, name: str = OWNER) -> Side:
        return Side(self, name)


@pytest.fixture
def pair() -> Iterator[Pair]:
    from diagnostic_msgs.msg import DiagnosticArray
    from mill_plant.plant_node import make_node
    from rclpy.parameter import Parameter

    with Pair(185, period=0.02) as pair:
        pair.drive = pair.add(
            make_node(
                context=pair.context,
                parameter_overrides=[
                    Parameter('timing', value='realtime'),
                    Parameter('sample_period', value=0.005),
                    Parameter('cutting_model', value='none'),  # air: a jog, no workpiece
                    Parameter('ros2_control.commands_topic', value=COMMANDS),
                ],
            )
        )
        pair.said = []
        pair.node('listener').create_subscription(
            DiagnosticArray,
            '/diagnostics',
            lambda m: pair.said.extend(s.message for s in m.status),
            10,
        )
        yield pair


def pid_to(targets: dict[str, float]) -> Callable[[Any], list[float]]:
    """A PID position loop on each joint towards `targets`, from the states it reads (what
    a ros2_control effort controller closes), its integral over the states' stamps."""
    integral = dict.fromkeys(AXES, 0.0)
    last: list[float] = []

    def law(msg: Any) -> list[float]:
        t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        dt = min(t - last[0], 0.01) if last else 0.0
        last[:] = [t]
        out = []
        for axis in AXES:
            i = list(msg.name).index(axis)
            v = msg.velocity[i] if math.isfinite(msg.velocity[i]) else 0.0
            e = targets[axis] - msg.position[i]
            integral[axis] += e * dt
            u = KP * e + KI * integral[axis] - KD * v
            out.append(max(-LIMIT, min(LIMIT, u)))
        return out

    return law


def near(msg: Any, targets: dict[str, float], within: float) -> bool:
    """Every axis within `within` of its target in the state msg, and slow (< 1 mm/s)."""
    return all(
        abs(msg.position[i] - targets[a]) < within and abs(msg.velocity[i]) < 1e-3
        for i, a in enumerate(msg.name)
    )


def settle(pair: Any, side: Any, targets: dict[str, float], within: float) -> bool:
    """Every axis near its target in 60 states in a row (0.3 s; not an overshoot's crossing)."""

    def settled() -> bool:
        last = side.history[-60:]
        return len(last) == 60 and all(near(m, targets, within) for m in last)

    return pair.spin_until(settled, timeout=8.0)


def test_a_ros2_control_effort_loop_moves_every_axis_where_it_commands(pair) -> None:
    side = pair.side()
    assert pair.spin_until(lambda: side.states >= 5)
    assert list(side.latest.name) == list(AXES)
    start = {a: side.position(a) for a in AXES}
    targets = {'x': start['x'] + 0.0005, 'y': start['y'] - 0.0005, 'z': start['z'] + 0.0003}
    side.law = pid_to(targets)
    assert settle(pair, side, targets, 2e-5)
    drive = pair.drive
    for axis in AXES:
        assert abs(side.position(axis) - targets[axis]) < 2e-5
        assert drive.table.by_axis[axis].stamp > 0  # taken from the pair, per axis
        assert not drive.table.by_axis[axis].stopped
    # The states carry what the drive applied: the efforts the side sent a period before.
    assert all(math.isfinite(u) for u in side.latest.effort)
    assert drive.intake.invalid_commands == dict.fromkeys(AXES, 0)
    assert not drive.ownership.foreign


def test_a_position_command_is_refused_in_one_line_and_a_foreign_node_moves_nothing(
    pair,
) -> None:
    side = pair.side()
    assert pair.spin_until(lambda: side.states >= 5)
    targets = {a: side.position(a) for a in AXES}
    side.law = pid_to(targets)  # the owner holds every axis where it stands
    assert settle(pair, side, targets, 2e-5)
    # The owner sends a position command (a block with command_interface "position").
    drops = pair.drive.reports.drops
    side.send(position=[targets[a] + 0.01 for a in AXES])
    assert pair.spin_until(lambda: drops.counts.get(COMMANDS, 0) == 1)
    assert drops.last_reason[COMMANDS].startswith('position commands refused: the drive takes')
    assert pair.spin_until(lambda: any('position commands refused' in m for m in pair.said))
    said = [m for m in pair.said if 'position commands refused' in m]
    assert len(said) == 1 and '\n' not in said[0]
    assert said[0].startswith(f'dropped a message on {COMMANDS} from /{OWNER}')
    pair.spin(0.2)
    assert near(side.latest, targets, 2e-5)  # held by its efforts; the position moved nothing
    # A node of another name on the commands topic: full effort at every state.
    rogue = pair.side('rogue')
    rogue.law = lambda msg: [LIMIT, LIMIT, LIMIT]
    own = pair.drive.ownership
    assert pair.spin_until(lambda: own.foreign_messages >= 50)
    assert {n for n in own.foreign[COMMANDS] if n != 'rogue'} == {"/rogue (frame_id '')"}
    assert drops.last_reason[COMMANDS] == (f"sent by /rogue, not by its owner '{OWNER}'")
    pair.spin(0.3)
    assert near(side.latest, targets, 2e-5)  # held by its owner, the rogue unheard
    assert not any(pair.drive.table.by_axis[a].stopped for a in AXES)


def test_silence_from_ros2_control_brakes_every_axis(pair) -> None:
    side = pair.side()
    assert pair.spin_until(lambda: side.states >= 5)
    targets = {a: side.position(a) for a in AXES}
    side.law = pid_to(targets)
    assert settle(pair, side, targets, 2e-5)
    side.law = None  # the controller manager stops writing
    table = pair.drive.table.by_axis
    assert pair.spin_until(lambda: all(table[a].stopped for a in AXES), timeout=5.0)
    for axis in AXES:
        assert table[axis].stopped.startswith('no fresh command for ')
    count = side.states
    assert pair.spin_until(lambda: side.states > count + 3)
    assert all(math.isnan(u) for u in side.latest.effort)  # the drive says: braked
    assert all(abs(side.position(a) - targets[a]) < 1e-3 for a in AXES)  # within excursion
    assert any(f'on {COMMANDS} (from {OWNER})' in m for m in pair.said)


def test_lockstep_refuses_the_pair_at_configure() -> None:
    from mill_plant.plant_node import make_node
    from rclpy.parameter import Parameter

    with Graph(185) as graph:
        node = graph.add(
            make_node(
                context=graph.context,
                parameter_overrides=[Parameter('ros2_control.commands_topic', value=COMMANDS)],
            )
        )
        assert node.backend is None and node.pair is None  # not configured
