"""States cannot be ratcheted ahead (issue 37 item 3): a publisher writing the plant's name
in frame_id and stamping each state one period ahead of the newest it hears is dropped as
foreign, and the real plant's states are still taken, step by step, in lockstep. Real
rclpy nodes in a private domain: the observer node, a plant, a controller and the rogue."""

from __future__ import annotations

import math
from typing import Any

from mill_common.in_process import Graph

T = 1_000_000  # the sample period [ns] (1 ms, the default)
STEPS = 60


def test_a_ratcheting_state_stream_is_dropped_and_the_plants_is_taken() -> None:
    from mill_common.codec import decode_joint_state
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from mill_observers.observer_node import ObserverNode
    from sensor_msgs.msg import JointState

    with Graph(170, period=0.01) as graph:
        observer = graph.named(ObserverNode, 'x_observer')
        plant, controller, rogue = (graph.node(n) for n in ('plant', 'x_controller', 'rogue'))
        states = plant.create_publisher(JointState, 'mill/x/state', DATA_QOS)
        commands = controller.create_publisher(JointState, 'mill/x/joint_command', DATA_QOS)
        forged = rogue.create_publisher(JointState, 'mill/x/state', DATA_QOS)
        estimated: list[int] = []
        sent: list[int] = []

        def state(ns: int) -> None:
            sent.append(ns)
            states.publish(joint_state_bytes(ns, ('x',), position=(1e-6 * ns / T,), sender='plant'))

        def answer(msg: Any) -> None:  # the controller: a command for each estimate
            ns = from_stamp(msg.header.stamp)
            estimated.append(ns)
            commands.publish(joint_state_bytes(ns, ('x',), effort=(0.0,), sender='x_controller'))

        def next_state(msg: Any) -> None:  # the plant: the next state once answered
            ns = from_stamp(msg.header.stamp)
            if ns + T not in sent and len(set(sent)) < STEPS:
                state(ns + T)

        def ratchet(msg: Any) -> None:  # the rogue: each state one period ahead, as the plant
            ns = from_stamp(msg.header.stamp)
            forged.publish(joint_state_bytes(ns + T, ('x',), position=(1.0,), sender='plant'))

        take = take_serialized
        take(controller, JointState, 'mill/x/estimate', decode_joint_state, answer, DATA_QOS, print)
        take(
            plant,
            JointState,
            'mill/x/joint_command',
            decode_joint_state,
            next_state,
            DATA_QOS,
            print,
        )
        take(rogue, JointState, 'mill/x/state', decode_joint_state, ratchet, DATA_QOS, print)
        graph.spin_until(lambda: all_estimated(estimated, state), 20.0)
        # every step of the plant, in order (a step offered again is answered again)
        assert list(dict.fromkeys(estimated)) == [k * T for k in range(STEPS)]
        topic = 'mill/x/state'
        dropped = observer.guard.drops.counts.get(topic, 0)
        assert dropped >= STEPS // 2  # the rogue's states, one per state it heard
        assert observer.guard.drops.last_reason[topic] == "sent by /rogue, not by its owner 'plant'"


def all_estimated(estimated: list[int], state: Any) -> bool:
    """Every step estimated; if not one yet, the first state offered again (until the
    observer has matched the plant)."""
    if len(set(estimated)) >= STEPS:
        return True
    if not estimated:
        state(0)
    return False


def test_contested_commands_are_taken_as_brakes_and_the_observer_goes_on() -> None:
    # Issue 37 item 2: a second x_controller answering beside the real one. The drive takes
    # their commands as brake requests; the observer refused them outright and stalled (in
    # a whole run, for 10 s, silencing the real controller behind it).
    from mill_common.codec import decode_joint_state
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from mill_observers.observer_node import ObserverNode
    from sensor_msgs.msg import JointState

    with Graph(170, period=0.01) as graph:
        observer = graph.named(ObserverNode, 'x_observer')
        plant, real, copy = (graph.node(n) for n in ('plant', 'x_controller', 'x_controller'))
        states = plant.create_publisher(JointState, 'mill/x/state', DATA_QOS)
        publishers = [
            (c.create_publisher(JointState, 'mill/x/joint_command', DATA_QOS), u)
            for c, u in ((real, 0.0), (copy, 10.0))
        ]
        estimated: list[int] = []
        sent: list[int] = []

        def state(ns: int) -> None:
            sent.append(ns)
            states.publish(joint_state_bytes(ns, ('x',), position=(0.0,), sender='plant'))

        def answer(msg: Any) -> None:  # both controllers answer each estimate
            ns = from_stamp(msg.header.stamp)
            estimated.append(ns)
            for pub, u in publishers:
                pub.publish(joint_state_bytes(ns, ('x',), effort=(u,), sender='x_controller'))

        def next_state(msg: Any) -> None:
            ns = from_stamp(msg.header.stamp)
            if ns + T not in sent and len(set(sent)) < STEPS:
                state(ns + T)

        take = take_serialized
        take(real, JointState, 'mill/x/estimate', decode_joint_state, answer, DATA_QOS, print)
        take(
            plant,
            JointState,
            'mill/x/joint_command',
            decode_joint_state,
            next_state,
            DATA_QOS,
            print,
        )
        graph.spin_until(lambda: all_estimated(estimated, state), 20.0)
        # every step estimated, in order: no stall on the contested commands
        assert list(dict.fromkeys(estimated)) == [k * T for k in range(STEPS)]
        topic = 'mill/x/joint_command'
        assert observer.guard.drops.counts.get(topic, 0) >= STEPS // 2  # refused, counted
        assert observer.guard.drops.last_reason[topic].startswith(
            "2 publishers claim to be 'x_controller': /x_controller (gid "
        )
        # taken as brakes: the observer predicted no 10 N·m (the copy's) after the contest
        newest = observer.steps.newest_command
        assert newest is not None and math.isnan(newest)
