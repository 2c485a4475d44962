"""The trajectory node's manual commands (issue 34, item 5), from a client of its own.

The trajectory node runs in this process, timing realtime, with a stand-in for the rest of
the graph (x's state, observer and controller: the job starts on them); the operator is a
separate rclpy node in a ROS context of its own, which calls ~/jog, ~/jog_stop, ~/home,
~/set_home, ~/mdi, ~/resume as `ros2 service call` would, and reads where the reference
takes the axes on /mill/reference.
"""

from __future__ import annotations

import os
import random
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
import rclpy

JOB = 0.3  # [s] a dwell where the axes stand: the job
TIMEOUT = 10.0  # [s] for anything to arrive


class Operator:
    """The operator's client: services of the trajectory, and the reference it publishes."""

    def __init__(self, ns: str) -> None:
        from mill_interfaces.srv import Jog, Mdi
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from std_srvs.srv import Trigger
        from trajectory_msgs.msg import JointTrajectory

        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context)
        self.node = Node('operator', namespace=ns, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.types = {'jog': Jog, 'mdi': Mdi}
        self.clients = {
            name: self.node.create_client(self.types.get(name, Trigger), f'trajectory/{name}')
            for name in ('jog', 'jog_stop', 'home', 'set_home', 'mdi', 'resume')
        }
        self.last: Any = None  # the newest reference message
        self.node.create_subscription(JointTrajectory, 'mill/reference', self._heard, 10)

    def _heard(self, msg: Any) -> None:
        self.last = msg

    def call(self, name: str, **request: Any) -> tuple[bool, str]:
        from std_srvs.srv import Trigger

        client = self.clients[name]
        assert client.wait_for_service(timeout_sec=TIMEOUT)
        future = client.call_async(self.types.get(name, Trigger).Request(**request))
        self.executor.spin_until_future_complete(future, timeout_sec=TIMEOUT)
        result = future.result()
        assert result is not None, f'{name}: no answer'
        return bool(result.success), str(result.message)

    def at_rest(self) -> tuple[float, float, float]:
        """Where the reference stands once every point of a message is at rest and the same."""
        end = time.monotonic() + TIMEOUT
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)
            msg = self.last
            if msg is None or not msg.points:
                continue
            first = tuple(msg.points[0].positions[:3])
            still = all(
                tuple(p.positions[:3]) == first and not any(p.velocities[:3]) for p in msg.points
            )
            if still:
                return first  # type: ignore[return-value]
        raise AssertionError('the reference never came to rest')

    def moved(self) -> tuple[float, float, float]:
        """Where the reference comes to rest after a move has begun."""
        end = time.monotonic() + TIMEOUT
        while not (self.last is not None and self._moves(self.last)):
            assert time.monotonic() < end, 'the reference never moved'
            self.executor.spin_once(timeout_sec=0.02)
        return self.at_rest()

    @staticmethod
    def _moves(msg: Any) -> bool:
        return any(any(p.velocities[:3]) for p in msg.points)

    def moving(self) -> bool:
        """Spin until a reference message arrives: whether it moves."""
        self.last = None
        end = time.monotonic() + TIMEOUT
        while self.last is None and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)
        assert self.last is not None
        return self._moves(self.last)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


class StandIn:
    """What the trajectory waits for in realtime before the job starts, for axis x alone:
    its state (at 0), an observer's estimate topic, a controller that reads the reference
    and commands once `go` is set."""

    def __init__(self, context: Any, ns: str) -> None:
        from rclpy.node import Node
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory

        from mill_common import topics

        self.node = Node('x_stand_in', namespace=ns, context=context)
        self.go = False
        self.state = self.node.create_publisher(JointState, topics.state('x'), 10)
        self.node.create_publisher(JointState, topics.estimate('x'), 10)
        self.command = self.node.create_publisher(JointState, topics.joint_command('x'), 10)
        self.node.create_subscription(JointTrajectory, topics.REFERENCE, lambda msg: None, 10)
        self.msg = JointState
        self.node.create_timer(0.02, self._tick)

    def _tick(self) -> None:
        msg = self.msg(name=['x'], position=[0.0], velocity=[0.0], effort=[0.0])
        msg.header.stamp = self.node.get_clock().now().to_msg()
        self.state.publish(msg)
        if self.go:
            self.command.publish(self.msg(name=['x'], effort=[0.0]))


