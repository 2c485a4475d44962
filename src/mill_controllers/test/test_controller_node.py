"""The axis controller node in this process: what a run-time parameter change does to it.

A trip is cleared by ~/reset_trip alone, not by a write of following_error_limit
(issue 34).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest


@pytest.fixture
def controller(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    """controller(*ros_args) -> an AxisControllerNode `x_controller` in a context of its own."""
    import rclpy
    from mill_controllers.axis_controller_node import AxisControllerNode

    from mill_common import ros_params

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    monkeypatch.setattr(ros_params, 'command_line', [])
    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    nodes: list[Any] = []

    def make(*ros_args: str) -> Any:
        args = ['--ros-args', '-r', '__node:=x_controller', *ros_args]
        nodes.append(AxisControllerNode(context=context, cli_args=args))
        return nodes[-1]

    yield make
    for node in nodes:
        node.destroy_node()
    rclpy.try_shutdown(context=context)


def set_one(node: Any, name: str, value: Any) -> Any:
    """The result of setting one parameter, as `ros2 param set` gets it."""
    from rclpy.parameter import Parameter

    (result,) = node.set_parameters([Parameter(name, value=value)])
    return result


def test_a_trip_is_cleared_by_reset_trip_alone(controller) -> None:
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_srvs.srv import Trigger

    node = controller('-p', 'following_error_limit:=0.001')
    trip = node.loop.trip
    assert trip.command(0.25, 2e-3, 1.0) != trip.command(0.25, 2e-3, 1.0)  # NaN: braked
    for limit in (0.001, 0.01, float('inf')):  # the value it has, a larger one, none
        assert set_one(node, 'following_error_limit', limit).successful
        assert trip.limit == limit and trip.tripped, limit
    assert set_one(node, 'controller', 'pd').successful and trip.tripped

    probe = Node('operator', context=node.context)
    executor = SingleThreadedExecutor(context=node.context)
    for n in (node, probe):
        executor.add_node(n)
    try:
        client = probe.create_client(Trigger, '/x_controller/reset_trip')
        assert client.wait_for_service(timeout_sec=10)
        answers = []
        for _ in range(2):
            future = client.call_async(Trigger.Request())
            executor.spin_until_future_complete(future, timeout_sec=10)
            answers.append(future.result().message)
    finally:
        executor.shutdown()
        probe.destroy_node()
    assert answers == ['trip cleared', 'no trip to clear']
    assert not trip.tripped and trip.command(0.3, 1.0, 2.0) == 2.0  # limit inf: no trip
