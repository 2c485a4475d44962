"""Bad parameters: refused at start-up with one line naming them, refused at run time with a
reason naming them while the node keeps its previous values and keeps running.

Start-up cases pass plain `-p NAME:=VALUE` without the scenario file: a node-specific
entry of a params file (`x_controller: ros__parameters: ...`) takes precedence over a plain
`-p` (rcl stores `-p` under `/**`), so with the scenario file the bad value would not even
reach the node. `-p NODE:NAME:=VALUE` is the form that overrides a file.
"""

from __future__ import annotations

import pytest
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.parameter import Parameter, parameter_value_to_python

from test.conftest import ros_node

PLANT = ('mill_plant.plant_node', 'plant_node', 'plant')
CONTROLLER = ('mill_controllers.axis_controller_node', 'axis_controller', 'x_controller')
OBSERVER = ('mill_observers.observer_node', 'observer_node', 'x_observer')

# (node, -p argument, parameter the error must name)
BAD_STARTUP = [
    (CONTROLLER, 'controller:=bogus', 'controller'),
    (CONTROLLER, 'pd.omega_c:=0.0', 'pd.omega_c'),
    (CONTROLLER, 'pd.omega_c:=-5.0', 'pd.omega_c'),
    (CONTROLLER, 'pd.zeta_c:=0.0', 'pd.zeta_c'),
    (CONTROLLER, 'pd.zeta_c:=-0.7', 'pd.zeta_c'),
    (CONTROLLER, 'axis:=w', 'axis'),
    (OBSERVER, 'gpi.omega_o:=0.0', 'gpi.omega_o'),
    (OBSERVER, 'gpi.omega_o:=-700.0', 'gpi.omega_o'),
    (OBSERVER, 'gpi.zeta_o:=0.0', 'gpi.zeta_o'),
    (OBSERVER, 'gpi.zeta_o:=-0.5', 'gpi.zeta_o'),
    (OBSERVER, 'axis:=w', 'axis'),
    (PLANT, 'axes:=["x","w"]', 'axes'),
    (PLANT, 'mass:=[17.551, 0.0, 22.505]', 'mass'),
    (PLANT, 'mass:=[17.551, 23.896, -1.0]', 'mass'),
]


@pytest.mark.system
@pytest.mark.parametrize(
    ('node', 'arg', 'param'), BAD_STARTUP, ids=[f'{n[1]}-{a}' for n, a, _ in BAD_STARTUP]
)
def test_bad_startup_parameter_exits_2_with_one_line(start_node, node, arg, param) -> None:
    module, executable, name = node
    proc = start_node(module, name, '-p', arg, params_file=False)
    code, _out, err = proc.wait(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith(f'{executable}: error: invalid parameter {param}='), lines[0]


class ParameterClient:
    """set_parameters / get_parameters of one remote node, each call bounded in time."""

    def __init__(self, node, executor, target: str) -> None:
        self._executor = executor
        self._set = node.create_client(SetParameters, f'/{target}/set_parameters')
        self._get = node.create_client(GetParameters, f'/{target}/get_parameters')
        for client in (self._set, self._get):
            assert client.wait_for_service(timeout_sec=60), f'{client.srv_name} never appeared'

    def _call(self, client, request):
        future = client.call_async(request)
        self._executor.spin_until_future_complete(future, timeout_sec=30)
        assert future.done(), f'{client.srv_name} did not answer'
        return future.result()

    def set(self, name: str, value):
        request = SetParameters.Request()
        request.parameters = [Parameter(name, value=value).to_parameter_msg()]
        response = self._call(self._set, request)
        assert len(response.results) == 1
        return response.results[0]

    def get(self, *names: str) -> dict:
        response = self._call(self._get, GetParameters.Request(names=list(names)))
        values = zip(names, response.values, strict=True)
        return {n: parameter_value_to_python(v) for n, v in values}


def _assert_rejected(result, name: str) -> None:
    assert not result.successful, f'{name}: change accepted'
    assert name in result.reason, result.reason


@pytest.mark.system
def test_controller_rejects_bad_changes_at_run_time(start_node) -> None:
    controller = start_node(CONTROLLER[0], 'x_controller')
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        before = params.get('pd.omega_c', 'controller', 'axis')
        assert before == {'pd.omega_c': 12.0, 'controller': 'adrc', 'axis': 'x'}

        _assert_rejected(params.set('pd.omega_c', -1.0), 'pd.omega_c')
        _assert_rejected(params.set('controller', 'bogus'), 'controller')
        _assert_rejected(params.set('axis', 'y'), 'axis')  # read-only
        assert params.get('pd.omega_c', 'controller', 'axis') == before
        assert controller.alive()

        assert params.set('pd.omega_c', 20.0).successful
        assert params.get('pd.omega_c', 'controller', 'axis') == {**before, 'pd.omega_c': 20.0}
        assert params.get('pd.zeta_c') == {'pd.zeta_c': 0.7071}  # still answering
        # `ros2 param set ... 25` sends an integer: stored as the double it means.
        assert params.set('pd.omega_c', 25).successful
        value = params.get('pd.omega_c')['pd.omega_c']
        assert isinstance(value, float) and value == 25.0
    assert controller.alive()


@pytest.mark.system
def test_observer_rejects_bad_changes_at_run_time(start_node) -> None:
    observer = start_node(OBSERVER[0], 'x_observer')
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_observer')
        before = params.get('gpi.zeta_o', 'gpi.omega_o', 'observer')
        assert before == {'gpi.zeta_o': 0.7071, 'gpi.omega_o': 700.0, 'observer': 'gpi'}

        _assert_rejected(params.set('gpi.zeta_o', 0.0), 'gpi.zeta_o')
        _assert_rejected(params.set('observer', 'bogus'), 'observer')
        assert params.get('gpi.zeta_o', 'gpi.omega_o', 'observer') == before
        assert params.set('gpi.zeta_o', 0.9).successful
        assert params.get('gpi.zeta_o') == {'gpi.zeta_o': 0.9}
    assert observer.alive()
