"""A contested estimate does not stall the controller (issue 37): a second x_observer
publishing estimates beside the real one gets both refused, and the controller answers each
of their steps with a brake request (effort NaN, which the drive takes as one) instead of
waiting for an estimate that never comes, without feeding anything into its law; once the
copy is gone, finite commands resume. Real rclpy nodes in a private domain, in this
process: the controller node, a plant, a trajectory and two observers of the same name."""

from __future__ import annotations

import math
from typing import Any

from mill_common.in_process import Graph

T = 1_000_000  # the sample period [ns] (1 ms, the default)
CONTESTED_STEPS = 40
AFTER = 20  # steps answered once the copy is gone


def test_a_contested_estimate_is_answered_by_brakes_and_the_controller_goes_on() -> None:
    from mill_common.codec import decode_joint_state, encode_joint_trajectory
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from mill_common.signals import AxisReference, ControlInputs, Estimate
    from mill_controllers.axis_controller_node import AxisControllerNode
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory

    with Graph(190, period=0.01) as graph:
        controller = graph.named(AxisControllerNode, 'x_controller')
        plant, trajectory, real, copy = (
            graph.node(n) for n in ('plant', 'trajectory', 'x_observer', 'x_observer')
        )
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

        def resumed() -> int:
            """Finite commands answering steps after the contested ones."""
            return sum(math.isfinite(u) for ns, u in commands.items() if ns >= CONTESTED_STEPS * T)

        def run(until: int, finite: int = 0) -> None:
            def answered() -> bool:
                if len(commands) >= until and resumed() >= finite:
                    return True
                if controller._join.references.newest is None:
                    reference.publish(path)  # again until the controller has it
                elif not sent:
                    state(0)
                elif not commands:
                    state(0)  # offered again until the controller has matched the plant
                return False

            graph.spin_until(answered, 20.0)

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
        graph.remove(copy)
        graph.spin_until(lambda: controller.count_publishers(topic) <= 1, 20.0)
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