@pytest.fixture
def graph(monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Any, Operator, StandIn]]:
    """The trajectory node (realtime, a JOB s dwell at the origin) spinning in a thread of its
    own beside its stand-in, and the operator."""
    from mill_common.in_process import node_factory
    from mill_trajectory.trajectory_node import TrajectoryNode
    from rclpy.executors import SingleThreadedExecutor

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(random.randint(150, 220)))
    ns = f'/manual{os.getpid()}'  # nothing of another test's graph on the same domain
    with node_factory(TrajectoryNode, 'trajectory') as make:
        node = make(
            *('-p', 'timing:=realtime', '-p', 'axes:=[x]', '-p', 'trajectory:=program'),
            *('-p', f'program.segments:=["dwell {JOB}"]', '-p', 'travel.max:=[0.1, 0.1, 0.05]'),
            *('-r', f'__ns:={ns}'),
        )
        stand_in = StandIn(node.context, ns)
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        executor.add_node(stand_in.node)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()
        op = Operator(ns)
        try:
            yield node, op, stand_in
        finally:
            op.close()
            executor.shutdown()
            thread.join(timeout=5)
            stand_in.node.destroy_node()


def test_jog_home_set_home_and_mdi_between_jobs_and_every_refusal_says_why(
    graph: tuple[Any, Operator, StandIn],
) -> None:
    node, op, stand_in = graph
    # Before the job has started, and while it runs: refused.
    ok, said = op.call('jog', axis='x', distance=0.001)
    assert not ok and said == (
        'the job has not started yet (it starts once every axis controller commands): '
        'wait for it to end'
    )
    stand_in.go = True  # the job starts
    end = time.monotonic() + TIMEOUT
    running = []
    while node.progress.done_at is None and time.monotonic() < end:
        ok, said = op.call('home')
        if said.startswith('a job is running'):
            running.append(said)
        time.sleep(0.02)
    assert node.progress.done_at is not None, 'the job never ended'
    assert running, 'no command during the job'
    assert all(s.endswith(' s of 0.30 s): wait for its end') for s in running), running
    assert op.call('resume') == (False, 'resume: this job has no pause and cannot hold its feed')
    assert op.at_rest() == (0.0, 0.0, 0.0)

    # Jog by increment: 2 mm of x at jog.speed.
    ok, said = op.call('jog', axis='x', distance=0.002)
    assert ok, said
    assert said.startswith('jog x +2.000 mm: to (2.000, 0.000, 0.000) mm in ')
    ok, said = op.call('jog', axis='y', distance=0.001)  # while x moves
    assert not ok and said == 'jog x +2.000 mm is under way: wait for its end or call ~/jog_stop'
    assert op.moved() == pytest.approx((0.002, 0.0, 0.0), abs=1e-12)

    # Refusals, one line each, and nothing moves.
    assert op.call('jog', axis='q', distance=0.001) == (False, "unknown axis 'q': one of x, y, z")
    assert op.call('jog', axis='z', distance=0.06) == (
        False,
        'jog z +60.000 mm would leave the machine travel: z = 0.06 m is above travel.max 0.05 m',
    )
    ok, said = op.call('mdi', line='G1 X5 Y')
    assert not ok and said == 'mdi:1:7: word Y has no number'
    assert op.call('jog_stop') == (
        False,
        'nothing to stop: no jog, home or MDI move is under way',
    )
    assert not op.moving()

    # Continuous jog of y, stopped on the way.
    ok, said = op.call('jog', axis='y', velocity=-0.01)
    assert ok and said.startswith('continuous jog of y at -10.000 mm/s'), said
    time.sleep(0.3)
    assert op.moving()
    ok, said = op.call('jog_stop')
    assert ok and said.endswith('stopping along its path within the limits'), said
    stopped = op.at_rest()
    assert stopped[0] == pytest.approx(0.002, abs=1e-12) and -0.1 < stopped[1] < -0.002

    # Set home here, move away with one MDI line, and go home.
    ok, said = op.call('set_home')
    assert ok and said.startswith('home set to (2.000, '), said
    ok, said = op.call('mdi', line='G91 G1 X-3 Z-2 F600')
    assert ok, said
    assert op.moved() == pytest.approx((-0.001, stopped[1], -0.002), abs=1e-12)
    ok, said = op.call('home')
    assert ok and said.startswith('home to (2.000, '), said
    assert op.moved() == pytest.approx(stopped, abs=1e-12)


def test_a_lockstep_job_refuses_manual_commands_and_says_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from mill_common.in_process import node_factory
    from mill_trajectory.trajectory_node import TrajectoryNode
    from rclpy.executors import SingleThreadedExecutor

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(random.randint(150, 220)))
    ns = f'/lockstep{os.getpid()}'
    with node_factory(TrajectoryNode, 'trajectory') as make:
        node = make('-r', f'__ns:={ns}')  # timing lockstep, the default
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()
        op = Operator(ns)
        try:
            ok, said = op.call('mdi', line='G0 X1')
            both = op.call('jog', axis='x', distance=0.001, velocity=0.01)
        finally:
            op.close()
            executor.shutdown()
            thread.join(timeout=5)
    assert not ok and said == (
        "timing lockstep replays a job on the plant's clock, sample by sample: "
        'manual commands need timing realtime'
    )
    assert both == (
        False,
        'give a distance (by increment) or a velocity (continuous), not both',
    )
