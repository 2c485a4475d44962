"""A contested estimate does not stall the controller (issue 37): a second x_observer
publishing estimates beside the real one gets both refused, and the controller answers each
of their steps with a brake request (effort NaN, which the drive takes as one) instead of
waiting for an estimate that never comes, without feeding anything into its law; once the
copy is gone, finite commands resume. Real rclpy nodes in a private domain, in this
process: the controller node, a plant, a trajectory and two observers of the same name."""

from __future__ import annotations

import math
import os
import time
from typing import Any

import pytest

T = 1_000_000  # the sample period [ns] (1 ms, the default)
CONTESTED_STEPS = 40
AFTER = 20  # steps answered once the copy is gone


def test_a_contested_estimate_is_answered_by_brakes_and_the_controller_goes_on(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import rclpy
    from mill_common.codec import decode_joint_state, encode_joint_trajectory
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from mill_common.signals import AxisReference, ControlInputs, Estimate
    from mill_controllers.axis_controller_node import AxisControllerNode
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory

    from mill_common import ros_params

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(190 + os.getpid() % 25))
    monkeypatch.setattr(ros_params, 'command_line', [])
    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    nodes: list[Any] = []
    try:
        controller = AxisControllerNode(
            context=context, cli_args=['--ros-args', '-r', '__node:=x_controller']
        )
        plant, trajectory, real, copy = (
            Node(n, context=context) for n in ('plant', 'trajectory', 'x_observer', 'x_observer')
        )
        nodes += [controller, plant, trajectory, real, copy]
        states = plant.create_publisher(JointState, 'mill/x/state', DATA_QOS)
        reference = trajectory.create_publisher(JointTrajectory, 'mill/reference', DATA_QOS)
        observers = [
            o.create_publisher(JointState, 'mill/x/estimate', DATA_QOS) for o in (real, copy)
        ]
        points = [([0.0], [0.0], [0.0], [], k * T) for k in range(400)]
        path = encode_joint_trajectory(0, 'trajectory', ('x',), points)
        commands: dict[int, float] = {}
        sent: list[int] = []

        def state(ns: int) -> None:
            sent.append(ns)
            # effort 0: the drive says it has not stopped the axis
            msg = joint_state_bytes(ns, ('x',), position=(0.0,), effort=(0.0,), sender='plant')
            states.publish(msg)

        def estimate(msg: Any) -> None:  # every observer still there answers each state
            ns = from_stamp(msg.header.stamp)
            for pub in observers:
                pub.publish(
                    joint_state_bytes(ns, ('x',), (0.0,), (0.0,), (0.0,), sender='x_observer')
                )

        def command(msg: Any) -> None:  # the plant: the next state once answered
            ns = from_stamp(msg.header.stamp)
            commands.setdefault(ns, msg.effort[0])
            if ns + T not in sent:
                state(ns + T)

        take = take_serialized
        take(real, JointState, 'mill/x/state', decode_joint_state, estimate, DATA_QOS, print)
        take(
            plant, JointState, 'mill/x/joint_command', decode_joint_state, command, DATA_QOS, print
        )
        for node in nodes:
            executor.add_node(node)

        def resumed() -> int:
            """Finite commands answering steps after the contested ones."""
            return sum(math.isfinite(u) for ns, u in commands.items() if ns >= CONTESTED_STEPS * T)

        def run(until: int, finite: int = 0) -> None:
            end = time.monotonic() + 20.0
            while time.monotonic() < end and (len(commands) < until or resumed() < finite):
                if controller._join.references.newest is None:
                    reference.publish(path)  # again until the controller has it
                elif not sent:
                    state(0)
                elif not commands:
                    state(0)  # offered again until the controller has matched the plant
                executor.spin_once(timeout_sec=0.01)

        run(CONTESTED_STEPS)
        # every step answered, in order: no stall on the contested estimates
        assert sorted(commands) == [k * T for k in range(CONTESTED_STEPS)]
        braked = [ns for ns, u in commands.items() if math.isnan(u)]
        assert len(braked) >= CONTESTED_STEPS // 2
        assert math.isnan(commands[(CONTESTED_STEPS - 1) * T])  # still contested
        topic = 'mill/x/estimate'
        assert controller.guard.drops.counts.get(topic, 0) >= len(braked)
        assert controller.guard.drops.last_reason[topic].startswith(
            "2 publishers claim to be 'x_observer': /x_observer (gid "
        )
        stepped = controller.loop.last_ns
        assert stepped < min(braked)  # the law saw none of the braked steps

        # the copy goes: finite commands again, and only those, once they resume
        observers.pop()
        end = time.monotonic() + 20.0
        executor.remove_node(copy)
        copy.destroy_node()
        nodes.remove(copy)
        while controller.count_publishers(topic) > 1 and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
        controller._graph.look()  # what its once-a-second timer does: the copy is gone
        run(CONTESTED_STEPS, finite=AFTER)
        assert sorted(commands) == [k * T for k in range(len(commands))]  # none skipped
        after = [commands[ns] for ns in sorted(commands) if ns >= CONTESTED_STEPS * T]
        first = next(i for i, u in enumerate(after) if math.isfinite(u))
        assert all(math.isfinite(u) for u in after[first:])  # braked no more
        assert len(after) - first == AFTER
        assert not controller.loop.trip.tripped
        # the law is usable: 1 mm behind its reference at rest, it commands a finite effort
        rest = ControlInputs(0.0, 0.0, AxisReference(1e-3, 0.0, 0.0), Estimate(0.0, 0.0, 0.0))
        assert math.isfinite(controller.loop.law.compute(rest))
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
