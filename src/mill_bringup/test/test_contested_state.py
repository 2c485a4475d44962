"""A contested state does not stall the axis (issue 37): a second "plant" publishing
mill/x/state beside the real one gets both refused by the observer and the controller, and
each of their steps is answered by a brake request (effort NaN, the drive's brake) instead
of being waited on: the observer passes the step without an estimate, the controller answers
it without stepping its law (in a servo cycle the observer hands it the contested step).
Once the copy is gone, finite commands resume. Real rclpy
nodes in a private domain, in this process: the observer and controller nodes (as separate
nodes, and joined in one servo cycle as mill_container joins them), two plants of the same
name and a trajectory."""

from __future__ import annotations

import math
from typing import Any

import pytest
from mill_common.in_process import Graph

T = 1_000_000  # the sample period [ns] (1 ms, the default)
CONTESTED_STEPS = 40
AFTER = 20  # finite commands once the copy is gone


@pytest.mark.parametrize('servo', [False, True], ids=['separate', 'servo_cycle'])
def test_a_contested_state_is_answered_by_brakes_and_the_axis_goes_on(servo: bool) -> None:
    from mill_bringup.container import connect_servo_cycles
    from mill_common.codec import decode_joint_state, encode_joint_trajectory
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from mill_common.signals import AxisReference, ControlInputs, Estimate
    from mill_controllers.axis_controller_node import AxisControllerNode
    from mill_observers.observer_node import ObserverNode
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory

    with Graph(150, period=0.01) as graph:
        controller = graph.named(AxisControllerNode, 'x_controller')
        observer = graph.named(ObserverNode, 'x_observer')
        if servo:
            connect_servo_cycles([observer, controller])
            assert observer.servo is not None
            # What the in-process bus's mute does (mill_container enables the bus): the
            # controller takes no state or estimate of its own, only those handed over.
            for slot in ('position', 'estimate'):
                controller._inputs[slot].destroy()
        plant, copy, trajectory = (graph.node(n) for n in ('plant', 'plant', 'trajectory'))
        publishers = [
            p.create_publisher(JointState, 'mill/x/state', DATA_QOS) for p in (plant, copy)
        ]
        reference = trajectory.create_publisher(JointTrajectory, 'mill/reference', DATA_QOS)
        points = [([0.0], [0.0], [0.0], [], k * T) for k in range(400)]
        path = encode_joint_trajectory(0, 'trajectory', ('x',), points)
        commands: dict[int, float] = {}
        estimates: dict[int, float] = {}
        sent: list[int] = []

        def state(ns: int) -> None:  # both plants send each state
            sent.append(ns)
            # effort 0: the drive says it has not stopped the axis
            msg = joint_state_bytes(ns, ('x',), position=(0.0,), effort=(0.0,), sender='plant')
            for pub in publishers:
                pub.publish(msg)

        def command(msg: Any) -> None:  # the real plant: the next state once answered
            ns = from_stamp(msg.header.stamp)
            commands.setdefault(ns, msg.effort[0])
            if ns + T not in sent:
                state(ns + T)

        def estimated(msg: Any) -> None:
            estimates.setdefault(from_stamp(msg.header.stamp), msg.position[0])

        take = take_serialized
        take(
            plant, JointState, 'mill/x/joint_command', decode_joint_state, command, DATA_QOS, print
        )
        take(
            trajectory,
            JointState,
            'mill/x/estimate',
            decode_joint_state,
            estimated,
            DATA_QOS,
            print,
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
                elif not commands:
                    state(0)  # offered again until the nodes have matched the plant
                return False

            graph.spin_until(answered, 20.0)

        run(CONTESTED_STEPS)
        # every step answered, in order: no stall on the contested states
        assert sorted(commands) == [k * T for k in range(CONTESTED_STEPS)]
        braked = [ns for ns, u in commands.items() if math.isnan(u)]
        assert len(braked) >= CONTESTED_STEPS // 2
        assert math.isnan(commands[(CONTESTED_STEPS - 1) * T])  # still contested
        topic = 'mill/x/state'
        for node in (observer,) if servo else (controller, observer):  # those that took them
            assert node.guard.drops.counts.get(topic, 0) >= len(braked)
            assert node.guard.drops.last_reason[topic].startswith(
                "2 publishers claim to be 'plant': /plant (gid "
            )
        assert not set(braked) & set(estimates)  # no estimate of a state nobody owns
        assert controller.loop.last_ns < min(braked)  # the law saw none of the braked steps

        # the copy goes: finite commands again, and only those, once they resume
        publishers.pop()
        graph.remove(copy)
        graph.spin_until(
            lambda: all(n.count_publishers(topic) <= 1 for n in (controller, observer)), 20.0
        )
        for node in (controller, observer):
            node._graph.look()  # what its once-a-second timer does: the copy is gone
        run(CONTESTED_STEPS, finite=AFTER)
        assert sorted(commands) == [k * T for k in range(len(commands))]  # none skipped
        after = [commands[ns] for ns in sorted(commands) if ns >= CONTESTED_STEPS * T]
        first = next(i for i, u in enumerate(after) if math.isfinite(u))
        assert all(math.isfinite(u) for u in after[first:])  # braked no more
        assert len(after) - first == AFTER
        assert not controller.loop.trip.tripped
        again = [ns for ns in estimates if ns > max(braked)]
        assert len(again) >= AFTER // 2  # estimated again ...
        assert all(estimates[ns] == 0.0 for ns in again)  # ... at the measured position
        rest = ControlInputs(0.0, 0.0, AxisReference(1e-3, 0.0, 0.0), Estimate(0.0, 0.0, 0.0))
        assert math.isfinite(controller.loop.law.compute(rest))
