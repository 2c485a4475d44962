"""NodeParameters on a real rclpy node (in this process): what it refuses, in which words."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from mill_common.param_sources import key_matches
from mill_common.parameters import ParamSpec, positive

# Whether rcl (Jazzy) gives the entry KEY to node /x_controller and to /ns/x_controller:
# what rcl does, checked below; key_matches must agree.
RCL_KEY_MATCHES = [
    ('/**', True, True),
    ('**', True, True),
    ('/**/*', True, True),
    ('/**/x_controller', True, True),
    ('/*', True, False),
    ('*', True, False),
    ('x_controller', True, False),
    ('/x_controller', True, False),
    ('/*/x_controller', False, True),
    ('/*/*', False, True),
    ('/ns/x_controller', False, True),
    ('ns/x_controller', False, True),
    ('/ns/*', False, True),
    ('/ns/**', False, True),
    ('/**/ns/x_controller', False, True),
    ('/ns/**/x_controller', False, True),
    ('/**/y', False, False),
    ('/ns', False, False),
    ('/other/x_controller', False, False),
]

SPECS = [('pd.omega_c', ParamSpec('pd.omega_c', 12.0, 'bandwidth [rad/s]', positive))]


@pytest.fixture
def start(monkeypatch: pytest.MonkeyPatch) -> Iterator:
    """start(name, namespace, *ros_args) -> rclpy node, in a context of its own."""
    import rclpy
    from rclpy.node import Node

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(101 + os.getpid() % 19))
    contexts = []
    nodes: list[Node] = []

    def make(name: str, namespace: str, *ros_args: str) -> Node:
        context = rclpy.Context()
        rclpy.init(args=['test', '--ros-args', *ros_args], context=context)
        contexts.append(context)
        nodes.append(Node(name, namespace=namespace, context=context))
        return nodes[-1]

    yield make
    for n in nodes:
        n.destroy_node()
    for c in contexts:
        rclpy.try_shutdown(context=c)


@pytest.fixture
def command_line(monkeypatch: pytest.MonkeyPatch) -> Iterator:
    """command_line(argv, process_nodes): what run_nodes tells NodeParameters."""
    from mill_common import ros_params

    def set_it(argv: list[str], process_nodes: tuple[str, ...] = ()) -> None:
        monkeypatch.setattr(ros_params, 'command_line', argv)
        monkeypatch.setattr(ros_params, 'process_nodes', process_nodes)

    yield set_it


@pytest.mark.parametrize(('key', 'root', 'inside'), RCL_KEY_MATCHES)
def test_key_matches_agrees_with_rcl(start, tmp_path: Path, key: str, root, inside) -> None:
    f = tmp_path / 'p.yaml'
    f.write_text(f'"{key}":\n  ros__parameters:\n    a: 1\n')
    for namespace in ('/', '/ns'):
        node = start('x_controller', namespace, '--params-file', str(f))
        given = 'a' in node._parameter_overrides
        assert given is (root if namespace == '/' else inside), namespace
        assert key_matches(key, node.get_fully_qualified_name()) is given, namespace


def test_a_change_of_an_undeclared_name_names_it(start, command_line) -> None:
    from mill_common.ros_params import NodeParameters
    from rclpy.exceptions import ParameterNotDeclaredException
    from rclpy.parameter import Parameter

    command_line([])
    node = start('x_controller', '/')
    NodeParameters(node, SPECS, lambda values: None)
    with pytest.raises(ParameterNotDeclaredException) as info:
        node.set_parameters_atomically([Parameter('pd.omega', value=20.0)])
    # what `ros2 param set` shows as the reason (rclpy's parameter service: str(exception))
    assert str(info.value) == (
        'unknown parameter pd.omega=20.0 (did you mean pd.omega_c?): '
        '/x_controller has no such parameter'
    )
    assert node.set_parameters_atomically([Parameter('pd.omega_c', value=20.0)]).successful


def test_a_params_file_with_nothing_for_the_node_is_refused(
    start, command_line, tmp_path: Path
) -> None:
    from mill_common.ros_params import NodeParameters

    f = tmp_path / 'p.yaml'
    f.write_text('y_controller:\n  ros__parameters:\n    pd.omega_c: 20.0\n')
    args = ['--params-file', str(f)]
    command_line(['x', '--ros-args', *args])
    node = start('x_controller', '/', *args)
    with pytest.raises(ValueError) as info:
        NodeParameters(node, SPECS, lambda values: None)
    assert str(info.value) == (
        f'--params-file {f}: nothing in it is for /x_controller (its entries: /y_controller)'
    )
    # In a container with y_controller the file is for the process: each node takes its own.
    command_line(['x', '--ros-args', *args], ('x_controller', 'y_controller'))
    node = start('x_controller', '/', *args)
    assert NodeParameters(node, SPECS, lambda values: None).values == {'pd.omega_c': 12.0}


def _get_all_parameters(node) -> dict[str, object]:
    """Every listed name of `node` through its own ListParameters and GetParameters
    services, as `ros2 param dump` asks: name -> value (None where no value came back)."""
    from rcl_interfaces.srv import GetParameters, ListParameters
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import parameter_value_to_python

    context = node.context
    probe = Node('probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(probe)
    try:
        base = node.get_fully_qualified_name()

        def call(kind, suffix, request):
            client = probe.create_client(kind, f'{base}/{suffix}')
            assert client.wait_for_service(timeout_sec=10), suffix
            future = client.call_async(request)
            executor.spin_until_future_complete(future, timeout_sec=10)
            assert future.done(), suffix
            return future.result()

        names = list(call(ListParameters, 'list_parameters', ListParameters.Request()).result.names)
        values = call(GetParameters, 'get_parameters', GetParameters.Request(names=names)).values
        got = [parameter_value_to_python(v) for v in values]
        return dict(zip(names, got + [None] * (len(names) - len(got)), strict=True))
    finally:
        executor.remove_node(node)
        executor.shutdown()
        probe.destroy_node()


def test_get_parameters_answers_every_name_also_an_empty_list(start, command_line) -> None:
    # rclpy answers a GetParameters request with no value at all when one name is unset:
    # `ros2 param dump` showed `ros__parameters: {}` for every node with an empty list.
    from mill_common.node_params import realtime_specs
    from mill_common.parameters import StringList, number_list
    from mill_common.ros_params import NodeParameters
    from rcl_interfaces.msg import ParameterType
    from rclpy.parameter import Parameter

    command_line([])
    specs = [
        *SPECS,
        *realtime_specs(),  # cpu_affinity: [] and read-only
        ('topics', ParamSpec('topics', [], 'topics', StringList('topic names'))),
        ('gains', ParamSpec('gains', [], 'gains', number_list())),
    ]
    node = start('x_controller', '/')
    params = NodeParameters(node, specs, lambda values: None)
    got = _get_all_parameters(node)
    assert set(got) >= {'pd.omega_c', 'cpu_affinity', 'topics', 'gains', 'use_sim_time'}
    assert {n: v for n, v in got.items() if v is None} == {}
    assert got['pd.omega_c'] == 12.0 and got['realtime_priority'] == 0
    assert got['cpu_affinity'] == [] and got['topics'] == [] and got['gains'] == []
    # typed as declared, read-only as declared
    types = {n: node.get_parameter(n).type_ for n in ('cpu_affinity', 'topics', 'gains')}
    assert types == {
        'cpu_affinity': Parameter.Type.INTEGER_ARRAY,
        'topics': Parameter.Type.STRING_ARRAY,
        'gains': Parameter.Type.DOUBLE_ARRAY,
    }
    assert node.describe_parameter('cpu_affinity').read_only
    assert node.describe_parameter('cpu_affinity').type == ParameterType.PARAMETER_INTEGER_ARRAY
    assert not node.set_parameters([Parameter('cpu_affinity', value=[0])])[0].successful
    assert node.set_parameters([Parameter('topics', value=['/a'])])[0].successful
    assert params.values['topics'] == ['/a'] and params.values['cpu_affinity'] == []
