"""Bad parameters: refused at start-up with one line naming them, refused at run time with a
reason naming them while the node keeps its previous values and keeps running.

Start-up cases pass plain `-p NAME:=VALUE` without the scenario file: a node-specific
entry of a params file (`x_controller: ros__parameters: ...`) takes precedence over a plain
`-p` (rcl stores `-p` under `/**`), so with the scenario file the bad value would not even
reach the node. `-p NODE:NAME:=VALUE` is the form that overrides a file.
"""

from __future__ import annotations

import pytest
from mill_common.ros import DATA_QOS, joint_state
from mill_common.signals import FopdtEstimate
from sensor_msgs.msg import JointState

from mill_common import topics
from test.conftest import ParameterClient, ros_node, wait_until

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


@pytest.mark.system
def test_switch_to_a_law_needing_a_model_waits_for_one(start_node) -> None:
    """adaptive_pi with model_source observer designs with the rls observer's estimate: a
    switch to it is refused with the reason while no estimate has arrived, accepted after."""

    controller = start_node(
        CONTROLLER[0], 'x_controller', '-p', 'x_controller:controller:=machine_pi'
    )
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        assert params.set('adaptive_pi.model_source', 'observer').successful  # not running
        refused = params.set('controller', 'adaptive_pi')
        assert not refused.successful
        assert topics.observer_state('x') in refused.reason, refused.reason
        assert params.get('controller') == {'controller': 'machine_pi'}
        assert controller.alive()

        pub = node.create_publisher(JointState, topics.observer_state('x'), DATA_QOS)
        assert wait_until(lambda: pub.get_subscription_count() > 0, 30)
        status = FopdtEstimate(29.0, 2.0, 1.25e-4, 0.5, 500).as_status()
        # From the observer the controller trusts (observer_node: x_observer by default).
        pub.publish(joint_state(0, tuple(status), tuple(status.values()), sender='x_observer'))

        def accepted() -> bool:
            executor.spin_once(timeout_sec=0.05)
            return params.set('controller', 'adaptive_pi').successful

        assert wait_until(accepted, 30)
        assert params.get('controller') == {'controller': 'adaptive_pi'}
    assert controller.alive()
