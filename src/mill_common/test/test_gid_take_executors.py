"""The GID take under each executor a node may spin with (mill_common.node_main): every
message once, in order, with its publisher's GID. GidSubscription.execute runs the callback
itself (no coroutine): rclpy's C++ EventsExecutor calls what it returns as a Task, rclpy's
SingleThreadedExecutor awaits it."""

from __future__ import annotations

import os
import struct
import time
from typing import Any

import pytest

TOPIC = '/mill_gid_take_test'
COUNT = 50


@pytest.mark.parametrize('kind', ['events', 'single'])
def test_each_message_once_in_order_with_its_publisher_gid(
    kind: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    import rclpy
    from mill_common.codec import encode_joint_state
    from mill_common.graph_owner import DONE, GidSubscription
    from mill_common.node_main import make_executor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(190 + os.getpid() % 25))
    monkeypatch.setenv('MILL_EXECUTOR', kind)
    rclpy.init(args=[])
    try:
        sender, receiver = Node('gid_take_sender'), Node('gid_take_receiver')
        pub = sender.create_publisher(JointState, TOPIC, 100)
        got: list[tuple[int, bytes]] = []

        def on_message(data: bytes, gid: bytes) -> None:
            got.append((struct.unpack_from('<i', data, 4)[0], gid))

        sub = GidSubscription(receiver, JointState, TOPIC, on_message, 100)
        executor: Any = make_executor()
        executor.add_node(receiver)
        end = time.monotonic() + 10.0
        while sub.get_publisher_count() < 1 and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        for k in range(COUNT):
            pub.publish(encode_joint_state(k * 1_000_000_000, 'gid_take_sender', ('x',), (0.0,)))
        while len(got) < COUNT and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        for _ in range(5):  # nothing more comes: no message twice
            executor.spin_once(timeout_sec=0.02)
        infos = receiver.get_publishers_info_by_topic(TOPIC)
        assert [k for k, _ in got] == list(range(COUNT))  # stamp seconds 0 .. COUNT - 1
        assert {gid for _, gid in got} == {bytes(infos[0].endpoint_gid)}
        assert sub.execute(None) is DONE  # nothing taken: nothing called
        assert len(got) == COUNT
        executor.shutdown()
    finally:
        rclpy.try_shutdown()
