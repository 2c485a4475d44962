"""What the recorder tests share: nodes in a context of their own."""

from __future__ import annotations

import pytest


@pytest.fixture
def node_in(monkeypatch: pytest.MonkeyPatch):
    import rclpy
    from rclpy.node import Node

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    context = rclpy.Context()
    rclpy.init(context=context)
    nodes = []

    def make(namespace: str, remap: str = '') -> Node:
        args = ['--ros-args', '-r', remap] if remap else None
        nodes.append(Node('rec', namespace=namespace, context=context, cli_args=args))
        return nodes[-1]

    yield make
    for n in nodes:
        n.destroy_node()
    rclpy.try_shutdown(context=context)
