"""An impostor of the x controller moves nothing (issue 37 item 1, issue 34 item 3).

A lockstep slotting job runs while a node of this test, `rogue`, answers every x state it
hears with 10 N·m, `x_controller` written in its frame_id and the state's stamp (the attack
of issue 37, under which x went from −0.075 m to +1.822 m). The drive identifies commands
by their publisher GID: the rogue's are dropped, the run equals the offline simulator's
exactly (what the real controller alone makes), and the summary names the attacker.
"""

from __future__ import annotations

import json
import threading

import pytest

from test.conftest import start_scenario


@pytest.mark.system
def test_a_rogue_with_the_owners_frame_id_moves_nothing_and_is_named(ros_env, tmp_path) -> None:
    import rclpy
    from mill_common.codec import decode_joint_state
    from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState

    out = tmp_path / 'run'
    context = rclpy.Context()
    rclpy.init(args=[], context=context, domain_id=int(ros_env['ROS_DOMAIN_ID']))
    rogue = Node('rogue', context=context)
    pub = rogue.create_publisher(JointState, 'mill/x/joint_command', DATA_QOS)
    sent = [0]

    def answer(msg: object) -> None:
        ns = from_stamp(msg.header.stamp)  # type: ignore[attr-defined]
        pub.publish(joint_state_bytes(ns, ('x',), effort=(10.0,), sender='x_controller'))
        sent[0] += 1

    take_serialized(rogue, JointState, 'mill/x/state', decode_joint_state, answer, DATA_QOS, print)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(rogue)
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    try:
        proc = start_scenario(
            ros_env,
            *('slotting', '--layout', 'processes', '--duration', '2', '--compare-offline'),
            *('--output', str(out)),
        )
        stdout, stderr = proc.communicate(timeout=600)
    finally:
        stop.set()
        spinner.join(timeout=5)
        executor.shutdown()
        rogue.destroy_node()
        rclpy.try_shutdown(context=context)
    text = stdout + stderr
    assert (out / 'summary.json').exists(), text[-3000:]
    summary = json.loads((out / 'summary.json').read_text())
    assert sent[0] > 100, text[-3000:]  # it did answer the states, all along the job
    assert summary['events'] == [], text[-3000:]  # no trip, no brake, no stop
    # The machine moved exactly as the offline simulator, without any rogue, computes.
    assert summary['offline_max_difference'] == 0.0, text[-3000:]
    # named by the drive (by the graph, or by a message: '/rogue (frame_id 'x_controller')')
    named = ' '.join(summary['foreign_publishers'])
    assert 'rogue' in named and 'mill/x/joint_command' in named, summary['foreign_publishers']
    # and left out of the runner's record and bag by its publisher GID
    assert any('from /rogue (by its publisher GID' in p for p in summary['problems'])
    assert proc.returncode == 3, text[-3000:]  # a good job, its record not intact
