"""Nodes built in the test's own process, each set of them in a ROS context of its own.

What the in-process node tests of every package share: a private domain on loopback, no
command line of the test runner taken for the node's, one context torn down at the end.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def node_factory(node_class: Any, name: str) -> Iterator[Callable[..., Any]]:
    """make(*ros_args) -> a `node_class` named `name`; every node made is destroyed and the
    context shut down on exit. Sets ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_DOMAIN_ID only
    where unset, in this process."""
    import rclpy

    from mill_common import ros_params

    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    saved = ros_params.command_line
    ros_params.command_line = []
    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    nodes: list[Any] = []

    def make(*ros_args: str) -> Any:
        args = ['--ros-args', '-r', f'__node:={name}', *ros_args]
        nodes.append(node_class(context=context, cli_args=args))
        return nodes[-1]

    try:
        yield make
    finally:
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
        ros_params.command_line = saved


def set_one(node: Any, name: str, value: Any) -> Any:
    """The result of setting one parameter, as `ros2 param set` gets it."""
    from rclpy.parameter import Parameter

    (result,) = node.set_parameters([Parameter(name, value=value)])
    return result
