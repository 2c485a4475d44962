"""The monitor's late subscription (mill_bringup.monitor.Monitor, late / late_after)."""

from __future__ import annotations

import os
import time


def test_the_reference_is_read_only_once_every_axis_state_was_heard(monkeypatch) -> None:
    import rclpy
    from mill_bringup.monitor import Monitor
    from mill_common.ros import DATA_QOS, joint_state_bytes
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory

    from mill_common import topics

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # test_node_main's range: its node has no topics, unlike the other unit tests' nodes
    monkeypatch.setenv('ROS_DOMAIN_ID', str(120 + os.getpid() % 30))
    rclpy.init()
    try:
        kept = {
            topics.state('x'): 'sensor_msgs/msg/JointState',
            topics.state('y'): 'sensor_msgs/msg/JointState',
            topics.REFERENCE: 'trajectory_msgs/msg/JointTrajectory',
        }
        monitor = Monitor(
            kept, late={topics.REFERENCE}, late_after=[topics.state('x'), topics.state('y')]
        )
        drive = rclpy.create_node('drive')
        trajectory = rclpy.create_node('trajectory')
        states = {a: drive.create_publisher(JointState, topics.state(a), DATA_QOS) for a in 'xy'}
        reference = trajectory.create_publisher(JointTrajectory, topics.REFERENCE, DATA_QOS)
        executor = SingleThreadedExecutor()
        for node in (monitor, drive, trajectory):
            executor.add_node(node)

        def spin(seconds: float) -> None:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.02)

        def send(axes: str) -> None:
            for axis in axes:
                states[axis].publish(joint_state_bytes(1, (axis,), position=(0.0,)))

        deadline = time.monotonic() + 30
        while monitor.count_subscribers(topics.state('y')) < 1 and time.monotonic() < deadline:
            spin(0.1)
        send('x')  # one axis heard: the reference is not read yet
        spin(1.0)
        assert reference.get_subscription_count() == 0
        send('y')  # every axis heard: it is read from now on
        while reference.get_subscription_count() < 1 and time.monotonic() < deadline:
            spin(0.1)
        assert reference.get_subscription_count() == 1
        for node in (monitor, drive, trajectory):
            node.destroy_node()
    finally:
        rclpy.try_shutdown()
