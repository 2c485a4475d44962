"""Every kind of node answers `ros2 param dump`: its GetParameters service gives a value for
each name its ListParameters lists (in this process, one node of each kind of the catalogue,
built with its defaults as the container builds it)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import pytest
from mill_bringup.catalogue import KINDS, NodeKind


@pytest.fixture
def context(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    import rclpy

    from mill_common import ros_params

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    monkeypatch.setattr(ros_params, 'command_line', [])
    ctx = rclpy.Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def parameter_dump(node: Any) -> dict[str, Any]:
    """name -> value as `ros2 param dump` gets them: ListParameters, then GetParameters for
    every listed name (None: no value came back for that name)."""
    from rcl_interfaces.srv import GetParameters, ListParameters
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import parameter_value_to_python

    probe = Node('param_probe', context=node.context)
    executor = SingleThreadedExecutor(context=node.context)
    for n in (node, probe):
        executor.add_node(n)
    base = node.get_fully_qualified_name()

    def call(kind: Any, service: str, request: Any) -> Any:
        client = probe.create_client(kind, f'{base}/{service}')
        assert client.wait_for_service(timeout_sec=10), service
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=10)
        assert future.done(), f'{service}: no reply'
        return future.result()

    try:
        names = list(call(ListParameters, 'list_parameters', ListParameters.Request()).result.names)
        values = call(GetParameters, 'get_parameters', GetParameters.Request(names=names)).values
    finally:
        executor.shutdown()
        probe.destroy_node()
    got: list[Any] = [parameter_value_to_python(v) for v in values]
    return dict(zip(names, got + [None] * (len(names) - len(got)), strict=True))


@pytest.mark.parametrize('kind', KINDS, ids=[k.executable for k in KINDS])
def test_every_declared_parameter_has_a_value(context: Any, kind: NodeKind) -> None:
    node = kind.build()(context=context)
    try:
        dump = parameter_dump(node)
        declared = {full for full, _spec in kind.parameter_specs()}
        assert declared <= set(dump)
        assert sorted(n for n, v in dump.items() if v is None) == []
        for full, spec in kind.parameter_specs():
            if spec.default == []:
                assert dump[full] == [], full
    finally:
        node.destroy_node()
