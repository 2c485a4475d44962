"""A realtime job starts only once every axis is commanded; until then the axes are held.

Started by hand: a realtime drive of x, the trajectory and the observer of x; the test
process is x's controller (a reader of the reference) that does not command at first. The
trajectory must hold x where it stands, say `waiting` and name the silent command topic,
and start the job only after the first command (at a point of the hold's grid).
"""

from __future__ import annotations

import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.ros import DATA_QOS, from_stamp, joint_state
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from test.conftest import ros_node

# Timing under load is what it checks: alone on the machine (scripts/test.sh, serial).
pytestmark = pytest.mark.serial

JOB = 'trajectory: job'
STATE = topics.state('x')
COMMAND = topics.joint_command('x')
T_NS = 1_000_000  # sample_period of the scenario file


def node_args(node: str, **values: str) -> list[str]:
    """-p NODE:NAME:=VALUE (a plain -p loses to the scenario file's entry for the node)."""
    return [a for name, value in values.items() for a in ('-p', f'{node}:{name}:={value}')]


def values(status: DiagnosticStatus) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}


def spin_until(executor: SingleThreadedExecutor, predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not predicate():
        executor.spin_once(timeout_sec=0.05)
    return predicate()


@pytest.mark.system
def test_the_job_holds_the_axes_and_names_the_silent_controller_until_it_commands(
    start_node,
) -> None:
    plant = start_node(
        'mill_plant.plant_node',
        'plant',
        *node_args('plant', axes='["x"]', min_subscribers='2', cutting_model='none'),
        *node_args('plant', timing='realtime'),
    )
    others = [
        start_node(
            'mill_trajectory.trajectory_node',
            'trajectory',
            *node_args('trajectory', timing='realtime', axes='["x"]'),
        ),
        start_node(
            'mill_observers.observer_node',
            'x_observer',
            *node_args('x_observer', timing='realtime'),
        ),
    ]
    jobs: list[DiagnosticStatus] = []
    positions: list[float] = []  # of x, as the drive reports them
    held: list[float] = []  # x of every reference point before the job started
    held_stamps: list[int] = []
    commanding = [False]
    first_command: list[int] = []
    with ros_node('x_controller') as (node, executor):  # the owner the drive expects
        pub = node.create_publisher(JointState, COMMAND, DATA_QOS)

        def on_state(msg: JointState) -> None:
            positions.append(msg.position[0])
            if commanding[0]:  # no torque: the axis stays where it is
                ns = from_stamp(msg.header.stamp)
                first_command[:] = first_command or [ns]
                pub.publish(joint_state(ns, ('x',), effort=(0.0,), sender='x_controller'))

        def on_reference(msg: JointTrajectory) -> None:
            if not any('start_stamp_ns' in values(s) for s in jobs):
                held.extend(p.positions[msg.joint_names.index('x')] for p in msg.points)
                held_stamps.append(from_stamp(msg.header.stamp))

        def on_diagnostics(msg: DiagnosticArray) -> None:
            jobs.extend(s for s in msg.status if s.name == JOB)

        node.create_subscription(JointState, STATE, on_state, DATA_QOS)
        node.create_subscription(JointTrajectory, topics.REFERENCE, on_reference, DATA_QOS)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 10)

        def waiting() -> list[DiagnosticStatus]:
            return [s for s in jobs if values(s).get('state') == 'waiting']

        # Discovery may take a minute on a loaded machine; then the hold says so each second.
        # This node's own subscriptions match in any order (in CI once, the drive's states
        # reached it only after three statuses had): wait for all three.
        assert spin_until(executor, lambda: len(waiting()) >= 3 and held and positions, 120), (
            [(s.message, values(s)) for s in jobs],
            (len(held), len(positions)),
            [n.alive() for n in (plant, *others)],
        )
        for status in waiting():
            assert status.message == f'holding the axes: no command yet on {COMMAND}'
            assert 'start_stamp_ns' not in values(status)
        assert held and positions
        assert max(abs(x - positions[-1]) for x in held) < 1e-12, (min(held), max(held))

        commanding[0] = True

        def started() -> bool:
            return any('start_stamp_ns' in values(s) for s in jobs)

        assert spin_until(executor, started, 30), [s.message for s in jobs[-3:]]
        assert all(n.alive() for n in (plant, *others))
    start = int(next(values(s)['start_stamp_ns'] for s in jobs if 'start_stamp_ns' in values(s)))
    # On the hold's grid (its points are replaced stamp for stamp), and not before the first
    # command could have been seen (one period).
    assert {t % T_NS for t in held_stamps} == {start % T_NS}, (held_stamps[:3], start)
    assert start >= first_command[0] - T_NS, (start, first_command[0])
